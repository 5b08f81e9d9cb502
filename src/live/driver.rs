//! The live driver: everything between a session and the renderer for an image that follows the
//! session as it is edited. It holds the loaded hair and environment, the [`Renderer`], the display
//! pass into the texture a viewport draws, and what of the session the renderer has been told.
//! [`LiveDriver::sync`] tells the renderer only what changed (it is never rebuilt for a parameter);
//! [`LiveDriver::step`] hands finished tables over, submits the next bounded unit of refinement and
//! shows what a finished unit left. It knows no UI: the editor wraps it (texture upload, repaints),
//! and `bench` and the tests drive the same driver, on the same render thread ([`super::pump`]).

use super::prepare::{Prepared, paint_for, paint_key, painted};
use super::settings::*;
use super::state::*;
use super::tables::{HandedOver, TableWork};
use crate::envmap::SrbfSet;
use crate::gpu::GpuContext;
use crate::hair::Hair;
use crate::hair::normalize::Normalization;
use crate::render::display::{DisplayInfo, DisplayPass};
use crate::render::passes::background::{Background, BackgroundMap};
use crate::render::passes::occluder::Occluder;
use crate::render::refine::preview::PreviewMode;
use crate::render::refine::{ImageReady, Progress};
use crate::render::scene::Environment;
use crate::render::{Camera, HairLook, RenderError, Renderer};
use crate::scattering::lut::Luts;
use crate::session::assemble::{
    LoadedHairSource, base_absorption, mean_absorption, occluder_mesh, renderer_look,
    shown_occluder, turned_lights,
};
use crate::session::{AssembleError, EnvironmentSource, Session};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Assemble(#[from] AssembleError),
}

pub struct LiveDriver {
    pub ctx: GpuContext,
    pub hair: Arc<Hair>,
    /// The hair's bounding box (the framed camera reads it every frame).
    pub bounds: (glam::Vec3, glam::Vec3),
    pub normalization: Normalization,
    pub occluder: Option<Occluder>,
    /// The environment with its lights unturned.
    pub environment: Environment,
    pub renderer: Renderer,
    pub display: DisplayPass,
    applied: Applied,
    /// Each point's absorption with the paint over it (what the renderer has).
    pub sigma_a: Vec<[f32; 3]>,
    /// The brush's view of the hair (view depth read back, points projected).
    pub(super) picking: super::picking::Picking,
    /// Keep a picker for the current view (the brush is the active tool).
    picking_wanted: bool,
    /// The tables on their way to the renderer.
    tables: TableWork,
    /// A camera held back while a preview is under way.
    wanted_camera: Option<Camera>,
    /// The absorption without paint, the paint file and its warnings, a stroke under way.
    pub paint: PaintState,
    /// The image the display shows and the view it shows it in.
    pub shown: Shown,
    /// When the current refinement started and when its images came.
    pub clock: RefineClock,
    /// Errors of the render thread's steps, for the UI.
    pub health: Health,
    /// Where the hair, head and environment came from.
    pub sources: Sources,
}

impl LiveDriver {
    /// Builds the renderer for `session` with a loaded hair and environment at a viewport size, from
    /// what [`crate::live::prepare::prepare`] computed off the UI thread.
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
            normalization: hair.normalization,
            occluder,
            environment,
            renderer,
            display,
            sigma_a,
            picking: Default::default(),
            applied: Applied {
                look: session.look,
                occluder: session.occluder.clone(),
                paint: paint_key(session),
                env_yaw: session.env_yaw,
                render: session.render,
                camera: *camera,
                thickness_scale: session.look.thickness_scale,
            },
            picking_wanted: false,
            tables: TableWork::new(budget_share(&ctx, true)),
            wanted_camera: None,
            paint: PaintState {
                mean_sigma_a: look.params.sigma_a,
                base_sigma_a,
                last_paint_warning: warning.clone(),
                paint_warning: warning,
                paint_file: None,
                paint_restart: false,
                painting: false,
            },
            shown: Shown {
                display_generation: 0,
                view: None,
                wanted_view: ViewSettings::default(),
                shown_count: 0,
                shown_restart: 0,
                showing: ImageReady::Full,
                shown_sharp: 0,
                previews_shown: 0,
                shown_converged: None,
            },
            clock: RefineClock {
                progress: None,
                refine_started: Instant::now(),
                converged_in: None,
                preview_in: None,
                full_image_in: None,
                restarts: 0,
            },
            health: Health {
                errors: Vec::new(),
                failed: false,
                warning_announced: false,
            },
            sources: Sources {
                hair_name: hair.name,
                hair_source: session.hair.clone(),
                hair_mesh: hair.mesh,
                occluder_mesh,
                background_map,
                environment_source: session.environment.clone(),
            },
            ctx,
        };
        live.apply_background(session.render.background, session.env_yaw);
        Ok(live)
    }

    /// The session's background to the renderer: the environment's map turned by the yaw (the
    /// display composites the image over it), or none (a flat colour is the display's alone).
    fn apply_background(&mut self, background: Background, env_yaw: f64) {
        let map = &self.sources.background_map;
        match background {
            Background::Environment => self.renderer.set_background(
                &self.ctx,
                Some(map),
                map.yaw + env_yaw.to_radians() as f32,
            ),
            _ => self.renderer.set_background(&self.ctx, None, 0.0),
        }
        self.shown.view = None;
    }

    /// Whether the renderer must be rebuilt for this session (hair or render settings it cannot
    /// change in place); environment changes go through [`LiveDriver::set_environment`].
    pub fn needs_rebuild(&self, session: &Session) -> bool {
        let (a, b) = (&self.applied.render, &session.render);
        self.sources.hair_source != session.hair
            || self.applied.occluder.mesh != session.occluder.mesh
            || self.sources.environment_source != session.environment
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
                self.paint.paint_file = None;
            }
            // Applied before anything can fail, so a failure is reported once, not every frame.
            self.applied.look = session.look;
            self.applied.paint = paint;
            let look = if absorption_changed {
                if base_changed {
                    self.paint.base_sigma_a = base_absorption(&session.look, &self.hair)?;
                }
                let (layer, warning) = paint_for(session, &self.hair, &mut self.paint.paint_file);
                // Reported once, not once per frame of a colour drag.
                if warning != self.paint.last_paint_warning {
                    self.paint.paint_warning.clone_from(&warning);
                    self.paint.last_paint_warning = warning;
                }
                self.sigma_a = painted(&self.paint.base_sigma_a, layer.as_ref());
                // Shown at once; the volume and grid follow the first image (`step`).
                self.renderer
                    .set_absorption_deferred(&self.ctx, &self.sigma_a)?;
                self.paint.mean_sigma_a = mean_absorption(&self.sigma_a);
                session.look.validate().map_err(AssembleError::Look)?;
                renderer_look(&session.look, self.paint.mean_sigma_a)
            } else {
                session.look.validate().map_err(AssembleError::Look)?;
                renderer_look(&session.look, self.paint.mean_sigma_a)
            };
            self.set_look_deferred(look);
            changed = true;
        }
        if session.env_yaw != self.applied.env_yaw {
            let lights = turned_lights(&self.environment.lights, session.env_yaw);
            self.renderer.set_lights(&self.ctx, &lights.lights);
            let base = self.sources.background_map.yaw;
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
                    self.occluder =
                        shown_occluder(&session.occluder, self.sources.occluder_mesh.clone())?;
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
            self.shown.view = None;
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
        if t != self.applied.thickness_scale {
            self.applied.thickness_scale = t;
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
        self.sources.background_map = background_map;
        self.sources.environment_source = source;
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
        self.shown.display_generation += 1;
        self.shown.view = None;
        self.restarted();
        Ok(())
    }

    /// What the viewport shows behind the hair (for the unturned lights).
    pub fn background_map(&self) -> &Arc<BackgroundMap> {
        &self.sources.background_map
    }

    /// Counts the display textures made (a viewport registers the texture anew when it changes).
    pub fn display_generation(&self) -> u64 {
        self.shown.display_generation
    }

    /// The session's paint as the renderer has it now (a dab wrote its points).
    pub fn note_paint(&mut self, session: &Session) {
        self.applied.paint = paint_key(session);
    }

    /// A change the image does not show yet: times are measured from here (and a failed step is
    /// tried again).
    pub(super) fn restarted(&mut self) {
        self.health.failed = false;
        self.clock.refine_started = Instant::now();
        self.showing_anew();
    }

    /// The change's first image is still to come (a new eta's draft: the images before it kept the
    /// old index); its times count from the change.
    fn showing_anew(&mut self) {
        self.clock.preview_in = None;
        self.clock.full_image_in = None;
        self.restarted_as_refinement();
    }

    /// A restart that refines the change on screen (its tables, its volume): its times still count
    /// from the change.
    fn restarted_as_refinement(&mut self) {
        self.clock.converged_in = None;
        self.clock.restarts += 1;
        // The last refinement's progress (converged, say) says nothing about this one.
        self.clock.progress = None;
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
        if self.paint.paint_restart && !self.renderer.preview_under_way() {
            self.paint.paint_restart = false;
            self.renderer.restart();
            self.restarted();
        }
        // The tables' build starts once the change shows (or the image is converged: a change the
        // frame does not read before its tables), at once without a preview, or for a new eta or
        // eccentricity: its draft at once, the table once the draft's preview shows.
        let change_shown = self.first_image_in().is_some()
            || self.clock.progress.is_some_and(|p| p.converged)
            || self.renderer.preview_factor() < 2;
        self.tables.start(change_shown);
        self.tables.poll();
        // New tables restart the refinement (with dual scattering, from the shadow grid, whose forward
        // terms read them), and so does a deferred absorption change (from the volume). Right after a
        // change the refinement shows a preview, then the full image with the old grid: rebuild once
        // that full image is on screen ([`TableWork::hand_over`]); anything waiting goes over when the
        // refinement has nothing left to show.
        let shown =
            self.clock.full_image_in.is_some() || self.clock.progress.is_some_and(|p| p.converged);
        match self.tables.hand_over(&self.ctx, &mut self.renderer, shown) {
            Some(HandedOver::Draft) => self.showing_anew(),
            Some(HandedOver::Tables) => self.restarted_as_refinement(),
            None => {}
        }
        // With tables on the way, the volume waits for them: they rebuild the grid too.
        if shown
            && !self.tables.waiting()
            && !self.paint.painting
            && self.renderer.rebuild_stale_volume()
        {
            self.restarted_as_refinement();
        }
        self.renderer.set_budget_share(self.tables.budget_share());
        let progress = self.renderer.refine(&self.ctx)?;
        // A unit that finished between the two polls.
        self.note_ready(progress.ready);
        let ready = ready.or(progress.ready);
        // Converged without a unit in flight (nothing changed since) shows nothing new.
        if progress.converged && self.clock.converged_in.is_none() {
            self.clock.converged_in = Some(self.clock.refine_started.elapsed());
        }
        let converged_now =
            progress.converged && self.shown.shown_converged != Some(self.clock.restarts);
        if converged_now {
            self.shown.shown_converged = Some(self.clock.restarts);
            self.shown.showing = ImageReady::Full;
        }
        // The first pass sharpens the preview band by band.
        let sharper = self.shown.showing == ImageReady::Preview
            && self.renderer.sharp_rows() > self.shown.shown_sharp;
        if ready.is_some() || converged_now || sharper || self.shown.view != Some(view) {
            self.show(view);
        }
        self.clock.progress = Some(progress);
        Ok(progress)
    }

    /// A finished unit left `ready` worth showing: it becomes the image shown, and the times of the
    /// first images of this change are noted (the renderer counts only units planned after it).
    fn note_ready(&mut self, ready: Option<ImageReady>) {
        let Some(image) = ready else {
            return;
        };
        self.shown.showing = image;
        self.shown.previews_shown += (image == ImageReady::Preview) as u64;
        let stats = self.renderer.refine_stats();
        let since = self.clock.refine_started.elapsed();
        if stats.preview.is_some() {
            self.clock.preview_in.get_or_insert(since);
        }
        if stats.first_pass.is_some() {
            self.clock.full_image_in.get_or_insert(since);
        }
    }

    /// When the first image of the last change was shown: its preview, or the full image's first
    /// pass.
    pub fn first_image_in(&self) -> Option<Duration> {
        self.clock.preview_in.or(self.clock.full_image_in)
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
            self.renderer.image(self.shown.showing),
            &info,
            view.solo,
        );
        self.ctx.queue.submit([enc.finish()]);
        self.shown.view = Some(view);
        self.shown.shown_sharp = self.renderer.sharp_rows();
        self.shown.shown_count += 1;
    }

    /// Counts the refinement's restarts (a change, or a refinement of it).
    pub fn restarts(&self) -> u64 {
        self.clock.restarts
    }

    /// The view the display should show (applied by the next step).
    pub fn set_view(&mut self, view: ViewSettings) {
        self.shown.wanted_view = view;
    }

    /// Keep a picker for the current view (while the brush is the active tool).
    pub fn set_picking(&mut self, wanted: bool) {
        self.picking_wanted = wanted;
    }

    /// Times of the current refinement count from `origin` (the editor's launch, for its first
    /// scene) instead of from when the driver was made.
    pub fn count_from(&mut self, origin: Instant) {
        self.clock.refine_started = origin;
    }

    /// The errors of the steps taken since the last call.
    pub fn take_errors(&mut self) -> Vec<String> {
        std::mem::take(&mut self.health.errors)
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
        !self.health.failed && self.work_left()
    }

    fn work_left(&self) -> bool {
        !self.clock.progress.is_some_and(|p| p.converged)
            || self.tables_pending()
            || self.shown.view != Some(self.shown.wanted_view)
            || (self.picking_wanted && self.picking_pending())
    }

    /// One step of the render thread: [`LiveDriver::step`] with the view asked for, and the
    /// picker's read-back and build while the brush wants one. Errors are kept for the UI
    /// ([`LiveDriver::take_errors`]).
    pub fn pump_step(&mut self) -> StepOutcome {
        // A step that failed is not retried until something changes (it would fail again).
        if self.health.failed {
            return StepOutcome::idle();
        }
        let (shown, restarts) = (self.shown.shown_count, self.clock.restarts);
        let fraction = self.clock.progress.map(|p| p.fraction);
        let result = self.step(self.shown.wanted_view);
        if self.picking_wanted {
            self.update_picking();
        }
        let progress = match result {
            Ok(p) => p,
            Err(e) => {
                self.health.errors.push(e.to_string());
                self.health.failed = true;
                return StepOutcome {
                    news: true,
                    urgent: true,
                    ..StepOutcome::idle()
                };
            }
        };
        let shown_new = self.shown.shown_count != shown;
        // The first image of a change, and the converged one, are drawn at once.
        let urgent = shown_new
            && (self.shown.shown_restart != restarts
                || self.clock.restarts != restarts
                || progress.converged);
        if shown_new {
            self.shown.shown_restart = self.clock.restarts;
        }
        // A warning for the UI is news once; the progress bar's advance is news too (paced).
        let warning = self.paint.paint_warning.is_some() && !self.health.warning_announced;
        self.health.warning_announced = self.paint.paint_warning.is_some();
        let advanced = self.clock.progress.map(|p| p.fraction) != fraction;
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
        self.health.errors.push(format!(
            "the viewport's refinement stopped: {why}; change something to restart it"
        ));
        self.health.failed = true;
    }

    /// Whether tables are still being built or not yet handed to the renderer, or a deferred
    /// absorption change still waits for its volume: the image is not the session's final one yet.
    pub fn tables_pending(&self) -> bool {
        self.tables.pending(&self.renderer) || self.renderer.volume_stale()
    }
}
