//! The noise floors of the check: each table's N̂0 read from its own bins (module docs of
//! [`super`]), the measured table's against the draws' median.
//!
//! Takes a table's energies and its statistics' context ([`noise_floor`]); gives its
//! floor, and for the check ([`NoiseFloors`]) the offset in dB and whether it passes.

use super::stats::StatContext;
use super::MAX_NOISE_DB;

/// The noise floors: the measured table's and the draws', each N̂0 read from the table's
/// own bins (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseFloors {
    /// The measured table's recorded N0 (metadata `n0`; the draws were drawn with it).
    pub recorded_n0: f64,
    /// The measured table's floor N̂0.
    pub measured: f64,
    /// Each draw's floor N̂0.
    pub draws: Vec<f64>,
}

impl NoiseFloors {
    /// The draws' median floor.
    pub fn draws_median(&self) -> f64 {
        crate::stats::median(&self.draws).unwrap_or(f64::NAN)
    }
    /// The measured floor over the draws' median, dB.
    pub fn offset_db(&self) -> f64 {
        10.0 * (self.measured / self.draws_median()).log10()
    }
    /// Whether the floors agree within [`MAX_NOISE_DB`] (a NaN offset does not).
    pub fn agree(&self) -> bool {
        self.offset_db().abs() <= MAX_NOISE_DB
    }
    /// One line naming both floors.
    pub fn line(&self) -> String {
        format!(
            "noise: the measured table's floor {:.3e} is {:+.1} dB from the draws' {:.3e} (fails beyond ±{MAX_NOISE_DB} dB; the recorded N0 the draws carry {:.3e})",
            self.measured,
            self.offset_db(),
            self.draws_median(),
            self.recorded_n0
        )
    }
}

/// The quantile of the noise floor's estimator ([`noise_floor`]).
pub const FLOOR_QUANTILE: f64 = 0.25;

/// The noise floor N̂0 of energies `e` read from its own bins: the lower quartile of the
/// bins after the coupling gate (NaN profiles left out) over TW · q_k, q_k the lower
/// quartile of the detector's Gamma(k, k) law, k = TW·N_p (NaN without a bin).
pub fn noise_floor(ctx: &StatContext, e: &[f64], tw: f64, pulses: usize) -> f64 {
    let mut v: Vec<f64> = e
        .chunks(ctx.nb)
        .flat_map(|prof| &prof[ctx.first_bin.min(prof.len())..])
        .copied()
        .filter(|x| !x.is_nan())
        .collect();
    if v.is_empty() {
        return f64::NAN;
    }
    let i = ((v.len() - 1) as f64 * FLOOR_QUANTILE).round() as usize;
    let (_, q, _) = v.select_nth_unstable_by(i, f64::total_cmp);
    *q / (tw * crate::energy::noise::law_quantile(tw * pulses as f64, FLOOR_QUANTILE))
}
