//! The fiber-density volume built on the GPU (`shaders/fiber_density.wgsl`), the twin of
//! [`crate::shadow::FiberDensity::build`]; run whenever geometry changes.

use super::context::{GpuContext, compute_pipeline};
use crate::hair::Hair;
use crate::shadow::voxels::VolumeGrid;
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

/// The volume's placement as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct VolumeInfo {
    pub origin: [f32; 3],
    pub voxel: f32,
    pub dims: [u32; 3],
    pub segment_count: u32,
}

const _: () = assert!(std::mem::size_of::<VolumeInfo>() == 32);

/// Fixed-point channels per voxel in the deposit buffer (see the shader).
const CHANNELS: u64 = 11;

/// Strand geometry on the GPU: points (xyz, diameter), per-point absorption (the buffer the brush
/// paints), and the first point of every segment.
pub struct GpuHair {
    pub points: wgpu::Buffer,
    pub absorption: wgpu::Buffer,
    pub segments: wgpu::Buffer,
    pub segment_count: u32,
}

impl GpuHair {
    /// (xyz, diameter x `thickness_scale`) per point, as the points buffer holds them.
    pub fn point_data(hair: &Hair, thickness_scale: f32) -> Vec<[f32; 4]> {
        let mut points = Vec::with_capacity(hair.point_count());
        for s in 0..hair.strand_count() {
            for p in hair.strand_range(s) {
                let x = hair.positions[p];
                points.push([x.x, x.y, x.z, hair.thickness_at(s, p) * thickness_scale]);
            }
        }
        points
    }

    pub fn new(device: &wgpu::Device, hair: &Hair, sigma_a: &[[f32; 3]]) -> Self {
        let points = Self::point_data(hair, 1.0);
        let mut segments = Vec::new();
        for s in 0..hair.strand_count() {
            let r = hair.strand_range(s);
            segments.extend((r.start as u32)..(r.end as u32 - 1));
        }
        let absorption: Vec<[f32; 4]> = sigma_a.iter().map(|s| [s[0], s[1], s[2], 0.0]).collect();
        let init = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            })
        };
        // An empty buffer cannot be bound: keep at least one element.
        if segments.is_empty() {
            segments.push(0);
        }
        Self {
            points: init("hair points", bytemuck::cast_slice(&points)),
            absorption: init("hair absorption", bytemuck::cast_slice(&absorption)),
            segment_count: if hair.point_count() > 1 {
                segments.len() as u32
            } else {
                0
            },
            segments: init("hair segments", bytemuck::cast_slice(&segments)),
        }
    }
}

/// The volume on the GPU: three vec4 per voxel, (a, M_xx, M_yy, M_zz), (M_xy, M_xz, M_yz, rho_L),
/// (sigma_a, 0), as in [`crate::shadow::FiberDensity`].
pub struct GpuFiberDensity {
    pub grid: VolumeGrid,
    pub info: wgpu::Buffer,
    pub sums: wgpu::Buffer,
    pub volume: wgpu::Buffer,
    /// The fraction of each voxel inside the occluder ([`crate::shadow::solid::solid_fraction`]),
    /// zero without one.
    pub solid: wgpu::Buffer,
}

impl GpuFiberDensity {
    pub fn new(device: &wgpu::Device, grid: VolumeGrid, segment_count: u32) -> Self {
        let n = grid.voxel_count() as u64;
        let info = VolumeInfo {
            origin: grid.origin.to_array(),
            voxel: grid.voxel,
            dims: grid.dims.map(|d| d as u32),
            segment_count,
        };
        Self {
            grid,
            info: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("volume info"),
                contents: bytemuck::bytes_of(&info),
                // Also storage: the shadow-grid build reads it so (shadow_grid_build.wgsl).
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE,
            }),
            sums: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("volume sums"),
                size: n * CHANNELS * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            volume: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("volume"),
                size: n * 48,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            solid: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("volume solid"),
                size: n * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }

    /// The occluder's fraction of each voxel (None: no occluder); the next resolve adds it.
    pub fn set_solid(&self, queue: &wgpu::Queue, fraction: Option<&[f32]>) {
        let n = self.grid.voxel_count();
        match fraction {
            Some(f) if f.len() == n => queue.write_buffer(&self.solid, 0, bytemuck::cast_slice(f)),
            _ => queue.write_buffer(&self.solid, 0, bytemuck::cast_slice(&vec![0f32; n])),
        }
    }

    /// Reads the volume back (tests, debugging): 12 floats per voxel.
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<[f32; 12]>, String> {
        ctx.read_buffer(&self.volume)
    }
}

/// The two compute pipelines (deposit per segment, resolve per voxel).
pub struct FiberDensityPass {
    deposit: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
}

impl FiberDensityPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("fiber_density"),
            source: wgpu::ShaderSource::Wgsl(super::shaders::FIBER_DENSITY.into()),
        });
        Self {
            deposit: compute_pipeline(device, &module, "deposit"),
            resolve: compute_pipeline(device, &module, "resolve"),
        }
    }

    /// Clears the sums, deposits every segment, resolves every voxel.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        hair: &GpuHair,
        target: &GpuFiberDensity,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let all = 0..hair.segment_count;
        let voxels = 0..target.grid.voxel_count() as u32;
        self.record(
            device,
            encoder,
            hair,
            target,
            Some(all),
            Some(voxels),
            timestamps,
        );
    }

    /// Deposits segments `segments` (clearing the sums first when the range starts at 0): a part of
    /// a build, finished by [`FiberDensityPass::encode_resolve`].
    pub fn encode_deposit(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        hair: &GpuHair,
        target: &GpuFiberDensity,
        segments: std::ops::Range<u32>,
    ) {
        self.record(device, encoder, hair, target, Some(segments), None, None);
    }

    /// Resolves voxels `voxels` (of [`GpuFiberDensity`]'s grid, in index order) from the deposited
    /// sums (after every segment was deposited).
    pub fn encode_resolve(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        hair: &GpuHair,
        target: &GpuFiberDensity,
        voxels: std::ops::Range<u32>,
    ) {
        self.record(device, encoder, hair, target, None, Some(voxels), None);
    }

    /// One compute pass: the deposit of `segments` (after clearing the sums when they start at 0)
    /// and the resolve of voxels `resolve`.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        hair: &GpuHair,
        target: &GpuFiberDensity,
        segments: Option<std::ops::Range<u32>>,
        resolve: Option<std::ops::Range<u32>>,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        if segments.as_ref().is_some_and(|r| r.start == 0) {
            encoder.clear_buffer(&target.sums, 0, None);
        }
        let range_buffer = |label, r: &std::ops::Range<u32>| {
            super::context::buffer_init(
                device,
                label,
                bytemuck::cast_slice(&[r.start, r.end.saturating_sub(r.start), 0, 0]),
                wgpu::BufferUsages::STORAGE,
            )
        };
        let range = segments.as_ref().map(|r| range_buffer("deposit range", r));
        let voxels = resolve.as_ref().map(|r| range_buffer("resolve range", r));
        let bind = |pipeline: &wgpu::ComputePipeline, range: &wgpu::Buffer, deposit: bool| {
            let mut entries = vec![
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: target.info.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: range.as_entire_binding(),
                },
            ];
            if deposit {
                entries.extend([
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: hair.points.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: hair.absorption.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: hair.segments.as_entire_binding(),
                    },
                ]);
            } else {
                entries.push(wgpu::BindGroupEntry {
                    binding: 5,
                    resource: target.volume.as_entire_binding(),
                });
                entries.push(wgpu::BindGroupEntry {
                    binding: 7,
                    resource: target.solid.as_entire_binding(),
                });
            }
            entries.push(wgpu::BindGroupEntry {
                binding: 4,
                resource: target.sums.as_entire_binding(),
            });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("fiber_density"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
        };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("fiber density"),
            timestamp_writes: timestamps,
        });
        if let (Some(r), Some(range)) = (&segments, &range) {
            pass.set_pipeline(&self.deposit);
            pass.set_bind_group(0, &bind(&self.deposit, range, true), &[]);
            let (x, y) = dispatch_2d(r.end.saturating_sub(r.start));
            pass.dispatch_workgroups(x, y, 1);
        }
        if let (Some(r), Some(voxels)) = (&resolve, &voxels) {
            pass.set_pipeline(&self.resolve);
            pass.set_bind_group(0, &bind(&self.resolve, voxels, false), &[]);
            let (x, y) = dispatch_2d(r.end.saturating_sub(r.start));
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

/// Workgroups of 64 covering `n` invocations, as (x, y) with x <= 65535 (the shader flattens them).
pub fn dispatch_2d(n: u32) -> (u32, u32) {
    let groups = n.div_ceil(64).max(1);
    let x = groups.min(65535);
    (x, groups.div_ceil(x))
}
