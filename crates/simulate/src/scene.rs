//! The simulator's scene: `[scene]` parameters (checked once, [`SceneValid`]) and the
//! pose-independent scatterers built from the layout, `[scene]` and `[clutter]`.
//!
//! Takes a [`Layout`], a [`SceneValid`], the optional clutter model, the bandwidth and the
//! manifest seed; gives a [`Scene`] whose scatterers are drawn in a fixed order from one
//! ChaCha stream (diffuse walls, then corners and edges ring by ring, then clutter clusters
//! along the perimeter, then the extra targets), so the scene depends on the seed only.
//! * diffuse walls: σ per metre of wall spread over `scatterers_per_cell` uniform random
//!   scatterers per range cell (c/2B of wall length), complex Gaussian RRCS of variance
//!   σ·len/n each, with the wall's free-side normal for the Lambertian factor;
//! * ring vertices: a left turn of the counter-clockwise perimeter is a concave corner
//!   (dihedral, σ = `corner_rcs_m2`); every other vertex (perimeter or obstacle) is a
//!   convex edge (σ = `edge_rcs_m2`); uniform random phase;
//! * clutter: [`perimeter_walk`] places the centres; ray r of a cluster sits behind the
//!   centre at depth c·τ_r/2 (τ_r exponential increments of rate λ) and lateral offset
//!   d_ref·tan(φ_r) (φ_r Laplacian, d_ref = 2 m), σ_r = σ_c·e^{−τ_r/γ}.

use super::draws::{cgauss, draw_rays, draw_shadowed, laplace, perimeter_walk};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::C0;
use crate::error::{Error, Result};
use crate::model_file::ModelConfig;
use crate::params::{ParamGuard, Valid};
use geo::Coord;
use num_complex::Complex64;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Dielectric description of a wall material.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Relative permittivity (real part).
    pub eps_r: f64,
    /// Loss tangent.
    #[serde(default)]
    pub loss_tangent: f64,
}

impl Material {
    /// Normal-incidence Fresnel reflection coefficient.
    pub fn gamma(&self) -> Complex64 {
        let eps = Complex64::new(self.eps_r, -self.eps_r * self.loss_tangent);
        let n = eps.sqrt();
        (Complex64::new(1.0, 0.0) - n) / (Complex64::new(1.0, 0.0) + n)
    }
}

/// An extra point target.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PointTarget {
    /// x, m.
    pub x_m: f64,
    /// y, m.
    pub y_m: f64,
    /// RRCS √σ, m.
    pub rrcs_m: f64,
    /// Optional `[via_x_m, via_y_m]`: the point the path is seen through — the last
    /// reflection of a multi-bounce path, the target then being the image of a reflector
    /// through that wall (image method). Occlusion is tested from the pose to this point,
    /// not to the target.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub via_m: Option<[f64; 2]>,
}

fn d_true() -> bool {
    true
}

/// `[scene]`: the simulator's physical scene (ground truth; analysis never reads it).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// Include the layout's walls, corners, edges and clutter.
    #[serde(default = "d_true")]
    pub walls: bool,
    /// Diffuse RCS per metre of wall, m²/m.
    pub wall_rcs_per_m: f64,
    /// Random diffuse scatterers per range cell (≥ 10).
    pub scatterers_per_cell: f64,
    /// Specular image paths.
    #[serde(default = "d_true")]
    pub specular: bool,
    /// σ of a concave corner (dihedral), m².
    pub corner_rcs_m2: f64,
    /// σ of a convex edge (door frame, pillar or cabinet edge), m².
    pub edge_rcs_m2: f64,
    /// Coupling level, dB (S21).
    pub coupling_db: f64,
    /// Coupling delay, ns.
    pub coupling_delay_ns: f64,
    /// Frequency knots at which the array pattern is computed (0 = every frequency point).
    #[serde(default = "d_knots")]
    pub pattern_knots: usize,
    /// Materials by name.
    #[serde(default)]
    pub materials: BTreeMap<String, Material>,
    /// Extra point targets.
    #[serde(default)]
    pub targets: Vec<PointTarget>,
}

fn d_knots() -> usize {
    0
}

/// `[scene]` that passed [`ParamGuard::check`].
pub type SceneValid = Valid<SceneConfig>;

impl ParamGuard for SceneConfig {
    type Checked = SceneValid;

    /// Validate; errors name the field (`scene.<field>`) and the allowed range.
    fn check(&self) -> Result<SceneValid> {
        if self.walls && self.scatterers_per_cell < 10.0 {
            return Err(Error::param(
                "scene.scatterers_per_cell",
                "must be >= 10 (DESIGN §2)",
            ));
        }
        for (n, v) in [
            ("scene.wall_rcs_per_m", self.wall_rcs_per_m),
            ("scene.corner_rcs_m2", self.corner_rcs_m2),
            ("scene.edge_rcs_m2", self.edge_rcs_m2),
            ("scene.coupling_delay_ns", self.coupling_delay_ns),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::param(n, "must be finite and >= 0"));
            }
        }
        if !self.coupling_db.is_finite() {
            return Err(Error::param("scene.coupling_db", "must be finite"));
        }
        if self.pattern_knots == 1 {
            return Err(Error::param(
                "scene.pattern_knots",
                "must be 0 (every point) or >= 2",
            ));
        }
        for (i, t) in self.targets.iter().enumerate() {
            let via_ok = t.via_m.is_none_or(|v| v.iter().all(|c| c.is_finite()));
            if !(t.x_m.is_finite()
                && t.y_m.is_finite()
                && t.rrcs_m.is_finite()
                && t.rrcs_m > 0.0
                && via_ok)
            {
                return Err(Error::param(
                    format!("scene.targets[{i}]"),
                    "x_m, y_m (and via_m) finite and rrcs_m > 0",
                ));
            }
        }
        Ok(Valid::new(self.clone()))
    }
}

impl SceneConfig {
    /// The material called `name`: the `[scene.materials]` entry, else a built-in default
    /// (concrete, plasterboard, glass, wood, metal; anything else εr = 4, tan δ = 0.05).
    pub(super) fn material(&self, name: &str) -> Material {
        self.materials.get(name).copied().unwrap_or(match name {
            "concrete" => Material {
                eps_r: 5.3,
                loss_tangent: 0.06,
            },
            "plasterboard" => Material {
                eps_r: 2.8,
                loss_tangent: 0.05,
            },
            "glass" => Material {
                eps_r: 6.3,
                loss_tangent: 0.03,
            },
            "wood" => Material {
                eps_r: 2.0,
                loss_tangent: 0.07,
            },
            "metal" => Material {
                eps_r: 1e8,
                loss_tangent: 0.0,
            },
            _ => Material {
                eps_r: 4.0,
                loss_tangent: 0.05,
            },
        })
    }
}

/// Kind of a ground-truth scatterer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScattererKind {
    /// Diffuse wall scatterer.
    Diffuse,
    /// Concave corner.
    Corner,
    /// Convex edge.
    Edge,
    /// Clutter ray.
    Clutter,
    /// Extra point target.
    Target,
    /// Specular image path (per pose; its position is the normal-incidence point).
    Specular,
}

impl ScattererKind {
    /// Name in the truth tables.
    pub fn name(&self) -> &'static str {
        match self {
            ScattererKind::Diffuse => "diffuse",
            ScattererKind::Corner => "corner",
            ScattererKind::Edge => "edge",
            ScattererKind::Clutter => "clutter",
            ScattererKind::Target => "target",
            ScattererKind::Specular => "specular",
        }
    }
}

/// A pose-independent scatterer.
#[derive(Debug, Clone)]
pub struct Scatterer {
    /// Kind.
    pub kind: ScattererKind,
    /// Position, m.
    pub pos: Coord<f64>,
    /// Complex RRCS (|x|² = σ), m.
    pub x: Complex64,
    /// Clutter cluster.
    pub cluster: Option<usize>,
    /// Point whose visibility decides this scatterer's (the cluster centre for clutter).
    pub anchor: Coord<f64>,
    /// Free-side unit normal for Lambertian weighting (diffuse only).
    pub normal: Option<Coord<f64>>,
    /// The wall it lies on (index into the layout's `walls`; diffuse only).
    pub wall: Option<usize>,
}

impl Scatterer {
    /// A scatterer seen through its own position, without a Lambertian normal.
    fn point(kind: ScattererKind, pos: Coord<f64>, x: Complex64) -> Scatterer {
        Scatterer {
            kind,
            pos,
            x,
            cluster: None,
            anchor: pos,
            normal: None,
            wall: None,
        }
    }

    /// A discrete point scatterer (corner, edge or target): its own one-ray true cluster.
    pub fn is_discrete(&self) -> bool {
        matches!(
            self.kind,
            ScattererKind::Corner | ScattererKind::Edge | ScattererKind::Target
        )
    }
}

/// A clutter cluster of the ground truth.
#[derive(Debug, Clone)]
pub struct TruthCluster {
    /// Centre, m.
    pub centre: Coord<f64>,
    /// Arc length of the perimeter point it was placed from, m.
    pub arc_m: f64,
    /// Offset from the wall, m.
    pub offset_m: f64,
    /// Number of rays.
    pub rays: usize,
    /// σ of its first ray, m².
    pub sigma_m2: f64,
}

/// The built scene.
pub struct Scene {
    /// Scatterers.
    pub scatterers: Vec<Scatterer>,
    /// Clutter clusters.
    pub clusters: Vec<TruthCluster>,
    pub(super) layout: Layout,
    pub(super) cfg: SceneValid,
}

impl Scene {
    /// Build the pose-independent scatterers from the layout, `[scene]` and `[clutter]`.
    pub fn build(
        layout: Layout,
        cfg: SceneValid,
        clutter: Option<&ModelConfig>,
        bandwidth_hz: f64,
        seed: u64,
    ) -> Scene {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut sc = Vec::new();
        let mut clusters = Vec::new();
        if cfg.walls {
            diffuse_walls(&layout, &cfg, bandwidth_hz, &mut rng, &mut sc);
            corners_and_edges(&layout, &cfg, &mut rng, &mut sc);
            if let Some(m) = clutter {
                clutter_clusters(&layout, m, &mut rng, &mut sc, &mut clusters);
            }
        }
        for t in &cfg.targets {
            let pos = Coord { x: t.x_m, y: t.y_m };
            let mut s = Scatterer::point(ScattererKind::Target, pos, Complex64::new(t.rrcs_m, 0.0));
            if let Some([x, y]) = t.via_m {
                s.anchor = Coord { x, y };
            }
            sc.push(s);
        }
        Scene {
            scatterers: sc,
            clusters,
            layout,
            cfg,
        }
    }
}

/// Diffuse wall scatterers: `scatterers_per_cell` per range cell c/2B of every wall.
fn diffuse_walls(
    layout: &Layout,
    cfg: &SceneConfig,
    bandwidth_hz: f64,
    rng: &mut ChaCha8Rng,
    sc: &mut Vec<Scatterer>,
) {
    let cell = C0 / (2.0 * bandwidth_hz);
    let density = cfg.scatterers_per_cell / cell;
    for (wi, w) in layout.walls.iter().enumerate() {
        let len = w.length();
        let n = (len * density).ceil() as usize;
        let sigma_each = cfg.wall_rcs_per_m * len / n as f64;
        let nrm = w.normal();
        for _ in 0..n {
            let t: f64 = rng.gen();
            let pos = w.line.start + w.line.delta() * t;
            sc.push(Scatterer {
                kind: ScattererKind::Diffuse,
                pos,
                x: cgauss(rng) * sigma_each.sqrt(),
                cluster: None,
                anchor: pos,
                normal: Some(nrm),
                wall: Some(wi),
            });
        }
    }
}

/// Corners (concave vertices of the perimeter) and edges (every other ring vertex).
fn corners_and_edges(
    layout: &Layout,
    cfg: &SceneConfig,
    rng: &mut ChaCha8Rng,
    sc: &mut Vec<Scatterer>,
) {
    let rings: Vec<(Vec<Coord<f64>>, bool)> =
        std::iter::once((layout.perimeter.exterior().0.clone(), true))
            .chain(
                layout
                    .obstacles
                    .iter()
                    .map(|o| (o.polygon.exterior().0.clone(), false)),
            )
            .collect();
    for (ring, is_perimeter) in rings {
        let n = ring.len() - 1;
        for i in 0..n {
            let a = ring[(i + n - 1) % n];
            let v = ring[i];
            let b = ring[(i + 1) % n];
            let cross = (v.x - a.x) * (b.y - v.y) - (v.y - a.y) * (b.x - v.x);
            // CCW ring: left turn = convex vertex of the polygon
            let concave_from_free = is_perimeter && cross > 0.0;
            let (kind, sigma) = if concave_from_free {
                (ScattererKind::Corner, cfg.corner_rcs_m2)
            } else {
                (ScattererKind::Edge, cfg.edge_rcs_m2)
            };
            let phase: f64 = rng.gen::<f64>() * 2.0 * PI;
            sc.push(Scatterer::point(
                kind,
                v,
                Complex64::from_polar(sigma.sqrt(), phase),
            ));
        }
    }
}

/// Clutter clusters along the perimeter: their rays as virtual scatterers behind the
/// centre, each seen through the centre's visibility (its anchor).
fn clutter_clusters(
    layout: &Layout,
    m: &ModelConfig,
    rng: &mut ChaCha8Rng,
    sc: &mut Vec<Scatterer>,
    clusters: &mut Vec<TruthCluster>,
) {
    let b = m.intra_cluster_aoa.value.to_radians() / 2f64.sqrt();
    let d_ref = 2.0;
    perimeter_walk(layout, m, rng, |rng, s, off, centre, nrm| {
        let tangent = Coord {
            x: nrm.y,
            y: -nrm.x,
        };
        let nrays = draw_rays(rng, m.rays_per_cluster.value);
        let sigma_c = draw_shadowed(rng, m.cluster_rrcs.value);
        if !layout.is_free(centre) {
            return;
        }
        let cid = clusters.len();
        let mut tau = 0.0;
        for r in 0..nrays {
            if r > 0 {
                tau += Exp::new(m.intra_cluster_rate.value)
                    .expect("positive")
                    .sample(rng);
            }
            // drawn for the reference ray too (keeps the stream)
            let lap = laplace(rng, b);
            let lap = if r == 0 { 0.0 } else { lap };
            // c₀·τ/2 in the scene's own operation order (its draws stay bit-for-bit)
            let depth = crate::units::C0 * tau * 1e-9 / 2.0;
            let lateral = d_ref * lap.tan();
            let pos = Coord {
                x: centre.x - nrm.x * depth + tangent.x * lateral,
                y: centre.y - nrm.y * depth + tangent.y * lateral,
            };
            let sigma = sigma_c * (-tau / m.ray_decay.value).exp();
            let phase: f64 = rng.gen::<f64>() * 2.0 * PI;
            sc.push(Scatterer {
                kind: ScattererKind::Clutter,
                pos,
                x: Complex64::from_polar(sigma.sqrt(), phase),
                cluster: Some(cid),
                anchor: centre,
                normal: None,
                wall: None,
            });
        }
        clusters.push(TruthCluster {
            centre,
            arc_m: s,
            offset_m: off,
            rays: nrays,
            sigma_m2: sigma_c,
        });
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg() -> SceneConfig {
        SceneConfig {
            walls: true,
            wall_rcs_per_m: 0.01,
            scatterers_per_cell: 20.0,
            specular: true,
            corner_rcs_m2: 0.1,
            edge_rcs_m2: 0.01,
            coupling_db: -30.0,
            coupling_delay_ns: 0.2,
            pattern_knots: 0,
            materials: BTreeMap::new(),
            targets: vec![],
        }
    }

    #[test]
    fn check_names_the_field_and_range() {
        assert!(cfg().check().is_ok());
        let e = SceneConfig {
            pattern_knots: 1,
            ..cfg()
        }
        .check()
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("scene.pattern_knots") && e.contains(">= 2"),
            "{e}"
        );
        let e = SceneConfig {
            scatterers_per_cell: 5.0,
            ..cfg()
        }
        .check()
        .unwrap_err()
        .to_string();
        assert!(e.contains("scene.scatterers_per_cell"), "{e}");
    }

    #[test]
    fn scene_depends_on_the_seed_only() {
        let square = r#"{"type":"FeatureCollection","features":[
          {"type":"Feature","properties":{"role":"perimeter"},
           "geometry":{"type":"Polygon","coordinates":[[[0,0],[4,0],[4,2],[0,2],[0,0]]]}}]}"#;
        let layout = Layout::from_geojson(square, std::path::Path::new("t.geojson")).unwrap();
        let build = |seed| Scene::build(layout.clone(), cfg().check().unwrap(), None, 6e9, seed);
        let (a, b) = (build(7), build(7));
        assert_eq!(a.scatterers.len(), b.scatterers.len());
        assert!(a
            .scatterers
            .iter()
            .zip(&b.scatterers)
            .all(|(x, y)| x.pos == y.pos && x.x == y.x));
        // four concave corners of the perimeter, the rest diffuse
        let corners = a
            .scatterers
            .iter()
            .filter(|s| s.kind == ScattererKind::Corner)
            .count();
        assert_eq!(corners, 4);
    }
}
