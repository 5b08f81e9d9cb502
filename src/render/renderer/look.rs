//! The look and its tables: the hair parameters the renderer shades with ([`HairLook`]), the tables
//! built from them ([`ParamTables`], through the process's cache: [`super::table_cache`]), and the
//! renderer's setters that upload a new look or new tables.

use super::Renderer;
use crate::gpu::GpuContext;
use crate::gpu::dual_eval::dual_tables_texels;
use crate::gpu::fast_eval::GpuLuts;
use crate::gpu::forward::forward_table_texels;
use crate::render::reference::REFERENCE_VARIANT;
use crate::render::renderer::table_cache::with_cache;
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::dual_terms::DualTables;
use crate::scattering::fast_params::{DEFAULT_QUADRATURE_SEGMENTS, FastHairParams};
use crate::scattering::params::{HairParams, LongitudinalModel};
use crate::shadow::forward::ForwardTable;
use std::sync::Arc;

/// The hair parameters in both forms: the exact ones (for the tables built on the CPU) and the fast
/// model's uniform (quadrature segments, d_f, d_b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairLook {
    pub params: HairParams,
    pub fast: FastHairParams,
}

/// The look and the tables built for it, on the GPU.
pub(in crate::render) struct LookTables {
    pub(in crate::render) luts: GpuLuts,
    pub(in crate::render) look: HairLook,
    /// The exact parameters the forward and dual tables were built for.
    pub(in crate::render) tables_for: HairParams,
    pub(in crate::render) params: wgpu::Buffer,
    pub(in crate::render) forward_table: wgpu::Buffer,
    pub(in crate::render) dual_tables: wgpu::Buffer,
    /// The azimuthal table the buffer holds (sized for the largest, an elliptical fiber's).
    pub(in crate::render) azimuthal: Arc<AzimuthalTable>,
    pub(in crate::render) azimuthal_table: wgpu::Buffer,
}

impl HairLook {
    /// Whether `other` differs from this look in its eta or eccentricity and in nothing else.
    pub fn index_only_change(&self, other: &HairLook) -> bool {
        let mut same = *other;
        same.params.eta = self.params.eta;
        same.params.eccentricity = self.params.eccentricity;
        same.fast.eta = self.fast.eta;
        same.fast.eccentricity = self.fast.eccentricity;
        same == *self && other != self
    }

    /// Xu's m = 4 segments and Zinke's d_f = d_b = 0.7.
    pub fn new(params: HairParams) -> Self {
        Self {
            params,
            fast: FastHairParams::new(&params, DEFAULT_QUADRATURE_SEGMENTS),
        }
    }

    pub fn with_dual(mut self, d_f: f32, d_b: f32) -> Self {
        self.fast.d_f = d_f;
        self.fast.d_b = d_b;
        self
    }

    /// The longitudinal function (normalised by default).
    pub fn with_longitudinal(mut self, model: LongitudinalModel) -> Self {
        self.fast = self.fast.with_longitudinal(model);
        self
    }

    /// The exact model's form of this look's longitudinal function, for the references.
    pub fn longitudinal(&self) -> LongitudinalModel {
        self.fast.longitudinal_model()
    }
}

/// The tables that depend on hair parameters and are built on the CPU: the forward table (eta, alpha,
/// beta; read per crossed fiber's absorption), the dual-scattering tables (all parameters but the
/// absorption, which is their second axis: read per point's) and the azimuthal table of the exact
/// window integrals (eta and eccentricity; read per point's absorption).
/// The editor builds them on a worker thread ([`Renderer::set_params_deferred`], [`Renderer::set_tables`]).
#[derive(Clone)]
pub struct ParamTables {
    pub forward: ForwardTable,
    pub dual: DualTables,
    pub azimuthal: Arc<AzimuthalTable>,
}

/// Whether tables built for `a` serve `b`: every table reads each point's absorption on its own
/// axis, so only the other parameters matter (a melanin, dye or paint change needs no rebuild).
pub fn same_tables(a: &HairParams, b: &HairParams) -> bool {
    HairParams {
        sigma_a: b.sigma_a,
        ..*a
    } == *b
}

/// Builds the [`ParamTables`] of `params`, keeping `reuse` when its eta and eccentricity are the same
/// (and it is no draft);
/// the process keeps the tables of the last few parameter sets ([`crate::render::renderer::table_cache`]), so a set
/// built before is taken from there.
pub fn build_tables(params: &HairParams, reuse: Option<&Arc<AzimuthalTable>>) -> ParamTables {
    // The caller's table where it serves, kept or built: callers tell a new azimuthal table by
    // identity.
    let reuse = reuse.filter(|t| t.fits_hair(params)).cloned();
    if let Some(mut tables) = with_cache(|c| c.get(params)) {
        if let Some(r) = reuse {
            tables.azimuthal = r;
        }
        return tables;
    }
    let reuse = reuse.or_else(|| with_cache(|c| c.azimuthal(params)));
    let azimuthal = || {
        reuse.unwrap_or_else(|| {
            Arc::new(AzimuthalTable::build(
                params.eta as f32,
                params.eccentricity as f32,
            ))
        })
    };
    let ((forward, dual), azimuthal) = rayon::join(
        || {
            rayon::join(
                || ForwardTable::build(params, REFERENCE_VARIANT),
                || DualTables::build(params, REFERENCE_VARIANT),
            )
        },
        azimuthal,
    );
    let tables = ParamTables {
        forward,
        dual,
        azimuthal,
    };
    with_cache(|c| c.keep(params, &tables));
    tables
}

/// The azimuthal table a new eta or eccentricity previews with while [`build_tables`] builds the
/// tables: the process's kept table for that index when it has one, else a draft
/// ([`AzimuthalTable::build_draft`]: on two cores 0.06-0.07 s for a round fiber and 0.22-0.25 s for
/// an elliptical one, against 0.8 s and 3 s). Only the azimuthal table: the forward and dual tables
/// (another 0.1 s) change little with the index and follow with the tables, as for any other
/// parameter ([`Renderer::set_azimuthal_table`]). A draft is never kept.
pub fn build_draft_table(params: &HairParams) -> Arc<AzimuthalTable> {
    with_cache(|c| c.azimuthal(params)).unwrap_or_else(|| {
        Arc::new(AzimuthalTable::build_draft(
            params.eta as f32,
            params.eccentricity as f32,
        ))
    })
}

/// What a worker builds for new hair parameters ([`TableBuild::build`]).
#[derive(Clone)]
pub enum TableBuild {
    /// For a new eta or eccentricity, first: its azimuthal table alone, a draft unless the process
    /// keeps one ([`build_draft_table`], [`Renderer::set_azimuthal_table`]).
    Azimuthal(Arc<AzimuthalTable>),
    Tables(ParamTables),
}

impl TableBuild {
    /// With `draft` (a new eta or eccentricity, shown at once) the draft table, unless the process
    /// keeps the tables of `params` (an undo): then, and without `draft`, the tables. `reuse` as
    /// for [`build_tables`].
    pub fn build(params: &HairParams, reuse: Option<&Arc<AzimuthalTable>>, draft: bool) -> Self {
        if draft && !crate::render::renderer::table_cache::holds(params) {
            Self::Azimuthal(build_draft_table(params))
        } else {
            Self::Tables(build_tables(params, reuse))
        }
    }

    pub fn azimuthal(&self) -> &Arc<AzimuthalTable> {
        match self {
            Self::Azimuthal(t) => t,
            Self::Tables(t) => &t.azimuthal,
        }
    }

    /// The azimuthal table alone: the forward and dual tables are still to be built.
    pub fn azimuthal_only(&self) -> bool {
        matches!(self, Self::Azimuthal(_))
    }
}

impl Renderer {
    /// Hair parameters changed: the uniform is rewritten; when the exact parameters changed, the
    /// forward and dual-scattering tables are rebuilt on the CPU and uploaded, and the shadow grid
    /// (whose T_f reads the forward table) is marked for rebuilding. No geometry, pipeline or volume
    /// rebuild.
    pub fn set_params(&mut self, ctx: &GpuContext, look: &HairLook) {
        ctx.queue
            .write_buffer(&self.look.params, 0, bytemuck::bytes_of(&look.fast));
        self.look.look = *look;
        if self.tables_needed(&look.params) {
            let tables = build_tables(&look.params, Some(&self.look.azimuthal));
            self.set_tables(ctx, &look.params, &tables);
        }
        self.restart_refinement();
    }

    /// Hair parameters changed, without waiting for the tables: the uniform is rewritten now (single
    /// scattering shows the change in the next frame); returns true when the renderer needs tables for
    /// them ([`Renderer::tables_needed`]), and then the caller builds the tables ([`build_tables`], off
    /// the UI thread) and hands them to [`Renderer::set_tables`]. Until then multiple scattering and
    /// forward transmittance use the old tables, and a new eta or eccentricity waits for an azimuthal
    /// table made for it (the frame keeps the old index: `write_params`); the editor hands it a draft
    /// first ([`TableBuild::build`], [`Renderer::set_azimuthal_table`]).
    pub fn set_params_deferred(&mut self, ctx: &GpuContext, look: &HairLook) -> bool {
        let tables_needed = self.tables_needed(&look.params);
        let (before, index_only) = (self.frame_params(), self.look.look.index_only_change(look));
        self.look.look = *look;
        self.write_params(ctx);
        // A new eta or eccentricity alone changes nothing a frame reads until a table made for it
        // arrives: the image stays, and the cores stay free for that table's build. Any other
        // change restarts, even one the frame's parameters do not show (the tables will).
        if !index_only || self.frame_params() != before {
            self.restart_refinement();
        }
        tables_needed
    }

    /// Whether `params` need tables this renderer does not hold: other parameters than the
    /// absorption, or an azimuthal table not made for them (a draft, [`build_draft_table`], or one
    /// shown ahead of its tables for another index: [`Renderer::set_azimuthal_table`]).
    pub fn tables_needed(&self, params: &HairParams) -> bool {
        !same_tables(params, &self.look.tables_for) || !self.look.azimuthal.fits_hair(params)
    }

    /// Writes the look's fast parameters, with the azimuthal table's eta and eccentricity while the
    /// table for new ones is being built: a frame never reads a table made for another index (an eta or
    /// eccentricity change shows when a table made for it arrives: in the editor its draft, 0.06-0.07 s
    /// of build on two cores for a round fiber and 0.22-0.25 s for an elliptical one, then the table,
    /// 0.8 s and 3 s).
    pub(super) fn write_params(&self, ctx: &GpuContext) {
        let fast = self.frame_params();
        ctx.queue
            .write_buffer(&self.look.params, 0, bytemuck::bytes_of(&fast));
    }

    /// The fast parameters a frame reads: the look's, with the azimuthal table's eta and
    /// eccentricity while the table for new ones is being built.
    pub(super) fn frame_params(&self) -> FastHairParams {
        let mut fast = self.look.look.fast;
        if !self.look.azimuthal.for_index(&fast) {
            fast.eta = self.look.azimuthal.eta;
            fast.eccentricity = self.look.azimuthal.eccentricity;
        }
        fast
    }

    /// The azimuthal table in use (kept by a rebuild for the same eta and eccentricity).
    pub fn azimuthal_table(&self) -> &Arc<AzimuthalTable> {
        &self.look.azimuthal
    }

    /// Takes what a worker built for `params` ([`TableBuild`]); false when ignored (the look has
    /// moved on since).
    pub fn take_tables(
        &mut self,
        ctx: &GpuContext,
        params: &HairParams,
        built: &TableBuild,
    ) -> bool {
        match built {
            TableBuild::Azimuthal(table) => self.set_azimuthal_table(ctx, params, table),
            TableBuild::Tables(tables) => self.set_tables(ctx, params, tables),
        }
    }

    /// A new eta or eccentricity's azimuthal table ahead of its other tables (its draft,
    /// [`build_draft_table`]): the index shows from the next frame, its single scattering a preview
    /// away. The forward and dual tables, which change little with the index, stay until the tables
    /// arrive ([`Renderer::set_tables`]), as after any other parameter change: the shadow grid is
    /// kept, and the renderer still asks for the tables ([`Renderer::tables_needed`]). Ignored
    /// (false) when the look has moved on or the table is not for its index.
    pub fn set_azimuthal_table(
        &mut self,
        ctx: &GpuContext,
        params: &HairParams,
        table: &Arc<AzimuthalTable>,
    ) -> bool {
        if !same_tables(params, &self.look.look.params) || !table.made_for_hair(params) {
            return false;
        }
        if !Arc::ptr_eq(&self.look.azimuthal, table) {
            self.upload_azimuthal(ctx, table);
            self.restart_refinement();
        }
        true
    }

    /// The azimuthal table to the GPU, and the parameters a frame reads with it (`write_params`).
    pub(super) fn upload_azimuthal(&mut self, ctx: &GpuContext, table: &Arc<AzimuthalTable>) {
        ctx.queue
            .write_buffer(&self.look.azimuthal_table, 0, table.gpu_bytes());
        self.look.azimuthal = table.clone();
        self.write_params(ctx);
    }

    /// Uploads tables built for `params`; ignored (false) when the look has moved on since.
    pub fn set_tables(
        &mut self,
        ctx: &GpuContext,
        params: &HairParams,
        tables: &ParamTables,
    ) -> bool {
        if !same_tables(params, &self.look.look.params) {
            return false;
        }
        ctx.queue.write_buffer(
            &self.look.forward_table,
            0,
            bytemuck::cast_slice(&forward_table_texels(&tables.forward)),
        );
        ctx.queue.write_buffer(
            &self.look.dual_tables,
            0,
            bytemuck::cast_slice(&dual_tables_texels(&tables.dual)),
        );
        let azimuthal_changed = !Arc::ptr_eq(&self.look.azimuthal, &tables.azimuthal);
        // The table after its draft (or after a kept table for its index, shown ahead of its
        // tables): the index is on screen, and the refinement goes on as a refinement. Tables for
        // another index (an undo while a draft shows) owe a preview.
        let after_draft = azimuthal_changed && self.look.azimuthal.made_for_hair(params);
        // Whether the forward and dual tables are new (the grid's forward terms read the forward
        // table): not for tables of the parameters these were built for.
        let others_changed = !same_tables(params, &self.look.tables_for);
        if azimuthal_changed {
            self.upload_azimuthal(ctx, &tables.azimuthal);
        }
        self.look.tables_for = *params;
        // The forward and dual tables are read only with multiple scattering (the grid's forward
        // terms, the shading's dual terms); without it only a new azimuthal table changes the image.
        // A new azimuthal table shows a change not on screen yet (an eta or eccentricity change waits
        // for it): a preview is owed, unless its draft showed it; the others refine the change
        // already shown.
        let regrid = self.settings.multiple_scattering && others_changed;
        if after_draft {
            if regrid {
                self.restart_as_refinement(|r| r.mark_shadow_grid_dirty());
            } else {
                self.restart_as_refinement(|r| r.restart_refinement());
            }
        } else if azimuthal_changed {
            if regrid {
                self.mark_shadow_grid_dirty();
            } else {
                self.restart_refinement();
            }
        } else if regrid {
            // The grid's transmittance and the single scattering read no table: a converged image
            // keeps its single scattering, and only multiple scattering is shaded again.
            self.refine_multiple_only(|r| r.mark_shadow_grid_dirty());
        }
        true
    }

    /// The hair parameters the renderer holds.
    pub fn look(&self) -> &HairLook {
        &self.look.look
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only an eta or eccentricity change alone leaves the refinement as it is
    /// ([`Renderer::set_params_deferred`]); a change the fast form does not carry restarts it.
    #[test]
    fn an_index_only_change_is_told_apart() {
        let a = HairLook::new(HairParams::default());
        let mut p = a.params;
        p.eta = 1.6;
        p.eccentricity = 0.9;
        assert!(a.index_only_change(&HairLook::new(p)));
        assert!(!a.index_only_change(&a), "the same look is no change");
        let mut q = p;
        q.beta_r *= 0.5;
        assert!(!a.index_only_change(&HairLook::new(q)));
        let mut r = a.params;
        r.glint_scale *= 2.0;
        assert!(!a.index_only_change(&HairLook::new(r)));
    }
}
