//! The generated head: an ellipsoid skull with a scalp region bounded by a hairline, and a face
//! (brow, eye sockets, nose, cheekbones, lips, chin, a jaw narrower than the skull, a nape turning in
//! towards the neck) as a relief of the ellipsoid below the hairline.
//! Face towards +Z, crown towards +Y, centre at the origin, centimetres.
//!
//! The head is star-shaped about its centre: the surface in a direction is the ellipsoid's point
//! scaled by `1 + relief`. The relief is exactly zero over the scalp and a little beyond it, so roots,
//! their normals and the hair resting on the skull see the plain ellipsoid.

use crate::hair::mesh::TriangleMesh;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct Head {
    pub centre: Vec3,
    /// Semi-axes (x: half width, y: half height, z: half depth), cm.
    pub radii: Vec3,
    /// Whether the face's relief is carved (false: the plain ellipsoid).
    pub face: bool,
}

impl Default for Head {
    fn default() -> Self {
        // An adult skull: about 15 cm wide, 22 cm tall, 19 cm deep.
        Self {
            centre: Vec3::ZERO,
            radii: Vec3::new(7.5, 11.0, 9.5),
            face: true,
        }
    }
}

/// Latitude rings of the generated head's mesh (80 vertices a ring: ~6k triangles with the neck);
/// fine enough for the nose and the lips, whose relief spans a few rings.
pub const HEAD_MESH_RINGS: usize = 40;

impl Head {
    /// The head as the renderer draws it: [`Head::mesh`] with [`HEAD_MESH_RINGS`] and the neck.
    pub fn occluder_mesh(&self) -> TriangleMesh {
        self.mesh(HEAD_MESH_RINGS, true)
    }

    /// Implicit value: < 1 inside, 1 on the surface (the squared distance from the centre over the
    /// surface's in the same direction).
    pub fn implicit(&self, p: Vec3) -> f32 {
        let v = p - self.centre;
        let base = (v / self.radii).length_squared();
        let k = 1.0 + self.relief(v.normalize_or(Vec3::Y));
        base / (k * k)
    }

    /// Surface point and outward normal in the direction `dir` (unit) from the centre.
    pub fn surface(&self, dir: Vec3) -> (Vec3, Vec3) {
        let relief = self.relief(dir);
        let p = self.centre + dir * self.ellipsoid_distance(dir) * (1.0 + relief);
        if relief == 0.0 {
            // The relief and its gradient vanish together (its bumps and mask are flat at their
            // edges): the ellipsoid's own normal, exactly.
            return (
                p,
                ((p - self.centre) / (self.radii * self.radii)).normalize(),
            );
        }
        (p, self.gradient(p).normalize_or(dir))
    }

    /// Pushes `p` radially out to the surface inflated by `margin` (relative), if inside it.
    pub fn push_out(&self, p: Vec3, margin: f32) -> Vec3 {
        let v = (p - self.centre) / self.radii;
        let r = v.length();
        let limit = 1.0 + margin;
        if r >= limit * (1.0 + self.relief((p - self.centre).normalize_or(Vec3::Y))) {
            return p;
        }
        // Over the skull, along the ellipsoid's scaled radius; where the face's relief is, along the
        // true radius (on which the relief is defined, so the result lies exactly on the surface).
        let v = if r > 1e-6 { v / r } else { Vec3::Y };
        let q = self.centre + v * limit * self.radii;
        let dir = (q - self.centre).normalize_or(Vec3::Y);
        if self.relief(dir) == 0.0 {
            return q;
        }
        let dir = (p - self.centre).normalize_or(Vec3::Y);
        self.centre + dir * self.ellipsoid_distance(dir) * (1.0 + self.relief(dir)) * limit
    }

    /// Distance from the centre to the ellipsoid along the unit direction `dir`.
    fn ellipsoid_distance(&self, dir: Vec3) -> f32 {
        1.0 / (dir / self.radii).length()
    }

    /// The implicit's gradient by central differences (where the relief is: its bumps have no
    /// convenient closed-form gradient, and this is needed only for a root's normal).
    fn gradient(&self, p: Vec3) -> Vec3 {
        let h = 0.01;
        let d = |e: Vec3| self.implicit(p + e * h) - self.implicit(p - e * h);
        Vec3::new(d(Vec3::X), d(Vec3::Y), d(Vec3::Z))
    }

    /// The face's relative change of the radius in the unit direction `dir` from the centre: zero
    /// over the scalp (up to a few degrees below the hairline), fading in below it.
    pub fn relief(&self, dir: Vec3) -> f32 {
        if !self.face {
            return 0.0;
        }
        let below = (self.polar_deg(dir) - self.hairline_deg(dir) - 3.0) / 12.0;
        let mask = smoothstep(below);
        if mask == 0.0 {
            return 0.0;
        }
        mask * face_relief((dir / self.radii).normalize())
    }

    fn polar_deg(&self, dir: Vec3) -> f32 {
        dir.y.clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// The hairline's polar angle (degrees from the crown) in the azimuth of `dir`: ~55 over the
    /// forehead, ~75 at the sides, ~95 behind (the nape).
    fn hairline_deg(&self, dir: Vec3) -> f32 {
        let azimuth = dir.x.atan2(dir.z); // 0 at the face, +-pi at the back
        75.0 - 20.0 * azimuth.cos()
    }

    /// The skull as a closed triangle mesh (outward winding, counter-clockwise seen from outside):
    /// latitude rings from the crown down, `2 rings` vertices each, carved by the face's relief. With
    /// a neck, the rings stop at the first one below the equator wholly inside the neck's circle, a
    /// flat annulus joins it to a neck (widening a little) that runs down to 1.75 half-heights below the centre (~10 cm
    /// below the jaw), and a
    /// disc closes it.
    pub fn mesh(&self, rings: usize, neck: bool) -> TriangleMesh {
        use std::f32::consts::{PI, TAU};
        let rings = rings.max(3);
        let n = 2 * rings;
        let neck_r = self.neck_radius();
        let around = |j: usize| {
            let az = TAU * j as f32 / n as f32;
            Vec3::new(az.sin(), 0.0, az.cos())
        };
        let ring = |i: usize| -> Vec<Vec3> {
            let p = PI * i as f32 / rings as f32;
            (0..n)
                .map(|j| self.carved(around(j) * p.sin() + Vec3::Y * p.cos()))
                .collect()
        };
        // The last skull ring lies wholly inside the neck's circle (the annulus does not fold).
        let inside_neck = |i: usize| {
            ring(i)
                .iter()
                .all(|v| (*v - self.centre).with_y(0.0).length() < neck_r)
        };
        let count = if neck {
            (rings / 2 + 1..=rings)
                .find(|&i| inside_neck(i))
                .unwrap_or(rings)
                + 1
        } else {
            rings + 1
        };
        let positions: Vec<Vec3> = (0..count).flat_map(ring).collect();
        let mut positions = positions;
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
            // The lowest vertex of the ring: the relief tilts it, and the annulus must not rise.
            let y0 = positions[top..]
                .iter()
                .map(|v| v.y)
                .fold(f32::MAX, f32::min);
            let bottom = self.centre.y - 1.75 * self.radii.y;
            let base = positions.len();
            // Widening a little towards the shoulders.
            for (y, r) in [(y0, neck_r), (bottom, 1.1 * neck_r)] {
                for j in 0..n {
                    positions.push(self.centre + around(j) * r + Vec3::Y * (y - self.centre.y));
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

    /// The point of the unit sphere `s` (the ellipsoid's parameter) moved onto the surface: the
    /// ellipsoid's point scaled by the relief in its direction.
    fn carved(&self, s: Vec3) -> Vec3 {
        let e = s * self.radii;
        self.centre + e * (1.0 + self.relief(e.normalize_or(Vec3::Y)))
    }

    /// The neck's radius: a slim adult neck's (~28 cm around) with a face (its jaw and nape turn in to
    /// meet it), less under the plain ellipsoid, whose round bottom narrows only near its pole.
    fn neck_radius(&self) -> f32 {
        let narrow = self.radii.x.min(self.radii.z);
        if self.face {
            0.6 * narrow
        } else {
            0.45 * narrow
        }
    }

    /// Whether the unit direction from the centre lies on the scalp: above a hairline that sits at
    /// ~55 degrees from the crown over the forehead, ~95 behind (the nape) and ~75 at the sides.
    pub fn on_scalp(&self, dir: Vec3) -> bool {
        self.polar_deg(dir) < self.hairline_deg(dir)
    }
}

/// Hermite smoothstep of `x` clamped to [0, 1]: flat at both ends.
fn smoothstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// A bump of height 1 at `centre` falling to 0 (flat) at `scale` away along each axis.
fn bump(s: Vec3, centre: Vec3, scale: Vec3) -> f32 {
    let d2 = ((s - centre) / scale).length_squared();
    if d2 >= 1.0 {
        0.0
    } else {
        (1.0 - d2) * (1.0 - d2)
    }
}

/// The face's features as relative radius changes, at the point `s` of the unit sphere the ellipsoid
/// is scaled from (x right, y up, z towards the face). Proportions after an adult head: brow at the
/// eyes' height plus a little, nose down to a third of the way to the chin, the jaw narrower than the
/// skull, the back of the head turning in above the neck.
fn face_relief(s: Vec3) -> f32 {
    let side = Vec3::new(s.x.abs(), s.y, s.z);
    let low = |from: f32, to: f32| smoothstep((from - s.y) / (from - to));
    // Below the cheekbones the face narrows towards the chin; behind, the skull turns in to the neck.
    let jaw = -0.3 * low(-0.05, -0.7) * s.x * s.x;
    let nape = -0.2 * low(-0.3, -0.85) * smoothstep(-s.z / 0.6);
    let features = [
        // (amplitude, centre, half extent)
        (0.05, Vec3::new(0.0, 0.16, 0.99), Vec3::new(0.6, 0.11, 0.3)), // brow ridge
        (
            -0.07,
            Vec3::new(0.33, 0.02, 0.94),
            Vec3::new(0.18, 0.12, 0.25),
        ), // eye sockets
        (0.2, Vec3::new(0.0, -0.18, 0.98), Vec3::new(0.1, 0.24, 0.25)), // nose bridge
        (
            0.09,
            Vec3::new(0.0, -0.34, 0.94),
            Vec3::new(0.12, 0.1, 0.25),
        ), // nose tip
        (
            0.05,
            Vec3::new(0.55, -0.15, 0.8),
            Vec3::new(0.22, 0.15, 0.3),
        ), // cheekbones
        (
            -0.04,
            Vec3::new(0.5, -0.45, 0.75),
            Vec3::new(0.2, 0.18, 0.3),
        ), // hollows under them
        (
            0.04,
            Vec3::new(0.0, -0.55, 0.84),
            Vec3::new(0.18, 0.08, 0.25),
        ), // lips
        (0.12, Vec3::new(0.0, -0.8, 0.6), Vec3::new(0.28, 0.17, 0.3)), // chin
    ];
    let carved: f32 = features.iter().map(|&(a, c, e)| a * bump(side, c, e)).sum();
    jaw + nape + carved
}
