//! Parameters of the bias correction: [`CorrectionParams`] (what `fit --correction-draws`
//! and the library's callers fill in) and its checked form [`CorrectionValid`].
//!
//! * `draws` — R, the simulated campaigns per evaluation point, in [`MIN_DRAWS`,
//!   `MAX_DRAWS`]. The correction's interval scales the draws' spread by √(1 + 1/R) and
//!   uses Student's t with R − 1 degrees of freedom, so a small R widens it rather than
//!   making it wrong; the figures behind the default are in `docs/correction.md`.
//! * `iterations` — the most steps after the start (two candidates each), in
//!   [0, [`MAX_ITERATIONS`]].
//! * `step` — the finite-difference step of the binding function's slopes, relative (the
//!   log of a positive quantity moves by ln(1 + step); the rate 1/Γ by step times itself,
//!   at least by the rate whose e-fold is the energy table's delay span).
//! * `min_slope` — a quantity whose own slope is below this is not identifiable: the
//!   chain's estimate moves by less than this fraction of the quantity's move, so the
//!   data's sampling error is magnified more than 1/min_slope times. 0.25, a stated choice.
//! * `far_factor` — F, how far the fold check looks: the binding function is also
//!   evaluated with each quantity at 1/F and F times its fitted value (on
//!   [`CorrectionParams::far_draws`] of the common draws), and a secant slope below
//!   `min_slope` on either side flags the quantity as not identifiable (values that far
//!   apart read alike). In [1.5, 10]; 3, a stated choice: the z01 office's d_c read the same
//!   at 5.4 times apart (`docs/correction.md`).
//! * `resamples` — random 80 % subsamples of each position's MPCs for the partition
//!   stability (0: not measured).
//! * `seed` — the draws' seed (default: the campaign's).

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// Bias-correction parameters (unchecked).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectionParams {
    /// Simulated campaigns per evaluation point (R).
    pub draws: usize,
    /// Newton steps after the start (at most).
    pub iterations: usize,
    /// Relative finite-difference step of the slopes.
    pub step: f64,
    /// Slope below which a quantity is not identifiable.
    pub min_slope: f64,
    /// How far the fold check looks (the quantity at 1/F and F times its value).
    pub far_factor: f64,
    /// Subsamples of the partition stability (0: none).
    pub resamples: usize,
    /// Seed of the draws (None: the campaign's).
    pub seed: Option<u64>,
}

/// Fewest draws per evaluation point (a spread needs a few).
pub const MIN_DRAWS: usize = 4;
/// Most draws per evaluation point.
pub const MAX_DRAWS: usize = 1000;
/// Most Newton iterations.
pub const MAX_ITERATIONS: usize = 20;

impl Default for CorrectionParams {
    fn default() -> Self {
        CorrectionParams {
            draws: 8,
            iterations: 3,
            step: 0.25,
            min_slope: 0.25,
            far_factor: 3.0,
            resamples: 5,
            seed: None,
        }
    }
}

impl CorrectionParams {
    /// The smaller run `reproduce` makes (R = 4, one Newton step, 3 resamples), so the
    /// main job stays quick; its intervals are wider for it.
    pub fn quick() -> Self {
        CorrectionParams {
            draws: 4,
            iterations: 1,
            resamples: 3,
            ..Default::default()
        }
    }

    /// Draws at each far point of the fold check: a third of R (common draws, so the
    /// secant's noise is the difference's, not each point's), at least 2.
    pub fn far_draws(&self) -> usize {
        self.draws.div_ceil(3).max(2)
    }
}

/// Checked correction parameters.
pub type CorrectionValid = Valid<CorrectionParams>;

impl ParamGuard for CorrectionParams {
    type Checked = CorrectionValid;

    fn check(&self) -> Result<CorrectionValid> {
        if !(MIN_DRAWS..=MAX_DRAWS).contains(&self.draws) {
            return Err(Error::param(
                "correction_draws",
                format!(
                    "--correction-draws must be in [{MIN_DRAWS}, {MAX_DRAWS}], got {}",
                    self.draws
                ),
            ));
        }
        if self.iterations > MAX_ITERATIONS {
            return Err(Error::param(
                "iterations",
                format!("must be at most {MAX_ITERATIONS}, got {}", self.iterations),
            ));
        }
        if !(self.step.is_finite() && self.step > 0.0 && self.step <= 1.0) {
            return Err(Error::param(
                "step",
                format!("must be in (0, 1], got {}", self.step),
            ));
        }
        if !(self.min_slope.is_finite() && self.min_slope > 0.0 && self.min_slope < 1.0) {
            return Err(Error::param(
                "min_slope",
                format!("must be in (0, 1), got {}", self.min_slope),
            ));
        }
        if !(self.far_factor.is_finite() && (1.5..=10.0).contains(&self.far_factor)) {
            return Err(Error::param(
                "far_factor",
                format!("must be in [1.5, 10], got {}", self.far_factor),
            ));
        }
        Ok(Valid::new(*self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_parameters_are_refused_with_their_field() {
        assert!(CorrectionParams::default().check().is_ok());
        assert!(CorrectionParams::quick().check().is_ok());
        let bad = |p: CorrectionParams| p.check().unwrap_err().to_string();
        let d = CorrectionParams::default();
        assert!(bad(CorrectionParams { draws: 3, ..d }).contains("--correction-draws"));
        assert!(bad(CorrectionParams {
            iterations: 21,
            ..d
        })
        .contains("iterations"));
        assert!(bad(CorrectionParams { step: 0.0, ..d }).contains("step"));
        assert!(bad(CorrectionParams {
            min_slope: 1.0,
            ..d
        })
        .contains("min_slope"));
        assert!(bad(CorrectionParams {
            far_factor: 1.0,
            ..d
        })
        .contains("far_factor"));
        assert_eq!(CorrectionParams::default().far_draws(), 3);
        assert_eq!(CorrectionParams::quick().far_draws(), 2);
    }
}
