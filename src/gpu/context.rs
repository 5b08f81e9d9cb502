//! Headless wgpu device creation.

use serde::Serialize;
use std::sync::Arc;

/// How to pick an adapter.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Ask for a software (CPU) adapter such as lavapipe. Also set by `STRANDLIGHT_SOFTWARE_GPU=1`.
    pub force_software: bool,
}

impl GpuOptions {
    pub fn from_env() -> Self {
        let force_software = std::env::var("STRANDLIGHT_SOFTWARE_GPU")
            .map(|v| v == "1" || v.eq_ignore_ascii_case("true"))
            .unwrap_or(false);
        Self { force_software }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found ({0}). Install a Vulkan driver; on Debian/Ubuntu without a GPU: \
         `apt-get install mesa-vulkan-drivers libvulkan1` (software Vulkan, lavapipe)"
    )]
    NoAdapter(String),
    #[error(
        "the GPU adapter '{adapter}' lacks what the hair's K-buffer needs (of {missing}: 64-bit atomics, \
         Vulkan's VK_KHR_shader_atomic_int64), and no other adapter has it; on Debian/Ubuntu \
         `apt-get install mesa-vulkan-drivers` gives lavapipe, which has it"
    )]
    MissingFeatures { adapter: String, missing: String },
    #[error("the GPU adapter '{adapter}' refused a device: {source}")]
    RequestDevice {
        adapter: String,
        source: wgpu::RequestDeviceError,
    },
}

/// What was chosen, for logs and benchmark JSON.
#[derive(Clone, Debug, Serialize)]
pub struct AdapterSummary {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
}

impl AdapterSummary {
    fn new(info: &wgpu::AdapterInfo) -> Self {
        Self {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
        }
    }
}

/// What the renderer cannot do without: 64-bit integers and their atomics (the K-buffer's keys,
/// `shaders/kbuffer.wgsl`). Vulkan has them with VK_KHR_shader_atomic_int64 (NVIDIA, AMD, Intel,
/// lavapipe), DX12 with shader model 6.6.
pub const REQUIRED_FEATURES: wgpu::Features = wgpu::Features::SHADER_INT64
    .union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX)
    .union(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS);

/// A device and queue, with the adapter they came from.
#[derive(Clone)]
pub struct GpuContext {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub summary: AdapterSummary,
}

impl GpuContext {
    /// Creates a device without a window. Backends can be restricted with `WGPU_BACKEND`
    /// (e.g. `vulkan`); the device gets the adapter's own limits and the optional features
    /// strandlight uses when they are available (timestamp queries, float32 filtering).
    pub fn new_headless(options: &GpuOptions) -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: options.force_software,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        // The preferred adapter may lack the K-buffer's 64-bit atomics where another has them
        // (DX12 below shader model 6.6 beside Vulkan): take the first that has them.
        let adapter = if adapter.features().contains(REQUIRED_FEATURES) {
            adapter
        } else {
            let others = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
            others
                .into_iter()
                .filter(|a| {
                    !options.force_software || a.get_info().device_type == wgpu::DeviceType::Cpu
                })
                .find(|a| a.features().contains(REQUIRED_FEATURES))
                .ok_or_else(|| GpuError::MissingFeatures {
                    adapter: adapter.get_info().name,
                    missing: format!("{REQUIRED_FEATURES:?}"),
                })?
        };
        let info = adapter.get_info();
        let summary = AdapterSummary::new(&info);
        let (device, queue) =
            pollster::block_on(adapter.request_device(&Self::device_descriptor(&adapter)))
                .map_err(|source| GpuError::RequestDevice {
                    adapter: summary.name.clone(),
                    source,
                })?;
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            summary,
        })
    }

    /// A context around a device someone else created (the editor's, shared with egui).
    pub fn from_parts(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Self {
        let summary = AdapterSummary::new(&adapter.get_info());
        Self {
            instance,
            adapter,
            device,
            queue,
            summary,
        }
    }

    /// The features and limits the renderer asks of `adapter` (eframe must request the same).
    pub fn device_descriptor(adapter: &wgpu::Adapter) -> wgpu::DeviceDescriptor<'static> {
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::FLOAT32_FILTERABLE;
        wgpu::DeviceDescriptor {
            label: Some("strandlight device"),
            // The K-buffer's 64-bit atomics are required: without them device creation names them.
            required_features: (adapter.features() & wanted) | REQUIRED_FEATURES,
            required_limits: adapter.limits(),
            ..Default::default()
        }
    }

    /// Copies `buffer` (which needs COPY_SRC) into a mappable buffer after the work already submitted,
    /// waits for the GPU, and returns its contents as `T`s (tests, read-backs of results).
    pub fn read_buffer<T: bytemuck::Pod>(&self, buffer: &wgpu::Buffer) -> Result<Vec<T>, String> {
        let size = buffer.size();
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buffer, 0, &readback, 0, size);
        self.queue.submit([enc.finish()]);
        let slice = readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| format!("waiting for the GPU: {e}"))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| format!("reading a buffer back: {e}"))?;
        // Copied out, so the result is aligned for T whatever the mapping's alignment.
        Ok(bytemuck::pod_collect_to_vec(&data[..]))
    }
}

/// Buffers being copied back without waiting (the editor's export): [`GpuContext::start_read`], then
/// [`PendingRead::poll`] once a frame until the copies are mapped.
pub struct PendingRead {
    buffers: Vec<wgpu::Buffer>,
    mapped: Arc<std::sync::atomic::AtomicUsize>,
    failed: Arc<std::sync::atomic::AtomicBool>,
}

impl PendingRead {
    /// The contents of every buffer (bytes, in the order given) once all are mapped; None while
    /// the GPU is still at them (this polls the device without blocking).
    pub fn poll(&self, device: &wgpu::Device) -> Option<Result<Vec<Vec<u8>>, String>> {
        use std::sync::atomic::Ordering;
        if let Err(e) = device.poll(wgpu::PollType::Poll) {
            return Some(Err(format!("waiting for the GPU: {e}")));
        }
        if self.failed.load(Ordering::Acquire) {
            return Some(Err("a read-back buffer could not be mapped".into()));
        }
        if self.mapped.load(Ordering::Acquire) < self.buffers.len() {
            return None;
        }
        let out = self
            .buffers
            .iter()
            .map(|b| {
                b.slice(..)
                    .get_mapped_range()
                    .map(|d| d.to_vec())
                    .map_err(|e| format!("reading a buffer back: {e}"))
            })
            .collect();
        Some(out)
    }
}

impl GpuContext {
    /// Copies each of `buffers` (COPY_SRC) into a mappable buffer after the work already
    /// submitted and asks for them mapped, without waiting (see [`PendingRead`]).
    pub fn start_read(&self, buffers: &[&wgpu::Buffer]) -> PendingRead {
        use std::sync::atomic::Ordering;
        let mut enc = self.device.create_command_encoder(&Default::default());
        let copies: Vec<wgpu::Buffer> = buffers
            .iter()
            .map(|b| {
                let c = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("readback"),
                    size: b.size(),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                enc.copy_buffer_to_buffer(b, 0, &c, 0, b.size());
                c
            })
            .collect();
        self.queue.submit([enc.finish()]);
        let mapped = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let failed = Arc::new(std::sync::atomic::AtomicBool::new(false));
        for c in &copies {
            let (mapped, failed) = (mapped.clone(), failed.clone());
            c.slice(..)
                .map_async(wgpu::MapMode::Read, move |r| match r {
                    Ok(()) => {
                        mapped.fetch_add(1, Ordering::AcqRel);
                    }
                    Err(_) => failed.store(true, Ordering::Release),
                });
        }
        PendingRead {
            buffers: copies,
            mapped,
            failed,
        }
    }

    /// Runs a batch kernel: `inputs` bound at bindings 0.. of group 0, then the `queries` (a storage
    /// buffer), then a results buffer of `per_query` values of R for each query; one invocation per
    /// query in workgroups of 64; returns the results read back.
    pub fn run_batch<Q: bytemuck::Pod, R: bytemuck::Pod>(
        &self,
        pipeline: &wgpu::ComputePipeline,
        inputs: &[&wgpu::Buffer],
        queries: &[Q],
        per_query: usize,
    ) -> Result<Vec<R>, String> {
        use wgpu::util::DeviceExt;
        if queries.is_empty() {
            return Ok(Vec::new());
        }
        let q = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("batch queries"),
                contents: bytemuck::cast_slice(queries),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let size = (queries.len() * per_query * std::mem::size_of::<R>()) as u64;
        let results = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("batch results"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let buffers: Vec<&wgpu::Buffer> = inputs.iter().copied().chain([&q, &results]).collect();
        let bind = bind_buffers(&self.device, pipeline, "batch", &buffers, Vec::new());
        let mut enc = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(queries.len().div_ceil(64) as u32, 1, 1);
        }
        self.queue.submit([enc.finish()]);
        self.read_buffer(&results)
    }
}

/// A compute pipeline for one entry point of `module`, with the layout derived from the shader.
pub fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A buffer holding `contents`, as `DeviceExt::create_buffer_init` makes it, except that a lost
/// device does not panic: wgpu's helper unwraps the mapping, which fails once the device is gone, and
/// the frame loop makes small buffers per unit (a lost device must reach the editor as an error).
/// The largest storage buffer the device binds (the binding's limit or the buffer's, the smaller).
pub fn binding_limit(device: &wgpu::Device) -> u64 {
    let l = device.limits();
    l.max_storage_buffer_binding_size.min(l.max_buffer_size)
}

pub fn buffer_init(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let align = wgpu::COPY_BUFFER_ALIGNMENT;
    let size = (contents.len() as u64).div_ceil(align).max(1) * align;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: true,
    });
    // On a lost device the buffer is invalid and never mapped: unmapping it would be one more error.
    if let Ok(mut view) = buffer.get_mapped_range_mut(..) {
        view.slice(..contents.len()).copy_from_slice(contents);
        drop(view);
        buffer.unmap();
    }
    buffer
}

/// A bind group for group 0 of `pipeline` of the given (binding, buffer) pairs.
pub fn bind_entries(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    label: &str,
    entries: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = entries
        .iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}

/// A bind group for group 0 of `pipeline`: `buffers` at bindings 0, 1, ... and the `extra` entries.
pub fn bind_buffers(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    label: &str,
    buffers: &[&wgpu::Buffer],
    extra: Vec<wgpu::BindGroupEntry>,
) -> wgpu::BindGroup {
    let mut entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    entries.extend(extra);
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}
