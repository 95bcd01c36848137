//! Scoring a map: the map's and the all-free map's figures on three regions
//! ([`MetricsPair`]), the map's errors per reference class ([`ClassFigures`]), the regions
//! themselves ([`Regions`]), and the metrics table of the report ([`metrics_table`]).
//!
//! Regions (mapper-independent, never from the reference's classes, so every method is
//! scored on the same cells):
//! * building = the cells inside the layout's perimeter or crossed by one of its walls (the
//!   layout's geometry);
//! * observable = the cells in line of sight of some pose within its detection range: inside
//!   the −3 dB main lobe of at least one (pose, direction), within the usable bins, with the
//!   segment from the pose to the cell centre crossing no wall of the layout (a crossing
//!   within half a cell diagonal of the centre, measured along the segment, does not count,
//!   so the cells a wall passes through are in line of sight from the side they face); from
//!   the poses the data were recorded at (fused runs: the first run's layout);
//! * whole map = every cell, `Outside` reference cells counted as free.
//!
//! Per class ([`ClassFigures`], on the whole grid): the fraction of the reference's free
//! cells (inside the perimeter) and of its outside cells (beyond the walls) marked occupied,
//! and the fraction of the reference's occupied cells in the observable region with a map
//! occupied cell within one cell (8-neighbourhood).
//!
//! Three-class figures ([`ThreeClassFigures`], when the run has a truth: [`super::objects`]):
//! the same three regions scored against structure, objects and free space
//! ([`evaluate_three_class`], definitions in [`crate::metrics`]), each beside the
//! all-free map's, with the cells a wall touches only along an edge as an ignore band
//! ([`LayoutRaster::edge_band`](crate::reference::LayoutRaster::edge_band)). A campaign without a truth has `three_class: null`.
//!
//! Detectable figures (`three_class.detectable`, `simulate`'s truth only): the wall cells
//! and objects some pose and direction could have detected ([`crate::detectable`]), the
//! share of them the map found within one cell, and the detectable share of the
//! observable region's wall cells — the ceiling beside the observable and building
//! figures; and the map's false cells by cause (`three_class.false_cells`: main-lobe arc,
//! side lobe, folded, image, noise).

use crate::campaign::layout::Layout;
use crate::detectable::DetectableReturns;
use crate::export::{Cell, Column, Table};
use crate::grid::ObservationModel;
use crate::memo::Memo;
use crate::metrics::{
    evaluate, evaluate_detectable, evaluate_three_class, false_cells_by_cause, structure_cells,
    DetectableMetrics, FalseCells, MapMetrics, ThreeClassMetrics,
};
use crate::objects::Objects;
use crate::og::LogOddsMap;
use crate::reference::{CellClass, LayoutRaster, ReferenceMap};
use rayon::prelude::*;
use serde::Serialize;

/// Metrics of a map and of the all-free map on the observable region, the building and the
/// whole map, with the map's errors per reference class.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MetricsPair {
    /// The map on the observable region (line of sight within the detection range).
    pub observable: MapMetrics,
    /// The all-free map on the observable region.
    pub observable_all_free: MapMetrics,
    /// The map on the building (inside the perimeter or on a wall).
    pub building: MapMetrics,
    /// The all-free map on the building.
    pub building_all_free: MapMetrics,
    /// The map on the whole grid.
    pub whole: MapMetrics,
    /// The all-free map on the whole grid.
    pub whole_all_free: MapMetrics,
    /// Errors per reference class.
    pub classes: ClassFigures,
    /// Figures against the three-class reference (structure, objects, free), when the run
    /// has a truth.
    pub three_class: Option<ThreeClassFigures>,
}

/// A map's and the all-free map's figures against the three-class reference on the three
/// regions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ThreeClassFigures {
    /// Objects in the truth (on the grid).
    pub objects: usize,
    /// The map on the observable region.
    pub observable: ThreeClassMetrics,
    /// The all-free map on the observable region.
    pub observable_all_free: ThreeClassMetrics,
    /// The map on the building.
    pub building: ThreeClassMetrics,
    /// The all-free map on the building.
    pub building_all_free: ThreeClassMetrics,
    /// The map on the whole grid.
    pub whole: ThreeClassMetrics,
    /// The all-free map on the whole grid.
    pub whole_all_free: ThreeClassMetrics,
    /// The map against the detectable reference (`simulate`'s truth only:
    /// [`crate::detectable`]).
    pub detectable: Option<DetectableMetrics>,
    /// The map's false cells by cause on the whole grid (`simulate`'s truth only).
    pub false_cells: Option<FalseCells>,
}

/// A map's errors per reference class (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClassFigures {
    /// Fraction of the reference's free cells (inside the perimeter) marked occupied.
    pub free_marked_occupied: f64,
    /// Reference free cells.
    pub free_cells: usize,
    /// Fraction of the reference's outside cells (beyond the walls) marked occupied.
    pub outside_marked_occupied: f64,
    /// Reference outside cells.
    pub outside_cells: usize,
    /// Fraction of the reference's occupied cells in the observable region found within one
    /// cell.
    pub walls_found_1: f64,
    /// Reference occupied cells in the observable region.
    pub observable_wall_cells: usize,
}

/// The scoring regions of a map job (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Regions {
    /// Line of sight of some pose within its detection range.
    pub observable: Vec<bool>,
    /// Inside the perimeter or on a wall.
    pub building: Vec<bool>,
    /// The truth's objects, for the three-class figures (`None`: layout classes only).
    pub objects: Option<Objects>,
    /// The cells a wall touches only along an edge or at a corner, an ignore band of the
    /// three-class figures ([`LayoutRaster::edge_band`](crate::reference::LayoutRaster::edge_band); empty: none).
    pub edge_band: Vec<bool>,
    /// The cells holding a return some pose and direction could detect (`simulate`'s truth
    /// only, [`crate::detectable`]; `None`: no detectable reference).
    pub detectable: Option<DetectableReturns>,
}

/// Score a log-odds map (binary at p > 0.5) against the reference.
pub fn score(map: &LogOddsMap, reference: &ReferenceMap, regions: &Regions) -> MetricsPair {
    score_binary(&map.binary(), reference, regions)
}

/// Score a binary map (true = occupied) against the reference.
pub fn score_binary(bin: &[bool], reference: &ReferenceMap, regions: &Regions) -> MetricsPair {
    let (rows, cols) = (reference.spec.rows, reference.spec.cols);
    let refo = structure_cells(&reference.cells);
    let free = vec![false; bin.len()];
    let all = vec![true; bin.len()];
    let observable = evaluate(bin, &refo, &regions.observable, rows, cols);
    let marked = |class: CellClass| -> (f64, usize) {
        let (mut n, mut occ) = (0usize, 0usize);
        for (c, &b) in reference.cells.iter().zip(bin) {
            if *c == class {
                n += 1;
                occ += b as usize;
            }
        }
        (if n > 0 { occ as f64 / n as f64 } else { 0.0 }, n)
    };
    let (free_marked_occupied, free_cells) = marked(CellClass::Free);
    let (outside_marked_occupied, outside_cells) = marked(CellClass::Outside);
    let no_band;
    let band = if regions.edge_band.is_empty() {
        no_band = vec![false; bin.len()];
        &no_band
    } else {
        &regions.edge_band
    };
    let three_class = regions.objects.as_ref().map(|o| {
        let e = |m: &[bool], region: &[bool]| {
            evaluate_three_class(m, &reference.cells, band, &o.cells, region, rows, cols)
        };
        ThreeClassFigures {
            objects: o.cells.len(),
            observable: e(bin, &regions.observable),
            observable_all_free: e(&free, &regions.observable),
            building: e(bin, &regions.building),
            building_all_free: e(&free, &regions.building),
            whole: e(bin, &all),
            whole_all_free: e(&free, &all),
            detectable: regions.detectable.as_ref().map(|d| {
                evaluate_detectable(
                    bin,
                    &reference.cells,
                    &d.walls,
                    &d.objects,
                    &o.cells,
                    &regions.observable,
                    rows,
                    cols,
                )
            }),
            false_cells: regions.detectable.as_ref().map(|d| {
                false_cells_by_cause(bin, &reference.cells, band, &o.cells, &d.cause, rows, cols)
            }),
        }
    });
    MetricsPair {
        three_class,
        observable,
        observable_all_free: evaluate(&free, &refo, &regions.observable, rows, cols),
        building: evaluate(bin, &refo, &regions.building, rows, cols),
        building_all_free: evaluate(&free, &refo, &regions.building, rows, cols),
        whole: evaluate(bin, &refo, &all, rows, cols),
        whole_all_free: evaluate(&free, &refo, &all, rows, cols),
        classes: ClassFigures {
            free_marked_occupied,
            free_cells,
            outside_marked_occupied,
            outside_cells,
            walls_found_1: observable.recall_1,
            observable_wall_cells: observable.reference_occupied,
        },
    }
}

/// The building of a layout on the reference's grid: inside the perimeter or crossed by a
/// wall ([`LayoutRaster::rasterize_on`]).
pub fn building_region(layout: &Layout, reference: &ReferenceMap) -> Vec<bool> {
    layout
        .rasterize_on(reference.spec)
        .cells
        .iter()
        .map(|c| *c != CellClass::Outside)
        .collect()
}

/// The observable region of a set of runs (module docs): main-lobe coverage within the
/// usable bins and line of sight through the layout's walls.
pub fn observable_region(runs: &[&ObservationModel], layout: &Layout) -> Vec<bool> {
    let keys: Vec<String> = runs.iter().map(|m| m.memo_key()).collect();
    let key = format!("{keys:?} {layout:?}");
    REGION_MEMO
        .get_or::<std::convert::Infallible>(key, || Ok(observable_region_of(runs, layout)))
        .unwrap_or_else(|e| match e {})
}

/// Observable regions already made in this process ([`crate::memo`]): the
/// experiments score many maps of the same poses.
static REGION_MEMO: Memo<Vec<bool>> = Memo::new();

/// [`observable_region`] without the memo.
fn observable_region_of(runs: &[&ObservationModel], layout: &Layout) -> Vec<bool> {
    let mut region = vec![false; runs.first().map_or(0, |m| m.spec.len())];
    for m in runs {
        let main = m.params.main_weight();
        let tol = m.spec.cell_m * std::f64::consts::FRAC_1_SQRT_2;
        let per_pose: Vec<Vec<u32>> = (0..m.poses.len())
            .into_par_iter()
            .map(|p| {
                let g = m.pose_geometry(p);
                let pose = m.poses[p];
                let at = geo::Coord {
                    x: pose.x_m,
                    y: pose.y_m,
                };
                let mut v = Vec::new();
                for (i, &th) in g.theta.iter().enumerate() {
                    let c = g.cell[i] as usize;
                    if region[c] || !(0..m.directions()).any(|d| m.weight(d, th) >= main) {
                        continue;
                    }
                    let centre = m.spec.center(c / m.spec.cols, c % m.spec.cols);
                    if !layout.occluded(at, centre, tol) {
                        v.push(g.cell[i]);
                    }
                }
                v
            })
            .collect();
        for v in per_pose {
            for c in v {
                region[c as usize] = true;
            }
        }
    }
    region
}

/// The metrics table of the report: one row per map (name, its [`MetricsPair`], the link
/// to its `metrics.json` or `None`): ψ, F1, F1 within one cell and the wrong-cell rate on
/// the observable region, ψ and the wrong-cell rate on the building, the per-class errors,
/// ψ, F1 and the wrong-cell rate on the whole map, and (with a truth) the three-class
/// wrong cells on the building beside the all-free map's, ψ, F1 within one cell and free
/// cells marked occupied on the building, and the objects found; with `simulate`'s truth
/// the detectable wall cells found within one cell and their share of the observable
/// wall cells ([`crate::detectable`]).
pub fn metrics_table(rows: &[(String, MetricsPair, Option<String>)]) -> Table {
    let mut t = Table::new(vec![
        Column::new("map", "map"),
        Column::new("ψ obs.", "psi_observable"),
        Column::new("F1 obs.", "f1_observable"),
        Column::new("F1 (1 cell) obs.", "f1_1_observable"),
        Column::new("wrong cells obs.", "wrong_cell_rate_observable"),
        Column::new("ψ building", "psi_building"),
        Column::new("wrong cells building", "wrong_cell_rate_building"),
        Column::new("free marked occ.", "free_marked_occupied"),
        Column::new("outside marked occ.", "outside_marked_occupied"),
        Column::new("walls found (1 cell)", "walls_found_1"),
        Column::new("ψ whole", "psi_whole"),
        Column::new("F1 whole", "f1_whole"),
        Column::new("F1 (1 cell) whole", "f1_1_whole"),
        Column::new("wrong cells whole", "wrong_cell_rate_whole"),
        Column::new(
            "3-class wrong building (all-free)",
            "three_class_wrong_building",
        ),
        Column::new("3-class ψ building", "three_class_psi_building"),
        Column::new("3-class F1 (1 cell) building", "three_class_f1_1_building"),
        Column::new(
            "3-class free marked occ. building",
            "three_class_free_marked_building",
        ),
        Column::new("objects found", "objects_found"),
        Column::new(
            "detectable walls found (1 cell)",
            "detectable_walls_found_1",
        ),
        Column::new(
            "detectable share of obs. walls",
            "detectable_share_of_observable",
        ),
        Column::new(
            "false cells: arc / side lobe / folded / image / noise",
            "false_cells_by_cause",
        ),
        Column::new("metrics", "metrics"),
    ]);
    for (name, m, link) in rows {
        let (o, w) = (&m.observable, &m.whole);
        t.push(vec![
            Cell::text(name.clone()),
            Cell::fixed(o.psi, 3),
            Cell::fixed(o.f1, 3),
            Cell::fixed(o.f1_1, 3),
            Cell::fixed(o.wrong_cell_rate, 3),
            Cell::fixed(m.building.psi, 3),
            Cell::fixed(m.building.wrong_cell_rate, 4),
            Cell::fixed(m.classes.free_marked_occupied, 3),
            Cell::fixed(m.classes.outside_marked_occupied, 3),
            Cell::fixed(m.classes.walls_found_1, 3),
            Cell::fixed(w.psi, 3),
            Cell::fixed(w.f1, 3),
            Cell::fixed(w.f1_1, 3),
            Cell::fixed(w.wrong_cell_rate, 4),
            match &m.three_class {
                Some(t) => Cell::num(
                    t.building.wrong as f64,
                    format!("{} ({})", t.building.wrong, t.building_all_free.wrong),
                ),
                None => Cell::missing("—"),
            },
            match &m.three_class {
                Some(t) => Cell::fixed(t.building.psi, 3),
                None => Cell::missing("—"),
            },
            match &m.three_class {
                Some(t) => Cell::fixed(t.building.f1_1, 3),
                None => Cell::missing("—"),
            },
            match &m.three_class {
                Some(t) => Cell::fixed(t.building.free_marked_occupied, 3),
                None => Cell::missing("—"),
            },
            match &m.three_class {
                Some(t) => Cell::text(format!("{} of {}", t.whole.objects_found, t.whole.objects)),
                None => Cell::missing("—"),
            },
            match m.three_class.and_then(|t| t.detectable) {
                Some(d) => Cell::fixed(d.walls_found_1, 3),
                None => Cell::missing("—"),
            },
            match m.three_class.and_then(|t| t.detectable) {
                Some(d) => Cell::fixed(d.detectable_share_of_observable, 3),
                None => Cell::missing("—"),
            },
            match m.three_class.and_then(|t| t.false_cells) {
                Some(f) => Cell::num(
                    f.total as f64,
                    format!(
                        "{} / {} / {} / {} / {}",
                        f.main_lobe_arc, f.side_lobe, f.folded, f.image, f.noise
                    ),
                ),
                None => Cell::missing("—"),
            },
            match link {
                Some(href) => Cell::Link {
                    text: "metrics.json".into(),
                    href: href.clone(),
                },
                None => Cell::missing(""),
            },
        ]);
    }
    t
}

impl MetricsPair {
    /// The all-free map's figures as a pair of their own (the map's figures replaced by the
    /// all-free ones).
    pub fn all_free(&self) -> MetricsPair {
        MetricsPair {
            observable: self.observable_all_free,
            observable_all_free: self.observable_all_free,
            building: self.building_all_free,
            building_all_free: self.building_all_free,
            whole: self.whole_all_free,
            whole_all_free: self.whole_all_free,
            classes: ClassFigures {
                free_marked_occupied: 0.0,
                outside_marked_occupied: 0.0,
                walls_found_1: 0.0,
                ..self.classes
            },
            three_class: self.three_class.map(|t| ThreeClassFigures {
                observable: t.observable_all_free,
                building: t.building_all_free,
                whole: t.whole_all_free,
                detectable: t.detectable.map(|d| d.all_free()),
                false_cells: t.false_cells.map(|_| FalseCells::default()),
                ..t
            }),
        }
    }
}
