//! The live driver: everything between a session and the renderer for an image that follows the
//! session as it is edited. It holds the loaded hair and environment, the [`Renderer`], the display
//! pass into the texture a viewport draws, and what of the session the renderer has been told.
//! [`LiveDriver::sync`] tells the renderer only what changed (it is never rebuilt for a parameter);
//! [`LiveDriver::step`] hands finished tables over, submits the next bounded unit of refinement and
//! shows what a finished unit left. It knows no UI: the editor wraps it (texture upload, repaints),
//! and `bench` and the tests drive the same driver, on the same render thread ([`super::pump`]).

use super::tables::{HandedOver, TableWork};
use crate::envmap::SrbfSet;
use crate::gpu::GpuContext;
use crate::hair::Hair;
use crate::hair::TriangleMesh;
use crate::hair::normalize::Normalization;
use crate::paint::SharedLayer;
use crate::paint::brush::effective;
use crate::render::display::{DisplayInfo, DisplayPass, Solo, ViewTransform};
use crate::render::passes::background::{Background, BackgroundMap};
use crate::render::passes::occluder::Occluder;
use crate::render::refine::preview::PreviewMode;
use crate::render::refine::{ImageReady, Progress};
use crate::render::renderer::{ParamTables, build_tables};
use crate::render::scene::Environment;
use crate::render::{Camera, HairLook, RenderError, Renderer};
use crate::scattering::lut::Luts;
use crate::session::assemble::{
    LoadedHairSource, base_absorption, mean_absorption, occluder_mesh, renderer_look,
    shown_occluder, turned_lights,
};
use crate::session::{
    AssembleError, EnvironmentSource, HairSource, Look, OccluderOptions, RenderOptions, Session,
};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How the viewport shows the linear image (never the EXR).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewSettings {
    pub transform: ViewTransform,
    /// Viewport exposure, stops, on top of the session's.
    pub exposure: f32,
    /// Render resolution as a fraction of the viewport's pixels.
    pub scale: f32,
    /// The beauty or one component alone.
    pub solo: Solo,
}

impl Default for ViewSettings {
    /// Every pixel of the viewport rendered (a hardware GPU's default).
    fn default() -> Self {
        Self {
            transform: ViewTransform::Filmic,
            exposure: 0.0,
            scale: 1.0,
            solo: Solo::Beauty,
        }
    }
}

impl ViewSettings {
    /// The default view for an adapter: the viewport at full resolution, but half of it on a
    /// software GPU, where the live driver alone took 6.6 s to converge a 10000-strand scene at the
    /// default window's full viewport (654x734; `render --session` 4.8 s) and 4.6 s at half of it
    /// (3.7 s), before the editor's own frames: a first look at every change within a few seconds
    /// matters more there than the last pixel; the resolution buttons raise it.
    pub fn for_adapter(device_type: wgpu::DeviceType) -> Self {
        Self {
            scale: if device_type == wgpu::DeviceType::Cpu {
                SOFTWARE_VIEW_SCALE
            } else {
                1.0
            },
            ..Self::default()
        }
    }
}

/// The default render scale on a software GPU ([`ViewSettings::for_adapter`]).
pub const SOFTWARE_VIEW_SCALE: f32 = 0.5;

/// The viewport's background (display-encoded grey).
pub const BACKGROUND: [f32; 3] = [0.16, 0.16, 0.17];

#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Assemble(#[from] AssembleError),
}

/// The least time between two UI frames for refinement's progress on a software GPU: there a UI
/// frame (egui's 1280x800 window rasterised and presented by lavapipe) costs ~75 ms of the same two
/// cores the refinement runs on, and frames every 100 ms made the default scene converge in 14 s
/// instead of 8.5 s; two a second keep the UI under a fifth of the machine. A hardware GPU draws at
/// display rate.
pub const SOFTWARE_WAKE_INTERVAL: Duration = Duration::from_millis(500);

/// What one step of the render thread left ([`LiveDriver::pump_step`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutcome {
    /// A unit (or a read-back) is on the GPU: wait for it before the next step.
    pub gpu_busy: bool,
    /// Work remains.
    pub working: bool,
    /// A new image (or a warning) for the UI.
    pub news: bool,
    /// The first image of a change, the converged image or an error: the UI draws it at once.
    pub urgent: bool,
}

/// What a scene needs computed from the session and the hair before the renderer is built: the
/// per-point absorption, the look in the renderer's form and its tables (all CPU work, done on the
/// loading worker).
pub struct Prepared {
    pub sigma_a: Vec<[f32; 3]>,
    /// The look's absorption before the paint (the brush mixes toward and away from it).
    pub base_sigma_a: Vec<[f32; 3]>,
    pub look: HairLook,
    pub tables: ParamTables,
    /// The session's paint could not be shown (a layer made for another hair, an unreadable file).
    pub warning: Option<String>,
}

/// The refinement unit budget for this adapter: on a software GPU egui's own frames run on the same
/// two cores and cost ~50 ms each, so units of the default 30 ms left the refinement a third of the
/// machine; 35 ms units trade some UI rate for throughput there and keep every unit of the default
/// scene under 50 ms (80 ms until the bands were sized by their segments: a UI frame then waited
/// behind units of up to 0.7 s). A hardware GPU keeps the default.
pub fn unit_budget(ctx: &GpuContext) -> std::time::Duration {
    if ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        SOFTWARE_UNIT_BUDGET
    } else {
        crate::render::refine::DEFAULT_UNIT_BUDGET
    }
}

pub const SOFTWARE_UNIT_BUDGET: std::time::Duration = std::time::Duration::from_millis(35);

/// The share of the unit budget the refinement's units after the preview get while tables are
/// wanted or built on a worker (`building`): on a software GPU the build takes its cores, and units
/// sized to the whole budget from costs measured without it ran 1.5 times as long (S1's eta edits,
/// whose azimuthal table takes 1.3-1.6 s: units of up to 56-63 ms at 35 ms, lavapipe, two
/// cores). A hardware GPU keeps the whole budget ([`Renderer::set_budget_share`]).
pub fn budget_share(ctx: &GpuContext, building: bool) -> f64 {
    if building && ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        SOFTWARE_SHARE_WHILE_BUILDING
    } else {
        1.0
    }
}

pub const SOFTWARE_SHARE_WHILE_BUILDING: f64 = 2.0 / 3.0;

/// Computes [`Prepared`] (off the UI thread).
pub fn prepare(session: &Session, hair: &Hair) -> Result<Prepared, AssembleError> {
    let base_sigma_a = base_absorption(&session.look, hair)?;
    let (layer, warning) = paint_for(session, hair, &mut None);
    let sigma_a = painted(&base_sigma_a, layer.as_ref());
    let look = renderer_look(&session.look, mean_absorption(&sigma_a));
    let tables = build_tables(&look.params, None);
    Ok(Prepared {
        sigma_a,
        base_sigma_a,
        look,
        tables,
        warning,
    })
}

/// The session's paint for this hair: the layer in memory, else its file. A layer made for another
/// hair is left out with a warning (the session keeps it: undoing the hair change brings it back).
pub fn paint_for(
    session: &Session,
    hair: &Hair,
    file: &mut PaintFileCache,
) -> (Option<SharedLayer>, Option<String>) {
    let (points, strands) = (hair.point_count(), hair.strand_count());
    let layer = match (&session.paint_layer, &session.paint) {
        (Some(l), _) => l.clone(),
        (None, Some(path)) => {
            // Read once per file (a colour drag asks every frame).
            if file.as_ref().is_none_or(|(p, _)| p != path) {
                let read = crate::paint::PaintLayer::read(path)
                    .map(SharedLayer::new)
                    .map_err(|e| format!("{e}; the hair is shown unpainted"));
                *file = Some((path.clone(), read));
            }
            match file.as_ref().map(|(_, r)| r.clone()) {
                Some(Ok(l)) => l,
                Some(Err(e)) => return (None, Some(e)),
                None => return (None, None),
            }
        }
        (None, None) => return (None, None),
    };
    if layer.get().fits(points, strands) {
        (Some(layer), None)
    } else {
        let l = layer.get();
        let text = format!(
            "the paint layer was painted on {} points in {} strands, this hair has {points} points in {strands} strands: it is not shown",
            l.points.len(),
            l.strand_count
        );
        (None, Some(text))
    }
}

/// The paint file last read for a session without a layer in memory, and what it gave.
pub type PaintFileCache = Option<(std::path::PathBuf, Result<SharedLayer, String>)>;

/// Each point's absorption: the base with the layer over it.
pub fn painted(base: &[[f32; 3]], layer: Option<&SharedLayer>) -> Vec<[f32; 3]> {
    match layer {
        Some(l) => base
            .iter()
            .zip(&l.get().points)
            .map(|(b, v)| effective(*b, *v))
            .collect(),
        None => base.to_vec(),
    }
}

/// What identifies the session's paint: its file and the revision of the layer in memory.
fn paint_key(session: &Session) -> (Option<std::path::PathBuf>, Option<u64>) {
    match &session.paint_layer {
        // The layer in memory is the paint, whatever file it was saved to.
        Some(l) => (None, Some(l.revision())),
        None => (session.paint.clone(), None),
    }
}

/// What the renderer was last told.
#[derive(Clone, Debug, PartialEq)]
struct Applied {
    look: Look,
    occluder: OccluderOptions,
    paint: (Option<std::path::PathBuf>, Option<u64>),
    env_yaw: f64,
    render: RenderOptions,
    camera: Camera,
}

pub struct LiveDriver {
    pub ctx: GpuContext,
    pub hair: Arc<Hair>,
    /// The hair's bounding box (the framed camera reads it every frame).
    pub bounds: (glam::Vec3, glam::Vec3),
    pub hair_name: String,
    pub hair_source: HairSource,
    /// The hair's own occluder mesh and how the hair came into world space (an occluder file of the
    /// session is brought into it too), and the occluder shown.
    pub hair_mesh: Option<TriangleMesh>,
    pub normalization: Normalization,
    /// The occluder's mesh (the session's file, or the hair's own), shown or not, and the occluder
    /// shown.
    occluder_mesh: Option<TriangleMesh>,
    pub occluder: Option<Occluder>,
    /// The environment with its lights unturned.
    pub environment: Environment,
    /// What the viewport shows behind the hair (for the unturned lights).
    background_map: Arc<BackgroundMap>,
    pub environment_source: EnvironmentSource,
    pub renderer: Renderer,
    pub display: DisplayPass,
    /// Counts the display textures made (each size makes one).
    display_generation: u64,
    applied: Applied,
    /// The fibre thickness scale the renderer's points have.
    thickness_scale: f32,
    /// The mean absorption of the points (the dual tables' sigma_a), kept while only the look's other
    /// parameters change.
    pub(super) mean_sigma_a: [f64; 3],
    /// Each point's absorption without paint, and with it (what the renderer has).
    pub base_sigma_a: Vec<[f32; 3]>,
    pub sigma_a: Vec<[f32; 3]>,
    /// The session's paint could not be shown (reported once by the app), the last such report, and
    /// the paint file last read.
    pub paint_warning: Option<String>,
    last_paint_warning: Option<String>,
    paint_file: PaintFileCache,
    /// The brush's view of the hair (view depth read back, points projected).
    pub(super) picking: super::picking::Picking,
    /// A dab changed the absorption while a preview was under way: the refinement restarts when
    /// it is done (a restart per dab would never let a preview finish).
    pub(super) paint_restart: bool,
    /// A stroke is under way (its dabs repaint the converged image; the volume and grid follow
    /// once it ends).
    pub(super) painting: bool,
    /// The view the display shows, and the one asked for ([`LiveDriver::set_view`]).
    view: Option<ViewSettings>,
    wanted_view: ViewSettings,
    /// Keep a picker for the current view (the brush is the active tool).
    picking_wanted: bool,
    /// Errors of steps taken on the render thread, for the UI to report; a step failed, and no
    /// change has come since; the paint warning was announced to the UI.
    errors: Vec<String>,
    failed: bool,
    warning_announced: bool,
    /// Display passes submitted (each is an image the UI has not drawn yet), and the restart of
    /// the last one.
    shown_count: u64,
    shown_restart: u64,
    /// The tables on their way to the renderer.
    tables: TableWork,
    /// A camera held back while a preview is under way.
    wanted_camera: Option<Camera>,
    /// The budget's share for units while tables are wanted or built ([`budget_share`], found once).
    building_share: f64,
    pub progress: Option<Progress>,
    /// When the current refinement started, and how long it took to converge.
    pub refine_started: Instant,
    pub converged_in: Option<Duration>,
    /// When the preview of the last change was shown, and the full image's first pass.
    pub preview_in: Option<Duration>,
    pub full_image_in: Option<Duration>,
    /// The image the display shows, how many previews it has shown, and the full image's sharp rows
    /// it drew over the last.
    showing: ImageReady,
    shown_sharp: u32,
    pub previews_shown: u64,
    /// Restarts of the refinement (a change or a refinement of it), and the one whose converged
    /// image was displayed.
    restarts: u64,
    shown_converged: Option<u64>,
}

impl LiveDriver {
    /// Builds the renderer for `session` with a loaded hair and environment at a viewport size, from
    /// what [`prepare`] computed off the UI thread.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: GpuContext,
        luts: &Luts,
        session: &Session,
        hair: LoadedHairSource,
        environment: Environment,
        background_map: Arc<BackgroundMap>,
        prepared: Prepared,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Self, LiveError> {
        let lights = turned_lights(&environment.lights, session.env_yaw);
        let settings = session.render.settings(width, height);
        let Prepared {
            sigma_a,
            base_sigma_a,
            look,
            tables,
            warning,
        } = prepared;
        let mut renderer = Renderer::with_tables(
            &ctx,
            settings,
            luts,
            &hair.hair,
            &sigma_a,
            &look,
            &lights.lights,
            camera,
            tables,
        )?;
        renderer.set_unit_budget(unit_budget(&ctx));
        renderer.set_preview(PreviewMode::Auto);
        if session.look.thickness_scale != 1.0 {
            renderer.set_thickness_scale(&ctx, &hair.hair, session.look.thickness_scale)?;
        }
        let display = DisplayPass::new(&ctx.device, width, height);
        // A mesh file that no longer loads: the hair's own, reported with the paint's warnings.
        let (occluder_mesh, occluder_warning) =
            match occluder_mesh(&session.occluder, hair.mesh.as_ref(), &hair.normalization) {
                Ok(m) => (m, None),
                Err(e) => (
                    hair.mesh.clone(),
                    Some(format!("{e}; showing the hair's own head instead")),
                ),
            };
        let occluder = shown_occluder(&session.occluder, occluder_mesh.clone())?;
        renderer.set_occluder(&ctx, occluder.as_ref());
        let warning = match (warning, occluder_warning) {
            (Some(a), Some(b)) => Some(format!("{a}; {b}")),
            (a, b) => a.or(b),
        };
        let mut live = Self {
            bounds: hair.hair.bounds(),
            hair: Arc::new(hair.hair),
            hair_name: hair.name,
            hair_source: session.hair.clone(),
            hair_mesh: hair.mesh,
            normalization: hair.normalization,
            occluder_mesh,
            occluder,
            background_map,
            environment,
            environment_source: session.environment.clone(),
            renderer,
            display,
            display_generation: 0,
            mean_sigma_a: look.params.sigma_a,
            base_sigma_a,
            sigma_a,
            last_paint_warning: warning.clone(),
            paint_warning: warning,
            paint_file: None,
            picking: Default::default(),
            paint_restart: false,
            painting: false,
            thickness_scale: session.look.thickness_scale,
            applied: Applied {
                look: session.look,
                occluder: session.occluder.clone(),
                paint: paint_key(session),
                env_yaw: session.env_yaw,
                render: session.render,
                camera: *camera,
            },
            view: None,
            wanted_view: ViewSettings::default(),
            picking_wanted: false,
            errors: Vec::new(),
            failed: false,
            warning_announced: false,
            shown_count: 0,
            shown_restart: 0,
            tables: TableWork::new(),
            wanted_camera: None,
            building_share: budget_share(&ctx, true),
            progress: None,
            refine_started: Instant::now(),
            converged_in: None,
            preview_in: None,
            full_image_in: None,
            showing: ImageReady::Full,
            shown_sharp: 0,
            previews_shown: 0,
            restarts: 0,
            shown_converged: None,
            ctx,
        };
        live.apply_background(session.render.background, session.env_yaw);
        Ok(live)
    }

    /// The session's background to the renderer: the environment's map turned by the yaw (the
    /// display composites the image over it), or none (a flat colour is the display's alone).
    fn apply_background(&mut self, background: Background, env_yaw: f64) {
        let map = &self.background_map;
        match background {
            Background::Environment => self.renderer.set_background(
                &self.ctx,
                Some(map),
                map.yaw + env_yaw.to_radians() as f32,
            ),
            _ => self.renderer.set_background(&self.ctx, None, 0.0),
        }
        self.view = None;
    }

    /// Whether the renderer must be rebuilt for this session (hair or render settings it cannot
    /// change in place); environment changes go through [`LiveDriver::set_environment`].
    pub fn needs_rebuild(&self, session: &Session) -> bool {
        let (a, b) = (&self.applied.render, &session.render);
        self.hair_source != session.hair
            || self.applied.occluder.mesh != session.occluder.mesh
            || self.environment_source != session.environment
            || a.samples != b.samples
            || a.fragments != b.fragments
            || a.tail != b.tail
            || a.volume_resolution != b.volume_resolution
            || a.shadow_grid_resolution != b.shadow_grid_resolution
    }

    /// Tells the renderer what changed in `session` and the camera (not the hair source: see
    /// [`LiveDriver::needs_rebuild`]).
    pub fn sync(&mut self, session: &Session, camera: &Camera) -> Result<(), LiveError> {
        let mut changed = false;
        let paint = paint_key(session);
        if session.look != self.applied.look || paint != self.applied.paint {
            let (old, new) = (&self.applied.look, &session.look);
            let base_changed = new.root != old.root
                || new.tip != old.tip
                || new.strand_variation != old.strand_variation
                || new.variation_seed != old.variation_seed;
            let absorption_changed = base_changed || paint != self.applied.paint;
            if paint != self.applied.paint {
                // Another file or layer: read it afresh.
                self.paint_file = None;
            }
            // Applied before anything can fail, so a failure is reported once, not every frame.
            self.applied.look = session.look;
            self.applied.paint = paint;
            let look = if absorption_changed {
                if base_changed {
                    self.base_sigma_a = base_absorption(&session.look, &self.hair)?;
                }
                let (layer, warning) = paint_for(session, &self.hair, &mut self.paint_file);
                // Reported once, not once per frame of a colour drag.
                if warning != self.last_paint_warning {
                    self.paint_warning.clone_from(&warning);
                    self.last_paint_warning = warning;
                }
                self.sigma_a = painted(&self.base_sigma_a, layer.as_ref());
                // Shown at once; the volume and grid follow the first image (`step`).
                self.renderer
                    .set_absorption_deferred(&self.ctx, &self.sigma_a)?;
                self.mean_sigma_a = mean_absorption(&self.sigma_a);
                session.look.validate().map_err(AssembleError::Look)?;
                renderer_look(&session.look, self.mean_sigma_a)
            } else {
                session.look.validate().map_err(AssembleError::Look)?;
                renderer_look(&session.look, self.mean_sigma_a)
            };
            self.set_look_deferred(look);
            changed = true;
        }
        if session.env_yaw != self.applied.env_yaw {
            let lights = turned_lights(&self.environment.lights, session.env_yaw);
            self.renderer.set_lights(&self.ctx, &lights.lights);
            let base = self.background_map.yaw;
            self.renderer
                .set_background_yaw(&self.ctx, base + session.env_yaw.to_radians() as f32);
            self.applied.env_yaw = session.env_yaw;
            changed = true;
        }
        if session.occluder != self.applied.occluder {
            // Shown or hidden, or another albedo (another mesh file reloads the scene). Applied
            // before anything can fail, so a failure is reported once.
            let (was, now) = (self.applied.occluder.show, session.occluder.show);
            self.applied.occluder = session.occluder.clone();
            let albedo = session.occluder.albedo;
            match (&mut self.occluder, was == now) {
                // Hidden before and after (its colour edited): nothing to draw.
                (None, true) if !now => {
                    session.occluder.validate().map_err(AssembleError::Look)?;
                }
                (Some(o), true) => {
                    session.occluder.validate().map_err(AssembleError::Look)?;
                    o.albedo = albedo;
                    self.renderer.set_occluder_albedo(&self.ctx, albedo);
                }
                _ => {
                    self.occluder = shown_occluder(&session.occluder, self.occluder_mesh.clone())?;
                    self.renderer
                        .set_occluder(&self.ctx, self.occluder.as_ref());
                }
            }
            changed = true;
        }
        let (a, b) = (self.applied.render, session.render);
        if (a.shadows, a.multiple_scattering) != (b.shadows, b.multiple_scattering) {
            self.renderer
                .set_toggles(&self.ctx, b.shadows, b.multiple_scattering);
            changed = true;
        }
        if a.background != b.background {
            self.apply_background(b.background, session.env_yaw);
        }
        if a.exposure != b.exposure {
            // Only the resolve changes: no restart, the display shows it at once.
            self.renderer.set_exposure(&self.ctx, b.exposure);
            self.view = None;
        }
        self.applied.render = session.render;
        // During a drag the camera waits for the preview under way (a move per UI frame would restart
        // it before it is ever shown); the latest goes over as soon as it is complete (`step`).
        if *camera == self.applied.camera {
            self.wanted_camera = None;
        } else if self.renderer.preview_under_way() {
            self.wanted_camera = Some(*camera);
        } else {
            self.apply_camera(camera);
            changed = true;
        }
        // The fibre thickness, against what the renderer has (not the applied look: a look that failed
        // validation for another field must not leave the renderer's diameters behind).
        let t = session.look.thickness_scale;
        if t != self.thickness_scale {
            self.thickness_scale = t;
            if !(t.is_finite() && (0.05..=20.0).contains(&t)) {
                return Err(AssembleError::Look(format!(
                    "the fiber thickness scale lies in [0.05, 20], got {t}"
                ))
                .into());
            }
            // Shown at once with the old volume and grid, which follow the first image (`step`).
            self.renderer
                .set_thickness_scale_deferred(&self.ctx, &self.hair, t)?;
            changed = true;
        }
        if changed {
            self.restarted();
        }
        Ok(())
    }

    /// The look in the renderer's form goes to the renderer now (single scattering shows it at
    /// once); its tables are built off the UI thread when the parameters they depend on changed.
    pub(super) fn set_look_deferred(&mut self, look: HairLook) {
        let needs = self.renderer.set_params_deferred(&self.ctx, &look);
        self.tables.look_changed(&look, needs, &self.renderer);
    }

    /// A new environment (already loaded, with the map shown behind the hair), turned by the
    /// session's yaw.
    pub fn set_environment(
        &mut self,
        environment: Environment,
        background_map: Arc<BackgroundMap>,
        source: EnvironmentSource,
        env_yaw: f64,
    ) {
        let lights: SrbfSet = turned_lights(&environment.lights, env_yaw);
        self.renderer.set_lights(&self.ctx, &lights.lights);
        self.environment = environment;
        self.background_map = background_map;
        self.environment_source = source;
        self.applied.env_yaw = env_yaw;
        self.apply_background(self.applied.render.background, env_yaw);
        self.restarted();
    }

    /// The render size follows the viewport. A new size makes a new display texture
    /// ([`LiveDriver::display_generation`] tells a viewport to take it).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), LiveError> {
        if (width, height) == (self.display.width, self.display.height) {
            return Ok(());
        }
        self.renderer.set_size(&self.ctx, width, height)?;
        self.display = DisplayPass::new(&self.ctx.device, width, height);
        self.display_generation += 1;
        self.view = None;
        self.restarted();
        Ok(())
    }

    /// What the viewport shows behind the hair (for the unturned lights).
    pub fn background_map(&self) -> &Arc<BackgroundMap> {
        &self.background_map
    }

    /// Counts the display textures made (a viewport registers the texture anew when it changes).
    pub fn display_generation(&self) -> u64 {
        self.display_generation
    }

    /// The session's paint as the renderer has it now (a dab wrote its points).
    pub fn note_paint(&mut self, session: &Session) {
        self.applied.paint = paint_key(session);
    }

    /// A change the image does not show yet: times are measured from here (and a failed step is
    /// tried again).
    pub(super) fn restarted(&mut self) {
        self.failed = false;
        self.refine_started = Instant::now();
        self.showing_anew();
    }

    /// The change's first image is still to come (a new eta's draft: the images before it kept the
    /// old index); its times count from the change.
    fn showing_anew(&mut self) {
        self.preview_in = None;
        self.full_image_in = None;
        self.restarted_as_refinement();
    }

    /// A restart that refines the change on screen (its tables, its volume): its times still count
    /// from the change.
    fn restarted_as_refinement(&mut self) {
        self.converged_in = None;
        self.restarts += 1;
        // The last refinement's progress (converged, say) says nothing about this one.
        self.progress = None;
    }

    fn apply_camera(&mut self, camera: &Camera) {
        self.renderer.set_camera(&self.ctx, camera);
        self.applied.camera = *camera;
        self.wanted_camera = None;
    }

    /// One UI frame's work: shows the image a finished unit left, takes finished tables, submits one
    /// bounded refinement unit and, when the image or the view changed, the display pass. Never waits
    /// for the GPU.
    pub fn step(&mut self, view: ViewSettings) -> Result<Progress, LiveError> {
        // The image the last unit finished goes to the display before the next unit is queued.
        let ready = self.renderer.poll_refinement(&self.ctx)?;
        self.note_ready(ready);
        // A camera held back behind a preview goes over the moment it is done, before the next unit
        // (a full-resolution one) is queued.
        if let Some(camera) = self.wanted_camera
            && !self.renderer.preview_under_way()
        {
            self.apply_camera(&camera);
            self.restarted();
        }
        // Likewise the dabs painted while a preview was under way.
        if self.paint_restart && !self.renderer.preview_under_way() {
            self.paint_restart = false;
            self.renderer.restart();
            self.restarted();
        }
        // The tables' build starts once the change shows (or the image is converged: a change the
        // frame does not read before its tables), at once without a preview, or for a new eta or
        // eccentricity: its draft at once, the table once the draft's preview shows.
        let change_shown = self.first_image_in().is_some()
            || self.progress.is_some_and(|p| p.converged)
            || self.renderer.preview_factor() < 2;
        self.tables.start(change_shown);
        self.tables.poll();
        // New tables restart the refinement (with dual scattering, from the shadow grid, whose forward
        // terms read them), and so does a deferred absorption change (from the volume). Right after a
        // change the refinement shows a preview, then the full image with the old grid: rebuild once
        // that full image is on screen ([`TableWork::hand_over`]); anything waiting goes over when the
        // refinement has nothing left to show.
        let shown = self.full_image_in.is_some() || self.progress.is_some_and(|p| p.converged);
        match self.tables.hand_over(&self.ctx, &mut self.renderer, shown) {
            Some(HandedOver::Draft) => self.showing_anew(),
            Some(HandedOver::Tables) => self.restarted_as_refinement(),
            None => {}
        }
        // With tables on the way, the volume waits for them: they rebuild the grid too.
        if shown && !self.tables.waiting() && !self.painting && self.renderer.rebuild_stale_volume()
        {
            self.restarted_as_refinement();
        }
        let building = self.tables.building();
        self.renderer
            .set_budget_share(if building { self.building_share } else { 1.0 });
        let progress = self.renderer.refine(&self.ctx)?;
        // A unit that finished between the two polls.
        self.note_ready(progress.ready);
        let ready = ready.or(progress.ready);
        // Converged without a unit in flight (nothing changed since) shows nothing new.
        if progress.converged && self.converged_in.is_none() {
            self.converged_in = Some(self.refine_started.elapsed());
        }
        let converged_now = progress.converged && self.shown_converged != Some(self.restarts);
        if converged_now {
            self.shown_converged = Some(self.restarts);
            self.showing = ImageReady::Full;
        }
        // The first pass sharpens the preview band by band.
        let sharper =
            self.showing == ImageReady::Preview && self.renderer.sharp_rows() > self.shown_sharp;
        if ready.is_some() || converged_now || sharper || self.view != Some(view) {
            self.show(view);
        }
        self.progress = Some(progress);
        Ok(progress)
    }

    /// A finished unit left `ready` worth showing: it becomes the image shown, and the times of the
    /// first images of this change are noted (the renderer counts only units planned after it).
    fn note_ready(&mut self, ready: Option<ImageReady>) {
        let Some(image) = ready else {
            return;
        };
        self.showing = image;
        self.previews_shown += (image == ImageReady::Preview) as u64;
        let stats = self.renderer.refine_stats();
        let since = self.refine_started.elapsed();
        if stats.preview.is_some() {
            self.preview_in.get_or_insert(since);
        }
        if stats.first_pass.is_some() {
            self.full_image_in.get_or_insert(since);
        }
    }

    /// When the first image of the last change was shown: its preview, or the full image's first
    /// pass.
    pub fn first_image_in(&self) -> Option<Duration> {
        self.preview_in.or(self.full_image_in)
    }

    /// The display pass of the image shown, through the view transform.
    fn show(&mut self, view: ViewSettings) {
        let background = self.applied.render.background;
        let flat = match background {
            Background::Colour(c) => c.map(|v| v as f32 / 255.0),
            _ => BACKGROUND,
        };
        let info = DisplayInfo {
            render_scale: self.renderer.settings.exposure.exp2(),
            environment: (background == Background::Environment && self.renderer.has_background())
                as u32,
            ..DisplayInfo::new(
                self.display.width,
                self.display.height,
                view.transform,
                view.exposure,
                flat,
            )
        };
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("display"),
            });
        self.display.encode(
            &self.ctx.device,
            &self.ctx.queue,
            &mut enc,
            self.renderer.image(self.showing),
            &info,
            view.solo,
        );
        self.ctx.queue.submit([enc.finish()]);
        self.view = Some(view);
        self.shown_sharp = self.renderer.sharp_rows();
        self.shown_count += 1;
    }

    /// Counts the refinement's restarts (a change, or a refinement of it).
    pub fn restarts(&self) -> u64 {
        self.restarts
    }

    /// The view the display should show (applied by the next step).
    pub fn set_view(&mut self, view: ViewSettings) {
        self.wanted_view = view;
    }

    /// Keep a picker for the current view (while the brush is the active tool).
    pub fn set_picking(&mut self, wanted: bool) {
        self.picking_wanted = wanted;
    }

    /// Times of the current refinement count from `origin` (the editor's launch, for its first
    /// scene) instead of from when the driver was made.
    pub fn count_from(&mut self, origin: Instant) {
        self.refine_started = origin;
    }

    /// The errors of the steps taken since the last call.
    pub fn take_errors(&mut self) -> Vec<String> {
        std::mem::take(&mut self.errors)
    }

    /// How often at most the render thread wakes a UI for an image that only refines the one it
    /// shows (the first image of a change and the converged one wake it at once).
    pub fn wake_interval(&self) -> Duration {
        if self.ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
            SOFTWARE_WAKE_INTERVAL
        } else {
            Duration::from_millis(16)
        }
    }

    /// Whether anything is left to do: refinement, tables, the picker.
    pub fn working(&self) -> bool {
        !self.failed && self.work_left()
    }

    fn work_left(&self) -> bool {
        !self.progress.is_some_and(|p| p.converged)
            || self.tables_pending()
            || self.view != Some(self.wanted_view)
            || (self.picking_wanted && self.picking_pending())
    }

    /// One step of the render thread: [`LiveDriver::step`] with the view asked for, and the
    /// picker's read-back and build while the brush wants one. Errors are kept for the UI
    /// ([`LiveDriver::take_errors`]).
    pub fn pump_step(&mut self) -> StepOutcome {
        // A step that failed is not retried until something changes (it would fail again).
        if self.failed {
            return StepOutcome::idle();
        }
        let (shown, restarts) = (self.shown_count, self.restarts);
        let fraction = self.progress.map(|p| p.fraction);
        let result = self.step(self.wanted_view);
        if self.picking_wanted {
            self.update_picking();
        }
        let progress = match result {
            Ok(p) => p,
            Err(e) => {
                self.errors.push(e.to_string());
                self.failed = true;
                return StepOutcome {
                    news: true,
                    urgent: true,
                    ..StepOutcome::idle()
                };
            }
        };
        let shown_new = self.shown_count != shown;
        // The first image of a change, and the converged one, are drawn at once.
        let urgent = shown_new
            && (self.shown_restart != restarts || self.restarts != restarts || progress.converged);
        if shown_new {
            self.shown_restart = self.restarts;
        }
        // A warning for the UI is news once; the progress bar's advance is news too (paced).
        let warning = self.paint_warning.is_some() && !self.warning_announced;
        self.warning_announced = self.paint_warning.is_some();
        let advanced = self.progress.map(|p| p.fraction) != fraction;
        StepOutcome {
            gpu_busy: progress.busy
                || progress.submitted.is_some()
                || (self.picking_wanted && self.picking.reading()),
            working: self.working(),
            news: shown_new || warning || advanced,
            urgent: urgent || warning,
        }
    }

    /// A step panicked on the render thread: reported, and no step is taken until something
    /// changes (the driver may be half-way through that step; a change restarts the refinement).
    pub fn step_panicked(&mut self, why: &str) {
        self.errors.push(format!(
            "the viewport's refinement stopped: {why}; change something to restart it"
        ));
        self.failed = true;
    }

    /// Whether tables are still being built or not yet handed to the renderer, or a deferred
    /// absorption change still waits for its volume: the image is not the session's final one yet.
    pub fn tables_pending(&self) -> bool {
        self.tables.pending(&self.renderer) || self.renderer.volume_stale()
    }
}
