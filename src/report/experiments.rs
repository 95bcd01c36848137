//! HTML of the mapping experiments ([`crate::pipeline::experiment`]): each experiment's
//! report section (caption, panel, plots, findings, the "every map" table, file links) and
//! the `pradar experiment` index page.
//!
//! Links inside a section are written with the placeholder `{P}` for the experiments folder
//! relative to the page, replaced by [`section`]: the same section serves
//! `DIR/index.html` (`""`) and the `reproduce` report (`"experiments/"`).

use super::{html_escape, html_table, kv_table, write_index as write_page, Section};
use crate::error::Result;
use crate::export::{Cell, Column, Table};
use crate::pipeline::experiment::lab::score_columns;
use crate::pipeline::experiment::{CaseFigures, ExperimentResult};
use std::path::Path;

/// The section body of one experiment: caption, panel, `extra` (plots; may use `{P}`),
/// findings, the "every map" table and links to the experiment's files.
pub fn result_html(
    name: &str,
    caption: &str,
    extra: &str,
    findings: &[(String, String)],
    cases: &[CaseFigures],
) -> String {
    let mut html = format!(
        "<p>{}</p>\n<a href=\"{{P}}{name}/{name}.png\"><img src=\"{{P}}{name}/{name}.png\" alt=\"{name}\" style=\"max-width:1280px\"></a>\n{extra}",
        html_escape(caption)
    );
    html.push_str(&kv_table(findings));
    html.push_str("<details><summary>every map</summary>\n");
    html.push_str(&html_table(&every_map_table(cases)));
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
pub fn ekf_mean_figures(keys: &[&str]) -> String {
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

/// The report section of a result, links prefixed by `prefix` (the experiments folder
/// relative to the page: `""` for `DIR/index.html`, `"experiments/"` in `reproduce`).
pub fn section(r: &ExperimentResult, prefix: &str) -> Section {
    let title = match r.name.as_str() {
        "fig5" => "Experiment fig5: EKF maps from the campaign's sweeps and from model data",
        "fig6" => "Experiment fig6: OG vs EKF, N = 16 vs N = 100 (model data)",
        "prior-sensitivity" => "Experiment prior-sensitivity: OG prior and EKF μ0 ±40 %",
        _ => "Experiment pose-noise: ψ as pose noise grows",
    };
    Section {
        title: title.into(),
        html: r.html.replace("{P}", prefix),
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
