//! The resolve pass (`shaders/resolve.wgsl`): coverage, depth, sample ids, the exposed beauty and the
//! background behind every pixel.

use crate::gpu::context::{buffer_init, compute_pipeline};
use crate::gpu::shaders;
use crate::render::passes::targets::FrameTargets;
use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ResolveInfo {
    /// 2^EV.
    pub exposure_scale: f32,
    pub samples: u32,
    /// The background map's size (0 x 0: none) and its yaw, radians ([`crate::render::passes::background::BackgroundMap`]).
    pub env_width: u32,
    pub env_height: u32,
    pub env_yaw: f32,
    pub _pad: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<ResolveInfo>() == 32);

impl ResolveInfo {
    /// No background map yet ([`crate::render::renderer::Renderer::set_background`] gives one).
    pub fn new(exposure: f32, samples: u32) -> Self {
        Self {
            exposure_scale: exposure.exp2(),
            samples,
            env_width: 0,
            env_height: 0,
            env_yaw: 0.0,
            _pad: [0; 3],
        }
    }
}

pub struct ResolvePass {
    pipeline: wgpu::ComputePipeline,
}

impl ResolvePass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("resolve"),
            source: wgpu::ShaderSource::Wgsl(shaders::resolve_module().into()),
        });
        Self {
            pipeline: compute_pipeline(device, &module, "resolve"),
        }
    }

    /// Encodes the resolve of image rows `rows` (all of them after visibility or an exposure change;
    /// a band's after progressive refinement shaded it: at 720x480 on lavapipe a whole-image resolve
    /// costs ~18 ms, which after every band would be most of the refinement's time). With
    /// `background`, the rows' background is looked up too (after visibility, a new camera or map;
    /// a shading band leaves it as it is). With `normalise` (refinement under way), the hair's radiance is scaled by
    /// its alpha over the weight shaded so far, so a partly shaded image shows its final brightness.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        camera: &wgpu::Buffer,
        info: &wgpu::Buffer,
        environment: &wgpu::Buffer,
        targets: &FrameTargets,
        rows: std::ops::Range<u32>,
        (background, normalise): (bool, bool),
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let row0 = rows.start.min(targets.height);
        let count = rows.end.min(targets.height).saturating_sub(row0);
        // A storage buffer, not the uniform: lavapipe recompiles a shader per bind group whose
        // uniforms it inlines (shadow_grid_build.wgsl).
        let band = buffer_init(
            device,
            "resolve rows",
            bytemuck::cast_slice(&[row0, count, background as u32, normalise as u32]),
            wgpu::BufferUsages::STORAGE,
        );
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: info.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&targets.visibility),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(&targets.depth),
            },
        ];
        let outputs = targets.components.iter().chain([
            &targets.beauty,
            &targets.view_depth,
            &targets.sample_ids,
        ]);
        for (k, b) in outputs.enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: 4 + k as u32,
                resource: b.as_entire_binding(),
            });
        }
        for (binding, b) in [
            (12, &band),
            (13, environment),
            (14, &targets.background),
            (15, &targets.occluder),
            (16, &targets.kbuffer.pixel_info),
        ] {
            entries.push(wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            });
        }
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resolve"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("resolve"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        if count > 0 {
            pass.dispatch_workgroups(targets.width.div_ceil(8), count.div_ceil(8), 1);
        }
    }
}
