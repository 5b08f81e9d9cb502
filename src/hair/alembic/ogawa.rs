//! Ogawa, the container of Alembic archives since Alembic 1.5: a tree of groups and data blocks
//! addressed by 64-bit offsets. Header (16 bytes): `Ogawa`, a byte 0xff once the writer finished,
//! the version 1 as a big-endian u16, the little-endian u64 offset of the root group. A group is a u64 child count then one u64 per
//! child: the high bit marks a data block, the rest is its offset (0: empty). A data block is a u64
//! size then its bytes. Every offset and size is checked against the file before it is used, so a
//! corrupt file is an error and never a large allocation.

/// A child of a group.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    Group(u64),
    Data(u64),
}

pub struct Ogawa<'a> {
    bytes: &'a [u8],
}

const HDF5_MAGIC: &[u8] = b"\x89HDF\r\n\x1a\n";
const DATA_BIT: u64 = 1 << 63;

impl<'a> Ogawa<'a> {
    /// The container and its root group.
    pub fn open(bytes: &'a [u8]) -> Result<(Self, Node), String> {
        if bytes.starts_with(HDF5_MAGIC) {
            return Err(
                "an HDF5-based Alembic archive (written before Alembic 1.5), which is \
                        not read; re-export it as Ogawa, the default since Alembic 1.5"
                    .into(),
            );
        }
        if bytes.len() < 16 || &bytes[..5] != b"Ogawa" {
            return Err("not an Alembic (Ogawa) archive".into());
        }
        if bytes[5] != 0xff {
            return Err("the archive was not finished by its writer".into());
        }
        let version = u16::from_be_bytes([bytes[6], bytes[7]]);
        if version != 1 {
            return Err(format!("Ogawa version {version}, where 1 is read"));
        }
        let o = Self { bytes };
        let root = o.u64_at(8)?;
        Ok((o, Node::Group(root)))
    }

    fn u64_at(&self, at: u64) -> Result<u64, String> {
        let at = usize::try_from(at).map_err(|_| "an offset beyond the file")?;
        let b = self
            .bytes
            .get(at..at.saturating_add(8))
            .filter(|b| b.len() == 8)
            .ok_or_else(|| {
                format!(
                    "an offset {at} beyond the file's {} bytes",
                    self.bytes.len()
                )
            })?;
        Ok(u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
    }

    /// A group's children.
    pub fn children(&self, group: Node) -> Result<Vec<Node>, String> {
        let Node::Group(at) = group else {
            return Err("a data block where a group belongs".into());
        };
        if at == 0 {
            return Ok(Vec::new());
        }
        let count = self.u64_at(at)?;
        let room = (self.bytes.len() as u64).saturating_sub(at + 8) / 8;
        if count > room {
            return Err(format!(
                "a group of {count} children, more than the file can hold"
            ));
        }
        (0..count)
            .map(|k| {
                let v = self.u64_at(at + 8 + 8 * k)?;
                Ok(if v & DATA_BIT != 0 {
                    Node::Data(v & !DATA_BIT)
                } else {
                    Node::Group(v)
                })
            })
            .collect()
    }

    /// A data block's bytes.
    pub fn data(&self, node: Node) -> Result<&'a [u8], String> {
        let Node::Data(at) = node else {
            return Err("a group where a data block belongs".into());
        };
        if at == 0 {
            return Ok(&[]);
        }
        let size = self.u64_at(at)?;
        let start = at + 8;
        let end = start
            .checked_add(size)
            .filter(|&e| e <= self.bytes.len() as u64)
            .ok_or_else(|| format!("a block of {size} bytes beyond the end of the file"))?;
        Ok(&self.bytes[start as usize..end as usize])
    }
}

/// Little-endian reading from a block, each read checked.
pub struct Reader<'a> {
    pub rest: &'a [u8],
}

impl<'a> Reader<'a> {
    pub fn new(rest: &'a [u8]) -> Self {
        Self { rest }
    }

    pub fn bytes(&mut self, n: usize) -> Result<&'a [u8], String> {
        if n > self.rest.len() {
            return Err(format!(
                "{n} bytes wanted where {} are left",
                self.rest.len()
            ));
        }
        let (head, tail) = self.rest.split_at(n);
        self.rest = tail;
        Ok(head)
    }

    pub fn u8(&mut self) -> Result<u8, String> {
        Ok(self.bytes(1)?[0])
    }

    pub fn u16(&mut self) -> Result<u16, String> {
        let b = self.bytes(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    pub fn u32(&mut self) -> Result<u32, String> {
        let b = self.bytes(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub fn f64(&mut self) -> Result<f64, String> {
        let b = self.bytes(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(f64::from_le_bytes(a))
    }

    pub fn string(&mut self, n: usize) -> Result<String, String> {
        String::from_utf8(self.bytes(n)?.to_vec()).map_err(|_| "a name that is not UTF-8".into())
    }
}
