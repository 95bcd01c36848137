//! Reports: plots (plotters, PNG with a committed font so images are deterministic) and the
//! HTML index (`reports/<name>/index.html`) linking every plot and table.
//!
//! Takes energy matrices, campaign summaries and stage timings; gives per-position heat maps
//! (range vs direction, dB relative to the position's peak) and the index page.
//!
//! All HTML lives here: the shared pieces ([`html_escape`], [`html_table`] for an
//! [`export::Table`](crate::export::Table), [`kv_table`], [`write_index`]) in this file; the
//! `reproduce` page in [`reproduce`], the experiments' sections and page in [`experiments`].

pub mod maps;

use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

pub use crate::export::LineChart;

pub mod calibrate;
pub mod check;
pub mod experiments;
pub mod explore;
pub mod reproduce;

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
/// `marks` are (angle_rel_deg, range_m) points drawn as white circles (extracted MPCs);
/// `label` names the position in the title (the lab's label); a direction without a sweep
/// is left blank.
pub fn energy_heatmap(
    em: &EnergyMatrix,
    p: usize,
    label: &str,
    path: &Path,
    floor_db: f64,
    marks: &[(f64, f64)],
) -> Result<()> {
    register_font();
    let nd = em.directions();
    let nb = em.bins;
    let peak = (0..nd)
        .filter(|&d| em.has(p, d))
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
    let rmax = crate::units::range_m(em.delay_ns(nb - 1));
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (640, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("position {label}: energy (dB re peak)"),
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
        let db = |e: f64| crate::units::db(e.max(1e-300) / peak).max(floor_db);
        let dr = crate::units::range_m(em.meta.bin_width_ns);
        chart
            .draw_series((0..nd).filter(|&d| em.has(p, d)).flat_map(|d| {
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
        chart
            .draw_series(
                marks
                    .iter()
                    .map(|&(a, r)| Circle::new((a, r), 4, WHITE.stroke_width(1))),
            )
            .map_err(|e| plot_err(path, e))?;
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// A distinct colour for cluster `i`.
pub fn cluster_colour(i: usize) -> RGBColor {
    const P: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    P[i % P.len()]
}

/// MPCs of one position in the delay–angle plane, coloured by cluster (`labels` local to the
/// position; None — a diffuse MPC — drawn as a small grey dot), marker size by power.
pub fn mpc_clusters_plot(
    path: &Path,
    title: &str,
    pts: &[(f64, f64, f64)],
    labels: &[Option<usize>],
    max_delay_ns: f64,
) -> Result<()> {
    register_font();
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (560, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(-95.0..95.0, 0.0..max_delay_ns.max(1.0))
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc("angle re heading (deg)")
            .y_desc("delay (ns)")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        let pmax = pts.iter().map(|p| p.2).fold(f64::MIN, f64::max);
        chart
            .draw_series(pts.iter().zip(labels).map(|(&(a, d, pw), &l)| match l {
                Some(l) => {
                    let size = (6.0 + (pw - pmax) / 6.0).clamp(2.0, 6.0) as i32;
                    Circle::new((a, d), size, cluster_colour(l).filled())
                }
                None => Circle::new((a, d), 1, RGBColor(150, 150, 150).filled()),
            }))
            .map_err(|e| plot_err(path, e))?;
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// MPCs (dots, coloured by campaign-wide cluster id; diffuse ones grey) and cluster
/// centroids (crosses) in the global frame over the layout's walls, with the poses (black
/// triangles).
pub fn global_map_plot(
    path: &Path,
    layout: &crate::campaign::Layout,
    poses: &[(f64, f64)],
    mpcs: &[(f64, f64, Option<usize>)],
    centroids: &[(f64, f64, usize)],
) -> Result<()> {
    register_font();
    let bb = layout.bbox();
    let (x0, x1, y0, y1) = (
        bb.min().x - 1.0,
        bb.max().x + 1.0,
        bb.min().y - 1.0,
        bb.max().y + 1.0,
    );
    let w = 1000u32;
    let h = ((w as f64) * (y1 - y0) / (x1 - x0)).clamp(250.0, 1000.0) as u32 + 60;
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "MPCs and cluster centroids, global frame (m)",
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(layout.walls.iter().map(|wl| {
                PathElement::new(
                    vec![
                        (wl.line.start.x, wl.line.start.y),
                        (wl.line.end.x, wl.line.end.y),
                    ],
                    BLACK.stroke_width(2),
                )
            }))
            .map_err(|e| plot_err(path, e))?;
        let clip = |x: f64, y: f64| x > x0 && x < x1 && y > y0 && y < y1;
        chart
            .draw_series(
                mpcs.iter()
                    .filter(|m| clip(m.0, m.1))
                    .map(|&(x, y, c)| match c {
                        Some(c) => Circle::new((x, y), 2, cluster_colour(c).filled()),
                        None => Circle::new((x, y), 1, RGBColor(150, 150, 150).filled()),
                    }),
            )
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(
                centroids
                    .iter()
                    .filter(|m| clip(m.0, m.1))
                    .map(|&(x, y, c)| Cross::new((x, y), 6, cluster_colour(c).stroke_width(2))),
            )
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(
                poses
                    .iter()
                    .map(|&(x, y)| TriangleMarker::new((x, y), 5, BLACK.filled())),
            )
            .map_err(|e| plot_err(path, e))?;
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// Escape text for HTML.
pub fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Render a [`Table`](crate::export::Table) as an HTML `<table>`: a header row of the
/// displayed columns (their HTML header where set), one row per row, text escaped,
/// [`Cell::Link`](crate::export::Cell::Link) cells as links.
pub fn html_table(t: &crate::export::Table) -> String {
    use crate::export::Cell;
    let cols: Vec<usize> = (0..t.columns.len())
        .filter(|&i| t.columns[i].displayed())
        .collect();
    let mut h = String::from("<table><tr>");
    for &i in &cols {
        let c = &t.columns[i];
        let head = c.html_header.as_deref().unwrap_or(&c.header);
        h.push_str(&format!("<th>{}</th>", html_escape(head)));
    }
    h.push_str("</tr>\n");
    for r in &t.rows {
        h.push_str("<tr>");
        for &i in &cols {
            match &r[i] {
                Cell::Link { text, href } => h.push_str(&format!(
                    "<td><a href=\"{}\">{}</a></td>",
                    html_escape(href),
                    html_escape(text)
                )),
                c => h.push_str(&format!("<td>{}</td>", html_escape(c.shown()))),
            }
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    h
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

/// Histogram of `samples` (density-normalised) with the fitted pdf, and the empirical vs
/// fitted CDF beside it.
///
/// The x range is the 0.5 % to 99.5 % quantiles (from 0 when the samples are non-negative),
/// with √n bins (5 to 40); the pdf and CDF are drawn on 201 points of that range.
pub fn fit_plot(
    path: &Path,
    title: &str,
    unit: &str,
    samples: &[f64],
    fitted: &crate::fit::Fitted,
) -> Result<()> {
    register_font();
    if samples.len() < 2 {
        return Err(Error::input(path, "fewer than 2 samples to plot"));
    }
    let mut v = samples.to_vec();
    v.sort_by(f64::total_cmp);
    let hist = Histogram::of(&v);
    let (lo, hi) = (hist.lo, hist.hi);
    let grid: Vec<f64> = (0..=200)
        .map(|i| lo + (hi - lo) * i as f64 / 200.0)
        .collect();
    let pdf: Vec<(f64, f64)> = grid.iter().map(|&x| (x, fitted.pdf(x))).collect();
    let cdf: Vec<(f64, f64)> = grid.iter().map(|&x| (x, fitted.cdf(x))).collect();
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (900, 360)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let (left, right) = root.split_horizontally(450);
        let caption = format!("{title}: histogram, fitted {}", fitted.family.name());
        draw_histogram(&left, path, &caption, unit, &hist, &pdf)?;
        draw_cdfs(&right, path, unit, (lo, hi), &v, &cdf)?;
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// A density-normalised histogram of sorted samples.
struct Histogram {
    /// Range start.
    lo: f64,
    /// Range end.
    hi: f64,
    /// Bin width.
    w: f64,
    /// Density per bin.
    dens: Vec<f64>,
}

impl Histogram {
    /// The histogram of sorted samples `v` (at least 2) over their 0.5–99.5 % range.
    fn of(v: &[f64]) -> Histogram {
        let lo = v[(v.len() as f64 * 0.005) as usize].min(0.0_f64.max(v[0]));
        let hi = v[((v.len() - 1) as f64 * 0.995) as usize];
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 1.0, lo + 1.0)
        };
        let nbins = ((v.len() as f64).sqrt().ceil() as usize).clamp(5, 40);
        let w = (hi - lo) / nbins as f64;
        let mut counts = vec![0usize; nbins];
        for &x in v {
            if x >= lo && x <= hi {
                counts[(((x - lo) / w) as usize).min(nbins - 1)] += 1;
            }
        }
        let dens = counts
            .iter()
            .map(|&c| c as f64 / (v.len() as f64 * w))
            .collect();
        Histogram { lo, hi, w, dens }
    }
}

/// The left chart of [`fit_plot`]: the histogram and the fitted pdf (red).
fn draw_histogram(
    area: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    path: &Path,
    caption: &str,
    unit: &str,
    hist: &Histogram,
    pdf: &[(f64, f64)],
) -> Result<()> {
    let (lo, hi, w) = (hist.lo, hist.hi, hist.w);
    let ymax = (hist.dens.iter())
        .chain(pdf.iter().map(|p| &p.1))
        .cloned()
        .fold(0.0, f64::max)
        .max(1e-12)
        * 1.1;
    let mut c1 = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(50)
        .build_cartesian_2d(lo..hi, 0.0..ymax)
        .map_err(|e| plot_err(path, e))?;
    c1.configure_mesh()
        .x_desc(unit)
        .y_desc("density")
        .label_style(("sans-serif", 11))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    c1.draw_series(hist.dens.iter().enumerate().map(|(i, &d)| {
        let x0 = lo + i as f64 * w;
        Rectangle::new(
            [(x0, 0.0), (x0 + w, d)],
            RGBColor(31, 119, 180).mix(0.5).filled(),
        )
    }))
    .map_err(|e| plot_err(path, e))?;
    c1.draw_series(line_path(pdf.iter().cloned(), RED.stroke_width(2)))
        .map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// The right chart of [`fit_plot`]: the empirical CDF of sorted `v` (black) and the fitted
/// CDF (red).
fn draw_cdfs(
    area: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    path: &Path,
    unit: &str,
    (lo, hi): (f64, f64),
    v: &[f64],
    cdf: &[(f64, f64)],
) -> Result<()> {
    let mut c2 = ChartBuilder::on(area)
        .caption("empirical vs fitted CDF", ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(40)
        .build_cartesian_2d(lo..hi, 0.0..1.0)
        .map_err(|e| plot_err(path, e))?;
    c2.configure_mesh()
        .x_desc(unit)
        .label_style(("sans-serif", 11))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    let n = v.len() as f64;
    c2.draw_series(line_path(
        v.iter().enumerate().map(|(i, &x)| (x, (i + 1) as f64 / n)),
        BLACK.stroke_width(1),
    ))
    .map_err(|e| plot_err(path, e))?;
    c2.draw_series(line_path(cdf.iter().cloned(), RED.stroke_width(2)))
        .map_err(|e| plot_err(path, e))?;
    Ok(())
}

fn line_path(
    points: impl IntoIterator<Item = (f64, f64)>,
    style: ShapeStyle,
) -> std::iter::Once<PathElement<(f64, f64)>> {
    std::iter::once(PathElement::new(
        points.into_iter().collect::<Vec<_>>(),
        style,
    ))
}

/// One tile of a map panel: a title and one RGB colour per grid cell (row-major, row 0 =
/// lowest y, as the map files).
#[derive(Debug, Clone)]
pub struct MapTile {
    /// Title drawn above the tile.
    pub title: String,
    /// Cell colours.
    pub cells: Vec<RGBColor>,
}

/// Colour of a binary map cell scored against the reference: occupied in both black, free in
/// both white, false occupied red, missed occupied blue, outside the perimeter (predicted
/// free) light grey.
pub fn scored_colour(map: bool, reference: crate::mapping::reference::CellClass) -> RGBColor {
    use crate::mapping::reference::CellClass;
    match (map, reference) {
        (true, CellClass::Occupied) => RGBColor(0, 0, 0),
        (false, CellClass::Occupied) => RGBColor(40, 90, 230),
        (true, _) => RGBColor(220, 30, 30),
        (false, CellClass::Free) => RGBColor(255, 255, 255),
        (false, CellClass::Outside) => RGBColor(215, 215, 215),
    }
}

/// Maps side by side: `tiles` on a grid of `columns`, each `rows` × `cols` cells drawn
/// `scale` pixels per cell, titled. Written atomically as PNG.
pub fn map_panel(
    path: &Path,
    rows: usize,
    cols: usize,
    tiles: &[MapTile],
    columns: usize,
) -> Result<()> {
    register_font();
    if tiles.is_empty() || columns == 0 || rows == 0 || cols == 0 {
        return Err(plot_err(path, "empty map panel"));
    }
    if let Some(t) = tiles.iter().find(|t| t.cells.len() != rows * cols) {
        return Err(plot_err(
            path,
            format!(
                "tile `{}` has {} cells, grid {rows} x {cols}",
                t.title,
                t.cells.len()
            ),
        ));
    }
    let scale = (420 / cols).clamp(1, 6) as i32;
    let (tw, th) = (cols as i32 * scale, rows as i32 * scale);
    let (pad, head) = (10, 24);
    let ncol = columns.min(tiles.len()) as i32;
    let nrow = tiles.len().div_ceil(columns) as i32;
    let w = (ncol * (tw + pad) + pad) as u32;
    let h = (nrow * (th + head + pad) + pad) as u32;
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        for (k, t) in tiles.iter().enumerate() {
            let (gx, gy) = ((k % columns) as i32, (k / columns) as i32);
            let x0 = pad + gx * (tw + pad);
            let y0 = pad + gy * (th + head + pad) + head;
            root.draw(&Text::new(
                t.title.clone(),
                (x0, y0 - head + 4),
                ("sans-serif", 14).into_font().color(&BLACK),
            ))
            .map_err(|e| plot_err(path, e))?;
            for r in 0..rows {
                let y = y0 + (rows - 1 - r) as i32 * scale;
                for c in 0..cols {
                    let x = x0 + c as i32 * scale;
                    root.draw(&Rectangle::new(
                        [(x, y), (x + scale, y + scale)],
                        t.cells[r * cols + c].filled(),
                    ))
                    .map_err(|e| plot_err(path, e))?;
                }
            }
            root.draw(&Rectangle::new(
                [(x0 - 1, y0 - 1), (x0 + tw, y0 + th)],
                BLACK.stroke_width(1),
            ))
            .map_err(|e| plot_err(path, e))?;
        }
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// Line charts side by side (one PNG, 480 × 380 pixels per chart), points marked, legend
/// per chart. Written atomically.
pub fn line_plots(path: &Path, charts: &[LineChart]) -> Result<()> {
    register_font();
    if charts.is_empty() {
        return Err(plot_err(path, "no chart"));
    }
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (480 * charts.len() as u32, 380)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let areas = root.split_evenly((1, charts.len()));
        for (area, ch) in areas.iter().zip(charts) {
            let pts = ch.series.iter().flat_map(|s| s.1.iter());
            let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for &(x, y) in pts.filter(|p| p.0.is_finite() && p.1.is_finite()) {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
            if x0 > x1 {
                (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
            }
            let (dx, dy) = ((x1 - x0).max(1e-9) * 0.05, (y1 - y0).max(1e-9) * 0.1);
            let mut chart = ChartBuilder::on(area)
                .caption(&ch.title, ("sans-serif", 15))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(55)
                .build_cartesian_2d((x0 - dx)..(x1 + dx), (y0 - dy)..(y1 + dy))
                .map_err(|e| plot_err(path, e))?;
            chart
                .configure_mesh()
                .x_desc(ch.x_label.as_str())
                .y_desc(ch.y_label.as_str())
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(|e| plot_err(path, e))?;
            for (i, (name, s)) in ch.series.iter().enumerate() {
                let col = cluster_colour(i);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        s.clone(),
                        col.stroke_width(2),
                    )))
                    .map_err(|e| plot_err(path, e))?
                    .label(name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], col.stroke_width(2))
                    });
                chart
                    .draw_series(s.iter().map(|&p| Circle::new(p, 4, col.filled())))
                    .map_err(|e| plot_err(path, e))?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 12))
                .draw()
                .map_err(|e| plot_err(path, e))?;
        }
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}
