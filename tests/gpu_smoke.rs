//! GPU smoke test: a device on whatever adapter exists (lavapipe in CI) runs a compute shader.
//! Without an adapter this FAILS with instructions; it never passes silently.

use strandlight::gpu::{GpuContext, GpuOptions};
use wgpu::util::DeviceExt;

const SHADER: &str = r#"
@group(0) @binding(0) var<storage, read_write> data: array<f32>;

// Each invocation replaces x by x * x + 1 (so a wrong dispatch or binding is visible).
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i < arrayLength(&data)) {
        data[i] = data[i] * data[i] + 1.0;
    }
}
"#;

#[test]
fn compute_shader_runs_on_the_adapter() {
    let ctx = match GpuContext::new_headless(&GpuOptions::from_env()) {
        Ok(c) => c,
        Err(e) => panic!("GPU smoke test needs an adapter: {e}"),
    };
    println!("adapter: {:?}", ctx.summary);
    if let Ok(b) = std::env::var("WGPU_BACKEND") {
        // CI pins Vulkan: a silent fallback to GL would hide a missing driver.
        assert!(
            ctx.summary
                .backend
                .to_lowercase()
                .contains(&b.to_lowercase()),
            "WGPU_BACKEND={b} but the adapter is on {}",
            ctx.summary.backend
        );
    }
    let n = 1000usize;
    let input: Vec<f32> = (0..n).map(|i| i as f32 * 0.01).collect();
    let device = &ctx.device;
    let storage = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("smoke data"),
        contents: bytemuck::cast_slice(&input),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("smoke readback"),
        size: (n * 4) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("smoke"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("smoke"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("smoke"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: storage.as_entire_binding(),
        }],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(n.div_ceil(64) as u32, 1, 1);
    }
    enc.copy_buffer_to_buffer(&storage, 0, &readback, 0, (n * 4) as u64);
    ctx.queue.submit([enc.finish()]);
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.expect("map readback"));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("device poll");
    let view = slice.get_mapped_range().expect("mapped range");
    let out: &[f32] = bytemuck::cast_slice(&view);
    for (i, (&x, &y)) in input.iter().zip(out).enumerate() {
        assert!(
            (y - (x * x + 1.0)).abs() < 1e-5,
            "element {i}: {y} != {x}^2 + 1"
        );
    }
    println!("compute smoke test: {n} values correct");
}
