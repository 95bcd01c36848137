//! Options of a calibration run: [`CalibrateParams`] (plain data) and its checked form
//! [`CalibrateValid`], the only type [`calibrate`](super::calibrate()) takes.
//!
//! * `simulations` — the simulation budget (default 3000), ≥ `population`;
//! * `population` — N, simulations of the first (prior) generation and of every later
//!   generation (default 400), in [20, [`MAX_POPULATION`] = 10 000] (the first generation
//!   alone is N simulations);
//! * the budget is at most [`MAX_SIMULATIONS`] = 100 000 (about an hour at the corridor's
//!   30 simulations/s on 2 cores): a larger one would run for many hours;
//! * `alpha` — the share of the merged population kept at each generation (default 0.5),
//!   in (0, 1); N_α = ⌊αN⌋ ≥ 10 particles carry the posterior;
//! * `min_acceptance` — stop when fewer than this share of a generation's proposals fall
//!   below the previous tolerance (default 0.05), in (0, 1);
//! * `seed` — any `u64` (default: the campaign seed, hashed with its own key, so the
//!   simulations never share a stream with a `synth` run of the same seed);
//! * `cull` — as `synth`'s (default 1e-3), in [0, 1);
//! * `adjust` — report the regression-adjusted particles (default) or the raw ones
//!   (`--distance summaries` only: the MMD has no summaries to regress on);
//! * `distance` — [`Distance::SummariesQuantiles`] (default), [`Distance::Summaries`]
//!   or [`Distance::Mmd`];
//! * `ridge` — the projection's ridge penalty, [`Ridge::Cv`] (default: the fixed
//!   penalty, [`Ridge::Fixed`], gives 95 % intervals that cover d_c and the rays per
//!   cluster in only 16 of 20 environments, `docs/calibrate.md`) or [`Ridge::CvDrop`]
//!   (no effect with the MMD).

use super::abc::Ridge;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// The ABC distance between the data and a simulation (`--distance`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Distance {
    /// Semi-automatic summaries: 42 pooled statistics of the matrix regressed onto the
    /// parameters ([`summaries`](super::summaries)).
    Summaries,
    /// The semi-automatic summaries with 45 more raw statistics: the quantiles 10, 25,
    /// 50, 75, 90 % of the predictive check's per-profile and per-position statistics
    /// ([`quantile_summaries`](super::summaries::quantile_summaries)).
    SummariesQuantiles,
    /// The MMD between the per-profile and per-position statistics' distributions
    /// ([`mmd`](super::mmd)).
    Mmd,
}

impl Distance {
    /// Every value, in the order the command line lists them.
    pub const ALL: [Distance; 3] = [
        Distance::Summaries,
        Distance::SummariesQuantiles,
        Distance::Mmd,
    ];

    /// Name (`summaries`, `summaries-quantiles`, `mmd`): the command-line value and the
    /// `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            Distance::Summaries => "summaries",
            Distance::SummariesQuantiles => "summaries-quantiles",
            Distance::Mmd => "mmd",
        }
    }
}

impl std::fmt::Display for Distance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Distance {
    type Err = Error;
    /// Parse a [`Distance::name`].
    fn from_str(s: &str) -> Result<Distance> {
        crate::params::parse_name(
            s,
            &Self::ALL,
            Self::name,
            "calibrate.distance",
            "ABC distance",
        )
    }
}

/// The largest population N (the first generation alone is N simulations, and the kernel
/// weights cost N·N_α per generation).
pub const MAX_POPULATION: usize = 10_000;

/// The smallest population N (and simulation budget) the check accepts.
pub const MIN_POPULATION: usize = 20;

/// The largest simulation budget (about an hour at the corridor's 30 simulations/s).
pub const MAX_SIMULATIONS: usize = 100_000;

/// Options of a calibration run (builder style; [`ParamGuard::check`] gives the
/// [`CalibrateValid`] calibrate takes).
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrateParams {
    /// Simulation budget.
    pub simulations: usize,
    /// Population size N (simulations per generation).
    pub population: usize,
    /// Share of the merged population kept at each generation.
    pub alpha: f64,
    /// Stop when a generation's acceptance rate falls below this.
    pub min_acceptance: f64,
    /// Seed (default: the campaign's).
    pub seed: Option<u64>,
    /// The simulator's ray cull (as `synth`).
    pub cull: f64,
    /// Report the regression-adjusted particles (default true) instead of the raw ones.
    pub adjust: bool,
    /// The distance.
    pub distance: Distance,
    /// The projection's ridge penalty.
    pub ridge: Ridge,
}

impl Default for CalibrateParams {
    fn default() -> Self {
        CalibrateParams {
            simulations: 3000,
            population: 400,
            alpha: 0.5,
            min_acceptance: 0.05,
            seed: None,
            cull: 1e-3,
            adjust: true,
            distance: Distance::SummariesQuantiles,
            ridge: Ridge::Cv,
        }
    }
}

impl CalibrateParams {
    /// Set the seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = Some(seed);
        self
    }
    /// Set the simulation budget.
    pub fn simulations(mut self, n: usize) -> Self {
        self.simulations = n;
        self
    }
    /// Set the distance.
    pub fn distance(mut self, d: Distance) -> Self {
        self.distance = d;
        self
    }
    /// Set the population size.
    pub fn population(mut self, n: usize) -> Self {
        self.population = n;
        self
    }
    /// N_α, the particles kept per generation.
    pub fn kept(&self) -> usize {
        (self.alpha * self.population as f64).floor() as usize
    }
}

/// Checked calibration options.
pub type CalibrateValid = Valid<CalibrateParams>;

impl ParamGuard for CalibrateParams {
    type Checked = CalibrateValid;

    /// Every field in its range (module docs); the error names the field.
    fn check(&self) -> Result<CalibrateValid> {
        if !(MIN_POPULATION..=MAX_POPULATION).contains(&self.population) {
            return Err(Error::param(
                "calibrate.population",
                format!(
                    "must be in [{MIN_POPULATION}, {MAX_POPULATION}], got {}",
                    self.population
                ),
            ));
        }
        if self.simulations < self.population || self.simulations > MAX_SIMULATIONS {
            return Err(Error::param(
                "calibrate.simulations",
                format!(
                    "must be in [population = {}, {MAX_SIMULATIONS}], got {}",
                    self.population, self.simulations
                ),
            ));
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return Err(Error::param(
                "calibrate.alpha",
                format!("must be in (0, 1), got {}", self.alpha),
            ));
        }
        if self.kept() < 10 {
            return Err(Error::param(
                "calibrate.alpha",
                format!(
                    "keeps {} particles of {} (at least 10 needed)",
                    self.kept(),
                    self.population
                ),
            ));
        }
        if !(self.min_acceptance > 0.0 && self.min_acceptance < 1.0) {
            return Err(Error::param(
                "calibrate.min_acceptance",
                format!("must be in (0, 1), got {}", self.min_acceptance),
            ));
        }
        if !(self.cull.is_finite() && self.cull >= 0.0 && self.cull < 1.0) {
            return Err(Error::param(
                "calibrate.cull",
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
        assert!(CalibrateParams::default().check().is_ok());
        let bad = [
            CalibrateParams::default().population(5),
            CalibrateParams::default().simulations(10),
            CalibrateParams {
                alpha: 1.0,
                ..Default::default()
            },
            CalibrateParams {
                alpha: 0.01,
                ..Default::default()
            },
            CalibrateParams {
                min_acceptance: f64::NAN,
                ..Default::default()
            },
            CalibrateParams {
                cull: -1.0,
                ..Default::default()
            },
        ];
        for p in bad {
            let e = p.check().unwrap_err().to_string();
            assert!(e.contains("calibrate."), "{e}");
        }
    }

    /// Each value reads back from its name, the command-line spelling.
    #[test]
    fn distance_names_round_trip() {
        assert_eq!(
            Distance::ALL.map(|v| v.to_string()),
            ["summaries", "summaries-quantiles", "mmd"]
        );
        for v in Distance::ALL {
            assert_eq!(v.to_string().parse::<Distance>().unwrap(), v);
        }
        let e = "x".parse::<Distance>().unwrap_err().to_string();
        assert!(e.contains("(summaries|summaries-quantiles|mmd)"), "{e}");
    }

    /// Each value reads back from its name, the command-line spelling.
    #[test]
    fn ridge_names_round_trip() {
        assert_eq!(
            Ridge::ALL.map(|v| v.to_string()),
            ["fixed", "cv", "cv-drop"]
        );
        for v in Ridge::ALL {
            assert_eq!(v.to_string().parse::<Ridge>().unwrap(), v);
        }
        let e = "x".parse::<Ridge>().unwrap_err().to_string();
        assert!(e.contains("(fixed|cv|cv-drop)"), "{e}");
    }
}
