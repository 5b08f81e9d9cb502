//! Light-space sweeps through the shadow grid (Bertails et al. 2005: the light's transmittance
//! accumulated slice by slice along its direction, each slice read once): the path integrals of
//! [`PathIntegrals`] (optical depth, and with multiple scattering the forward-scattering terms of
//! T_f and the light-weighted sigma_f^2) from every grid point towards a light, in one pass over the
//! grid per direction instead of a cone march per grid point. Twin of `shaders/shadow_grid_build.wgsl`.
//!
//! A sweep along omega (unit, towards the light) walks the grid's slices across the axis on which omega
//! is largest, starting at the slice nearest the light. A point's path is its own segment up to the
//! previous slice (`step` cm, read at its midpoint) and the path from where it lands there,
//! interpolated bilinearly in that slice (zero outside the grid: no hair lies outside it). The
//! midpoints of every sweep across axis a lie on the planes between the slices: [`MidplaneSamples`]
//! holds what the integrands need at those planes' points (the pyramid's (a, M) at the coarsest level
//! whose voxel is at most half the grid spacing, so that no strand slips between neighbouring paths,
//! the voxel's absorption and solid share), read once for every light and direction; a sweep reads
//! them bilinearly at its midpoints and the pyramid no more. The
//! interpolation spreads the shadow laterally by about sqrt(n / 6) spacings after n slices; the SRBF's
//! width is the average over the directions of [`srbf_cones_on_ring`] with [`SWEEP_RING`] on the ring
//! (the centre and three: the cone march, the reference, takes six), each a thin path.

use super::cone::{DensityPyramid, srbf_cones_on_ring};
use super::fiber_density::FiberDensity;
use super::forward::{ForwardTable, PathIntegrals, forward_integrand_of, forward_spread_weighted};
use super::grid::{
    GRID_INSIDE_SOLID, GRID_MIN_TRANSMITTANCE, GridShadow, GridSources, GridValues, ShadowGrid,
};
use super::voxels::crossings;
use glam::Vec3;
use rayon::prelude::*;

/// One sweep of a light's: the direction its paths run (towards the light, or away from it for the
/// depth behind), and the weight of its transmittance in the light's average.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepDirection {
    pub omega: Vec3,
    pub weight: f32,
    /// The centre reversed: the optical depth of the hair behind the point (multiple scattering).
    pub behind: bool,
}

/// Directions on the ring of a wide light's sweeps (its centre holds the other half of the weight).
/// Three rather than the cone march's six: on the clump of `tests/fiber_density.rs` the worst
/// difference from Monte Carlo stayed 0.032 (grid 48) and 0.037 (grid 24), and a light costs 4 sweeps
/// instead of 7 (5 instead of 8 with multiple scattering).
pub const SWEEP_RING: u32 = 3;

/// The sweeps of a light (twin of `sweep_direction` in the WGSL): the directions of
/// [`srbf_cones_on_ring`] ([`SWEEP_RING`]) with their weights, and with `forward` (multiple
/// scattering) the centre reversed.
pub fn sweep_directions(centre: Vec3, lambda: f32, forward: bool) -> Vec<SweepDirection> {
    let mut out: Vec<SweepDirection> = srbf_cones_on_ring(centre, lambda, SWEEP_RING)
        .into_iter()
        .map(|(omega, _, weight)| SweepDirection {
            omega,
            weight,
            behind: false,
        })
        .collect();
    if forward {
        out.push(SweepDirection {
            omega: -centre,
            weight: 1.0,
            behind: true,
        });
    }
    out
}

/// How a sweep along omega walks the grid (twin of `SweepAxes` in the WGSL): slices across axis `a`
/// (omega's largest component; ties to the lower axis), the others `b` < `c`; `towards_high`: the light
/// lies towards the high indices of `a`, so the sweep starts there. A point's segment to the previous
/// slice is `step` cm long and lands `shift` spacings away along (b, c).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepAxes {
    pub a: usize,
    pub b: usize,
    pub c: usize,
    pub towards_high: bool,
    pub step: f32,
    pub shift: [f32; 2],
}

impl SweepAxes {
    pub fn new(grid: &ShadowGrid, omega: Vec3) -> Self {
        let m = omega.abs();
        let a = if m.x >= m.y && m.x >= m.z {
            0
        } else if m.y >= m.z {
            1
        } else {
            2
        };
        let (b, c) = other_axes(a);
        let wa = m[a].max(1e-6);
        Self {
            a,
            b,
            c,
            towards_high: omega[a] > 0.0,
            step: grid.spacing / wa,
            shift: [omega[b] / wa, omega[c] / wa],
        }
    }

    /// The grid index along `a` of the i-th slice swept.
    pub fn slice(&self, grid: &ShadowGrid, i: u32) -> u32 {
        if self.towards_high {
            grid.dims[self.a] - 1 - i
        } else {
            i
        }
    }

    /// The grid point at index k along `a`, (ib, ic) along (b, c).
    pub fn point_index(&self, grid: &ShadowGrid, k: u32, ib: u32, ic: u32) -> usize {
        let mut idx = [0u32; 3];
        idx[self.a] = k;
        idx[self.b] = ib;
        idx[self.c] = ic;
        (idx[2] as usize * grid.dims[1] as usize + idx[1] as usize) * grid.dims[0] as usize
            + idx[0] as usize
    }
}

/// The pyramid level a sweep reads: the coarsest whose voxel v is at most half the grid spacing (1 %
/// tolerance); one level, not two blended (level 0 on the default 128-voxel volume and 48-point
/// grid). A sample sees a strand within 1.5 v (its voxel's box and the trilinear tent): at least 0.5
/// spacing only when v is about half the spacing, so on finer levels a thin strand can pass between
/// neighbouring paths, and along a diagonal path (steps up to 1.73 spacings, one sample each) between
/// samples. Coarser levels blur the hair's lit edge outwards and darkened a clump's lit side (blond
/// clump against ray shooting: worst mean-colour error 12.8 % at level 1, 8.5 % at level 0).
pub fn sweep_lod(grid: &ShadowGrid, pyramid: &DensityPyramid) -> f32 {
    ((grid.spacing / pyramid.levels[0].voxel).log2() - 0.99)
        .max(0.0)
        .floor()
}

/// What a sweep reads at a point (twin of `build_midplane_samples` in
/// `shaders/shadow_grid_build.wgsl`): the pyramid's extinction and orientation tensor at
/// [`sweep_lod`], the level-0 voxel's absorption (with multiple scattering) and solid share.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridSample {
    pub a: f32,
    pub m: [f32; 6],
    pub sigma_a: [f32; 3],
    pub solid: f32,
}

/// Samples per grid spacing across a sweep's planes ([`MidplaneSamples`]): at the grid's own spacing
/// the bilinear reading blurs the density over a spacing, so every SRBF direction sees nearly the same
/// paths, and the average of exp(-tau) over them came out too dark (back-lit blond clump of
/// tests/ms_reference.rs: TT 33 % under the ray-shooting reference against 13 % when each midpoint read
/// the pyramid itself).
pub const MIDPLANE_REFINE: u32 = 2;

/// The samples on the planes between the grid's slices, for the sweeps across each axis a: plane j
/// (0..=dims[a], the cells' boundary j spacings from the origin) at [`MIDPLANE_REFINE`] points per
/// spacing along the other two axes b < c; None outside the volume (zero integrands).
/// Light-independent: read once per grid build. Twin of the GPU's `grid_samples` buffer (six words a
/// point, [`crate::shadow::sample_packing`]; the lattices of axes 0, 1, 2 one after another): the
/// samples are held as the GPU unpacks them ([`GridSample::quantised`]).
pub struct MidplaneSamples {
    pub samples: Vec<Option<GridSample>>,
    /// The first sample of each axis' lattice.
    pub offsets: [usize; 3],
}

impl MidplaneSamples {
    /// The lattices' sizes, (dims[a] + 1) (R dims[b]) (R dims[c]) each (R = [`MIDPLANE_REFINE`]), and
    /// their first samples.
    pub fn layout(grid: &ShadowGrid) -> ([usize; 3], usize) {
        let d = grid.dims.map(|d| d as usize);
        let r = MIDPLANE_REFINE as usize;
        let sizes = [0, 1, 2].map(|a| (d[a] + 1) * r * d[(a + 1) % 3] * r * d[(a + 2) % 3]);
        ([0, sizes[0], sizes[0] + sizes[1]], sizes.iter().sum())
    }

    /// Sample `i` of the lattices: its axis a, plane j and the fine indices (ib, ic) along b < c.
    pub fn coordinates(grid: &ShadowGrid, i: usize) -> (usize, u32, u32, u32) {
        let (offsets, _) = Self::layout(grid);
        let a = if i >= offsets[2] {
            2
        } else if i >= offsets[1] {
            1
        } else {
            0
        };
        let r = i - offsets[a];
        let (nb, nc) = Self::fine_dims(grid, a);
        (
            a,
            (r / (nb * nc)) as u32,
            (r % nb) as u32,
            ((r / nb) % nc) as u32,
        )
    }

    /// Fine points along b and c of axis a's planes.
    fn fine_dims(grid: &ShadowGrid, a: usize) -> (usize, usize) {
        let (b, c) = other_axes(a);
        let r = MIDPLANE_REFINE as usize;
        (r * grid.dims[b] as usize, r * grid.dims[c] as usize)
    }

    /// The position of sample (a, j, ib, ic) (ib, ic fine indices).
    pub fn position(grid: &ShadowGrid, a: usize, j: u32, ib: u32, ic: u32) -> Vec3 {
        let (b, c) = other_axes(a);
        let r = MIDPLANE_REFINE as f32;
        let mut q = Vec3::ZERO;
        q[a] = j as f32;
        q[b] = (ib as f32 + 0.5) / r;
        q[c] = (ic as f32 + 0.5) / r;
        grid.origin + q * grid.spacing
    }

    /// Every sample, from the pyramid at [`sweep_lod`] and `volume` (the forward sources' volume:
    /// absorption and solid; without it the points inside the pyramid's box are inside).
    pub fn build(
        grid: &ShadowGrid,
        pyramid: &DensityPyramid,
        volume: Option<&FiberDensity>,
    ) -> Self {
        let lod = sweep_lod(grid, pyramid);
        let (offsets, total) = Self::layout(grid);
        let samples = (0..total)
            .into_par_iter()
            .map(|i| {
                let (a, j, ib, ic) = Self::coordinates(grid, i);
                let x = Self::position(grid, a, j, ib, ic);
                let (sigma_a, solid) = match volume {
                    Some(v) => {
                        let voxel = v.voxel_at(x)?;
                        (
                            v.absorption[voxel],
                            v.solid.get(voxel).copied().unwrap_or(0.0),
                        )
                    }
                    None if pyramid.inside(x) => ([0.0; 3], 0.0),
                    None => return None,
                };
                let (a, m) = pyramid.extinction_at(x, lod);
                Some(
                    GridSample {
                        a,
                        m,
                        sigma_a,
                        solid,
                    }
                    .quantised(),
                )
            })
            .collect();
        Self { samples, offsets }
    }

    /// The samples at the midpoint of the path from slice `k`'s point (ib, ic) to the previous
    /// slice of sweep `ax` (`midplane_sample` in the WGSL): on the plane between the two slices at
    /// (ib, ic) + shift / 2, bilinear in that plane (the absorption weighted by the extinction, as the
    /// fibers crossed weigh it); None when no sample around it is inside the volume. `lattice` is the
    /// sweep's ([`SweepLattice::new`] of `ax`, found once per sweep).
    pub fn midpoint(
        &self,
        grid: &ShadowGrid,
        ax: &SweepAxes,
        lattice: &SweepLattice,
        k: u32,
        ib: u32,
        ic: u32,
    ) -> Option<GridSample> {
        let j = if ax.towards_high { k + 1 } else { k };
        let r = MIDPLANE_REFINE as i32;
        let (u0, v0) = (
            r * ib as i32 + lattice.mid_offset[0],
            r * ic as i32 + lattice.mid_offset[1],
        );
        let (nb, nc) = Self::fine_dims(grid, ax.a);
        let plane = self.offsets[ax.a] + j as usize * nc * nb;
        let mut out = GridSample::default();
        let (mut inside, mut absorbing) = (false, 0.0);
        let [fu, fv] = lattice.mid_frac;
        for corner in 0..4 {
            let (high_u, high_v) = (corner & 1 == 1, corner >= 2);
            let (iu, iv) = (u0 + high_u as i32, v0 + high_v as i32);
            if iu < 0 || iv < 0 || iu >= nb as i32 || iv >= nc as i32 {
                continue;
            }
            let i = iv as usize * nb + iu as usize;
            let w = if high_u { fu } else { 1.0 - fu } * if high_v { fv } else { 1.0 - fv };
            let Some(s) = &self.samples[plane + i] else {
                continue;
            };
            inside = true;
            out.a += w * s.a;
            out.solid += w * s.solid;
            for (o, m) in out.m.iter_mut().zip(s.m) {
                *o += w * m;
            }
            for (o, sig) in out.sigma_a.iter_mut().zip(s.sigma_a) {
                *o += w * s.a * sig;
            }
            absorbing += w * s.a;
        }
        out.sigma_a = out.sigma_a.map(|x| x / absorbing.max(1e-30));
        inside.then_some(out)
    }
}

/// The axes other than a, in increasing order.
fn other_axes(a: usize) -> (usize, usize) {
    match a {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// Where a sweep reads, alike for all its points (the shift is the sweep's; twin of `SweepLattice` in
/// `shaders/shadow_grid_build.wgsl`): point (ib, ic) reads the previous slice at (ib, ic) + shift,
/// between columns ib + slice_offset\[0\] and the next (weights 1 - slice_frac\[0\] and
/// slice_frac\[0\]), rows alike; and the plane's fine samples at (R ib, R ic) + mid_offset and the
/// next, weights from mid_frac (its midpoint, (ib + 1/2 + shift / 2) spacings, in fine points).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepLattice {
    pub slice_offset: [i32; 2],
    pub slice_frac: [f32; 2],
    pub mid_offset: [i32; 2],
    pub mid_frac: [f32; 2],
}

impl SweepLattice {
    pub fn new(ax: &SweepAxes) -> Self {
        let r = MIDPLANE_REFINE as f32;
        let s = ax.shift.map(f32::floor);
        let m = ax.shift.map(|x| 0.5 * (r - 1.0) + 0.5 * r * x);
        let mf = m.map(f32::floor);
        Self {
            slice_offset: s.map(|x| x as i32),
            slice_frac: [ax.shift[0] - s[0], ax.shift[1] - s[1]],
            mid_offset: mf.map(|x| x as i32),
            mid_frac: [m[0] - mf[0], m[1] - mf[1]],
        }
    }

    /// The previous slice read at (ib, ic) + shift: rows ic + slice_offset\[1\] and the next, each
    /// [`slice_row`] (the GPU walks runs of a column along c and reads each row once per run).
    fn slice_bilinear(
        &self,
        slice: &[PathIntegrals],
        nb: u32,
        nc: u32,
        ib: u32,
        ic: u32,
    ) -> PathIntegrals {
        let u0 = ib as i32 + self.slice_offset[0];
        let v0 = ic as i32 + self.slice_offset[1];
        let fu = self.slice_frac[0];
        let lo = slice_row(slice, nb, nc, u0, fu, v0);
        let hi = slice_row(slice, nb, nc, u0, fu, v0 + 1);
        let fv = self.slice_frac[1];
        PathIntegrals::default()
            .add_scaled(&lo, 1.0 - fv)
            .add_scaled(&hi, fv)
    }
}

/// Row iv of the slice read between columns u0 and u0 + 1 (weights 1 - f and f); points outside the
/// slice are outside the grid, where no hair is: zero (`slice_row` in the WGSL).
fn slice_row(slice: &[PathIntegrals], nb: u32, nc: u32, u0: i32, f: f32, iv: i32) -> PathIntegrals {
    let mut out = PathIntegrals::default();
    if iv < 0 || iv >= nc as i32 {
        return out;
    }
    let row = iv as usize * nb as usize;
    if u0 >= 0 && u0 < nb as i32 {
        out = out.add_scaled(&slice[row + u0 as usize], 1.0 - f);
    }
    if u0 + 1 >= 0 && u0 + 1 < nb as i32 {
        out = out.add_scaled(&slice[row + (u0 + 1) as usize], f);
    }
    out
}

/// The integrands at a sample along omega (a sweep's, `sweep_integrand` in the WGSL): with the
/// forward table all of them, else the optical depth alone; `behind`'s counts hair only (an
/// occluder's solid is not fibres that scatter light back).
pub fn sweep_integrand(
    sample: Option<&GridSample>,
    table: Option<&ForwardTable>,
    omega: Vec3,
    behind: bool,
) -> PathIntegrals {
    let Some(s) = sample else {
        return PathIntegrals::default();
    };
    match table {
        Some(table) if !behind => forward_integrand_of(s.a, s.m, s.sigma_a, table, omega),
        _ => PathIntegrals {
            tau: crossings(s.a, s.m, omega) * if behind { 1.0 - s.solid } else { 1.0 },
            ..Default::default()
        },
    }
}

/// One sweep along omega: `visit(point, integrals)` for every grid point, the integrals of its path
/// out of the grid with the first `skip` cm left out (the point's own fiber). Only the optical depth
/// without `table`. `behind`: the reversed sweep of the depth behind the point (optical depth alone,
/// hair only).
pub fn sweep(
    grid: &ShadowGrid,
    samples: &MidplaneSamples,
    table: Option<&ForwardTable>,
    omega: Vec3,
    skip: f32,
    behind: bool,
    mut visit: impl FnMut(usize, &PathIntegrals),
) {
    let ax = SweepAxes::new(grid, omega);
    let lattice = SweepLattice::new(&ax);
    let (nb, nc) = (grid.dims[ax.b], grid.dims[ax.c]);
    let mut prev: Vec<PathIntegrals> = Vec::new();
    for i in 0..grid.dims[ax.a] {
        let k = ax.slice(grid, i);
        let cur: Vec<(PathIntegrals, PathIntegrals)> = (0..nb * nc)
            .into_par_iter()
            .map(|j| {
                let (ib, ic) = (j % nb, j / nb);
                let up = if prev.is_empty() {
                    PathIntegrals::default()
                } else {
                    lattice.slice_bilinear(&prev, nb, nc, ib, ic)
                };
                let f = sweep_integrand(
                    samples.midpoint(grid, &ax, &lattice, k, ib, ic).as_ref(),
                    table,
                    omega,
                    behind,
                );
                (
                    up.add_scaled(&f, ax.step),
                    up.add_scaled(&f, (ax.step - skip).max(0.0)),
                )
            })
            .collect();
        for (j, (_, out)) in cur.iter().enumerate() {
            let j = j as u32;
            visit(ax.point_index(grid, k, j % nb, j / nb), out);
        }
        prev = cur.into_iter().map(|(field, _)| field).collect();
    }
}

/// What the sweeps of a light add up per grid point before [`finish`]: sum w direct, sum w T_f (RGB),
/// sum w (T_f - direct) sigma_f^2 (RGB), and the depth behind.
type Accumulator = [f32; 8];

/// Adds one direction's path integrals to a point's accumulator (twin of `accumulate` in the WGSL).
fn accumulate(acc: &mut Accumulator, d: &SweepDirection, f: &PathIntegrals, forward: bool) {
    if d.behind {
        acc[7] = f.tau;
        return;
    }
    let direct = (-f.tau).exp();
    acc[0] += d.weight * direct;
    if forward {
        for c in 0..3 {
            let tf = (-f.loss(c)).exp();
            let s = d.weight * (tf - direct).max(0.0);
            acc[1 + c] += d.weight * tf;
            acc[4 + c] += s * forward_spread_weighted(f.mass[c], f.spread[c]);
        }
    }
}

/// A point's stored value from its accumulator (twin of `finish` in the WGSL): transmittances as
/// logarithms floored at [`GRID_MIN_TRANSMITTANCE`] (ln T at most 0), sigma_f^2 the forward-scattered light's average.
fn finish(acc: &Accumulator, forward: bool) -> GridShadow {
    let ln = |t: f32| t.max(GRID_MIN_TRANSMITTANCE).ln();
    // At most 0: the GPU keeps the occluder flag in its sign bit (`grid_ln_t_stored`).
    let t = ln(acc[0]).min(0.0);
    if !forward {
        return GridShadow {
            transmittance: t,
            transmittance_f: [t; 3],
            sigma_f2: [0.0; 3],
            depth_behind: 0.0,
        };
    }
    GridShadow {
        transmittance: t,
        transmittance_f: std::array::from_fn(|c| ln(acc[1 + c])),
        sigma_f2: std::array::from_fn(|c| acc[4 + c] / (acc[1 + c] - acc[0]).max(1e-12)),
        depth_behind: acc[7],
    }
}

/// Every grid point's stored value for one light (logarithms, as the GPU grid holds them): the
/// sweeps of [`sweep_directions`] over the grid's [`MidplaneSamples`], combined as
/// [`super::grid::srbf_forward`] combines its cones.
pub fn sweep_light(
    grid: &ShadowGrid,
    src: &GridSources,
    samples: &MidplaneSamples,
    centre: Vec3,
    lambda: f32,
) -> Vec<GridShadow> {
    let forward = src.forward.is_some();
    let table = src.forward.map(|(_, t)| t);
    let mut acc = vec![[0f32; 8]; grid.point_count()];
    for d in sweep_directions(centre, lambda, forward) {
        sweep(grid, samples, table, d.omega, src.skip, d.behind, |i, f| {
            accumulate(&mut acc[i], &d, f, forward);
        });
    }
    acc.iter()
        .enumerate()
        .map(|(i, a)| {
            let mut g = finish(a, forward);
            if src.occluder.is_some_and(|v| v.inside_solid(grid.point(i))) {
                g.depth_behind = GRID_INSIDE_SOLID;
            }
            g
        })
        .collect()
}

/// The CPU grid is built here, by the sweeps, so that the grid's types need nothing of them.
impl GridValues {
    /// The values for lights given as (centre direction, lambda).
    pub fn build(grid: ShadowGrid, src: &GridSources, lights: &[(Vec3, f32)]) -> Self {
        let volume = src.forward.map(|(v, _)| v).or(src.occluder);
        let samples = MidplaneSamples::build(&grid, src.pyramid, volume);
        Self {
            grid,
            lights: lights
                .iter()
                .map(|&(centre, lambda)| sweep_light(&grid, src, &samples, centre, lambda))
                .collect(),
        }
    }
}
