//! Which tables the live image needs and when they are built and handed over: the one place the
//! driver decides about tables. The renderer says whether a look needs tables it does not hold
//! ([`Renderer::set_params_deferred`]); this decides which to build (a draft of a new index's
//! azimuthal table first, the full set after), reuses those built or being built when they serve,
//! builds one set at a time on a worker, and holds a finished set until the image can take it.

use super::jobs::Job;
use crate::gpu::GpuContext;
use crate::render::renderer::{TableBuild, same_tables, table_cache};
use crate::render::{HairLook, Renderer};
use crate::scattering::HairParams;
use crate::scattering::azimuthal_table::AzimuthalTable;
use std::sync::Arc;

/// Tables built for these parameters.
type Tables = (HairParams, TableBuild);

/// The tables on their way to the renderer.
pub(super) struct TableWork {
    /// The build under way, and the parameters it is for.
    job: Option<Job<Tables>>,
    building: Option<HairParams>,
    /// Tables to build (for these parameters, reusing this azimuthal table when it fits).
    wanted: Option<(HairParams, Arc<AzimuthalTable>)>,
    /// Tables built but not yet handed to the renderer ([`TableWork::hand_over`]).
    held: Option<Tables>,
    /// The last build died (a draft in the renderer then stays).
    failed: bool,
    /// The budget's share for units while tables are wanted or built (`budget_share`).
    building_share: f64,
}

/// What handing tables over did to the image.
pub(super) enum HandedOver {
    /// A new index's draft azimuthal table: the image shows the change from here.
    Draft,
    /// The full tables: the image refines the change it shows.
    Tables,
}

impl TableWork {
    pub(super) fn new(building_share: f64) -> Self {
        Self {
            building_share,
            job: None,
            building: None,
            wanted: None,
            held: None,
            failed: false,
        }
    }

    /// A new look went to the renderer, which `needs` tables for it: tables built or being built
    /// for parameters that differ only in the absorption serve (a draft's table follows it);
    /// else tables are wanted, reusing the held azimuthal table when it fits (an eta change in
    /// the works) or the renderer's (rebuilt only for a new eta or eccentricity).
    pub(super) fn look_changed(&mut self, look: &HairLook, needs: bool, renderer: &Renderer) {
        let fits = |p: &HairParams| same_tables(p, &look.params);
        let held_fits = self
            .held
            .as_ref()
            .is_some_and(|(p, t)| fits(p) && !t.azimuthal_only())
            || (self.job.is_some() && self.building.as_ref().is_some_and(fits));
        if needs && !held_fits {
            let params = look.params;
            let azimuthal = self
                .held
                .as_ref()
                .map(|(_, t)| t.azimuthal().clone())
                .filter(|t| t.fits_hair(&params))
                .unwrap_or_else(|| renderer.azimuthal_table().clone());
            // A newer build replaces an older one; take_tables ignores stale tables anyway. It
            // starts once the change's preview is on screen (`start`): on two cores the build
            // would slow the preview, and a slider drag would start one per frame.
            self.held = None;
            self.wanted = Some((params, azimuthal));
        } else {
            // The renderer's or the held tables fit: an intermediate look's build is not wanted.
            self.wanted = None;
        }
    }

    /// Starts the wanted build when the change shows (`change_shown`: its first image is on
    /// screen, the image is converged, or no preview comes first) or, for a new eta or
    /// eccentricity, which shows only with an azimuthal table made for it, at once: its draft.
    pub(super) fn start(&mut self, change_shown: bool) {
        let start = self.wanted.as_ref().is_some_and(|(params, azimuthal)| {
            // One build at a time (a slider drag would pile them up on the GPU's cores), but
            // tables the process keeps (an undo after a new eta's draft) need none.
            (self.job.is_none() || table_cache::holds(params))
                && (change_shown || !azimuthal.made_for_hair(params))
        });
        if start && let Some((params, azimuthal)) = self.wanted.take() {
            // A build under way (only when the process keeps these tables) is for parameters left
            // behind: its result is dropped.
            self.building = Some(params);
            // A new eta or eccentricity shows first with a draft of its azimuthal table alone (a
            // twelfth of the build), then with the tables, built next.
            let draft = !azimuthal.made_for_hair(&params);
            self.job = Some(Job::spawn(
                "hair tables",
                || {},
                move |_| (params, TableBuild::build(&params, Some(&azimuthal), draft)),
            ));
        }
    }

    /// Takes a finished build into the held tables.
    pub(super) fn poll(&mut self) {
        match self.job.as_mut().and_then(|job| job.poll()) {
            Some(Ok(tables)) => {
                self.job = None;
                self.failed = false;
                self.held = Some(tables);
            }
            // A build that died leaves the old tables (the shading still follows the look), or
            // the draft: then the image is as final as it gets ([`TableWork::pending`]).
            Some(Err(_)) => {
                self.job = None;
                self.failed = true;
            }
            None => {}
        }
    }

    /// Hands the held tables to the renderer when the image can take them: once the change is
    /// `shown` (so it shows sharp in about one pass's time and its multiple scattering follows), at
    /// once when the grid is being rebuilt anyway (one rebuild, not two) or when the azimuthal
    /// table is new (an eta or eccentricity change shows only with a table made for it).
    pub(super) fn hand_over(
        &mut self,
        ctx: &GpuContext,
        renderer: &mut Renderer,
        shown: bool,
    ) -> Option<HandedOver> {
        let ready = self.held.as_ref().is_some_and(|(_, t)| {
            shown
                || renderer.shadow_grid_stale()
                || !Arc::ptr_eq(t.azimuthal(), renderer.azimuthal_table())
        });
        if !ready {
            return None;
        }
        let (params, tables) = self.held.take()?;
        if !renderer.take_tables(ctx, &params, &tables) {
            return None;
        }
        if tables.azimuthal_only() {
            // The tables are built once the draft's preview shows, unless a newer change asked
            // for other tables meanwhile.
            if self.wanted.is_none() {
                self.wanted = Some((params, tables.azimuthal().clone()));
            }
            Some(HandedOver::Draft)
        } else {
            Some(HandedOver::Tables)
        }
    }

    /// Tables are wanted, being built or held: the volume waits for them (they rebuild the grid
    /// too).
    pub(super) fn waiting(&self) -> bool {
        self.building() || self.held.is_some()
    }

    /// Tables are wanted or being built.
    fn building(&self) -> bool {
        self.wanted.is_some() || self.job.is_some()
    }

    /// The share of the unit budget refinement gets: smaller while tables are wanted or being
    /// built, which take the same cores.
    pub(super) fn budget_share(&self) -> f64 {
        if self.building() {
            self.building_share
        } else {
            1.0
        }
    }

    /// Whether the image still waits for tables: being built, not yet handed over, or a draft
    /// shown whose build has not died.
    pub(super) fn pending(&self, renderer: &Renderer) -> bool {
        self.waiting() || (renderer.azimuthal_table().draft && !self.failed)
    }
}
