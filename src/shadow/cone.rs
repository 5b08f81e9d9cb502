//! Soft shadows for wide SRBF lights: the fiber-density volume mip-mapped (2x2x2 averages of the
//! extinction a and tensor M), and cone marching that reads, at distance s along the light's centre
//! direction, the level whose voxel matches the cone's width 2 s tan(half-angle) (the role of Ren et
//! al. 2010's convolution optical depth maps). The cone's half-angle for an SRBF of bandwidth lambda is
//! the angle at which G falls to 1/e: 1 - cos(angle) = lambda^2 / 2.
//!
//! The light's transmittance is the G-weighted average of exp(-tau(omega)); one cone (exp of the averaged
//! tau) underestimates it (Jensen) and misses the tails of wide SRBFs, so wide lights are split into
//! seven cones ([`DensityPyramid::srbf_transmittance`]); the test measures the rest against Monte Carlo.

use super::fiber_density::FiberDensity;
use super::voxels::{box_exit, crossings, trilinear};
use glam::Vec3;

/// One mip level: (a, M) per voxel, dims halved (rounded up) from the level below.
#[derive(Clone, Debug)]
pub struct DensityLevel {
    pub dims: [usize; 3],
    pub voxel: f32,
    pub extinction: Vec<f32>,
    pub extinction_tensor: Vec<[f32; 6]>,
}

/// The mip pyramid over a [`FiberDensity`] (level 0 is the volume itself).
#[derive(Clone, Debug)]
pub struct DensityPyramid {
    pub origin: Vec3,
    pub levels: Vec<DensityLevel>,
}

impl DensityLevel {
    fn index(&self, i: [i64; 3]) -> Option<usize> {
        if (0..3).any(|ax| i[ax] < 0 || i[ax] >= self.dims[ax] as i64) {
            return None;
        }
        Some((i[2] as usize * self.dims[1] + i[1] as usize) * self.dims[0] + i[0] as usize)
    }

    /// Trilinear (a, M) at p.
    pub fn sample(&self, origin: Vec3, p: Vec3) -> (f32, [f32; 6]) {
        trilinear(
            self.dims,
            self.voxel,
            origin,
            &self.extinction,
            &self.extinction_tensor,
            p,
        )
    }
}

impl DensityPyramid {
    pub fn build(volume: &FiberDensity) -> Self {
        let mut levels = vec![DensityLevel {
            dims: volume.dims,
            voxel: volume.voxel,
            extinction: volume.extinction.clone(),
            extinction_tensor: volume.extinction_tensor.clone(),
        }];
        while levels.last().is_some_and(|l| l.dims.iter().any(|&d| d > 1)) {
            let below = levels.last().expect("non-empty");
            let dims = below.dims.map(|d| d.div_ceil(2));
            let n = dims[0] * dims[1] * dims[2];
            let mut extinction = vec![0.0; n];
            let mut tensor = vec![[0.0; 6]; n];
            for k in 0..dims[2] {
                for j in 0..dims[1] {
                    for i in 0..dims[0] {
                        let v = (k * dims[1] + j) * dims[0] + i;
                        // Average of the 8 children (children outside count as empty space).
                        for c in 0..8 {
                            let idx = [
                                (2 * i + (c & 1)) as i64,
                                (2 * j + ((c >> 1) & 1)) as i64,
                                (2 * k + ((c >> 2) & 1)) as i64,
                            ];
                            if let Some(u) = below.index(idx) {
                                extinction[v] += 0.125 * below.extinction[u];
                                for t in 0..6 {
                                    tensor[v][t] += 0.125 * below.extinction_tensor[u][t];
                                }
                            }
                        }
                    }
                }
            }
            let voxel = 2.0 * below.voxel;
            levels.push(DensityLevel {
                dims,
                voxel,
                extinction,
                extinction_tensor: tensor,
            });
        }
        Self {
            origin: volume.origin,
            levels,
        }
    }

    /// Whether p lies in the volume's box (level 0's), as `FiberDensity::voxel_at` finds it.
    pub fn inside(&self, p: Vec3) -> bool {
        let l = &self.levels[0];
        let q = ((p - self.origin) / l.voxel).floor();
        q.min_element() >= 0.0 && (0..3).all(|a| (q[a] as usize) < l.dims[a])
    }

    /// Crossings per cm along omega at p, read at continuous level `lod` (linear between levels).
    pub fn crossings_at(&self, p: Vec3, omega: Vec3, lod: f32) -> f32 {
        let (a, m) = self.extinction_at(p, lod);
        crossings(a, m, omega)
    }

    /// (a, M) at p at continuous level `lod` (trilinear in each level, linear between levels).
    pub fn extinction_at(&self, p: Vec3, lod: f32) -> (f32, [f32; 6]) {
        let top = (self.levels.len() - 1) as f32;
        let lod = lod.clamp(0.0, top);
        let l0 = lod.floor() as usize;
        let l1 = (l0 + 1).min(self.levels.len() - 1);
        let t = lod - l0 as f32;
        let (a0, m0) = self.levels[l0].sample(self.origin, p);
        let (a1, m1) = self.levels[l1].sample(self.origin, p);
        (
            a0 + t * (a1 - a0),
            std::array::from_fn(|c| m0[c] + t * (m1[c] - m0[c])),
        )
    }

    /// Optical depth averaged over the cone around omega (half-angle `half_angle`) from p, out of the
    /// volume; `skip` cm left out at the start. Steps grow with the cone (half the level's voxel).
    pub fn cone_optical_depth(&self, p: Vec3, omega: Vec3, half_angle: f32, skip: f32) -> f32 {
        let exit = self.exit(p, omega);
        let tan = half_angle.min(1.5).tan();
        let mut s = skip;
        let mut tau = 0.0;
        while s < exit {
            let (h, lod) = self.cone_step(s, tan, exit);
            tau += self.crossings_at(p + omega * (s + 0.5 * h), omega, lod) * h;
            s += h;
        }
        tau
    }

    /// Whether any hair lies in the cube [p - r, p + r] (to the resolution of the finest level whose voxel
    /// is at least r / 2, or the coarsest: at most 5^3 voxels): the voxels of that level overlapping the
    /// cube, any extinction above zero. A shadow-grid point with no hair within one grid spacing plus a
    /// voxel is read by no shading point (the tests compare the grid where it is read).
    pub fn hair_near(&self, p: Vec3, r: f32) -> bool {
        let Some(level) = self
            .levels
            .iter()
            .find(|l| l.voxel >= 0.5 * r)
            .or(self.levels.last())
        else {
            return false;
        };
        let lo = ((p - Vec3::splat(r) - self.origin) / level.voxel).floor();
        let hi = ((p + Vec3::splat(r) - self.origin) / level.voxel).floor();
        let range = |ax: usize| {
            let top = level.dims[ax] as i64 - 1;
            (lo[ax] as i64).max(0)..=(hi[ax] as i64).min(top)
        };
        for z in range(2) {
            for y in range(1) {
                for x in range(0) {
                    if level
                        .index([x, y, z])
                        .is_some_and(|v| level.extinction[v] > 0.0)
                    {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Distance from p along omega (unit) to where the ray leaves the pyramid's box.
    pub fn exit(&self, p: Vec3, omega: Vec3) -> f32 {
        box_exit(
            self.origin,
            self.levels[0].voxel,
            self.levels[0].dims,
            p,
            omega,
        )
    }

    /// One step of a cone march at distance s (`tan` of the half-angle): (step length, level). The
    /// step is half the cone's width there (at least half a level-0 voxel), the level that width's.
    pub fn cone_step(&self, s: f32, tan: f32, exit: f32) -> (f32, f32) {
        let base = self.levels[0].voxel;
        let width = (2.0 * s * tan).max(base);
        ((0.5 * width).min(exit - s).max(1e-6), (width / base).log2())
    }

    /// The SRBF light's transmittance at p: the G-weighted average of exp(-tau) over its directions,
    /// by cones. Half of G's mass (cos(angle) above the median w_m of the von Mises-Fisher law
    /// F(w) = (e^(kappa (w - 1)) - e^(-2 kappa)) / (1 - e^(-2 kappa)), kappa = 2 / lambda^2) is one cone about the centre;
    /// the other half is six cones on the ring at the outer half's median angle, each a sixth of the
    /// ring wide. Averaging exp(-tau) over seven cones keeps wide lights' far tails (which reach round
    /// the hair) and most of the Jensen gap that one averaged tau misses.
    pub fn srbf_transmittance(&self, p: Vec3, centre: Vec3, lambda: f32, skip: f32) -> f32 {
        srbf_cones(centre, lambda)
            .into_iter()
            .map(|(d, half_angle, w)| w * (-self.cone_optical_depth(p, d, half_angle, skip)).exp())
            .sum()
    }
}

/// Half-angle of the central cone of [`srbf_cones`] (the cone holding half the SRBF's weight, at least
/// 1e-4); twin of `srbf_centre_cone` in `shaders/density_pyramid.wgsl`.
pub fn srbf_centre_cone(lambda: f32) -> f32 {
    let kappa = 2.0 / (lambda * lambda);
    let e = (-2.0 * kappa).exp();
    (1.0 + (0.5 * (1.0 - e) + e).ln() / kappa)
        .clamp(-1.0, 1.0)
        .acos()
        .max(1e-4)
}

/// The cones of [`DensityPyramid::srbf_transmittance`]: (direction, half-angle, weight). One cone of
/// half-angle max(inner, 1e-4) when the inner half of G is narrower than 0.05 rad, else the central cone
/// (weight 1/2) and six on the ring (1/12 each).
pub fn srbf_cones(centre: Vec3, lambda: f32) -> Vec<(Vec3, f32, f32)> {
    srbf_cones_on_ring(centre, lambda, 6)
}

/// [`srbf_cones`] with `ring_cones` (at least 1) cones on the ring, weight 1/(2 ring_cones) each (the
/// shadow grid's sweeps take three, [`super::sweep::SWEEP_RING`]).
pub fn srbf_cones_on_ring(centre: Vec3, lambda: f32, ring_cones: u32) -> Vec<(Vec3, f32, f32)> {
    assert!(ring_cones >= 1, "an SRBF's ring needs a cone");
    let kappa = 2.0 / (lambda * lambda);
    let e = (-2.0 * kappa).exp();
    let quantile = |q: f32| (1.0 + (q * (1.0 - e) + e).ln() / kappa).clamp(-1.0, 1.0);
    let inner = quantile(0.5).acos();
    if inner < 0.05 {
        return vec![(centre, inner.max(1e-4), 1.0)];
    }
    let ring = quantile(0.25).acos();
    let e1 = if centre.x.abs() < 0.9 {
        Vec3::X
    } else {
        Vec3::Y
    };
    let e1 = (e1 - centre * centre.dot(e1)).normalize();
    let e2 = centre.cross(e1);
    let n = ring_cones.max(1) as f32;
    let sub = (ring * std::f32::consts::PI / n).min(ring);
    let mut cones = vec![(centre, inner, 0.5)];
    for k in 0..ring_cones {
        let a = k as f32 * std::f32::consts::TAU / n;
        let d = (centre * ring.cos() + (e1 * a.cos() + e2 * a.sin()) * ring.sin()).normalize();
        cones.push((d, sub, 0.5 / n));
    }
    cones
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hair::procedural::Style;
    use crate::render::scene::generated_hair;

    /// hair_near never misses hair that level 0 holds in the cube (brute force over the level-0
    /// voxels overlapping it); it may report hair a coarser voxel holds just outside.
    #[test]
    fn hair_near_finds_every_voxel_of_hair_in_the_cube() {
        let hair = generated_hair(Style::Bob, 300, 12, 3);
        let sigma = vec![[0.5f32; 3]; hair.point_count()];
        let volume = FiberDensity::build(&hair, &sigma, 0.4);
        let pyramid = DensityPyramid::build(&volume);
        let l0 = &pyramid.levels[0];
        let extent = Vec3::new(l0.dims[0] as f32, l0.dims[1] as f32, l0.dims[2] as f32) * l0.voxel;
        let (mut near, mut brute_near, mut extra) = (0, 0, 0);
        let mut state = 12345u64;
        let mut rand = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..3000 {
            let p = pyramid.origin + Vec3::new(rand(), rand(), rand()) * extent;
            let r = l0.voxel * (0.5 + 4.0 * rand());
            let lo = ((p - Vec3::splat(r) - pyramid.origin) / l0.voxel).floor();
            let hi = ((p + Vec3::splat(r) - pyramid.origin) / l0.voxel).floor();
            let mut brute = false;
            for z in lo.z as i64..=hi.z as i64 {
                for y in lo.y as i64..=hi.y as i64 {
                    for x in lo.x as i64..=hi.x as i64 {
                        brute |= l0.index([x, y, z]).is_some_and(|v| l0.extinction[v] > 0.0);
                    }
                }
            }
            let h = pyramid.hair_near(p, r);
            assert!(
                h || !brute,
                "hair at level 0 in the cube around {p} (r {r}) missed"
            );
            near += h as u32;
            brute_near += brute as u32;
            extra += (h && !brute) as u32;
        }
        println!(
            "3000 cubes: hair in {brute_near} (level 0), reported in {near} ({extra} from coarser voxels)"
        );
        assert!(
            brute_near > 300 && brute_near < 2700,
            "the test samples both"
        );
    }
}
