//! The drawn channel of the statistical model: clusters along the layout perimeter
//! ([`ChannelModel::draw`]) and the rays a pose sees of them ([`ChannelModel::rays_from`]).
//!
//! Takes a checked model file ([`ModelConfig`]) and the layout; gives the clusters (centre,
//! arc length, offset d_p, σ, rays with excess delays and AoA offsets) and, per pose, the
//! seen rays with their delay, angle and |A|² before the array.
//!
//! * Clusters come from [`perimeter_walk`] (shared with the simulator's clutter): spacings
//!   ~ d_c, centroid offsets ~ d_p (capped at 1.5 m), a centre outside the free space
//!   dropped. Rays: 1 + Poisson(mean − 1), excess delays with exponential gaps of rate λ
//!   (τ_0 = 0), Laplacian AoA offsets of scale b = std/√2 (φ_0 = 0, the reference ray).
//! * Seen from a pose at distance r from the centroid, the first arrival is at range
//!   r − m, m the members' mean extra depth c·τ_k/2, so the fitted centroid (the members'
//!   mean position) is the drawn one. A cluster is seen when the segment pose → centroid
//!   crosses no wall.
//! * Powers (model schema 2): every cluster at its own range,
//!   |A|² = σ_l · e^{−(T_l − T_0)/Γ} · e^{−τ_k/γ} / ((4π)³ r_l⁴), r_l = c·T_l/2 the range
//!   of the cluster's first arrival and T_0 the first arrival of the first visible cluster
//!   in the scanned half-plane: each cluster follows the radar equation (a point target
//!   of σ_l at r_l, as `simulate`'s clutter), and Γ is the decay *in excess* of it
//!   (Γ = ∞: none). Why: anchoring every cluster of a pose at the first cluster's range
//!   d_0 (schema 1, below) lets one cluster 0.3 m from a pose lift all of that pose's
//!   clusters by (r_l/d_0)⁴, so draws of one model differed wildly (the check rejected
//!   its own model's data 8 times in 20) and Γ had to stand in for the path loss.
//! * Schema 1 files keep their meaning: |A|² = σ_l · e^{−(T_l − T_0)/Γ} · e^{−τ_k/γ} /
//!   ((4π)³ d_0⁴), d_0 = c·T_0/2, Γ the total decay.
//!
//! ```
//! use pradar_formats::campaign::layout::Layout;
//! use pradar_channel::model::file::ModelConfig;
//! use pradar_channel::model::ChannelModel;
//! use geo::Coord;
//! # fn main() -> pradar_formats::error::Result<()> {
//! let hall = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/tests/hall.geojson");
//! let layout = Layout::load(std::path::Path::new(hall))?;
//! let channel = ChannelModel::draw(&layout, &ModelConfig::table1_defaults(), 1)?;
//! assert!(!channel.clusters.is_empty());
//! let rays = channel.rays_from(&layout, Coord { x: 0.0, y: 0.0 }, 0.0);
//! assert!(rays.iter().all(|r| r.tau_s > 0.0 && r.amp2 > 0.0));
//! # Ok(())
//! # }
//! ```

use crate::campaign::layout::Layout;
use crate::error::{Error, Result};
use crate::model::file::ModelConfig;
use crate::simulate::{draw_rays, draw_shadowed, laplace, perimeter_walk};
use crate::units::wrap_rad;
use geo::Coord;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp};
use std::f64::consts::PI;

/// One ray of a model cluster (pose-independent).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelRay {
    /// Excess delay after the cluster's first arrival, ns.
    pub excess_ns: f64,
    /// AoA offset from the cluster bearing, rad.
    pub aoa_rad: f64,
}

/// A cluster of the statistical model.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelCluster {
    /// Centroid, m.
    pub centre: Coord<f64>,
    /// Arc length of its perimeter point, m.
    pub arc_m: f64,
    /// Offset from the wall (d_p), m.
    pub offset_m: f64,
    /// σ of its first ray, m².
    pub sigma_m2: f64,
    /// Rays, the reference first.
    pub rays: Vec<ModelRay>,
    /// Mean extra one-way depth of its rays, m.
    pub mean_depth_m: f64,
}

/// The drawn channel: clusters along the layout perimeter.
#[derive(Debug, Clone)]
pub struct ChannelModel {
    /// Model parameters.
    pub config: ModelConfig,
    /// Clusters.
    pub clusters: Vec<ModelCluster>,
}

impl ChannelModel {
    /// Draw the clusters of `config` along `layout`'s perimeter.
    pub fn draw(layout: &Layout, config: &ModelConfig, seed: u64) -> Result<ChannelModel> {
        // every quantity needs a value to draw from (a schema-1 flagged one has none)
        config.require_estimable(&Default::default())?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5379_6e74_6800_0000);
        let lambda = config.intra_cluster_rate.value;
        let b = config.intra_cluster_aoa.value.to_radians() / 2f64.sqrt();
        let gaps =
            Exp::new(lambda).map_err(|e| Error::param("intra_cluster_rate", e.to_string()))?;
        let mut clusters = Vec::new();
        perimeter_walk(layout, config, &mut rng, |rng, arc, off, centre, _| {
            let n = draw_rays(rng, config.rays_per_cluster.value);
            let sigma = draw_shadowed(rng, config.cluster_rrcs.value);
            let mut tau = 0.0;
            let rays: Vec<ModelRay> = (0..n)
                .map(|k| {
                    if k > 0 {
                        tau += gaps.sample(rng);
                    }
                    let phi = laplace(rng, b);
                    ModelRay {
                        excess_ns: tau,
                        aoa_rad: if k == 0 { 0.0 } else { phi },
                    }
                })
                .collect();
            if !layout.is_free(centre) {
                return;
            }
            let mean_depth_m = rays
                .iter()
                // c₀·τ/2 in the original operation order (bit-identical cluster locations)
                .map(|r| crate::units::C0 * r.excess_ns * 1e-9 / 2.0)
                .sum::<f64>()
                / n as f64;
            clusters.push(ModelCluster {
                centre,
                arc_m: arc,
                offset_m: off,
                sigma_m2: sigma,
                rays,
                mean_depth_m,
            });
        });
        Ok(ChannelModel {
            config: config.clone(),
            clusters,
        })
    }

    /// The rays seen from a pose (x, y, heading in degrees): every ray of every cluster whose
    /// centroid is in line of sight, with its complex amplitude factor before the array.
    pub fn rays_from(&self, layout: &Layout, at: Coord<f64>, heading_deg: f64) -> Vec<SeenRay> {
        let heading = heading_deg.to_radians();
        let mut seen: Vec<(usize, f64, f64)> = Vec::new(); // (cluster, first arrival s, bearing)
        for (l, c) in self.clusters.iter().enumerate() {
            let v = c.centre - at;
            let r = v.x.hypot(v.y);
            if r < 0.1 || layout.occluded(at, c.centre, 1e-3) {
                continue;
            }
            let first = (r - c.mean_depth_m).max(0.05);
            seen.push((l, crate::units::delay_s(first), v.y.atan2(v.x)));
        }
        let in_front = |th: f64| wrap_rad(th - heading).abs() < PI / 2.0;
        let Some(t0) = seen
            .iter()
            .filter(|s| in_front(s.2))
            .map(|s| s.1)
            .min_by(f64::total_cmp)
        else {
            return Vec::new();
        };
        let d0 = crate::units::range_from_delay_s(t0);
        let own_range = self.config.schema_version >= 2;
        let radar = |d: f64| 1.0 / ((4.0 * PI).powi(3) * d.powi(4));
        let gamma_c = self.config.cluster_decay.value * 1e-9;
        let gamma_r = self.config.ray_decay.value;
        let mut out = Vec::new();
        for (l, t, th) in seen {
            let c = &self.clusters[l];
            let re = radar(if own_range {
                crate::units::range_from_delay_s(t)
            } else {
                d0
            });
            // Γ = ∞ (schema 2): no excess decay, e^{−x/∞} = 1
            let pc = c.sigma_m2 * (-(t - t0).max(0.0) / gamma_c).exp() * re;
            for r in &c.rays {
                let tau = t + r.excess_ns * 1e-9;
                let theta = th + r.aoa_rad;
                let range = crate::units::range_from_delay_s(tau);
                out.push(SeenRay {
                    source: RaySource::Cluster(l),
                    tau_s: tau,
                    theta,
                    amp2: pc * (-r.excess_ns / gamma_r).exp(),
                    pos: Coord {
                        x: at.x + range * theta.cos(),
                        y: at.y + range * theta.sin(),
                    },
                    phase: 0.0,
                });
            }
        }
        out
    }
}

/// What a seen ray comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RaySource {
    /// A ray of model cluster `l` (index into [`ChannelModel::clusters`]).
    Cluster(usize),
    /// A diffuse point scatterer of wall `w` (index into the layout's walls).
    Wall(usize),
    /// The specular (image-method) return of wall `w` ([`super::walls`]).
    Specular(usize),
    /// Layout vertex `i` (a corner or an edge, [`super::walls::vertices`]).
    Vertex(usize),
}

/// A ray seen from a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenRay {
    /// Its source: a model cluster or a diffuse wall point.
    pub source: RaySource,
    /// Round-trip delay, s.
    pub tau_s: f64,
    /// Global angle of arrival, rad.
    pub theta: f64,
    /// |A|² (received power = G²λ²|A|²).
    pub amp2: f64,
    /// Where the echo maps to, m.
    pub pos: Coord<f64>,
    /// Phase of the scatterer's complex amplitude, rad, added to the path phase
    /// −2πf_c(τ + τ_g): 0 for cluster rays, uniform for diffuse points (complex Gaussian).
    pub phase: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two one-ray clusters of σ = 1 m² straight ahead of a pose at the origin of the
    /// 16 m × 10 m hall, at 2 m and 6 m.
    fn two_clusters(config: ModelConfig) -> (Layout, ChannelModel) {
        let p = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/tests/hall.geojson");
        let layout = Layout::load(std::path::Path::new(p)).unwrap();
        let cluster = |x: f64| ModelCluster {
            centre: Coord { x, y: 0.0 },
            arc_m: 0.0,
            offset_m: 0.3,
            sigma_m2: 1.0,
            rays: vec![ModelRay {
                excess_ns: 0.0,
                aoa_rad: 0.0,
            }],
            mean_depth_m: 0.0,
        };
        let model = ChannelModel {
            config,
            clusters: vec![cluster(2.0), cluster(6.0)],
        };
        (layout, model)
    }

    #[test]
    fn each_cluster_follows_the_radar_equation_at_its_own_range() {
        let radar = |d: f64| 1.0 / ((4.0 * PI).powi(3) * d.powi(4));
        // schema 2 with no excess decay: each cluster is a point target at its range
        let mut m = ModelConfig::table1_defaults();
        assert_eq!(m.schema_version, 2);
        m.cluster_decay.value = f64::INFINITY;
        m.check().unwrap();
        let (layout, ch) = two_clusters(m.clone());
        let rays = ch.rays_from(&layout, Coord { x: 0.0, y: 0.0 }, 0.0);
        assert_eq!(rays.len(), 2);
        for (ray, d) in rays.iter().zip([2.0, 6.0]) {
            assert!(
                (ray.amp2 / radar(d) - 1.0).abs() < 1e-9,
                "{} at {d} m",
                ray.amp2
            );
        }
        // a finite excess decay multiplies the farther one by e^{−ΔT/Γ}
        m.cluster_decay.value = 10.0;
        let (layout, ch) = two_clusters(m);
        let rays = ch.rays_from(&layout, Coord { x: 0.0, y: 0.0 }, 0.0);
        let dt_ns = crate::units::delay_ns(6.0) - crate::units::delay_ns(2.0);
        let want = radar(6.0) * (-dt_ns / 10.0).exp();
        assert!((rays[1].amp2 / want - 1.0).abs() < 1e-9);
        // schema 1 keeps its meaning: both anchored at the first cluster's range
        let v1 = ModelConfig {
            schema_version: 1,
            ..ModelConfig::table1_defaults()
        };
        let (layout, ch) = two_clusters(v1);
        let rays = ch.rays_from(&layout, Coord { x: 0.0, y: 0.0 }, 0.0);
        let want = radar(2.0) * (-dt_ns / 12.0).exp();
        assert!((rays[1].amp2 / want - 1.0).abs() < 1e-9);
    }
}
