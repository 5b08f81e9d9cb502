//! Helpers shared by integration tests: small valid files of every format, and the shared data.
#![allow(dead_code)]

use std::path::PathBuf;

/// `../shared/data` next to the repository, if present.
pub fn shared_data() -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    if p.is_dir() {
        Some(p)
    } else {
        println!("skipped: ../shared/data is absent (tests on third-party files need it)");
        None
    }
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A TressFX 3.x file: 296-byte header, float3 positions.
pub fn tressfx3(strands: u32, per: u32) -> Vec<u8> {
    let mut b = vec![0u8; 296];
    b[0..4].copy_from_slice(&3.0f32.to_le_bytes());
    b[4..8].copy_from_slice(&strands.to_le_bytes());
    b[8..12].copy_from_slice(&per.to_le_bytes());
    for s in 0..strands {
        for k in 0..per {
            b.extend(f32s(&[s as f32, 10.0 - k as f32, 0.5 * k as f32]));
        }
    }
    b
}

/// A TressFX 4.x file: 160-byte header with offsets, float4 positions, float2 strand UVs.
pub fn tressfx4(strands: u32, per: u32) -> Vec<u8> {
    let mut b = vec![0u8; 160];
    let pos = 160u32;
    let uv = pos + strands * per * 16;
    b[0..4].copy_from_slice(&4.0f32.to_le_bytes());
    b[4..8].copy_from_slice(&strands.to_le_bytes());
    b[8..12].copy_from_slice(&per.to_le_bytes());
    b[12..16].copy_from_slice(&pos.to_le_bytes());
    b[16..20].copy_from_slice(&uv.to_le_bytes());
    for s in 0..strands {
        for k in 0..per {
            b.extend(f32s(&[
                s as f32,
                1.0 - 0.1 * k as f32,
                0.05 * k as f32,
                if k < 2 { 0.0 } else { 1.0 },
            ]));
        }
    }
    for s in 0..strands {
        b.extend(f32s(&[s as f32 / strands as f32, 0.5]));
    }
    b
}

/// A GLB with one LINE_STRIP strand, two LINES strands, and a TRIANGLES quad, under a node
/// translated by (0, 10, 0).
pub fn glb() -> Vec<u8> {
    let strip: Vec<f32> = (0..5).flat_map(|k| [0.0, -(k as f32), 0.0]).collect();
    let lines_pos: Vec<f32> = (0..6)
        .flat_map(|k| [1.0, -(k as f32 % 3.0), k as f32 / 3.0])
        .collect();
    let lines_idx: [u32; 8] = [0, 1, 1, 2, 3, 4, 4, 5];
    let tri_pos: [f32; 12] = [
        -1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, -1.0, 0.0, 1.0,
    ];
    let tri_idx: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut push = |bytes: Vec<u8>, bin: &mut Vec<u8>| {
        let off = bin.len();
        bin.extend(bytes);
        views.push((off, bin.len() - off));
    };
    push(f32s(&strip), &mut bin);
    push(f32s(&lines_pos), &mut bin);
    push(
        lines_idx.iter().flat_map(|x| x.to_le_bytes()).collect(),
        &mut bin,
    );
    push(f32s(&tri_pos), &mut bin);
    push(
        tri_idx.iter().flat_map(|x| x.to_le_bytes()).collect(),
        &mut bin,
    );
    let bv: Vec<String> = views
        .iter()
        .map(|(o, l)| format!(r#"{{"buffer":0,"byteOffset":{o},"byteLength":{l}}}"#))
        .collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[0,10,0]}}],
"meshes":[{{"primitives":[
 {{"attributes":{{"POSITION":0}},"mode":3}},
 {{"attributes":{{"POSITION":1}},"indices":2,"mode":1}},
 {{"attributes":{{"POSITION":3}},"indices":4,"mode":4}}]}}],
"buffers":[{{"byteLength":{}}}],
"bufferViews":[{}],
"accessors":[
 {{"bufferView":0,"componentType":5126,"count":5,"type":"VEC3","min":[0,-4,0],"max":[0,0,0]}},
 {{"bufferView":1,"componentType":5126,"count":6,"type":"VEC3","min":[1,-2,0],"max":[1,0,1.6666666]}},
 {{"bufferView":2,"componentType":5125,"count":8,"type":"SCALAR"}},
 {{"bufferView":3,"componentType":5126,"count":4,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]}},
 {{"bufferView":4,"componentType":5125,"count":6,"type":"SCALAR"}}]}}"#,
        bin.len(),
        bv.join(",")
    );
    let mut j = json.into_bytes();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(bin);
    out
}

pub const OBJ: &str =
    "o quad\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvn 0 1 0\nf 1//1 2//1 3//1 4//1\n";

/// One frame of `hair` with the look's absorption at every point (a renderer made, drawn once, read
/// back), and whether it was shaded by segment (`Renderer::shades_segments`).
pub fn render_uniform(
    ctx: &strandlight::gpu::GpuContext,
    settings: &strandlight::render::RenderSettings,
    luts: &strandlight::scattering::lut::Luts,
    hair: &strandlight::hair::Hair,
    look: &strandlight::render::HairLook,
    lights: &[strandlight::envmap::SrbfLight],
    camera: &strandlight::render::Camera,
) -> (strandlight::render::Frame, bool) {
    let sigma_a = vec![look.fast.sigma_a_rgb(); hair.point_count()];
    let mut r = strandlight::render::Renderer::new(
        ctx,
        settings.clone(),
        luts,
        hair,
        &sigma_a,
        look,
        lights,
        camera,
    )
    .expect("renderer");
    r.render_frame(ctx);
    (r.read_frame(ctx).expect("read back"), r.shades_segments())
}

/// A procedural bob (12 points per strand) framed at three-quarters, with uniform absorption: the
/// scene the renderer and the reference modes are compared on.
pub struct BobScene {
    pub hair: strandlight::hair::Hair,
    pub sigma_a: Vec<[f32; 3]>,
    pub look: strandlight::render::HairLook,
    pub camera: strandlight::render::Camera,
    pub settings: strandlight::render::RenderSettings,
}

/// `strands` strands of a bob, `width` x `height` pixels, shadows on, dual scattering if `multiple`.
pub fn bob_scene(
    strands: usize,
    width: u32,
    height: u32,
    params: strandlight::scattering::params::HairParams,
    multiple: bool,
) -> BobScene {
    let hair = strandlight::render::scene::generated_hair(
        strandlight::hair::procedural::Style::Bob,
        strands,
        12,
        3,
    );
    let look = strandlight::render::HairLook::new(params);
    let (lo, hi) = hair.bounds();
    let camera = strandlight::render::Camera::framing(
        lo,
        hi,
        35.0,
        10.0,
        width as f32 / height as f32,
        0.95,
    );
    BobScene {
        sigma_a: vec![look.fast.sigma_a_rgb(); hair.point_count()],
        hair,
        look,
        camera,
        settings: strandlight::render::RenderSettings {
            width,
            height,
            shadows: true,
            multiple_scattering: multiple,
            volume_resolution: 48,
            shadow_grid_resolution: 32,
            ..Default::default()
        },
    }
}

impl BobScene {
    /// The GPU frame under SRBF lights.
    pub fn render(
        &self,
        ctx: &strandlight::gpu::GpuContext,
        luts: &strandlight::scattering::lut::Luts,
        lights: &[strandlight::envmap::SrbfLight],
    ) -> strandlight::render::Frame {
        render_uniform(
            ctx,
            &self.settings,
            luts,
            &self.hair,
            &self.look,
            lights,
            &self.camera,
        )
        .0
    }

    /// The reference modes' scene under 1024 directions importance-sampled from `env` (turned by `yaw`).
    pub fn reference<'a>(
        &'a self,
        env: &'a strandlight::envmap::EnvMap,
        yaw: f64,
    ) -> strandlight::render::reference::ReferenceScene<'a> {
        strandlight::render::reference::ReferenceScene {
            hair: &self.hair,
            sigma_a: &self.sigma_a,
            look: &self.look,
            lighting: strandlight::render::reference::ReferenceLighting::Environment {
                env,
                yaw,
                directions: 1024,
            },
            settings: &self.settings,
            camera: &self.camera,
        }
    }
}

/// Mean radiance of the hair: the beauty summed over covered pixels over their summed coverage
/// (the un-premultiplied mean), RGB.
pub fn mean_radiance(f: &strandlight::render::Frame) -> [f64; 3] {
    let alpha: f64 = f.covered().map(|i| f.beauty[i][3] as f64).sum();
    std::array::from_fn(|c| {
        f.covered().map(|i| f.beauty[i][c] as f64).sum::<f64>() / alpha.max(1e-30)
    })
}

/// The multiple-scattering share of the beauty: (MS.global + MS.local) / beauty, summed over covered
/// pixels and channels.
pub fn ms_share(f: &strandlight::render::Frame) -> f64 {
    let (mut ms, mut all) = (0.0f64, 0.0f64);
    for i in f.covered() {
        for c in 0..3 {
            ms += (f.components[3][i][c] + f.components[4][i][c]) as f64;
            all += f.beauty[i][c] as f64;
        }
    }
    ms / all.max(1e-30)
}

/// Mean radiance of the hair in the given components (0..3: R + TT + TRT), as [`mean_radiance`].
pub fn mean_components(
    f: &strandlight::render::Frame,
    components: std::ops::Range<usize>,
) -> [f64; 3] {
    let alpha: f64 = f.covered().map(|i| f.beauty[i][3] as f64).sum();
    std::array::from_fn(|c| {
        f.covered()
            .map(|i| {
                components
                    .clone()
                    .map(|t| f.components[t][i][c] as f64)
                    .sum::<f64>()
            })
            .sum::<f64>()
            / alpha.max(1e-30)
    })
}

/// A seeded uniform f32 generator for test scenes.
pub struct Uniform(rand_pcg::Pcg64Mcg);

impl Uniform {
    pub fn new(seed: u64) -> Self {
        Self(<rand_pcg::Pcg64Mcg as rand_core::SeedableRng>::seed_from_u64(seed))
    }

    pub fn random_range(&mut self, r: std::ops::Range<f32>) -> f32 {
        let u = (rand_core::Rng::next_u64(&mut self.0) >> 40) as f32 / (1u64 << 24) as f32;
        r.start + (r.end - r.start) * u
    }
}

/// A disciplined clump: `n` straight fibers along +y (root at the top), 8 cm long, roots uniform over
/// x in [-2, 2], z in [-1, 1], each tilted by up to 3 degrees, 12 segments, diameter 80 um.
pub fn clump(n: usize, seed: u64) -> strandlight::hair::Hair {
    let mut rng = Uniform::new(seed);
    let strands = (0..n)
        .map(|_| {
            let root = glam::Vec3::new(
                rng.random_range(-2.0..2.0),
                4.0,
                rng.random_range(-1.0..1.0),
            );
            let tilt = glam::Vec3::new(
                rng.random_range(-0.05..0.05),
                -1.0,
                rng.random_range(-0.05..0.05),
            )
            .normalize();
            strandlight::hair::RawStrand {
                points: (0..13)
                    .map(|j| root + tilt * (8.0 * j as f32 / 12.0))
                    .collect(),
                ..Default::default()
            }
        })
        .collect();
    strandlight::hair::Hair::from_strands(strands, 0.008).0
}

/// The named float channels of an EXR's first layer (panics with the name when one is missing).
pub fn read_exr_channels(path: &std::path::Path, names: &[&str]) -> Vec<Vec<f32>> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .expect("a readable EXR");
    names
        .iter()
        .map(|name| {
            let c = image
                .layer_data
                .channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == *name)
                .unwrap_or_else(|| panic!("channel {name} missing"));
            match &c.sample_data {
                exr::prelude::FlatSamples::F32(v) => v.clone(),
                other => panic!("{name} is not float32: {other:?}"),
            }
        })
        .collect()
}

/// The `strandlight` binary, with its fit cache in the temporary folder.
pub fn strandlight_command() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_strandlight"));
    c.env(
        "STRANDLIGHT_CACHE",
        std::env::temp_dir().join("strandlight-test-cache"),
    );
    c
}

/// File `name` in this process's temporary folder for the tests of `what`.
pub fn temp_file(what: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("strandlight-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d.join(name)
}

/// A `python3` command that can import `module` (a test-time checker such as `pxr` from
/// `usd-core` or `OpenEXR`), or None with a printed reason. Where `STRANDLIGHT_REQUIRE_CHECKERS` is
/// set (CI installs the checkers), a missing module is a failure rather than a skip; a missing
/// Python is always a skip.
pub fn python_with(module: &str) -> Option<std::process::Command> {
    let probe = std::process::Command::new("python3")
        .args(["-c", &format!("import {module}")])
        .output();
    match probe {
        Err(e) => {
            println!("skipped: python3 is not available ({e})");
            None
        }
        Ok(out) if !out.status.success() => {
            let why = String::from_utf8_lossy(&out.stderr);
            assert!(
                std::env::var_os("STRANDLIGHT_REQUIRE_CHECKERS").is_none(),
                "the Python checker `{module}` is required here but cannot be imported: {why}"
            );
            println!("skipped: Python cannot import `{module}` (pip install it to run this check)");
            None
        }
        Ok(_) => Some(std::process::Command::new("python3")),
    }
}
