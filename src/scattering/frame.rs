//! The fiber frame and angle conventions (Marschner et al. 2003, Sec. 2; docs/hair-model.md,
//! "Frame and angles").
//!
//! This is the one definition used everywhere in strandlight:
//! - `u` is the fiber tangent, pointing from root to tip; `v` and `w` span the normal plane.
//! - The longitudinal inclination theta is the angle from the normal plane, in [-pi/2, pi/2]:
//!   `sin(theta) = dot(omega, u)`.
//! - The azimuth phi is measured inside the normal plane from `v` towards `w`:
//!   `omega = sin(theta) u + cos(theta) (cos(phi) v + sin(phi) w)`.
//! - Both omega_i (towards the light) and omega_o (towards the viewer) point away from the fiber.
//! - theta_h = (theta_i + theta_o)/2, theta_d = (theta_o - theta_i)/2, phi = phi_o - phi_i,
//!   phi_h = (phi_i + phi_o)/2.

use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// A direction in the fiber frame, as the two Marschner angles (radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FiberAngles {
    /// Longitudinal inclination from the normal plane, [-pi/2, pi/2].
    pub theta: f64,
    /// Azimuth in the normal plane, (-pi, pi].
    pub phi: f64,
}

impl FiberAngles {
    pub fn new(theta: f64, phi: f64) -> Self {
        Self { theta, phi }
    }

    /// Unit vector in fiber-frame coordinates (x = v, y = w, z = u).
    pub fn to_local(self) -> DVec3 {
        let (st, ct) = self.theta.sin_cos();
        let (sp, cp) = self.phi.sin_cos();
        DVec3::new(ct * cp, ct * sp, st)
    }

    /// Angles of a fiber-frame vector (x = v, y = w, z = u); need not be normalised.
    pub fn from_local(d: DVec3) -> Self {
        let d = d.normalize();
        Self {
            theta: d.z.clamp(-1.0, 1.0).asin(),
            phi: d.y.atan2(d.x),
        }
    }
}

/// An orthonormal fiber frame in world space.
#[derive(Clone, Copy, Debug)]
pub struct FiberFrame {
    pub u: DVec3,
    pub v: DVec3,
    pub w: DVec3,
}

impl FiberFrame {
    /// A frame from the tangent alone; `v` is any unit vector orthogonal to `u`
    /// (the model is isotropic in azimuth for a = 1; with eccentricity the caller picks `v`
    /// as the major axis through [`FiberFrame::with_normal`]).
    pub fn from_tangent(u: DVec3) -> Self {
        let u = u.normalize();
        let helper = if u.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        Self::with_normal(u, helper)
    }

    /// A frame whose `v` is the component of `n` orthogonal to `u`.
    pub fn with_normal(u: DVec3, n: DVec3) -> Self {
        let u = u.normalize();
        let v = (n - u * n.dot(u)).normalize();
        let w = u.cross(v);
        Self { u, v, w }
    }

    /// Angles of a world-space direction in this frame.
    pub fn angles(&self, omega: DVec3) -> FiberAngles {
        FiberAngles::from_local(DVec3::new(
            omega.dot(self.v),
            omega.dot(self.w),
            omega.dot(self.u),
        ))
    }

    /// World-space direction of fiber-frame angles.
    pub fn direction(&self, a: FiberAngles) -> DVec3 {
        let l = a.to_local();
        self.v * l.x + self.w * l.y + self.u * l.z
    }
}

/// Half and difference angles of a pair of directions (Marschner 2003, Sec. 2.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfAngles {
    /// theta_h = (theta_i + theta_o)/2
    pub theta_h: f64,
    /// theta_d = (theta_o - theta_i)/2
    pub theta_d: f64,
    /// phi = phi_o - phi_i, wrapped to (-pi, pi]
    pub phi: f64,
    /// phi_h = (phi_i + phi_o)/2 (used by eccentricity)
    pub phi_h: f64,
}

impl HalfAngles {
    pub fn new(i: FiberAngles, o: FiberAngles) -> Self {
        Self {
            theta_h: 0.5 * (i.theta + o.theta),
            theta_d: 0.5 * (o.theta - i.theta),
            phi: wrap_angle(o.phi - i.phi),
            phi_h: 0.5 * (i.phi + o.phi),
        }
    }
}

/// Wraps an angle to (-pi, pi].
pub fn wrap_angle(x: f64) -> f64 {
    let mut y = (x + PI).rem_euclid(TAU) - PI;
    if y <= -PI {
        y += TAU;
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_round_trip_through_world_space() {
        let frame = FiberFrame::from_tangent(DVec3::new(0.3, -0.8, 0.5));
        for &(t, p) in &[(0.1, 0.2), (-1.2, 3.0), (0.7, -2.5), (1.5, 0.0)] {
            let a = FiberAngles::new(t, p);
            let b = frame.angles(frame.direction(a));
            assert!((a.theta - b.theta).abs() < 1e-12 && wrap_angle(a.phi - b.phi).abs() < 1e-12);
        }
        let d = frame.direction(FiberAngles::new(0.4, 0.0));
        assert!((d.dot(frame.u) - 0.4f64.sin()).abs() < 1e-12);
    }

    #[test]
    fn wrap_is_in_half_open_interval() {
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(0.5 - 4.0 * PI) - 0.5).abs() < 1e-12);
    }
}
