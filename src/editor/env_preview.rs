//! The environment panel's pictures: the environment image beside its SRBF reconstruction (what the
//! renderer actually lights with), both at the same exposure, with the fit's error; and the map the
//! viewport shows behind the hair.

use crate::colour::{aces_filmic, srgb_encode};
use crate::envmap::EnvMap;
use crate::render::passes::background::BackgroundMap;
use crate::render::scene::Environment;
use std::sync::Arc;

pub const PREVIEW_WIDTH: usize = 192;
pub const PREVIEW_HEIGHT: usize = 96;

/// The textures are handles: a clone shares them (the scene panel keeps one in egui's memory).
#[derive(Clone)]
pub struct EnvPreview {
    /// The environment it was made for (its name and light count).
    pub key: (String, usize),
    pub image: Option<egui::TextureHandle>,
    pub fit: egui::TextureHandle,
    /// The fit's solid-angle-weighted relative L2 error, when the fit recorded it.
    pub relative_l2: Option<f64>,
}

/// Box-filters an equirectangular map to the preview size.
fn resample(env: &EnvMap, w: usize, h: usize) -> Vec<[f32; 3]> {
    let mut out = vec![[0.0f32; 3]; w * h];
    for y in 0..h {
        let (y0, y1) = (
            y * env.height / h,
            ((y + 1) * env.height / h).max(y * env.height / h + 1),
        );
        for x in 0..w {
            let (x0, x1) = (
                x * env.width / w,
                ((x + 1) * env.width / w).max(x * env.width / w + 1),
            );
            let mut acc = [0.0f64; 3];
            for sy in y0..y1.min(env.height) {
                for sx in x0..x1.min(env.width) {
                    let p = env.pixels[sy * env.width + sx];
                    for c in 0..3 {
                        acc[c] += p[c] as f64;
                    }
                }
            }
            let n = ((y1 - y0) * (x1 - x0)).max(1) as f64;
            out[y * w + x] = acc.map(|a| (a / n) as f32);
        }
    }
    out
}

fn luminance(p: [f32; 3]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

fn to_image(pixels: &[[f32; 3]], scale: f32) -> egui::ColorImage {
    let bytes: Vec<u8> = pixels
        .iter()
        .flat_map(|p| {
            let e = |v: f32| (255.0 * srgb_encode(aces_filmic(v * scale)) + 0.5) as u8;
            [e(p[0]), e(p[1]), e(p[2]), 255]
        })
        .collect();
    egui::ColorImage::from_rgba_unmultiplied([PREVIEW_WIDTH, PREVIEW_HEIGHT], &bytes)
}

/// The two pictures of an environment as CPU images, made off the UI thread (with the scene or the
/// environment they show: resampling a large map takes tens of milliseconds).
pub struct EnvPictures {
    pub key: (String, usize),
    pub image: Option<egui::ColorImage>,
    pub fit: egui::ColorImage,
    pub relative_l2: Option<f64>,
    /// What the viewport shows behind the hair (for the unturned lights: the session's yaw is added).
    pub background: Arc<BackgroundMap>,
}

/// The two pictures of `env`, exposed so that the image's median luminance sits at 0.18, with the
/// map the viewport shows behind the hair (made where the environment was loaded).
pub fn pictures(env: &Environment, background: Arc<BackgroundMap>) -> EnvPictures {
    let (w, h) = (PREVIEW_WIDTH, PREVIEW_HEIGHT);
    let fit = env.lights.render(w, h);
    let image = env.image.as_ref().map(|i| resample(i, w, h));
    let reference = image.as_ref().unwrap_or(&fit.pixels);
    let mut lum: Vec<f32> = reference.iter().map(|p| luminance(*p)).collect();
    lum.sort_by(f32::total_cmp);
    let median = lum.get(lum.len() / 2).copied().unwrap_or(1.0).max(1e-6);
    let scale = 0.18 / median;
    EnvPictures {
        key: (env.name.clone(), env.lights.lights.len()),
        image: image.map(|p| to_image(&p, scale)),
        fit: to_image(&fit.pixels, scale),
        relative_l2: env.lights.fit.as_ref().map(|f| f.relative_l2),
        background,
    }
}

/// The pictures of an environment loaded on its own (a file opened for an edit), with the
/// background map made from it.
pub fn pictures_of(env: &Environment) -> EnvPictures {
    pictures(env, Arc::new(BackgroundMap::from_environment(env)))
}

/// The pictures as egui textures (the UI thread's part: an upload).
pub fn upload(ctx: &egui::Context, p: &EnvPictures) -> EnvPreview {
    let name = &p.key.0;
    EnvPreview {
        key: p.key.clone(),
        image: p.image.as_ref().map(|i| {
            ctx.load_texture(
                format!("env image {name}"),
                i.clone(),
                egui::TextureOptions::LINEAR,
            )
        }),
        fit: ctx.load_texture(
            format!("env fit {name}"),
            p.fit.clone(),
            egui::TextureOptions::LINEAR,
        ),
        relative_l2: p.relative_l2,
    }
}
