//! HTML of the `reproduce` report (made by `pradar reproduce` and `pradar report`): the Table 1 sections
//! (with the fit plots, the K note and the K_max table), the MPC and cluster section, the
//! stage timings, and the page that gathers them ([`write_index`]).

use super::{html_escape, html_table, kv_table, write_index as write_page, Section};
use crate::cluster::Clustering;
use crate::error::Result;
use crate::export::Table;
use std::path::Path;

/// Everything the `reproduce` page shows, in page order.
pub struct ReproducePage {
    /// Page title.
    pub title: String,
    /// The campaign's name (in the section titles).
    pub name: String,
    /// Campaign summary (key, value).
    pub campaign: Vec<(String, String)>,
    /// The positions' labels (one heat map and one cluster plot each).
    pub labels: Vec<String>,
    /// The predictive check of the fitted model (above Table 1).
    pub check: Section,
    /// Table 1 section body ([`table1_html`]).
    pub table1: String,
    /// Geometry-only Table 1 section body ([`geometry_html`]).
    pub geometry: String,
    /// The MPC and cluster summary (key, value).
    pub mpcs: Vec<(String, String)>,
    /// The maps section.
    pub maps: Section,
    /// The experiments' sections.
    pub experiments: Vec<Section>,
    /// Stage timings (label, s); a stage may run beside others.
    pub timings: Vec<(String, f64)>,
    /// Wall time of the whole job, s.
    pub wall_s: f64,
}

/// Write the `reproduce` page: campaign, energy heat maps, Table 1, the geometry-only
/// Table 1, MPCs and clusters, maps, the experiments, stage timings.
pub fn write_index(path: &Path, page: &ReproducePage) -> Result<()> {
    let mut sections = vec![
        Section {
            title: "Campaign".into(),
            html: kv_table(&page.campaign),
        },
        Section {
            title: "Energy matrices (range vs direction, dB re position peak)".into(),
            html: heat_maps_html(&page.labels),
        },
        page.check.clone(),
        Section {
            title: format!("Table 1 ({})", page.name),
            html: page.table1.clone(),
        },
        Section {
            title: format!("Table 1 of {} without clutter (geometry only)", page.name),
            html: page.geometry.clone(),
        },
        Section {
            title: "MPCs (2-D CLEAN) and clusters (K-means)".into(),
            html: mpcs_html(&page.mpcs, &page.labels),
        },
        page.maps.clone(),
    ];
    sections.extend(page.experiments.iter().cloned());
    sections.push(Section {
        title: "Stage timings".into(),
        html: timings_html(&page.timings, page.wall_s),
    });
    write_page(path, &page.title, &sections)
}

/// The per-position energy heat maps `energy_pNN.png`.
fn heat_maps_html(labels: &[String]) -> String {
    (labels.iter().enumerate())
        .map(|(p, l)| {
            let l = html_escape(l);
            format!("<a href=\"energy_p{p:02}.png\" title=\"position {l}\"><img src=\"energy_p{p:02}.png\" alt=\"position {l}\"></a>\n")
        })
        .collect()
}

/// The MPC summary, the global MPC map and the per-position cluster plots.
fn mpcs_html(summary: &[(String, String)], labels: &[String]) -> String {
    let mut h = kv_table(summary);
    h.push_str("<p>MPCs are marked (white circles) on the energy heat maps above.</p>\n<a href=\"mpcs_global.png\"><img style=\"max-width:900px\" src=\"mpcs_global.png\" alt=\"global\"></a><br>\n");
    for (p, l) in labels.iter().enumerate() {
        let l = html_escape(l);
        h.push_str(&format!("<a href=\"clusters_p{p:02}.png\" title=\"position {l}\"><img src=\"clusters_p{p:02}.png\" alt=\"clusters {l}\"></a>\n"));
    }
    h
}

/// The stage timings with the job's wall time (less than their sum where stages ran side
/// by side).
fn timings_html(timings: &[(String, f64)], wall_s: f64) -> String {
    let total = wall_s;
    let mut rows: Vec<(String, String)> = timings
        .iter()
        .map(|(k, v)| (k.clone(), format!("{v:.2} s")))
        .collect();
    rows.push(("total (wall)".into(), format!("{total:.2} s")));
    kv_table(&rows)
}

/// `<p>not run: {why}</p>` (escaped), a stage that cannot run on this campaign.
pub fn not_run(why: &str) -> String {
    format!("<p>not run: {}</p>", html_escape(why))
}

/// `<p>{what} failed: {error}</p>` (the error escaped).
pub fn failed(what: &str, e: &dyn std::fmt::Display) -> String {
    format!("<p>{what} failed: {}</p>", html_escape(&e.to_string()))
}

/// `<p>not run: the fit gave no model (…)</p>`, the experiments' section when the fit failed.
pub fn experiments_not_run(e: &dyn std::fmt::Display) -> Section {
    Section {
        title: "Experiments".into(),
        html: format!(
            "<p>not run: the fit gave no model ({})</p>",
            html_escape(&e.to_string())
        ),
    }
}

/// `<p>not run: the fitted model leaves … not estimable (…)</p>`, the experiments' section
/// when the fit is partial: their model data (`synth`) need every quantity.
pub fn experiments_not_run_partial(not_estimable: &[(String, String)]) -> Section {
    let which: Vec<String> = not_estimable
        .iter()
        .map(|(q, r)| format!("{q} ({r})"))
        .collect();
    Section {
        title: "Experiments".into(),
        html: format!(
            "<p>not run: the fitted model leaves {} not estimable, and the model data need every quantity</p>",
            html_escape(&which.join(", "))
        ),
    }
}

/// A fit plot of Table 1: `Some(png)` when drawn, `None` when the quantity had fewer than
/// 2 samples.
pub type FitPlot = (String, Option<String>);

/// The fitted Table 1 after its table (`rows_html`, as the pipeline gives
/// it, already closed): the closing note with links and the fit plots.
pub fn table1_fitted_html(name: &str, rows_html: &str, plots: &[FitPlot]) -> String {
    let mut h = rows_html.to_string();
    h.push_str(&format!("<p>From the clusters of {}; reported beside the paper with no pass mark (<a href=\"table1.md\">table1.md</a>, <a href=\"fitted_model.toml\">fitted_model.toml</a>).</p>\n", html_escape(name)));
    for (name, png) in plots {
        match png {
            None => h.push_str(&format!("<p>{name}: fewer than 2 samples, no plot.</p>\n")),
            Some(png) => h.push_str(&format!("<a href=\"{png}\"><img style=\"max-width:640px\" src=\"{png}\" alt=\"{name}\"></a>\n")),
        }
    }
    h
}

/// The Table 1 section: the K note, Table 1 (or why the fit failed) and the K_max table (or
/// why it failed).
pub fn table1_html(k_note: &str, table1: &str, kmax: &str) -> String {
    format!("{k_note}{table1}{kmax}")
}

/// The K_max sensitivity table with its heading and note.
pub fn kmax_html(t: &Table) -> String {
    format!(
        "<h3>Table 1 against the clustering cap K_max</h3>{}<p>Where positions end at the cap, the criterion still preferred more clusters: these values are set by K_max, not found (<a href=\"table1_kmax.md\">table1_kmax.md</a>).</p>\n",
        html_table(t)
    )
}

/// A paragraph on the K chosen per position, saying where K_max bound
/// ([`Clustering::positions_at_k_max`]).
pub fn k_cap_note(c: &Clustering, k_max: usize) -> String {
    let ks: Vec<String> = c.positions.iter().map(|p| p.k.to_string()).collect();
    let capped = c.positions_at_k_max(k_max);
    let mut h = format!("<p>K chosen per position: {}.", ks.join(", "));
    if !capped.is_empty() {
        h.push_str(&format!(
            " <b>K = K_max = {k_max} at {} of {} positions</b>: the criterion still preferred more clusters there, so the cluster counts, and with them Λ, λ, the AoA spread and d_c, are set by K_max rather than found (README, \"Corridor and K_max\").",
            capped.len(),
            c.positions.len()
        ));
    }
    h.push_str("</p>\n");
    h
}

/// The geometry-only Table 1: its rows (`rows_html`, as the pipeline
/// gives), what was simulated and found, and the K note.
pub fn geometry_html(
    rows_html: &str,
    mpcs: usize,
    clusters: usize,
    positions: usize,
    k_note: &str,
) -> String {
    let mut h = rows_html.to_string();
    h.push_str(&format!(
        "<p>The campaign simulated without its <code>[clutter]</code> section: walls (diffuse and specular), corners, edges and objects only; {mpcs} MPCs in {clusters} clusters over {positions} positions. What the chain calls clusters here is the layout's own structure (<a href=\"table1_geometry.md\">table1_geometry.md</a>).</p>\n",
    ));
    h.push_str(k_note);
    h
}
