//! What the frame sees and how it is shown: camera and tile, image size, lights, the shadow and
//! multiple-scattering toggles, exposure and the background.

use super::{RenderError, Renderer, environment_buffer, gpu_lights};
use crate::envmap::SrbfLight;
use crate::gpu::GpuContext;
use crate::gpu::context::binding_limit;
use crate::render::camera::{Camera, Tile};
use crate::render::passes::background::BackgroundMap;
use crate::render::passes::kbuffer::KBufferTargets;
use crate::render::passes::resolve::ResolveInfo;
use crate::render::passes::segment_shading::SegmentTargets;
use crate::render::passes::targets::FrameTargets;

/// What the frame sees and the targets it renders into.
pub(in crate::render) struct ViewTargets {
    pub(in crate::render) camera: wgpu::Buffer,
    /// The camera the uniform was made from (rewritten when the image size changes).
    pub(in crate::render) camera_view: Camera,
    /// The tile of a larger still the camera renders (None: the whole image).
    pub(in crate::render) tile: Option<Tile>,
    pub(in crate::render) resolve_info: wgpu::Buffer,
    /// What `resolve_info` holds.
    pub(in crate::render) resolve_params: ResolveInfo,
    pub(in crate::render) targets: FrameTargets,
    /// The frame's per-segment radiance (None: the frame shades per fragment).
    pub(in crate::render) segment_targets: Option<SegmentTargets>,
    /// The fragments per pixel asked for (`settings.fragments` is fewer when the K-buffer would not
    /// fit one binding at this size).
    pub(in crate::render) requested_fragments: u32,
}

impl Renderer {
    /// Renders one tile of a larger still with `camera` (the image size becomes the tile's; the
    /// shadow grid is kept from tile to tile).
    pub fn set_camera_tile(
        &mut self,
        ctx: &GpuContext,
        camera: &Camera,
        tile: Tile,
    ) -> Result<(), RenderError> {
        self.set_size(ctx, tile.size[0], tile.size[1])?;
        self.invalidate_visibility();
        self.view.camera_view = *camera;
        self.view.tile = Some(tile);
        let u = camera.tile_uniform(&tile, self.settings.min_width_px);
        ctx.queue
            .write_buffer(&self.view.camera, 0, bytemuck::bytes_of(&u));
        self.update_shading_mode(&ctx.device);
        self.restart_refinement();
        Ok(())
    }

    pub fn set_camera(&mut self, ctx: &GpuContext, camera: &Camera) {
        self.invalidate_visibility();
        self.view.camera_view = *camera;
        self.view.tile = None;
        let u = camera.uniform(
            self.settings.width,
            self.settings.height,
            self.settings.min_width_px,
        );
        ctx.queue
            .write_buffer(&self.view.camera, 0, bytemuck::bytes_of(&u));
        self.update_shading_mode(&ctx.device);
        self.restart_refinement();
    }

    pub fn set_lights(&mut self, ctx: &GpuContext, lights: &[SrbfLight]) {
        let v = gpu_lights(lights);
        let bytes: &[u8] = bytemuck::cast_slice(&v);
        if bytes.len() as u64 > self.scene.lights.size() {
            self.scene.lights = crate::gpu::context::buffer_init(
                &ctx.device,
                "lights",
                bytes,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            );
        } else {
            ctx.queue.write_buffer(&self.scene.lights, 0, bytes);
        }
        self.scene.light_count = lights.len() as u32;
        if self.scene.light_count != self.scene.shadow_grid.light_count {
            self.scene.shadow_grid = self.scene.shadow_grid.with_lights(
                &ctx.device,
                self.scene.light_count,
                self.scene.skip,
                self.settings.multiple_scattering,
            );
            self.grid_buffer_made();
        }
        // An absorption change made while no grid read it (no lights) waits in the volume: the
        // grid's forward terms read it now.
        if self.stale.volume_absorption_old
            && self.settings.shadows
            && self.settings.multiple_scattering
            && self.scene.light_count > 0
        {
            self.mark_volume_dirty();
        } else {
            self.mark_shadow_grid_dirty();
        }
        self.update_batches(&ctx.device);
    }

    pub fn light_count(&self) -> u32 {
        self.scene.light_count
    }

    /// The image size changed (the editor's viewport): new frame targets and shading bands; the
    /// volume and the shadow grid are kept.
    pub fn set_size(
        &mut self,
        ctx: &GpuContext,
        width: u32,
        height: u32,
    ) -> Result<(), RenderError> {
        let max = ctx.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Size(width, height, max));
        }
        if (width, height) == (self.settings.width, self.settings.height) {
            return Ok(());
        }
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let bytes = width as u64 * height as u64 * 16;
        if bytes > limit {
            return Err(RenderError::TooLarge {
                what: format!("a {width}x{height} image"),
                bytes,
                limit,
            });
        }
        self.refinement
            .costs
            .resized(width as f64 / self.settings.width.max(1) as f64);
        self.resized_preview(width, height);
        self.settings.width = width;
        self.settings.height = height;
        self.settings.fragments = KBufferTargets::fitting(
            binding_limit(&ctx.device),
            width,
            height,
            self.view.requested_fragments,
        );
        self.view.targets = FrameTargets::new(
            &ctx.device,
            width,
            height,
            self.settings.samples,
            self.settings.kbuffer(),
        );
        // The camera uniform holds the image size (projection aspect, pixel rays); a tile's is written
        // by set_camera_tile after this.
        let camera = self.view.camera_view;
        self.set_camera(ctx, &camera);
        self.update_batches(&ctx.device);
        Ok(())
    }

    /// Shadows and multiple scattering on or off (no rebuild of anything but the batches; the grid
    /// is built when first needed).
    pub fn set_toggles(&mut self, ctx: &GpuContext, shadows: bool, multiple_scattering: bool) {
        if (shadows, multiple_scattering)
            == (self.settings.shadows, self.settings.multiple_scattering)
        {
            return;
        }
        if multiple_scattering != self.settings.multiple_scattering {
            // The grid's layout (and what it holds) depends on multiple scattering.
            self.scene.shadow_grid = self.scene.shadow_grid.with_lights(
                &ctx.device,
                self.scene.light_count,
                self.scene.skip,
                multiple_scattering,
            );
            self.grid_buffer_made();
            self.stale.shadow_grid_dirty = true;
            self.refinement.grid.done = 0;
        }
        self.settings.shadows = shadows;
        self.settings.multiple_scattering = multiple_scattering;
        self.update_batches(&ctx.device);
        // The grid's forward terms read the volume's absorption, and the grid is rebuilt now: the
        // volume first, so that it is rebuilt once.
        if self.stale.volume_absorption_old && shadows && multiple_scattering {
            self.mark_volume_dirty();
        }
    }

    /// Exposure in stops applied by the resolve pass (and by `read_frame`).
    pub fn set_exposure(&mut self, ctx: &GpuContext, exposure: f32) {
        self.settings.exposure = exposure;
        self.view.resolve_params.exposure_scale = exposure.exp2();
        self.resolve_again(ctx, "exposure");
    }

    /// The environment seen behind the hair (None: none; the background target holds zeros), turned
    /// by `yaw` radians about +Y (world = rotate_yaw(map direction, yaw); a map made for turned lights
    /// gives its own `yaw`). The resolve writes it with every image; here once more for the current one.
    pub fn set_background(&mut self, ctx: &GpuContext, map: Option<&BackgroundMap>, yaw: f32) {
        let r = &mut self.view.resolve_params;
        r.env_width = map.map_or(0, |m| m.width);
        r.env_height = map.map_or(0, |m| m.height);
        r.env_yaw = yaw;
        self.scene.background_map = environment_buffer(&ctx.device, map);
        self.resolve_again(ctx, "background");
    }

    /// Turns the background (the environment's yaw changed; no upload).
    pub fn set_background_yaw(&mut self, ctx: &GpuContext, yaw: f32) {
        if self.view.resolve_params.env_yaw != yaw {
            self.view.resolve_params.env_yaw = yaw;
            self.resolve_again(ctx, "background yaw");
        }
    }

    /// Writes the resolve's parameters and resolves the current image (and preview) again: only the
    /// resolve changed, which runs after every unit anyway.
    pub(super) fn resolve_again(&mut self, ctx: &GpuContext, label: &str) {
        ctx.queue.write_buffer(
            &self.view.resolve_info,
            0,
            bytemuck::bytes_of(&self.view.resolve_params),
        );
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        // Rows the last shading batch has finished resolve as render_frame's; the others normalised
        // while refinement runs.
        let height = self.settings.height;
        let done = self.stale.converged_rows.min(height);
        for (rows, normalise) in [(0..done, false), (done..height, true)] {
            if rows.is_empty() {
                continue;
            }
            self.passes.resolve_pass.encode(
                &ctx.device,
                &mut enc,
                &self.view.camera,
                &self.view.resolve_info,
                &self.scene.background_map,
                &self.view.targets,
                rows,
                (true, normalise),
                None,
            );
        }
        if let Some(p) = &self.preview {
            self.passes.resolve_pass.encode(
                &ctx.device,
                &mut enc,
                &p.camera,
                &self.view.resolve_info,
                &self.scene.background_map,
                &p.targets,
                0..p.targets.height,
                (true, false),
                None,
            );
        }
        ctx.queue.submit([enc.finish()]);
    }

    /// Whether the resolve writes a background (a map was given to [`Renderer::set_background`]).
    pub fn has_background(&self) -> bool {
        self.view.resolve_params.env_width > 0
    }

    /// The frame's targets (the display pass reads the beauty).
    pub fn targets(&self) -> &FrameTargets {
        &self.view.targets
    }
}
