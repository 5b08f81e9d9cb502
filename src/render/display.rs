//! The viewport's display pass (`shaders/display.wgsl`): the resolved beauty through a view transform
//! (standard or filmic, with a viewport exposure) over the environment (composited in linear light
//! before the transform) or a flat colour (mixed after it), into an Rgba8Unorm texture
//! that egui draws. Display only: stills and EXRs never pass here. [`display_pixel`] is the CPU twin.

use crate::colour::{aces_filmic, srgb_encode};
use crate::gpu::context::{bind_buffers, compute_pipeline};
use crate::render::passes::targets::FrameTargets;
use crate::render::refine::DisplayImage;
use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

pub const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// What the viewport shows: the beauty or one scattering component alone (the AOVs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Solo {
    #[default]
    Beauty,
    /// Index into the components: R, TT, TRT, MS.global, MS.local.
    Component(usize),
}

/// How linear radiance becomes a display value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ViewTransform {
    /// Clamp to [0, 1], sRGB encode.
    Standard,
    /// Narkowicz's fit of the ACES filmic curve, sRGB encode (the PNG previews' curve).
    #[default]
    Filmic,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct DisplayInfo {
    pub width: u32,
    pub height: u32,
    pub transform: u32,
    /// 0: the beauty; 1: the bound component alone.
    pub solo: u32,
    pub exposure_scale: f32,
    pub render_scale: f32,
    /// Size of the full image (the display's, or another, sampled bilinearly).
    pub source: [u32; 2],
    /// The flat background, display-encoded (without `environment`, or with a solo component).
    pub background: [f32; 3],
    /// 1: the beauty over the image's background target (the environment), in linear light.
    pub environment: u32,
    /// Size of the preview, and the rows of the full image drawn over it (every row: no preview).
    pub preview_source: [u32; 2],
    pub sharp_rows: u32,
    pub _pad3: u32,
}

const _: () = assert!(std::mem::size_of::<DisplayInfo>() == 64);

impl DisplayInfo {
    pub fn new(
        width: u32,
        height: u32,
        transform: ViewTransform,
        exposure_ev: f32,
        background: [f32; 3],
    ) -> Self {
        Self {
            width,
            height,
            transform: transform as u32,
            solo: 0,
            exposure_scale: exposure_ev.exp2(),
            render_scale: 1.0,
            source: [width, height],
            background,
            environment: 0,
            preview_source: [width, height],
            sharp_rows: u32::MAX,
            _pad3: 0,
        }
    }
}

/// One display value of the view transform (twin of the WGSL `view_transform`).
pub fn view_transform(x: f32, transform: ViewTransform) -> f32 {
    match transform {
        ViewTransform::Filmic => srgb_encode(aces_filmic(x)),
        ViewTransform::Standard => srgb_encode(x.clamp(0.0, 1.0)),
    }
}

/// One displayed pixel from a premultiplied beauty pixel, the solo component and the background
/// behind the pixel (twin of the WGSL `display_pixel`).
pub fn display_pixel(
    info: &DisplayInfo,
    beauty: [f32; 4],
    component: [f32; 4],
    background: [f32; 4],
) -> [f32; 4] {
    let t = if info.transform == 1 {
        ViewTransform::Filmic
    } else {
        ViewTransform::Standard
    };
    if info.environment == 1 && info.solo == 0 {
        let k = (1.0 - beauty[3]).clamp(0.0, 1.0);
        let c: [f32; 3] = std::array::from_fn(|i| {
            view_transform(info.exposure_scale * (beauty[i] + k * background[i]), t)
        });
        return [c[0], c[1], c[2], 1.0];
    }
    let p = if info.solo == 1 {
        let s = info.render_scale;
        [
            s * component[0],
            s * component[1],
            s * component[2],
            beauty[3],
        ]
    } else {
        beauty
    };
    let a = p[3].clamp(0.0, 1.0);
    let un = if p[3] > 0.0 {
        info.exposure_scale / p[3]
    } else {
        0.0
    };
    let c: [f32; 3] = std::array::from_fn(|i| view_transform(p[i] * un, t));
    let b = info.background;
    [
        b[0] + a * (c[0] - b[0]),
        b[1] + a * (c[1] - b[1]),
        b[2] + a * (c[2] - b[2]),
        1.0,
    ]
}

/// The premultiplied value of `image` (a `source`-sized image) under display pixel (x, y) of a
/// `display`-sized one: itself at the same size, bilinear with pixel centres aligned otherwise (twin of
/// the WGSL `source_taps` and `bilinear`).
pub fn source_sample(
    display: [u32; 2],
    source: [u32; 2],
    image: &[[f32; 4]],
    x: u32,
    y: u32,
) -> [f32; 4] {
    let [sw, sh] = source.map(|v| v.max(1));
    if [sw, sh] == display {
        return image[(y * sw + x) as usize];
    }
    let axis = |i: u32, s: u32, d: u32| {
        let p = ((i as f32 + 0.5) * s as f32 / d as f32 - 0.5).max(0.0);
        let c0 = (p.floor() as u32).min(s - 1);
        (c0, (c0 + 1).min(s - 1), p - p.floor())
    };
    let (x0, x1, fx) = axis(x, sw, display[0]);
    let (y0, y1, fy) = axis(y, sh, display[1]);
    let at = |x: u32, y: u32| image[(y * sw + x) as usize];
    let (a, b, c, d) = (at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1));
    std::array::from_fn(|k| {
        let top = a[k] + (b[k] - a[k]) * fx;
        let bottom = c[k] + (d[k] - c[k]) * fx;
        top + (bottom - top) * fy
    })
}

/// A beauty, a solo component and the background of one image, as the display reads them.
pub type DisplaySource<'a> = (&'a [[f32; 4]], &'a [[f32; 4]], &'a [[f32; 4]]);

/// Display pixel (x, y): the full image's rows above `info.sharp_rows`, the preview's below, each
/// sampled to the display's size, through [`display_pixel`] (twin of the WGSL `display`).
pub fn displayed_pixel(
    info: &DisplayInfo,
    full: DisplaySource,
    preview: DisplaySource,
    x: u32,
    y: u32,
) -> [f32; 4] {
    let display = [info.width, info.height];
    let row = y * info.source[1] / info.height.max(1);
    let (size, (beauty, component, background)) = if row >= info.sharp_rows {
        (info.preview_source, preview)
    } else {
        (info.source, full)
    };
    display_pixel(
        info,
        source_sample(display, size, beauty, x, y),
        source_sample(display, size, component, x, y),
        source_sample(display, size, background, x, y),
    )
}

/// The display texture for one image size and the pass that fills it.
pub struct DisplayPass {
    pipeline: wgpu::ComputePipeline,
    info: wgpu::Buffer,
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub width: u32,
    pub height: u32,
}

impl DisplayPass {
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(crate::gpu::shaders::DISPLAY.into()),
        });
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("display"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DISPLAY_FORMAT,
            usage: wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let info = DisplayInfo::new(width, height, ViewTransform::Filmic, 0.0, [0.0; 3]);
        Self {
            pipeline: compute_pipeline(device, &module, "display"),
            // Made at every viewport resize: without wgpu's panicking helper (buffer_init).
            info: crate::gpu::context::buffer_init(
                device,
                "display info",
                bytemuck::bytes_of(&info),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            view: texture.create_view(&Default::default()),
            texture,
            width,
            height,
        }
    }

    /// Copies the display texture into a buffer readable by [`crate::gpu::GpuContext::read_buffer`]
    /// (tests: the GPU display against [`display_pixel`]). Rows are padded to 256 bytes.
    pub fn copy_to_buffer(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
    ) -> (wgpu::Buffer, u32) {
        let row = (self.width * 4).div_ceil(256) * 256;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display read-back"),
            size: row as u64 * self.height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            self.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        (buffer, row)
    }

    /// Encodes the transform of the image's beauty or one component into the texture (bilinearly
    /// enlarged when smaller: the preview, under the full image's sharp rows).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        image: DisplayImage,
        info: &DisplayInfo,
        solo: Solo,
    ) {
        let targets = image.full;
        let component_of = |t: &'_ FrameTargets| match solo {
            Solo::Beauty => 0,
            Solo::Component(k) => k.min(t.components.len() - 1),
        };
        let (preview, sharp_rows) = image.preview.unwrap_or((targets, u32::MAX));
        let info = DisplayInfo {
            width: self.width,
            height: self.height,
            source: [targets.width, targets.height],
            preview_source: [preview.width, preview.height],
            sharp_rows,
            solo: matches!(solo, Solo::Component(_)) as u32,
            ..*info
        };
        queue.write_buffer(&self.info, 0, bytemuck::bytes_of(&info));
        let bind = bind_buffers(
            device,
            &self.pipeline,
            "display",
            &[&self.info, &targets.beauty],
            vec![
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&self.view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: targets.components[component_of(targets)].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: preview.beauty.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: preview.components[component_of(preview)].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: targets.background.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: preview.background.as_entire_binding(),
                },
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("display"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(info.width.div_ceil(8), info.height.div_ceil(8), 1);
    }
}
