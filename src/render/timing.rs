//! GPU time per pass from timestamp queries (when the adapter has TIMESTAMP_QUERY).

use crate::gpu::GpuContext;

/// A query set with a begin and an end timestamp per named pass.
pub struct PassTimer {
    names: Vec<&'static str>,
    query_set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    period_ns: f32,
}

impl PassTimer {
    /// None when the device lacks timestamp queries.
    pub fn new(ctx: &GpuContext, names: &[&'static str]) -> Option<Self> {
        if !ctx
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
        {
            return None;
        }
        let count = 2 * names.len() as u32;
        Some(Self {
            names: names.to_vec(),
            query_set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolved: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: count as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            period_ns: ctx.queue.get_timestamp_period(),
        })
    }

    fn index(&self, pass: &str) -> Option<u32> {
        self.names
            .iter()
            .position(|n| *n == pass)
            .map(|i| 2 * i as u32)
    }

    pub fn compute_writes(&self, pass: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.index(pass).map(|i| wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        })
    }

    pub fn render_writes(&self, pass: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.index(pass).map(|i| wgpu::RenderPassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        })
    }

    /// Copies the timestamps into the readable buffer (call last in the frame's encoder).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(
            &self.query_set,
            0..2 * self.names.len() as u32,
            &self.resolved,
            0,
        );
    }

    /// Milliseconds per pass of the last resolved frame, for the passes in `ran` (others are stale).
    pub fn read_ms(
        &self,
        ctx: &GpuContext,
        ran: &[&'static str],
    ) -> Result<Vec<(&'static str, f64)>, String> {
        let ticks: Vec<u64> = ctx.read_buffer(&self.resolved)?;
        Ok(self
            .names
            .iter()
            .enumerate()
            .filter(|(_, n)| ran.contains(n))
            .map(|(i, n)| {
                let dt = ticks[2 * i + 1].saturating_sub(ticks[2 * i]);
                (*n, dt as f64 * self.period_ns as f64 * 1e-6)
            })
            .collect())
    }
}
