//! Scoring a map job: the map's and the all-free map's figures on the observable region
//! and on the whole map ([`MetricsPair`]), the observable region itself, and the metrics
//! table of the report ([`metrics_table`]).
//!
//! Observable region = cells inside the −3 dB main lobe of at least one (pose, direction)
//! of any run, within the usable bins, and not `Outside` in the reference (from the poses
//! the data were recorded at; mapper-independent, so every method is scored on the same
//! cells). Whole map = every cell, `Outside` reference cells counted as free.

use super::LoadedRun;
use crate::campaign::layout::{CellClass, ReferenceMap};
use crate::export::{Cell, Column, Table};
use crate::mapping::grid::ObservationModel;
use crate::mapping::metrics::{evaluate, MapMetrics};
use crate::mapping::og::LogOddsMap;
use serde::Serialize;

/// Metrics of a map and of the all-free map, on the observable region and the whole map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MetricsPair {
    /// The map on the observable region.
    pub observable: MapMetrics,
    /// The all-free map on the observable region.
    pub observable_all_free: MapMetrics,
    /// The map on the whole grid.
    pub whole: MapMetrics,
    /// The all-free map on the whole grid.
    pub whole_all_free: MapMetrics,
}

/// Score a log-odds map (binary at p > 0.5) against the reference.
pub fn score(map: &LogOddsMap, reference: &ReferenceMap, observable: &[bool]) -> MetricsPair {
    score_binary(&map.binary(), reference, observable)
}

/// Score a binary map (true = occupied) against the reference.
pub fn score_binary(bin: &[bool], reference: &ReferenceMap, observable: &[bool]) -> MetricsPair {
    let (rows, cols) = (reference.spec.rows, reference.spec.cols);
    let refo: Vec<bool> = reference
        .cells
        .iter()
        .map(|c| *c == CellClass::Occupied)
        .collect();
    let free = vec![false; bin.len()];
    let all = vec![true; bin.len()];
    MetricsPair {
        observable: evaluate(bin, &refo, observable, rows, cols),
        observable_all_free: evaluate(&free, &refo, observable, rows, cols),
        whole: evaluate(bin, &refo, &all, rows, cols),
        whole_all_free: evaluate(&free, &refo, &all, rows, cols),
    }
}

/// Observable region of a set of runs on a reference (see the module docs).
pub fn observable_region(runs: &[&ObservationModel], reference: &ReferenceMap) -> Vec<bool> {
    let mut region: Vec<bool> = reference
        .cells
        .iter()
        .map(|c| *c != CellClass::Outside)
        .collect();
    let mut cov = vec![false; region.len()];
    for m in runs {
        for (c, v) in cov.iter_mut().zip(m.main_lobe_coverage()) {
            *c |= v;
        }
    }
    for (r, c) in region.iter_mut().zip(cov) {
        *r &= c;
    }
    region
}

/// Observable region of loaded runs, from the poses their data were recorded at.
pub fn runs_region(loaded: &[LoadedRun], reference: &ReferenceMap) -> Vec<bool> {
    let models: Vec<ObservationModel> = loaded
        .iter()
        .map(|l| {
            let mut m = l.model.clone();
            m.poses = l.true_poses.clone();
            m
        })
        .collect();
    let refs: Vec<&ObservationModel> = models.iter().collect();
    observable_region(&refs, reference)
}

/// The metrics table of the report: one row per map (name, its [`MetricsPair`], the link
/// to its `metrics.json` or `None`): ψ, F1, F1 within one cell and the wrong-cell rate on
/// the observable region and on the whole map (3 decimals; the whole map's wrong-cell
/// rate 4).
pub fn metrics_table(rows: &[(String, MetricsPair, Option<String>)]) -> Table {
    let mut t = Table::new(vec![
        Column::new("map", "map"),
        Column::new("ψ obs.", "psi_observable"),
        Column::new("F1 obs.", "f1_observable"),
        Column::new("F1 (1 cell) obs.", "f1_1_observable"),
        Column::new("wrong cells obs.", "wrong_cell_rate_observable"),
        Column::new("ψ whole", "psi_whole"),
        Column::new("F1 whole", "f1_whole"),
        Column::new("F1 (1 cell) whole", "f1_1_whole"),
        Column::new("wrong cells whole", "wrong_cell_rate_whole"),
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
            Cell::fixed(w.psi, 3),
            Cell::fixed(w.f1, 3),
            Cell::fixed(w.f1_1, 3),
            Cell::fixed(w.wrong_cell_rate, 4),
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
            whole: self.whole_all_free,
            whole_all_free: self.whole_all_free,
        }
    }
}
