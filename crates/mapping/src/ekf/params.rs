//! EKF parameters ([`EkfParams`], checked once into [`EkfValid`]) and the implementation
//! switch ([`EkfVariant`]).
//!
//! Defaults (reasons in [`crate::ekf`]): μ0 = 0.01 m, σ0 = 0.1 m, ε = 0.5, kernel
//! floor −30 dB, κ = 3.09, arc explanation γ = −26.5 dB, the scalable filter with 4 × 4
//! tiles, at most 20,000 cells for the dense filter. Derived: the binary threshold
//! η = Φ(κ) on p = P(x > μ0) and the lowest mean kept by the positivity step, 1e-3·μ0.

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// Which implementation of the EKF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum EkfVariant {
    /// Exact dense covariance ([`crate::ekf::DenseEkf`]).
    Dense,
    /// Block-diagonal covariance by tiles ([`crate::ekf::TiledEkf`]).
    Scalable,
}

impl EkfVariant {
    /// Every variant, in the order the command line lists them.
    pub const ALL: [EkfVariant; 2] = [EkfVariant::Dense, EkfVariant::Scalable];

    /// Name (`dense`, `scalable`): the command-line value, the serde name and the
    /// `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            EkfVariant::Dense => "dense",
            EkfVariant::Scalable => "scalable",
        }
    }
    /// Parse `dense` / `scalable`.
    pub fn parse(s: &str) -> Result<EkfVariant> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "ekf", "EKF variant")
    }
}

impl std::fmt::Display for EkfVariant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for EkfVariant {
    type Err = Error;
    /// Parse a [`EkfVariant::name`] (as [`EkfVariant::parse`]).
    fn from_str(s: &str) -> Result<EkfVariant> {
        EkfVariant::parse(s)
    }
}

/// How an energy row enters the filter ([`crate::ekf`] module docs, "Update").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EkfUpdate {
    /// Linearised once at the mean (the EKF; the maps' default).
    FirstOrder,
    /// The Gaussian second-order filter: the quadratic term's mean and variance added
    /// ([`crate::ekf::Linearized::second_order`]; the consistent confidence).
    SecondOrder,
}

impl EkfUpdate {
    /// Every value, in the order the command line lists them.
    pub const ALL: [EkfUpdate; 2] = [EkfUpdate::FirstOrder, EkfUpdate::SecondOrder];

    /// Name (`first-order`, `second-order`): the command-line value, the serde name and the
    /// `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            EkfUpdate::FirstOrder => "first-order",
            EkfUpdate::SecondOrder => "second-order",
        }
    }
}

impl std::fmt::Display for EkfUpdate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for EkfUpdate {
    type Err = Error;
    /// Parse a [`EkfUpdate::name`].
    fn from_str(s: &str) -> Result<EkfUpdate> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "update", "EKF update")
    }
}

/// EKF parameters (see the module docs for the reasons of the defaults).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EkfParams {
    /// Prior mean μ0 of the RRCS, m (0.01; must be > 0).
    pub mu0: f64,
    /// Prior standard deviation σ0, m (0.1).
    pub sigma0: f64,
    /// Relative model-error standard deviation ε of a bin's energy (0.5).
    pub model_error: f64,
    /// Window-kernel truncation, dB below its peak (−30).
    pub kernel_floor_db: f64,
    /// Binary rule: occupied when x̂ − κ·σ̂ > μ0 (κ = 3.09 = Φ⁻¹(1 − 10⁻³)).
    pub kappa: f64,
    /// Arc explanation γ ([`crate::ekf`] module docs): a cell is occupied only if
    /// on some detected echo's range ring its share c̃·x̂² is at least γ times the ring's
    /// largest ([`ARC_EXPLAIN`]); 0 = off.
    pub arc_explain: f64,
    /// Implementation (scalable).
    pub variant: EkfVariant,
    /// Linearisation of the energy rows (first order).
    pub update: EkfUpdate,
    /// Tile side of the scalable filter, cells (4).
    pub tile: usize,
    /// Largest grid the dense filter accepts (20,000 cells = 3.2 GB of covariance).
    pub max_dense_cells: usize,
}

/// EKF parameters that passed [`ParamGuard::check`].
pub type EkfValid = Valid<EkfParams>;

/// The default κ: Φ⁻¹(1 − 10⁻³), the Gaussian posterior's one-sided 10⁻³ quantile — a cell is
/// called occupied at the false-alarm rate per cell of the occupancy grid's detector
/// (`OgParams::pfa` = 10⁻³), so both mappers decide at the same rate and neither looks at
/// the reference.
pub const KAPPA: f64 = 3.090_232_306_167_813;

/// The default arc-explanation γ: 10^(−26.5/10) = 2.24·10⁻³, the two-way peak side-lobe
/// level of a uniform linear array (−13.26 dB one way; the mapper's array model has uniform
/// amplitude). A cell of the ring's strongest RRCS seen at the first side-lobe peak still
/// explains its echo at this γ; a cell whose share is below it on every ring it lies on
/// is not needed by any echo (reasons and measurements: [`crate::ekf`],
/// `docs/mapping.md`).
pub const ARC_EXPLAIN: f64 = 2.238_721_138_568_339e-3;

impl Default for EkfParams {
    fn default() -> Self {
        EkfParams {
            mu0: 0.01,
            sigma0: 0.1,
            model_error: 0.5,
            kernel_floor_db: -30.0,
            kappa: KAPPA,
            arc_explain: ARC_EXPLAIN,
            variant: EkfVariant::Scalable,
            update: EkfUpdate::FirstOrder,
            tile: 4,
            max_dense_cells: 20_000,
        }
    }
}

impl ParamGuard for EkfParams {
    type Checked = EkfValid;

    /// Every field in range: μ0 > 0, σ0 > 0, ε ≥ 0, kernel floor < 0 dB, κ ≥ 0, tile in
    /// 1..=64 cells, `max_dense_cells` > 0, γ in [0, 1].
    fn check(&self) -> Result<EkfValid> {
        if !(self.mu0.is_finite() && self.mu0 > 0.0) {
            return Err(Error::param(
                "mu0",
                "must be > 0 (the Jacobian 2·c·x vanishes at x = 0)",
            ));
        }
        if !(self.sigma0.is_finite() && self.sigma0 > 0.0) {
            return Err(Error::param("sigma0", "must be > 0"));
        }
        if !(self.model_error.is_finite() && self.model_error >= 0.0) {
            return Err(Error::param("model_error", "must be >= 0"));
        }
        if !(self.kernel_floor_db.is_finite() && self.kernel_floor_db < 0.0) {
            return Err(Error::param(
                "kernel_floor_db",
                "must be a negative dB level",
            ));
        }
        if !(self.kappa.is_finite() && self.kappa >= 0.0) {
            return Err(Error::param("kappa", "must be >= 0"));
        }
        if !(0.0..=1.0).contains(&self.arc_explain) {
            return Err(Error::param("arc_explain", "must be in [0, 1]"));
        }
        if self.tile == 0 || self.tile > 64 {
            return Err(Error::param("tile", "must be in 1..=64 cells"));
        }
        if self.max_dense_cells == 0 {
            return Err(Error::param("max_dense_cells", "must be > 0"));
        }
        Ok(Valid::new(*self))
    }
}

impl EkfParams {
    /// Binary threshold η = Φ(κ) on p = P(x > μ0).
    pub fn eta(&self) -> f64 {
        normal_cdf(self.kappa)
    }
    /// Lowest mean kept by the positivity step
    /// ([`crate::ekf::RrcsFilter::project_positive`]): 1e-3·μ0.
    pub fn x_min(&self) -> f64 {
        1e-3 * self.mu0
    }
}

/// Standard normal CDF Φ.
pub fn normal_cdf(z: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(-z / std::f64::consts::SQRT_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_are_checked() {
        assert!(EkfParams::default().check().is_ok());
        for (bad, field) in [
            (
                EkfParams {
                    mu0: 0.0,
                    ..Default::default()
                },
                "mu0",
            ),
            (
                EkfParams {
                    sigma0: -1.0,
                    ..Default::default()
                },
                "sigma0",
            ),
            (
                EkfParams {
                    sigma0: 0.0,
                    ..Default::default()
                },
                "sigma0",
            ),
            (
                EkfParams {
                    tile: 0,
                    ..Default::default()
                },
                "tile",
            ),
            (
                EkfParams {
                    model_error: f64::NAN,
                    ..Default::default()
                },
                "model_error",
            ),
            (
                EkfParams {
                    kernel_floor_db: 3.0,
                    ..Default::default()
                },
                "kernel_floor_db",
            ),
        ] {
            let e = bad.check().unwrap_err().to_string();
            assert!(e.contains(&format!("`{field}`")), "{e}");
        }
        // κ = Φ⁻¹(1 − 10⁻³): η = 0.999
        assert!((EkfParams::default().eta() - 0.999).abs() < 1e-6);
        assert!(EkfVariant::parse("dense").is_ok() && EkfVariant::parse("x").is_err());
    }

    /// Each value reads back from its name, the command-line spelling.
    #[test]
    fn variant_names_round_trip() {
        assert_eq!(
            EkfVariant::ALL.map(|v| v.to_string()),
            ["dense", "scalable"]
        );
        for v in EkfVariant::ALL {
            assert_eq!(v.to_string().parse::<EkfVariant>().unwrap(), v);
        }
        let e = "x".parse::<EkfVariant>().unwrap_err().to_string();
        assert!(e.contains("(dense|scalable)"), "{e}");
    }

    /// Each value reads back from its name, the command-line spelling.
    #[test]
    fn update_names_round_trip() {
        assert_eq!(
            EkfUpdate::ALL.map(|v| v.to_string()),
            ["first-order", "second-order"]
        );
        for v in EkfUpdate::ALL {
            assert_eq!(v.to_string().parse::<EkfUpdate>().unwrap(), v);
        }
        let e = "x".parse::<EkfUpdate>().unwrap_err().to_string();
        assert!(e.contains("(first-order|second-order)"), "{e}");
    }
}
