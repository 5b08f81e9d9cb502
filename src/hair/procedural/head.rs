//! The generated head: an ellipsoid skull with a scalp region bounded by a hairline.
//! Face towards +Z, crown towards +Y, centre at the origin, centimetres.

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

impl Head {
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

    /// Whether the unit direction from the centre lies on the scalp: above a hairline that sits at
    /// ~55 degrees from the crown over the forehead, ~95 behind (the nape) and ~80 at the sides.
    pub fn on_scalp(&self, dir: Vec3) -> bool {
        let polar = dir.y.clamp(-1.0, 1.0).acos().to_degrees();
        let azimuth = dir.x.atan2(dir.z); // 0 at the face, +-pi at the back
        let limit = 75.0 - 20.0 * azimuth.cos();
        polar < limit
    }
}
