//! The experiments' parameters ([`ExperimentParams`], the defaults) and their check
//! ([`ParamGuard`] → [`ExperimentValid`]): every experiment and the [`Lab`](super::Lab)
//! take only the checked type.
//!
//! The check covers the experiments' own fields and the mappers' parameters they pass on
//! (grid, OG, EKF), including the OG prior scaled by 1 ± `prior_change`, so that no
//! experiment fails half way through on a parameter.

use crate::error::{Error, Result};
use crate::mapping::{EkfParams, GridParams, OgParams};
use crate::params::{ParamGuard, Valid};

/// Parameters of the experiments (defaults: the issue's; builder setters; checked by
/// [`ParamGuard::check`] into an [`ExperimentValid`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentParams {
    /// Seeds of the model data (and of fig6's physics sweeps) (1, 2, 3).
    pub seeds: Vec<u64>,
    /// Array sizes compared by fig6 (16, 100).
    pub compare_elements: Vec<usize>,
    /// fig6's data per seed: model data (`synth`, the default) or physics sweeps.
    pub fig6_data: Fig6Data,
    /// Array size of prior-sensitivity (16).
    pub sensitivity_elements: usize,
    /// Relative change of the priors (0.4).
    pub prior_change: f64,
    /// Array size of pose-noise (100).
    pub pose_elements: usize,
    /// Position noise levels, m per axis (0, 0.02, 0.05, 0.1).
    pub position_noise_m: Vec<f64>,
    /// Heading noise levels, degrees (0, 1, 2, 5).
    pub heading_noise_deg: Vec<f64>,
    /// Grid parameters of every map.
    pub grid: GridParams,
    /// Base occupancy-grid parameters.
    pub og: OgParams,
    /// Base EKF parameters.
    pub ekf: EkfParams,
}

/// [`ExperimentParams`] that passed their check.
pub type ExperimentValid = Valid<ExperimentParams>;

impl Default for ExperimentParams {
    fn default() -> Self {
        ExperimentParams {
            seeds: vec![1, 2, 3],
            compare_elements: vec![16, 100],
            fig6_data: Fig6Data::Model,
            sensitivity_elements: 16,
            prior_change: 0.4,
            pose_elements: 100,
            position_noise_m: vec![0.0, 0.02, 0.05, 0.10],
            heading_noise_deg: vec![0.0, 1.0, 2.0, 5.0],
            grid: GridParams::default(),
            og: OgParams::default(),
            ekf: EkfParams::default(),
        }
    }
}

/// Where fig6's maps come from at each seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fig6Data {
    /// `synth` of the model file (the default: the corridor's three seeds at two N cost
    /// 12 model draws, about a second each; physics costs a simulation per N and seed).
    Model,
    /// The campaign's `[scene]` simulated at each N and seed (as the paper mapped its
    /// measured sweeps); needs a campaign with a `[scene]`.
    Physics,
}

impl Fig6Data {
    /// Every value, in `--help` order.
    pub const ALL: [Fig6Data; 2] = [Fig6Data::Model, Fig6Data::Physics];

    /// Its name on the command line and the page.
    pub fn name(&self) -> &'static str {
        match self {
            Fig6Data::Model => "model",
            Fig6Data::Physics => "physics",
        }
    }
}

impl std::str::FromStr for Fig6Data {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Fig6Data::ALL
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| Error::param("data", format!("`{s}` is not model or physics")))
    }
}

impl std::fmt::Display for Fig6Data {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl ExperimentParams {
    /// Set fig6's data.
    pub fn fig6_data(mut self, data: Fig6Data) -> Self {
        self.fig6_data = data;
        self
    }

    /// Set the seeds (model data; fig6's physics sweeps).
    pub fn seeds(mut self, seeds: Vec<u64>) -> Self {
        self.seeds = seeds;
        self
    }

    fn check_seeds(&self) -> Result<()> {
        if self.seeds.is_empty() {
            return Err(Error::param("seeds", "give at least one seed"));
        }
        let mut s = self.seeds.clone();
        s.sort_unstable();
        s.dedup();
        if s.len() != self.seeds.len() {
            return Err(Error::param("seeds", "seeds must be distinct"));
        }
        Ok(())
    }

    fn check_elements(&self) -> Result<()> {
        if self.compare_elements.len() < 2 {
            return Err(Error::param("compare_elements", "give two array sizes"));
        }
        let square = |n: usize| {
            let s = (n as f64).sqrt().round() as usize;
            n > 0 && s * s == n
        };
        let sizes = self
            .compare_elements
            .iter()
            .map(|&n| ("compare_elements", n));
        let single = [
            ("sensitivity_elements", self.sensitivity_elements),
            ("pose_elements", self.pose_elements),
        ];
        for (name, n) in sizes.chain(single) {
            if !square(n) {
                return Err(Error::param(
                    name,
                    format!("{n} is not a perfect square (use 16, 100 or 400)"),
                ));
            }
        }
        Ok(())
    }

    fn check_levels(&self) -> Result<()> {
        if !(self.prior_change.is_finite() && self.prior_change > 0.0 && self.prior_change < 1.0) {
            return Err(Error::param("prior_change", "must be in (0, 1)"));
        }
        for (name, v) in [
            ("position_noise_m", &self.position_noise_m),
            ("heading_noise_deg", &self.heading_noise_deg),
        ] {
            if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(Error::param(name, "levels must be finite and >= 0"));
            }
        }
        Ok(())
    }

    fn check_mappers(&self) -> Result<()> {
        self.grid.check()?;
        self.og.check()?;
        self.ekf.check()?;
        for f in [1.0 - self.prior_change, 1.0 + self.prior_change] {
            OgParams {
                prior: self.og.prior * f,
                ..self.og
            }
            .check()?;
        }
        Ok(())
    }
}

impl ParamGuard for ExperimentParams {
    type Checked = ExperimentValid;

    /// Seeds (at least one, distinct), array sizes (perfect squares, two compared), the prior
    /// change in (0, 1), noise levels finite and ≥ 0, and the mappers' parameters (the OG
    /// prior also at 1 ± the change).
    fn check(&self) -> Result<ExperimentValid> {
        self.check_seeds()?;
        self.check_elements()?;
        self.check_levels()?;
        self.check_mappers()?;
        Ok(Valid::new(self.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_pass_and_bad_fields_are_named() {
        assert!(ExperimentParams::default().check().is_ok());
        let e = ExperimentParams::default().seeds(vec![2, 2]).check();
        assert!(e.unwrap_err().to_string().contains("seeds"));
        let p = ExperimentParams {
            prior_change: 1.5,
            ..Default::default()
        };
        assert!(p.check().unwrap_err().to_string().contains("prior_change"));
        let p = ExperimentParams {
            pose_elements: 0,
            ..Default::default()
        };
        assert!(p.check().unwrap_err().to_string().contains("pose_elements"));
    }
}
