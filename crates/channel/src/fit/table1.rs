//! Table 1 of the paper, as the campaign fit reads it: one row per quantity with our
//! estimate, its 95 % position-bootstrap interval, the family, the KS p-value, the best
//! family by AIC, the paper's value and, when given, the same estimators on the
//! simulator's truth.
//!
//! Takes a [`ChannelFit`] (and the truth's); gives the rows with named fields
//! ([`rows`], [`Table1Row`]), one [`Table`] ([`table`]) that every rendering uses —
//! `table1.md` and `table1.csv` ([`write_table1`]) and the report's HTML
//! (`report::html_table`) — so the three agree.
//!
//! * Markdown and HTML show the values as text with their unit (3 decimals); d_c is shown
//!   as its mean spacing (the model value, the censored estimate Σ L / Σ k) in m and as ns
//!   one-way (m/c) and round-trip (2m/c), with the standard deviation of the complete gaps.
//! * The CSV has numeric columns so a script reads it back: `parameter, value, unit, lo,
//!   hi, family, ks_p, best_aic, paper, truth`; numbers at full precision, empty where
//!   missing; `paper` and `truth` in the value's unit. The paper's d_c, 5.02 ns, is read
//!   one-way as metres (1.505 m, as [`ModelConfig::table1_defaults`]).
//! * With a `[walls]` section (the levels read from the energy table, `model::levels`)
//!   rows for the walls' specular |Γ| (per material in its text), the corners' and
//!   edges' σ and the clusters' σ follow the others.
//! * With a `[diffuse]` section the dense component's four quantities follow the discrete
//!   clusters' rows (σ′, the Lambert exponent, the power share, the decay).
//! * A quantity the fit could not estimate shows "not estimable: <reason>; drawn at <v>
//!   (stated)" in the value cell, v the stated value of the model file (and "—" for its
//!   interval and KS p); its CSV value, lo, hi and ks_p are empty (a stated value is not
//!   an estimate).
//!   The same holds for the truth column.
//! * When the closed loop ran ([`ChannelFit::identified`] not empty: `report`, `fit
//!   --closed-loop R`) a column says per cluster quantity whether this campaign identifies
//!   it, by [`crate::fit::identify`]'s rule, with the chain's median reading on R draws of
//!   the written model and how many of their intervals cover the written value; the CSV
//!   splits it into `identifiable` (true/false), `closed_loop_median`,
//!   `closed_loop_covered` and `closed_loop_draws`, before `truth`. This is issue 54's
//!   second column: the estimator the held-out check chose is the chain itself, so its
//!   value and interval are the first column's, and the column adds the verdict.
//!
//! [`ModelConfig::table1_defaults`]: crate::model::file::ModelConfig::table1_defaults

use crate::error::Result;
use crate::export::{Cell, Column, Table};
use crate::fit::channel::ChannelFit;
use crate::fit::identify::Identification;
use crate::model::file::{ModelConfig, Quantity};
use crate::units::C0;
use std::path::Path;

/// One row of Table 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Table1Row {
    /// The quantity's name in the table.
    pub parameter: &'static str,
    /// Our estimate, in `unit` (NaN when not estimable).
    pub value: f64,
    /// Its unit.
    pub unit: String,
    /// The estimate as the table shows it (with its unit; d_c also in ns and with its std),
    /// or "not estimable: <reason>".
    pub value_shown: String,
    /// 95 % position-bootstrap interval.
    pub interval: Option<[f64; 2]>,
    /// The family of the model file.
    pub family: String,
    /// KS parametric-bootstrap p-value.
    pub ks_p: Option<f64>,
    /// Best family by AIC (empty where none was ranked).
    pub best_aic: String,
    /// The paper's value in `unit` and as the table shows it.
    pub paper: Option<(f64, &'static str)>,
    /// The same estimators on the simulator's truth: its value (NaN when not estimable)
    /// and its shown text.
    pub truth: Option<(f64, String)>,
    /// The closed loop's verdict ([`crate::fit::identify`]; `None` where it did not run or
    /// the row is not one of the seven cluster quantities).
    pub identified: Option<Identification>,
}

impl Table1Row {
    /// The interval as shown: `[lo, hi]` with 3 decimals, or "—".
    pub fn interval_shown(&self) -> String {
        self.interval
            .map(|[a, b]| format!("[{a:.3}, {b:.3}]"))
            .unwrap_or_else(|| "—".into())
    }

    /// The truth's value as shown, or "—".
    pub fn truth_shown(&self) -> &str {
        self.truth.as_ref().map_or("—", |t| t.1.as_str())
    }

    /// The row's cells: the closed loop's columns when `closed_loop`, the truth's last
    /// when `truth` (as [`columns`]).
    fn cells(&self, closed_loop: bool, truth: bool) -> Vec<Cell> {
        let opt = |v: Option<f64>| v.map_or(Cell::missing(""), |v| Cell::num(v, ""));
        // a value that is not a number (not estimable): its text, an empty CSV field
        let value = |v: f64, shown: &str| {
            if v.is_nan() {
                Cell::missing(shown)
            } else {
                Cell::num(v, shown)
            }
        };
        let mut cells = vec![
            Cell::text(self.parameter),
            value(self.value, &self.value_shown),
            Cell::text(self.unit.clone()),
            match self.interval {
                Some([lo, hi]) => Cell::interval(lo, hi, self.interval_shown()),
                None => Cell::missing("—"),
            },
            opt(self.interval.map(|i| i[0])),
            opt(self.interval.map(|i| i[1])),
            Cell::text(self.family.clone()),
            self.ks_p
                .map_or(Cell::missing("—"), |p| Cell::num(p, format!("{p:.3}"))),
            Cell::text(self.best_aic.clone()),
            self.paper
                .map_or(Cell::missing("—"), |(v, shown)| Cell::num(v, shown)),
        ];
        if closed_loop {
            let id = self.identified.as_ref();
            cells.extend([
                id.map_or(Cell::missing("—"), |i| Cell::text(i.shown(&self.unit))),
                id.map_or(Cell::missing(""), |i| {
                    Cell::text(i.identifiable().to_string())
                }),
                id.map_or(Cell::missing(""), |i| value(i.median, "")),
                id.map_or(Cell::missing(""), |i| Cell::count(i.covered)),
                id.map_or(Cell::missing(""), |i| Cell::count(i.draws)),
            ]);
        }
        if truth {
            cells.push(
                self.truth
                    .as_ref()
                    .map_or(Cell::missing("—"), |(v, shown)| value(*v, shown)),
            );
        }
        cells
    }
}

/// The columns of Table 1 (Markdown headers, the report's shorter HTML headers, CSV names);
/// the closed loop's only when it ran, the truth's last, only when there is a truth.
fn columns(closed_loop: bool, truth: bool) -> Vec<Column> {
    let mut c = vec![
        Column::new("parameter", "parameter"),
        Column::new("pradar", "value"),
        Column::new("unit", "unit").csv_only(),
        Column::new("95% interval (positions bootstrap)", "interval")
            .html("95% interval")
            .display_only(),
        Column::new("lo", "lo").csv_only(),
        Column::new("hi", "hi").csv_only(),
        Column::new("family", "family"),
        Column::new("KS p (param. bootstrap)", "ks_p").html("KS p"),
        Column::new("best family by AIC", "best_aic").html("best by AIC"),
        Column::new("paper Table 1", "paper").html("paper"),
    ];
    if closed_loop {
        c.extend([
            Column::new(
                "read back from draws of this model? (closed loop)",
                "closed_loop",
            )
            .html("read back? (closed loop)")
            .display_only(),
            Column::new("identifiable", "identifiable").csv_only(),
            Column::new("closed-loop median", "closed_loop_median").csv_only(),
            Column::new("intervals covering", "closed_loop_covered").csv_only(),
            Column::new("closed-loop draws", "closed_loop_draws").csv_only(),
        ]);
    }
    if truth {
        c.push(Column::new("simulator truth (same estimators)", "truth"));
    }
    c
}

/// Table 1 as one [`Table`]: `t.to_markdown()` is the table of `table1.md`, `t.to_csv()`
/// is `table1.csv`, `report::html_table(&t)` the report's. Without a truth there is no
/// truth column (a measured campaign has none to show).
pub fn table(f: &ChannelFit, truth: Option<&ChannelFit>) -> Table {
    let closed_loop = !f.identified.is_empty();
    let mut t = Table::new(columns(closed_loop, truth.is_some()));
    for r in rows(f, truth) {
        t.push(r.cells(closed_loop, truth.is_some()));
    }
    t
}

/// Table 1's rows, with the truth's values beside ours when given.
pub fn rows(f: &ChannelFit, truth: Option<&ChannelFit>) -> Vec<Table1Row> {
    let mut rows = ours(f);
    if let Some(t) = truth {
        for (r, t) in rows.iter_mut().zip(ours(t)) {
            r.truth = Some((t.value, t.value_shown));
        }
    }
    rows
}

/// Write table1.md (titled "Table 1: `name` channel parameters", `name` the campaign's) and
/// table1.csv (beside `md`).
pub fn write_table1(
    md: &Path,
    name: &str,
    f: &ChannelFit,
    truth: Option<&ChannelFit>,
) -> Result<()> {
    let t = table(f, truth);
    let mut s = format!("# Table 1: {name} channel parameters\n\n");
    s.push_str(&t.to_markdown());
    s.push_str("\nThe paper's values are printed beside ours for comparison; nothing is tuned toward them.\n");
    crate::io::write_bytes(md, s.as_bytes())?;
    crate::io::write_bytes(&md.with_extension("csv"), t.to_csv().as_bytes())
}

/// The rows of one fit (no truth).
fn ours(f: &ChannelFit) -> Vec<Table1Row> {
    let m = &f.model;
    let best = |k: &str| best_aic(f, k);
    let row = quantity_row;
    let ns1 = 1e9 / C0;
    let spacing = Table1Row {
        value_shown: spacing_shown(f),
        paper: Some((5.02 / ns1, "5.02 ns (\"standard deviation\")")),
        ..row(
            "inter-cluster perimeter distance d_c",
            &m.perimeter_spacing,
            best("perimeter_spacing"),
            None,
        )
    };
    let mut rows = vec![
        row(
            "inter-cluster arrival rate Λ",
            &m.inter_cluster_rate,
            best("inter_cluster_rate"),
            Some((0.21, "0.21 1/ns")),
        ),
        spacing,
        row(
            "intra-cluster arrival rate λ",
            &m.intra_cluster_rate,
            best("intra_cluster_rate"),
            Some((0.43, "0.43 1/ns")),
        ),
        row(
            "intra-cluster AoA (Laplacian std)",
            &m.intra_cluster_aoa,
            best("intra_cluster_aoa"),
            Some((16.9, "16.9 deg")),
        ),
        row(
            "perimeter offset d_p",
            &m.perimeter_offset,
            best("perimeter_offset"),
            None,
        ),
        row(
            "cluster power decay Γ (beyond r⁻⁴)",
            &m.cluster_decay,
            String::new(),
            None,
        ),
        row("ray power decay γ", &m.ray_decay, String::new(), None),
    ];
    // the closed loop's verdicts, by the seven rows' keys in their order
    for (r, key) in rows.iter_mut().zip(KEYS) {
        r.identified = f.identified.get(key).cloned();
    }
    // the dense component beside the discrete clusters (its truth column stays "—": the
    // simulator's walls are not clusters)
    rows.extend(diffuse_rows(m));
    // the levels read from the energy table (`model::levels`), beside the paper's
    // quantities
    rows.extend(level_rows(m));
    rows
}

/// The model file's keys of the seven cluster quantities, in the rows' order (Λ, d_c, λ,
/// the AoA std, d_p, Γ, γ): the keys of [`ChannelFit::identified`].
pub const KEYS: [&str; 7] = [
    "inter_cluster_rate",
    "perimeter_spacing",
    "intra_cluster_rate",
    "intra_cluster_aoa",
    "perimeter_offset",
    "cluster_decay",
    "ray_decay",
];

/// Takes the fit and a quantity's key; gives the name of its best family by AIC (empty
/// when none was ranked).
fn best_aic(f: &ChannelFit, k: &str) -> String {
    f.details
        .get(k)
        .and_then(|d| d.aic.first())
        .map(|a| a.0.clone())
        .unwrap_or_default()
}

/// Takes a row's parameter, its quantity, the best family by AIC and the paper's value;
/// gives the row (no truth).
fn quantity_row(
    parameter: &'static str,
    q: &Quantity,
    best_aic: String,
    paper: Option<(f64, &'static str)>,
) -> Table1Row {
    Table1Row {
        parameter,
        // a stated value is not an estimate: the CSV's value stays empty
        value: if q.is_estimable() { q.value } else { f64::NAN },
        unit: q.unit.clone(),
        value_shown: match &q.not_estimable {
            Some(reason) => stated_shown(reason, q),
            None if q.value == f64::INFINITY => "∞ (no excess decay)".to_string(),
            None => format!("{:.3} {}", q.value, q.unit),
        },
        interval: q.interval,
        family: q.family.clone(),
        ks_p: q.ks_p,
        best_aic,
        paper,
        truth: None,
        identified: None,
    }
}

/// Takes the model; gives the rows of its dense component (`[diffuse]`; none without it).
fn diffuse_rows(m: &ModelConfig) -> Vec<Table1Row> {
    let row = quantity_row;
    let mut rows = Vec::new();
    if let Some(d) = &m.diffuse {
        for (name, q) in [
            ("diffuse wall backscatter σ′", &d.wall_rcs_per_m),
            ("diffuse Lambert exponent n", &d.lambert_exponent),
            ("diffuse share of MPC power", &d.power_share),
            ("diffuse power decay", &d.decay),
        ] {
            rows.push(row(name, q, String::new(), None));
        }
    }
    rows
}

/// Takes the model; gives the rows of the levels read from the energy table (`[walls]`:
/// |Γ| with each material's, the vertices' σ, and the clusters' σ; none without it).
fn level_rows(m: &ModelConfig) -> Vec<Table1Row> {
    let row = quantity_row;
    let mut rows = Vec::new();
    if let Some(w) = &m.walls {
        let mut spec = row("wall specular |Γ|", &w.specular_gamma, String::new(), None);
        if !w.material_gamma.is_empty() && w.specular_gamma.is_estimable() {
            let per: Vec<String> = w
                .material_gamma
                .iter()
                .map(|(k, q)| format!("{k} {:.3}", q.value))
                .collect();
            spec.value_shown = format!("{} ({})", spec.value_shown, per.join(", "));
        }
        rows.push(spec);
        for (name, q) in [
            ("corner σ (dihedrals)", &w.corner_rcs),
            ("edge σ (other vertices)", &w.edge_rcs),
        ] {
            if let Some(q) = q {
                rows.push(row(name, q, String::new(), None));
            }
        }
        let mut sigma = row(
            "cluster σ (first ray)",
            &m.cluster_rrcs,
            String::new(),
            None,
        );
        if m.cluster_rrcs.is_estimable() {
            sigma.value_shown = format!("{:.3e} {}", m.cluster_rrcs.value, m.cluster_rrcs.unit);
        }
        rows.push(sigma);
    }
    rows
}

/// A value cell's text when the quantity is not estimable: the reason, and the stated value
/// synth draws in its place (schema 2; none in a schema-1 model).
fn stated_shown(reason: &str, q: &Quantity) -> String {
    if q.value.is_nan() {
        format!("not estimable: {reason}")
    } else if q.value == f64::INFINITY {
        format!("not estimable: {reason}; drawn at ∞ (stated)")
    } else {
        format!(
            "not estimable: {reason}; drawn at {:.3} {} (stated)",
            q.value, q.unit
        )
    }
}

/// d_c as shown: the mean spacing (the model value, the censored estimate) in m and ns
/// one-way / round-trip, and the std of the complete gaps.
fn spacing_shown(f: &ChannelFit) -> String {
    if let Some(reason) = &f.model.perimeter_spacing.not_estimable {
        return stated_shown(reason, &f.model.perimeter_spacing);
    }
    let dc = &f.dc_m;
    let n = dc.len().max(1) as f64;
    let dc_mean = f.model.perimeter_spacing.value;
    let gap_mean = dc.iter().sum::<f64>() / n;
    let dc_std = (dc.iter().map(|x| (x - gap_mean).powi(2)).sum::<f64>() / n).sqrt();
    let ns1 = 1e9 / C0;
    format!(
        "mean {:.3} m = {:.2} ns one-way / {:.2} ns round-trip; std {}",
        dc_mean,
        dc_mean * ns1,
        2.0 * dc_mean * ns1,
        if dc.len() >= 2 {
            format!(
                "{:.3} m = {:.2} / {:.2} ns",
                dc_std,
                dc_std * ns1,
                2.0 * dc_std * ns1
            )
        } else {
            "— (fewer than 2 complete gaps)".to_string()
        }
    )
}
