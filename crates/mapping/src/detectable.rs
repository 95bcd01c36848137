//! The detectable reference of a simulated scene (DESIGN §2 "Reference of a simulated
//! scene"; issue 55): the wall and object cells that some pose and direction of the
//! campaign could have detected. No mapper can find what no beam detected, so a map's
//! walls found among these cells is its score against the ceiling the sweeps allowed
//! ([`crate::metrics::evaluate_detectable`]); the observable region (line of sight within
//! the main lobe and range, [`crate::score`]) and the building stay beside it.
//!
//! Takes `simulate`'s truth paths (`truth/rays.parquet`: every path seen from each position,
//! occlusion by the layout's walls already applied by the simulator, with its reflection
//! point, delay, bearing relative to the heading, kind and boresight received power
//! P = G0²·λc²·|A|²), the run's observation model (poses, directions, the array's pattern at
//! the campaign's N, usable bins) and the run's occupancy-grid detector threshold η_E (the
//! table's N0, its pulses and `pfa`, [`crate::og::detection_threshold`]); gives the cells
//! holding a detectable wall return and those holding a detectable object return
//! ([`DetectableReturns`]).
//!
//! A path r of position p is detectable when, for some direction d whose main lobe holds
//! it (two-way weight within `main_lobe_db` of the direction's peak, as the observable
//! region), the expected energy of its delay bin k in that direction reaches the threshold:
//!
//!   E(p, d, k) = Σ_s P_s · (G_d(θ_s) / G0)² · K(0) ≥ η_E,
//!
//! the sum over the paths s of position p in bin k (delay within the usable bins) and in
//! d's main lobe; a cell holds a detectable return when a detectable path's reflection
//! point lies in it. G_d is the one-way gain of direction d towards the path's bearing θ_s
//! and G0 the peak gain over the directions (the broadside gain of the truth's powers,
//! [`crate::ObservationModel::broadside_weight`]); K(0) the energy of a unit point echo in
//! its own bin when centred there ([`crate::job::window_kernel`], the run's own window,
//! IFFT and bin integration). The choices, each on the ceiling's side:
//! * **a bin's return**, the incoherent (expected) sum of the paths of one bin in the main
//!   lobe: a detection at bin k in direction d is what a mapper places on the arc of cells
//!   at that range in the lobe, so every cell whose path makes up that bin was seen (a wall
//!   at oblique incidence in a wide beam spreads one bin's energy over several cells, none
//!   of which reaches η_E alone);
//! * **the threshold only**: the detector's local-maximum and range-side-lobe tests, noise
//!   (the threshold is the expected energy, not a draw) and an echo straddling two bins
//!   (up to 1.3 dB lower at the Hann kernel's peak) are left out;
//! * **the main lobe only**: a strong return seen through a direction's side lobe is
//!   detected, but a mapper places a detection in the main lobe, so it cannot put that
//!   return at its cell (the −3 dB lobe, as the observable region);
//! * **delays outside the usable bins are not detectable**: a path inside the coupling gate
//!   is never read, and one beyond the last bin folds into the span at another range,
//!   where no mapper can place it at its cell;
//! * paths more than 40 dB below η_E at boresight are skipped before the sum: a bin
//!   would need 10⁴ of them in one main lobe to reach η_E (the zoo's densest walls hold
//!   about one scatterer per 2.5 cm of wall, so a few tens per bin and lobe).
//!
//! Wall returns (`diffuse`, `specular`, `corner`, `edge`) count for the structure: a
//! reflection point on a wall lying exactly on a grid line can round into the cell on the
//! other side of the line (the boundary band), so a wall return whose cell is not a wall
//! cell marks the wall cells among its four neighbours. Object returns (`clutter`,
//! `target`) count for the objects of [`crate::objects`] (an image target beyond a wall is
//! no object and marks nothing).
//!
//! **False cells** (issue 55, item 2): what would explain a free cell (room or beyond
//! the walls, not a wall) that a map marks occupied. Over every (pose, direction) whose
//! main lobe holds the cell within the usable bins, the strongest path of that pose whose
//! apparent delay lies within one bin of the cell's and whose energy in that direction
//! reaches η_E by itself; its kind is the cause ([`FalseCause`]), in this order: *folded*
//! (true delay beyond the unambiguous 1/Δf, apparent delay its remainder), *side lobe*
//! (the path's bearing outside the direction's main lobe), *image* (its reflection point
//! beyond the walls: a multi-bounce path seen through one), *main-lobe arc* (a path in the
//! main lobe at the cell's range, elsewhere on the arc the lobe spans: the detection is
//! the path's, its place along the arc unknown to the mapper); none: *noise* (or weak paths
//! that only add up). A map's false cells are counted per cause
//! ([`crate::metrics::false_cells_by_cause`]).
//!
//! Only `simulate`'s truth has a detectable reference: `synth`'s rays are drawn per pose
//! around each cluster's centroid, not points in the room ([`crate::objects`]), and a
//! measured campaign has no truth.

use crate::error::{Error, Result};
use crate::grid::ObservationModel;
use crate::reference::{CellClass, ReferenceMap};
use geo::Coord;
use std::path::Path;

/// What explains a free cell marked occupied (module docs, "False cells"), in the order the
/// page lists them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FalseCause {
    /// A path in the cell's main lobe at the cell's range, elsewhere on the arc.
    MainLobeArc,
    /// A path at the cell's range seen through the direction's side lobe.
    SideLobe,
    /// A path from beyond the unambiguous range, folded to the cell's range.
    Folded,
    /// A path whose reflection point lies beyond the walls (an image seen through a wall).
    Image,
    /// No path alone reaches the threshold there: noise (or weak paths adding up).
    Noise,
}

/// Rows read from `rays.parquet` per slice.
const SLICE_ROWS: usize = 1 << 20;

/// Paths this far below the threshold at boresight (linear, −40 dB) are skipped (module
/// docs).
const SKIP_BELOW: f64 = 1e-4;

/// The cells holding a detectable return (module docs), row-major on the run's grid.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectableReturns {
    /// Wall cells holding a detectable wall return (or beside one across a grid line).
    pub walls: Vec<bool>,
    /// Cells holding a detectable object return (clutter scatterers, targets).
    pub objects: Vec<bool>,
    /// Per cell, what would explain it if a map marked it occupied where the reference has
    /// free space (module docs, "False cells").
    pub cause: Vec<FalseCause>,
    /// Paths read.
    pub paths: usize,
}

/// One path kept for the sum: position, cell, bearing (rad), boresight bin energy, wall
/// return or not.
struct Kept {
    pose: u32,
    bin: u32,
    cell: u32,
    theta: f64,
    energy: f64,
    wall: bool,
}

/// A path kind's return: `Some(true)` a wall's (`diffuse`, `specular`, `corner`, `edge`),
/// `Some(false)` an object's (`clutter`, `target`), `None` another kind.
fn wall_return(kind: &str) -> Option<bool> {
    match kind {
        "diffuse" | "specular" | "corner" | "edge" => Some(true),
        "clutter" | "target" => Some(false),
        _ => None,
    }
}

/// The truth's `rays.parquet` in a truth folder, when it is `simulate`'s (module docs).
pub fn truth_rays(truth_dir: &Path) -> Option<std::path::PathBuf> {
    let rays = truth_dir.join("rays.parquet");
    (truth_dir.join("scatterers.csv").is_file() && rays.is_file()).then_some(rays)
}

/// The detectable returns of the paths in `rays` and the cause each free cell would have if
/// a map marked it (module docs): `model` the run's observation model at the poses the data
/// were recorded at, `threshold` the detector's η_E, `k0` the energy of a unit point echo
/// centred in its bin, `period_ns` the sweep's unambiguous delay 1/Δf, `reference` the
/// layout's raster on the model's grid.
pub fn detectable_returns(
    rays: &Path,
    model: &ObservationModel,
    threshold: f64,
    k0: f64,
    period_ns: f64,
    reference: &ReferenceMap,
) -> Result<DetectableReturns> {
    if !(threshold.is_finite() && threshold > 0.0 && k0.is_finite() && k0 > 0.0) {
        return Err(Error::param(
            "detection threshold",
            "must be finite and > 0 for the detectable reference",
        ));
    }
    let spec = model.spec;
    if reference.spec != spec {
        return Err(Error::param(
            "cell_m",
            "the reference map is not on the observation model's grid",
        ));
    }
    let n = spec.len();
    let Some(last) = model.bins.checked_sub(1) else {
        return Ok(DetectableReturns {
            walls: vec![false; n],
            objects: vec![false; n],
            cause: vec![FalseCause::Noise; n],
            paths: 0,
        });
    };
    let last_bin = last as f64;
    let rows = crate::table::parquet_rows(rays)?;
    let bin_ns = model.bin_width_s * 1e9;
    let skip = threshold * SKIP_BELOW;
    let mut kept: Vec<Kept> = Vec::new();
    let mut strong: Vec<Strong> = Vec::new();
    let mut offset = 0;
    while offset < rows {
        let len = SLICE_ROWS.min(rows - offset);
        let df = crate::table::read_parquet(rays, Some((offset, len)))?;
        let pose = crate::table::i64_column(rays, &df, "position")?;
        let x = crate::table::f64_column(rays, &df, "x_m")?;
        let y = crate::table::f64_column(rays, &df, "y_m")?;
        let delay = crate::table::f64_column(rays, &df, "delay_ns")?;
        let angle = crate::table::f64_column(rays, &df, "angle_rel_deg")?;
        let power = crate::table::db_column(rays, &df, "power_db")?;
        let kind = crate::table::str_column(rays, &df, "kind")?
            .ok_or_else(|| Error::input(rays, "missing column `kind`"))?;
        for i in 0..pose.len() {
            let p = pose[i];
            if p < 0 || p as usize >= model.poses.len() {
                return Err(Error::input(
                    rays,
                    format!(
                        "column `position` row {}: {p} is not one of the campaign's {} poses",
                        offset + i,
                        model.poses.len()
                    ),
                ));
            }
            let energy = 10f64.powf(power[i] / 10.0) * k0;
            if !energy.is_finite() {
                return Err(Error::input(
                    rays,
                    format!(
                        "column `power_db` row {}: {} dB is not a received power",
                        offset + i,
                        power[i]
                    ),
                ));
            }
            if energy < skip {
                continue;
            }
            if energy >= threshold {
                // a path that alone reaches η_E at boresight: a candidate cause of false
                // cells, at its apparent (folded) delay
                let folded = period_ns.is_finite() && delay[i] >= period_ns;
                let apparent = if folded {
                    delay[i].rem_euclid(period_ns)
                } else {
                    delay[i]
                };
                let b = (apparent / bin_ns).round();
                if b >= model.min_bin as f64 && b <= last_bin {
                    // a wall's own return is never an image (a point on a wall lying on a
                    // grid line can round into the cell beyond it)
                    let outside = wall_return(&kind[i]) != Some(true)
                        && spec
                            .cell_of(Coord { x: x[i], y: y[i] })
                            .is_none_or(|(r, c)| {
                                reference.cells[r * spec.cols + c] == CellClass::Outside
                            });
                    strong.push(Strong {
                        pose: p as u32,
                        bin: b as u32,
                        theta: angle[i].to_radians(),
                        energy,
                        folded,
                        outside,
                    });
                }
            }
            let bin = (delay[i] / bin_ns).round();
            if bin < model.min_bin as f64 || bin > last_bin {
                continue;
            }
            let Some((r, c)) = spec.cell_of(Coord { x: x[i], y: y[i] }) else {
                continue;
            };
            let Some(wall) = wall_return(&kind[i]) else {
                continue;
            };
            kept.push(Kept {
                pose: p as u32,
                bin: bin as u32,
                cell: (r * spec.cols + c) as u32,
                theta: angle[i].to_radians(),
                energy,
                wall,
            });
        }
        offset += len;
    }
    kept.sort_by_key(|k| (k.pose, k.bin, k.cell));
    let mut walls = vec![false; n];
    let mut objects = vec![false; n];
    let main = model.params.main_weight();
    for group in kept.chunk_by(|a, b| (a.pose, a.bin) == (b.pose, b.bin)) {
        for d in 0..model.directions() {
            // only a direction whose main lobe holds a path places it at its cell
            let in_lobe = |k: &&Kept| model.weight(d, k.theta) >= main;
            let e: f64 = group
                .iter()
                .filter(in_lobe)
                .map(|k| k.energy * model.broadside_weight(d, k.theta))
                .sum();
            if e < threshold {
                continue;
            }
            for k in group.iter().filter(in_lobe) {
                if k.wall {
                    mark_wall(&mut walls, k.cell as usize, reference);
                } else {
                    objects[k.cell as usize] = true;
                }
            }
        }
    }
    let cause = false_causes(&mut strong, model, threshold, reference);
    Ok(DetectableReturns {
        walls,
        objects,
        cause,
        paths: rows,
    })
}

/// A path that alone reaches η_E at boresight, at its apparent bin.
struct Strong {
    pose: u32,
    bin: u32,
    theta: f64,
    energy: f64,
    folded: bool,
    outside: bool,
}

/// Per cell, the cause a free cell marked occupied would have (module docs): over every
/// (pose, direction) whose main lobe holds the cell within the usable bins, the strongest
/// path of that pose within one bin of the cell's whose energy in that direction reaches
/// η_E; its kind is the cause.
fn false_causes(
    strong: &mut [Strong],
    model: &ObservationModel,
    threshold: f64,
    reference: &ReferenceMap,
) -> Vec<FalseCause> {
    use rayon::prelude::*;
    strong.sort_by_key(|k| (k.pose, k.bin));
    let main = model.params.main_weight();
    let n = model.spec.len();
    let groups: Vec<&[Strong]> = strong.chunk_by(|a, b| a.pose == b.pose).collect();
    let per_pose: Vec<Vec<(u32, f64, FalseCause)>> = groups
        .par_iter()
        .map(|g| {
            let p = g[0].pose as usize;
            let geom = model.pose_geometry(p);
            let mut by_bin: Vec<Vec<&Strong>> = vec![Vec::new(); model.bins];
            for k in g.iter() {
                by_bin[k.bin as usize].push(k);
            }
            let mut out = Vec::new();
            for d in 0..model.directions() {
                let beam = model.beam(&geom, d);
                let bins = model.bins.min(beam.ptr.len().saturating_sub(1));
                for k in 0..bins {
                    let lo = k.saturating_sub(1);
                    let hi = (k + 1).min(model.bins - 1);
                    // the strongest path within one bin reaching η_E in direction d (the
                    // same for every cell of the bin)
                    let mut best: Option<(f64, FalseCause)> = None;
                    for s in (lo..=hi).flat_map(|b| by_bin[b].iter()) {
                        let e = s.energy * model.broadside_weight(d, s.theta);
                        if e < threshold || best.is_some_and(|b| b.0 >= e) {
                            continue;
                        }
                        let cause = if s.folded {
                            FalseCause::Folded
                        } else if model.weight(d, s.theta) < main {
                            FalseCause::SideLobe
                        } else if s.outside {
                            FalseCause::Image
                        } else {
                            FalseCause::MainLobeArc
                        };
                        best = Some((e, cause));
                    }
                    let Some((e, cause)) = best else { continue };
                    for j in beam.bin_range(k) {
                        let cell = beam.cell[j];
                        if (beam.weight[j] as f64) < main
                            || reference.cells[cell as usize] == CellClass::Occupied
                        {
                            continue;
                        }
                        out.push((cell, e, cause));
                    }
                }
            }
            out
        })
        .collect();
    let mut energy = vec![0.0f64; n];
    let mut cause = vec![FalseCause::Noise; n];
    for v in per_pose {
        for (cell, e, c) in v {
            let i = cell as usize;
            if e > energy[i] {
                energy[i] = e;
                cause[i] = c;
            }
        }
    }
    cause
}

/// Mark the wall cell `cell`, or (not a wall cell: a wall on a grid line rounded to the
/// other side) the wall cells among its four neighbours.
fn mark_wall(walls: &mut [bool], cell: usize, reference: &ReferenceMap) {
    let (rows, cols) = (reference.spec.rows, reference.spec.cols);
    let is_wall = |c: usize| reference.cells[c] == CellClass::Occupied;
    if is_wall(cell) {
        walls[cell] = true;
        return;
    }
    let (r, c) = (cell / cols, cell % cols);
    let mut near = Vec::with_capacity(4);
    if r > 0 {
        near.push(cell - cols);
    }
    if r + 1 < rows {
        near.push(cell + cols);
    }
    if c > 0 {
        near.push(cell - 1);
    }
    if c + 1 < cols {
        near.push(cell + 1);
    }
    for x in near {
        if is_wall(x) {
            walls[x] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::layout::Layout;
    use crate::campaign::manifest::Campaign;
    use crate::params::ParamGuard;
    use crate::reference::LayoutRaster;
    use crate::table::{col, frame, write_parquet};
    use crate::GridParams;

    /// The built-in corridor's first pose (0.5, −0.3), heading 0, 5° directions, N = 400;
    /// η = 1e-12 and K(0) = 1, so a path of boresight power η·x has energy η·x.
    fn corridor_model() -> (ObservationModel, ReferenceMap) {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/corridor");
        let c = Campaign::load(&Path::new(dir).join("campaign.toml")).unwrap();
        let layout = Layout::load(&Path::new(dir).join("layout.geojson")).unwrap();
        let grid = GridParams::default().check().unwrap();
        let reference = layout.rasterize(grid.cell_m, grid.margin_m);
        let model =
            ObservationModel::new(reference.spec, &grid, &c.manifest, 480, 1.0 / 6.0, 20).unwrap();
        (model, reference)
    }

    const ETA: f64 = 1e-12;

    /// A test path: (kind, x, y, bearing relative to the heading in degrees, energy in
    /// units of η, delay in ns: the round trip from pose 0 when `None`).
    type Path6<'a> = (&'a str, f64, f64, f64, f64, Option<f64>);

    fn write_rays(path: &Path, rows: &[Path6]) {
        let (px, py) = (0.5, -0.3);
        let delay = |r: &Path6| {
            r.5.unwrap_or(2.0 * (r.1 - px).hypot(r.2 - py) / 0.299_792_458)
        };
        let df = frame(
            path,
            vec![
                col("position", rows.iter().map(|_| 0i32).collect::<Vec<_>>()),
                col(
                    "kind",
                    rows.iter().map(|r| r.0.to_string()).collect::<Vec<_>>(),
                ),
                col("x_m", rows.iter().map(|r| r.1).collect::<Vec<_>>()),
                col("y_m", rows.iter().map(|r| r.2).collect::<Vec<_>>()),
                col("delay_ns", rows.iter().map(delay).collect::<Vec<_>>()),
                col(
                    "angle_rel_deg",
                    rows.iter().map(|r| r.3).collect::<Vec<_>>(),
                ),
                col(
                    "power_db",
                    rows.iter()
                        .map(|r| 10.0 * (r.4 * ETA).log10())
                        .collect::<Vec<_>>(),
                ),
            ],
        )
        .unwrap();
        write_parquet(path, &df, Vec::new()).unwrap();
    }

    fn cell(model: &ObservationModel, x: f64, y: f64) -> usize {
        let (r, c) = model.spec.cell_of(Coord { x, y }).unwrap();
        r * model.spec.cols + c
    }

    /// A wall return at 2η is detectable and one at 0.6η is not; two at 0.6η in one bin
    /// add to 1.2η and are, in two cells; a strong path inside the coupling gate or beyond
    /// the last bin is not; a clutter path marks the objects, not the walls; a foot
    /// point on the north wall (a grid line) marks the wall cell beside it; a position the
    /// campaign does not have is one error naming the file.
    #[test]
    fn a_path_is_detectable_when_its_bin_reaches_the_threshold() {
        let dir = tempfile::tempdir().unwrap();
        let rays = dir.path().join("rays.parquet");
        let (model, reference) = corridor_model();
        let north = 1.0; // the north wall's y (a grid line)
        let at45 = 0.5 + 1.3; // bearing 45° on the north wall
        let at30 = 0.5 + 1.3 / 30f64.to_radians().tan();
        let at45_ns = 2.0 * 1.3 * 2f64.sqrt() / 0.299_792_458;
        write_rays(
            &rays,
            &[
                ("specular", 0.5, north, 90.0, 2.0, None),
                (
                    "diffuse",
                    at45 - 0.04,
                    north + 1e-9,
                    45.0,
                    0.6,
                    Some(at45_ns),
                ),
                (
                    "diffuse",
                    at45 + 0.05,
                    north + 1e-9,
                    45.0,
                    0.6,
                    Some(at45_ns),
                ),
                ("diffuse", at30, north + 1e-9, 30.0, 0.6, None),
                ("specular", 0.5, -1.0, -90.0, 100.0, Some(200.0)),
                ("clutter", 0.5, 0.0, 90.0, 100.0, None),
                ("clutter", 3.05, -0.3, 0.0, 2.0, None),
            ],
        );
        let d = detectable_returns(&rays, &model, ETA, 1.0, f64::INFINITY, &reference).unwrap();
        let wall = |x: f64| -> bool {
            // the wall cell at x on the north wall: the one the rasteriser gave the wall
            let (a, b) = (cell(&model, x, north - 0.05), cell(&model, x, north + 0.05));
            let is = |c: usize| reference.cells[c] == CellClass::Occupied;
            assert!(is(a) ^ is(b), "one wall cell across the line at x = {x}");
            d.walls[if is(a) { a } else { b }]
        };
        assert!(wall(0.55), "the 2η specular foot is detectable");
        assert!(
            wall(at45 - 0.04) && wall(at45 + 0.05),
            "two 0.6η returns in one bin add up, each cell seen"
        );
        assert!(!wall(at30), "a single 0.6η return is not detectable");
        assert!(
            !d.walls[cell(&model, 0.55, -1.0)],
            "a return beyond the last bin is not"
        );
        assert!(
            !d.objects[cell(&model, 0.55, 0.05)],
            "a gated return is not"
        );
        assert!(d.objects[cell(&model, 3.05, -0.3)]);
        assert_eq!(d.walls.iter().filter(|&&w| w).count(), 3);
        assert_eq!(d.objects.iter().filter(|&&o| o).count(), 1);
        assert_eq!(d.paths, 7);
        // every cell left without a strong path in reach is noise
        assert_eq!(d.cause[cell(&model, -0.5, 0.5)], FalseCause::Noise);
        let mut m = model.clone();
        m.poses.clear();
        let e = detectable_returns(&rays, &m, ETA, 1.0, f64::INFINITY, &reference).unwrap_err();
        assert!(e.to_string().contains("rays.parquet") && e.to_string().contains("position"));
    }

    /// A false cell's cause: a 10⁴η path 2.5 m straight ahead explains the free cells at its
    /// range in direction 0's main lobe (main-lobe arc; at N = 400 the lobe at 2.5 m is about
    /// one cell wide, so the cell tested is the path's own, which the scoring leaves out as
    /// an object's zone) and, through side lobes, cells at its
    /// range that other directions' main lobes hold (side lobe); the same path with its delay
    /// one period later (from beyond the unambiguous range) explains them as folded; a
    /// path whose reflection point lies beyond the walls as an image; no path: noise.
    #[test]
    fn a_free_cell_is_explained_by_the_strongest_path_at_its_range() {
        let dir = tempfile::tempdir().unwrap();
        let rays = dir.path().join("rays.parquet");
        let (model, reference) = corridor_model();
        let ahead = 16.0 / 0.299_792_458 * 2.5 / 8.0; // 2.5 m round trip, ns
        let causes = |rows: &[Path6], period: f64| {
            write_rays(&rays, rows);
            detectable_returns(&rays, &model, ETA, 1.0, period, &reference)
                .unwrap()
                .cause
        };
        let c = causes(&[("clutter", 3.0, -0.3, 0.0, 1e4, Some(ahead))], 100.0);
        let here = cell(&model, 3.05, -0.25);
        assert_eq!(c[here], FalseCause::MainLobeArc);
        let side: Vec<usize> = (0..c.len())
            .filter(|&i| c[i] == FalseCause::SideLobe)
            .collect();
        assert!(!side.is_empty(), "side-lobe cells at the path's range");
        for &i in &side {
            let p = model.spec.center(i / model.spec.cols, i % model.spec.cols);
            let r = (p.x - 0.5).hypot(p.y + 0.3);
            assert!((r - 2.5).abs() < 0.15, "a side-lobe cell at {r:.2} m");
        }
        assert_eq!(c[cell(&model, -0.5, 0.5)], FalseCause::Noise);
        let c = causes(
            &[("clutter", 3.0, -0.3, 0.0, 1e4, Some(ahead + 100.0))],
            100.0,
        );
        assert_eq!(c[here], FalseCause::Folded);
        let c = causes(&[("target", 3.0, -1.3, 0.0, 1e4, Some(ahead))], 100.0);
        assert_eq!(
            c[here],
            FalseCause::Image,
            "reflection point beyond the south wall"
        );
    }
}
