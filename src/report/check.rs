//! The predictive check's outputs: the table ([`CheckResult::table`]) as
//! CSV/Markdown/HTML, and one CDF panel per statistic — the measured statistic's CDF
//! (black) inside the draws' band (the pointwise 5–95 % range of the draws' CDFs, shaded;
//! their pointwise median, blue), on 200 points spanning every draw's and the measured
//! values. The curve statistic (mean delay power profile) is drawn as its normalised
//! cumulative power against delay.

use super::{html_escape, html_table, plot_err, register_font, Section};
use crate::check::stats::NAMES;
use crate::check::CheckResult;
use crate::error::{Error, Result};
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
    let t = r.table();
    crate::io::write_bytes(&dir.join("check.csv"), t.to_csv().as_bytes())?;
    let md = format!("{}\n\n{}", r.verdict(), t.to_markdown());
    crate::io::write_bytes(&dir.join("check.md"), md.as_bytes())?;
    cdf_plot(&dir.join("check_cdfs.png"), r)?;
    let sec = section(
        "Does the model reproduce the channel?",
        what,
        r,
        "check_cdfs.png",
    );
    super::write_index(&dir.join("index.html"), "pradar check", &[sec])
}
