//! What a mapping experiment measured, as data: the cases ([`Case`], one map each), their
//! scores ([`CaseFigures`]) and one experiment's result ([`ExperimentResult`]: figures,
//! findings, and what its page shows — caption, [`Panel`], curves, [`Figure`]s).
//!
//! The experiments (`pipeline::experiment`) make these; the report
//! ([`crate::report::experiments`]) draws them. Scoring: ψ, F1 and the wrong-cell count of a
//! map on three regions — the whole map, the observable region and the interior (the map's
//! building region: inside the perimeter or on a wall), each from the map's own metrics
//! (`metrics.json`); a wrong-cell count is the metric's rate times the region's cells,
//! rounded.

use crate::export::{Cell, Column, LineChart};
use crate::job::SlamSummary;
use crate::pose_noise::PoseNoise;
use crate::reference::ReferenceMap;
use crate::slam::{OdometryNoise, PosesFrom};
use serde::Serialize;

/// Where a map's data come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum DataSource {
    /// The campaign's sweeps (simulated or measured).
    Sweeps,
    /// `synth` with the model file, this seed.
    Model(u64),
    /// The campaign's `[scene]` simulated at the case's N with the manifest's seed plus
    /// this seed (a new realisation of its clutter and noise, as `explore`'s seeds).
    Physics(u64),
}

/// One map of an experiment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Case {
    /// Data.
    pub source: DataSource,
    /// Array elements.
    pub elements: usize,
    /// Mapper (`og` or `ekf`).
    pub method: &'static str,
    /// OG prior p0.
    pub og_prior: f64,
    /// EKF prior mean μ0, m.
    pub mu0: f64,
    /// Pose noise given to the mapper.
    pub pose_noise: PoseNoise,
    /// Where the mapper's poses come from (the manifest's, or an odometry's: `experiment
    /// slam`); the figures' `slam` says which.
    #[serde(skip)]
    pub poses_from: PosesFrom,
    /// The odometry's noise when the poses come from one.
    #[serde(skip)]
    pub odometry: OdometryNoise,
}

/// Figures of one map (see the module docs for the three regions).
#[derive(Debug, Clone, Serialize)]
pub struct CaseFigures {
    /// Folder under `maps/`.
    pub key: String,
    /// The case.
    pub case: Case,
    /// ψ on the whole map, cells.
    pub psi_whole: f64,
    /// ψ on the observable region, cells.
    pub psi_observable: f64,
    /// Occupied F1 on the whole map.
    pub f1_whole: f64,
    /// Occupied F1 on the observable region.
    pub f1_observable: f64,
    /// Wrong cells on the whole map.
    pub wrong_whole: usize,
    /// Wrong cells on the observable region.
    pub wrong_observable: usize,
    /// Cells of the observable region.
    pub observable_cells: usize,
    /// Occupied cells of the map (whole).
    pub map_occupied: usize,
    /// ψ of the all-free map, whole.
    pub all_free_psi_whole: f64,
    /// ψ of the all-free map, observable region.
    pub all_free_psi_observable: f64,
    /// Wrong cells of the all-free map, whole.
    pub all_free_wrong_whole: usize,
    /// ψ on the interior (the building: inside the perimeter or on a wall).
    pub psi_interior: f64,
    /// Wrong cells on the interior.
    pub wrong_interior: usize,
    /// Occupied F1 on the interior.
    pub f1_interior: f64,
    /// Cells of the interior.
    pub interior_cells: usize,
    /// Wrong cells of the all-free map on the interior.
    pub all_free_wrong_interior: usize,
    /// The map's errors per reference class.
    pub classes: crate::score::ClassFigures,
    /// The map against the three-class reference (structure, the data's truth objects,
    /// free), when the data have a truth (simulated sweeps, model data).
    pub three_class: Option<crate::score::ThreeClassFigures>,
    /// The poses from an odometry (`experiment slam`): its source, σ, seed and the
    /// position RMSEs; absent with the manifest's poses.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slam: Option<SlamSummary>,
}

/// What one experiment measured and wrote.
#[derive(Debug, Clone, Serialize)]
pub struct ExperimentResult {
    /// Experiment name.
    pub name: String,
    /// Every map, with its figures.
    pub cases: Vec<CaseFigures>,
    /// Derived statements (e.g. fig6's N = 16 vs N = 100 check, relative ψ changes).
    pub findings: Vec<(String, String)>,
    /// What the experiment shows, in one paragraph (the report's caption).
    #[serde(skip)]
    pub caption: String,
    /// The maps shown side by side (`NAME.png`, drawn by the report).
    #[serde(skip)]
    pub panel: Panel,
    /// Curves (`NAME_plot.png` when not empty, drawn by the report).
    #[serde(skip)]
    pub charts: Vec<LineChart>,
    /// Other figures the report shows.
    #[serde(skip)]
    pub figures: Vec<Figure>,
}

/// One map of an experiment's panel: its title and its binary map (row-major, row 0 = lowest
/// y, as the map files).
#[derive(Debug, Clone)]
pub struct PanelTile {
    /// Title drawn above the map.
    pub title: String,
    /// Occupied cells.
    pub occupied: Vec<bool>,
}

/// The maps an experiment shows side by side, each to be scored against `reference`.
#[derive(Debug, Clone)]
pub struct Panel {
    /// The reference map the tiles are coloured against.
    pub reference: ReferenceMap,
    /// The maps, in reading order.
    pub tiles: Vec<PanelTile>,
    /// Tiles per row.
    pub columns: usize,
}

/// A figure of a result beside its panel and table.
#[derive(Debug, Clone, PartialEq)]
pub enum Figure {
    /// The EKF mean RRCS images (`maps/<key>/ekf_mean.png`) of these maps.
    EkfMeans(Vec<String>),
    /// The experiment's curve plot (`NAME/NAME_plot.png`), with its alternative text.
    Plot(String),
}

/// The score columns every experiment table shows: ψ, wrong cells and F1 on the whole map,
/// the observable region (with its size) and the interior.
pub fn score_columns() -> Vec<Column> {
    let col = Column::new;
    vec![
        col("ψ whole", "psi_whole"),
        col("wrong whole", "wrong_whole"),
        col("F1 whole", "f1_whole"),
        col("ψ obs.", "psi_observable"),
        col("wrong obs.", "wrong_observable"),
        col("F1 obs.", "f1_observable"),
        col("obs. cells", "observable_cells"),
        col("ψ interior", "psi_interior"),
        col("wrong interior", "wrong_interior"),
        col("F1 interior", "f1_interior"),
    ]
}

impl CaseFigures {
    /// This map's cells under [`score_columns`] (ψ and F1 shown with 3 decimals).
    pub fn score_cells(&self) -> Vec<Cell> {
        let c = self;
        vec![
            Cell::fixed(c.psi_whole, 3),
            Cell::count(c.wrong_whole),
            Cell::fixed(c.f1_whole, 3),
            Cell::fixed(c.psi_observable, 3),
            Cell::count(c.wrong_observable),
            Cell::fixed(c.f1_observable, 3),
            Cell::count(c.observable_cells),
            Cell::fixed(c.psi_interior, 3),
            Cell::count(c.wrong_interior),
            Cell::fixed(c.f1_interior, 3),
        ]
    }
}
