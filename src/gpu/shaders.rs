//! WGSL sources, embedded at build time and concatenated in dependency order (WGSL has no includes).
//! Each file in `shaders/` mirrors a Rust file of the same name in `src/scattering/`.

pub const CIRCULAR_GAUSSIAN: &str = include_str!("../../shaders/circular_gaussian.wgsl");
pub const LUT: &str = include_str!("../../shaders/lut.wgsl");
pub const FAST_AZIMUTHAL: &str = include_str!("../../shaders/fast_azimuthal.wgsl");
pub const AZIMUTHAL_TABLE: &str = include_str!("../../shaders/azimuthal_table.wgsl");
pub const FAST_RESPONSE: &str = include_str!("../../shaders/fast_response.wgsl");
pub const FAST_EVAL: &str = include_str!("../../shaders/fast_eval.wgsl");
pub const DENSITY_PYRAMID: &str = include_str!("../../shaders/density_pyramid.wgsl");
pub const DENSITY_DOWNSAMPLE: &str = include_str!("../../shaders/density_downsample.wgsl");
pub const TRANSMITTANCE_EVAL: &str = include_str!("../../shaders/transmittance_eval.wgsl");
pub const FORWARD_SCATTERING: &str = include_str!("../../shaders/forward_scattering.wgsl");
pub const FORWARD_EVAL: &str = include_str!("../../shaders/forward_eval.wgsl");
pub const CAMERA: &str = include_str!("../../shaders/camera.wgsl");
pub const VISIBILITY: &str = include_str!("../../shaders/visibility.wgsl");
pub const KBUFFER: &str = include_str!("../../shaders/kbuffer.wgsl");
pub const SHADING: &str = include_str!("../../shaders/shading.wgsl");
pub const RESOLVE: &str = include_str!("../../shaders/resolve.wgsl");
pub const OCCLUDER: &str = include_str!("../../shaders/occluder.wgsl");
pub const DUAL_RESPONSE: &str = include_str!("../../shaders/dual_response.wgsl");
pub const DUAL_EVAL: &str = include_str!("../../shaders/dual_eval.wgsl");
pub const FIBER_DENSITY: &str = include_str!("../../shaders/fiber_density.wgsl");
pub const DISPLAY: &str = include_str!("../../shaders/display.wgsl");

/// The dual-scattering test harness: the fast model, the dual responses, bindings and entry point.
pub fn dual_eval_module() -> String {
    [fast_model_library().as_str(), DUAL_RESPONSE, DUAL_EVAL].join("\n")
}

pub const SHADOW_GRID: &str = include_str!("../../shaders/shadow_grid.wgsl");
pub const SHADOW_GRID_BUILD: &str = include_str!("../../shaders/shadow_grid_build.wgsl");

/// The shadow-grid build pass: light-space sweeps, forward scattering and the grid.
pub fn shadow_grid_build_module() -> String {
    [
        CIRCULAR_GAUSSIAN,
        DENSITY_PYRAMID,
        FORWARD_SCATTERING,
        SHADOW_GRID,
        SHADOW_GRID_BUILD,
    ]
    .join("\n")
}

/// The occluder's shading: PI, the shadow-grid lookup, camera, and the kernel.
pub fn occluder_module() -> String {
    [CIRCULAR_GAUSSIAN, SHADOW_GRID, CAMERA, OCCLUDER].join("\n")
}

/// The visibility pass (the occluder into the multisampled id target).
pub fn visibility_module() -> String {
    [CIRCULAR_GAUSSIAN, CAMERA, VISIBILITY].join("\n")
}

/// The K-buffer's raster and composite passes.
pub fn kbuffer_module() -> String {
    [CIRCULAR_GAUSSIAN, CAMERA, KBUFFER].join("\n")
}

/// The shading pass: the fast model, dual scattering, the shadow-grid lookup, camera, and the kernel.
pub fn shading_module() -> String {
    [
        fast_model_library().as_str(),
        DUAL_RESPONSE,
        SHADOW_GRID,
        CAMERA,
        SHADING,
    ]
    .join("\n")
}

/// The resolve pass.
pub fn resolve_module() -> String {
    [CIRCULAR_GAUSSIAN, CAMERA, RESOLVE].join("\n")
}

/// The forward-scattering test harness (constants, cone marching for the crossings, the march).
pub fn forward_eval_module() -> String {
    [
        CIRCULAR_GAUSSIAN,
        DENSITY_PYRAMID,
        FORWARD_SCATTERING,
        FORWARD_EVAL,
    ]
    .join("\n")
}

/// The transmittance test harness: constants, cone marching, bindings and entry point. The
/// including module declares `pyramid_info` and `pyramid`.
pub fn transmittance_eval_module() -> String {
    [CIRCULAR_GAUSSIAN, DENSITY_PYRAMID, TRANSMITTANCE_EVAL].join("\n")
}

/// The fast-model library (no bindings, no entry points): the including module declares the
/// storage buffers `lut_c` and `azimuthal_table`.
pub fn fast_model_library() -> String {
    [
        CIRCULAR_GAUSSIAN,
        LUT,
        FAST_AZIMUTHAL,
        AZIMUTHAL_TABLE,
        FAST_RESPONSE,
    ]
    .join("\n")
}

/// Every complete shader module strandlight builds, by name (validated by naga in the tests).
pub fn modules() -> Vec<(&'static str, String)> {
    vec![
        (
            "fast_eval",
            format!("{}\n{}", fast_model_library(), FAST_EVAL),
        ),
        ("fiber_density", FIBER_DENSITY.to_string()),
        ("density_downsample", DENSITY_DOWNSAMPLE.to_string()),
        ("transmittance_eval", transmittance_eval_module()),
        ("forward_eval", forward_eval_module()),
        ("visibility", visibility_module()),
        ("shading", shading_module()),
        ("resolve", resolve_module()),
        ("occluder", occluder_module()),
        ("display", DISPLAY.to_string()),
        ("shadow_grid_build", shadow_grid_build_module()),
        ("dual_eval", dual_eval_module()),
    ]
}
