//! The orbit camera shared by the renderer, the reference mode and the editor: a target, yaw and
//! pitch in degrees, a distance in centimetres and a vertical field of view. World space is +Y up.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub target: [f32; 3],
    /// Rotation about +Y, degrees; 0 looks along -Z (the camera sits on +Z).
    pub yaw: f32,
    /// Elevation, degrees, in (-90, 90).
    pub pitch: f32,
    /// Eye to target, cm.
    pub distance: f32,
    /// Vertical field of view, degrees.
    pub fov_y: f32,
}

/// Named viewpoints (yaw, pitch) for `--camera`.
pub const CAMERA_PRESETS: [(&str, f32, f32); 6] = [
    ("front", 0.0, 5.0),
    ("three-quarter", 35.0, 10.0),
    ("side", 90.0, 5.0),
    ("back", 180.0, 5.0),
    ("back-three-quarter", 145.0, 10.0),
    ("top", 0.0, 70.0),
];

impl Camera {
    /// A camera looking at a bounding box from (yaw, pitch), far enough that the box's bounding sphere
    /// fills `fill` of the smaller field of view.
    pub fn framing(lo: Vec3, hi: Vec3, yaw: f32, pitch: f32, aspect: f32, fill: f32) -> Self {
        let fov_y = 30.0f32;
        let centre = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-3);
        let half = (0.5 * fov_y.to_radians()).tan() * aspect.min(1.0);
        let distance = radius / (half.atan().sin() * fill.clamp(0.1, 1.0));
        Self {
            target: centre.to_array(),
            yaw,
            pitch,
            distance,
            fov_y,
        }
    }

    pub fn preset(name: &str) -> Option<(f32, f32)> {
        CAMERA_PRESETS
            .iter()
            .find(|(n, _, _)| *n == name)
            .map(|&(_, y, p)| (y, p))
    }

    pub fn eye(&self) -> Vec3 {
        let (y, p) = (
            self.yaw.to_radians(),
            self.pitch.clamp(-89.0, 89.0).to_radians(),
        );
        Vec3::from(self.target)
            + self.distance * Vec3::new(p.cos() * y.sin(), p.sin(), p.cos() * y.cos())
    }

    /// Near and far planes around the target (the scene lies within `distance` of it).
    pub fn clip_planes(&self) -> (f32, f32) {
        (0.02 * self.distance, 3.0 * self.distance)
    }

    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), Vec3::from(self.target), Vec3::Y)
    }

    pub fn projection(&self, width: u32, height: u32) -> Mat4 {
        let (near, far) = self.clip_planes();
        let aspect = width as f32 / height.max(1) as f32;
        glam::camera::rh::proj::directx::perspective(self.fov_y.to_radians(), aspect, near, far)
    }

    /// World-space ray (origin, unit direction) through pixel coordinates (x, y) (0.5 = a pixel centre,
    /// y down), exactly as the shading pass builds it.
    pub fn ray(&self, width: u32, height: u32, x: f32, y: f32) -> (Vec3, Vec3) {
        let u = self.uniform(width, height, 1.0);
        pixel_ray(&u, x, y)
    }

    pub fn uniform(&self, width: u32, height: u32, min_width_px: f32) -> CameraUniform {
        self.tile_uniform(
            &Tile {
                full: [width, height],
                origin: [0, 0],
                size: [width, height],
            },
            min_width_px,
        )
    }

    /// The camera of one tile of a larger image: the full image's projection narrowed to the tile's
    /// pixels (an off-centre frustum), so a still rendered tile by tile is the untiled one.
    pub fn tile_uniform(&self, tile: &Tile, min_width_px: f32) -> CameraUniform {
        let [width, height] = tile.size;
        let [fw, fh] = [tile.full[0].max(1) as f32, tile.full[1].max(1) as f32];
        // NDC of the tile's centre in the full image, and the scale taking the tile's NDC range to [-1, 1].
        let (sx, sy) = (fw / width.max(1) as f32, fh / height.max(1) as f32);
        let cx = 2.0 * (tile.origin[0] as f32 + 0.5 * width as f32) / fw - 1.0;
        let cy = 1.0 - 2.0 * (tile.origin[1] as f32 + 0.5 * height as f32) / fh;
        let narrow = Mat4::from_cols(
            Vec4::new(sx, 0.0, 0.0, 0.0),
            Vec4::new(0.0, sy, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 1.0, 0.0),
            Vec4::new(-cx * sx, -cy * sy, 0.0, 1.0),
        );
        let view_proj = narrow * self.projection(tile.full[0], tile.full[1]) * self.view();
        let eye = self.eye();
        let forward = (Vec3::from(self.target) - eye).normalize_or(Vec3::NEG_Z);
        let pixel_angle = 2.0 * (0.5 * self.fov_y.to_radians()).tan() / fh;
        let (near, far) = self.clip_planes();
        CameraUniform {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            eye: eye.to_array(),
            pixel_angle,
            forward: forward.to_array(),
            min_width_px,
            size: [width, height],
            near,
            far,
            width_scale: 1.0,
            _pad: [0.0; 3],
        }
    }
}

/// A rectangle of pixels of a larger image (tiled stills).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// The whole image's size.
    pub full: [u32; 2],
    /// The tile's top-left pixel in it.
    pub origin: [u32; 2],
    /// The tile's size.
    pub size: [u32; 2],
}

impl Tile {
    /// The tiles (row-major, at most `tile` pixels a side) covering a width x height image.
    pub fn cover(width: u32, height: u32, tile: u32) -> Vec<Tile> {
        let t = tile.max(16);
        let mut out = Vec::new();
        for y0 in (0..height).step_by(t as usize) {
            for x0 in (0..width).step_by(t as usize) {
                out.push(Tile {
                    full: [width, height],
                    origin: [x0, y0],
                    size: [t.min(width - x0), t.min(height - y0)],
                });
            }
        }
        out
    }
}

/// The camera as the shaders read it (`shaders/camera.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct CameraUniform {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    /// Size of a pixel at unit distance along the view axis.
    pub pixel_angle: f32,
    pub forward: [f32; 3],
    /// Ribbons are at least this many pixels wide (thinner fibers would fall between the samples).
    pub min_width_px: f32,
    pub size: [u32; 2],
    pub near: f32,
    pub far: f32,
    /// Ribbons are drawn this many times as wide (a thinned preview draws every k-th strand k times
    /// as wide: the same coverage from a k-th of the segments); 1 otherwise.
    pub width_scale: f32,
    pub _pad: [f32; 3],
}

const _: () = assert!(std::mem::size_of::<CameraUniform>() == 192);

/// A point on screen: pixel coordinates (0.5 = a pixel centre, y down) and view depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    pub x: f32,
    pub y: f32,
    pub depth: f32,
}

/// Projects `p` with the camera (None behind the eye).
pub fn project(c: &CameraUniform, p: Vec3) -> Option<Projected> {
    let m = Mat4::from_cols_array_2d(&c.view_proj);
    let clip = m * Vec4::new(p.x, p.y, p.z, 1.0);
    if clip.w <= 1e-6 {
        return None;
    }
    let (nx, ny) = (clip.x / clip.w, clip.y / clip.w);
    Some(Projected {
        x: 0.5 * (nx + 1.0) * c.size[0] as f32,
        y: 0.5 * (1.0 - ny) * c.size[1] as f32,
        depth: (p - Vec3::from(c.eye)).dot(Vec3::from(c.forward)),
    })
}

/// The ray through pixel coordinates (x, y) (twin of `pixel_ray` in `shaders/camera.wgsl`).
pub fn pixel_ray(c: &CameraUniform, x: f32, y: f32) -> (Vec3, Vec3) {
    let inv = Mat4::from_cols_array_2d(&c.inv_view_proj);
    let ndc_x = 2.0 * x / c.size[0] as f32 - 1.0;
    let ndc_y = 1.0 - 2.0 * y / c.size[1] as f32;
    let far = inv * Vec4::new(ndc_x, ndc_y, 1.0, 1.0);
    let far = far.truncate() / far.w;
    let eye = Vec3::from(c.eye);
    (eye, (far - eye).normalize())
}

/// Parameter t in [0, 1] of the point of segment a..b closest to the ray (o, d) (twin of
/// `closest_on_segment` in `shaders/camera.wgsl`).
pub fn closest_on_segment(o: Vec3, d: Vec3, a: Vec3, b: Vec3) -> f32 {
    let e = b - a;
    let w = a - o;
    let (ee, ed, we, wd) = (e.dot(e), e.dot(d), w.dot(e), w.dot(d));
    let den = ee - ed * ed;
    if den <= 1e-12 * ee.max(1e-30) {
        return 0.5;
    }
    ((ed * wd - we) / den).clamp(0.0, 1.0)
}
