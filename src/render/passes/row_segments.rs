//! Where a frame's segment shading lies, for sizing progressive refinement's bands
//! (`mark_first_rows` and `count_first_rows` of `shaders/shading.wgsl`): per image row, the visible
//! segments whose topmost kept fragment lies in it. Bands run from the top and each light batch
//! claims a segment in the first band that shows it, so these are exactly the segments a band of
//! rows shades, and a band's cost is about its count times the cost of a segment under a light. The
//! counts are read back asynchronously after the visibility pass (a few kilobytes, never waited for).

use crate::gpu::context::{bind_entries as bind, compute_pipeline};
use crate::render::frame::Frame;
use crate::render::passes::segment_shading::SegmentTargets;
use std::sync::{Arc, Mutex};

/// The counts from a frame's K-buffer (the CPU twin of the two kernels).
pub fn row_segments(frame: &Frame) -> Vec<u32> {
    let width = frame.width as usize;
    let mut first_row: std::collections::HashMap<u32, usize> = Default::default();
    for i in 0..frame.pixel_count() {
        for f in frame.kept_fragments(i).iter().filter(|f| f.weight > 0.0) {
            let row = first_row.entry(f.id).or_insert(i / width);
            *row = (*row).min(i / width);
        }
    }
    let mut counts = vec![0; frame.height as usize];
    for row in first_row.into_values() {
        counts[row] += 1;
    }
    counts
}

/// The two kernels.
pub struct RowSegmentsPass {
    mark: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
}

/// What the kernels read and write.
pub struct RowSegmentsInputs<'a> {
    pub camera: &'a wgpu::Buffer,
    /// A frame batch's uniform (its K-buffer slots).
    pub batch: &'a wgpu::Buffer,
    pub fragments: &'a wgpu::Buffer,
    pub segments: &'a SegmentTargets,
    pub segment_count: u32,
    pub height: u32,
}

impl RowSegmentsPass {
    pub fn new(device: &wgpu::Device, module: &wgpu::ShaderModule) -> Self {
        Self {
            mark: compute_pipeline(device, module, "mark_first_rows"),
            count: compute_pipeline(device, module, "count_first_rows"),
        }
    }

    /// Counts into `counts` (one u32 per row). Leaves the segments' claims cleared.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &RowSegmentsInputs,
        width: u32,
        counts: &wgpu::Buffer,
    ) {
        inputs.segments.clear(encoder);
        encoder.clear_buffer(counts, 0, None);
        let mark = bind(
            device,
            &self.mark,
            "mark first rows",
            &[
                (0, inputs.camera),
                (2, inputs.batch),
                (18, inputs.fragments),
                (20, &inputs.segments.batches),
            ],
        );
        let count = bind(
            device,
            &self.count,
            "count first rows",
            &[
                (0, inputs.camera),
                (20, &inputs.segments.batches),
                (29, counts),
            ],
        );
        let groups = inputs.segment_count.max(1).div_ceil(64);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("row segments"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.mark);
        pass.set_bind_group(0, &mark, &[]);
        pass.dispatch_workgroups(width.div_ceil(8), inputs.height.div_ceil(8), 1);
        pass.set_pipeline(&self.count);
        pass.set_bind_group(0, &count, &[]);
        pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
        drop(pass);
        inputs.segments.clear(encoder);
    }
}

enum ReadState {
    /// Copied, not yet asked for.
    Copied,
    Mapping,
    Mapped,
    Failed,
}

/// The counts' buffer and the read-back under way.
pub struct RowSegmentsReadback {
    pub counts: wgpu::Buffer,
    height: u32,
    pending: Option<(wgpu::Buffer, Arc<Mutex<ReadState>>)>,
}

impl RowSegmentsReadback {
    pub fn new(device: &wgpu::Device, height: u32) -> Self {
        Self {
            counts: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("row segments"),
                size: 4 * height.max(1) as u64,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            height,
            pending: None,
        }
    }

    /// Drops a read-back under way.
    pub fn cancel(&mut self) {
        self.pending = None;
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Copies the counts for reading (after [`RowSegmentsPass::encode`] in the same encoder); a
    /// read-back still under way is dropped.
    pub fn encode_copy(&mut self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder) {
        let size = self.counts.size();
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("row segments read-back"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.copy_buffer_to_buffer(&self.counts, 0, &staging, 0, size);
        self.pending = Some((staging, Arc::new(Mutex::new(ReadState::Copied))));
    }

    /// After the copy's submission: asks for the mapping (it lands in a later poll).
    pub fn request(&mut self) {
        let Some((staging, state)) = &self.pending else {
            return;
        };
        {
            let Ok(mut s) = state.lock() else {
                return;
            };
            if !matches!(*s, ReadState::Copied) {
                return;
            }
            *s = ReadState::Mapping;
        }
        // The lock is released: wgpu may call back at once (a lost device does).
        let flag = state.clone();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            if let Ok(mut s) = flag.lock() {
                *s = if r.is_ok() {
                    ReadState::Mapped
                } else {
                    ReadState::Failed
                };
            }
        });
    }

    /// The counts, once mapped (after a device poll); None while under way or when none was asked
    /// for. A failed read-back is dropped.
    pub fn take(&mut self) -> Option<Vec<u32>> {
        let (staging, state) = self.pending.as_ref()?;
        let done = match state.lock().as_deref() {
            Ok(ReadState::Mapped) => true,
            Ok(ReadState::Failed) | Err(_) => false,
            Ok(_) => return None,
        };
        let counts = done
            .then(|| staging.slice(..).get_mapped_range().ok())
            .flatten()
            .map(|bytes| bytemuck::cast_slice::<u8, u32>(&bytes).to_vec());
        self.pending = None;
        counts
    }
}

impl crate::render::Renderer {
    /// The frame's visible segments per row (topmost row) as refinement holds them: None until they
    /// are read back after the view's visibility pass (shading by segment only).
    pub fn row_segments(&self) -> Option<&[u32]> {
        self.refinement.costs.row_segments.as_deref()
    }

    /// The same for the preview's K-buffer.
    pub fn preview_row_segments(&self) -> Option<&[u32]> {
        self.preview.as_ref()?.row_segments.as_deref()
    }

    /// After the frame's whole visibility pass (in the same encoder): counts its segments per row
    /// when refinement has no counts for this view and the frame shades by segment.
    pub(in crate::render) fn encode_row_segments(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let mut readback = self.row_readback.take();
        self.encode_row_segments_into(device, encoder, &mut readback);
        self.row_readback = readback;
    }

    /// [`Self::encode_row_segments`] with the read-back apart (`render_frame` holds its timer).
    pub(in crate::render) fn encode_row_segments_into(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        readback: &mut Option<RowSegmentsReadback>,
    ) {
        let Some(segments) = self
            .view
            .segment_targets
            .as_ref()
            .filter(|_| self.by_segment)
        else {
            return;
        };
        if self.refinement.costs.row_segments.is_some() {
            return;
        }
        let r = ready_readback(device, readback, self.view.targets.height);
        self.passes.shading_pass.encode_row_segments(
            device,
            encoder,
            &self.view.camera,
            &self.view.targets,
            segments,
            r,
        );
    }

    /// After the preview's whole visibility pass: the same for the preview's K-buffer.
    pub(in crate::render) fn encode_preview_row_segments(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let Some(segments) = self
            .view
            .segment_targets
            .as_ref()
            .filter(|_| self.by_segment)
        else {
            return;
        };
        let Some(p) = self.preview.as_mut() else {
            return;
        };
        p.row_segments = None;
        let r = ready_readback(device, &mut p.row_readback, p.targets.height);
        self.passes
            .shading_pass
            .encode_row_segments(device, encoder, &p.camera, &p.targets, segments, r);
    }

    /// After a submission: asks for the counts' mapping if they were copied in it.
    pub(in crate::render) fn request_row_segments(&mut self) {
        let preview = self.preview.as_mut().and_then(|p| p.row_readback.as_mut());
        for r in self.row_readback.iter_mut().chain(preview) {
            r.request();
        }
    }

    /// After a device poll: hands counts that have landed to refinement (and the preview).
    pub(in crate::render) fn receive_row_segments(&mut self) {
        let height = self.view.targets.height as usize;
        if let Some(counts) = self.row_readback.as_mut().and_then(|r| r.take())
            && counts.len() == height
        {
            self.refinement.costs.row_segments = Some(counts);
        }
        if let Some(p) = &mut self.preview
            && let Some(counts) = p.row_readback.as_mut().and_then(|r| r.take())
            && counts.len() == p.targets.height as usize
        {
            p.row_segments = Some(counts);
        }
    }

    /// The view changed: the counts (and read-backs under way) no longer describe it.
    pub(in crate::render) fn forget_row_segments(&mut self) {
        self.refinement.costs.row_segments = None;
        if let Some(r) = &mut self.row_readback {
            r.cancel();
        }
        if let Some(p) = &mut self.preview {
            p.row_segments = None;
            if let Some(r) = &mut p.row_readback {
                r.cancel();
            }
        }
    }
}

/// `slot`'s read-back, made anew unless it has `height` rows.
fn ready_readback<'a>(
    device: &wgpu::Device,
    slot: &'a mut Option<RowSegmentsReadback>,
    height: u32,
) -> &'a mut RowSegmentsReadback {
    match slot.take() {
        Some(r) if r.height() == height => slot.insert(r),
        _ => slot.insert(RowSegmentsReadback::new(device, height)),
    }
}
