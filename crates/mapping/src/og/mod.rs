//! Occupancy grids (DESIGN §2 "Mapping"): log-odds maps from energy matrices, with the
//! side-lobe-aware inverse sensor model (`og`) and the classic boresight-only baseline
//! (`og-boresight`).
//!
//! Takes an [`ObservationModel`](crate::grid::ObservationModel), the run's [`EnergyMatrix`](crate::energy::EnergyMatrix) and [`OgParams`]; gives a
//! [`LogOddsMap`] (log-odds per cell, the cells that got evidence) and [`OgStats`].
//!
//! Equations and choices:
//! * log-odds l = ln(p/(1−p)), prior l0 = ln(p0/(1−p0)) (p0 = 0.5 by default), increments
//!   l_occ = ln(p_occ/(1−p_occ)), l_free = ln(p_free/(1−p_free)); a run's log-odds are
//!   clamped to ±`clamp` after every increment;
//! * detector per (pose, direction, bin): energy E_k > η_E, η_E the (1 − P_fa) quantile of
//!   the noise-only bin energy, modelled as Gamma(shape TW·N_p, mean N0·TW) (mean N0·TW,
//!   variance N0²·TW/N_p, the energy detector's statistics with the stored mean over N_p
//!   pulses); bins before `min_bin` (coupling gate plus the window kernel's half-width) are
//!   not used; a detection must also be a local maximum of the profile not explained by the
//!   window kernel's range side lobes of a stronger bin ([`Detector`]), so one echo gives
//!   one detected bin;
//! * `og` (side-lobe aware): what the scan can see comes from
//!   [`crate::grid::visibility`]: per direction its occluder (the strongest
//!   detection not explained by a side lobe of another direction, or an earlier one that
//!   lies on a surface of the current map) and per cell its depth δ behind the pose's
//!   visibility polygon. Then: the cells with w ≥ `free_db` (−10 dB) of every bin before
//!   the occluder and in front of the polygon (δ < −g) get Δl_i = l_free·s_{k,i}·w_i (a
//!   cell wholly in front of it on boresight gets l_free once; weaker illumination, weaker
//!   free evidence); every detection up to g beyond the occluder credits the visible cells
//!   of its range ring (δ ≤ `credit_depth_m`, 0.05 m by default; δ ≤ g with `guard`) (main
//!   and side lobes down to −40 dB, [`crate::grid::Beam`]) with Δl_i = l_occ·r_i,
//!   r_i = w_i·s_{k,i}·p_i·a_i / Σ_j w_j·s_{k,j}·p_j·a_j (two-way weight × the cell's share
//!   of the bin × current belief × affinity with the echo: one cause per detection shared by
//!   responsibility, not a blur by the pattern). With `credit = echo` (an option) a_i is
//!   the cell's affinity with the echoes [`angular`] resolves at that bin and fitted from
//!   this direction (Gaussian in bearing, the amplitude-comparison spread), and a detection
//!   that fitted none is withheld: an echo seen in a lobe's skirt or side lobe is credited
//!   once, at its bearing, by the direction that looks at it, instead of marking the arc
//!   each direction points at (the largest causes of false cells, `docs/mapping.md`);
//!   `ring` (the default: fewer wrong cells at N = 16 on the built-in scenes, more walls
//!   found on most scenes measured) sets a_i = 1. Detections before the occluder (weaker, or explained by a side lobe:
//!   leakage of an echo another direction credits, or a surface the main lobe just cleared)
//!   and detections more than g beyond it (shadowed: multipath or echoes from behind the
//!   surface) are withheld, counted in [`OgStats::withheld`]; bins after the occluder
//!   without a detection give no evidence. Two rules bound what a scan sees (figures in
//!   `docs/mapping.md`): `bound_silent = nearer` (a direction without an occluder
//!   bounds the visibility polygon at the nearer of its first detection and the range
//!   interpolated from its neighbours' occluders, instead of lying at the maximum range:
//!   indoors every bearing ends at a surface, and a beam that detects none was most likely
//!   looking at a smooth wall at oblique incidence, whose specular echo goes elsewhere, so
//!   its free evidence must not run through that wall; `off` and `leak`, at its first
//!   detection, are the alternatives; [`crate::grid::SilentBound`]) and
//!   `credit_depth_m = 0.05` (a ring's occupancy credit only to the cells whose centre lies
//!   at most 0.05 m, half a cell of the default 0.1 m grid, behind the polygon: a cell
//!   whose centre lies further beyond the surface does not hold it, and without the limit
//!   the guard's two bins leave a rim of credited cells beyond every wall the polygon now
//!   reaches). Together they find the walls the silent beams cleared without that rim;
//!   `off` and no depth limit are the alternatives, measured in `docs/mapping.md`. The map
//!   the occluders are confirmed against is the belief the responsibilities use (the
//!   scan's snapshot), a cell being a surface when p > max(0.5, p0);
//! * `og-boresight` (baseline, the classic laser-like model): only the cells crossed by the
//!   boresight ray; a cell gets l_occ if any bin the ray spends in it is detected, l_free if
//!   the ray leaves it before the first detected bin;
//! * order and determinism: poses are processed in order; the beliefs p_i used by the
//!   responsibilities are those at the start of the pose's scan (a scan is one observation),
//!   the directions' increments are computed in parallel from that snapshot and added in
//!   direction order, so maps are bit-identical for any number of threads;
//! * binary map: occupied when p > η = 0.5 (more likely occupied than free), a rule that
//!   never looks at the reference; cells without evidence stay at the prior and count as
//!   free in binary maps;
//! * fusion ([`fuse`]): each run is mapped on its own from the prior, and the fused log-odds
//!   are l0 + Σ_runs (l_run − l0), the sum of the runs' evidence (not clamped).

//!
//! Layout: [`params`] ([`OgParams`] → [`OgValid`]), [`detector`] (threshold and
//! [`Detector`]), [`angular`] (echo bearings across a scan's directions), [`scan`] (the
//! inverse sensor models and [`og_map`]); this file holds the
//! method, the map and the fusion.
//!
//! ```
//! use pradar_mapping::og::{fuse, LogOddsMap};
//! let mut a = LogOddsMap::prior(1, 2, 0.0);
//! a.logodds = vec![1.0, -0.5];
//! let f = fuse(&[a.clone(), a]).unwrap();
//! assert_eq!(f.logodds, vec![2.0, -1.0]);
//! assert_eq!(f.binary(), vec![true, false]);
//! ```

pub mod angular;
pub mod detector;
pub mod params;
pub mod scan;

pub use detector::{detection_threshold, Detector};
pub use params::{sigmoid, OgCredit, OgParams, OgValid};
pub use scan::{og_map, og_map_stats};

use crate::error::{Error, Result};

/// Inverse sensor model (`og` by default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Side-lobe-aware occupancy grid (responsibilities over the range ring).
    #[default]
    Og,
    /// Boresight-only baseline.
    OgBoresight,
    /// EKF over the RRCS per cell ([`crate::ekf`]; not an inverse sensor model:
    /// [`og_map`] refuses it, [`crate::job::run_map`] dispatches it).
    Ekf,
}

impl Method {
    /// Every mapper, in the order the command line lists them.
    pub const ALL: [Method; 3] = [Method::Og, Method::OgBoresight, Method::Ekf];

    /// Command-line / file name (and the `Display`).
    pub fn name(&self) -> &'static str {
        match self {
            Method::Og => "og",
            Method::OgBoresight => "og-boresight",
            Method::Ekf => "ekf",
        }
    }
    /// Parse a name (`og`, `og-boresight`, `ekf`).
    pub fn parse(s: &str) -> Result<Method> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "method", "method")
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = Error;
    /// Parse a [`Method::name`] (as [`Method::parse`]).
    fn from_str(s: &str) -> Result<Method> {
        Method::parse(s)
    }
}

/// A log-odds occupancy map.
#[derive(Debug, Clone, PartialEq)]
pub struct LogOddsMap {
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Prior log-odds l0.
    pub l0: f64,
    /// Log-odds per cell (row-major, row 0 = lowest y).
    pub logodds: Vec<f64>,
    /// Cells that received any evidence.
    pub observed: Vec<bool>,
}

impl LogOddsMap {
    /// A map at the prior.
    pub fn prior(rows: usize, cols: usize, l0: f64) -> LogOddsMap {
        LogOddsMap {
            rows,
            cols,
            l0,
            logodds: vec![l0; rows * cols],
            observed: vec![false; rows * cols],
        }
    }
    /// Occupancy probabilities.
    pub fn probs(&self) -> Vec<f64> {
        self.logodds.iter().map(|&l| sigmoid(l)).collect()
    }
    /// Binary map: occupied when p > 0.5 (l > 0).
    pub fn binary(&self) -> Vec<bool> {
        self.logodds.iter().map(|&l| l > 0.0).collect()
    }
}

/// Work done by a mapper.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct OgStats {
    /// (pose, direction) scans processed.
    pub scans: u64,
    /// Detected bins.
    pub detections: u64,
    /// Detections withheld (`og` only): before the occluder of their beam, or more than the
    /// guard beyond it.
    pub withheld: u64,
    /// Cell updates (log-odds increments applied).
    pub cell_updates: u64,
    /// (cell, bin) entries evaluated by the inverse sensor model (beam entries for `og`,
    /// ray cells for `og-boresight`).
    pub entries: u64,
    /// Wall time, s.
    pub seconds: f64,
}

/// Fuse runs mapped on the same grid: l = l0 + Σ_runs (l_run − l0) (runs in order).
pub fn fuse(runs: &[LogOddsMap]) -> Result<LogOddsMap> {
    let first = runs
        .first()
        .ok_or_else(|| Error::param("runs", "nothing to fuse"))?;
    let mut out = LogOddsMap::prior(first.rows, first.cols, first.l0);
    for r in runs {
        if r.rows != first.rows || r.cols != first.cols || r.l0 != first.l0 {
            return Err(Error::param(
                "runs",
                "runs must share the grid and the prior to be fused",
            ));
        }
    }
    for (i, l) in out.logodds.iter_mut().enumerate() {
        let mut acc = first.l0;
        for r in runs {
            acc += r.logodds[i] - r.l0;
        }
        *l = acc;
        out.observed[i] = runs.iter().any(|r| r.observed[i]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamGuard;

    #[test]
    fn method_names_round_trip() {
        assert_eq!(
            Method::ALL.map(|m| m.to_string()),
            ["og", "og-boresight", "ekf"]
        );
        for m in Method::ALL {
            assert_eq!(Method::parse(m.name()).unwrap(), m);
            assert_eq!(m.to_string().parse::<Method>().unwrap(), m);
        }
        let e = Method::parse("ekf2").unwrap_err().to_string();
        assert!(
            e.contains("unknown method `ekf2` (og|og-boresight|ekf)"),
            "{e}"
        );
    }

    #[test]
    fn params_check() {
        assert!(OgParams::default().check().is_ok());
        let bad = OgParams {
            prior: 1.0,
            ..Default::default()
        };
        assert!(bad.check().unwrap_err().to_string().contains("prior"));
        for (bad, field) in [
            (
                OgParams {
                    prior: 0.0,
                    ..Default::default()
                },
                "prior",
            ),
            (
                OgParams {
                    prior: -0.1,
                    ..Default::default()
                },
                "prior",
            ),
            (
                OgParams {
                    pfa: 0.0,
                    ..Default::default()
                },
                "pfa",
            ),
            (
                OgParams {
                    pfa: 1.0,
                    ..Default::default()
                },
                "pfa",
            ),
            (
                OgParams {
                    pfa: f64::NAN,
                    ..Default::default()
                },
                "pfa",
            ),
            (
                OgParams {
                    p_occ: 0.4,
                    ..Default::default()
                },
                "p_occ",
            ),
            (
                OgParams {
                    credit_depth_m: Some(-0.01),
                    ..Default::default()
                },
                "credit_depth_m",
            ),
            (
                OgParams {
                    credit_depth_m: Some(f64::INFINITY),
                    ..Default::default()
                },
                "credit_depth_m",
            ),
        ] {
            let e = bad.check().unwrap_err().to_string();
            assert!(
                e.contains(&format!("`{field}`")) && e.contains("must be"),
                "{e}"
            );
            assert_eq!(e.lines().count(), 1);
        }
    }
}
