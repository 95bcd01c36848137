//! What the explore run means, as data: per configuration and mapper the spread over seeds
//! ([`Summary`]), the Pareto front, the cheapest configuration within 5 % of the best F1
//! against the paper's setting ([`Verdict`]), and the tables (`explore.csv|.md`: one row
//! per configuration, mapper and seed; `summary.csv|.md`: one per configuration and
//! mapper), numbers kept as numbers. The plots and the page are the report's
//! ([`crate::report::explore`]).

use super::{pareto_front, Config, ExploreOutput, ExploreRow};
use crate::export::{Cell, Column, Table};

/// Mean, min and max over seeds.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
}

impl Spread {
    /// Of `v` (NaN for none).
    pub fn of(v: &[f64]) -> Spread {
        if v.is_empty() {
            return Spread {
                mean: f64::NAN,
                min: f64::NAN,
                max: f64::NAN,
            };
        }
        Spread {
            mean: v.iter().sum::<f64>() / v.len() as f64,
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// One configuration and mapper over its seeds.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// The configuration.
    pub config: Config,
    /// Mapper.
    pub mapper: &'static str,
    /// Energy per scan, J.
    pub energy_j: f64,
    /// Scan time, s.
    pub scan_time_s: f64,
    /// Processing share of the energy.
    pub processing_share: f64,
    /// F1 within one cell.
    pub f1: Spread,
    /// Walls found within one cell.
    pub walls_found: Spread,
    /// Room cells marked occupied.
    pub free_marked_occupied: Spread,
    /// Cells beyond the walls marked occupied.
    pub beyond_marked_occupied: Spread,
    /// ψ.
    pub psi: Spread,
    /// Wrong cells.
    pub wrong: Spread,
    /// The all-free map's wrong cells (mean).
    pub all_free_wrong: f64,
    /// On the Pareto front of (energy, mean F1) of its mapper.
    pub pareto: bool,
}

/// Per configuration and mapper (configuration order, then mapper order), with the Pareto
/// front of each mapper marked.
pub fn summarize(out: &ExploreOutput) -> Vec<Summary> {
    let mut mappers: Vec<&'static str> = Vec::new();
    for r in &out.rows {
        if !mappers.contains(&r.mapper) {
            mappers.push(r.mapper);
        }
    }
    let mut s = Vec::new();
    for cfg in &out.configs {
        for &m in &mappers {
            let rows: Vec<&ExploreRow> = (out.rows.iter())
                .filter(|r| r.config == *cfg && r.mapper == m)
                .collect();
            if rows.is_empty() {
                continue;
            }
            let sp = |f: &dyn Fn(&ExploreRow) -> f64| {
                Spread::of(&rows.iter().map(|r| f(r)).collect::<Vec<_>>())
            };
            let c = rows[0].cost;
            s.push(Summary {
                config: *cfg,
                mapper: m,
                energy_j: c.energy_j,
                scan_time_s: c.scan_time_s,
                processing_share: c.processing_share(),
                f1: sp(&|r| r.scores.f1_1),
                walls_found: sp(&|r| r.scores.walls_found_1),
                free_marked_occupied: sp(&|r| r.scores.free_marked_occupied),
                beyond_marked_occupied: sp(&|r| r.scores.beyond_marked_occupied),
                psi: sp(&|r| r.scores.psi),
                wrong: sp(&|r| r.scores.wrong as f64),
                all_free_wrong: sp(&|r| r.scores.all_free_wrong as f64).mean,
                pareto: false,
            });
        }
    }
    for &m in &mappers {
        let idx: Vec<usize> = (0..s.len()).filter(|&i| s[i].mapper == m).collect();
        let pts: Vec<(f64, f64)> = idx.iter().map(|&i| (s[i].energy_j, s[i].f1.mean)).collect();
        for k in pareto_front(&pts) {
            s[idx[k]].pareto = true;
        }
    }
    s
}

/// The answer for one mapper: the best mean F1, the cheapest configuration within 5 % of
/// it, and the paper's setting (indices into the summaries).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verdict {
    /// Mapper.
    pub mapper: &'static str,
    /// The best mean F1.
    pub best: usize,
    /// The cheapest configuration whose mean F1 ≥ 0.95 × the best.
    pub cheapest: usize,
    /// The paper's setting.
    pub paper: usize,
}

/// Fraction of the best mean F1 a configuration must reach to count as "as good" (0.95).
pub const WITHIN: f64 = 0.95;

/// The verdict per mapper (mapper order), over the summaries with a finite F1.
pub fn verdicts(s: &[Summary], paper: &Config) -> Vec<Verdict> {
    let mut mappers: Vec<&'static str> = Vec::new();
    for x in s {
        if !mappers.contains(&x.mapper) {
            mappers.push(x.mapper);
        }
    }
    let mut v = Vec::new();
    for m in mappers {
        let idx: Vec<usize> = (0..s.len())
            .filter(|&i| s[i].mapper == m && s[i].f1.mean.is_finite())
            .collect();
        let Some(&best) = idx
            .iter()
            .max_by(|&&a, &&b| s[a].f1.mean.total_cmp(&s[b].f1.mean).then(b.cmp(&a)))
        else {
            continue;
        };
        let bar = WITHIN * s[best].f1.mean;
        let cheapest = *idx
            .iter()
            .filter(|&&i| s[i].f1.mean >= bar)
            .min_by(|&&a, &&b| s[a].energy_j.total_cmp(&s[b].energy_j).then(a.cmp(&b)))
            .expect("the best is within");
        let Some(&p) = idx.iter().find(|&&i| s[i].config == *paper) else {
            continue;
        };
        v.push(Verdict {
            mapper: m,
            best,
            cheapest,
            paper: p,
        });
    }
    v
}

/// One sentence per verdict: the cheapest configuration within 5 % of the best F1, its
/// energy per scan and F1 against the paper's setting.
pub fn verdict_text(s: &[Summary], v: &Verdict) -> String {
    let (b, c, p) = (&s[v.best], &s[v.cheapest], &s[v.paper]);
    format!(
        "{}: best mean F1 {:.3} ({}); cheapest within 5 %: {} — {:.3} mJ per scan, {:.1} ms, F1 {:.3} (seeds {:.3}–{:.3}); the paper's {}: {:.3} mJ, {:.1} ms, F1 {:.3} — {:.1} % of its energy, F1 {:+.3}",
        v.mapper.to_uppercase(),
        b.f1.mean,
        b.config.label(),
        c.config.label(),
        c.energy_j * 1e3,
        c.scan_time_s * 1e3,
        c.f1.mean,
        c.f1.min,
        c.f1.max,
        p.config.label(),
        p.energy_j * 1e3,
        p.scan_time_s * 1e3,
        p.f1.mean,
        100.0 * c.energy_j / p.energy_j,
        c.f1.mean - p.f1.mean
    )
}

fn config_columns() -> Vec<Column> {
    let col = Column::new;
    vec![
        col("N", "elements"),
        col("pulses", "pulses"),
        col("step (°)", "step_deg"),
        col("B (GHz)", "bandwidth_ghz"),
        col("P_tx (dBm)", "tx_power_dbm"),
        col("mapper", "mapper"),
    ]
}

fn config_cells(c: &Config, mapper: &str) -> Vec<Cell> {
    let plain = |v: f64| Cell::num(v, v.to_string());
    vec![
        Cell::count(c.elements),
        Cell::count(c.pulses),
        plain(c.step_deg),
        plain(c.bandwidth_ghz),
        plain(c.tx_power_dbm),
        Cell::text(mapper),
    ]
}

/// `explore.csv|.md`: one row per configuration, mapper and seed.
pub fn rows_table(out: &ExploreOutput) -> Table {
    let col = Column::new;
    let mut columns = config_columns();
    columns.extend([
        col("seed", "seed"),
        col("directions", "directions"),
        col("samples/pulse", "samples_per_pulse"),
        col("energy/scan (mJ)", "energy_per_scan_j"),
        col("scan time (ms)", "scan_time_s"),
        col("processing share", "processing_share"),
        col("F1 (1 cell)", "f1_1"),
        col("walls found", "walls_found_1"),
        col("room occupied", "free_marked_occupied"),
        col("beyond occupied", "beyond_marked_occupied"),
        col("ψ", "psi"),
        col("wrong cells", "wrong"),
        col("all-free wrong", "all_free_wrong"),
    ]);
    let mut t = Table::new(columns);
    for r in &out.rows {
        let mut row = config_cells(&r.config, r.mapper);
        let s = &r.scores;
        row.extend([
            Cell::num(r.seed as f64, r.seed.to_string()),
            Cell::count(r.directions),
            Cell::count(r.samples),
            Cell::num(r.cost.energy_j, format!("{:.3}", r.cost.energy_j * 1e3)),
            Cell::num(
                r.cost.scan_time_s,
                format!("{:.2}", r.cost.scan_time_s * 1e3),
            ),
            Cell::fixed(r.cost.processing_share(), 3),
            Cell::fixed(s.f1_1, 3),
            Cell::fixed(s.walls_found_1, 3),
            Cell::fixed(s.free_marked_occupied, 4),
            Cell::fixed(s.beyond_marked_occupied, 4),
            Cell::fixed(s.psi, 3),
            Cell::count(s.wrong),
            Cell::count(s.all_free_wrong),
        ]);
        t.push(row);
    }
    t
}

/// `summary.csv|.md`: one row per configuration and mapper (means, F1 and walls found with
/// their range over seeds, the Pareto flag).
pub fn summary_table(s: &[Summary]) -> Table {
    let col = Column::new;
    let mut columns = config_columns();
    columns.extend([
        col("energy/scan (mJ)", "energy_per_scan_j"),
        col("scan time (ms)", "scan_time_s"),
        col("processing share", "processing_share"),
        col("F1 (1 cell)", "f1_1_mean"),
        col("F1 range", "f1_1"),
        col("walls found", "walls_found_1_mean"),
        col("walls range", "walls_found_1"),
        col("room occupied", "free_marked_occupied_mean"),
        col("beyond occupied", "beyond_marked_occupied_mean"),
        col("ψ", "psi_mean"),
        col("wrong cells", "wrong_mean"),
        col("all-free wrong", "all_free_wrong_mean"),
        col("Pareto", "pareto"),
    ]);
    let mut t = Table::new(columns);
    let range = |x: &Spread| Cell::interval(x.min, x.max, format!("{:.3}–{:.3}", x.min, x.max));
    for x in s {
        let mut row = config_cells(&x.config, x.mapper);
        row.extend([
            Cell::num(x.energy_j, format!("{:.3}", x.energy_j * 1e3)),
            Cell::num(x.scan_time_s, format!("{:.2}", x.scan_time_s * 1e3)),
            Cell::fixed(x.processing_share, 3),
            Cell::fixed(x.f1.mean, 3),
            range(&x.f1),
            Cell::fixed(x.walls_found.mean, 3),
            range(&x.walls_found),
            Cell::fixed(x.free_marked_occupied.mean, 4),
            Cell::fixed(x.beyond_marked_occupied.mean, 4),
            Cell::fixed(x.psi.mean, 3),
            Cell::fixed(x.wrong.mean, 1),
            Cell::fixed(x.all_free_wrong, 1),
            Cell::text(if x.pareto { "yes" } else { "" }),
        ]);
        t.push(row);
    }
    t
}

/// `timing.csv`: the measured wall-clock seconds of every job (not deterministic; apart
/// from the tables above).
pub fn timing_table(out: &ExploreOutput) -> Table {
    let col = Column::new;
    let mut columns = config_columns();
    columns.truncate(5);
    columns.extend([
        col("seed", "seed"),
        col("scans", "scans"),
        col("data (s)", "data_s"),
        col("energy stage (s)", "energy_stage_s"),
    ]);
    let mappers: Vec<&str> = out
        .timings
        .first()
        .map(|t| t.map_s.iter().map(|m| m.0).collect())
        .unwrap_or_default();
    for m in &mappers {
        columns.push(Column::new(format!("{m} (s)"), format!("{m}_s")));
    }
    let mut t = Table::new(columns);
    for x in &out.timings {
        let mut row = config_cells(&x.config, "");
        row.truncate(5);
        row.extend([
            Cell::num(x.seed as f64, x.seed.to_string()),
            Cell::count(x.scans),
            Cell::fixed(x.data_s, 3),
            Cell::fixed(x.energy_s, 3),
        ]);
        row.extend(x.map_s.iter().map(|m| Cell::fixed(m.1, 3)));
        t.push(row);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_of_values() {
        let s = Spread::of(&[0.5, 0.7, 0.6]);
        assert!((s.mean - 0.6).abs() < 1e-15);
        assert_eq!((s.min, s.max), (0.5, 0.7));
        assert!(Spread::of(&[]).mean.is_nan());
    }
}
