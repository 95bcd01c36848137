//! The calibration's report section: the marginal posteriors of the free
//! quantities (weighted histograms in ln scale, one panel each, with the median, the 95 %
//! credible interval and, when given, the cluster chain's value), their posterior
//! correlations (in ln units), and the cluster-based fit beside the posterior, each
//! quantity where the chain's value lies outside the credible interval flagged.

use super::{html_escape, plot_err, register_font, Section};
use crate::calibrate::Calibration;
use crate::error::Result;
use crate::model::file::ModelConfig;
use crate::stats::weighted_quantile;
use plotters::prelude::*;
use std::path::Path;

/// Marginal posterior panels (4 per row, 320 × 240 pixels each) into `path` (PNG, written
/// atomically). `chain`: the cluster fit's model, drawn as a red line where it has a value.
pub fn posterior_plot(path: &Path, cal: &Calibration, chain: Option<&ModelConfig>) -> Result<()> {
    register_font();
    let k = cal.free.len();
    if k == 0 {
        return Err(plot_err(path, "no free quantity"));
    }
    let cols = k.min(4);
    let rows = k.div_ceil(cols);
    crate::io::write_rendered(path, "png", |tmp| {
        let root =
            BitMapBackend::new(tmp, (320 * cols as u32, 240 * rows as u32)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let areas = root.split_evenly((rows, cols));
        let parts = cal.particles();
        let w = &cal.posterior.weights;
        for (i, name) in cal.free.iter().enumerate() {
            let x: Vec<f64> = parts.iter().map(|t| t[i]).collect();
            let (lo, hi) = x
                .iter()
                .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(*v), a.1.max(*v)));
            let (lo, hi) = if hi > lo {
                (lo, hi)
            } else {
                (lo - 0.5, hi + 0.5)
            };
            let nbins = 20;
            let width = (hi - lo) / nbins as f64;
            let mut h = vec![0.0; nbins];
            for (v, wi) in x.iter().zip(w) {
                let b = (((v - lo) / width) as usize).min(nbins - 1);
                h[b] += wi / width;
            }
            let top = h.iter().copied().fold(0.0, f64::max).max(1e-12) * 1.1;
            let unit = cal
                .model
                .quantity(name)
                .map_or(String::new(), |q| q.unit.clone());
            let mut chart = ChartBuilder::on(&areas[i])
                .caption(format!("{name} ({unit})"), ("sans-serif", 14))
                .margin(8)
                .x_label_area_size(30)
                .y_label_area_size(40)
                .build_cartesian_2d(lo..hi, 0.0..top)
                .map_err(|e| plot_err(path, e))?;
            chart
                .configure_mesh()
                .x_desc("value (ln scale)")
                .x_label_formatter(&|v| format!("{:.3}", v.exp()))
                .x_labels(4)
                .y_labels(3)
                .label_style(("sans-serif", 11))
                .draw()
                .map_err(|e| plot_err(path, e))?;
            chart
                .draw_series(h.iter().enumerate().map(|(b, y)| {
                    let x0 = lo + b as f64 * width;
                    Rectangle::new([(x0, 0.0), (x0 + width, *y)], BLUE.mix(0.4).filled())
                }))
                .map_err(|e| plot_err(path, e))?;
            let line =
                |v: f64, c: RGBColor| PathElement::new(vec![(v, 0.0), (v, top)], c.stroke_width(2));
            let med = weighted_quantile(&x, w, 0.5).expect("a non-empty population");
            let q0 = weighted_quantile(&x, w, 0.025).expect("a non-empty population");
            let q1 = weighted_quantile(&x, w, 0.975).expect("a non-empty population");
            chart
                .draw_series([
                    line(med, BLACK),
                    line(q0, RGBColor(120, 120, 120)),
                    line(q1, RGBColor(120, 120, 120)),
                ])
                .map_err(|e| plot_err(path, e))?;
            // an estimated value of the chain's only (a stated one is not its estimate)
            let estimated = chain
                .and_then(|m| m.quantity(name))
                .filter(|q| q.is_estimable())
                .map(|q| q.value);
            if let Some(v) = estimated {
                if v.is_finite() && v > 0.0 && v.ln() >= lo && v.ln() <= hi {
                    chart
                        .draw_series([line(v.ln(), RED)])
                        .map_err(|e| plot_err(path, e))?;
                }
            }
        }
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// The section: the marginal posteriors (`<dir>/<plot>`), the posterior beside the
/// cluster chain (flagged where the chain lies outside the 95 % interval) and the
/// correlation table.
pub fn section(
    dir: &Path,
    plot: &str,
    cal: &Calibration,
    chain: Option<&ModelConfig>,
) -> Result<Section> {
    posterior_plot(&dir.join(plot), cal, chain)?;
    let mut html = format!(
        "<p>ABC-SMC calibration (no clustering): {} simulations, {} generations, final ε {:.3}. Black: posterior median, grey: 95 % credible interval, red: the cluster chain's value.</p>\n<img src=\"{}\" alt=\"marginal posteriors\">\n",
        cal.posterior.simulations,
        cal.posterior.generations,
        cal.posterior.epsilon,
        html_escape(plot)
    );
    html.push_str(
        "<table><tr><th>quantity</th><th>posterior median</th><th>95 % credible interval</th><th>width / prior's (ln)</th><th>cluster chain</th><th></th></tr>\n",
    );
    for (k, name) in cal.free.iter().enumerate() {
        let Some(q) = cal.model.quantity(name) else {
            continue;
        };
        let [lo, hi] = q.interval.unwrap_or([f64::NAN; 2]);
        let c = chain.and_then(|m| m.quantity(name));
        let (shown, flag) = match c {
            Some(q) if !q.is_estimable() => (
                format!("not estimable (stated {})", crate::error::short(q.value)),
                "",
            ),
            Some(q) if q.value == f64::INFINITY => (
                "∞".to_string(),
                if hi.is_finite() && hi < crate::calibrate::EXCESS_DECAY_PRIOR.1 {
                    "outside the credible interval"
                } else {
                    ""
                },
            ),
            Some(q) if q.value.is_finite() => (
                format!("{:.4}", q.value),
                if q.value < lo || q.value > hi {
                    "outside the credible interval"
                } else {
                    ""
                },
            ),
            Some(_) => ("not estimable".to_string(), ""),
            None => ("—".to_string(), ""),
        };
        let share = cal.width_share(k);
        html.push_str(&format!(
            "<tr><td>{} ({})</td><td>{:.4}</td><td>[{lo:.4}, {hi:.4}]</td><td>{:.2}{}</td><td>{}</td><td>{}</td></tr>\n",
            html_escape(name),
            html_escape(&q.unit),
            q.value,
            share,
            if cal.informed(k) {
                ""
            } else {
                " (not informed: posterior ≈ prior)"
            },
            html_escape(&shown),
            flag
        ));
    }
    html.push_str(&format!(
        "</table>\n<p>Width / prior's: ln(hi/lo) of the 95 % interval over ln(hi/lo) of the prior range; at ≥ {} the data did not inform the quantity (a flat posterior gives ≈ 0.95) and its median means little.</p>\n<p>Posterior correlations (ln units):</p>\n<table><tr><th></th>",
        crate::calibrate::UNINFORMED_SHARE
    ));
    for name in &cal.free {
        html.push_str(&format!("<th>{}</th>", html_escape(name)));
    }
    html.push_str("</tr>\n");
    for (a, row) in cal.correlations().iter().enumerate() {
        html.push_str(&format!("<tr><th>{}</th>", html_escape(&cal.free[a])));
        for v in row {
            html.push_str(&format!("<td>{v:+.2}</td>"));
        }
        html.push_str("</tr>\n");
    }
    html.push_str("</table>\n");
    Ok(Section {
        title: "Calibration (ABC-SMC, without clustering)".into(),
        html,
    })
}
