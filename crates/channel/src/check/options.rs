//! The check's options and its level: α ([`ALPHA`]), the noise floors' tolerance
//! ([`MAX_NOISE_DB`]), the draw counts R it accepts ([`DRAWS_RANGE`], default
//! [`DEFAULT_DRAWS`]).
//!
//! Takes the options as given ([`CheckParams`]); gives them checked ([`CheckValid`]) or
//! one error naming the option.

use super::PosteriorSample;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// The check's level: it fails when its p-value is at or below α.
pub const ALPHA: f64 = 0.05;

/// The largest difference (dB) between the measured table's noise floor and the draws'
/// median floor a passing check may have.
pub const MAX_NOISE_DB: f64 = 1.0;

/// The default number of draws R: (R + 1)·α = 2, so the rule can reject at α and its
/// false rejection is exactly α.
pub const DEFAULT_DRAWS: usize = 39;

/// Options of a check.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckParams {
    /// Draws R, in [`DRAWS_RANGE`] (default [`DEFAULT_DRAWS`]).
    pub draws: usize,
    /// Seed (default: the campaign's).
    pub seed: Option<u64>,
    /// synth's ray cull (default 1e-3, as synth).
    pub cull: f64,
    /// A posterior sample (`calibrate`'s final population): each draw's free quantities
    /// come from a particle drawn by weight, the rest from the model file (None: every
    /// draw is the model file's, the plug-in check).
    pub posterior: Option<PosteriorSample>,
}

/// The fewest draws R at which the check can fail on its statistics: the smallest R with
/// 1/(R + 1) ≤ [`ALPHA`] (19 at α = 0.05). The Monte Carlo p-value (1 + k)/(R + 1) is at
/// least 1/(R + 1), so with fewer draws it never reaches α.
pub const MIN_DRAWS: usize = min_draws(ALPHA);

/// The smallest R ≥ 1 with 1/(R + 1) ≤ `alpha` (`alpha` in (0, 1)).
const fn min_draws(alpha: f64) -> usize {
    let mut r = 1;
    while 1.0 / ((r + 1) as f64) > alpha {
        r += 1;
    }
    r
}

/// The draw counts [`CheckParams`]'s check accepts (`--draws`): from [`MIN_DRAWS`] (with
/// fewer the p-value cannot reach α) to 1000.
pub const DRAWS_RANGE: std::ops::RangeInclusive<usize> = MIN_DRAWS..=1000;

/// Why `--draws` has [`DRAWS_RANGE`]'s lower end (the one-line error says it): "with fewer
/// than 19 draws the p-value (1 + k)/(R + 1) cannot reach α = 0.05".
pub fn draws_why() -> String {
    format!(
        "with fewer than {MIN_DRAWS} draws the p-value (1 + k)/(R + 1) cannot reach α = {ALPHA}"
    )
}

impl Default for CheckParams {
    fn default() -> Self {
        CheckParams {
            draws: DEFAULT_DRAWS,
            seed: None,
            cull: 1e-3,
            posterior: None,
        }
    }
}

/// Checked check options.
pub type CheckValid = Valid<CheckParams>;

impl ParamGuard for CheckParams {
    type Checked = CheckValid;

    fn check(&self) -> Result<CheckValid> {
        if !DRAWS_RANGE.contains(&self.draws) {
            return Err(Error::param(
                "--draws",
                format!(
                    "must be in [{}, {}] ({}), got {}",
                    DRAWS_RANGE.start(),
                    DRAWS_RANGE.end(),
                    draws_why(),
                    self.draws
                ),
            ));
        }
        if !(0.0..1.0).contains(&self.cull) {
            return Err(Error::param(
                "check.cull",
                format!("must be in [0, 1), got {}", self.cull),
            ));
        }
        Ok(Valid::new(self.clone()))
    }
}
