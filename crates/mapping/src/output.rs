//! Map files (DESIGN §3 "Maps"): PNG for people, PGM + YAML (ROS `map_server` convention)
//! for tools. Every file is written atomically.
//!
//! Takes per-cell grey values (row 0 = lowest y, as in [`GridSpec`]); gives:
//! * binary PGM (`P5`, maxval 255), one byte per cell, image row 0 = the grid's TOP row
//!   (highest y), as map_server expects;
//! * YAML: `image`, `resolution` (cell side, m), `origin: [x0, y0, 0.0]` (the lower-left
//!   corner of the grid), `negate: 0`, `occupied_thresh`, `free_thresh`; map_server reads a
//!   pixel v as occupancy p = (255 − v)/255, occupied when p > occupied_thresh, free when
//!   p < free_thresh, unknown otherwise;
//! * PNG (grey, each cell drawn as `scale` × `scale` pixels, same orientation as the PGM).
//!
//! Grey coding: soft maps v = round(255·(1 − p)) (p = 1 black); binary maps occupied 0,
//! free 254; the reference map occupied 0, free 254, outside 205 (map_server's "unknown").

use crate::error::{Error, Result};
use crate::reference::GridSpec;
use plotters::prelude::*;
use std::io::Write;
use std::path::Path;

/// Grey value of a soft map cell of occupancy `p`.
pub fn soft_grey(p: f64) -> u8 {
    (255.0 * (1.0 - p.clamp(0.0, 1.0))).round() as u8
}

/// Grey of an occupied cell in binary maps.
pub const GREY_OCCUPIED: u8 = 0;
/// Grey of a free cell in binary maps.
pub const GREY_FREE: u8 = 254;
/// Grey of an unknown / outside cell.
pub const GREY_UNKNOWN: u8 = 205;

fn check_len(spec: &GridSpec, grey: &[u8], path: &Path) -> Result<()> {
    if grey.len() != spec.len() || spec.is_empty() {
        return Err(Error::input(
            path,
            format!(
                "map has {} cells, grid {} x {}",
                grey.len(),
                spec.rows,
                spec.cols
            ),
        ));
    }
    Ok(())
}

/// Write a binary PGM (P5) with the top (highest y) grid row first.
pub fn write_pgm(path: &Path, spec: &GridSpec, grey: &[u8]) -> Result<()> {
    check_len(spec, grey, path)?;
    crate::io::write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        write!(w, "P5\n{} {}\n255\n", spec.cols, spec.rows).map_err(io)?;
        for r in (0..spec.rows).rev() {
            w.write_all(&grey[r * spec.cols..(r + 1) * spec.cols])
                .map_err(io)?;
        }
        Ok(())
    })
}

/// Write the map_server YAML for `image` (a file name next to the YAML).
pub fn write_yaml(
    path: &Path,
    image: &str,
    spec: &GridSpec,
    occupied_thresh: f64,
    free_thresh: f64,
) -> Result<()> {
    let text = format!(
        "image: {image}\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: {occupied_thresh}\nfree_thresh: {free_thresh}\n",
        spec.cell_m, spec.x0_m, spec.y0_m
    );
    crate::io::write_bytes(path, text.as_bytes())
}

/// Write a grey PNG, each cell `scale` pixels wide, top (highest y) row first.
pub fn write_png(path: &Path, spec: &GridSpec, grey: &[u8], scale: u32) -> Result<()> {
    check_len(spec, grey, path)?;
    let scale = scale.max(1);
    let (w, h) = (spec.cols as u32 * scale, spec.rows as u32 * scale);
    let perr = |e: &dyn std::fmt::Display| Error::Plot {
        file: path.to_path_buf(),
        msg: e.to_string(),
    };
    crate::io::write_rendered(path, "png", |tmp| {
        let root = BitMapBackend::new(tmp, (w, h)).into_drawing_area();
        for r in 0..spec.rows {
            let y0 = (spec.rows - 1 - r) as i32 * scale as i32;
            for c in 0..spec.cols {
                let g = grey[r * spec.cols + c];
                let x0 = c as i32 * scale as i32;
                root.draw(&Rectangle::new(
                    [(x0, y0), (x0 + scale as i32, y0 + scale as i32)],
                    RGBColor(g, g, g).filled(),
                ))
                .map_err(|e| perr(&e))?;
            }
        }
        root.present().map_err(|e| perr(&e))?;
        Ok(())
    })
}

/// Write `<stem>.pgm`, `<stem>.yaml` and `<stem>.png` in `dir`.
pub fn write_map_files(
    dir: &Path,
    stem: &str,
    spec: &GridSpec,
    grey: &[u8],
    occupied_thresh: f64,
    free_thresh: f64,
) -> Result<()> {
    let pgm = format!("{stem}.pgm");
    write_pgm(&dir.join(&pgm), spec, grey)?;
    write_yaml(
        &dir.join(format!("{stem}.yaml")),
        &pgm,
        spec,
        occupied_thresh,
        free_thresh,
    )?;
    let scale = (800 / spec.cols.max(1)).clamp(1, 8) as u32;
    write_png(&dir.join(format!("{stem}.png")), spec, grey, scale)
}
