//! The hair-parameter tables ([`ParamTables`]) of the last few parameter sets, kept for the process:
//! a renderer made again for the same look (a second view, a test's next render, the reference
//! beside the renderer) or an edit undone takes them from here instead of building them again
//! (about 0.85 s on two cores for the default fiber, nearly all of it the azimuthal table: about
//! half of a renderer's creation).
//!
//! The tables are a pure function of the parameters other than the absorption ([`same_tables`]):
//! a cached entry is exactly what a new build would give. (The key is conservative: the caustic
//! parameters, which no table reads, are part of it.)

use std::sync::{Arc, Mutex};

use crate::render::renderer::{ParamTables, same_tables};
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::params::HairParams;

/// Parameter sets kept (a round fiber's tables take ~22 MB, an eccentric fiber's ~75 MB: most of it
/// the azimuthal table, its f32 cells and the GPU's half-precision copy).
pub const CACHED_PARAMETER_SETS: usize = 4;

/// Tables by parameter set, most recently used last.
pub struct TableCache {
    entries: Vec<(HairParams, ParamTables)>,
    capacity: usize,
}

impl TableCache {
    pub const fn new(capacity: usize) -> Self {
        Self {
            entries: Vec::new(),
            capacity,
        }
    }

    /// The tables of `params`, if kept (moved to the most recently used place).
    pub fn get(&mut self, params: &HairParams) -> Option<ParamTables> {
        let i = self
            .entries
            .iter()
            .position(|(p, _)| same_tables(p, params))?;
        let entry = self.entries.remove(i);
        let tables = entry.1.clone();
        self.entries.push(entry);
        Some(tables)
    }

    /// Keeps `tables`, built for `params`, dropping the least recently used sets beyond the capacity.
    pub fn keep(&mut self, params: &HairParams, tables: &ParamTables) {
        self.entries.retain(|(p, _)| !same_tables(p, params));
        self.entries.push((*params, tables.clone()));
        let excess = self.entries.len().saturating_sub(self.capacity);
        self.entries.drain(..excess);
    }

    /// Whether the tables of `params` are kept (no lookup's reordering).
    pub fn holds(&self, params: &HairParams) -> bool {
        self.entries.iter().any(|(p, _)| same_tables(p, params))
    }

    /// A kept azimuthal table for `params`' eta and eccentricity (the other parameters may differ).
    pub fn azimuthal(&self, params: &HairParams) -> Option<Arc<AzimuthalTable>> {
        self.entries
            .iter()
            .rev()
            .find(|(_, t)| t.azimuthal.fits_hair(params))
            .map(|(_, t)| t.azimuthal.clone())
    }
}

/// The process's cache ([`crate::render::renderer::build_tables`] reads and fills it).
static CACHE: Mutex<TableCache> = Mutex::new(TableCache::new(CACHED_PARAMETER_SETS));

/// Runs `f` on the process's cache, locked (`f` must not build tables: the lock is not re-entrant).
/// A poisoned lock only means that another thread panicked while holding it: every entry is
/// pushed whole, so the cache is still valid.
pub(crate) fn with_cache<R>(f: impl FnOnce(&mut TableCache) -> R) -> R {
    f(&mut CACHE.lock().unwrap_or_else(|e| e.into_inner()))
}

/// Whether the process keeps the tables of `params` ([`TableCache::holds`]).
pub fn holds(params: &HairParams) -> bool {
    with_cache(|c| c.holds(params))
}

/// Forgets every kept set (the next build of any parameters builds anew: benchmarks time it).
pub fn clear() {
    with_cache(|c| c.entries.clear());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::renderer::build_tables;
    use crate::scattering::dual_terms::DualTables;
    use crate::shadow::forward::ForwardTable;

    /// Tables that are told apart by their contents (no build: the cache's logic alone).
    fn tagged(tag: f32, p: &HairParams) -> ParamTables {
        ParamTables {
            forward: ForwardTable {
                a_f: vec![tag],
                beta_f2: vec![],
            },
            dual: DualTables { rows: vec![] },
            azimuthal: Arc::new(AzimuthalTable {
                eta: p.eta as f32,
                eccentricity: p.eccentricity as f32,
                draft: false,
                cells: vec![[tag; 4]],
                gpu: vec![],
            }),
        }
    }

    fn tag(t: &ParamTables) -> f32 {
        t.forward.a_f[0]
    }

    /// A kept set serves its parameters at any absorption and no other set; the least recently
    /// used set goes first (a read counts as a use); a kept azimuthal table serves any set of the
    /// same eta and eccentricity.
    #[test]
    fn kept_tables_serve_the_same_parameters_only() {
        let p = HairParams::default();
        let mut cache = TableCache::new(2);
        cache.keep(&p, &tagged(1.0, &p));
        let dyed = HairParams {
            sigma_a: [2.0, 1.0, 0.5],
            ..p
        };
        assert_eq!(cache.get(&dyed).as_ref().map(tag), Some(1.0));
        let others = [
            HairParams {
                beta_r: p.beta_r * 1.5,
                ..p
            },
            HairParams {
                alpha_r: p.alpha_r * 0.5,
                ..p
            },
            HairParams {
                eccentricity: 0.9,
                ..p
            },
            HairParams { eta: 1.6, ..p },
            HairParams {
                caustic_fade: p.caustic_fade * 2.0,
                ..p
            },
        ];
        for o in &others {
            assert!(cache.get(o).is_none(), "{o:?} served by {p:?}'s tables");
        }
        let wider = others[0];
        assert!(
            cache.azimuthal(&wider).is_some(),
            "the same eta and eccentricity"
        );
        assert!(cache.azimuthal(&others[2]).is_none() && cache.azimuthal(&others[3]).is_none());
        // [p], then [p, wider]; reading p makes wider the least recently used, which a third set
        // pushes out.
        cache.keep(&wider, &tagged(2.0, &wider));
        assert_eq!(cache.get(&p).as_ref().map(tag), Some(1.0));
        cache.keep(&others[1], &tagged(3.0, &others[1]));
        assert!(cache.get(&wider).is_none());
        assert_eq!(cache.get(&p).as_ref().map(tag), Some(1.0));
        // Keeping a set again replaces its entry.
        cache.keep(&dyed, &tagged(4.0, &p));
        assert_eq!(cache.get(&p).as_ref().map(tag), Some(4.0));
        assert_eq!(cache.entries.len(), 2);
    }

    /// build_tables takes a kept set instead of building (a tagged set stands for it), with the
    /// caller's azimuthal table in place of the kept one where it serves the parameters.
    #[test]
    fn build_tables_takes_a_kept_set_and_keeps_the_callers_table() {
        // An eta no other test uses (tests run in parallel and share the process's cache).
        let p = HairParams {
            eta: 1.5123,
            ..HairParams::default()
        };
        with_cache(|c| c.keep(&p, &tagged(7.0, &p)));
        let t = build_tables(&p, None);
        assert_eq!(tag(&t), 7.0, "built anew");
        let own = tagged(8.0, &p).azimuthal;
        let t = build_tables(&p, Some(&own));
        assert_eq!(tag(&t), 7.0);
        assert!(Arc::ptr_eq(&t.azimuthal, &own));
        with_cache(|c| c.entries.retain(|(q, _)| !same_tables(q, &p)));
    }
}
