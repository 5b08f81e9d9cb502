//! Scene normalisation. **World units are centimetres, +Y is up** (the one place this is stated;
//! everything after loading assumes it).
//!
//! Files come Z-up or Y-up, in centimetres, millimetres or metres. glTF is +Y up by specification and
//! TressFX by engine convention; for cyHair the up axis is detected as the axis of largest extent,
//! oriented from tips to roots. Units come from the bounding-box extent of the hairstyle (a head of
//! hair spans roughly 15 to 150 cm). Both can be overridden (`--up`, `--units`, `--scale`).

use glam::Vec3;
use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
pub enum UpAxis {
    #[value(name = "y")]
    #[serde(rename = "+Y")]
    PosY,
    #[value(name = "z")]
    #[serde(rename = "+Z")]
    PosZ,
    #[value(name = "x")]
    #[serde(rename = "+X")]
    PosX,
    #[value(name = "-y")]
    #[serde(rename = "-Y")]
    NegY,
    #[value(name = "-z")]
    #[serde(rename = "-Z")]
    NegZ,
    #[value(name = "-x")]
    #[serde(rename = "-X")]
    NegX,
}

impl UpAxis {
    /// Rotation (as a function) taking this axis to +Y, right-handed.
    pub fn to_y_up(self, p: Vec3) -> Vec3 {
        match self {
            UpAxis::PosY => p,
            UpAxis::PosZ => Vec3::new(p.x, p.z, -p.y),
            UpAxis::PosX => Vec3::new(-p.y, p.x, p.z),
            UpAxis::NegY => Vec3::new(p.x, -p.y, -p.z),
            UpAxis::NegZ => Vec3::new(p.x, -p.z, p.y),
            UpAxis::NegX => Vec3::new(p.y, -p.x, p.z),
        }
    }

    fn from_axis(axis: usize, positive: bool) -> Self {
        match (axis, positive) {
            (0, true) => UpAxis::PosX,
            (0, false) => UpAxis::NegX,
            (1, true) => UpAxis::PosY,
            (1, false) => UpAxis::NegY,
            (2, true) => UpAxis::PosZ,
            _ => UpAxis::NegZ,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    #[value(name = "m")]
    Metres,
    #[value(name = "cm")]
    Centimetres,
    #[value(name = "mm")]
    Millimetres,
}

impl Units {
    /// Factor to centimetres.
    pub fn to_cm(self) -> f32 {
        match self {
            Units::Metres => 100.0,
            Units::Centimetres => 1.0,
            Units::Millimetres => 0.1,
        }
    }
}

/// Detects the up axis of a hairstyle: the axis of largest extent (hair hangs; heads are taller
/// than wide), positive unless tips hang far above roots. glTF (+Y by specification) and TressFX (+Y by
/// engine convention) do not need this.
pub fn detect_up(roots: &[Vec3], tips: &[Vec3], bounds: (Vec3, Vec3)) -> UpAxis {
    let n = roots.len().max(1) as f32;
    let mean_drop: Vec3 = roots.iter().zip(tips).map(|(r, t)| *r - *t).sum::<Vec3>() / n;
    let e = bounds.1 - bounds.0;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    // Negative up axes are rare; flip only when tips hang far above roots (a mohawk's stand-up
    // strands must not flip a +Y file).
    UpAxis::from_axis(axis, mean_drop[axis] >= -0.25 * e[axis])
}

/// Detects units from the largest bounding-box extent: under 5 units is metres, over 500 is
/// millimetres, otherwise centimetres.
pub fn detect_units(extent: f32) -> Units {
    if extent < 5.0 {
        Units::Metres
    } else if extent > 500.0 {
        Units::Millimetres
    } else {
        Units::Centimetres
    }
}

/// How a file was brought into world space, for reports.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Normalization {
    pub up: UpAxis,
    /// "given", "detected" or "format convention".
    pub up_source: &'static str,
    pub units: Units,
    pub units_detected: bool,
    /// Centimetres per unit as the file declares them (USD `metersPerUnit`); where set, they
    /// replace `units`.
    pub declared_cm_per_unit: Option<f32>,
    /// Extra user scale applied after the unit conversion.
    pub scale: f32,
}

impl Normalization {
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.up.to_y_up(p) * self.length_factor()
    }

    pub fn length_factor(&self) -> f32 {
        self.declared_cm_per_unit
            .unwrap_or_else(|| self.units.to_cm())
            * self.scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_take_the_axis_to_y_and_keep_handedness() {
        for up in [
            UpAxis::PosX,
            UpAxis::PosY,
            UpAxis::PosZ,
            UpAxis::NegX,
            UpAxis::NegY,
            UpAxis::NegZ,
        ] {
            let axis = match up {
                UpAxis::PosX => Vec3::X,
                UpAxis::PosY => Vec3::Y,
                UpAxis::PosZ => Vec3::Z,
                UpAxis::NegX => -Vec3::X,
                UpAxis::NegY => -Vec3::Y,
                UpAxis::NegZ => -Vec3::Z,
            };
            assert_eq!(up.to_y_up(axis), Vec3::Y, "{up:?}");
            let (a, b) = (Vec3::new(0.3, 0.1, 0.7), Vec3::new(-0.2, 0.9, 0.4));
            let c = up.to_y_up(a.cross(b));
            assert!((c - up.to_y_up(a).cross(up.to_y_up(b))).length() < 1e-6);
        }
    }

    #[test]
    fn detection() {
        let roots = [Vec3::new(0.0, 0.0, 10.0), Vec3::new(1.0, 1.0, 9.0)];
        let tips = [Vec3::new(0.0, 2.0, -20.0), Vec3::new(1.0, -1.0, -25.0)];
        let bounds = (Vec3::new(0.0, -1.0, -25.0), Vec3::new(1.0, 2.0, 10.0));
        assert_eq!(detect_up(&roots, &tips, bounds), UpAxis::PosZ);
        assert_eq!(detect_units(0.9), Units::Metres);
        assert_eq!(detect_units(60.0), Units::Centimetres);
        assert_eq!(detect_units(900.0), Units::Millimetres);
    }
}
