//! fig6: OG and EKF at N = 16 and N = 100, every seed, on model data (`synth` of the model
//! file, the default; with the campaign's sweeps simulated once at both N beside, when the
//! campaign has a `[scene]`) or on physics sweeps (`--data physics`: the campaign's
//! `[scene]` simulated at each N and seed, the manifest's seed plus the seed, as the paper
//! mapped its measured sweeps).
//!
//! The paper's statement "N = 16 has more wrong cells than N = 100" is checked per mapper
//! and seed, on the interior and on the whole map; the means over seeds are listed beside.
//! The page's description names the data.

use super::lab::{join_u, mean, result, CaseFigures, DataSource, Lab, Mapped, Panel};
use super::{ExperimentResult, Fig6Data};
use crate::error::Result;

type Findings = Vec<(String, String)>;

impl Lab<'_> {
    pub(super) fn fig6(&mut self) -> Result<ExperimentResult> {
        let sizes = self.params.compare_elements.clone();
        let (cases, sweeps_note) = self.fig6_cases(&sizes);
        let done = self.map_all("fig6", &cases)?;
        let panel = self.fig6_panel(&done, &sizes);
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let (small, large) = (sizes[0], sizes[1]);
        let mut findings = Vec::new();
        for interior in [true, false] {
            findings.extend(self.more_wrong_findings(&cases, (small, large), interior));
            if self.params.fig6_data == Fig6Data::Model {
                findings.extend(sweeps_findings(
                    &cases,
                    (small, large),
                    interior,
                    sweeps_note.as_deref(),
                ));
            }
        }
        findings.extend(mean_findings(&cases, &sizes, self.params.fig6_data));
        let first = self.params.seeds[0];
        let data = match self.params.fig6_data {
            Fig6Data::Model => "model data (synth of the model file; `--data physics` maps the campaign's scene simulated per seed)",
            Fig6Data::Physics => "physics sweeps (the campaign's scene simulated at each N with its seed plus the seed: a new realisation of its clutter and noise per seed; the findings count wrong cells against the three-class reference, so the simulator's objects are not wrong cells)",
        };
        let beside = match self.params.fig6_data {
            Fig6Data::Model => " The same comparison on the campaign's sweeps simulated at both N is listed beside it.",
            Fig6Data::Physics => "",
        };
        Ok(result(
            "fig6",
            &format!("OG (side-lobe aware) vs EKF on {data} at N = {small} and N = {large}, seeds {}; the panel shows seed {first} (colours as fig5). Wrong cells and ψ on the interior (the reference's known cells) and on the whole map (the same cells for both N in each).{beside}", join_u(&self.params.seeds)),
            cases,
            findings,
            panel,
            Vec::new(),
            Vec::new(),
        ))
    }

    /// The seeds' data ([`Fig6Data`]: model data or physics sweeps) at every size, seed and
    /// mapper; with model data, then the campaign's sweeps at every size and mapper when
    /// every size could be simulated (else why not, as the note).
    pub(super) fn fig6_cases(&mut self, sizes: &[usize]) -> (Vec<super::Case>, Option<String>) {
        let mut cases = Vec::new();
        for &n in sizes {
            for s in self.seeds() {
                for m in ["og", "ekf"] {
                    cases.push(self.base_case(self.fig6_source(s), n, m));
                }
            }
        }
        if self.params.fig6_data == Fig6Data::Physics {
            return (cases, None);
        }
        let mut sweeps_note = None;
        for &n in sizes {
            if let Some(why) = self.sweeps_failure(n) {
                sweeps_note = Some(why);
            }
        }
        if sweeps_note.is_none() {
            for &n in sizes {
                for m in ["og", "ekf"] {
                    cases.push(self.base_case(DataSource::Sweeps, n, m));
                }
            }
        }
        (cases, sweeps_note)
    }

    /// fig6's data at seed `s` ([`Fig6Data`]).
    fn fig6_source(&self, s: u64) -> DataSource {
        match self.params.fig6_data {
            Fig6Data::Model => DataSource::Model(s),
            Fig6Data::Physics => DataSource::Physics(s),
        }
    }

    /// The panel: per data source (first seed, sweeps) and size, the reference then OG and
    /// EKF, titled with the interior / whole wrong cells.
    fn fig6_panel(&self, done: &[Mapped], sizes: &[usize]) -> Panel {
        let first = self.params.seeds[0];
        let mut tiles = Vec::new();
        for src in [self.fig6_source(first), DataSource::Sweeps] {
            for &n in sizes {
                let row: Vec<&Mapped> = ["og", "ekf"]
                    .iter()
                    .filter_map(|m| {
                        done.iter().find(|d| {
                            d.0.case.elements == n
                                && d.0.case.method == *m
                                && d.0.case.source == src
                        })
                    })
                    .collect();
                if row.is_empty() {
                    continue;
                }
                tiles.push(self.reference_tile());
                for d in row {
                    let what = match src {
                        DataSource::Model(s) => format!("model s{s}"),
                        DataSource::Physics(s) => format!("physics s{s}"),
                        DataSource::Sweeps => "sweeps".into(),
                    };
                    tiles.push(self.tile(
                        format!(
                            "{what}, N = {n}, {}: {} / {} wrong",
                            d.0.case.method.to_uppercase(),
                            wrong_of(&d.0, true),
                            wrong_of(&d.0, false)
                        ),
                        &d.1,
                    ));
                }
            }
        }
        self.panel(tiles, 3)
    }

    /// Per mapper on the seeds' data: in how many seeds N = small has more wrong cells than
    /// N = large on the region.
    fn more_wrong_findings(
        &self,
        cases: &[CaseFigures],
        (small, large): (usize, usize),
        interior: bool,
    ) -> Findings {
        let region = region_name(interior);
        let mut findings = Vec::new();
        for m in ["og", "ekf"] {
            let mut holds = 0;
            let mut pairs = Vec::new();
            for s in self.seeds() {
                let src = self.fig6_source(s);
                let (a, b) = (
                    wrong_cells(cases, src, small, m, interior).unwrap_or(0),
                    wrong_cells(cases, src, large, m, interior).unwrap_or(0),
                );
                holds += (a > b) as usize;
                pairs.push(format!("seed {s}: {a} vs {b}"));
            }
            findings.push((
                format!(
                    "{} data, {}: N = {small} more wrong cells than N = {large} ({region})",
                    self.params.fig6_data.name(),
                    m.to_uppercase()
                ),
                format!(
                    "{holds} of {} seeds ({})",
                    self.params.seeds.len(),
                    pairs.join("; ")
                ),
            ));
        }
        findings
    }
}

fn region_name(interior: bool) -> &'static str {
    if interior {
        "interior"
    } else {
        "whole map"
    }
}

/// Wrong cells of the case with these data, N and mapper on the region, if it was mapped
/// ([`wrong_of`]).
fn wrong_cells(
    cases: &[CaseFigures],
    src: DataSource,
    n: usize,
    m: &str,
    interior: bool,
) -> Option<usize> {
    cases
        .iter()
        .find(|c| c.case.elements == n && c.case.method == m && c.case.source == src)
        .map(|c| wrong_of(c, interior))
}

/// A case's wrong cells on the region: on physics sweeps against the three-class reference
/// (the simulator's objects are not wrong cells; the building for the interior), else
/// against the layout.
fn wrong_of(c: &CaseFigures, interior: bool) -> usize {
    match (c.case.source, c.three_class) {
        (DataSource::Physics(_), Some(t)) if interior => t.building.wrong,
        (DataSource::Physics(_), Some(t)) => t.whole.wrong,
        _ if interior => c.wrong_interior,
        _ => c.wrong_whole,
    }
}

/// Per mapper on the simulated sweeps: whether N = small has more wrong cells than N = large
/// on the region (or why it was not run).
fn sweeps_findings(
    cases: &[CaseFigures],
    (small, large): (usize, usize),
    interior: bool,
    sweeps_note: Option<&str>,
) -> Findings {
    let region = region_name(interior);
    let mut findings = Vec::new();
    for m in ["og", "ekf"] {
        let v = match (
            wrong_cells(cases, DataSource::Sweeps, small, m, interior),
            wrong_cells(cases, DataSource::Sweeps, large, m, interior),
        ) {
            (Some(a), Some(b)) => {
                format!("{} ({a} vs {b})", if a > b { "yes" } else { "no" })
            }
            _ => format!("not run: {}", sweeps_note.unwrap_or("no sweeps")),
        };
        findings.push((
            format!(
                "simulated sweeps, {}: N = {small} more wrong cells than N = {large} ({region})",
                m.to_uppercase()
            ),
            v,
        ));
    }
    findings
}

/// Per size and mapper on the seeds' data: mean wrong cells, ψ and F1 over seeds.
fn mean_findings(cases: &[CaseFigures], sizes: &[usize], data: Fig6Data) -> Findings {
    let mut findings = Vec::new();
    for &n in sizes {
        for m in ["og", "ekf"] {
            let sel: Vec<&CaseFigures> = cases
                .iter()
                .filter(|c| {
                    c.case.elements == n
                        && c.case.method == m
                        && match data {
                            Fig6Data::Model => matches!(c.case.source, DataSource::Model(_)),
                            Fig6Data::Physics => matches!(c.case.source, DataSource::Physics(_)),
                        }
                })
                .collect();
            // the wrong cells on the findings' basis ([`wrong_of`]); ψ and F1 on the layout
            let wrong = |c: &&CaseFigures, interior| wrong_of(c, interior) as f64;
            let w: Vec<f64> = sel.iter().map(|c| wrong(c, true)).collect();
            let p: Vec<f64> = sel.iter().map(|c| c.psi_interior).collect();
            let f: Vec<f64> = sel.iter().map(|c| c.f1_interior).collect();
            let ww: Vec<f64> = sel.iter().map(|c| wrong(c, false)).collect();
            let pw: Vec<f64> = sel.iter().map(|c| c.psi_whole).collect();
            findings.push((
                format!(
                    "{} data, N = {n}, {} (mean over seeds)",
                    data.name(),
                    m.to_uppercase()
                ),
                format!(
                    "interior: wrong cells {:.1}, ψ {:.3}, F1 {:.3}; whole map: wrong cells {:.1}, ψ {:.3}",
                    mean(&w),
                    mean(&p),
                    mean(&f),
                    mean(&ww),
                    mean(&pw)
                ),
            ));
        }
    }
    findings
}
