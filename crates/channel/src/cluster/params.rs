//! Clustering parameters ([`ClusterParams`]), the K-selection [`Criterion`] and their check.
//!
//! Takes the values a user or the CLI fills in; gives, through [`ParamGuard::check`], a
//! [`ClusterValid`] that every clustering algorithm takes. Every field is checked once there
//! and an out-of-range value is one [`Error::Param`] naming the field (and the CLI flag
//! where there is one) and the allowed range.

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// Criterion that picks K among 2..K_max.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Criterion {
    /// Largest mean silhouette.
    Silhouette,
    /// Largest Calinski–Harabasz index.
    CalinskiHarabasz,
    /// Gap statistic (Tibshirani, Walther & Hastie 2001) against `gap_refs` uniform
    /// reference sets over the data's bounding box: the smallest K with
    /// Gap(K) ≥ Gap(K+1) − s(K+1); handles K = 1 natively.
    Gap,
    /// Smallest BIC of an exponential-delay × Laplacian-angle mixture (the channel model's
    /// cluster shape); handles K = 1 natively.
    ChannelBic,
    /// Smallest BIC of a diagonal-Gaussian mixture (X-means); handles K = 1 natively.
    GaussBic,
    /// Largest leave-one-out log-likelihood of a Gaussian-delay × Laplacian-angle mixture;
    /// handles K = 1 natively.
    CrossValidated,
    /// `CrossValidated` with the delay spread and the angular scale shared by the clusters
    /// of a position (pooled within-cluster MLEs; the channel model's clusters share λ and
    /// the AoA law), each cluster keeping its own location and weight.
    CrossValidatedShared,
}

impl Criterion {
    /// Every value, in the order the command line lists them.
    pub const ALL: [Criterion; 7] = [
        Criterion::Silhouette,
        Criterion::CalinskiHarabasz,
        Criterion::Gap,
        Criterion::ChannelBic,
        Criterion::GaussBic,
        Criterion::CrossValidated,
        Criterion::CrossValidatedShared,
    ];

    /// Name (`silhouette`, `ch`, `gap`, `channel-bic`, `gauss-bic`, `cv`, `cv-shared`): the
    /// command-line value and the `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            Criterion::Silhouette => "silhouette",
            Criterion::CalinskiHarabasz => "ch",
            Criterion::Gap => "gap",
            Criterion::ChannelBic => "channel-bic",
            Criterion::GaussBic => "gauss-bic",
            Criterion::CrossValidated => "cv",
            Criterion::CrossValidatedShared => "cv-shared",
        }
    }
}

impl std::fmt::Display for Criterion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Criterion {
    type Err = Error;
    /// Parse a [`Criterion::name`].
    fn from_str(s: &str) -> Result<Criterion> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "criterion", "criterion")
    }
}

impl Criterion {
    /// Whether the criterion scores K by a likelihood (and so includes K = 1).
    pub fn is_likelihood(self) -> bool {
        matches!(
            self,
            Criterion::ChannelBic
                | Criterion::GaussBic
                | Criterion::CrossValidated
                | Criterion::CrossValidatedShared
        )
    }
}

/// Largest `k_max` accepted: a position holds a few tens of clusters, and the search over
/// K costs about K^2.3.
pub const MAX_K: usize = 64;

/// Clustering parameters (unchecked; [`ParamGuard::check`] gives the [`ClusterValid`] the
/// algorithms take).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClusterParams {
    /// Largest K tried.
    pub k_max: usize,
    /// Seed of the k-means++ draws.
    pub seed: u64,
    /// K-means restarts per K.
    pub n_runs: usize,
    /// Below this best mean silhouette, K = 1.
    pub min_silhouette: f64,
    /// Criterion.
    pub criterion: Criterion,
    /// Reference data sets of the gap statistic (any value; at least 2 are drawn).
    pub gap_refs: usize,
    /// Rescale the features by the pooled within-cluster standard deviations of each K's
    /// solution and refit (3 rounds): K-means in the metric of a shared-diagonal-covariance
    /// mixture, so a feature that does not separate clusters (e.g. delay when clusters
    /// overlap in delay) does not dominate.
    pub adaptive_scaling: bool,
    /// Delay resolution, ns: floor of the delay scales in the likelihood criteria.
    pub delay_res_ns: f64,
    /// Angle resolution, degrees: floor of the angle scales in the likelihood criteria.
    pub angle_res_deg: f64,
    /// Concentration α of the cross-validated criterion's "new cluster" term (0: none).
    pub new_cluster_weight: f64,
    /// Width (degrees) of the scanned sector, over which the "new cluster" density is
    /// uniform (default 180, the half-plane; `pradar cluster` takes it from the MPC table's
    /// `sector_deg` metadata, which `extract` writes from the campaign's directions).
    pub sector_deg: f64,
}

/// Clustering parameters that passed [`ParamGuard::check`].
pub type ClusterValid = Valid<ClusterParams>;

impl Default for ClusterParams {
    fn default() -> Self {
        ClusterParams {
            k_max: 16,
            seed: 1,
            n_runs: 10,
            min_silhouette: 0.25,
            criterion: Criterion::CrossValidated,
            gap_refs: 10,
            adaptive_scaling: true,
            delay_res_ns: 1.0 / 6.0,
            angle_res_deg: 5.0,
            new_cluster_weight: 1.0,
            sector_deg: 180.0,
        }
    }
}

impl ClusterParams {
    /// Builder: K_max.
    pub fn k_max(mut self, k: usize) -> Self {
        self.k_max = k;
        self
    }
    /// Builder: criterion.
    pub fn criterion(mut self, c: Criterion) -> Self {
        self.criterion = c;
        self
    }
    /// Builder: seed.
    pub fn seed(mut self, s: u64) -> Self {
        self.seed = s;
        self
    }
    /// Builder: width of the scanned sector (degrees).
    pub fn sector_deg(mut self, w: f64) -> Self {
        self.sector_deg = w;
        self
    }
}

impl ParamGuard for ClusterParams {
    type Checked = ClusterValid;

    /// Every field in range, or one error naming the first field that is not.
    fn check(&self) -> Result<ClusterValid> {
        if self.k_max == 0 {
            return Err(Error::param(
                "k_max",
                format!("must be >= 1 (--k-max), got {}", self.k_max),
            ));
        }
        if self.k_max > MAX_K {
            return Err(Error::param(
                "k_max",
                format!(
                    "must be <= {MAX_K} (--k-max), got {} (a position holds a few tens of clusters; the time grows as K^2.3)",
                    self.k_max
                ),
            ));
        }
        if self.n_runs == 0 {
            return Err(Error::param("n_runs", "must be >= 1, got 0"));
        }
        if !(-1.0..=1.0).contains(&self.min_silhouette) {
            return Err(Error::param(
                "min_silhouette",
                format!("must lie in [-1, 1], got {}", self.min_silhouette),
            ));
        }
        if !(self.delay_res_ns > 0.0 && self.delay_res_ns.is_finite()) {
            return Err(Error::param(
                "delay_res_ns",
                format!("must be finite and > 0 ns, got {}", self.delay_res_ns),
            ));
        }
        if !(self.angle_res_deg > 0.0 && self.angle_res_deg.is_finite()) {
            return Err(Error::param(
                "angle_res_deg",
                format!("must be finite and > 0 degrees, got {}", self.angle_res_deg),
            ));
        }
        if !(self.new_cluster_weight >= 0.0 && self.new_cluster_weight.is_finite()) {
            return Err(Error::param(
                "new_cluster_weight",
                format!("must be finite and >= 0, got {}", self.new_cluster_weight),
            ));
        }
        if !(self.sector_deg > 0.0 && self.sector_deg <= 360.0) {
            return Err(Error::param(
                "sector_deg",
                format!("must lie in (0, 360] degrees, got {}", self.sector_deg),
            ));
        }
        Ok(Valid::new(*self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every out-of-range field is one error naming that field (and its range), no panic.
    #[test]
    fn out_of_range_fields_are_one_clear_error() {
        assert!(ClusterParams::default().check().is_ok());
        let d = ClusterParams::default();
        let cases: Vec<(ClusterParams, &str, &str)> = vec![
            (d.k_max(0), "k_max", "--k-max"),
            (ClusterParams { n_runs: 0, ..d }, "n_runs", ">= 1"),
            (
                ClusterParams {
                    min_silhouette: 1.5,
                    ..d
                },
                "min_silhouette",
                "[-1, 1]",
            ),
            (
                ClusterParams {
                    min_silhouette: f64::NAN,
                    ..d
                },
                "min_silhouette",
                "[-1, 1]",
            ),
            (
                ClusterParams {
                    delay_res_ns: 0.0,
                    ..d
                },
                "delay_res_ns",
                "> 0",
            ),
            (
                ClusterParams {
                    delay_res_ns: f64::INFINITY,
                    ..d
                },
                "delay_res_ns",
                "> 0",
            ),
            (
                ClusterParams {
                    angle_res_deg: -1.0,
                    ..d
                },
                "angle_res_deg",
                "> 0",
            ),
            (
                ClusterParams {
                    new_cluster_weight: -0.5,
                    ..d
                },
                "new_cluster_weight",
                ">= 0",
            ),
            (d.sector_deg(0.0), "sector_deg", "(0, 360]"),
            (d.sector_deg(400.0), "sector_deg", "(0, 360]"),
            (d.sector_deg(f64::NAN), "sector_deg", "(0, 360]"),
        ];
        for (p, field, range) in cases {
            let e = p.check().unwrap_err().to_string();
            assert!(e.contains(field) && e.contains(range), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
    }

    /// Each value reads back from its name, the command-line spelling.
    #[test]
    fn criterion_names_round_trip() {
        assert_eq!(
            Criterion::ALL.map(|v| v.to_string()),
            [
                "silhouette",
                "ch",
                "gap",
                "channel-bic",
                "gauss-bic",
                "cv",
                "cv-shared"
            ]
        );
        for v in Criterion::ALL {
            assert_eq!(v.to_string().parse::<Criterion>().unwrap(), v);
        }
        let e = "x".parse::<Criterion>().unwrap_err().to_string();
        assert!(
            e.contains("(silhouette|ch|gap|channel-bic|gauss-bic|cv|cv-shared)"),
            "{e}"
        );
    }
}
