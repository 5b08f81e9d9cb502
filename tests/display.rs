//! The viewport's display pass (shaders/display.wgsl) against its CPU twin (`source_sample`,
//! `display_pixel`), on lavapipe: both view transforms, the viewport exposure, partial coverage over the
//! background (a flat colour, and the environment target composited in linear light), a solo
//! component, a smaller image enlarged bilinearly, and a preview under the full image's first rows.

use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::render::display::{
    DisplayInfo, DisplayPass, Solo, ViewTransform, displayed_pixel,
};
use strandlight::render::passes::targets::FrameTargets;
use strandlight::render::refine::DisplayImage;

#[test]
fn the_display_pass_matches_its_cpu_twin() {
    let ctx = GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)");
    let (w, h) = (37u32, 11u32);
    let targets = FrameTargets::new(&ctx.device, w, h, 4, (1, Default::default()));
    let n = (w * h) as usize;
    // Radiance from 0 to ~8 (past the filmic shoulder), coverage from 0 to 1.
    let beauty: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let a = (i % 5) as f32 / 4.0;
            let x = 8.0 * (i as f32 / n as f32).powi(2);
            [a * x, a * 0.5 * x, a * 0.1 * x, a]
        })
        .collect();
    let component: Vec<[f32; 4]> = beauty
        .iter()
        .map(|p| [0.3 * p[0], 0.2 * p[1], p[2], 0.0])
        .collect();
    ctx.queue
        .write_buffer(&targets.beauty, 0, bytemuck::cast_slice(&beauty));
    ctx.queue
        .write_buffer(&targets.components[1], 0, bytemuck::cast_slice(&component));
    // The environment behind each pixel: a gradient up to ~3.
    let background: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let x = 3.0 * (i % 7) as f32 / 6.0;
            [x, 0.5 * x, 0.2 + 0.1 * x, 1.0]
        })
        .collect();
    ctx.queue
        .write_buffer(&targets.background, 0, bytemuck::cast_slice(&background));
    // A preview: a third of the size, other values.
    let (pw, ph) = (w.div_ceil(3), h.div_ceil(3));
    let preview = FrameTargets::new(&ctx.device, pw, ph, 4, (1, Default::default()));
    let pn = (pw * ph) as usize;
    let preview_beauty: Vec<[f32; 4]> = (0..pn)
        .map(|i| {
            let a = 0.25 + 0.75 * (i % 3) as f32 / 2.0;
            [a * 0.3 * i as f32, a * 0.2, a, a]
        })
        .collect();
    let preview_component: Vec<[f32; 4]> = preview_beauty
        .iter()
        .map(|p| [p[2], p[1], p[0], 0.0])
        .collect();
    let preview_background: Vec<[f32; 4]> =
        (0..pn).map(|i| [0.1 * i as f32, 1.0, 0.5, 1.0]).collect();
    ctx.queue.write_buffer(
        &preview.background,
        0,
        bytemuck::cast_slice(&preview_background),
    );
    ctx.queue
        .write_buffer(&preview.beauty, 0, bytemuck::cast_slice(&preview_beauty));
    ctx.queue.write_buffer(
        &preview.components[1],
        0,
        bytemuck::cast_slice(&preview_component),
    );
    let mut worst = 0.0f32;
    // The display at the image's size, larger than it (3x wider, not a whole multiple), and the
    // preview under the image's first 5 rows.
    for (dw, dh, with_preview) in [(w, h, false), (3 * w - 2, 3 * h + 1, false), (w, h, true)] {
        let pass = DisplayPass::new(&ctx.device, dw, dh);
        for (transform, ev, solo, environment) in [
            (ViewTransform::Filmic, 0.0, Solo::Beauty, 0),
            (ViewTransform::Standard, 0.0, Solo::Beauty, 0),
            (ViewTransform::Filmic, 1.5, Solo::Beauty, 0),
            (ViewTransform::Standard, -1.0, Solo::Component(1), 0),
            (ViewTransform::Filmic, 0.5, Solo::Beauty, 1),
            (ViewTransform::Standard, 0.0, Solo::Beauty, 1),
            (ViewTransform::Filmic, 0.0, Solo::Component(1), 1),
        ] {
            let info = DisplayInfo {
                render_scale: 2.0,
                environment,
                ..DisplayInfo::new(dw, dh, transform, ev, [0.2, 0.3, 0.4])
            };
            let sharp_rows = 5;
            let image = DisplayImage {
                full: &targets,
                preview: with_preview.then_some((&preview, sharp_rows)),
            };
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            pass.encode(&ctx.device, &ctx.queue, &mut enc, image, &info, solo);
            let (buffer, row) = pass.copy_to_buffer(&ctx.device, &mut enc);
            ctx.queue.submit([enc.finish()]);
            let bytes: Vec<u8> = ctx.read_buffer(&buffer).expect("read back");
            let cpu_info = DisplayInfo {
                solo: matches!(solo, Solo::Component(_)) as u32,
                source: [w, h],
                preview_source: if with_preview { [pw, ph] } else { [w, h] },
                sharp_rows: if with_preview { sharp_rows } else { u32::MAX },
                ..info
            };
            let full = (&beauty[..], &component[..], &background[..]);
            let small = if with_preview {
                (
                    &preview_beauty[..],
                    &preview_component[..],
                    &preview_background[..],
                )
            } else {
                full
            };
            for y in 0..dh {
                for x in 0..dw {
                    let want = displayed_pixel(&cpu_info, full, small, x, y);
                    for c in 0..4 {
                        let got =
                            bytes[y as usize * row as usize + 4 * x as usize + c] as f32 / 255.0;
                        worst = worst.max((got - want[c]).abs());
                    }
                }
            }
        }
    }
    println!("display pass against display_pixel: worst {worst:.4} (one 8-bit step is 0.0039)");
    assert!(worst <= 1.0 / 255.0 + 1e-4, "{worst}");
}
