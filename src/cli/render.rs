//! `strandlight render`: a still of a hairstyle under an environment, as linear EXR (and a PNG preview).

use super::params_args::ParamArgs;
use anyhow::{Context, bail};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::hair::procedural::Style;
use strandlight::paint::dye::parse_colour;
use strandlight::render::camera::CAMERA_PRESETS;
use strandlight::render::frame::check_output_folders;
use strandlight::render::passes::background::{Background, BackgroundMap};
use strandlight::render::reference::path_trace::{PathTraceSettings, path_trace_frame};
use strandlight::render::reference::{
    ReferenceLighting, ReferenceScene, reference_frame, sample_srbf_lights,
};
use strandlight::render::tiled::{needs_tiles, render_tiled, tile_side};
use strandlight::render::{Camera, Renderer};
use strandlight::scattering::lut::Luts;
use strandlight::session::assemble::{StillHeader, still_attributes};
use strandlight::session::{
    Absorption, EnvironmentSource, HairSource, Look, OccluderOptions, RenderOptions,
    SESSION_VERSION, Scene, Session, ViewCamera,
};

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// A session saved by the editor (.slsession): hair, environment, look, camera and render settings
    /// come from it, and the scene flags below are ignored (outputs, --reference and --software apply).
    #[arg(long)]
    pub session: Option<PathBuf>,
    /// Hair file (.hair, .tfx, .gltf, .glb, .usd, .usda, .usdc, .usdz, .abc); default: a generated wavy hairstyle (10k strands).
    #[arg(long)]
    pub hair: Option<PathBuf>,
    /// USD or Alembic: the prim or object path whose curves are the hair.
    #[arg(long, requires = "hair")]
    pub hair_prim: Option<String>,
    /// The time sampled curves are read at (USD: a time code; Alembic: seconds).
    #[arg(long, requires = "hair")]
    pub hair_time: Option<f64>,
    /// Style of the generated hair (when no --hair is given).
    #[arg(long, value_enum, conflicts_with = "hair")]
    pub style: Option<Style>,
    /// Strands of the generated style.
    #[arg(long, default_value_t = 10_000)]
    pub strands: usize,
    /// Points per generated strand.
    #[arg(long, default_value_t = 27)]
    pub points: usize,
    /// Environment: .srbf.json, or .hdr / .exr (fitted, cached); default: the built-in sunny sky.
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// SRBF lights fitted to an .hdr / .exr environment.
    #[arg(long, default_value_t = 40)]
    pub lights: usize,
    /// Turn the environment about +Y (degrees).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub env_yaw: f64,
    #[command(flatten)]
    pub params: ParamArgs,
    /// Dye colour of the whole hair (#rrggbb sRGB or r,g,b linear), turned into absorption by Chiang
    /// et al. 2016's inversion; replaces the preset's melanin absorption.
    #[arg(long)]
    pub dye: Option<String>,
    /// Dye colour at the roots (a root-to-tip gradient with --dye-tip).
    #[arg(long)]
    pub dye_root: Option<String>,
    /// Dye colour at the tips.
    #[arg(long)]
    pub dye_tip: Option<String>,
    /// Azimuthal roughness beta_N of the colour inversion (Chiang 2016).
    #[arg(long, default_value_t = 0.3)]
    pub beta_n: f64,
    /// Per-strand variation of the absorption: log-normal with this standard deviation.
    #[arg(long, default_value_t = 0.0)]
    pub strand_variation: f32,
    /// Multiplies every fiber's diameter (the file's, or 70 um): denser shadows, wider ribbons.
    #[arg(long, default_value_t = 1.0)]
    pub thickness_scale: f32,
    /// Seed of the per-strand variation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The head under the hair: an OBJ or glTF mesh (in the hair file's units and axes), or `none`;
    /// default: the generated head for generated hair, the mesh a glTF hair file carries.
    #[arg(long)]
    pub occluder: Option<PathBuf>,
    /// The head's diffuse colour (#rrggbb sRGB or r,g,b linear).
    #[arg(long)]
    pub skin: Option<String>,
    /// Paint layer (.slpaint, as the editor saves it) applied over the absorption (with --session:
    /// instead of the session's).
    #[arg(long)]
    pub paint: Option<PathBuf>,
    /// Camera preset: front, three-quarter, side, back, back-three-quarter, top.
    #[arg(long, default_value = "three-quarter")]
    pub camera: String,
    /// Orbit yaw in degrees (overrides the preset's).
    #[arg(long, allow_negative_numbers = true)]
    pub yaw: Option<f32>,
    /// Orbit pitch in degrees (overrides the preset's).
    #[arg(long, allow_negative_numbers = true)]
    pub pitch: Option<f32>,
    /// Camera distance to the hair's centre in cm (default: frame the hair).
    #[arg(long)]
    pub distance: Option<f32>,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 30.0)]
    pub fov: f32,
    #[arg(long, default_value_t = 720)]
    pub width: u32,
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// The head's samples per pixel (MSAA: 2 or 4).
    #[arg(long, default_value_t = 4)]
    pub samples: u32,
    /// Hair fragments kept per pixel by the K-buffer (1 to 32; each is shaded).
    #[arg(long, default_value_t = strandlight::render::passes::kbuffer::DEFAULT_FRAGMENTS)]
    pub fragments: u32,
    /// The fragments behind the kept ones: drop (Yu 2012), fold (into the last kept) or spread (over
    /// the kept ones).
    #[arg(long, default_value = "spread")]
    pub tail: strandlight::render::passes::kbuffer::Tail,
    /// Exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// No self-shadowing.
    #[arg(long)]
    pub no_shadows: bool,
    /// Single scattering only (no dual scattering: MS.global and MS.local stay zero).
    #[arg(long)]
    pub single_scattering: bool,
    /// Zinke's forward-scattering density factor d_f.
    #[arg(long, default_value_t = 0.7)]
    pub d_f: f32,
    /// Zinke's backward-scattering density factor d_b.
    #[arg(long, default_value_t = 0.7)]
    pub d_b: f32,
    /// SRBF lights per shading pass (1..=16).
    #[arg(long, default_value_t = 16)]
    pub lights_per_pass: u32,
    /// Voxels along the hair's longest side (fiber-density volume).
    #[arg(long, default_value_t = 128)]
    pub volume_resolution: u32,
    /// Points of the per-light shadow grid along the hair's longest side.
    #[arg(long, default_value_t = 48)]
    pub shadow_grid: u32,
    /// Render in tiles of at most this many pixels a side (default: only when the image's buffers
    /// exceed what the GPU binds at once, then 1024).
    #[arg(long)]
    pub tile: Option<u32>,
    /// Linear float EXR (RGBA, alpha = coverage).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Behind the hair: env (the environment seen through the camera: its image, or the SRBF
    /// reconstruction for a .srbf.json), transparent, or a colour #rrggbb. Default: the environment in
    /// the PNG (with --session, the session's choice) and transparent in the EXR; given, it applies to
    /// both, and the EXR then holds the hair over it with alpha 1 and the coverage in `coverage`.
    #[arg(long)]
    pub background: Option<Background>,
    /// Add AOV layers to the EXR: Z and the components R, TT, TRT, MS.global, MS.local.
    #[arg(long)]
    pub aovs: bool,
    /// Tonemapped PNG preview.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Shade the same visible points on the CPU with the exact model instead: under directions
    /// importance-sampled from the environment image (or, for .srbf.json, sampled from its lobes).
    /// `--reference` (or `--reference=dual`): with multiple scattering (the default), Zinke's dual
    /// scattering with every direction's shadow ray traced through the explicit fibers; with
    /// --single-scattering, the volume's exp(-tau) shadows. `--reference=path`: a path tracer through
    /// the explicit fibers, every order of scattering (see --spp, --max-depth); with
    /// --single-scattering, single scattering with exact shadows (--no-shadows is ignored: a path
    /// tracer always has occlusion). MS.global holds all orders above single scattering.
    #[arg(long, value_enum, num_args = 0..=1, require_equals = true, default_missing_value = "dual")]
    pub reference: Option<ReferenceMode>,
    /// Directions sampled by --reference (per visible point with --reference=path and an image).
    #[arg(long, default_value_t = 1024)]
    pub reference_directions: usize,
    /// Paths per visible point of --reference=path.
    #[arg(long, default_value_t = PathTraceSettings::default().samples_per_pixel)]
    pub spp: u32,
    /// Most bounces after the visible point of --reference=path.
    #[arg(long, default_value_t = PathTraceSettings::default().max_depth)]
    pub max_depth: u32,
    /// Use a software adapter (lavapipe).
    #[arg(long)]
    pub software: bool,
}

/// Which reference `--reference` computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ReferenceMode {
    /// Single scattering and Zinke's dual scattering by ray shooting (the default).
    Dual,
    /// Brute-force path tracing through the explicit fibers.
    Path,
}

/// The session the scene flags describe (the editor's sessions are read with `--session`).
fn session_from_args(args: &RenderArgs) -> anyhow::Result<Session> {
    let params = args.params.resolve()?;
    let dye = |c: &Option<String>| -> anyhow::Result<Option<Absorption>> {
        c.as_deref()
            .map(|s| {
                let colour = parse_colour(s).map_err(anyhow::Error::msg)?;
                Ok(Absorption::Dye {
                    colour,
                    beta_n: args.beta_n,
                })
            })
            .transpose()
    };
    let whole = dye(&args.dye)?.unwrap_or(Absorption::SigmaA {
        sigma_a: params.sigma_a,
    });
    let (preset_yaw, preset_pitch) = Camera::preset(&args.camera).with_context(|| {
        let names: Vec<&str> = CAMERA_PRESETS.iter().map(|p| p.0).collect();
        format!(
            "unknown camera preset '{}' (one of {})",
            args.camera,
            names.join(", ")
        )
    })?;
    if !(args.fov > 1.0 && args.fov < 170.0) {
        bail!("--fov must lie in (1, 170) degrees");
    }
    if let Some(d) = args.distance
        && !(d > 0.0 && d.is_finite())
    {
        bail!("--distance must be positive");
    }
    if !(0.0..=1.0).contains(&args.d_f) || !(0.0..=1.0).contains(&args.d_b) {
        bail!("--d-f and --d-b lie in [0, 1]");
    }
    Ok(Session {
        version: SESSION_VERSION,
        hair: match &args.hair {
            Some(path) => HairSource::File {
                path: path.clone(),
                blake3: None,
                prim: args.hair_prim.clone(),
                time: args.hair_time,
            },
            None => HairSource::generated(
                args.style.unwrap_or(Style::Wavy),
                args.strands,
                args.points,
                1,
            ),
        },
        environment: match &args.env {
            Some(path) => EnvironmentSource::File {
                path: path.clone(),
                lights: args.lights,
                blake3: None,
                fitted: None,
            },
            None => EnvironmentSource::Builtin,
        },
        env_yaw: args.env_yaw,
        look: Look {
            params,
            root: dye(&args.dye_root)?.unwrap_or(whole),
            tip: Some(dye(&args.dye_tip)?.unwrap_or(whole)),
            strand_variation: args.strand_variation.max(0.0),
            variation_seed: args.seed,
            d_f: args.d_f,
            d_b: args.d_b,
            longitudinal: args.params.longitudinal.unwrap_or_default(),
            thickness_scale: args.thickness_scale,
        },
        camera: ViewCamera {
            yaw: args.yaw.unwrap_or(preset_yaw),
            pitch: args.pitch.unwrap_or(preset_pitch),
            fov_y: args.fov,
            target: None,
            distance: args.distance,
        },
        render: RenderOptions {
            width: args.width,
            height: args.height,
            samples: args.samples,
            fragments: args.fragments,
            tail: args.tail,
            exposure: args.exposure,
            shadows: !args.no_shadows,
            multiple_scattering: !args.single_scattering,
            volume_resolution: args.volume_resolution,
            shadow_grid_resolution: args.shadow_grid,
            background: args.background.unwrap_or_default(),
        },
        paint: args.paint.clone(),
        paint_layer: None,
        occluder: OccluderOptions {
            show: args.occluder.as_deref() != Some(std::path::Path::new("none")),
            mesh: args.occluder.clone().filter(|p| p.as_os_str() != "none"),
            albedo: match &args.skin {
                Some(c) => parse_colour(c)
                    .map_err(anyhow::Error::msg)?
                    .map(|v| v as f32),
                None => OccluderOptions::default().albedo,
            },
        },
    })
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    if args.output.is_none() && args.png.is_none() {
        bail!("nothing to write: give -o still.exr and/or --png preview.png");
    }
    check_output_folders(
        args.output
            .iter()
            .chain(args.png.iter())
            .map(PathBuf::as_path),
    )?;
    let session = match &args.session {
        Some(path) => {
            let mut s = Session::read(path)?;
            // A paint layer named on the command line replaces the session's.
            if let Some(p) = &args.paint {
                s.paint = Some(p.clone());
            }
            s
        }
        None => session_from_args(&args)?,
    };
    let scene = Scene::assemble(&session)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let Scene {
        hair,
        hair_name,
        environment: env,
        sigma_a,
        look,
        camera,
        mut settings,
        occluder,
        ..
    } = scene;
    settings.lights_per_pass = args.lights_per_pass;
    let mut options = GpuOptions::from_env();
    options.force_software |= args.software;
    let ctx = GpuContext::new_headless(&options)?;
    eprintln!("adapter: {} ({})", ctx.summary.name, ctx.summary.backend);
    let luts = Luts::default_tables();
    let t = Instant::now();
    // Tiles when asked, or when the image's buffers would exceed what the GPU binds at once.
    let tile = match args.tile {
        Some(t) if t < 16 => bail!("--tile must be at least 16 pixels, got {t}"),
        Some(t) => t,
        None if needs_tiles(&ctx, settings.width, settings.height, settings.fragments) => {
            tile_side(&ctx, settings.fragments)
        }
        None => 0,
    };
    // The reference modes shade the frame's K-buffer fragments, which a tiled still does not keep.
    if tile > 0 && args.reference.is_some() {
        bail!(
            "--reference needs an untiled image ({}x{} with {} fragments a pixel would be rendered in tiles): render it smaller or with fewer --fragments",
            settings.width,
            settings.height,
            settings.fragments
        );
    }
    let mut first = settings.clone();
    if tile > 0 {
        first.width = settings.width.min(tile);
        first.height = settings.height.min(tile);
    }
    let mut renderer = Renderer::new(
        &ctx,
        first,
        &luts,
        &hair,
        &sigma_a,
        &look,
        &env.lights.lights,
        &camera,
    )?;
    // The reference modes trace hair alone (their shadow rays know no mesh): their image has no head.
    if args.reference.is_some() && occluder.is_some() {
        eprintln!("warning: the reference modes draw no head; rendering without it");
    } else {
        renderer.set_occluder(&ctx, occluder.as_ref());
    }
    // The PNG shows the session's background unless told otherwise; the EXR only a background asked
    // for.
    let png_background = args.background.unwrap_or(session.render.background);
    let needs_map = (args.png.is_some() && png_background == Background::Environment)
        || (args.output.is_some() && args.background == Some(Background::Environment));
    if needs_map {
        let map = BackgroundMap::from_environment(&env);
        renderer.set_background(&ctx, Some(&map), map.yaw);
    }
    let frame_started = Instant::now();
    let mut frame = if tile > 0 {
        eprintln!(
            "rendering {}x{} in tiles of {tile} pixels",
            settings.width, settings.height
        );
        render_tiled(
            &ctx,
            &mut renderer,
            &camera,
            settings.width,
            settings.height,
            tile,
        )?
    } else {
        renderer.render_frame(&ctx);
        renderer.read_frame(&ctx)?
    };
    if let Some(times) = renderer.pass_times(&ctx)? {
        let list: Vec<String> = times
            .iter()
            .map(|(n, ms)| format!("{n} {ms:.2} ms"))
            .collect();
        let of = if tile > 0 { " (the last tile)" } else { "" };
        eprintln!("GPU time per pass{of}: {}", list.join(", "));
    }
    // The frame alone is what an edit in the editor costs (the renderer and its tables exist).
    eprintln!(
        "rendered {}x{} ({} strands, {} lights) in {:.2} s (frame {:.2} s)",
        settings.width,
        settings.height,
        hair.strand_count(),
        env.lights.lights.len(),
        t.elapsed().as_secs_f64(),
        frame_started.elapsed().as_secs_f64()
    );
    let mut mode = "srbf".to_string();
    if let Some(reference) = args.reference {
        let t = Instant::now();
        let directions = args.reference_directions.max(1);
        // The environment image when there is one (the fit's error is then part of what is measured),
        // else the SRBF lobes themselves, sampled.
        let lighting = match env.image.as_ref() {
            Some(image) => ReferenceLighting::Environment {
                env: image,
                yaw: env.lights.yaw,
                directions,
            },
            None => {
                let per_light = directions.div_ceil(env.lights.lights.len().max(1)).max(16);
                ReferenceLighting::Directional(sample_srbf_lights(&env.lights.lights, per_light, 7))
            }
        };
        let source = match lighting {
            ReferenceLighting::Environment { .. } => "environment image",
            ReferenceLighting::Directional(_) => "SRBF lobes",
        };
        let scene = ReferenceScene {
            hair: &hair,
            sigma_a: &sigma_a,
            look: &look,
            lighting,
            settings: &settings,
            camera: &camera,
        };
        let what = match reference {
            ReferenceMode::Dual => {
                frame = reference_frame(&frame, &scene);
                match (settings.multiple_scattering, settings.shadows) {
                    (true, true) => "dual scattering, shadow rays through the fibers".to_string(),
                    (true, false) => "dual scattering, unshadowed".to_string(),
                    (false, true) => "single scattering, volume shadows".to_string(),
                    (false, false) => "single scattering, unshadowed".to_string(),
                }
            }
            ReferenceMode::Path => {
                let pt = PathTraceSettings {
                    samples_per_pixel: args.spp.max(1),
                    max_depth: args.max_depth,
                    ..Default::default()
                };
                frame = path_trace_frame(&frame, &scene, &pt);
                if settings.multiple_scattering {
                    format!(
                        "path traced, {} paths per point, at most {} bounces",
                        pt.samples_per_pixel, pt.max_depth
                    )
                } else {
                    format!(
                        "path traced single scattering with shadow rays, {} samples per point",
                        pt.samples_per_pixel
                    )
                }
            }
        };
        eprintln!(
            "reference: {directions} directions from the {source}, {what}, shaded on the CPU in {:.2} s",
            t.elapsed().as_secs_f64()
        );
        mode = format!("reference ({directions} directions from the {source}; {what})");
    }
    let attributes = still_attributes(
        &session,
        &StillHeader {
            hair_name: &hair_name,
            environment: &env,
            look: &look,
            camera: &camera,
            settings: &settings,
            adapter: &ctx.summary.name,
            mode: &mode,
        },
    );
    if let Some(o) = &args.output {
        frame.write_exr(o, &attributes, args.aovs, args.background)?;
        eprintln!("wrote {}", o.display());
    }
    if let Some(p) = &args.png {
        frame.write_png(p, png_background)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
