//! The visibility pass: the occluder (the head) into the multisampled id and depth targets
//! (`shaders/visibility.wgsl`), then the hair's fragments into the K-buffer, which reads that depth
//! ([`crate::render::passes::kbuffer`]), and after the last segment the K-buffer's composite.

use crate::gpu::fiber_density::GpuHair;
use crate::gpu::shaders;
use crate::render::passes::kbuffer::{KBufferPass, SegmentSubset};
use crate::render::passes::occluder::GpuOccluder;
use crate::render::passes::targets::{DEPTH_FORMAT, FrameTargets, VISIBILITY_FORMAT};

pub struct VisibilityPass {
    occluder: wgpu::RenderPipeline,
    kbuffer: KBufferPass,
}

impl VisibilityPass {
    pub fn new(device: &wgpu::Device, samples: u32) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("visibility"),
            source: wgpu::ShaderSource::Wgsl(shaders::visibility_module().into()),
        });
        Self {
            occluder: Self::pipeline(device, &module, samples, "occluder"),
            kbuffer: KBufferPass::new(device),
        }
    }

    /// The pipeline of entry points `vs_<what>` and `fs_<what>` (the same targets, depth test and
    /// multisampling).
    fn pipeline(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        samples: u32,
        what: &str,
    ) -> wgpu::RenderPipeline {
        let (vs, fs) = (format!("vs_{what}"), format!("fs_{what}"));
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("visibility"),
            layout: None,
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(&vs),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: samples,
                mask: !0,
                alpha_to_coverage_enabled: false,
            },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(&fs),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: VISIBILITY_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// Draws segments `range` (all of them for a whole frame; progressive refinement's bounded units
    /// draw parts): the range starting at 0 clears the targets and draws the occluder first; the range
    /// reaching the last segment ends with the K-buffer's composite. The K-buffer does not depend on
    /// the order the segments are drawn in. With `subset`, its listed segments stand for the hair
    /// (`range` indexes the list).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        camera: &wgpu::Buffer,
        hair: &GpuHair,
        occluder: Option<&GpuOccluder>,
        targets: &FrameTargets,
        range: std::ops::Range<u32>,
        subset: Option<&SegmentSubset>,
        timestamps: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let clear = range.start == 0;
        if clear {
            self.encode_occluder(device, encoder, camera, occluder, targets);
        }
        self.kbuffer.encode(
            device,
            encoder,
            camera,
            hair,
            (&targets.depth, occluder.is_some()),
            &targets.kbuffer,
            range,
            clear,
            subset,
            timestamps,
        );
    }

    /// Clears the id and depth targets and draws the occluder's triangles (when there is one).
    fn encode_occluder(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        camera: &wgpu::Buffer,
        occluder: Option<&GpuOccluder>,
        targets: &FrameTargets,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("visibility"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.visibility,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if let Some(o) = occluder {
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("visibility occluder"),
                layout: &self.occluder.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: camera.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: o.positions.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: o.triangles.as_entire_binding(),
                    },
                ],
            });
            pass.set_pipeline(&self.occluder);
            pass.set_bind_group(0, &bind, &[]);
            pass.draw(0..3 * o.triangle_count, 0..1);
        }
    }
}
