//! The objects of a simulated scene's truth, for scoring only (DESIGN §2, "Reference of a
//! simulated scene"): what is physically in the room but not in the layout. No mapper reads
//! them; [`super::score`] scores every map against them beside the layout-only figures.
//!
//! Where the truth is found ([`find_truth`], first that exists): `<energy stem>_truth/`
//! beside the energy table (what `synth` writes by default: model data are mapped with the
//! campaign they were drawn for, whose own `truth/` is the simulator's scene, not what the
//! model drew), then `truth/` beside the campaign manifest (what `simulate` writes). A
//! measured campaign has neither, and is scored on the layout's classes only.
//!
//! What an object is ([`load_objects`]):
//! * `simulate`'s truth (`scatterers.csv`): each clutter cluster (the cells of its
//!   scatterers) and each target inside the layout's free space (its cell). A target
//!   outside the free space is a multi-bounce image seen through a wall (`via_m`): it is
//!   seen, not there, so it is no object (its cells stay "beyond the walls");
//! * `synth`'s truth (`clusters.csv`, no `scatterers.csv`): each cluster's centroid cell.
//!   Synth's rays are drawn per pose around the centroid (excess delays, AoA offsets), so
//!   they are not points in the room; the centroid is the cluster's one fixed place.

use crate::campaign::layout::Layout;
use crate::error::{Error, Result};
use crate::reference::GridSpec;
use geo::Coord;
use std::path::{Path, PathBuf};

/// The objects of a truth on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Objects {
    /// The truth folder read.
    pub source: PathBuf,
    /// `scatterers` (simulate) or `centroids` (synth).
    pub kind: &'static str,
    /// Each object's cells (row-major indices), none empty.
    pub cells: Vec<Vec<usize>>,
}

/// The truth folder of a run, if any (module docs).
pub fn find_truth(campaign: &Path, energy: &Path) -> Option<PathBuf> {
    let synth = crate::model::synth::default_truth_dir(energy);
    if synth.join("clusters.csv").is_file() {
        return Some(synth);
    }
    let beside = campaign.parent().unwrap_or(Path::new(".")).join("truth");
    beside.join("scatterers.csv").is_file().then_some(beside)
}

/// Rows of a plain CSV file (header, comma-separated, no quoting) as (header, rows).
fn read_rows(path: &Path) -> Result<(Vec<String>, Vec<Vec<String>>)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .ok_or_else(|| Error::input(path, "empty file"))?
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|s| s.trim().to_string()).collect())
        .collect();
    Ok((header, rows))
}

fn column(path: &Path, header: &[String], name: &str) -> Result<usize> {
    header
        .iter()
        .position(|h| h == name)
        .ok_or_else(|| Error::input(path, format!("no column `{name}`")))
}

fn number(path: &Path, line: usize, v: &str) -> Result<f64> {
    v.parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| Error::input(path, format!("line {line}: `{v}` is not a finite number")))
}

/// The objects of the truth in `dir` on the grid `spec` (module docs); points off the grid
/// are dropped.
pub fn load_objects(dir: &Path, layout: &Layout, spec: GridSpec) -> Result<Objects> {
    let cell = |x: f64, y: f64| spec.cell_of(Coord { x, y }).map(|(r, c)| r * spec.cols + c);
    let scatterers = dir.join("scatterers.csv");
    if scatterers.is_file() {
        let p = scatterers.as_path();
        let (h, rows) = read_rows(p)?;
        let (k, x, y, cl) = (
            column(p, &h, "kind")?,
            column(p, &h, "x_m")?,
            column(p, &h, "y_m")?,
            column(p, &h, "cluster_id")?,
        );
        let mut clusters: std::collections::BTreeMap<i64, Vec<usize>> = Default::default();
        let mut targets = Vec::new();
        for (i, r) in rows.iter().enumerate() {
            let line = i + 2;
            let get = |j: usize| r.get(j).map(String::as_str).unwrap_or("");
            let kind = get(k);
            if kind != "clutter" && kind != "target" {
                continue;
            }
            let (px, py) = (number(p, line, get(x))?, number(p, line, get(y))?);
            let Some(c) = cell(px, py) else { continue };
            if kind == "target" {
                if layout.is_free(Coord { x: px, y: py }) {
                    targets.push(vec![c]);
                }
            } else {
                let id = number(p, line, get(cl))? as i64;
                let v = clusters.entry(id).or_default();
                if !v.contains(&c) {
                    v.push(c);
                }
            }
        }
        let mut cells: Vec<Vec<usize>> = clusters.into_values().collect();
        cells.extend(targets);
        return Ok(Objects {
            source: dir.to_path_buf(),
            kind: "scatterers",
            cells,
        });
    }
    let clusters = dir.join("clusters.csv");
    let p = clusters.as_path();
    let (h, rows) = read_rows(p)?;
    let (x, y) = (column(p, &h, "x_m")?, column(p, &h, "y_m")?);
    let mut cells = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let get = |j: usize| r.get(j).map(String::as_str).unwrap_or("");
        let (px, py) = (number(p, i + 2, get(x))?, number(p, i + 2, get(y))?);
        if let Some(c) = cell(px, py) {
            cells.push(vec![c]);
        }
    }
    Ok(Objects {
        source: dir.to_path_buf(),
        kind: "centroids",
        cells,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::LayoutRaster;

    fn corridor() -> Layout {
        let p = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/corridor/layout.geojson"
        );
        Layout::load(Path::new(p)).unwrap()
    }

    /// simulate's truth: two clutter clusters (one of two scatterers in one cell, one of two
    /// cells), a target in the room and a target beyond the north wall (an image): three
    /// objects; diffuse and corner rows are not objects.
    #[test]
    fn simulate_truth_gives_clusters_and_targets_in_the_room() {
        let dir = tempfile::tempdir().unwrap();
        let truth = dir.path().join("truth");
        std::fs::create_dir(&truth).unwrap();
        std::fs::write(
            truth.join("scatterers.csv"),
            "scatterer_id,kind,x_m,y_m,rrcs_m,cluster_id,wall_id\n\
             0,diffuse,1.0,-1.0,0.01,-1,0\n\
             1,corner,-1.0,-1.0,0.7,-1,-1\n\
             2,clutter,2.01,0.01,0.1,0,-1\n\
             3,clutter,2.04,0.04,0.1,0,-1\n\
             4,clutter,5.01,0.51,0.1,3,-1\n\
             5,clutter,5.31,0.51,0.1,3,-1\n\
             6,target,1.55,-0.45,0.3,-1,-1\n\
             7,target,1.55,1.8,0.3,-1,-1\n",
        )
        .unwrap();
        let layout = corridor();
        let reference = layout.rasterize(0.1, 0.5);
        let campaign = dir.path().join("campaign.toml");
        let found = find_truth(&campaign, &dir.path().join("energy.parquet")).unwrap();
        assert_eq!(found, truth);
        let o = load_objects(&found, &layout, reference.spec).unwrap();
        assert_eq!(o.kind, "scatterers");
        let sizes: Vec<usize> = o.cells.iter().map(Vec::len).collect();
        assert_eq!(sizes, vec![1, 2, 1]);
        let s = reference.spec;
        let (r, c) = s.cell_of(Coord { x: 1.55, y: -0.45 }).unwrap();
        assert_eq!(o.cells[2], vec![r * s.cols + c]);
    }

    /// synth's truth (no scatterers.csv): one object per cluster centroid, and it wins over
    /// the campaign's own `truth/` (model data drawn for a simulated campaign); no truth at
    /// all (a measured campaign): none found.
    #[test]
    fn synth_truth_gives_centroids_and_no_truth_gives_none() {
        let dir = tempfile::tempdir().unwrap();
        let energy = dir.path().join("n16_s1.parquet");
        assert!(find_truth(&dir.path().join("campaign.toml"), &energy).is_none());
        let sim = dir.path().join("truth");
        std::fs::create_dir(&sim).unwrap();
        std::fs::write(
            sim.join("scatterers.csv"),
            "scatterer_id,kind,x_m,y_m,rrcs_m,cluster_id,wall_id
",
        )
        .unwrap();
        assert_eq!(
            find_truth(&dir.path().join("campaign.toml"), &energy),
            Some(sim)
        );
        let truth = dir.path().join("n16_s1_truth");
        std::fs::create_dir(&truth).unwrap();
        std::fs::write(
            truth.join("clusters.csv"),
            "cluster_id,x_m,y_m,arc_m,offset_m,rays,sigma_m2\n0,1.03,-0.96,2.0,0.04,16,1e-5\n1,1.85,-0.94,2.8,0.05,8,1e-5\n",
        )
        .unwrap();
        let found = find_truth(&dir.path().join("campaign.toml"), &energy).unwrap();
        let layout = corridor();
        let o = load_objects(&found, &layout, layout.rasterize(0.1, 0.5).spec).unwrap();
        assert_eq!((o.kind, o.cells.len()), ("centroids", 2));
    }
}
