//! Parameters of the campaign fit: [`FitParams`] (what the CLI's `fit --bootstrap --seed`
//! fill in) and its checked form [`FitValid`], the only type the fit takes.
//!
//! * `bootstrap` — resamples of the position bootstrap (intervals) and of the parametric
//!   bootstrap of the KS p-values (at most 500 of them for KS), in
//!   [`MIN_BOOTSTRAP`, `MAX_BOOTSTRAP`]. Every quantity of Table 1 carries a 95 %
//!   percentile interval: with fewer than 40 resamples its 2.5 % tails hold no resample,
//!   the interval is the resamples' range and can exclude the estimate (one resample is
//!   an "interval" of one point). 0 and 1 are therefore refused with one line naming the
//!   flag and the range, not run.
//! * `seed` — any `u64`; each quantity's resampling stream is keyed by it.

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// Fit parameters (unchecked; [`ParamGuard::check`] gives the [`FitValid`] the fit takes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitParams {
    /// Bootstrap resamples (intervals and KS p-values), in [`MIN_BOOTSTRAP`, `MAX_BOOTSTRAP`].
    pub bootstrap: usize,
    /// Seed (any value).
    pub seed: u64,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            bootstrap: 1000,
            seed: 1,
        }
    }
}

/// Fewest bootstrap resamples: one in each 2.5 % tail of a 95 % percentile interval.
pub const MIN_BOOTSTRAP: usize = 40;
/// Most bootstrap resamples (the interval's Monte Carlo error is negligible long before).
pub const MAX_BOOTSTRAP: usize = 100_000;

/// Checked fit parameters.
pub type FitValid = Valid<FitParams>;

impl ParamGuard for FitParams {
    type Checked = FitValid;

    /// `bootstrap` in [`MIN_BOOTSTRAP`, `MAX_BOOTSTRAP`] (else: "--bootstrap must be in
    /// [40, 100000] …"); every seed is valid.
    fn check(&self) -> Result<FitValid> {
        if !(MIN_BOOTSTRAP..=MAX_BOOTSTRAP).contains(&self.bootstrap) {
            return Err(Error::param(
                "bootstrap",
                format!(
                    "--bootstrap must be in [{MIN_BOOTSTRAP}, {MAX_BOOTSTRAP}] (a 95 % percentile interval needs a resample in each 2.5 % tail), got {}",
                    self.bootstrap
                ),
            ));
        }
        Ok(Valid::new(*self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_bootstrap_is_refused_with_one_line() {
        let e = FitParams {
            bootstrap: 0,
            seed: 1,
        }
        .check()
        .unwrap_err()
        .to_string();
        assert!(e.contains("--bootstrap must be in [40, 100000]"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        assert!(FitParams::default().check().is_ok());
        for b in [1, 39, 100_001] {
            let bad = FitParams {
                bootstrap: b,
                seed: 9,
            };
            assert!(bad.check().is_err(), "{b}");
        }
        let least = FitParams {
            bootstrap: 40,
            seed: 9,
        };
        assert_eq!(*least.check().unwrap(), least);
        assert_eq!(*FitValid::default(), FitParams::default());
    }
}
