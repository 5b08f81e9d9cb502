//! The generated head: an ellipsoid skull with a scalp region bounded by a hairline.
//! Face towards +Z, crown towards +Y, centre at the origin, centimetres.

use crate::hair::mesh::TriangleMesh;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct Head {
    pub centre: Vec3,
    /// Semi-axes (x: half width, y: half height, z: half depth), cm.
    pub radii: Vec3,
}

impl Default for Head {
    fn default() -> Self {
        // An adult skull: about 15 cm wide, 22 cm tall, 19 cm deep.
        Self {
            centre: Vec3::ZERO,
            radii: Vec3::new(7.5, 11.0, 9.5),
        }
    }
}

/// Latitude rings of the generated head's mesh (64 vertices a ring: ~4k triangles with the neck).
pub const HEAD_MESH_RINGS: usize = 32;

impl Head {
    /// The head as the renderer draws it: [`Head::mesh`] with [`HEAD_MESH_RINGS`] and the neck.
    pub fn occluder_mesh(&self) -> TriangleMesh {
        self.mesh(HEAD_MESH_RINGS, true)
    }

    /// Implicit value: < 1 inside, 1 on the surface.
    pub fn implicit(&self, p: Vec3) -> f32 {
        ((p - self.centre) / self.radii).length_squared()
    }

    /// Surface point and outward normal in the direction `dir` (unit) from the centre.
    pub fn surface(&self, dir: Vec3) -> (Vec3, Vec3) {
        let q = dir / self.radii;
        let t = 1.0 / q.length();
        let p = self.centre + dir * t;
        let n = ((p - self.centre) / (self.radii * self.radii)).normalize();
        (p, n)
    }

    /// Pushes `p` radially out to the surface inflated by `margin` (relative), if inside it.
    pub fn push_out(&self, p: Vec3, margin: f32) -> Vec3 {
        let v = (p - self.centre) / self.radii;
        let r = v.length();
        let limit = 1.0 + margin;
        if r >= limit {
            return p;
        }
        let v = if r > 1e-6 { v / r } else { Vec3::Y };
        self.centre + v * limit * self.radii
    }

    /// The skull as a closed triangle mesh (outward winding, counter-clockwise seen from outside):
    /// latitude rings from the crown down, `2 rings` vertices each. With a neck, the rings stop at the
    /// first one below the equator inside the neck's circle (radius 0.45 of the head's narrower half
    /// axis), a flat annulus joins it to a cylinder that runs down to two half-heights below the
    /// centre, and a disc closes it.
    pub fn mesh(&self, rings: usize, neck: bool) -> TriangleMesh {
        use std::f32::consts::{PI, TAU};
        let rings = rings.max(3);
        let n = 2 * rings;
        let narrow = self.radii.x.min(self.radii.z);
        let wide = self.radii.x.max(self.radii.z);
        let neck_r = 0.45 * narrow;
        let polar = |i: usize| PI * i as f32 / rings as f32;
        // The last skull ring lies wholly inside the neck's circle (the annulus does not fold).
        let count = if neck {
            (rings / 2 + 1..=rings)
                .find(|&i| polar(i).sin() * wide < neck_r)
                .unwrap_or(rings)
                + 1
        } else {
            rings + 1
        };
        let around = |j: usize| {
            let az = TAU * j as f32 / n as f32;
            Vec3::new(az.sin(), 0.0, az.cos())
        };
        let mut positions = Vec::new();
        for i in 0..count {
            let p = polar(i);
            for j in 0..n {
                let dir = around(j) * p.sin() + Vec3::Y * p.cos();
                positions.push(self.centre + dir * self.radii);
            }
        }
        let mut triangles = Vec::new();
        // Quads between two rings starting at vertices `upper` and `lower`.
        let band = |triangles: &mut Vec<[u32; 3]>, upper: usize, lower: usize| {
            for j in 0..n {
                let k = (j + 1) % n;
                let (a, b, c, d) = (upper + j, upper + k, lower + j, lower + k);
                triangles.push([a as u32, c as u32, b as u32]);
                triangles.push([b as u32, c as u32, d as u32]);
            }
        };
        for i in 0..count - 1 {
            band(&mut triangles, i * n, (i + 1) * n);
        }
        if neck {
            let top = (count - 1) * n;
            let y0 = positions[top].y;
            let bottom = self.centre.y - 2.0 * self.radii.y;
            let base = positions.len();
            for y in [y0, bottom] {
                for j in 0..n {
                    positions
                        .push(self.centre + around(j) * neck_r + Vec3::Y * (y - self.centre.y));
                }
            }
            band(&mut triangles, top, base);
            band(&mut triangles, base, base + n);
            let centre = positions.len() as u32;
            positions.push(Vec3::new(self.centre.x, bottom, self.centre.z));
            let low = base + n;
            for j in 0..n {
                triangles.push([(low + j) as u32, centre, (low + (j + 1) % n) as u32]);
            }
        }
        TriangleMesh {
            positions,
            triangles,
        }
    }

    /// Whether the unit direction from the centre lies on the scalp: above a hairline that sits at
    /// ~55 degrees from the crown over the forehead, ~95 behind (the nape) and ~80 at the sides.
    pub fn on_scalp(&self, dir: Vec3) -> bool {
        let polar = dir.y.clamp(-1.0, 1.0).acos().to_degrees();
        let azimuth = dir.x.atan2(dir.z); // 0 at the face, +-pi at the back
        let limit = 75.0 - 20.0 * azimuth.cos();
        polar < limit
    }
}
