//! The fiber-density volume of self-shadowing (after Bertails et al. 2005), physically scaled: the
//! CPU twin of the GPU compute pass the renderer runs whenever geometry changes.
//!
//! Per voxel: the fiber length density rho_L (cm of fiber per cm^3), the length-weighted orientation
//! tensor T = <u u^T> (trace 1), the length-weighted mean absorption sigma_a and fiber diameter D.
//! A ray in direction omega crosses, per unit path length, rho_L D |sin(omega, u)| fibers on average (a
//! fiber of length l and diameter D presents the projected area l D |omega x u| to the ray), so the
//! expected crossings along a path are tau = integral rho_L D sqrt(1 - omega^T T omega) ds and the fraction
//! of light arriving without crossing any fiber is exp(-tau) (Poisson). sqrt(<sin^2>) stands in for
//! <|sin|>: exact for aligned fibers, 4% high for isotropic ones. No opacity constant is involved.

use super::voxels::{VolumeGrid, box_exit, crossings, trilinear};
use crate::hair::Hair;
use glam::Vec3;

/// The volume. Voxel (i, j, k) covers origin + voxel * [i, i+1) x [j, j+1) x [k, k+1).
#[derive(Clone, Debug)]
pub struct FiberDensity {
    pub dims: [usize; 3],
    pub origin: Vec3,
    pub voxel: f32,
    /// a = rho_L D per voxel (expected crossings per cm of path for a ray perpendicular to the fibers).
    pub extinction: Vec<f32>,
    /// M = rho_L D <u u^T> per voxel as (xx, yy, zz, xy, xz, yz); trace M = a.
    pub extinction_tensor: Vec<[f32; 6]>,
    /// Length-weighted mean sigma_a (RGB) of the fibers in the voxel; in an empty voxel, that of its
    /// 26 neighbours.
    pub absorption: Vec<[f32; 3]>,
    /// rho_L, cm of fiber per cm^3.
    pub length_density: Vec<f32>,
    /// The fraction of the voxel inside an occluder ([`FiberDensity::add_solid`]; empty: none).
    pub solid: Vec<f32>,
}

/// The absorption of an empty voxel: the length-weighted mean over its 26 neighbours (0 if they are
/// empty too). Trilinear reading gives an empty voxel next to hair a non-zero crossing density; the
/// fibers a ray crosses there are its neighbours', so the forward march must see their absorption,
/// not none (clear fibers). Twin of `resolve` in `shaders/fiber_density.wgsl`.
fn neighbour_absorption(dims: [usize; 3], v: usize, length: &[f64], sums: &[[f64; 3]]) -> [f32; 3] {
    let (i, j, k) = (
        (v % dims[0]) as i64,
        ((v / dims[0]) % dims[1]) as i64,
        (v / (dims[0] * dims[1])) as i64,
    );
    let (mut len, mut sig) = (0f64, [0f64; 3]);
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (x, y, z) = (i + dx, j + dy, k + dz);
                if x < 0
                    || y < 0
                    || z < 0
                    || x >= dims[0] as i64
                    || y >= dims[1] as i64
                    || z >= dims[2] as i64
                {
                    continue;
                }
                let u = (z as usize * dims[1] + y as usize) * dims[0] + x as usize;
                len += length[u];
                for c in 0..3 {
                    sig[c] += sums[u][c];
                }
            }
        }
    }
    if len <= 0.0 {
        return [0.0; 3];
    }
    sig.map(|x| (x / len) as f32)
}

impl FiberDensity {
    /// Deposits every segment's length into the voxels it passes through (sub-sampled at a quarter
    /// voxel), with its direction tensor, absorption (mean of its two points) and diameter.
    /// `sigma_a` holds one RGB absorption per point of `hair`.
    pub fn build(hair: &Hair, sigma_a: &[[f32; 3]], voxel: f32) -> Self {
        let grid = VolumeGrid::around(hair, voxel);
        let (origin, voxel, dims) = (grid.origin, grid.voxel, grid.dims);
        let n = dims[0] * dims[1] * dims[2];
        let mut length = vec![0f64; n];
        let mut tensor = vec![[0f64; 6]; n];
        let mut absorption = vec![[0f64; 3]; n];
        let mut diameter = vec![0f64; n];
        let index = |p: Vec3| -> Option<usize> {
            let q = (p - origin) / voxel;
            let (i, j, k) = (q.x.floor(), q.y.floor(), q.z.floor());
            if i < 0.0 || j < 0.0 || k < 0.0 {
                return None;
            }
            let (i, j, k) = (i as usize, j as usize, k as usize);
            (i < dims[0] && j < dims[1] && k < dims[2]).then(|| (k * dims[1] + j) * dims[0] + i)
        };
        for s in 0..hair.strand_count() {
            let range = hair.strand_range(s);
            for p in range.start..range.end - 1 {
                let (a, b) = (hair.positions[p], hair.positions[p + 1]);
                let l = a.distance(b);
                if l <= 0.0 {
                    continue;
                }
                let u = (b - a) / l;
                let uu = [
                    u.x * u.x,
                    u.y * u.y,
                    u.z * u.z,
                    u.x * u.y,
                    u.x * u.z,
                    u.y * u.z,
                ];
                let sig: [f32; 3] =
                    std::array::from_fn(|c| 0.5 * (sigma_a[p][c] + sigma_a[p + 1][c]));
                let d = 0.5 * (hair.thickness_at(s, p) + hair.thickness_at(s, p + 1));
                let steps = ((l / (0.25 * voxel)).ceil() as usize).max(1);
                let dl = (l / steps as f32) as f64;
                for k in 0..steps {
                    let x = a + (b - a) * ((k as f32 + 0.5) / steps as f32);
                    if let Some(v) = index(x) {
                        length[v] += dl;
                        for c in 0..6 {
                            tensor[v][c] += dl * uu[c] as f64;
                        }
                        for c in 0..3 {
                            absorption[v][c] += dl * sig[c] as f64;
                        }
                        diameter[v] += dl * d as f64;
                    }
                }
            }
        }
        let volume = (voxel as f64).powi(3);
        let mut out = Self {
            dims,
            origin,
            voxel,
            extinction: vec![0.0; n],
            extinction_tensor: vec![[0.0; 6]; n],
            absorption: vec![[0.0; 3]; n],
            length_density: vec![0.0; n],
            solid: Vec::new(),
        };
        for v in 0..n {
            if length[v] <= 0.0 {
                out.absorption[v] = neighbour_absorption(dims, v, &length, &absorption);
                continue;
            }
            let rho = length[v] / volume;
            let d = diameter[v] / length[v];
            out.length_density[v] = rho as f32;
            out.extinction[v] = (rho * d) as f32;
            out.extinction_tensor[v] =
                std::array::from_fn(|c| (rho * d * tensor[v][c] / length[v]) as f32);
            out.absorption[v] = std::array::from_fn(|c| (absorption[v][c] / length[v]) as f32);
        }
        out
    }

    /// Adds an opaque solid (an occluder) with `fraction` of each voxel inside it
    /// ([`super::solid::solid_fraction`]): its isotropic extinction, and the extinction-weighted mix of
    /// the fibers' absorption with the solid's. Twin of `resolve` in `shaders/fiber_density.wgsl`.
    pub fn add_solid(&mut self, fraction: &[f32]) {
        use super::solid::{SOLID_SIGMA_A, solid_extinction};
        self.solid = fraction.to_vec();
        self.solid.resize(self.extinction.len(), 0.0);
        for (v, &s) in fraction.iter().enumerate().take(self.extinction.len()) {
            if s <= 0.0 {
                continue;
            }
            let a_s = solid_extinction(s, self.voxel);
            let a_h = self.extinction[v];
            self.absorption[v] = self.absorption[v].map(|sig| {
                if a_h > 0.0 {
                    (a_h * sig + a_s * SOLID_SIGMA_A) / (a_h + a_s)
                } else {
                    SOLID_SIGMA_A
                }
            });
            self.extinction[v] = a_h + a_s;
        }
    }

    /// The occluder's fraction of the voxel containing p (0 outside the volume or without one).
    pub fn solid_at(&self, p: Vec3) -> f32 {
        self.voxel_at(p)
            .and_then(|v| self.solid.get(v))
            .copied()
            .unwrap_or(0.0)
    }

    /// Whether p lies in a voxel more than half inside the occluder (the shadow grid's points there are
    /// left out of its interpolation: their transmittance is the solid's, not the hair's).
    pub fn inside_solid(&self, p: Vec3) -> bool {
        self.solid_at(p) > 0.5
    }

    /// The voxel containing p.
    pub fn voxel_at(&self, p: Vec3) -> Option<usize> {
        let q = ((p - self.origin) / self.voxel).floor();
        if q.min_element() < 0.0 {
            return None;
        }
        let (i, j, k) = (q.x as usize, q.y as usize, q.z as usize);
        (i < self.dims[0] && j < self.dims[1] && k < self.dims[2])
            .then(|| (k * self.dims[1] + j) * self.dims[0] + i)
    }

    /// Expected fiber crossings per cm along omega (unit) at p: sqrt(a^2 - a omega^T M omega), with
    /// (a, M) read trilinearly.
    pub fn crossings_per_length(&self, p: Vec3, omega: Vec3) -> f32 {
        let (a, m) = trilinear(
            self.dims,
            self.voxel,
            self.origin,
            &self.extinction,
            &self.extinction_tensor,
            p,
        );
        crossings(a, m, omega)
    }

    /// Expected crossings tau from p towards the light along omega (unit), by the midpoint rule with
    /// steps of half a voxel until the ray leaves the volume; `skip` cm are left out at the start (the
    /// shaded fiber itself).
    pub fn optical_depth(&self, p: Vec3, omega: Vec3, skip: f32) -> f32 {
        let h = 0.5 * self.voxel;
        let exit = box_exit(self.origin, self.voxel, self.dims, p, omega);
        if !exit.is_finite() || exit <= skip {
            return 0.0;
        }
        let steps = ((exit - skip) / h).ceil() as usize;
        let dh = (exit - skip) / steps as f32;
        (0..steps)
            .map(|k| {
                self.crossings_per_length(p + omega * (skip + (k as f32 + 0.5) * dh), omega) * dh
            })
            .sum()
    }

    /// The fraction of light from direction omega reaching p without crossing a fiber: exp(-tau).
    pub fn transmittance(&self, p: Vec3, omega: Vec3, skip: f32) -> f32 {
        (-self.optical_depth(p, omega, skip)).exp()
    }
}
