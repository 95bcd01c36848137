//! Reports: plots (plotters, PNG with a committed font so images are deterministic) and the
//! HTML index (`reports/<name>/index.html`) linking every plot and table.
//!
//! Takes energy matrices, campaign summaries and stage timings; gives per-position heat maps
//! (range vs direction, dB relative to the position's peak) and the index page.

use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Register the committed font as plotters' "sans-serif" (idempotent).
pub fn register_font() {
    REGISTER.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Plot {
        file: path.to_path_buf(),
        msg: e.to_string(),
    }
}

/// Heat map of one position: direction (x, degrees relative) vs range (y, m = delay·c/2),
/// colour = energy in dB relative to the position's peak, clipped at `floor_db`.
pub fn energy_heatmap(em: &EnergyMatrix, p: usize, path: &Path, floor_db: f64) -> Result<()> {
    register_font();
    crate::io::ensure_parent(path)?;
    let tmp = crate::io::temp_path(path).with_extension("png");
    let nd = em.directions();
    let nb = em.bins;
    let peak = (0..nd)
        .flat_map(|d| em.profile(p, d).iter().copied())
        .fold(f64::MIN_POSITIVE, f64::max);
    let step = if nd > 1 {
        em.angles_rel_deg[1] - em.angles_rel_deg[0]
    } else {
        5.0
    };
    let (a0, a1) = (
        em.angles_rel_deg[0] - step / 2.0,
        em.angles_rel_deg[nd - 1] + step / 2.0,
    );
    let rmax = em.delay_ns(nb - 1) * 0.299_792_458 / 2.0;
    {
        let root = BitMapBackend::new(&tmp, (640, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("position {p}: energy (dB re peak)"),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .right_y_label_area_size(10)
            .build_cartesian_2d(a0..a1, 0.0..rmax)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("direction re heading (deg)")
            .y_desc("range (m)")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        let db = |e: f64| (10.0 * (e.max(1e-300) / peak).log10()).max(floor_db);
        let dr = em.meta.bin_width_ns * 0.299_792_458 / 2.0;
        chart
            .draw_series((0..nd).flat_map(|d| {
                let prof = em.profile(p, d);
                let a = em.angles_rel_deg[d];
                (0..nb).map(move |b| {
                    let v = (db(prof[b]) - floor_db) / (-floor_db);
                    let c = ViridisRGB::get_color(v);
                    let r = b as f64 * dr;
                    Rectangle::new(
                        [
                            (a - step / 2.0, r - dr / 2.0),
                            (a + step / 2.0, r + dr / 2.0),
                        ],
                        c.filled(),
                    )
                })
            }))
            .map_err(|e| plot_err(path, e))?;
        root.present().map_err(|e| plot_err(path, e))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

/// Escape text for HTML.
pub fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A section of the index page.
#[derive(Debug, Clone, Default)]
pub struct Section {
    /// Heading.
    pub title: String,
    /// HTML body (already escaped where needed).
    pub html: String,
}

/// Render a two-column key/value table.
pub fn kv_table(rows: &[(String, String)]) -> String {
    let mut s = String::from("<table>\n");
    for (k, v) in rows {
        s.push_str(&format!(
            "<tr><th>{}</th><td>{}</td></tr>\n",
            html_escape(k),
            html_escape(v)
        ));
    }
    s.push_str("</table>\n");
    s
}

/// Write `index.html` with the given sections.
pub fn write_index(path: &Path, title: &str, sections: &[Section]) -> Result<()> {
    let mut h = String::new();
    h.push_str(&format!(
        "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>body{{font-family:sans-serif;max-width:1300px;margin:auto}} table{{border-collapse:collapse}} td,th{{border:1px solid #ccc;padding:3px 8px;text-align:left}} img{{max-width:420px;margin:4px}}</style></head><body>\n<h1>{t}</h1>\n",
        t = html_escape(title)
    ));
    for s in sections {
        h.push_str(&format!("<h2>{}</h2>\n{}\n", html_escape(&s.title), s.html));
    }
    h.push_str("</body></html>\n");
    crate::io::write_bytes(path, h.as_bytes())
}
