//! The occluder (the head, or any mesh) in the picture. The visibility pass draws it opaque before the
//! hair (its samples hold -(triangle + 1)); the occluder pass (`shaders/occluder.wgsl`) shades it as a
//! diffuse surface under the same SRBF lights, light batch by light batch with the hair's shading,
//! each light's irradiance by Hill's fitted SG-cosine convolution ([`sg_irradiance`], against quadrature
//! in the tests) and its transmittance through the hair from the shadow grid; the fiber-density volume
//! holds it as an opaque solid ([`crate::shadow::solid`]), so it shadows the hair. [`shade_occluder`]
//! is the CPU twin.

use crate::envmap::SrbfLight;
use crate::gpu::context::{bind_buffers, compute_pipeline};
use crate::gpu::shaders;
use crate::hair::TriangleMesh;
use crate::render::camera::CameraUniform;
use crate::render::passes::batch::{ShadeBatch, ShadingInputs};
use crate::render::passes::targets::FrameTargets;
use crate::shadow::grid::GridValues;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use wgpu::util::DeviceExt;

/// A diffuse skin albedo (linear; a light skin tone's, about sRGB #c8a08c).
pub const SKIN_ALBEDO: [f32; 3] = [0.58, 0.36, 0.26];
/// The shadow grid is read this many grid spacings off the occluder's surface, along its normal (the
/// grid points next to it lie partly inside the solid).
pub const SHADOW_OFFSET_SPACINGS: f32 = 1.0;
/// A sample's id in [`crate::render::Frame::sample_ids`] when it shows the occluder: triangle + 1 with
/// this bit set.
pub const OCCLUDER_ID_BIT: u32 = 1 << 31;

/// The occluder's triangle (index) of a resolved sample id, if it shows the occluder.
pub fn occluder_triangle(id: u32) -> Option<u32> {
    (id & OCCLUDER_ID_BIT != 0).then(|| (id & !OCCLUDER_ID_BIT) - 1)
}

/// A mesh with its vertex normals and diffuse albedo.
#[derive(Clone, Debug, PartialEq)]
pub struct Occluder {
    pub mesh: TriangleMesh,
    pub normals: Vec<Vec3>,
    pub albedo: [f32; 3],
}

impl Occluder {
    pub fn new(mesh: TriangleMesh, albedo: [f32; 3]) -> Self {
        Self {
            normals: mesh.vertex_normals(),
            mesh,
            albedo,
        }
    }

    /// Where the ray (origin, unit dir) meets triangle `tri`'s plane and the interpolated normal there
    /// (facing the ray): twin of `occluder_surface` in `shaders/occluder.wgsl`.
    pub fn surface(&self, tri: u32, origin: Vec3, dir: Vec3) -> (Vec3, Vec3) {
        let t = self.mesh.triangles[tri as usize];
        let [a, b, c] = t.map(|i| self.mesh.positions[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let face = e1.cross(e2);
        let den = face.dot(dir);
        let t_hit = if den.abs() > 1e-20 {
            face.dot(a - origin) / den
        } else {
            0.0
        };
        let p = origin + t_hit * dir;
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let w = p - a;
        let (d20, d21) = (w.dot(e1), w.dot(e2));
        let det = (d00 * d11 - d01 * d01).max(1e-30);
        let v = ((d11 * d20 - d01 * d21) / det).clamp(0.0, 1.0);
        let u = ((d00 * d21 - d01 * d20) / det).clamp(0.0, 1.0 - v);
        let [na, nb, nc] = t.map(|i| self.normals[i as usize]);
        let mut n = (na * (1.0 - u - v) + nb * v + nc * u).normalize();
        if n.dot(dir) > 0.0 {
            n = -n;
        }
        (p, n)
    }
}

/// Irradiance of an SRBF of unit amplitude (G(w) = exp(2 (w.xi - 1) / lambda^2)) on a surface whose
/// normal makes cosine `mu` with the lobe's centre: Hill 2016's fitted convolution of a spherical
/// Gaussian of sharpness s = 2 / lambda^2 with the clamped cosine, normalised, times 2 pi / s. Twin of
/// `sg_irradiance` in `shaders/occluder.wgsl`.
pub fn sg_irradiance(mu: f32, lambda: f32) -> f32 {
    let s = 2.0 / (lambda * lambda);
    let (c0, c1) = (0.36f32, 1.0 / (4.0 * 0.36f32));
    let eml = (-s).exp();
    let em2l = eml * eml;
    let rl = 1.0 / s;
    let scale = 1.0 + 2.0 * em2l - rl;
    let bias = (eml - em2l) * rl - em2l;
    let x = (1.0 - scale).max(0.0).sqrt();
    let (x0, x1) = (c0 * mu, c1 * x);
    let n = x0 + x1;
    let y = if x0.abs() <= x1 && x > 0.0 {
        n * n / x
    } else {
        mu.clamp(0.0, 1.0)
    };
    // Hill normalises by the approximate integral 2 pi / s (the exact one has a factor 1 - e^-2s).
    (scale * y + bias).max(0.0) * std::f32::consts::TAU / s
}

/// Radiance of the occluder's surface point `p` with normal `n` towards the camera under `lights`
/// (the grid's light k is lights' k), each light scaled by its transmittance read `offset` cm off the
/// surface when shadows are given (clamped at the grid's faces, as the hair reads it, and fading to
/// unshadowed within a grid spacing outside them: [`grid_outside`]). Twin of
/// `shade_occluder` in
/// `shaders/occluder.wgsl`.
pub fn shade_occluder(
    albedo: [f32; 3],
    p: Vec3,
    n: Vec3,
    lights: &[SrbfLight],
    first: usize,
    shadows: Option<&GridValues>,
    offset: f32,
) -> [f32; 3] {
    let q = p + offset * n;
    let outside = shadows.map_or(1.0, |g| grid_outside(&g.grid, q));
    let mut sum = [0f32; 3];
    for (k, l) in lights.iter().enumerate() {
        let e = sg_irradiance(n.dot(l.dir().normalize().as_vec3()), l.lambda as f32);
        if e <= 0.0 {
            continue;
        }
        let t = shadows.map_or(1.0, |g| {
            let t = g.shadow(q, first + k).transmittance;
            t + (1.0 - t) * outside
        });
        for c in 0..3 {
            sum[c] += t * e * l.rgb[c] as f32;
        }
    }
    std::array::from_fn(|c| albedo[c] / std::f32::consts::PI * sum[c])
}

/// How far `p` lies outside the grid's box, in grid spacings, clamped to [0, 1]: the grid's reading
/// (clamped at its faces) fades to unshadowed over one spacing outside it. Twin of `grid_outside` in
/// `shaders/occluder.wgsl`.
pub fn grid_outside(g: &crate::shadow::grid::ShadowGrid, p: Vec3) -> f32 {
    let q = (p - g.origin) / g.spacing;
    let dims = Vec3::from(g.dims.map(|d| d as f32));
    (-q).max(q - dims).max(Vec3::ZERO).length().clamp(0.0, 1.0)
}

/// The occluder's radiance in every pixel of a frame (coverage-weighted: each distinct triangle among
/// a pixel's samples once, with its share), before exposure: the CPU twin of the occluder pass over
/// the frame's sample ids.
pub fn shade_occluder_frame(
    frame: &crate::render::Frame,
    camera: &CameraUniform,
    occluder: &Occluder,
    lights: &[SrbfLight],
    shadows: Option<&GridValues>,
    offset: f32,
) -> Vec<[f32; 3]> {
    use rayon::prelude::*;
    let samples = (frame.samples as usize).min(4);
    (0..frame.pixel_count())
        .into_par_iter()
        .map(|i| {
            let ids = &frame.sample_ids[i][..samples];
            let (x, y) = (
                (i % frame.width as usize) as f32,
                (i / frame.width as usize) as f32,
            );
            let (origin, dir) = crate::render::camera::pixel_ray(camera, x + 0.5, y + 0.5);
            let mut out = [0f32; 3];
            for (k, &id) in ids.iter().enumerate() {
                let Some(tri) = occluder_triangle(id) else {
                    continue;
                };
                if ids[..k].contains(&id) {
                    continue;
                }
                let count = ids.iter().filter(|&&o| o == id).count();
                let (p, n) = occluder.surface(tri, origin, dir);
                let l = shade_occluder(occluder.albedo, p, n, lights, 0, shadows, offset);
                for c in 0..3 {
                    out[c] += count as f32 / frame.samples as f32 * l[c];
                }
            }
            // Seen through the hair in front of it.
            let t = frame
                .pixel_fragments
                .get(i)
                .map_or(1.0, |p| p.occluder_transmittance);
            out.map(|v| t * v)
        })
        .collect()
}

/// The occluder pass's parameters (a storage buffer: lavapipe recompiles per bind group what it
/// inlines from uniforms).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct OccluderInfo {
    pub albedo: [f32; 3],
    pub normal_offset: f32,
}

const _: () = assert!(std::mem::size_of::<OccluderInfo>() == 16);

/// The occluder on the GPU: positions and normals (xyz, 0), three indices per triangle.
pub struct GpuOccluder {
    pub positions: wgpu::Buffer,
    pub normals: wgpu::Buffer,
    pub triangles: wgpu::Buffer,
    pub info: wgpu::Buffer,
    pub triangle_count: u32,
    normal_offset: f32,
}

impl GpuOccluder {
    pub fn new(device: &wgpu::Device, occluder: &Occluder, normal_offset: f32) -> Self {
        let storage = |label: &str, bytes: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let vec4 =
            |v: &[Vec3]| -> Vec<[f32; 4]> { v.iter().map(|p| p.extend(0.0).to_array()).collect() };
        let info = OccluderInfo {
            albedo: occluder.albedo,
            normal_offset,
        };
        Self {
            positions: storage(
                "occluder positions",
                bytemuck::cast_slice(&vec4(&occluder.mesh.positions)),
            ),
            normals: storage(
                "occluder normals",
                bytemuck::cast_slice(&vec4(&occluder.normals)),
            ),
            triangles: storage(
                "occluder triangles",
                bytemuck::cast_slice(&occluder.mesh.triangles),
            ),
            info: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("occluder info"),
                contents: bytemuck::bytes_of(&info),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            }),
            triangle_count: occluder.mesh.triangles.len() as u32,
            normal_offset,
        }
    }

    pub fn set_albedo(&self, queue: &wgpu::Queue, albedo: [f32; 3]) {
        let info = OccluderInfo {
            albedo,
            normal_offset: self.normal_offset,
        };
        queue.write_buffer(&self.info, 0, bytemuck::bytes_of(&info));
    }
}

/// The occluder's shading: one dispatch per light batch (with the hair's first visibility sample's
/// batch, or the preview's), adding to the occluder buffer.
pub struct OccluderPass {
    pipeline: wgpu::ComputePipeline,
}

impl OccluderPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("occluder"),
            source: wgpu::ShaderSource::Wgsl(shaders::occluder_module().into()),
        });
        Self {
            pipeline: compute_pipeline(device, &module, "shade"),
        }
    }

    /// The batch's lights over its rows.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        occluder: &GpuOccluder,
        targets: &FrameTargets,
        batch: &ShadeBatch,
    ) {
        // A storage buffer, not a uniform: lavapipe inlines a uniform's values into the loops that
        // depend on them and recompiles per bind group (shadow_grid_build.wgsl).
        let batch_buffer = crate::gpu::context::buffer_init(
            device,
            "occluder batch",
            bytemuck::bytes_of(batch),
            wgpu::BufferUsages::STORAGE,
        );
        let buffers = [
            inputs.camera,
            &batch_buffer,
            inputs.shadow_grid,
            inputs.lights,
            inputs.shadow_values,
            &occluder.positions,
            &occluder.normals,
            &occluder.triangles,
            &occluder.info,
        ];
        let bind = bind_buffers(
            device,
            &self.pipeline,
            "occluder",
            &buffers,
            vec![
                wgpu::BindGroupEntry {
                    binding: 9,
                    resource: wgpu::BindingResource::TextureView(&targets.visibility),
                },
                wgpu::BindGroupEntry {
                    binding: 10,
                    resource: targets.occluder.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 11,
                    resource: targets.kbuffer.pixel_info.as_entire_binding(),
                },
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("occluder"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(targets.width.div_ceil(8), batch.rows.div_ceil(8), 1);
    }
}

/// Whether a batch also shades the occluder: the front K-buffer slot's (the occluder pass reads every
/// one of its own samples itself).
pub fn shades_occluder(batch: &ShadeBatch) -> bool {
    batch.slot == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The irradiance by quadrature over the sphere (the obviously-correct reference).
    fn irradiance_quadrature(mu: f64, lambda: f64) -> f64 {
        let n = glam::DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), mu, 0.0);
        let (nt, np) = (800, 1600);
        let mut sum = 0.0;
        for i in 0..nt {
            let theta = std::f64::consts::PI * (i as f64 + 0.5) / nt as f64;
            for j in 0..np {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5) / np as f64;
                let w = glam::DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                let g = (2.0 * (w.y - 1.0) / (lambda * lambda)).exp();
                sum += g * n.dot(w).max(0.0) * theta.sin();
            }
        }
        sum * std::f64::consts::PI / nt as f64 * std::f64::consts::TAU / np as f64
    }

    #[test]
    fn fitted_sg_irradiance_against_quadrature() {
        // The lobe widths of the committed fits (lambda from ~0.05 to ~1.5), normals from facing to
        // behind the lobe.
        let mut worst: f64 = 0.0;
        let mut worst_abs: f64 = 0.0;
        for lambda in [0.05, 0.15, 0.3, 0.6, 1.0, 1.5] {
            let mut w: f64 = 0.0;
            let peak = irradiance_quadrature(1.0, lambda);
            for mu in [1.0, 0.8, 0.5, 0.2, 0.0, -0.2, -0.5, -1.0] {
                let exact = irradiance_quadrature(mu, lambda);
                let fit = sg_irradiance(mu as f32, lambda as f32) as f64;
                // Relative to the lobe's peak irradiance (where it is lit at all).
                let err = (fit - exact).abs() / peak;
                worst_abs = worst_abs.max(err);
                w = w.max(err);
                if exact > 0.05 * peak {
                    worst = worst.max((fit - exact).abs() / exact);
                }
            }
            println!("lambda {lambda}: worst {:.2} % of the peak", 100.0 * w);
        }
        println!(
            "SG irradiance, fitted against quadrature: worst {:.1} % where lit (> 5 % of the peak), \
             {:.2} % of the peak anywhere",
            100.0 * worst,
            100.0 * worst_abs
        );
        // The fit's error is an error of energy: bounded against the lobe's peak irradiance (the
        // relative error is large only where little light arrives: a wide lobe seen from behind).
        assert!(worst_abs < 0.05, "{worst} {worst_abs}");
    }

    #[test]
    fn the_surface_point_and_normal_of_a_ray() {
        // The plain ellipsoid (no face): its implicit's gradient is the normal to compare with.
        let head = crate::hair::procedural::Head {
            face: false,
            ..Default::default()
        };
        let occ = Occluder::new(head.mesh(32, false), SKIN_ALBEDO);
        let origin = Vec3::new(0.3, 0.5, 40.0);
        let dir = Vec3::new(0.0, 0.0, -1.0);
        let (_, tri, _) = occ
            .mesh
            .intersect(origin, dir, 0.0)
            .expect("the ray hits the head");
        let (p, n) = occ.surface(tri as u32, origin, dir);
        // On the ellipsoid (the mesh is inscribed: a little inside), the normal its gradient's.
        let implicit = head.implicit(p);
        assert!(implicit <= 1.0 + 1e-4 && implicit > 0.98, "{implicit}");
        let grad = (p / (head.radii * head.radii)).normalize();
        assert!(n.dot(grad) > 0.995, "{n} {grad}");
    }
}
