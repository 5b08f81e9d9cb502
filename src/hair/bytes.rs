//! Bounds-checked little-endian reading for binary hair formats.

use super::error::HairError;
use glam::Vec3;
use std::path::Path;

pub struct Reader<'a> {
    pub bytes: &'a [u8],
    pub path: &'a Path,
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8], path: &'a Path) -> Self {
        Self { bytes, path }
    }

    pub fn err(&self, message: impl Into<String>) -> HairError {
        HairError::format(self.path, message)
    }

    pub fn slice(&self, offset: u64, len: u64, what: &str) -> Result<&'a [u8], HairError> {
        let end = offset
            .checked_add(len)
            .filter(|&e| e <= self.bytes.len() as u64);
        match end {
            Some(e) => Ok(&self.bytes[offset as usize..e as usize]),
            None => Err(self.err(format!(
                "file is truncated: {what} needs bytes {offset}..{} but the file has {}",
                offset.saturating_add(len),
                self.bytes.len()
            ))),
        }
    }

    pub fn u32_at(&self, offset: u64, what: &str) -> Result<u32, HairError> {
        let b = self.slice(offset, 4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub fn f32_at(&self, offset: u64, what: &str) -> Result<f32, HairError> {
        Ok(f32::from_bits(self.u32_at(offset, what)?))
    }

    /// `count` f32 values starting at `offset`, all finite.
    pub fn f32s(&self, offset: u64, count: u64, what: &str) -> Result<Vec<f32>, HairError> {
        let len = count
            .checked_mul(4)
            .ok_or_else(|| self.err(format!("{what}: count {count} overflows")))?;
        let b = self.slice(offset, len, what)?;
        let v: Vec<f32> = b
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err(self.err(format!("{what}: value {k} is not finite ({})", v[k])));
        }
        Ok(v)
    }

    /// `count` points of `stride` floats (3 or 4), keeping xyz.
    pub fn points(
        &self,
        offset: u64,
        count: u64,
        stride: u64,
        what: &str,
    ) -> Result<Vec<Vec3>, HairError> {
        let total = count
            .checked_mul(stride)
            .ok_or_else(|| self.err(format!("{what}: count {count} overflows")))?;
        let f = self.f32s(offset, total, what)?;
        Ok(f.chunks_exact(stride as usize)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect())
    }
}
