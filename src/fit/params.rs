//! Parameters of the campaign fit: [`FitParams`] (what the CLI's `fit --bootstrap --seed`
//! fill in) and its checked form [`FitValid`], the only type the fit takes.
//!
//! * `bootstrap` — resamples of the position bootstrap (intervals) and of the parametric
//!   bootstrap of the KS p-values (at most 500 of them for KS). It must be at least 1:
//!   every quantity of Table 1 carries an interval and a p-value, and 0 resamples give
//!   neither (`--bootstrap 0` is refused with one line naming the flag and the range).
//! * `seed` — any `u64`; each quantity's resampling stream is keyed by it.

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// Fit parameters (unchecked; [`ParamGuard::check`] gives the [`FitValid`] the fit takes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitParams {
    /// Bootstrap resamples (intervals and KS p-values), at least 1.
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

/// Checked fit parameters.
pub type FitValid = Valid<FitParams>;

impl ParamGuard for FitParams {
    type Checked = FitValid;

    /// `bootstrap` ≥ 1 (0 is refused: "--bootstrap must be at least 1 …"); every seed is
    /// valid.
    fn check(&self) -> Result<FitValid> {
        if self.bootstrap < 1 {
            return Err(Error::param(
                "bootstrap",
                format!(
                    "--bootstrap must be at least 1 (resamples for the intervals and KS p-values), got {}",
                    self.bootstrap
                ),
            ));
        }
        Ok(Valid::new(*self))
    }
}

impl Default for FitValid {
    /// The default parameters (1000 resamples, seed 1), which pass the check.
    fn default() -> Self {
        FitParams::default()
            .check()
            .expect("the default fit parameters are valid")
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
        assert!(e.contains("--bootstrap must be at least 1"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        assert!(FitParams::default().check().is_ok());
        let one = FitParams {
            bootstrap: 1,
            seed: 9,
        };
        assert_eq!(*one.check().unwrap(), one);
        assert_eq!(*FitValid::default(), FitParams::default());
    }
}
