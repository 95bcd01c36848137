//! The predictive check's outputs: the table ([`CheckResult::table`]) as
//! CSV/Markdown/HTML, and one CDF panel per statistic — the measured statistic's CDF
//! (black) inside the draws' band (the pointwise 5–95 % range of the draws' CDFs, shaded;
//! their pointwise median, blue), on 200 points spanning every draw's and the measured
//! values. The curve statistic (mean delay power profile) is drawn as its normalised
//! cumulative power against delay. The held-out check ([`HoldoutResult`]) has its table and
//! lines ([`holdout_html`]) and `check --holdout --out`'s files ([`write_holdout`]).

use super::{html_escape, html_table, plot_err, register_font, Section};
use crate::check::stats::NAMES;
use crate::check::{CheckResult, HoldoutResult};
use crate::error::{Error, Result};
use crate::export::Table;
use plotters::prelude::*;
use std::path::Path;

/// Points on each panel's x axis.
const POINTS: usize = 200;

/// The CDF panels (3 per row, 360 × 270 pixels each) into `path` (PNG, atomically).
pub fn cdf_plot(path: &Path, r: &CheckResult) -> Result<()> {
    register_font();
    crate::io::ensure_parent(path)?;
    let k = r.stats.len();
    let cols = 3;
    let rows = k.div_ceil(cols);
    let bin_ns = r.measured.bin_ns;
    crate::io::write_rendered(path, "png", |tmp| {
        let root =
            BitMapBackend::new(tmp, (360 * cols as u32, 270 * rows as u32)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let areas = root.split_evenly((rows, cols));
        for (s, res) in r.stats.iter().enumerate() {
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            for st in std::iter::once(&r.measured).chain(&r.draws) {
                if let Some((a, b)) = st.values[s].range(bin_ns) {
                    lo = lo.min(a);
                    hi = hi.max(b);
                }
            }
            if !lo.is_finite() {
                (lo, hi) = (0.0, 1.0);
            }
            if hi <= lo {
                (lo, hi) = (lo - 0.5, hi + 0.5);
            }
            let pad = 0.03 * (hi - lo);
            let (lo, hi) = (lo - pad, hi + pad);
            let xs: Vec<f64> = (0..POINTS)
                .map(|i| lo + (hi - lo) * i as f64 / (POINTS - 1) as f64)
                .collect();
            let curves: Vec<Vec<f64>> = r
                .draws
                .iter()
                .map(|d| d.values[s].cdf_at(&xs, bin_ns))
                .collect();
            let band: Vec<(f64, f64, f64)> = (0..POINTS)
                .map(|i| {
                    // the pointwise quantiles of the finite values (NaN when none)
                    let mut col: Vec<f64> = curves
                        .iter()
                        .map(|c| c[i])
                        .filter(|v| v.is_finite())
                        .collect();
                    col.sort_by(f64::total_cmp);
                    let q = |q: f64| crate::stats::sorted::quantile(&col, q).unwrap_or(f64::NAN);
                    (q(0.05), q(0.5), q(0.95))
                })
                .collect();
            let meas = r.measured.values[s].cdf_at(&xs, bin_ns);
            let unit = NAMES[s].1;
            let mut chart = ChartBuilder::on(&areas[s])
                .caption(
                    format!(
                        "{} (KS {:.2}, adjusted p {:.3})",
                        res.name,
                        res.ks(),
                        res.adjusted_p
                    ),
                    ("sans-serif", 13),
                )
                .margin(8)
                .x_label_area_size(30)
                .y_label_area_size(36)
                .build_cartesian_2d(lo..hi, 0.0..1.0)
                .map_err(|e| plot_err(path, e))?;
            chart
                .configure_mesh()
                .x_desc(unit)
                .y_desc("CDF")
                .label_style(("sans-serif", 11))
                .draw()
                .map_err(|e| plot_err(path, e))?;
            let poly: Vec<(f64, f64)> = xs
                .iter()
                .zip(&band)
                .filter(|(_, b)| b.0.is_finite() && b.2.is_finite())
                .map(|(x, b)| (*x, b.2))
                .chain(
                    xs.iter()
                        .zip(&band)
                        .rev()
                        .filter(|(_, b)| b.0.is_finite() && b.2.is_finite())
                        .map(|(x, b)| (*x, b.0)),
                )
                .collect();
            if poly.len() >= 3 {
                chart
                    .draw_series(std::iter::once(Polygon::new(poly, BLUE.mix(0.2).filled())))
                    .map_err(|e| plot_err(path, e))?;
            }
            let mid: Vec<(f64, f64)> = xs
                .iter()
                .zip(&band)
                .filter(|(_, b)| b.1.is_finite())
                .map(|(x, b)| (*x, b.1))
                .collect();
            chart
                .draw_series(std::iter::once(PathElement::new(mid, BLUE.stroke_width(1))))
                .map_err(|e| plot_err(path, e))?;
            let m: Vec<(f64, f64)> = xs
                .iter()
                .zip(&meas)
                .filter(|(_, v)| v.is_finite())
                .map(|(x, v)| (*x, *v))
                .collect();
            chart
                .draw_series(std::iter::once(PathElement::new(m, BLACK.stroke_width(2))))
                .map_err(|e| plot_err(path, e))?;
        }
        root.present().map_err(|e| plot_err(path, e))
    })
}

/// The report section: the verdict, the table and the CDF panels (`png`, relative to
/// the page). `what` names the model and the data, e.g. "the fitted model against the
/// corridor".
pub fn section(title: &str, what: &str, r: &CheckResult, png: &str) -> Section {
    let html = format!(
        "<p>{}: {} draws of <code>synth</code> (seeds from {}, carrying the measured table's \
         N0), statistics of <code>pradar check</code> (signal = bins 10 dB above each table's \
         own noise mean). KS measured↔draws is the median over draws; draw↔draw the median \
         over pairs; p = the measured table's rank among the draws' leave-one-out distances; \
         adjusted p = Westfall–Young max-T over the {} statistics. Fail: the check's p ≤ {} \
         or the measured noise floor more than {} dB from the draws'.</p>\n\
         <p><b>{}</b></p>\n{}\
         <p>Measured CDF (black) in the draws' 5–95 % band (shaded; median blue).</p>\n\
         <p><img src=\"{}\" alt=\"check CDFs\"></p>\n",
        html_escape(what),
        r.draws.len(),
        r.seed,
        r.stats.len(),
        crate::check::ALPHA,
        crate::check::MAX_NOISE_DB,
        html_escape(&r.verdict()),
        html_table(&r.table()),
        html_escape(png)
    );
    Section {
        title: title.into(),
        html,
    }
}

/// Write `check.csv`, `check.md`, `check_cdfs.png` and `index.html` into `dir`.
pub fn write(dir: &Path, what: &str, r: &CheckResult) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_tables(dir, "check", &r.verdict(), &r.table())?;
    cdf_plot(&dir.join("check_cdfs.png"), r)?;
    let sec = section(
        "Does the model reproduce the channel?",
        what,
        r,
        "check_cdfs.png",
    );
    super::write_index(&dir.join("index.html"), "pradar check", &[sec])
}

/// A table as `<stem>.csv` and as `<stem>.md` under its `head` line (a verdict).
fn write_tables(dir: &Path, stem: &str, head: &str, t: &Table) -> Result<()> {
    crate::io::write_bytes(&dir.join(format!("{stem}.csv")), t.to_csv().as_bytes())?;
    let md = format!("{head}\n\n{}", t.to_markdown());
    crate::io::write_bytes(&dir.join(format!("{stem}.md")), md.as_bytes())
}

/// The held-out check's `holdout.csv` and `holdout.md` (both ways' lines and the combined
/// verdict above the table) in `dir`, which must exist.
pub fn write_holdout_tables(dir: &Path, r: &HoldoutResult) -> Result<()> {
    write_tables(dir, "holdout", &r.lines().join("\n"), &r.table())
}

/// The held-out check's lines and table (HTML): one row per way with its p-value and
/// misses, then the combined verdict, for the report's check section and `check
/// --holdout --out`'s page.
pub fn holdout_html(r: &HoldoutResult) -> String {
    let levels: String = (r.ways.iter())
        .filter_map(|w| {
            w.levels_error.as_ref().map(|e| {
                format!(
                    "<p>The levels could not be read from half {} (its model is the cluster fit's): {}</p>\n",
                    html_escape(r.halves[w.fitted_on].name),
                    html_escape(e)
                )
            })
        })
        .collect();
    use crate::check::EstimatorKind;
    let by = match r.estimator {
        EstimatorKind::Smm => {
            "by the chain (CLEAN, K-means, fit, levels), then refined by simulated minimum \
                  distance (<code>--estimator smm</code>)"
        }
        EstimatorKind::Calibrate => &format!(
            "by <code>calibrate</code> (ABC-SMC, {} simulations; its posterior medians, \
             <code>--estimator calibrate</code>)",
            crate::check::holdout::CALIBRATE_SIMULATIONS
        ),
        EstimatorKind::Chain => {
            "by the same chain (CLEAN, K-means, fit, levels); <code>--estimator smm</code> or \
              <code>calibrate</code> checks another estimator's model the same way (minutes \
              each; compared on the zoo in docs/zoo.md)"
        }
    };
    format!(
        "<p>Held out (<code>pradar check --holdout</code>): the positions cut in walk order into \
         half {} and half {}; a model fitted on each half {by}, checked by the same rule ({} \
         draws each) against the other half's table. It passes only when both ways \
         pass.</p>\n{}{levels}<p><b>{}</b></p>\n",
        html_escape(&r.halves[0].describe()),
        html_escape(&r.halves[1].describe()),
        r.ways[0].result.draws.len(),
        html_table(&r.table()),
        html_escape(&r.verdict())
    )
}

/// The folder of the way fitted on half `fitted_on` (0: A): `fit_A_check_B`.
pub fn way_dir(fitted_on: usize) -> String {
    let n = crate::check::holdout::NAMES;
    format!("fit_{}_check_{}", n[fitted_on], n[1 - fitted_on])
}

/// The files `check --holdout --out` writes, relative to its folder: `holdout.md` (the
/// lines, then the table), `holdout.csv`, `index.html` and, per way, `fit_A_check_B/`
/// (`model.toml`, the model fitted on A, and `check.csv`, `check.md`, `check_cdfs.png` of
/// its check on B).
pub fn holdout_files() -> Vec<String> {
    let mut v: Vec<String> = ["holdout.md", "holdout.csv", "index.html"]
        .map(String::from)
        .to_vec();
    for k in 0..2 {
        let d = way_dir(k);
        for f in ["model.toml", "check.csv", "check.md", "check_cdfs.png"] {
            v.push(format!("{d}/{f}"));
        }
    }
    v
}

/// Write [`holdout_files`] into `dir`; `what` names the campaign's table.
pub fn write_holdout(dir: &Path, what: &str, r: &HoldoutResult) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_holdout_tables(dir, r)?;
    let mut sections = vec![Section {
        title: "Does the model reproduce positions the fit did not see?".into(),
        html: format!("<p>{}</p>\n{}", html_escape(what), holdout_html(r)),
    }];
    for w in &r.ways {
        let d = way_dir(w.fitted_on);
        let sub = dir.join(&d);
        std::fs::create_dir_all(&sub).map_err(|e| Error::io(&sub, e))?;
        w.model.save(&sub.join("model.toml"))?;
        write_tables(&sub, "check", &r.way_line(w), &w.result.table())?;
        cdf_plot(&sub.join("check_cdfs.png"), &w.result)?;
        let (fit, on) = r.pair(w);
        sections.push(section(
            &format!("Fitted on {}, checked on {}", fit.describe(), on.describe()),
            &format!(
                "the model fitted on half {} ({d}/model.toml) against half {} of {what}",
                fit.describe(),
                on.describe()
            ),
            &w.result,
            &format!("{d}/check_cdfs.png"),
        ));
    }
    super::write_index(&dir.join("index.html"), "pradar check --holdout", &sections)
}
