//! Equirectangular HDR environments: loading (.hdr, .exr), sanitising, writing, downsampling.

use super::direction::{pixel_direction, pixel_solid_angle};
use glam::DVec3;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum EnvError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
}

impl EnvError {
    fn format(path: &Path, message: impl Into<String>) -> Self {
        Self::Format {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// A linear RGB latitude-longitude map (width = 2 height), rows from the zenith down.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

/// What loading had to repair.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Sanitised {
    pub nan: usize,
    pub infinite: usize,
    pub negative: usize,
}

impl Sanitised {
    pub fn any(&self) -> bool {
        self.nan + self.infinite + self.negative > 0
    }
}

/// Largest accepted map (32k x 16k).
const MAX_WIDTH: usize = 32768;

impl EnvMap {
    /// Checks the layout and replaces NaN, infinite and negative values by 0, counting them.
    pub fn new(
        width: usize,
        height: usize,
        mut pixels: Vec<[f32; 3]>,
        path: &Path,
    ) -> Result<(Self, Sanitised), EnvError> {
        if width != 2 * height || height == 0 {
            return Err(EnvError::format(
                path,
                format!("{width}x{height} is not an equirectangular (2:1 latitude-longitude) map"),
            ));
        }
        if width > MAX_WIDTH {
            return Err(EnvError::format(
                path,
                format!("{width} pixels wide is more than {MAX_WIDTH}"),
            ));
        }
        if pixels.len() != width * height {
            return Err(EnvError::format(
                path,
                "pixel count does not match the size",
            ));
        }
        let mut s = Sanitised::default();
        for p in &mut pixels {
            for c in p.iter_mut() {
                if c.is_nan() {
                    s.nan += 1;
                    *c = 0.0;
                } else if c.is_infinite() {
                    s.infinite += 1;
                    *c = 0.0;
                } else if *c < 0.0 {
                    s.negative += 1;
                    *c = 0.0;
                }
            }
        }
        Ok((
            Self {
                width,
                height,
                pixels,
            },
            s,
        ))
    }

    pub fn direction(&self, x: usize, y: usize) -> DVec3 {
        pixel_direction(x, y, self.width, self.height)
    }

    pub fn solid_angle(&self, y: usize) -> f64 {
        pixel_solid_angle(y, self.width, self.height)
    }

    /// Radiant power per channel: sum of L d omega.
    pub fn power(&self) -> [f64; 3] {
        let mut p = [0.0; 3];
        for y in 0..self.height {
            let w = self.solid_angle(y);
            for x in 0..self.width {
                let c = self.pixels[y * self.width + x];
                for k in 0..3 {
                    p[k] += c[k] as f64 * w;
                }
            }
        }
        p
    }

    /// Box-filters by an integer factor, weighting by solid angle so the power is preserved.
    pub fn downsample(&self, factor: usize) -> EnvMap {
        let f = factor.max(1);
        let (w, h) = (self.width / f, self.height / f);
        let mut out = vec![[0f32; 3]; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = [0f64; 3];
                let mut wsum = 0.0;
                for yy in y * f..(y + 1) * f {
                    let sa = self.solid_angle(yy);
                    for xx in x * f..(x + 1) * f {
                        let c = self.pixels[yy * self.width + xx];
                        for k in 0..3 {
                            acc[k] += c[k] as f64 * sa;
                        }
                        wsum += sa;
                    }
                }
                out[y * w + x] = acc.map(|a| (a / wsum) as f32);
            }
        }
        EnvMap {
            width: w,
            height: h,
            pixels: out,
        }
    }

    /// Writes a tone-mapped 8-bit sRGB PNG preview (Reinhard on exposure-scaled radiance; the EXR
    /// stays the linear data, this is only for looking at).
    pub fn write_png_preview(&self, path: &Path, exposure: f32) -> Result<(), EnvError> {
        let srgb = |x: f32| (crate::colour::srgb_encode(x.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8;
        let mut img = image::RgbImage::new(self.width as u32, self.height as u32);
        for (i, px) in img.pixels_mut().enumerate() {
            let c = self.pixels[i].map(|v| v * exposure);
            px.0 = c.map(|v| srgb(v / (1.0 + v)));
        }
        img.save(path)
            .map_err(|e| EnvError::format(path, format!("writing PNG: {e}")))
    }

    /// Writes a float32 RGB OpenEXR (ZIP compressed).
    pub fn write_exr(&self, path: &Path) -> Result<(), EnvError> {
        use exr::prelude::*;
        let pixels = &self.pixels;
        let w = self.width;
        let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
            let p = pixels[pos.y() * w + pos.x()];
            (p[0], p[1], p[2])
        });
        let mut layer = Layer::new(
            (self.width, self.height),
            LayerAttributes::named("environment"),
            Encoding::SMALL_LOSSLESS,
            channels,
        );
        layer.encoding.compression = Compression::ZIP16;
        Image::from_layer(layer)
            .write()
            .to_file(path)
            .map_err(|e| EnvError::format(path, format!("writing EXR: {e}")))
    }
}

/// Loads a .hdr (Radiance RGBE, flat or RLE) or .exr (half or float, scanline or tiled).
pub fn load_env(path: &Path) -> Result<(EnvMap, Sanitised), EnvError> {
    let bytes = std::fs::read(path).map_err(|source| EnvError::Io {
        path: path.into(),
        source,
    })?;
    decode_env(&bytes, path)
}

/// Decodes environment bytes by the extension of `path` (which names the file in errors).
pub fn decode_env(bytes: &[u8], path: &Path) -> Result<(EnvMap, Sanitised), EnvError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "hdr" => decode_hdr(bytes, path),
        "exr" => decode_exr(bytes, path),
        _ => Err(EnvError::format(
            path,
            "unsupported environment type (expected .hdr or .exr)",
        )),
    }
}

/// Decodes Radiance RGBE bytes.
pub fn decode_hdr(bytes: &[u8], path: &Path) -> Result<(EnvMap, Sanitised), EnvError> {
    use image::ImageDecoder;
    let dec = image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes))
        .map_err(|e| EnvError::format(path, format!("invalid Radiance HDR: {e}")))?;
    let (w, h) = dec.dimensions();
    let (w, h) = (w as usize, h as usize);
    if w != 2 * h || h == 0 || w > MAX_WIDTH {
        return Err(EnvError::format(
            path,
            format!(
                "{w}x{h} is not an equirectangular (2:1 latitude-longitude) map of a supported size"
            ),
        ));
    }
    let mut buf = vec![0u8; dec.total_bytes() as usize];
    dec.read_image(&mut buf)
        .map_err(|e| EnvError::format(path, format!("invalid Radiance HDR data: {e}")))?;
    let floats: &[f32] = bytemuck::cast_slice(&buf);
    let pixels = floats.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    EnvMap::new(w, h, pixels, path)
}

/// Decodes OpenEXR bytes: the first layer's R, G, B (or Y as grey).
pub fn decode_exr(bytes: &[u8], path: &Path) -> Result<(EnvMap, Sanitised), EnvError> {
    use exr::prelude::*;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| EnvError::format(path, format!("invalid OpenEXR header: {e}")))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| EnvError::format(path, "OpenEXR file has no layers"))?;
    let compression = header.compression;
    // The exr crate decodes every compression but the HTJ2K ones; name them rather than let a
    // generic "unimplemented" message through.
    if matches!(compression, Compression::HTJ2K32 | Compression::HTJ2K256) {
        return Err(EnvError::format(
            path,
            format!(
                "uses {compression:?} (high-throughput JPEG 2000) compression, which strandlight cannot decode; re-save it with ZIP, PIZ, DWAA or no compression"
            ),
        ));
    }
    let size = header.layer_size;
    let (w, h) = (size.width(), size.height());
    if w != 2 * h || h == 0 || w > MAX_WIDTH {
        return Err(EnvError::format(
            path,
            format!(
                "{w}x{h} is not an equirectangular (2:1 latitude-longitude) map of a supported size"
            ),
        ));
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _| vec![[0f32; 3]; resolution.width() * resolution.height()],
            move |pixels: &mut Vec<[f32; 3]>,
                  pos: Vec2<usize>,
                  (r, g, b, _a): (f32, f32, f32, f32)| {
                if let Some(p) = pixels.get_mut(pos.y() * w + pos.x()) {
                    *p = [r, g, b];
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| {
            EnvError::format(path, format!("invalid OpenEXR data ({compression:?}): {e}"))
        })?;
    let layer = image.layer_data;
    let (lw, lh) = (layer.size.width(), layer.size.height());
    if (lw, lh) != (w, h) {
        return Err(EnvError::format(path, "layer size differs from the header"));
    }
    EnvMap::new(w, h, layer.channel_data.pixels, path)
}
