//! Physics-based campaign simulator (DESIGN §1, §2 "Scattering"): writes sweeps in the same
//! formats a VNA campaign would, plus its ground truth.
//!
//! Takes a manifest with the simulator-only `[scene]` and `[clutter]` (model schema)
//! sections and a layout; gives `DIR/campaign.toml` (with `[sweeps]`), the sweeps
//! (Touchstone or Parquet) and `DIR/truth/` (`scatterers.csv`, `clusters.csv`,
//! `rays.parquet`: every path seen from every position with its delay, angle and power).
//!
//! S21(f) for one (position, direction, pulse) is the coherent sum over paths
//! S21 = Σ F(θ_p, f)² · λ(f) · A_p · e^{−j2πf τ_p} + coupling + noise, with F the complex
//! one-way field of [`ArrayPattern`] (|F|² = gain; Tx and Rx identical, side by side),
//! evaluated at every frequency point (`pattern_knots = 0`, the default) or tabulated at
//! `pattern_knots` frequencies and interpolated linearly (faster, but the interpolation error
//! is periodic in frequency and shows as weak echo replicas at ±1/knot-spacing):
//! * point scatterer at range d with complex RRCS x (|x|² = σ): A = x / ((4π)^{3/2} d²),
//!   τ = 2d/c — the radar equation in amplitude;
//! * diffuse walls: σ per metre of wall spread over `scatterers_per_cell` (≥ 10) random
//!   off-grid scatterers per range cell (c/2B of wall length), complex Gaussian x, with a
//!   Lambertian factor √cos(incidence);
//! * specular walls (image method, monostatic: the normal-incidence point):
//!   A = Γ / (4π · 2d), Γ = (1 − √εr)/(1 + √εr) (Fresnel, normal incidence, εr complex);
//! * corners (dihedral, concave seen from the room), edges (convex: door frames, pillar and
//!   cabinet edges) as strong point scatterers;
//! * perimeter clutter clusters drawn from `[clutter]`: centres at arc-length spacing
//!   ~ family(d_c) along the perimeter, offset ~ family(d_p) into the room; rays with
//!   exponential excess delays (rate λ) and Laplacian angular offsets (std from the model,
//!   at a nominal 2 m viewing distance) as virtual scatterers behind the centre (multi-bounce
//!   paths appear beyond the wall), σ_ray = σ_c · e^{−τ/γ};
//! * optional `[[scene.targets]]` point targets; `walls = false` drops the layout's walls,
//!   corners and clutter (point-target scenes);
//! * Tx→Rx coupling: a −`coupling_db` term at `coupling_delay_ns` with a 2 GHz ripple (replicas at ±0.5 ns);
//! * complex white noise of variance floor/tx power per point, independent per pulse.
//!
//! Occlusion: a path is dropped when the segment from the pose to the scatterer crosses a
//! wall. Every random draw comes from the manifest seed: the scene from one ChaCha stream,
//! the noise of each sweep from its own stream keyed by (position, direction, pulse), so the
//! bytes do not depend on the thread count. The energy/mapping models know none of the
//! specular, Lambertian, clutter-geometry or coupling details (no inverse crime).

use crate::campaign::layout::Layout;
use crate::campaign::manifest::{one_line, Campaign, Steering, SweepFormat, SweepsConfig, C0};
use crate::campaign::modelfile::ModelConfig;
use crate::campaign::pattern::{ArrayPattern, PatternTable};
use crate::campaign::sweeps::{parquet_batch, write_touchstone_position, PositionSweeps};
use crate::error::{Error, Result};
use crate::table;
use geo::Coord;
use num_complex::Complex64;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp, Normal, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::Path;

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

impl SceneConfig {
    /// Validate; errors name the field.
    pub fn check(&self) -> Result<()> {
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
            if !(t.x_m.is_finite() && t.y_m.is_finite() && t.rrcs_m.is_finite() && t.rrcs_m > 0.0) {
                return Err(Error::param(
                    format!("scene.targets[{i}]"),
                    "x_m, y_m finite and rrcs_m > 0",
                ));
            }
        }
        Ok(())
    }

    fn material(&self, name: &str) -> Material {
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

/// One propagation path seen from a pose.
#[derive(Debug, Clone, Copy)]
pub struct Path1 {
    /// Round-trip delay, s.
    pub tau_s: f64,
    /// Global angle of arrival, rad.
    pub theta: f64,
    /// Frequency-independent amplitude factor A (S21 = F²·λ·A·e^{−j2πfτ}).
    pub amp: Complex64,
    /// Index into the scatterer list (usize::MAX for specular).
    pub scatterer: usize,
    /// Kind.
    pub kind: ScattererKind,
    /// Reflection point, m.
    pub pos: Coord<f64>,
}

/// The built scene.
pub struct Scene {
    /// Scatterers.
    pub scatterers: Vec<Scatterer>,
    /// Clutter clusters.
    pub clusters: Vec<TruthCluster>,
    layout: Layout,
    cfg: SceneConfig,
}

fn draw(rng: &mut ChaCha8Rng, family: &str, mean: f64) -> f64 {
    match family {
        "constant" => mean,
        "gaussian" => Normal::new(mean, 0.3 * mean)
            .expect("finite")
            .sample(rng)
            .max(0.05 * mean),
        _ => Exp::new(1.0 / mean).expect("positive").sample(rng),
    }
}

fn cgauss(rng: &mut ChaCha8Rng) -> Complex64 {
    let a: f64 = StandardNormal.sample(rng);
    let b: f64 = StandardNormal.sample(rng);
    Complex64::new(a, b) * std::f64::consts::FRAC_1_SQRT_2
}

/// Rays of a cluster: 1 + Poisson(mean − 1).
pub fn draw_rays(rng: &mut ChaCha8Rng, mean: f64) -> usize {
    let mean_extra = (mean - 1.0).max(0.0);
    1 + rand_distr::Poisson::new(mean_extra.max(1e-9))
        .map(|d| d.sample(rng) as usize)
        .unwrap_or(0)
}

/// A cluster's σ: `mean` times log-normal shadowing of 0.69 neper (3 dB) standard deviation.
pub fn draw_shadowed(rng: &mut ChaCha8Rng, mean: f64) -> f64 {
    mean * Normal::<f64>::new(0.0, 0.69).expect("ok").sample(rng).exp()
}

/// A zero-mean Laplacian draw of scale `b` (inverse CDF).
pub fn laplace(rng: &mut ChaCha8Rng, b: f64) -> f64 {
    let u: f64 = rng.gen::<f64>() - 0.5;
    -b * u.signum() * (1.0 - 2.0 * u.abs()).ln()
}

/// Walk the layout perimeter placing cluster centres (DESIGN §2: clusters along the
/// perimeter): the first at an arc length uniform in [0, d_c), then spacings drawn from
/// `perimeter_spacing` (its family, at least 0.05 m); each centre offset into the room along
/// the inward normal by a draw from `perimeter_offset` (at most 1.5 m). `each(rng, arc,
/// offset, centre, normal)` is called per centre right after its offset draw, so it may draw
/// the cluster's contents from the same stream; it decides whether to keep the centre.
pub fn perimeter_walk(
    layout: &Layout,
    m: &ModelConfig,
    rng: &mut ChaCha8Rng,
    mut each: impl FnMut(&mut ChaCha8Rng, f64, f64, Coord<f64>, Coord<f64>),
) {
    let total = layout.perimeter_length();
    let mut s = rng.gen::<f64>() * m.perimeter_spacing.value;
    while s < total {
        let (p, nrm) = layout.perimeter_point(s);
        let off = draw(rng, &m.perimeter_offset.family, m.perimeter_offset.value).min(1.5);
        let centre = Coord {
            x: p.x + nrm.x * off,
            y: p.y + nrm.y * off,
        };
        each(rng, s, off, centre, nrm);
        s += draw(rng, &m.perimeter_spacing.family, m.perimeter_spacing.value).max(0.05);
    }
}

impl Scene {
    /// Build the pose-independent scatterers from the layout, `[scene]` and `[clutter]`.
    pub fn build(
        layout: Layout,
        cfg: SceneConfig,
        clutter: Option<&ModelConfig>,
        bandwidth_hz: f64,
        seed: u64,
    ) -> Scene {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut sc = Vec::new();
        let mut clusters = Vec::new();
        if cfg.walls {
            let cell = C0 / (2.0 * bandwidth_hz);
            let density = cfg.scatterers_per_cell / cell;
            for w in &layout.walls {
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
                        x: cgauss(&mut rng) * sigma_each.sqrt(),
                        cluster: None,
                        anchor: pos,
                        normal: Some(nrm),
                    });
                }
            }
            // corners and edges
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
                    sc.push(Scatterer {
                        kind,
                        pos: v,
                        x: Complex64::from_polar(sigma.sqrt(), phase),
                        cluster: None,
                        anchor: v,
                        normal: None,
                    });
                }
            }
            if let Some(m) = clutter {
                let b = m.intra_cluster_aoa.value.to_radians() / 2f64.sqrt();
                let d_ref = 2.0;
                perimeter_walk(&layout, m, &mut rng, |rng, s, off, centre, nrm| {
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
                        let depth = crate::units::range_m(tau);
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
        }
        for t in &cfg.targets {
            let pos = Coord { x: t.x_m, y: t.y_m };
            sc.push(Scatterer {
                kind: ScattererKind::Target,
                pos,
                x: Complex64::new(t.rrcs_m, 0.0),
                cluster: None,
                anchor: pos,
                normal: None,
            });
        }
        Scene {
            scatterers: sc,
            clusters,
            layout,
            cfg,
        }
    }

    /// Every path visible from `pose` (x, y).
    pub fn paths(&self, at: Coord<f64>) -> Vec<Path1> {
        let k = (4.0 * PI).powf(1.5);
        let mut out: Vec<Path1> = self
            .scatterers
            .par_iter()
            .enumerate()
            .filter_map(|(i, s)| {
                let d = s.pos - at;
                let r = d.x.hypot(d.y);
                if r < 0.05 {
                    return None;
                }
                let mut amp = s.x / (k * r * r);
                if let Some(n) = s.normal {
                    let cos = -(d.x * n.x + d.y * n.y) / r;
                    if cos <= 0.0 {
                        return None;
                    }
                    amp *= cos.sqrt();
                }
                let occluded = if self.cfg.walls {
                    self.layout.occluded(at, s.anchor, 1e-3)
                } else {
                    false
                };
                if occluded {
                    return None;
                }
                Some(Path1 {
                    tau_s: crate::units::delay_s(r),
                    theta: d.y.atan2(d.x),
                    amp,
                    scatterer: i,
                    kind: s.kind,
                    pos: s.pos,
                })
            })
            .collect();
        if self.cfg.walls && self.cfg.specular {
            for w in &self.layout.walls {
                let dl = w.line.delta();
                let l2 = dl.x * dl.x + dl.y * dl.y;
                let t = ((at.x - w.line.start.x) * dl.x + (at.y - w.line.start.y) * dl.y) / l2;
                if !(0.0..=1.0).contains(&t) {
                    continue;
                }
                let foot = w.line.start + dl * t;
                let n = w.normal();
                let v = at - foot;
                let d = v.x.hypot(v.y);
                if d < 0.05 || v.x * n.x + v.y * n.y <= 0.0 || self.layout.occluded(at, foot, 1e-3)
                {
                    continue;
                }
                let gamma = self.cfg.material(&w.material).gamma();
                out.push(Path1 {
                    tau_s: crate::units::delay_s(d),
                    theta: (-v.y).atan2(-v.x),
                    amp: gamma / (4.0 * PI * 2.0 * d),
                    scatterer: usize::MAX,
                    kind: ScattererKind::Specular,
                    pos: foot,
                });
            }
        }
        out
    }
}

/// Synthesise the noise-free S21 of one (pose, direction) from its paths into `acc`.
#[allow(clippy::too_many_arguments)]
pub fn synth_sweep(
    paths: &[Path1],
    table: &PatternTable,
    heading: f64,
    theta_s: f64,
    steering: Steering,
    band: &crate::campaign::manifest::Band,
    cull: f64,
    acc: &mut [Complex64],
) {
    let nk = table.knots();
    let nf = band.points;
    let df = band.step_hz();
    let mut g = vec![Complex64::new(0.0, 0.0); nk];
    let exact = nk == nf;
    let lambdas: Vec<f64> = (0..nf).map(|k| C0 / band.freq(k)).collect();
    // frequency index range of each knot segment
    let seg: Vec<(usize, usize)> = (0..nk - 1)
        .map(|i| {
            let a = ((table.knot_hz(i) - band.start_hz) / df).ceil() as usize;
            let b = if i == nk - 2 {
                nf
            } else {
                ((table.knot_hz(i + 1) - band.start_hz) / df).ceil() as usize
            };
            (a.min(nf), b.min(nf))
        })
        .collect();
    for p in paths {
        let th = match steering {
            Steering::Mechanical => p.theta - heading - theta_s,
            Steering::Electronic => p.theta - heading,
        };
        let th = (th + PI).rem_euclid(2.0 * PI) - PI;
        if th.abs() >= PI / 2.0 {
            continue;
        }
        if exact {
            // the pattern at every frequency point: no interpolation in frequency
            let Some((ai, t)) = table.angle_cell(th) else {
                continue;
            };
            let (r0, r1) = (table.knots_at(ai), table.knots_at(ai + 1));
            // cull paths far below the noise (checked at five frequencies, with 20 dB slack)
            let est = [0, nf / 4, nf / 2, 3 * nf / 4, nf - 1]
                .iter()
                .map(|&k| (r0[k] * (1.0 - t) + r1[k] * t).norm_sqr() * lambdas[k] * p.amp.norm())
                .fold(0.0, f64::max);
            if est < 0.1 * cull {
                continue;
            }
            let mut ph = Complex64::from_polar(1.0, -2.0 * PI * (band.start_hz * p.tau_s).fract());
            let step = Complex64::from_polar(1.0, -2.0 * PI * (df * p.tau_s).fract());
            for ((v, (a, b)), lam) in acc.iter_mut().zip(r0.iter().zip(r1)).zip(&lambdas) {
                let f = a * (1.0 - t) + b * t;
                *v += f * f * (lam * p.amp) * ph;
                ph *= step;
            }
            continue;
        }
        let mut gmax = 0.0f64;
        for (ki, gk) in g.iter_mut().enumerate() {
            let f = table.at_knot(th, ki);
            let lambda = C0 / table.knot_hz(ki);
            *gk = f * f * lambda * p.amp;
            gmax = gmax.max(gk.norm());
        }
        if gmax < cull {
            continue;
        }
        for (i, &(a, b)) in seg.iter().enumerate() {
            if a >= b {
                continue;
            }
            let (fa, fb) = (table.knot_hz(i), table.knot_hz(i + 1));
            let (ga, gb) = (g[i], g[i + 1]);
            let f0 = band.freq(a);
            let mut ph = Complex64::from_polar(1.0, -2.0 * PI * (f0 * p.tau_s).fract());
            let step = Complex64::from_polar(1.0, -2.0 * PI * (df * p.tau_s).fract());
            let dg = (gb - ga) * (df / (fb - fa));
            let mut gv = ga + (gb - ga) * ((f0 - fa) / (fb - fa));
            for v in acc[a..b].iter_mut() {
                *v += gv * ph;
                ph *= step;
                gv += dg;
            }
        }
    }
}

/// What `simulate` produced.
#[derive(Debug, Clone)]
pub struct SimReport {
    /// Sweeps written.
    pub sweeps: usize,
    /// Scatterers in the scene.
    pub scatterers: usize,
    /// Clutter clusters.
    pub clusters: usize,
    /// Path of the written manifest.
    pub manifest: std::path::PathBuf,
}

fn noise_seed(seed: u64, p: usize, d: usize, k: usize) -> u64 {
    // splitmix64 over the indices: independent streams per sweep
    let mut z =
        seed ^ ((p as u64) << 40 ^ (d as u64) << 20 ^ k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Read `[scene]` and `[clutter]` from the manifest text (simulator only).
pub fn scene_sections(c: &Campaign) -> Result<(SceneConfig, Option<ModelConfig>)> {
    let text = crate::io::read_text(&c.path)?;
    let t: toml::Table =
        toml::from_str(&text).map_err(|e| Error::input(&c.path, one_line(&e.to_string())))?;
    let scene_v = t
        .get("scene")
        .cloned()
        .ok_or_else(|| Error::input(&c.path, "simulate needs a [scene] section"))?;
    let scene: SceneConfig = scene_v.try_into().map_err(|e: toml::de::Error| {
        Error::input(&c.path, format!("[scene]: {}", one_line(&e.to_string())))
    })?;
    scene
        .check()
        .map_err(|e| Error::input(&c.path, e.to_string()))?;
    let clutter = match t.get("clutter") {
        Some(v) => Some(ModelConfig::from_value(v.clone(), &c.path, "clutter")?),
        None => None,
    };
    Ok((scene, clutter))
}

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
                f(&|r| crate::energy::wrap_deg(r.angle_global_deg - heading_deg)),
            ),
            table::col("power_db", f(&|r| r.power_db)),
        ],
    )
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

/// Run the simulator: write the campaign into `out_dir`.
pub fn simulate(
    c: &Campaign,
    out_dir: &Path,
    format: SweepFormat,
    progress: &dyn Fn(usize, usize),
) -> Result<SimReport> {
    let m = &c.manifest;
    let (scene_cfg, clutter) = scene_sections(c)?;
    let layout = Layout::load(&c.layout_path())?;
    let knots = if scene_cfg.pattern_knots == 0 {
        m.band.points
    } else {
        scene_cfg.pattern_knots
    };
    let scene = Scene::build(
        layout,
        scene_cfg.clone(),
        clutter.as_ref(),
        m.band.bandwidth_hz(),
        m.seed,
    );
    let pattern = ArrayPattern::new(m.array, m.band.center_hz())?;
    let angles = m.directions.angles_deg();
    let tables = pattern.tables(&angles, &m.band, knots);
    let nd = angles.len();
    let (np, nk, nf) = (m.positions(), m.pulses, m.band.points);
    let sigma2 = m.noise.s21_variance();
    let sigma = (sigma2 / 2.0).sqrt();
    let cull = 1e-5 * sigma2.sqrt();
    let coupling_amp = 10f64.powf(-scene_cfg.coupling_db.abs() / 20.0);
    let tau_c = scene_cfg.coupling_delay_ns * 1e-9;
    let coupling: Vec<Complex64> = (0..nf)
        .map(|k| {
            let f = m.band.freq(k);
            let ripple = 1.0 + 0.1 * (2.0 * PI * (f - m.band.start_hz) / 2.0e9).cos();
            Complex64::from_polar(coupling_amp * ripple, -2.0 * PI * (f * tau_c).fract())
        })
        .collect();
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let truth_dir = out_dir.join("truth");
    std::fs::create_dir_all(&truth_dir).map_err(|e| Error::io(&truth_dir, e))?;
    let pattern_str = "sweeps/p{position:03}_d{direction:02}_k{pulse:02}.s2p".to_string();
    let sweeps_pq = out_dir.join("sweeps.parquet");
    let mut pq = match format {
        SweepFormat::Parquet => Some(table::ParquetStream::create(&sweeps_pq)?),
        SweepFormat::Touchstone => None,
    };
    let rays_path = truth_dir.join("rays.parquet");
    let mut rays = table::ParquetStream::create(&rays_path)?;
    let g0 = pattern.gain(0.0, 0.0, m.band.center_hz());
    let lc = C0 / m.band.center_hz();
    for p in 0..np {
        let pose = m.poses[p];
        let at = Coord {
            x: pose.x_m,
            y: pose.y_m,
        };
        let heading = pose.heading_deg.to_radians();
        let paths = scene.paths(at);
        let mut s21 = vec![Complex64::new(0.0, 0.0); nd * nk * nf];
        s21.par_chunks_mut(nk * nf)
            .enumerate()
            .for_each(|(d, chunk)| {
                let mut clean = coupling.clone();
                synth_sweep(
                    &paths,
                    &tables[d],
                    heading,
                    angles[d].to_radians(),
                    m.array.steering,
                    &m.band,
                    cull,
                    &mut clean,
                );
                for k in 0..nk {
                    let mut rng = ChaCha8Rng::seed_from_u64(noise_seed(m.seed, p, d, k));
                    for (o, cv) in chunk[k * nf..(k + 1) * nf].iter_mut().zip(&clean) {
                        let a: f64 = StandardNormal.sample(&mut rng);
                        let b: f64 = StandardNormal.sample(&mut rng);
                        *o = cv + Complex64::new(a, b) * sigma;
                    }
                }
            });
        let sw = PositionSweeps {
            position: p,
            directions: nd,
            pulses: nk,
            points: nf,
            s21,
        };
        match pq.as_mut() {
            Some(w) => w.write(&parquet_batch(&sweeps_pq, &m.band, &sw)?)?,
            None => write_touchstone_position(
                out_dir,
                &pattern_str,
                &m.band,
                &sw,
                &format!("pradar simulate: campaign {} position {p}\nS21 = backscatter channel (Tx port 1, Rx port 2); S11, S22 not simulated", m.name),
            )?,
        }
        // truth rays of this position
        let sid = |path: &Path1| (path.scatterer != usize::MAX).then_some(path.scatterer);
        let rows: Vec<TruthRay> = paths
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
                // boresight received power |S21|² = G0²·λc²·|A|²
                power_db: 10.0 * (g0 * g0 * lc * lc * x.amp.norm_sqr()).log10(),
            })
            .collect();
        let df = truth_rays_frame(&rays_path, p, pose.heading_deg, &rows)?;
        rays.write(&df)?;
        progress(p + 1, np);
    }
    if let Some(w) = pq {
        w.finish(None)?;
    }
    rays.finish(None)?;
    // scatterers and clusters
    let s = &scene.scatterers;
    let mut sdf = table::frame(
        &truth_dir,
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
    table::write_csv(&truth_dir.join("scatterers.csv"), &mut sdf)?;
    write_truth_clusters(&truth_dir, &scene.clusters)?;
    // the layout and the manifest
    let layout_out = out_dir.join("layout.geojson");
    let layout_text = crate::io::read_text(&c.layout_path())?;
    crate::io::write_bytes(&layout_out, layout_text.as_bytes())?;
    let text = crate::io::read_text(&c.path)?;
    let mut t: toml::Table =
        toml::from_str(&text).map_err(|e| Error::input(&c.path, one_line(&e.to_string())))?;
    t.insert(
        "layout".into(),
        toml::Value::String("layout.geojson".into()),
    );
    if let Some(toml::Value::Table(a)) = t.get_mut("array") {
        a.insert(
            "elements".into(),
            toml::Value::Integer(m.array.elements as i64),
        );
    }
    let sweeps = match format {
        SweepFormat::Touchstone => SweepsConfig {
            format,
            pattern: Some(pattern_str),
            files: vec![],
            path: None,
        },
        SweepFormat::Parquet => SweepsConfig {
            format,
            pattern: None,
            files: vec![],
            path: Some("sweeps.parquet".into()),
        },
    };
    t.insert(
        "sweeps".into(),
        toml::Value::try_from(&sweeps).map_err(|e| Error::input(&c.path, e.to_string()))?,
    );
    let manifest_out = out_dir.join("campaign.toml");
    let body = toml::to_string(&t).map_err(|e| Error::input(&manifest_out, e.to_string()))?;
    crate::io::write_bytes(
        &manifest_out,
        format!(
            "# written by pradar simulate from {}\n{body}",
            c.path.display()
        )
        .as_bytes(),
    )?;
    Ok(SimReport {
        sweeps: np * nd * nk,
        scatterers: scene.scatterers.len(),
        clusters: scene.clusters.len(),
        manifest: manifest_out,
    })
}
