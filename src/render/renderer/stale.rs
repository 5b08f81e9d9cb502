//! What the last frame or refinement left out of date.

/// What the last frame or refinement left out of date.
pub(in crate::render) struct Staleness {
    pub(in crate::render) volume_dirty: bool,
    /// The rows [0, converged_rows) whose every fragment is shaded (the others, part-way through
    /// progressive refinement, resolve normalised); u32::MAX after `render_frame`.
    pub(in crate::render) converged_rows: u32,
    /// The absorption changed but the volume (and the shadow grid's forward terms) still hold the old
    /// one ([`crate::render::Renderer::set_absorption_deferred`]).
    pub(in crate::render) volume_stale: bool,
    /// The stale volume's density changed too (a deferred thickness change): its rebuild changes the
    /// grid's transmittance, which single scattering reads.
    pub(in crate::render) volume_stale_density: bool,
    /// The volume holds an old absorption that nothing reads now (multiple scattering off): rebuilt
    /// when multiple scattering is turned on.
    pub(in crate::render) volume_absorption_old: bool,
    pub(in crate::render) shadow_grid_dirty: bool,
    /// The refinement's plan re-shades multiple scattering alone: the segments' single scattering
    /// from the last converged pass still holds (a change that reaches only the forward and
    /// dual-scattering terms: new tables, a deferred absorption's volume).
    pub(in crate::render) single_kept: bool,
    /// The frame's visibility pass has drawn the current camera and fibres (refinement reuses it
    /// after a parameter change).
    pub(in crate::render) visibility_valid: bool,
}
