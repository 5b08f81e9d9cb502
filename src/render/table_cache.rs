//! The hair-parameter tables ([`ParamTables`]) of the last few parameter sets, kept for the process:
//! a renderer made again for the same look (a second view, a test's next render, the reference
//! beside the renderer) or an edit undone takes them from here instead of building them again
//! (about 2.2 s on two cores for the default fiber, most of a renderer's creation).
//!
//! The tables are a pure function of the parameters other than the absorption ([`same_tables`]):
//! a cached entry is exactly what a new build would give.

use std::sync::{Arc, Mutex};

use super::renderer::{ParamTables, same_tables};
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::params::HairParams;

/// Parameter sets kept (a round fiber's tables take ~15 MB, an eccentric fiber's ~50 MB: most of it
/// the azimuthal table).
pub const CACHED_PARAMETER_SETS: usize = 4;

/// Tables by parameter set, most recently used last.
#[derive(Default)]
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

    /// A kept azimuthal table for `params`' eta and eccentricity (the other parameters may differ).
    pub fn azimuthal(&self, params: &HairParams) -> Option<Arc<AzimuthalTable>> {
        self.entries
            .iter()
            .rev()
            .find(|(_, t)| t.azimuthal.fits_hair(params))
            .map(|(_, t)| t.azimuthal.clone())
    }
}

/// The process's cache ([`super::renderer::build_tables`] reads and fills it).
static CACHE: Mutex<TableCache> = Mutex::new(TableCache::new(CACHED_PARAMETER_SETS));

/// Runs `f` on the process's cache. (A poisoned lock only means that another thread panicked while
/// holding it: every entry is pushed whole, so the cache is still valid.)
pub fn with_cache<R>(f: impl FnOnce(&mut TableCache) -> R) -> R {
    f(&mut CACHE.lock().unwrap_or_else(|e| e.into_inner()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::renderer::build_tables;

    /// A kept set serves its parameters at any absorption, not another eta; the least recently used
    /// set goes first; the process's cache gives a second build the first one's tables.
    #[test]
    fn kept_tables_serve_the_same_parameters() {
        // An eta no other test uses (tests run in parallel and share the process's cache).
        let p = HairParams {
            eta: 1.5123,
            ..HairParams::default()
        };
        let tables = build_tables(&p, None);
        let again = build_tables(&p, None);
        assert!(
            Arc::ptr_eq(&tables.azimuthal, &again.azimuthal) || with_cache(|c| c.get(&p).is_none())
        );
        let mut cache = TableCache::new(2);
        cache.keep(&p, &tables);
        let dyed = HairParams {
            sigma_a: [2.0, 1.0, 0.5],
            ..p
        };
        let hit = cache
            .get(&dyed)
            .expect("an absorption change uses the same tables");
        assert!(Arc::ptr_eq(&hit.azimuthal, &tables.azimuthal));
        assert_eq!(hit.dual, tables.dual);
        assert_eq!(
            (&hit.forward.a_f, &hit.forward.beta_f2),
            (&tables.forward.a_f, &tables.forward.beta_f2)
        );
        let wider = HairParams {
            beta_r: p.beta_r * 1.5,
            ..p
        };
        assert!(
            cache.get(&wider).is_none(),
            "another width needs its own tables"
        );
        assert!(
            cache.azimuthal(&wider).is_some(),
            "but the same azimuthal table"
        );
        let other_eta = HairParams { eta: 1.5124, ..p };
        assert!(cache.azimuthal(&other_eta).is_none());
        // Two more sets in a cache of two: p, the least recently used, goes.
        cache.keep(&wider, &tables);
        cache.keep(&other_eta, &tables);
        assert!(cache.get(&p).is_none() && cache.get(&wider).is_some());
    }
}
