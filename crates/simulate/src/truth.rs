//! The simulator's ground truth (`DIR/truth/`): `rays.parquet` (every path seen from every
//! position), `scatterers.csv` and `clusters.csv`.
//!
//! `rays.parquet` columns: `position` (i32); `scatterer_id` (index into `scatterers.csv`,
//! −1 for specular paths); `kind` (`diffuse`, `specular`, `corner`, `edge`, `clutter`,
//! `target`); `cluster_id` (clutter cluster, −1 for other kinds); `source_id` (the source's
//! id: the wall index into the layout's `walls` for `diffuse` and `specular`, the scatterer
//! id for `corner`, `edge` and `target`, the clutter cluster for `clutter`); `wall_id` (the
//! wall for `diffuse` and `specular`, −1 otherwise); `truth_cluster` (the path's true
//! cluster, unique over the scene, −1 for the diffuse wall returns; the definition is in
//! `docs/campaign.md`, "True clusters of a simulated scene"); `x_m`, `y_m`;
//! `delay_ns`; `angle_global_deg`; `angle_rel_deg`; `power_db`. `scatterers.csv` has
//! scatterer_id, kind, x_m, y_m, rrcs_m, cluster_id, wall_id.
//!
//! A ray's `power_db` is its received power at boresight, |S21|² = G0²·λc²·|A|² (G0 the
//! array gain at broadside and λc the wavelength at the band centre), so it compares with
//! the energy of an echo without the pattern's angular roll-off.

use super::paths::Path1;
use super::scene::{Scatterer, ScattererKind, Scene, TruthCluster};
use crate::error::Result;
use crate::table;
use geo::Coord;
use std::path::Path;

/// One row of `truth/rays.parquet` (a path seen from a position).
#[derive(Debug, Clone, Copy)]
pub struct TruthRay {
    /// Scatterer (−1 for specular paths and for rays without a scatterer row).
    pub scatterer_id: i64,
    /// Kind name (`clutter`, `diffuse`, …).
    pub kind: &'static str,
    /// Clutter cluster (−1 outside clusters).
    pub cluster_id: i64,
    /// The source's id: wall (`diffuse`, `specular`), scatterer (`corner`, `edge`,
    /// `target`) or clutter cluster (`clutter`).
    pub source_id: i64,
    /// Wall (`diffuse`, `specular`; −1 otherwise).
    pub wall_id: i64,
    /// True cluster (unique over the scene; −1 for diffuse wall returns).
    pub truth_cluster: i64,
    /// Where the path's echo maps to in the global frame, m.
    pub pos: Coord<f64>,
    /// Round-trip delay, ns.
    pub delay_ns: f64,
    /// Global angle of arrival, degrees.
    pub angle_global_deg: f64,
    /// Received power at boresight, dB (|S21|² = G0²·λc²·|A|²).
    pub power_db: f64,
}

impl TruthRay {
    /// A ray of cluster `cluster` of a drawn statistical model (`synth`): kind `clutter`,
    /// no scatterer row, `source_id` = `truth_cluster` = `cluster_id` = `cluster`.
    pub fn model_cluster(
        cluster: usize,
        pos: Coord<f64>,
        delay_ns: f64,
        angle_global_deg: f64,
        power_db: f64,
    ) -> TruthRay {
        TruthRay {
            scatterer_id: -1,
            kind: ScattererKind::Clutter.name(),
            cluster_id: cluster as i64,
            source_id: cluster as i64,
            wall_id: -1,
            truth_cluster: cluster as i64,
            pos,
            delay_ns,
            angle_global_deg,
            power_db,
        }
    }

    /// The specular return of wall `wall` (`synth`'s `[walls]`): kind `specular`, no
    /// scatterer row and no cluster (`cluster_id` = `truth_cluster` = −1), `source_id` =
    /// `wall_id` = `wall`.
    pub fn specular_wall(
        wall: usize,
        pos: Coord<f64>,
        delay_ns: f64,
        angle_global_deg: f64,
        power_db: f64,
    ) -> TruthRay {
        TruthRay {
            kind: ScattererKind::Specular.name(),
            ..TruthRay::diffuse_wall(wall, pos, delay_ns, angle_global_deg, power_db)
        }
    }

    /// Layout vertex `i` of `synth`'s `[walls]` (a corner or edge point): kind `edge`, no
    /// scatterer row, no cluster, `source_id` = `i`.
    pub fn vertex(
        i: usize,
        pos: Coord<f64>,
        delay_ns: f64,
        angle_global_deg: f64,
        power_db: f64,
    ) -> TruthRay {
        TruthRay {
            kind: ScattererKind::Edge.name(),
            wall_id: -1,
            ..TruthRay::diffuse_wall(i, pos, delay_ns, angle_global_deg, power_db)
        }
    }

    /// A diffuse return of wall `wall` (index into the layout's `walls`) without a
    /// scatterer row (`synth`'s diffuse draws): kind `diffuse`, `source_id` = `wall_id` =
    /// `wall`, `truth_cluster` −1 (the dense component).
    pub fn diffuse_wall(
        wall: usize,
        pos: Coord<f64>,
        delay_ns: f64,
        angle_global_deg: f64,
        power_db: f64,
    ) -> TruthRay {
        TruthRay {
            scatterer_id: -1,
            kind: ScattererKind::Diffuse.name(),
            cluster_id: -1,
            source_id: wall as i64,
            wall_id: wall as i64,
            truth_cluster: -1,
            pos,
            delay_ns,
            angle_global_deg,
            power_db,
        }
    }
}

/// The true-cluster numbering of a scene (`docs/campaign.md`, "True clusters of a
/// simulated scene").
#[derive(Debug, Clone)]
pub(super) struct TruthIds {
    /// Per scatterer: its true cluster (−1 for diffuse).
    by_scatterer: Vec<i64>,
    /// C + S: the first specular id.
    specular0: i64,
}

impl TruthIds {
    /// The numbering of `scene`.
    pub(super) fn of(scene: &Scene) -> TruthIds {
        let c = scene.clusters.len() as i64;
        let mut k = 0i64;
        let by_scatterer = scene
            .scatterers
            .iter()
            .map(|s| match s.cluster {
                Some(cl) => cl as i64,
                None if s.is_discrete() => {
                    k += 1;
                    c + k - 1
                }
                None => -1,
            })
            .collect();
        TruthIds {
            by_scatterer,
            specular0: c + k,
        }
    }
}

/// The truth rows of one position's paths; `g0` is the broadside gain and `lc` the
/// wavelength at the band centre, m.
pub(super) fn truth_rays(
    scene: &Scene,
    ids: &TruthIds,
    paths: &[Path1],
    g0: f64,
    lc: f64,
) -> Vec<TruthRay> {
    let sid = |path: &Path1| (path.scatterer != usize::MAX).then_some(path.scatterer);
    paths
        .iter()
        .map(|x| {
            let scatterer = sid(x);
            let cluster_id = scatterer
                .and_then(|i| scene.scatterers[i].cluster)
                .map(|c| c as i64)
                .unwrap_or(-1);
            let wall_id = x.wall.map(|w| w as i64).unwrap_or(-1);
            let (source_id, truth_cluster) = match (x.kind, scatterer) {
                (ScattererKind::Specular, _) => (wall_id, ids.specular0 + wall_id),
                (ScattererKind::Diffuse, _) => (wall_id, -1),
                (ScattererKind::Clutter, Some(i)) => (cluster_id, ids.by_scatterer[i]),
                (_, Some(i)) => (i as i64, ids.by_scatterer[i]),
                (_, None) => (-1, -1),
            };
            TruthRay {
                scatterer_id: scatterer.map(|i| i as i64).unwrap_or(-1),
                kind: x.kind.name(),
                cluster_id,
                source_id,
                wall_id,
                truth_cluster,
                pos: x.pos,
                delay_ns: x.tau_s * 1e9,
                angle_global_deg: x.theta.to_degrees(),
                // boresight received power |S21|² = G0²·λc²·|A|²; not `units::db`, whose
                // floor would turn a zero-σ scatterer's −∞ into −3000
                power_db: 10.0 * (g0 * g0 * lc * lc * x.amp.norm_sqr()).log10(),
            }
        })
        .collect()
}

/// One position's rows of `truth/rays.parquet` (the columns of the module docs).
pub fn truth_rays_frame(
    path: &Path,
    position: usize,
    heading_deg: f64,
    rows: &[TruthRay],
) -> Result<polars::prelude::DataFrame> {
    let f = |g: &dyn Fn(&TruthRay) -> f64| rows.iter().map(g).collect::<Vec<f64>>();
    table::frame(
        path,
        vec![
            table::col("position", vec![position as i32; rows.len()]),
            table::col(
                "scatterer_id",
                rows.iter().map(|r| r.scatterer_id).collect::<Vec<_>>(),
            ),
            table::col(
                "kind",
                rows.iter().map(|r| r.kind.to_string()).collect::<Vec<_>>(),
            ),
            table::col(
                "cluster_id",
                rows.iter().map(|r| r.cluster_id).collect::<Vec<_>>(),
            ),
            table::col(
                "source_id",
                rows.iter().map(|r| r.source_id).collect::<Vec<_>>(),
            ),
            table::col(
                "wall_id",
                rows.iter().map(|r| r.wall_id).collect::<Vec<_>>(),
            ),
            table::col(
                "truth_cluster",
                rows.iter().map(|r| r.truth_cluster).collect::<Vec<_>>(),
            ),
            table::col("x_m", f(&|r| r.pos.x)),
            table::col("y_m", f(&|r| r.pos.y)),
            table::col("delay_ns", f(&|r| r.delay_ns)),
            table::col("angle_global_deg", f(&|r| r.angle_global_deg)),
            table::col(
                "angle_rel_deg",
                f(&|r| crate::units::wrap_deg(r.angle_global_deg - heading_deg)),
            ),
            table::col("power_db", f(&|r| r.power_db)),
        ],
    )
}

/// Write `dir/scatterers.csv` (scatterer_id, kind, x_m, y_m, rrcs_m, cluster_id, wall_id).
pub fn write_truth_scatterers(dir: &Path, s: &[Scatterer]) -> Result<()> {
    let mut sdf = table::frame(
        dir,
        vec![
            table::col("scatterer_id", (0..s.len() as i64).collect::<Vec<_>>()),
            table::col(
                "kind",
                s.iter()
                    .map(|x| x.kind.name().to_string())
                    .collect::<Vec<_>>(),
            ),
            table::col("x_m", s.iter().map(|x| x.pos.x).collect::<Vec<_>>()),
            table::col("y_m", s.iter().map(|x| x.pos.y).collect::<Vec<_>>()),
            table::col("rrcs_m", s.iter().map(|x| x.x.norm()).collect::<Vec<_>>()),
            table::col(
                "cluster_id",
                s.iter()
                    .map(|x| x.cluster.map(|c| c as i64).unwrap_or(-1))
                    .collect::<Vec<_>>(),
            ),
            table::col(
                "wall_id",
                s.iter()
                    .map(|x| x.wall.map(|w| w as i64).unwrap_or(-1))
                    .collect::<Vec<_>>(),
            ),
        ],
    )?;
    table::write_csv(&dir.join("scatterers.csv"), &mut sdf)
}

/// Write `dir/clusters.csv` (cluster_id, x_m, y_m, arc_m, offset_m, rays, sigma_m2).
pub fn write_truth_clusters(dir: &Path, cl: &[TruthCluster]) -> Result<()> {
    let mut cdf = table::frame(
        dir,
        vec![
            table::col("cluster_id", (0..cl.len() as i64).collect::<Vec<_>>()),
            table::col("x_m", cl.iter().map(|c| c.centre.x).collect::<Vec<_>>()),
            table::col("y_m", cl.iter().map(|c| c.centre.y).collect::<Vec<_>>()),
            table::col("arc_m", cl.iter().map(|c| c.arc_m).collect::<Vec<_>>()),
            table::col(
                "offset_m",
                cl.iter().map(|c| c.offset_m).collect::<Vec<_>>(),
            ),
            table::col("rays", cl.iter().map(|c| c.rays as i64).collect::<Vec<_>>()),
            table::col(
                "sigma_m2",
                cl.iter().map(|c| c.sigma_m2).collect::<Vec<_>>(),
            ),
        ],
    )?;
    table::write_csv(&dir.join("clusters.csv"), &mut cdf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::layout::Layout;
    use crate::campaign::manifest::Campaign;
    use crate::params::ParamGuard;
    use crate::scene::{PointTarget, SceneConfig};
    use std::collections::{BTreeMap, BTreeSet};

    /// A 5 m × 3 m room with a box obstacle, specular walls, one target and the corridor's
    /// clutter model; the truth rows seen from three poses.
    fn scene_and_rows() -> (Scene, Vec<TruthRay>) {
        let geo = r#"{"type":"FeatureCollection","features":[
          {"type":"Feature","properties":{"role":"perimeter"},
           "geometry":{"type":"Polygon","coordinates":[[[0,0],[5,0],[5,3],[0,3],[0,0]]]}},
          {"type":"Feature","properties":{"role":"obstacle","name":"box"},
           "geometry":{"type":"Polygon","coordinates":[[[3.5,2.0],[4.0,2.0],[4.0,2.4],[3.5,2.4],[3.5,2.0]]]}}]}"#;
        let layout = Layout::from_geojson(geo, Path::new("t.geojson")).unwrap();
        let manifest =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/corridor/campaign.toml");
        let (_, clutter) =
            super::super::scene_sections(&Campaign::load(&manifest).unwrap()).unwrap();
        let cfg = SceneConfig {
            walls: true,
            wall_rcs_per_m: 0.01,
            scatterers_per_cell: 10.0,
            specular: true,
            corner_rcs_m2: 0.1,
            edge_rcs_m2: 0.01,
            coupling_db: -30.0,
            coupling_delay_ns: 0.2,
            pattern_knots: 0,
            materials: BTreeMap::new(),
            targets: vec![PointTarget {
                x_m: 1.0,
                y_m: 2.2,
                rrcs_m: 0.3,
                via_m: None,
            }],
        };
        let scene = Scene::build(layout, cfg.check().unwrap(), clutter.as_ref(), 6e9, 11);
        let ids = TruthIds::of(&scene);
        let rows = [(1.5, 1.0), (2.5, 1.2), (2.0, 1.6)]
            .into_iter()
            .flat_map(|(x, y)| {
                let paths = scene.paths(Coord { x, y });
                truth_rays(&scene, &ids, &paths, 1.0, 5e-3)
            })
            .collect();
        (scene, rows)
    }

    fn on_wall(scene: &Scene, w: i64, p: Coord<f64>) -> bool {
        let l = scene.layout.walls[w as usize].line;
        let d = l.delta();
        let t = ((p.x - l.start.x) * d.x + (p.y - l.start.y) * d.y) / (d.x * d.x + d.y * d.y);
        let foot = l.start + d * t.clamp(0.0, 1.0);
        (p.x - foot.x).hypot(p.y - foot.y) < 1e-9
    }

    #[test]
    fn every_path_carries_its_source_and_true_cluster() {
        let (scene, rows) = scene_and_rows();
        let c = scene.clusters.len() as i64;
        let s = scene.scatterers.iter().filter(|x| x.is_discrete()).count() as i64;
        assert!(c > 0 && s == 9, "C = {c}, S = {s}");
        let kinds: BTreeSet<&str> = rows.iter().map(|r| r.kind).collect();
        for k in ["diffuse", "specular", "corner", "edge", "clutter", "target"] {
            assert!(kinds.contains(k), "no `{k}` path: {kinds:?}");
        }
        // discrete scatterer -> true cluster, the same from every position
        let mut discrete: BTreeMap<i64, i64> = BTreeMap::new();
        let mut seen_from = BTreeMap::<i64, usize>::new();
        for r in &rows {
            match r.kind {
                "diffuse" => {
                    assert!(r.wall_id >= 0 && r.source_id == r.wall_id, "{r:?}");
                    assert_eq!(r.truth_cluster, -1, "{r:?}");
                    assert_eq!(
                        scene.scatterers[r.scatterer_id as usize].wall,
                        Some(r.wall_id as usize)
                    );
                    assert!(on_wall(&scene, r.wall_id, r.pos), "{r:?}");
                }
                "specular" => {
                    assert!(r.wall_id >= 0 && r.source_id == r.wall_id, "{r:?}");
                    assert_eq!(r.truth_cluster, c + s + r.wall_id, "{r:?}");
                    assert_eq!(r.scatterer_id, -1);
                    assert!(on_wall(&scene, r.wall_id, r.pos), "{r:?}");
                }
                "clutter" => {
                    assert!(r.cluster_id >= 0 && r.cluster_id < c, "{r:?}");
                    assert_eq!(r.truth_cluster, r.cluster_id, "{r:?}");
                    assert_eq!(r.source_id, r.cluster_id, "{r:?}");
                    assert_eq!(r.wall_id, -1);
                }
                _ => {
                    assert_eq!(r.source_id, r.scatterer_id, "{r:?}");
                    assert_eq!((r.wall_id, r.cluster_id), (-1, -1), "{r:?}");
                    assert!((c..c + s).contains(&r.truth_cluster), "{r:?}");
                    let t = *discrete.entry(r.scatterer_id).or_insert(r.truth_cluster);
                    assert_eq!(
                        t, r.truth_cluster,
                        "scatterer {} changes id",
                        r.scatterer_id
                    );
                    *seen_from.entry(r.scatterer_id).or_default() += 1;
                }
            }
        }
        // one-ray clusters: distinct scatterers have distinct ids
        let ids: BTreeSet<i64> = discrete.values().copied().collect();
        assert_eq!(ids.len(), discrete.len(), "{discrete:?}");
        assert!(
            seen_from.values().any(|&n| n > 1),
            "no scatterer seen twice"
        );
        // the target is the last discrete scatterer
        let target = rows.iter().find(|r| r.kind == "target").unwrap();
        assert_eq!(target.truth_cluster, c + s - 1);
    }

    #[test]
    fn frame_has_the_source_columns() {
        let (_, rows) = scene_and_rows();
        let df = truth_rays_frame(Path::new("rays"), 0, 0.0, &rows).unwrap();
        for name in [
            "source_id",
            "wall_id",
            "truth_cluster",
            "cluster_id",
            "kind",
        ] {
            assert!(df.column(name).is_ok(), "missing {name}");
        }
        let tc = table::i64_column(Path::new("rays"), &df, "truth_cluster").unwrap();
        assert!(tc.iter().zip(&rows).all(|(a, r)| *a == r.truth_cluster));
    }
}
