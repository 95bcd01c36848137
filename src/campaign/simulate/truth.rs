//! The simulator's ground truth (`DIR/truth/`): `rays.parquet` (every path seen from every
//! position), `scatterers.csv` and `clusters.csv`.
//!
//! A ray's `power_db` is its received power at boresight, |S21|² = G0²·λc²·|A|² (G0 the
//! array gain at broadside and λc the wavelength at the band centre), so it compares with
//! the energy of an echo without the pattern's angular roll-off. Specular paths have
//! `scatterer_id` −1 and rays outside clutter clusters `cluster_id` −1.

use super::paths::Path1;
use super::scene::{Scatterer, Scene, TruthCluster};
use crate::error::Result;
use crate::table;
use geo::Coord;
use std::path::Path;

/// One row of `truth/rays.parquet` (a path seen from a position).
#[derive(Debug, Clone, Copy)]
pub struct TruthRay {
    /// Scatterer (−1 for specular paths).
    pub scatterer_id: i64,
    /// Kind name (`clutter`, `diffuse`, …).
    pub kind: &'static str,
    /// Clutter cluster (−1 outside clusters).
    pub cluster_id: i64,
    /// Where the path's echo maps to in the global frame, m.
    pub pos: Coord<f64>,
    /// Round-trip delay, ns.
    pub delay_ns: f64,
    /// Global angle of arrival, degrees.
    pub angle_global_deg: f64,
    /// Received power at boresight, dB (|S21|² = G0²·λc²·|A|²).
    pub power_db: f64,
}

/// The truth rows of one position's paths; `g0` is the broadside gain and `lc` the
/// wavelength at the band centre, m.
pub(super) fn truth_rays(scene: &Scene, paths: &[Path1], g0: f64, lc: f64) -> Vec<TruthRay> {
    let sid = |path: &Path1| (path.scatterer != usize::MAX).then_some(path.scatterer);
    paths
        .iter()
        .map(|x| TruthRay {
            scatterer_id: sid(x).map(|i| i as i64).unwrap_or(-1),
            kind: x.kind.name(),
            cluster_id: sid(x)
                .and_then(|i| scene.scatterers[i].cluster)
                .map(|c| c as i64)
                .unwrap_or(-1),
            pos: x.pos,
            delay_ns: x.tau_s * 1e9,
            angle_global_deg: x.theta.to_degrees(),
            // boresight received power |S21|² = G0²·λc²·|A|²; not `units::db`, whose floor
            // would turn a zero-σ scatterer's −∞ into −3000
            power_db: 10.0 * (g0 * g0 * lc * lc * x.amp.norm_sqr()).log10(),
        })
        .collect()
}

/// One position's rows of `truth/rays.parquet` (columns position, scatterer_id, kind,
/// cluster_id, x_m, y_m, delay_ns, angle_global_deg, angle_rel_deg, power_db).
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

/// Write `dir/scatterers.csv` (scatterer_id, kind, x_m, y_m, rrcs_m, cluster_id).
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
