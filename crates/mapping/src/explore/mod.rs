//! `pradar explore`: the personal radar's design space (issue 47) — array size, pulses,
//! angular step, bandwidth and transmit power against map quality, energy per scan and
//! scan time.
//!
//! Takes a campaign with a `[scene]` (physics sweeps; or a model file, `synth` instead),
//! a grid of configurations ([`ExploreParams`]: N, pulses, step, bandwidth, transmit power),
//! mappers, seeds and an [`EnergyModel`]. For every configuration and seed the campaign is
//! changed to it (elements, pulses, direction step, band and transmit power; the manifest
//! seed is the campaign's plus the seed, so a seed draws a new scene and new noise),
//! simulated (or synthesised), put through the energy stage and every mapper, and each map
//! scored on the three-class reference (the run: [`run`], giving an
//! [`ExploreOutput`]); [`summary`] makes the tables and the verdict from it, and
//! [`crate::report::explore`] the Pareto plot, the heat maps and `index.html`. This module
//! holds the parameters, the result types, the [`energy_model`] and the Pareto front.
//!
//! Choices:
//! * **bandwidth**: the band keeps its centre and its frequency step (so its unambiguous
//!   delay), K = B/Δf + 1 points; the campaign's when not given;
//! * **scores** (three-class reference, [`crate::metrics::ThreeClassMetrics`]): on
//!   the building (inside the perimeter or on a wall, the same cells for every
//!   configuration) F1 within one cell, walls found within one cell, room cells marked
//!   occupied, ψ and wrong cells beside the all-free map's; cells beyond the walls marked
//!   occupied on the whole grid;
//! * **quality** of a configuration = its mean F1 over seeds (spread: min and max);
//! * **Pareto front** ([`pareto_front`]): the configurations no other beats in both energy
//!   per scan (lower) and mean F1 (higher);
//! * **the paper's setting** (400 elements, 1 pulse, 5°, the campaign's band and power) is
//!   always run, added to the grid when absent, and the cheapest configuration within 5 %
//!   of the best mean F1 is compared with it;
//! * **time estimate**: the cheapest job of the grid is run first on one thread and timed,
//!   and the grid's time is that time scaled by each job's work (directions × samples ×
//!   (1 + a share per pulse and per mapper), `Job::work` in the run) over the threads; a
//!   grid above [`ExploreParams::max_minutes`] is then refused with the estimate.

pub mod energy_model;
pub mod run;
pub mod summary;

pub use energy_model::{EnergyModel, EnergyModelValid, ScanCost, ScanShape};
pub use run::{run_grid, ExploreInputs};

use crate::error::{Error, Result};
use crate::metrics::ThreeClassMetrics;
use crate::params::{ParamGuard, Valid};
use crate::{EkfParams, GridParams, Method, OgParams};
use std::path::PathBuf;

/// One configuration of the radar.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Config {
    /// Elements per array N.
    pub elements: usize,
    /// Pulses per direction.
    pub pulses: usize,
    /// Angular step, degrees.
    pub step_deg: f64,
    /// Bandwidth, GHz.
    pub bandwidth_ghz: f64,
    /// Transmit power, dBm.
    pub tx_power_dbm: f64,
}

impl Config {
    /// Folder-safe name, e.g. `n100_p2_s5_b6_t0`.
    pub fn key(&self) -> String {
        format!(
            "n{}_p{}_s{}_b{}_t{}",
            self.elements, self.pulses, self.step_deg, self.bandwidth_ghz, self.tx_power_dbm
        )
    }
    /// Short label, e.g. `N=100 P=2 5° 6 GHz 0 dBm`.
    pub fn label(&self) -> String {
        format!(
            "N={} P={} {}° {} GHz {} dBm",
            self.elements, self.pulses, self.step_deg, self.bandwidth_ghz, self.tx_power_dbm
        )
    }
}

/// Where the data of every configuration come from.
#[derive(Debug, Clone, PartialEq)]
pub enum DataKind {
    /// The physics simulator on the campaign's `[scene]`.
    Sweeps,
    /// `synth` of this model file.
    Model(PathBuf),
}

/// The grid and what is run on it (defaults: the issue's; empty bandwidth and power lists
/// mean the campaign's own).
#[derive(Debug, Clone, PartialEq)]
pub struct ExploreParams {
    /// Elements per array (16, 36, 64, 100, 196, 400).
    pub elements: Vec<usize>,
    /// Pulses per direction (1, 2, 4, 8).
    pub pulses: Vec<usize>,
    /// Angular steps, degrees (2.5, 5, 10).
    pub step_deg: Vec<f64>,
    /// Bandwidths, GHz (the campaign's).
    pub bandwidth_ghz: Vec<f64>,
    /// Transmit powers, dBm (the campaign's).
    pub tx_power_dbm: Vec<f64>,
    /// Mappers (og).
    pub mappers: Vec<Method>,
    /// Seeds (1, 2, 3).
    pub seeds: Vec<u64>,
    /// Refuse a grid whose estimated time is above this, minutes (30).
    pub max_minutes: f64,
    /// Grid of every map.
    pub grid: GridParams,
    /// Occupancy-grid parameters.
    pub og: OgParams,
    /// EKF parameters.
    pub ekf: EkfParams,
}

/// [`ExploreParams`] that passed their check.
pub type ExploreValid = Valid<ExploreParams>;

impl Default for ExploreParams {
    fn default() -> Self {
        ExploreParams {
            elements: vec![16, 36, 64, 100, 196, 400],
            pulses: vec![1, 2, 4, 8],
            step_deg: vec![2.5, 5.0, 10.0],
            bandwidth_ghz: Vec::new(),
            tx_power_dbm: Vec::new(),
            mappers: vec![Method::Og],
            seeds: vec![1, 2, 3],
            max_minutes: 30.0,
            grid: GridParams::default(),
            og: OgParams::default(),
            ekf: EkfParams::default(),
        }
    }
}

fn distinct<T: PartialEq>(v: &[T]) -> bool {
    v.iter().enumerate().all(|(i, x)| !v[..i].contains(x))
}

impl ParamGuard for ExploreParams {
    type Checked = ExploreValid;

    /// Every list non-empty (bandwidth and power may be empty: the campaign's) and without
    /// repeats; N perfect squares; pulses ≥ 1; steps, bandwidths positive and finite; power
    /// finite; `max_minutes` positive; the mappers' parameters. An error names the field
    /// (`elements`, `mappers`, …; the command line names its flag instead).
    fn check(&self) -> Result<ExploreValid> {
        let lists = [
            (
                "elements",
                self.elements.is_empty(),
                distinct(&self.elements),
            ),
            ("pulses", self.pulses.is_empty(), distinct(&self.pulses)),
            (
                "step_deg",
                self.step_deg.is_empty(),
                distinct(&self.step_deg),
            ),
            ("bandwidth_ghz", false, distinct(&self.bandwidth_ghz)),
            ("tx_power_dbm", false, distinct(&self.tx_power_dbm)),
            ("mappers", self.mappers.is_empty(), distinct(&self.mappers)),
            ("seeds", self.seeds.is_empty(), distinct(&self.seeds)),
        ];
        for (name, empty, unique) in lists {
            if empty {
                return Err(Error::param(name, "give at least one value"));
            }
            if !unique {
                return Err(Error::param(name, "values must be distinct"));
            }
        }
        for &n in &self.elements {
            let s = (n as f64).sqrt().round() as usize;
            if n == 0 || s.checked_mul(s) != Some(n) {
                return Err(Error::param(
                    "elements",
                    format!("{n} is not a perfect square (e.g. 16, 36, 64, 100, 196, 400)"),
                ));
            }
        }
        if self.pulses.contains(&0) {
            return Err(Error::param("pulses", "pulses must be >= 1"));
        }
        for (name, v) in [
            ("step_deg", &self.step_deg),
            ("bandwidth_ghz", &self.bandwidth_ghz),
        ] {
            if v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(Error::param(name, "values must be finite and > 0"));
            }
        }
        // the band is drawn inside 57.5–63.5 GHz: more than 6 GHz is no personal radar's
        if self.bandwidth_ghz.iter().any(|x| *x > 6.0) {
            return Err(Error::param(
                "bandwidth_ghz",
                "values must be at most 6 GHz (57.5–63.5 GHz)",
            ));
        }
        if self.tx_power_dbm.iter().any(|x| !x.is_finite()) {
            return Err(Error::param("tx_power_dbm", "values must be finite"));
        }
        if !(self.max_minutes.is_finite() && self.max_minutes > 0.0) {
            return Err(Error::param("max_minutes", "must be > 0"));
        }
        if self.mappers.contains(&Method::OgBoresight) {
            return Err(Error::param("mappers", "og or ekf"));
        }
        self.grid.check()?;
        self.og.check()?;
        self.ekf.check()?;
        Ok(Valid::new(self.clone()))
    }
}

/// The paper's setting: 400 elements, 1 pulse, 5° (with the campaign's band and power).
pub const PAPER_ELEMENTS: usize = 400;
/// The paper's pulses per direction.
pub const PAPER_PULSES: usize = 1;
/// The paper's angular step, degrees.
pub const PAPER_STEP_DEG: f64 = 5.0;

/// Indices of the points on the Pareto front of (cost, quality) pairs — lower cost and
/// higher quality are better: a point is on the front when no other point has a cost ≤ its
/// own and a quality ≥ its own with one of the two strictly better. Identical points are
/// all on the front; a point with a NaN is never. Sorted by cost, then by quality
/// (highest first), then by index.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let ok = |p: &(f64, f64)| !(p.0.is_nan() || p.1.is_nan());
    let mut front: Vec<usize> = (0..points.len())
        .filter(|&i| ok(&points[i]))
        .filter(|&i| {
            let (c, q) = points[i];
            !points
                .iter()
                .filter(|p| ok(p))
                .any(|&(c2, q2)| c2 <= c && q2 >= q && (c2 < c || q2 > q))
        })
        .collect();
    front.sort_by(|&a, &b| {
        (points[a].0.total_cmp(&points[b].0))
            .then(points[b].1.total_cmp(&points[a].1))
            .then(a.cmp(&b))
    });
    front
}

/// The three-class scores of one map (module docs: "scores").
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Scores {
    /// F1 within one cell on the building.
    pub f1_1: f64,
    /// Walls found within one cell on the building.
    pub walls_found_1: f64,
    /// Room cells marked occupied (fraction).
    pub free_marked_occupied: f64,
    /// Cells beyond the walls marked occupied (fraction, whole grid).
    pub beyond_marked_occupied: f64,
    /// ψ on the building.
    pub psi: f64,
    /// Wrong cells on the building.
    pub wrong: usize,
    /// The all-free map's wrong cells on the building.
    pub all_free_wrong: usize,
}

impl Scores {
    /// The figures of a map's building (and whole-grid) three-class metrics.
    pub fn of(
        building: &ThreeClassMetrics,
        all_free: &ThreeClassMetrics,
        whole: &ThreeClassMetrics,
    ) -> Scores {
        Scores {
            f1_1: building.f1_1,
            walls_found_1: building.walls_found_1,
            free_marked_occupied: building.free_marked_occupied,
            beyond_marked_occupied: whole.beyond_marked_occupied,
            psi: building.psi,
            wrong: building.wrong,
            all_free_wrong: all_free.wrong,
        }
    }
}

/// One row of the table: a configuration, mapper and seed.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ExploreRow {
    /// The configuration.
    pub config: Config,
    /// Mapper name.
    pub mapper: &'static str,
    /// Seed.
    pub seed: u64,
    /// Directions of a scan.
    pub directions: usize,
    /// Samples per pulse.
    pub samples: usize,
    /// Energy and time per scan (the energy model).
    pub cost: ScanCost,
    /// Scores of the map.
    pub scores: Scores,
}

/// Measured wall-clock time of one job (not part of the deterministic table).
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    /// The configuration.
    pub config: Config,
    /// Seed.
    pub seed: u64,
    /// Positions (scans) of the campaign.
    pub scans: usize,
    /// Simulation or synth, s.
    pub data_s: f64,
    /// Energy stage, s (0 for model data).
    pub energy_s: f64,
    /// Each mapper, s.
    pub map_s: Vec<(&'static str, f64)>,
}

/// What the grid run ([`run_grid`]) gives.
#[derive(Debug, Clone)]
pub struct ExploreOutput {
    /// The campaign explored.
    pub campaign: PathBuf,
    /// "physics sweeps" or "synth of <model>".
    pub data: String,
    /// The configurations in grid order (the paper's last when it was added).
    pub configs: Vec<Config>,
    /// The paper's setting (400 elements, 1 pulse, 5°, the campaign's band and power).
    pub paper: Config,
    /// Rows in (configuration, mapper, seed) order.
    pub rows: Vec<ExploreRow>,
    /// Measured time per job, in job order.
    pub timings: Vec<Timing>,
    /// The estimate the grid was admitted with, minutes.
    pub estimate_minutes: f64,
    /// The campaign's default step, bandwidth and power (the heat maps' slice).
    pub slice: (f64, f64, f64),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_of_a_hand_made_set() {
        // (energy, F1)
        let pts = [
            (1.0, 0.50),      // 0: cheapest: on the front
            (2.0, 0.40),      // 1: dominated by 0
            (2.0, 0.70),      // 2: on the front
            (3.0, 0.70),      // 3: dominated by 2 (same F1, more energy)
            (4.0, 0.90),      // 4: on the front
            (4.0, 0.90),      // 5: identical to 4: on the front too
            (5.0, 0.85),      // 6: dominated by 4
            (6.0, 0.95),      // 7: the best F1: on the front
            (f64::NAN, 0.99), // 8: never
            (0.5, f64::NAN),  // 9: never
            (7.0, 0.95),      // 10: dominated by 7
        ];
        assert_eq!(pareto_front(&pts), vec![0, 2, 4, 5, 7]);
        assert_eq!(pareto_front(&[]), Vec::<usize>::new());
        assert_eq!(pareto_front(&[(1.0, 0.0)]), vec![0]);
    }

    #[test]
    fn defaults_pass_and_bad_lists_are_named() {
        assert!(ExploreParams::default().check().is_ok());
        let p = ExploreParams {
            elements: vec![16, 20],
            ..Default::default()
        };
        assert!(p.check().unwrap_err().to_string().contains("`elements`"));
        let p = ExploreParams {
            pulses: vec![0],
            ..Default::default()
        };
        assert!(p.check().unwrap_err().to_string().contains("`pulses`"));
        let p = ExploreParams {
            seeds: vec![1, 1],
            ..Default::default()
        };
        assert!(p.check().unwrap_err().to_string().contains("`seeds`"));
        let p = ExploreParams {
            step_deg: vec![-5.0],
            ..Default::default()
        };
        assert!(p.check().unwrap_err().to_string().contains("`step_deg`"));
    }
}
