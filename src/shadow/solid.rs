//! An occluder (the head) as an opaque solid in the fiber-density volume, so that the light-space
//! transmittance sees it as it sees the hair: hair on the far side of the head from a light is dark.
//!
//! Each voxel gets the fraction of it inside the closed mesh (2 x 2 x 2 sub-samples, inside by the
//! parity of the mesh's crossings along +x), and the volume's resolve adds the extinction
//! `SOLID_DEPTH_PER_VOXEL * fraction / voxel` (isotropic: no orientation tensor) with the absorption
//! `SOLID_SIGMA_A`, the forward table's last (a_f ~ 0: nothing is forward-scattered through skin).

use super::voxels::VolumeGrid;
use crate::hair::TriangleMesh;

/// Expected crossings per voxel of path through a wholly solid voxel (e^-8 = 3e-4 per voxel).
pub const SOLID_DEPTH_PER_VOXEL: f32 = 8.0;
/// The solid's absorption, cm^-1: the forward table's largest (its a_f is ~0).
pub const SOLID_SIGMA_A: f32 = crate::scattering::dual_terms::SIGMA_MAX;
/// Sub-samples per voxel axis.
const SUB: usize = 2;

/// The fraction of each voxel of `grid` inside `mesh` (x fastest, as the volume). A line that crosses
/// the mesh an odd number of times (an open mesh) leaves its last crossing unpaired: only closed
/// intervals count as inside.
pub fn solid_fraction(grid: &VolumeGrid, mesh: &TriangleMesh) -> Vec<f32> {
    let [nx, ny, nz] = grid.dims;
    let mut fraction = vec![0f32; grid.voxel_count()];
    let (ly, lz) = (ny * SUB, nz * SUB);
    // Sample lines along +x at sub-sample centres in y and z, nudged off the exact lattice so that a
    // generated mesh's vertices never lie on a line.
    let line_y = |j: usize| grid.origin.y + grid.voxel * ((j as f32 + 0.5) / SUB as f32 + 1.3e-4);
    let line_z = |k: usize| grid.origin.z + grid.voxel * ((k as f32 + 0.5) / SUB as f32 + 2.1e-4);
    let index = |v: f32, o: f32| ((v - o) / grid.voxel * SUB as f32 - 0.5).ceil().max(0.0) as usize;
    let mut crossings: Vec<Vec<f32>> = vec![Vec::new(); ly * lz];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        let (j0, k0) = (index(lo.y, grid.origin.y), index(lo.z, grid.origin.z));
        for k in k0..lz {
            let z = line_z(k);
            if z > hi.z {
                break;
            }
            for j in j0..ly {
                let y = line_y(j);
                if y > hi.y {
                    break;
                }
                // Barycentrics of (y, z) in the triangle's projection onto the y-z plane.
                let d = (b.y - a.y) * (c.z - a.z) - (c.y - a.y) * (b.z - a.z);
                if d.abs() < 1e-20 {
                    continue;
                }
                let u = ((y - a.y) * (c.z - a.z) - (c.y - a.y) * (z - a.z)) / d;
                let v = ((b.y - a.y) * (z - a.z) - (y - a.y) * (b.z - a.z)) / d;
                if u < 0.0 || v < 0.0 || u + v > 1.0 {
                    continue;
                }
                crossings[k * ly + j].push(a.x + u * (b.x - a.x) + v * (c.x - a.x));
            }
        }
    }
    let weight = 1.0 / (SUB * SUB * SUB) as f32;
    for (line, xs) in crossings.iter_mut().enumerate() {
        if xs.len() < 2 {
            continue;
        }
        xs.sort_by(f32::total_cmp);
        let (j, k) = (line % ly, line / ly);
        let row = ((k / SUB) * ny + j / SUB) * nx;
        for pair in xs.chunks_exact(2) {
            let (x0, x1) = (pair[0], pair[1]);
            // Sub-samples along x inside [x0, x1).
            let first = index(x0, grid.origin.x);
            for s in first..nx * SUB {
                let x = grid.origin.x + grid.voxel * (s as f32 + 0.5) / SUB as f32;
                if x >= x1 {
                    break;
                }
                if x >= x0 {
                    fraction[row + s / SUB] += weight;
                }
            }
        }
    }
    fraction
}

/// The solid's extinction (crossings per cm) for a voxel fraction.
pub fn solid_extinction(fraction: f32, voxel: f32) -> f32 {
    SOLID_DEPTH_PER_VOXEL * fraction / voxel
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hair::procedural::Head;
    use glam::Vec3;

    #[test]
    fn a_head_fills_its_volume_and_nothing_else() {
        // The plain ellipsoid (no face), whose volume is known exactly.
        let head = Head {
            face: false,
            ..Head::default()
        };
        let mesh = head.mesh(24, false);
        let grid = VolumeGrid {
            origin: Vec3::splat(-12.0),
            voxel: 0.5,
            dims: [48, 48, 48],
        };
        let f = solid_fraction(&grid, &mesh);
        let inside: f64 = f.iter().map(|&x| x as f64).sum::<f64>() * 0.125;
        let r = head.radii;
        let exact = 4.0 / 3.0 * std::f64::consts::PI * (r.x * r.y * r.z) as f64;
        println!("solid volume {inside:.1} cm^3, ellipsoid {exact:.1} (the mesh is inscribed)");
        assert!(inside < exact && inside > 0.95 * exact, "{inside} {exact}");
        // Wholly inside at the centre, empty at the corners, every fraction in [0, 1].
        let at = |p: Vec3| {
            let q = ((p - grid.origin) / grid.voxel).floor();
            f[(q.z as usize * 48 + q.y as usize) * 48 + q.x as usize]
        };
        assert_eq!(at(Vec3::ZERO), 1.0);
        assert_eq!(at(Vec3::splat(-11.0)), 0.0);
        assert!(f.iter().all(|&x| (0.0..=1.0 + 1e-6).contains(&x)));
        // With the neck: more solid, below the skull.
        let with_neck = solid_fraction(&grid, &head.mesh(24, true));
        assert_eq!(at(Vec3::new(0.0, -11.5, 0.0)), 0.0);
        let q = ((Vec3::new(0.0, -11.5, 0.0) - grid.origin) / grid.voxel).floor();
        assert_eq!(
            with_neck[(q.z as usize * 48 + q.y as usize) * 48 + q.x as usize],
            1.0
        );
    }

    #[test]
    fn an_open_mesh_adds_only_closed_intervals() {
        // One triangle: every line crosses it at most once, so nothing is inside.
        let mesh = TriangleMesh {
            positions: vec![
                Vec3::new(0.0, -5.0, -5.0),
                Vec3::new(0.0, 5.0, -5.0),
                Vec3::new(0.0, 0.0, 5.0),
            ],
            triangles: vec![[0, 1, 2]],
        };
        let grid = VolumeGrid {
            origin: Vec3::splat(-6.0),
            voxel: 1.0,
            dims: [12, 12, 12],
        };
        assert!(solid_fraction(&grid, &mesh).iter().all(|&x| x == 0.0));
    }
}
