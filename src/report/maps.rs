//! The maps section of the `reproduce` report: the occupancy maps (`og`, `og-boresight`)
//! and the EKF RRCS map (`ekf`, scalable filter) of one run, already written under
//! `report_dir/<sub>/<method>/` by the pipeline, shown beside the reference map with their
//! figures and the all-free map's ([`crate::mapping::score::metrics_table`], rendered by
//! [`crate::report::html_table`]).

use crate::mapping::score::{metrics_table, MetricsPair};
use crate::report::{html_escape, html_table, Section};

/// The report section of the maps of one run, written under `report_dir/<sub>/<method>/`
/// (each method's name and figures, in order; the first method's folder holds the
/// reference map): the figures and the metrics table.
pub fn report_section(maps: &[(&str, MetricsPair)], sub: &str) -> Section {
    let mut imgs = String::new();
    let mut rows: Vec<(String, MetricsPair, Option<String>)> = Vec::new();
    for (i, (name, metrics)) in maps.iter().enumerate() {
        if i == 0 {
            imgs.push_str(&format!(
                "<figure><img src=\"{sub}/{name}/reference.png\" alt=\"reference\"><figcaption>reference</figcaption></figure>\n"
            ));
        }
        for stem in [name.to_string(), format!("{name}_binary")] {
            imgs.push_str(&format!(
                "<figure><img src=\"{sub}/{name}/{stem}.png\" alt=\"{stem}\"><figcaption>{}</figcaption></figure>\n",
                html_escape(&stem)
            ));
        }
        rows.push((
            name.to_string(),
            *metrics,
            Some(format!("{sub}/{name}/metrics.json")),
        ));
    }
    if let Some(m) = rows.last().map(|r| r.1.all_free()) {
        rows.push(("all-free map".to_string(), m, None));
    }
    let table = html_table(&metrics_table(&rows));
    let html = format!(
        "<p>Occupancy grids (0.1 m cells; binary map: p &gt; 0.5) and the EKF map over RRCS (scalable filter; binary map: mean − 2·std &gt; μ0). Observable region: cells inside the −3 dB main lobe of some (pose, direction) within the usable bins, not outside the perimeter; whole map: every cell, outside cells counted as free. Detectable walls (a simulated campaign): the wall cells holding a simulator path whose delay bin, summed over the paths of that bin in the main lobe of some (pose, direction) within the usable bins, reaches the detector's threshold — what the sweeps allowed; found within one cell, and their share of the observable wall cells. False cells (a simulated campaign): the free cells marked occupied, each by the strongest single path that explains it — elsewhere on the main lobe's arc at its range, through a side lobe, folded from beyond the unambiguous range, an image beyond the walls — or noise. ψ in cells (lower is better).</p>\n<div>{imgs}</div>\n{table}"
    );
    Section {
        title: "Maps: occupancy grid (side-lobe aware vs boresight) and EKF".into(),
        html,
    }
}
