//! `pradar explore`'s images and page, drawn from its summaries
//! ([`crate::explore::summary`]): per mapper the Pareto plot `pareto_<m>.png`
//! (mean F1 against energy per scan, log scale, one colour per N, bars from the lowest to
//! the highest seed, the front joined) and the heat maps `heatmap_<m>.png` (mean F1 and
//! walls found over N × pulses at the campaign's step, bandwidth and power), and
//! `DIR/index.html` (the verdict, the plots, the summary table, the energy model's
//! constants). [`section`] is the same body for `report --explore`.

use super::{cluster_colour, html_escape, html_table, kv_table, plot_err, register_font, Section};
use crate::error::Result;
use crate::explore::summary::{summary_table, verdict_text, Summary, Verdict};
use crate::explore::EnergyModel;
use plotters::prelude::*;
use std::path::Path;

/// The mappers of the summaries, in order.
fn mappers(s: &[Summary]) -> Vec<&'static str> {
    let mut m: Vec<&'static str> = Vec::new();
    for x in s {
        if !m.contains(&x.mapper) {
            m.push(x.mapper);
        }
    }
    m
}

/// Mean F1 against energy per scan (mJ, log x) for one mapper.
pub fn pareto_plot(path: &Path, s: &[Summary], mapper: &str) -> Result<()> {
    register_font();
    let pts: Vec<&Summary> = s
        .iter()
        .filter(|x| x.mapper == mapper && x.f1.mean.is_finite())
        .collect();
    let mut ns: Vec<usize> = pts.iter().map(|x| x.config.elements).collect();
    ns.sort_unstable();
    ns.dedup();
    let e = |x: &Summary| x.energy_j * 1e3;
    let (mut x0, mut x1) = (f64::MAX, f64::MIN);
    let (mut y0, mut y1) = (f64::MAX, f64::MIN);
    for x in &pts {
        x0 = x0.min(e(x));
        x1 = x1.max(e(x));
        y0 = y0.min(x.f1.min);
        y1 = y1.max(x.f1.max);
    }
    if pts.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 0.0, 1.0);
    }
    let (x0, x1) = (x0 / 1.3, x1 * 1.3);
    let dy = (y1 - y0).max(0.02) * 0.1;
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (760, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{}: map quality against energy per scan",
                    mapper.to_uppercase()
                ),
                ("sans-serif", 17),
            )
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(55)
            .build_cartesian_2d((x0..x1).log_scale(), (y0 - dy)..(y1 + dy))
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_labels(6)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .x_desc("energy per scan (mJ)")
            .y_desc("F1 within one cell (mean over seeds)")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        let mut front: Vec<(f64, f64)> = (pts.iter())
            .filter(|x| x.pareto)
            .map(|x| (e(x), x.f1.mean))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(std::iter::once(PathElement::new(
                front,
                BLACK.stroke_width(1),
            )))
            .map_err(|e| plot_err(path, e))?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(1)));
        for (i, &n) in ns.iter().enumerate() {
            let col = cluster_colour(i);
            let sel: Vec<&&Summary> = pts.iter().filter(|x| x.config.elements == n).collect();
            chart
                .draw_series(sel.iter().map(|x| {
                    PathElement::new(
                        vec![(e(x), x.f1.min), (e(x), x.f1.max)],
                        col.stroke_width(1),
                    )
                }))
                .map_err(|e| plot_err(path, e))?;
            chart
                .draw_series(
                    sel.iter()
                        .map(|x| Circle::new((e(x), x.f1.mean), 4, col.filled())),
                )
                .map_err(|e| plot_err(path, e))?
                .label(format!("N = {n}"))
                .legend(move |(x, y)| Circle::new((x + 8, y), 4, col.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// Mean F1 and walls found over N (rows) × pulses (columns) for one mapper at the slice
/// (step, bandwidth, power); the value written in each cell.
pub fn heat_maps(path: &Path, s: &[Summary], mapper: &str, slice: (f64, f64, f64)) -> Result<()> {
    register_font();
    let sel: Vec<&Summary> = s
        .iter()
        .filter(|x| {
            x.mapper == mapper
                && x.config.step_deg == slice.0
                && x.config.bandwidth_ghz == slice.1
                && x.config.tx_power_dbm == slice.2
        })
        .collect();
    let mut ns: Vec<usize> = sel.iter().map(|x| x.config.elements).collect();
    ns.sort_unstable();
    ns.dedup();
    let mut ps: Vec<usize> = sel.iter().map(|x| x.config.pulses).collect();
    ps.sort_unstable();
    ps.dedup();
    let value = |n: usize, p: usize, walls: bool| {
        sel.iter()
            .find(|x| x.config.elements == n && x.config.pulses == p)
            .map(|x| if walls { x.walls_found.mean } else { x.f1.mean })
    };
    let top = |n: usize| if n >= 2 { n - 1 } else { 1 };
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (960, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let areas = root.split_evenly((1, 2));
        for (area, walls) in areas.iter().zip([false, true]) {
            let vals: Vec<f64> = (ns.iter())
                .flat_map(|&n| ps.iter().filter_map(move |&p| value(n, p, walls)))
                .filter(|v| v.is_finite())
                .collect();
            let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let what = if walls {
                "walls found"
            } else {
                "F1 within one cell"
            };
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!(
                        "{} {what}, {}°, {} GHz, {} dBm",
                        mapper.to_uppercase(),
                        slice.0,
                        slice.1,
                        slice.2
                    ),
                    ("sans-serif", 15),
                )
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(50)
                // `0..k` segmented has k + 1 cells: the last value's is `k`
                .build_cartesian_2d(
                    (0..top(ps.len())).into_segmented(),
                    (0..top(ns.len())).into_segmented(),
                )
                .map_err(|e| plot_err(path, e))?;
            let (ps2, ns2) = (ps.clone(), ns.clone());
            let centre = |v: &SegmentValue<usize>, list: &[usize]| match v {
                SegmentValue::CenterOf(i) => {
                    list.get(*i).map(|x| x.to_string()).unwrap_or_default()
                }
                _ => String::new(),
            };
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(ps.len().max(1))
                .y_labels(ns.len().max(1))
                .x_label_formatter(&move |x| centre(x, &ps2))
                .y_label_formatter(&move |y| centre(y, &ns2))
                .x_desc("pulses per direction")
                .y_desc("elements N")
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(|e| plot_err(path, e))?;
            for (i, &n) in ns.iter().enumerate() {
                for (j, &p) in ps.iter().enumerate() {
                    let Some(v) = value(n, p, walls) else {
                        continue;
                    };
                    let t = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            [
                                (SegmentValue::Exact(j), SegmentValue::Exact(i)),
                                (SegmentValue::Exact(j + 1), SegmentValue::Exact(i + 1)),
                            ],
                            ViridisRGB::get_color(t).filled(),
                        )))
                        .map_err(|e| plot_err(path, e))?;
                    let colour = if t > 0.6 { BLACK } else { WHITE };
                    chart
                        .draw_series(std::iter::once(Text::new(
                            format!("{v:.3}"),
                            (SegmentValue::CenterOf(j), SegmentValue::CenterOf(i)),
                            ("sans-serif", 13).into_font().color(&colour),
                        )))
                        .map_err(|e| plot_err(path, e))?;
                }
            }
        }
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// Draw every mapper's plots into `dir`.
pub fn write_plots(dir: &Path, s: &[Summary], slice: (f64, f64, f64)) -> Result<()> {
    for m in mappers(s) {
        pareto_plot(&dir.join(format!("pareto_{m}.png")), s, m)?;
        heat_maps(&dir.join(format!("heatmap_{m}.png")), s, m, slice)?;
    }
    Ok(())
}

/// The explore section's body; links relative to the page with `prefix` for the explore
/// folder (`""` for its own `index.html`).
pub fn section(
    prefix: &str,
    inputs: &[(String, String)],
    s: &[Summary],
    verdicts: &[Verdict],
    model: &EnergyModel,
) -> Section {
    let mut h = String::new();
    h.push_str("<p>The cheapest configuration within 5 % of the best mean F1 (within one cell, three-class reference, on the building), per mapper, against the paper's setting (400 elements, 1 pulse, 5°):</p>\n<ul>\n");
    for v in verdicts {
        h.push_str(&format!("<li>{}</li>\n", html_escape(&verdict_text(s, v))));
    }
    h.push_str("</ul>\n");
    h.push_str(&kv_table(inputs));
    for m in mappers(s) {
        h.push_str(&format!(
            "<p><a href=\"{prefix}pareto_{m}.png\"><img src=\"{prefix}pareto_{m}.png\" alt=\"Pareto {m}\" style=\"max-width:760px\"></a>\n<a href=\"{prefix}heatmap_{m}.png\"><img src=\"{prefix}heatmap_{m}.png\" alt=\"heat map {m}\" style=\"max-width:960px\"></a></p>\n"
        ));
    }
    h.push_str("<details><summary>every configuration (means over seeds)</summary>\n");
    h.push_str(&html_table(&summary_table(s)));
    h.push_str("</details>\n");
    let body = toml::to_string(model).unwrap_or_default();
    let consts: Vec<(String, String)> = body
        .lines()
        .filter_map(|l| l.split_once(" = "))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    h.push_str("<details><summary>energy model (per scan; docs/explore.md)</summary>\n");
    h.push_str(&kv_table(&consts));
    h.push_str("</details>\n");
    h.push_str(&format!(
        "<p>Files: <a href=\"{prefix}explore.csv\">explore.csv</a> (every configuration, mapper and seed), <a href=\"{prefix}summary.csv\">summary.csv</a>, <a href=\"{prefix}explore.md\">explore.md</a>, <a href=\"{prefix}energy_model.toml\">energy_model.toml</a>, <a href=\"{prefix}timing.csv\">timing.csv</a> (measured seconds per job).</p>\n"
    ));
    Section {
        title: "Design space (explore)".into(),
        html: h,
    }
}

/// `DIR/index.html` of `pradar explore`.
pub fn write_index(dir: &Path, section: &Section) -> Result<()> {
    super::write_index(
        &dir.join("index.html"),
        "pradar explore",
        std::slice::from_ref(section),
    )
}
