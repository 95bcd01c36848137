//! The closed loop at the written model: which of Table 1's quantities this campaign
//! identifies (Table 1's closed-loop column; issue 54 item 4).
//!
//! Takes the campaign, its energy table (and the table's path, which messages name), the
//! written model (the chain's, with the layout's levels) and its fit; gives, per cluster
//! quantity, an [`Identification`] by the rule of [`crate::fit::identify`]:
//!
//! 1. R tables drawn from the written model over the campaign's own poses and directions
//!    ([`EnergySimulator::for_table`]: the table's recorded N0, its missing sweeps missing,
//!    the fold and the coloured noise of the measurement), seed_r keyed from the seed
//!    (default the campaign's) on a stream of their own, so they never replay the check's
//!    draws;
//! 2. each read by the documented chain ([`extract_and_cluster`] with
//!    [`ChainParams::for_campaign`]: the commands' defaults, as `report` reads the campaign;
//!    a campaign clustered with other options is still read back with the defaults),
//!    [`fit_clustering`] with the fit's parameters (the same resamples and seed, so each
//!    draw has its own 95 % interval);
//! 3. per quantity, the readings against the written value and the campaign's interval.
//!
//! A draw whose fit fails (too few clusters, say) reads nothing; the rule then counts it
//! among the draws the chain did not read. When no draw can be read the run is an error
//! naming the first draw's. The draws run in parallel (rayon); each draw's
//! seed is fixed by its index, so the result does not depend on the thread count.
//!
//! Cost: R chains on the whole table (the corridor: about a second each on 2 cores), so
//! `report` runs it with [`DEFAULT_DRAWS`] and `fit` only when asked.

use crate::campaign::manifest::Campaign;
use crate::chain::{extract_and_cluster, ChainParams};
use crate::check::{keyed_seed, table_draw};
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::fit::channel::{fit_clustering, FitValid};
use crate::fit::identify::{identify, Identification, Reading};
use crate::fit::table1::KEYS;
use crate::model::file::{ModelConfig, Quantity};
use crate::model::EnergySimulator;
use crate::params::{ParamGuard, Valid};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

/// The draws' stream key (xor-ed into the seed; [`keyed_seed`]).
const STREAM: u64 = 0x436c_4c6f_6f70_0000;

/// Draws `report` runs.
pub const DEFAULT_DRAWS: usize = 6;

/// Most draws a run may ask for.
pub const MAX_DRAWS: usize = 100;

/// The closed loop's options.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedLoopParams {
    /// Draws R, 1 to [`MAX_DRAWS`] (default [`DEFAULT_DRAWS`]).
    pub draws: usize,
    /// Seed (default: the campaign's).
    pub seed: Option<u64>,
    /// synth's ray cull (default 1e-3, as synth), in [0, 1).
    pub cull: f64,
}

impl Default for ClosedLoopParams {
    fn default() -> Self {
        ClosedLoopParams {
            draws: DEFAULT_DRAWS,
            seed: None,
            cull: 1e-3,
        }
    }
}

/// Checked closed-loop options.
pub type ClosedLoopValid = Valid<ClosedLoopParams>;

impl ParamGuard for ClosedLoopParams {
    type Checked = ClosedLoopValid;

    /// Every field in its range; the error names the field.
    fn check(&self) -> Result<ClosedLoopValid> {
        if !(1..=MAX_DRAWS).contains(&self.draws) {
            return Err(Error::param(
                "closed_loop.draws",
                format!("must be in [1, {MAX_DRAWS}], got {}", self.draws),
            ));
        }
        if !(0.0..1.0).contains(&self.cull) {
            return Err(Error::param(
                "closed_loop.cull",
                format!("must be in [0, 1), got {}", self.cull),
            ));
        }
        Ok(Valid::new(self.clone()))
    }
}

/// Quantity `key` of [`KEYS`] of a model.
fn quantity<'a>(m: &'a ModelConfig, key: &str) -> &'a Quantity {
    m.quantity(key)
        .unwrap_or_else(|| unreachable!("{key} is a key of Table 1's cluster quantities"))
}

/// The closed loop of `written` (fitted on campaign `c`'s table `em`, read from
/// `energy_path`) with the fit's parameters `fit`: the verdict per key of [`KEYS`] (a
/// quantity that was not estimated has none), what [`ChannelFit::identified`] holds.
/// `progress(done, R)` after each draw.
///
/// [`ChannelFit::identified`]: crate::fit::channel::ChannelFit::identified
pub fn closed_loop(
    c: &Campaign,
    em: &EnergyMatrix,
    energy_path: &Path,
    written: &ModelConfig,
    fit: &FitValid,
    params: &ClosedLoopValid,
    progress: &dyn Fn(usize, usize),
) -> Result<BTreeMap<String, Identification>> {
    let sim = EnergySimulator::for_table(c, em, energy_path, params.cull)?;
    let chain = ChainParams::for_campaign(c)?;
    let seed = params.seed.unwrap_or(c.manifest.seed);
    let r = params.draws;
    progress(0, r);
    // a thread's worth of draws at a time, so progress is called from this thread only
    let chunk = rayon::current_num_threads().max(1);
    let mut readings: Vec<Result<ModelConfig>> = Vec::with_capacity(r);
    for start in (0..r).step_by(chunk) {
        let part: Vec<Result<ModelConfig>> = (start..(start + chunk).min(r))
            .into_par_iter()
            .map(|i| -> Result<Result<ModelConfig>> {
                let data = table_draw(&sim, em, written, keyed_seed(seed, STREAM, i))?;
                // the table's shape and metadata (its N0, gate, missing sweeps), the draw's
                // energies
                let drawn = EnergyMatrix {
                    meta: em.meta.clone(),
                    positions: em.positions,
                    angles_rel_deg: em.angles_rel_deg.clone(),
                    headings_deg: em.headings_deg.clone(),
                    bins: em.bins,
                    first: 0,
                    data,
                };
                // a draw the chain cannot fit reads nothing (the rule counts it)
                Ok(extract_and_cluster(&drawn, c, &chain)
                    .and_then(|(_, clustering)| fit_clustering(energy_path, &clustering, c, fit))
                    .map(|f| f.model))
            })
            .collect::<Result<_>>()?;
        readings.extend(part);
        progress(readings.len(), r);
    }
    // no draw read at all: the chain's error, not a verdict of "read in 0 of R"
    if readings.iter().all(|m| m.is_err()) {
        let first = readings.swap_remove(0).expect_err("every draw failed");
        return Err(Error::input(
            energy_path,
            format!("the closed loop: the chain read none of the {r} draws of the written model: {first}"),
        ));
    }
    let mut out = BTreeMap::new();
    for key in KEYS {
        let read: Vec<Reading> = (readings.iter())
            .map(|m| {
                m.as_ref().ok().and_then(|m| {
                    let q = quantity(m, key);
                    q.is_estimable().then_some((q.value, q.interval))
                })
            })
            .collect();
        if let Some(id) = identify(quantity(written, key), &read) {
            out.insert(key.to_string(), id);
        }
    }
    Ok(out)
}
