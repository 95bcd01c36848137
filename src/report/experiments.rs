//! The mapping experiments' images and HTML, drawn from their results
//! ([`crate::mapping::experiment::ExperimentResult`]; the experiments never call this
//! module): each experiment's panel `NAME/NAME.png` and curves `NAME/NAME_plot.png`, its
//! report section (caption, panel, plots, findings, the "every map" table, file links) and
//! the `pradar experiment` index page.
//!
//! Links inside a section are written with the placeholder `{P}` for the experiments folder
//! relative to the page, replaced by [`section`]: the same section serves
//! `DIR/index.html` (`""`) and the `reproduce` report (`"experiments/"`).

use super::{html_escape, html_table, kv_table, write_index as write_page, MapTile, Section};
use crate::error::Result;
use crate::export::{Cell, Column, Table};
use crate::mapping::experiment::{score_columns, CaseFigures, ExperimentResult, Figure};
use std::path::Path;

/// The section body of one experiment: caption, panel, figures (may use `{P}`), findings,
/// the "every map" table and links to the experiment's files.
pub fn result_html(r: &ExperimentResult) -> String {
    let name = r.name.as_str();
    let extra: String = r
        .figures
        .iter()
        .map(|f| match f {
            Figure::EkfMeans(keys) => ekf_mean_figures(keys),
            Figure::Plot(alt) => plot_img(name, alt),
        })
        .collect();
    let mut html = format!(
        "<p>{}</p>\n<a href=\"{{P}}{name}/{name}.png\"><img src=\"{{P}}{name}/{name}.png\" alt=\"{name}\" style=\"max-width:1280px\"></a>\n{extra}",
        html_escape(&r.caption)
    );
    html.push_str(&kv_table(&r.findings));
    html.push_str("<details><summary>every map</summary>\n");
    html.push_str(&html_table(&every_map_table(&r.cases)));
    html.push_str(&format!(
        "</details>\n<p>Files: <a href=\"{{P}}{name}/{name}.md\">{name}.md</a>, <a href=\"{{P}}{name}/{name}.csv\">{name}.csv</a>, <a href=\"{{P}}{name}/{name}.json\">{name}.json</a>.</p>\n"
    ));
    html
}

/// The "every map" table: each map linked to its `metrics.json`, with ψ, wrong cells and F1
/// on the three regions.
pub fn every_map_table(cases: &[CaseFigures]) -> Table {
    let mut columns = vec![Column::new("map", "map")];
    columns.extend(score_columns());
    let mut t = Table::new(columns);
    for c in cases {
        let mut row = vec![Cell::Link {
            text: c.key.clone(),
            href: format!("{{P}}maps/{}/metrics.json", c.key),
        }];
        row.extend(c.score_cells());
        t.push(row);
    }
    t
}

/// fig5's figures of the EKF mean RRCS of the maps `keys`.
pub fn ekf_mean_figures(keys: &[String]) -> String {
    keys.iter()
        .map(|k| format!(
            "<figure><img src=\"{{P}}maps/{k}/ekf_mean.png\" alt=\"{k}\"><figcaption>mean RRCS, {k}</figcaption></figure>\n"
        ))
        .collect()
}

/// The experiment's curve plot `{P}<name>/<name>_plot.png`.
pub fn plot_img(name: &str, alt: &str) -> String {
    format!("<img src=\"{{P}}{name}/{name}_plot.png\" alt=\"{alt}\" style=\"max-width:960px\">\n")
}

/// Draw a result's images into the experiments folder `out`: the panel `NAME/NAME.png`
/// (each map coloured against the reference by [`super::scored_colour`]) and, when it has
/// curves, `NAME/NAME_plot.png`.
pub fn write_figures(r: &ExperimentResult, out: &Path) -> Result<()> {
    let name = r.name.as_str();
    let dir = out.join(name);
    let p = &r.panel;
    let tiles: Vec<MapTile> = p
        .tiles
        .iter()
        .map(|t| MapTile {
            title: t.title.clone(),
            cells: t
                .occupied
                .iter()
                .zip(&p.reference.cells)
                .map(|(&b, &c)| super::scored_colour(b, c))
                .collect(),
        })
        .collect();
    let s = p.reference.spec;
    super::map_panel(
        &dir.join(format!("{name}.png")),
        s.rows,
        s.cols,
        &tiles,
        p.columns,
    )?;
    if !r.charts.is_empty() {
        super::line_plots(&dir.join(format!("{name}_plot.png")), &r.charts)?;
    }
    Ok(())
}

/// The report section of a result, links prefixed by `prefix` (the experiments folder
/// relative to the page: `""` for `DIR/index.html`, `"experiments/"` in `reproduce`).
pub fn section(r: &ExperimentResult, prefix: &str) -> Section {
    let title = match r.name.as_str() {
        "fig5" => "Experiment fig5: EKF maps from the campaign's sweeps and from model data",
        "fig6" => "Experiment fig6: OG vs EKF, N = 16 vs N = 100 (model data)",
        "prior-sensitivity" => "Experiment prior-sensitivity: OG prior and EKF μ0 ±40 %",
        "slam" => "Experiment slam: maps with true, dead-reckoned and estimated poses",
        _ => "Experiment pose-noise: ψ as pose noise grows",
    };
    Section {
        title: title.into(),
        html: result_html(r).replace("{P}", prefix),
    }
}

/// `pradar experiment`'s `index.html`: the inputs used, then each result's section.
pub fn write_index(
    path: &Path,
    inputs: &[(String, String)],
    results: &[ExperimentResult],
) -> Result<()> {
    let mut sections = vec![Section {
        title: "Inputs".into(),
        html: kv_table(inputs),
    }];
    sections.extend(results.iter().map(|r| section(r, "")));
    write_page(path, "pradar experiments", &sections)
}

/// `pradar experiment`'s images and page in `out`: every result's [`write_figures`], then
/// [`write_index`] as `out/index.html`.
pub fn write_all(
    out: &Path,
    inputs: &[(String, String)],
    results: &[ExperimentResult],
) -> Result<()> {
    for r in results {
        write_figures(r, out)?;
    }
    write_index(&out.join("index.html"), inputs, results)
}
