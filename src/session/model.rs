//! The session: everything that defines a picture, as the editor saves it and `render --session` reads
//! it. Plain data (serde), no GPU state; the CLI and the editor assemble scenes from it the same way
//! ([`super::assemble`]).

use crate::envmap::SrbfSet;
use crate::hair::procedural::Style;
use crate::paint::sigma_a_from_colour;
use crate::render::{Camera, RenderSettings};
use crate::scattering::params::sigma_a_from_melanin;
use crate::scattering::{HairParams, LongitudinalModel, Preset};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// The session file's format version.
pub const SESSION_VERSION: u32 = 1;

/// Where the hair comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum HairSource {
    /// The procedural generator around its generated head.
    Generated {
        style: Style,
        strands: usize,
        points: usize,
        seed: u64,
        /// Strand length range (min, max), cm (absent: the style's).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        length: Option<[f32; 2]>,
        /// 0 (none) to 1 (tips meet their clump's guide) (absent: the generator's 0.4).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        clumping: Option<f32>,
        /// 0 (none) to 1 (strong random tilts towards the tip) (absent: the generator's 0.1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        frizz: Option<f32>,
    },
    /// A hair file (.hair, .tfx, .gltf, .glb); the BLAKE3 of its bytes when it was chosen tells a
    /// changed file on reopening.
    File {
        path: PathBuf,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        blake3: Option<String>,
        /// A USD stage's prim whose curves are the hair (None: the default prim).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        prim: Option<String>,
        /// The time code time-sampled curves are read at (None: the earliest sample).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        time: Option<f64>,
    },
}

impl HairSource {
    /// The generator's settings with its defaults for the shape (length, clumping, frizz).
    pub fn generated(style: Style, strands: usize, points: usize, seed: u64) -> Self {
        HairSource::Generated {
            style,
            strands,
            points,
            seed,
            length: None,
            clumping: None,
            frizz: None,
        }
    }

    /// The generator's parameters (None for a file).
    pub fn style_params(&self) -> Option<crate::hair::procedural::StyleParams> {
        let HairSource::Generated {
            style,
            strands,
            points,
            seed,
            length,
            clumping,
            frizz,
        } = *self
        else {
            return None;
        };
        let mut p = crate::hair::procedural::StyleParams::new(style, strands, points, seed);
        if let Some([a, b]) = length {
            p.length = (a, b);
        }
        p.clumping = clumping.unwrap_or(p.clumping);
        p.frizz = frizz.unwrap_or(p.frizz);
        Some(p)
    }
}

/// Where the lights come from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum EnvironmentSource {
    /// The project's sunny sky and its committed 40-light fit.
    Builtin,
    /// An .hdr / .exr (fitted with `lights` SRBFs) or .srbf.json. The fitted lights are kept so that the
    /// session reopens without refitting.
    File {
        path: PathBuf,
        lights: usize,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        blake3: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        fitted: Option<Box<SrbfSet>>,
    },
}

/// How one end of the strands gets its absorption sigma_a (per unit fibre radius, RGB).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Absorption {
    /// Eumelanin and pheomelanin concentrations (d'Eon et al. 2011).
    Melanin { eumelanin: f64, pheomelanin: f64 },
    /// A dye colour (linear RGB, the multiple-scattering albedo) inverted by Chiang et al. 2016 Eq. 9
    /// with azimuthal roughness beta_n.
    Dye { colour: [f64; 3], beta_n: f64 },
    /// sigma_a itself.
    SigmaA { sigma_a: [f64; 3] },
}

impl Absorption {
    pub fn sigma_a(&self) -> [f64; 3] {
        match *self {
            Absorption::Melanin {
                eumelanin,
                pheomelanin,
            } => sigma_a_from_melanin(eumelanin, pheomelanin),
            Absorption::Dye { colour, beta_n } => sigma_a_from_colour(colour, beta_n),
            Absorption::SigmaA { sigma_a } => sigma_a,
        }
    }

    pub fn from_preset(preset: Preset) -> Self {
        let (eumelanin, pheomelanin) = preset.melanin();
        Absorption::Melanin {
            eumelanin,
            pheomelanin,
        }
    }
}

/// The hair look: Marschner's parameters (their sigma_a is replaced by the absorption below), the
/// absorption at the roots and tips, per-strand variation, Zinke's density factors and the
/// longitudinal function.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Look {
    pub params: HairParams,
    pub root: Absorption,
    /// None: the same as the root (no gradient).
    #[serde(default)]
    pub tip: Option<Absorption>,
    /// Per-strand log-normal variation of sigma_a (standard deviation of ln sigma_a).
    #[serde(default)]
    pub strand_variation: f32,
    #[serde(default = "one")]
    pub variation_seed: u64,
    pub d_f: f32,
    pub d_b: f32,
    #[serde(default)]
    pub longitudinal: LongitudinalModel,
    /// Multiplies every fiber's diameter (the file's, or 70 um): the fiber density volume's optical
    /// depth and the ribbons' width in the view scale with it.
    #[serde(default = "unit_scale", skip_serializing_if = "is_unit_scale")]
    pub thickness_scale: f32,
}

fn one() -> u64 {
    1
}

fn unit_scale() -> f32 {
    1.0
}

fn is_unit_scale(s: &f32) -> bool {
    *s == 1.0
}

impl Look {
    pub fn from_preset(preset: Preset) -> Self {
        Self {
            params: preset.params(),
            root: Absorption::from_preset(preset),
            tip: None,
            strand_variation: 0.0,
            variation_seed: 1,
            d_f: 0.7,
            d_b: 0.7,
            longitudinal: LongitudinalModel::Normalized,
            thickness_scale: 1.0,
        }
    }

    /// Checks every value, naming the offending one.
    /// A preset's melanin and lobe parameters over this look (the editor's preset buttons): the
    /// fibre's other settings stay, a root-to-tip gradient goes.
    pub fn apply_preset(&mut self, preset: Preset) {
        let p = Look::from_preset(preset);
        self.params = p.params;
        self.root = p.root;
        self.tip = None;
    }

    pub fn validate(&self) -> Result<(), String> {
        self.params.validate()?;
        for (name, a) in [("root", Some(self.root)), ("tip", self.tip)] {
            let Some(a) = a else { continue };
            if a.sigma_a().iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
                return Err(format!("the {name} absorption must be finite and >= 0"));
            }
        }
        if !(0.0..=1.0).contains(&self.d_f) || !(0.0..=1.0).contains(&self.d_b) {
            return Err(format!(
                "d_f and d_b lie in [0, 1], got {} and {}",
                self.d_f, self.d_b
            ));
        }
        if !(self.thickness_scale.is_finite() && (0.05..=20.0).contains(&self.thickness_scale)) {
            return Err(format!(
                "the fiber thickness scale lies in [0.05, 20], got {}",
                self.thickness_scale
            ));
        }
        if !(self.strand_variation.is_finite() && (0.0..=2.0).contains(&self.strand_variation)) {
            return Err(format!(
                "strand variation lies in [0, 2], got {}",
                self.strand_variation
            ));
        }
        Ok(())
    }
}

impl Default for Look {
    fn default() -> Self {
        Self::from_preset(Preset::Brown)
    }
}

/// The camera as the session keeps it: an orbit whose target and distance are framed around the hair
/// until the user moves them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewCamera {
    /// Degrees about +Y; 0 looks along -Z.
    pub yaw: f32,
    /// Degrees of elevation.
    pub pitch: f32,
    /// Vertical field of view, degrees.
    pub fov_y: f32,
    /// None: the hair's bounding-box centre.
    #[serde(default)]
    pub target: Option<[f32; 3]>,
    /// None: far enough to frame the hair.
    #[serde(default)]
    pub distance: Option<f32>,
}

impl Default for ViewCamera {
    fn default() -> Self {
        Self {
            yaw: 35.0,
            pitch: 10.0,
            fov_y: 30.0,
            target: None,
            distance: None,
        }
    }
}

impl ViewCamera {
    /// The orbit camera for a hair with bounds (lo, hi) and an image of this aspect.
    pub fn resolve(&self, lo: glam::Vec3, hi: glam::Vec3, aspect: f32) -> Camera {
        // As `render --fov` does: framed at the default field of view, then the session's.
        let mut c = Camera::framing(lo, hi, self.yaw, self.pitch, aspect, 0.9);
        c.fov_y = self.fov_y;
        if let Some(t) = self.target {
            c.target = t;
        }
        if let Some(d) = self.distance {
            c.distance = d;
        }
        c
    }

    /// Keeps a resolved camera (after the user moved it).
    pub fn from_camera(c: &Camera) -> Self {
        Self {
            yaw: c.yaw,
            pitch: c.pitch,
            fov_y: c.fov_y,
            target: Some(c.target),
            distance: Some(c.distance),
        }
    }
}

/// What a still is rendered with (the editor's viewport uses its own size).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    /// The occluder's (the head's) samples per pixel (2 or 4).
    pub samples: u32,
    /// Hair fragments kept per pixel by the K-buffer (1 to 32) and what becomes of the rest.
    #[serde(default = "default_fragments")]
    pub fragments: u32,
    #[serde(default)]
    pub tail: crate::render::passes::kbuffer::Tail,
    /// Exposure in stops (applied to the EXR as `render --exposure` does).
    pub exposure: f32,
    pub shadows: bool,
    pub multiple_scattering: bool,
    pub volume_resolution: u32,
    pub shadow_grid_resolution: u32,
    /// What the viewport and the PNG show behind the hair (the EXR writes it only when `render
    /// --background` asks).
    #[serde(default)]
    pub background: crate::render::passes::background::Background,
}

fn default_fragments() -> u32 {
    crate::render::passes::kbuffer::DEFAULT_FRAGMENTS
}

impl Default for RenderOptions {
    fn default() -> Self {
        let s = RenderSettings::default();
        Self {
            width: s.width,
            height: s.height,
            samples: s.samples,
            fragments: s.fragments,
            tail: s.tail,
            exposure: s.exposure,
            shadows: s.shadows,
            multiple_scattering: s.multiple_scattering,
            volume_resolution: s.volume_resolution,
            shadow_grid_resolution: s.shadow_grid_resolution,
            background: Default::default(),
        }
    }
}

impl RenderOptions {
    /// The renderer's settings at a given size.
    pub fn settings(&self, width: u32, height: u32) -> RenderSettings {
        RenderSettings {
            width,
            height,
            samples: self.samples,
            fragments: self.fragments,
            tail: self.tail,
            exposure: self.exposure,
            shadows: self.shadows,
            multiple_scattering: self.multiple_scattering,
            volume_resolution: self.volume_resolution,
            shadow_grid_resolution: self.shadow_grid_resolution,
            ..Default::default()
        }
    }
}

/// Everything that defines a picture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Session {
    pub version: u32,
    pub hair: HairSource,
    pub environment: EnvironmentSource,
    /// Turn of the environment about +Y, degrees.
    #[serde(default)]
    pub env_yaw: f64,
    pub look: Look,
    #[serde(default)]
    pub camera: ViewCamera,
    #[serde(default)]
    pub render: RenderOptions,
    /// A paint layer (SLPAINT1) applied over the look's absorption: the file the editor saves its
    /// layer to beside the session, and `render --paint` reads.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub paint: Option<PathBuf>,
    /// The paint layer in memory (the editor's brush; read from `paint` when the session is
    /// opened). When present it is the session's paint, whatever the file holds.
    #[serde(skip)]
    pub paint_layer: Option<crate::paint::SharedLayer>,
    /// The head (or another mesh) the hair sits on: drawn, shaded and shadowing the hair.
    #[serde(default)]
    pub occluder: OccluderOptions,
}

/// The occluder: the generated head for generated hair, the mesh a glTF hair file carries, or a mesh
/// file of its own (in the hair file's units and axes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OccluderOptions {
    pub show: bool,
    /// An OBJ or glTF mesh instead of the hair's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<PathBuf>,
    /// Diffuse albedo (linear RGB).
    pub albedo: [f32; 3],
}

impl Default for OccluderOptions {
    fn default() -> Self {
        Self {
            show: true,
            mesh: None,
            albedo: crate::render::passes::occluder::SKIN_ALBEDO,
        }
    }
}

impl OccluderOptions {
    pub fn validate(&self) -> Result<(), String> {
        if self
            .albedo
            .iter()
            .all(|a| a.is_finite() && (0.0..=1.0).contains(a))
        {
            Ok(())
        } else {
            Err(format!(
                "the occluder's albedo lies in [0, 1], got {:?}",
                self.albedo
            ))
        }
    }
}

impl Default for Session {
    /// The editor's first scene: a side-parted, shoulder-length style with a fringe, 14000 strands
    /// on the generated head under the sunny sky, framed as a portrait.
    /// - Each strand stands for a few hairs (the fibres are drawn 3.5 times their width): 14000
    ///   strands of true width let the scalp show through, and 50000 would cost 3.5 times the
    ///   shading.
    /// - A darker skin and an exposure a stop down: the face keeps its modelling under the key
    ///   light.
    /// - A 20-degree field of view (a portrait lens) after framing at 30: the hair fills most of a
    ///   portrait viewport's height.
    /// - The sky turned so that the sun is a key light above and beside the camera (unturned it sits
    ///   behind the head, lighting only a rim): the primary highlight runs across the crown in the
    ///   three-quarter view and the face is modelled from its side.
    fn default() -> Self {
        Self {
            version: SESSION_VERSION,
            hair: HairSource::generated(Style::SidePart, 14000, 16, 1),
            environment: EnvironmentSource::Builtin,
            env_yaw: DEFAULT_ENV_YAW,
            look: Look {
                thickness_scale: 3.5,
                ..Look::default()
            },
            camera: ViewCamera {
                fov_y: 20.0,
                ..ViewCamera::default()
            },
            render: RenderOptions {
                exposure: DEFAULT_EXPOSURE,
                ..RenderOptions::default()
            },
            paint: None,
            paint_layer: None,
            occluder: OccluderOptions {
                albedo: DEFAULT_SKIN_ALBEDO,
                ..OccluderOptions::default()
            },
        }
    }
}

impl Session {
    /// A session of `hair` with the renderer's own settings (the default look, the unturned sky, the
    /// framing camera, the renderer's skin and exposure): the first scene's art direction
    /// ([`Session::default`]) left out, for benchmarks and tests that compare against scenes made
    /// without a session.
    pub fn neutral(hair: HairSource) -> Self {
        Self {
            hair,
            env_yaw: 0.0,
            look: Look::default(),
            camera: ViewCamera::default(),
            render: RenderOptions::default(),
            occluder: OccluderOptions::default(),
            ..Self::default()
        }
    }
}

/// The default scene's skin (linear RGB): a little darker than the renderer's, so that the face
/// keeps its modelling under the key light.
pub const DEFAULT_SKIN_ALBEDO: [f32; 3] = [0.42, 0.26, 0.19];

/// The default scene's exposure, stops: the sun as a key light beside the camera would blow the
/// skin out at the renderer's default.
pub const DEFAULT_EXPOSURE: f32 = -1.0;

/// The default scene's turn of the built-in sky, degrees (see [`Session::default`]).
pub const DEFAULT_ENV_YAW: f64 = -110.0;

impl Session {
    /// The look's parameters as the renderer takes them, with sigma_a from the root absorption.
    pub fn params(&self) -> HairParams {
        HairParams {
            sigma_a: self.look.root.sigma_a(),
            ..self.look.params
        }
    }
}
