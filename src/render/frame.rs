//! A rendered frame read back from the GPU, and its files: linear float EXR (RGBA, alpha = coverage,
//! optionally with AOV layers R, TT, TRT, MS.global, MS.local and depth Z), with the render's
//! parameters as header attributes; a tonemapped PNG preview (ACES filmic, sRGB), never used for the EXR.

use crate::colour::{aces_filmic, srgb_encode};
use crate::render::passes::background::Background;
use crate::render::passes::kbuffer::{Fragment, PixelFragments};
use crate::render::passes::targets::COMPONENTS;
use std::path::Path;

#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// The occluder's samples per pixel.
    pub samples: u32,
    /// Linear RGB times 2^EV, premultiplied by coverage; alpha = the composited coverage of the hair
    /// (the K-buffer's) and of the occluder's samples behind it.
    pub beauty: Vec<[f32; 4]>,
    /// Distance along the view axis of the nearest fragment or occluder sample (1e10 where there is
    /// none).
    pub depth: Vec<f32>,
    /// The occluder's id per sample (its triangle + 1 with the top bit set; 0 = none); only the first
    /// four samples.
    pub sample_ids: Vec<[u32; 4]>,
    /// The K-buffer's kept fragments, `fragments_per_pixel` per pixel (segment + 1 and weight; empty
    /// for a still rendered in tiles).
    pub fragments: Vec<Fragment>,
    pub fragments_per_pixel: u32,
    /// The K-buffer's summary per pixel (empty for a still rendered in tiles).
    pub pixel_fragments: Vec<PixelFragments>,
    /// R, TT, TRT, MS.global, MS.local, with the same exposure as the beauty; they add up to it.
    pub components: Vec<Vec<[f32; 3]>>,
    /// The environment behind every pixel, exposed like the beauty (empty: the render had no
    /// background map). Not in the beauty: [`Frame::composited`] puts the hair over it.
    pub background: Vec<[f32; 3]>,
    /// The occluder's radiance (the head), exposed like the components and part of the beauty (empty:
    /// the render had no occluder).
    pub occluder: Vec<[f32; 3]>,
}

#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct OutputError {
    pub path: String,
    pub message: String,
}

fn out_err(path: &Path, message: impl std::fmt::Display) -> OutputError {
    OutputError {
        path: path.display().to_string(),
        message: message.to_string(),
    }
}

/// Attributes written into the EXR header (name, value); non-Latin-1 characters become '?'.
pub type Attributes = Vec<(String, String)>;

fn exr_text(s: &str) -> exr::prelude::Text {
    let latin: String = s
        .chars()
        .map(|c| if (c as u32) < 256 { c } else { '?' })
        .collect();
    exr::prelude::Text::new_or_none(&latin).unwrap_or_else(|| exr::prelude::Text::from("?"))
}

/// Fails before any rendering when an output could not be written: its folder must exist.
pub fn check_output_folders<'a>(
    outputs: impl IntoIterator<Item = &'a Path>,
) -> Result<(), OutputError> {
    for path in outputs {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if !dir.is_dir() {
            return Err(out_err(
                path,
                format!(
                    "the folder {} does not exist (nothing was rendered)",
                    dir.display()
                ),
            ));
        }
    }
    Ok(())
}

impl Frame {
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Pixel `i`'s kept hair fragments (segment + 1 and weight), front to back.
    pub fn kept_fragments(&self, i: usize) -> &[Fragment] {
        let k = self.fragments_per_pixel as usize;
        match self.fragments.get(i * k..(i + 1) * k) {
            Some(s) => &s[..s.iter().take_while(|f| f.id != 0).count()],
            None => &[],
        }
    }

    /// The hair's composited coverage of pixel `i` (0 for a frame without its K-buffer).
    pub fn hair_alpha(&self, i: usize) -> f32 {
        self.pixel_fragments.get(i).map_or(0.0, |p| p.alpha)
    }

    /// Pixels with any coverage.
    pub fn covered(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.pixel_count()).filter(|&i| self.beauty[i][3] > 0.0)
    }

    /// The same coverage and depth with other shading: `radiance[k]` (the components, before exposure)
    /// for pixel `pixels[k]`, every other pixel zero; the occluder's radiance is kept (it is part of
    /// the beauty).
    pub fn with_components(
        &self,
        pixels: &[usize],
        radiance: &[[[f32; 3]; 5]],
        exposure_scale: f32,
    ) -> Frame {
        let n = self.pixel_count();
        let mut out = self.clone();
        out.components = vec![vec![[0.0; 3]; n]; COMPONENTS.len()];
        for (i, px) in out.beauty.iter_mut().enumerate() {
            let head = self.occluder.get(i).copied().unwrap_or([0.0; 3]);
            px[0] = head[0];
            px[1] = head[1];
            px[2] = head[2];
        }
        for (&i, l) in pixels.iter().zip(radiance) {
            for t in 0..COMPONENTS.len() {
                let v = l[t].map(|x| x * exposure_scale);
                out.components[t][i] = v;
                for c in 0..3 {
                    out.beauty[i][c] += v[c];
                }
            }
        }
        out
    }

    /// The linear radiance behind pixel `i` for `background` (None: transparent, or no map for the
    /// environment), exposed like the beauty.
    pub fn background_at(&self, background: Background, i: usize) -> Option<[f32; 3]> {
        match background {
            Background::Transparent => None,
            Background::Environment => self.background.get(i).copied(),
            Background::Colour(c) => Some(Background::linear_colour(c)),
        }
    }

    /// The beauty over `background`, linear: hair + (1 - alpha) background with alpha 1 (the beauty
    /// itself where there is no background).
    pub fn composited(&self, background: Background) -> Vec<[f32; 4]> {
        (0..self.pixel_count())
            .map(|i| {
                let [r, g, b, a] = self.beauty[i];
                match self.background_at(background, i) {
                    Some(bg) => {
                        let t = (1.0 - a).clamp(0.0, 1.0);
                        [r + t * bg[0], g + t * bg[1], b + t * bg[2], 1.0]
                    }
                    None => [r, g, b, a],
                }
            })
            .collect()
    }

    /// Writes float32 EXR: R, G, B, A; with `aovs`, also Z and <component>.R/G/B for every component
    /// (and the occluder's `occluder.R/G/B` when there is one).
    /// With a background (`Some`, not transparent) R, G, B are the hair over it and A is 1, the hair's
    /// coverage goes to a `coverage` channel and, with `aovs`, (1 - coverage) background to
    /// `background.R/G/B`, so the layers still add up to the beauty.
    pub fn write_exr(
        &self,
        path: &Path,
        attributes: &Attributes,
        aovs: bool,
        background: Option<Background>,
    ) -> Result<(), OutputError> {
        use exr::prelude::*;
        let n = self.pixel_count();
        let channel = |name: &str, f: &dyn Fn(usize) -> f32| {
            AnyChannel::new(name, FlatSamples::F32((0..n).map(f).collect()))
        };
        let background = background.filter(|b| {
            *b != Background::Transparent
                && !(*b == Background::Environment && self.background.len() != n)
        });
        let beauty = match background {
            Some(b) => self.composited(b),
            None => self.beauty.clone(),
        };
        let mut channels: Vec<AnyChannel<FlatSamples>> = vec![
            channel("R", &|i| beauty[i][0]),
            channel("G", &|i| beauty[i][1]),
            channel("B", &|i| beauty[i][2]),
            channel("A", &|i| beauty[i][3]),
        ];
        if background.is_some() {
            channels.push(channel("coverage", &|i| self.beauty[i][3]));
        }
        if aovs {
            channels.push(channel("Z", &|i| self.depth[i]));
            let occluder = (self.occluder.len() == n).then_some(("occluder", &self.occluder));
            for (name, data) in COMPONENTS
                .iter()
                .copied()
                .zip(&self.components)
                .chain(occluder)
            {
                for (c, suffix) in ["R", "G", "B"].iter().enumerate() {
                    channels.push(channel(&format!("{name}.{suffix}"), &|i| data[i][c]));
                }
            }
            if background.is_some() {
                for (c, suffix) in ["R", "G", "B"].iter().enumerate() {
                    channels.push(channel(&format!("background.{suffix}"), &|i| {
                        beauty[i][c] - self.beauty[i][c]
                    }));
                }
            }
        }
        let mut attrs = LayerAttributes::named("strandlight");
        attrs.software_name = Some(Text::from("strandlight"));
        for (k, v) in attributes {
            attrs.other.insert(
                exr_text(&format!("strandlight.{k}")),
                AttributeValue::Text(exr_text(v)),
            );
        }
        let mut layer = Layer::new(
            (self.width as usize, self.height as usize),
            attrs,
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(channels.into()),
        );
        layer.encoding.compression = Compression::ZIP16;
        Image::from_layer(layer)
            .write()
            .to_file(path)
            .map_err(|e| out_err(path, format!("writing EXR: {e}")))
    }

    /// The preview: ACES filmic (Narkowicz's fit) on the exposed linear colour, sRGB encoded. Over the
    /// environment the composite is made in linear light before the tonemap, as the editor's display
    /// does; a flat colour is mixed after it (the picture shows exactly that colour); transparent
    /// keeps straight alpha.
    pub fn write_png(&self, path: &Path, background: Background) -> Result<(), OutputError> {
        let mut img = image::RgbaImage::new(self.width, self.height);
        let enc = |x: f32| srgb_encode(aces_filmic(x));
        let byte = |x: f32| (255.0 * x.clamp(0.0, 1.0) + 0.5) as u8;
        for (i, px) in img.pixels_mut().enumerate() {
            let [r, g, b, a] = self.beauty[i];
            let un = if a > 0.0 { 1.0 / a } else { 0.0 };
            let hair = [enc(r * un), enc(g * un), enc(b * un)];
            *px = match (background, self.background.get(i)) {
                (Background::Environment, Some(bg)) => {
                    let t = (1.0 - a).clamp(0.0, 1.0);
                    let c = [r + t * bg[0], g + t * bg[1], b + t * bg[2]];
                    image::Rgba([byte(enc(c[0])), byte(enc(c[1])), byte(enc(c[2])), 255])
                }
                (Background::Colour(c), _) => {
                    let a = a.clamp(0.0, 1.0);
                    let mix = |k: usize| byte(c[k] as f32 / 255.0 * (1.0 - a) + hair[k] * a);
                    image::Rgba([mix(0), mix(1), mix(2), 255])
                }
                _ => image::Rgba([byte(hair[0]), byte(hair[1]), byte(hair[2]), byte(a)]),
            };
        }
        img.save(path)
            .map_err(|e| out_err(path, format!("writing PNG: {e}")))
    }
}
