//! The voxel grid the self-shadowing volumes share, and reading it: where a volume lies
//! ([`VolumeGrid`]), trilinear reading of its extinction and tensor, the crossings per length they
//! give along a direction, and where a ray leaves the box.

use crate::hair::Hair;
use glam::Vec3;

/// Largest number of voxels along one axis.
pub const MAX_DIM: usize = 256;

/// Where the volume lies: one voxel of margin around the hair's bounds, the voxel grown if an axis
/// would need more than MAX_DIM voxels. Shared by the CPU builder and the GPU pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeGrid {
    pub origin: Vec3,
    pub voxel: f32,
    pub dims: [usize; 3],
}

impl VolumeGrid {
    pub fn around(hair: &Hair, voxel: f32) -> Self {
        let (lo, hi) = hair.bounds();
        let mut voxel = voxel.max(1e-4);
        let extent = (hi - lo).max(Vec3::splat(voxel));
        let largest = extent.max_element();
        if largest / voxel > (MAX_DIM - 2) as f32 {
            voxel = largest / (MAX_DIM - 2) as f32;
        }
        let origin = lo - Vec3::splat(voxel);
        let dims = [0, 1, 2].map(|a| ((extent[a] / voxel).ceil() as usize + 2).min(MAX_DIM));
        Self {
            origin,
            voxel,
            dims,
        }
    }

    pub fn voxel_count(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }
}

/// Distance from p along omega (unit) to where the ray leaves the box origin + voxel * [0, dims];
/// infinite for a zero direction.
pub fn box_exit(origin: Vec3, voxel: f32, dims: [usize; 3], p: Vec3, omega: Vec3) -> f32 {
    let hi = origin + voxel * Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
    let mut exit = f32::INFINITY;
    for ax in 0..3 {
        let w = omega[ax];
        if w.abs() > 1e-12 {
            let t = if w > 0.0 {
                (hi[ax] - p[ax]) / w
            } else {
                (origin[ax] - p[ax]) / w
            };
            exit = exit.min(t);
        }
    }
    exit
}

/// Trilinear reading of (a, M) at p over a grid with voxel centres at origin + voxel (i + 1/2); zero outside.
pub fn trilinear(
    dims: [usize; 3],
    voxel: f32,
    origin: Vec3,
    extinction: &[f32],
    tensor: &[[f32; 6]],
    p: Vec3,
) -> (f32, [f32; 6]) {
    let q = (p - origin) / voxel - Vec3::splat(0.5);
    let base = q.floor();
    let f = q - base;
    let (mut a, mut m) = (0.0, [0.0; 6]);
    let inside = (0..3).all(|ax| base[ax] >= 0.0 && base[ax] + 1.0 < dims[ax] as f32);
    if inside {
        // All eight corners in the grid (the common case): the same sums in the same order as
        // below, without the per-corner bounds tests.
        let v0 = (base.z as usize * dims[1] + base.y as usize) * dims[0] + base.x as usize;
        let (sy, sz) = (dims[0], dims[0] * dims[1]);
        let wx = [1.0 - f.x, f.x];
        let wy = [1.0 - f.y, f.y];
        let wz = [1.0 - f.z, f.z];
        for corner in 0..8 {
            let (ox, oy, oz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let v = v0 + ox + oy * sy + oz * sz;
            let w = 1.0 * wx[ox] * wy[oy] * wz[oz];
            a += w * extinction[v];
            let t = &tensor[v];
            for c in 0..6 {
                m[c] += w * t[c];
            }
        }
        return (a, m);
    }
    for corner in 0..8 {
        let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        let idx = [0, 1, 2].map(|ax| base[ax] as i64 + o[ax] as i64);
        if (0..3).any(|ax| idx[ax] < 0 || idx[ax] >= dims[ax] as i64) {
            continue;
        }
        let v = (idx[2] as usize * dims[1] + idx[1] as usize) * dims[0] + idx[0] as usize;
        let w: f32 = (0..3)
            .map(|ax| if o[ax] == 1 { f[ax] } else { 1.0 - f[ax] })
            .product();
        a += w * extinction[v];
        for c in 0..6 {
            m[c] += w * tensor[v][c];
        }
    }
    (a, m)
}

/// sqrt(a^2 - a omega^T M omega): expected crossings per cm along omega.
pub fn crossings(a: f32, m: [f32; 6], w: Vec3) -> f32 {
    let q = m[0] * w.x * w.x
        + m[1] * w.y * w.y
        + m[2] * w.z * w.z
        + 2.0 * (m[3] * w.x * w.y + m[4] * w.x * w.z + m[5] * w.y * w.z);
    (a * a - a * q).max(0.0).sqrt()
}
