//! Options of a synth run: [`SynthParams`] (builder style) and its checked form
//! [`SynthValid`], the only type [`synth`](super::synth()) and
//! [`synth_channel`](super::synth_channel()) take.
//!
//! * `seed` — any `u64` (default: the campaign seed);
//! * `truth_dir` — any folder (default: `<out stem>_truth` beside the output);
//! * `cull` — in [0, 1): rays weaker than this fraction of the mean noise-bin energy at
//!   their peak are skipped (default 1e-3, −30 dB);
//! * `n0` — the detector's noise level N0, positive (default: from the campaign's `[noise]`
//!   floor through the window, as the energy stage's N0). `check`, `calibrate` and the
//!   levels' draws set it to the measured table's recorded N0: the model is a model of this
//!   campaign's system, so its draws carry the measured noise.

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use std::path::PathBuf;

/// Options of a synth run (builder style; [`ParamGuard::check`] gives the [`SynthValid`]
/// synth takes).
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// Seed of the model and noise draws (default: the campaign seed).
    pub seed: Option<u64>,
    /// Ground-truth folder (default: `<out stem>_truth` beside the output).
    pub truth_dir: Option<PathBuf>,
    /// Rays weaker than this fraction of the mean noise-bin energy at their peak are skipped
    /// (default 1e-3, −30 dB), in [0, 1).
    pub cull: f64,
    /// The detector's noise level N0 (default: the campaign's `[noise]` floor), positive.
    pub n0: Option<f64>,
}

impl Default for SynthParams {
    fn default() -> Self {
        SynthParams {
            seed: None,
            truth_dir: None,
            cull: 1e-3,
            n0: None,
        }
    }
}

impl SynthParams {
    /// Set the seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = Some(seed);
        self
    }
    /// Set the noise level N0 (instead of the campaign's `[noise]` floor).
    pub fn n0(mut self, n0: f64) -> Self {
        self.n0 = Some(n0);
        self
    }
    /// Set the truth folder.
    pub fn truth_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.truth_dir = Some(dir.into());
        self
    }
}

/// Checked synth options.
pub type SynthValid = Valid<SynthParams>;

impl ParamGuard for SynthParams {
    type Checked = SynthValid;

    /// `cull` in [0, 1), `n0` positive and finite; every seed and folder is valid.
    fn check(&self) -> Result<SynthValid> {
        if let Some(n0) = self.n0 {
            if !(n0.is_finite() && n0 > 0.0) {
                return Err(Error::param(
                    "synth.n0",
                    format!("must be a positive number, got {n0}"),
                ));
            }
        }
        if !(self.cull.is_finite() && self.cull >= 0.0 && self.cull < 1.0) {
            return Err(Error::param(
                "synth.cull",
                format!("must be in [0, 1), got {}", self.cull),
            ));
        }
        Ok(Valid::new(self.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_check() {
        assert!(SynthParams::default().check().is_ok());
        assert_eq!(*SynthValid::default(), SynthParams::default());
        for cull in [f64::NAN, -0.1, 1.0, f64::INFINITY] {
            let p = SynthParams {
                cull,
                ..SynthParams::default()
            };
            let e = p.check().unwrap_err().to_string();
            assert!(e.contains("synth.cull") && e.contains("[0, 1)"), "{e}");
        }
        for n0 in [f64::NAN, 0.0, -1e-13, f64::INFINITY] {
            let e = SynthParams::default()
                .n0(n0)
                .check()
                .unwrap_err()
                .to_string();
            assert!(e.contains("synth.n0"), "{e}");
        }
        assert!(SynthParams::default().n0(1e-13).check().is_ok());
    }
}
