//! The scene zoo: a seeded generator of physics scenes unlike each other
//! and unlike the built-in corridor, the acceptance test of the chain (`pradar zoo`,
//! `scripts/zoo`, `docs/zoo.md`).
//!
//! [`generate`]`(seed, count)` gives `count` [`ZooScene`]s, each a layout (GeoJSON text) and a
//! campaign manifest (TOML text with `[scene]` and `[clutter]`) that `pradar simulate` takes
//! as they are; [`ZooScene::twin`] is the same campaign with nothing in it (noise and
//! coupling only: the N0 reference) and [`ZooScene::realisation`] the same scene drawn with
//! another seed (the check's second realisation). [`write`] puts them in `DIR/<name>/`,
//! `DIR/<name>-twin/` and `DIR/<name>-r2/` and lists them in `DIR/scenes.tsv`.
//!
//! Determinism: one ChaCha8 stream seeded with `seed` draws one 64-bit key per scene, and
//! each scene is drawn from its own ChaCha8 stream of that key, so the same seed gives the
//! same bytes and `generate(seed, n)` is the first `n` scenes of `generate(seed, m)`, m > n.
//!
//! # Families (scene `i` is family `i mod 7`)
//! * `room`: W × H, each 3–12 m, an alcove (0.8–2 m wide, 0.4–1.2 m deep) in one wall with
//!   probability 0.6, 0–2 obstacles;
//! * `office`: a room of 6–12 m with 3–8 obstacles (desks, cabinets, a pillar, a glass
//!   partition);
//! * `corridor`: 10–60 m long, 1.5–3.5 m wide, 0–4 door recesses (0.8–1.2 m wide,
//!   0.2–0.6 m deep), 0–3 obstacles;
//! * `l-hall`: two arms of 15–70 m and 10–70 m, 2–6 m wide;
//! * `t-hall`: a bar of 20–70 m, 2.5–6 m wide, with a stem of 8–40 m, 2–5 m wide;
//! * `u-hall`: a base of 15–50 m and two legs of 10–40 m, 2–5 m wide;
//! * `hall`: an open hall of 20–70 m × 10–25 m with a grid of concrete pillars every 5–10 m.
//!
//! Obstacles are rectangles: desks (wood, 1.2–1.8 × 0.6–0.8 m), cabinets (metal,
//! 0.4–1.0 × 0.4–0.6 m), pillars (concrete, 0.3–0.8 m square), partitions (glass,
//! 1–2 m × 0.05 m), kept 0.1 m inside the walls, 0.2 m from each other and 0.4 m from the
//! trajectory. About a third of the scenes are turned by a uniform angle (walls off the map
//! grid). 0–2 point targets (√σ 0.1–0.7 m, our choice: a person or a metal post) with
//! probability 0.4.
//!
//! The perimeter's material cycles over plasterboard, concrete, glass, wood and metal
//! (scene `i` takes `i mod 5`), so any zoo of five or more scenes has all five; N cycles over
//! 16, 100, 400 (`i mod 3`); the step is one of 2.5, 3, 4, 4.5, 5, 6, 7.5, 9, 10° (steps that
//! divide the half-plane), 1–4 pulses, one-bit or ideal phases.
//!
//! Trajectories (12–40 poses at equal arc length along a route): `line` (a straight route),
//! `loop` (a closed rectangle inside a room or hall), `turn` (a route through the L, T or
//! U's corners), with the heading `along` the route, `changes` (the route's direction plus
//! an offset of 0, ±45, ±90 or 180° held for 3–6 poses) or `spin` (turning by 15–45° per
//! pose). Affordability: poses × directions × pulses ≤ [`SWEEP_BUDGET`] (poses dropped
//! first, then pulses), which keeps one `pradar simulate` under a minute on two cores
//! (measured in `docs/zoo.md`).
//!
//! # Materials ([`materials`])
//! ε_r and tan δ at 60 GHz from ITU-R P.2040-1 (07/2015), Table 3: ε_r = a, σ = c·f^d
//! (f in GHz, S/m), tan δ = σ/(2πf ε₀ ε_r): concrete (5.31, 0.0326, 0.8095) → tan δ 0.051,
//! plasterboard (2.94, 0.0116, 0.7076) → 0.021, glass (6.27, 0.0043, 1.1925) → 0.027, wood
//! (1.99, 0.0047, 1.0718) → 0.057; metal (σ = 10⁷ S/m) as the simulator's conductor
//! (ε_r = 10⁸, |Γ| = 1), as in the corridor.
//!
//! # Clutter ranges (`[clutter]`, log-uniform within each)
//! * intra-cluster ray rate λ 0.2–1.0 /ns: the IEEE 802.11ad conference-room model
//!   (Maltsev et al., IEEE 802.11-09/0334r8, 2010: 0.31–0.37 /ns) and the source paper's
//!   Table 1 (0.43 /ns) lie inside; the upper end is our choice (denser rays resolved by
//!   6 GHz of bandwidth);
//! * ray decay γ 2–6 ns: 802.11ad's 3.7–4.5 ns inside; ends our choice;
//! * cluster decay Γ 5–25 ns: our choice around the corridor's 12 ns (60 GHz indoor cluster
//!   decays of a few to a few tens of ns: Gustafson et al., "On mm-wave multipath clustering
//!   and channel modeling", IEEE TAP 62(3), 2014);
//! * inter-cluster rate Λ 0.1–0.4 /ns: around the source paper's 0.21 /ns (our choice; the
//!   simulator places clusters by d_c, not by Λ);
//! * intra-cluster AoA std 5–30° (Laplacian): the source paper's 16.9° inside; ends our
//!   choice, spanning the few-degree to ~20° intra-cluster azimuth spreads reported at
//!   60 GHz indoors (Xu, Kukshya, Rappaport, IEEE JSAC 20(3), 2002; Gustafson et al. 2014);
//! * perimeter spacing d_c 0.75–4 m (the paper's 5.02 ns one-way, 1.505 m, inside; ends our
//!   choice), exponential, or Gaussian in a quarter of the scenes (regularly spaced
//!   furniture: our choice); perimeter offset d_p 0.1–0.8 m (our choice);
//! * rays per cluster 3–10 (802.11ad's 4 post-cursor rays plus the cluster's first inside;
//!   our choice), cluster σ 0.003–0.03 m² (our choice around the corridor's 0.01 m²);
//! * `[scene]`: diffuse wall σ′ 0.005–0.05 m²/m, corner σ 0.1–1 m², edge σ 0.01–0.1 m² (our
//!   choice around the corridor's 0.02, 0.5 and 0.05).
//!
//! Processing is the corridor's (801 points over 57.5–63.5 GHz, Hann, oversample 5, gated
//! coupling of 3 ns, `max_delay_ns` 80, `noise_from_ns` 100): the unambiguous delay is
//! 1/7.5 MHz = 133 ns (20 m one way), so echoes from farther walls of the large halls alias
//! into the noise bins. That is deliberate: the zoo measures what the chain does there.

use crate::campaign::manifest::{
    ArrayConfig, Band, CouplingRemoval, Directions, Manifest, NoiseConfig, Pose, Processing,
    Steering, WindowKind, SCHEMA_VERSION,
};
use crate::error::{Error, Result};
use crate::model::file::{ModelConfig, Quantity};
use crate::simulate::{Material, PointTarget, SceneConfig};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Largest poses × directions × pulses of a zoo scene (its simulation time is about
/// proportional; `docs/zoo.md` gives the measured times).
pub const SWEEP_BUDGET: usize = 4000;

/// The five materials of the zoo, in the order the perimeter cycles through them.
pub const MATERIALS: [&str; 5] = ["plasterboard", "concrete", "glass", "wood", "metal"];

/// The allowed direction steps, degrees (each divides 180).
const STEPS: [f64; 9] = [2.5, 3.0, 4.0, 4.5, 5.0, 6.0, 7.5, 9.0, 10.0];

/// A scene family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// A room of 3–12 m, maybe with an alcove.
    Room,
    /// A furnished room of 6–12 m.
    Office,
    /// A corridor of 10–60 m with door recesses.
    Corridor,
    /// An L-shaped hall.
    LHall,
    /// A T-shaped hall.
    THall,
    /// A U-shaped hall.
    UHall,
    /// An open hall with a pillar grid.
    Hall,
}

impl Family {
    /// All families, in the order scenes cycle through them.
    pub const ALL: [Family; 7] = [
        Family::Room,
        Family::Office,
        Family::Corridor,
        Family::LHall,
        Family::THall,
        Family::UHall,
        Family::Hall,
    ];

    /// Its name in scene names.
    pub fn name(&self) -> &'static str {
        match self {
            Family::Room => "room",
            Family::Office => "office",
            Family::Corridor => "corridor",
            Family::LHall => "l-hall",
            Family::THall => "t-hall",
            Family::UHall => "u-hall",
            Family::Hall => "hall",
        }
    }
}

/// ε_r and tan δ of the zoo's materials at 60 GHz (ITU-R P.2040-1 Table 3; metal as the
/// simulator's conductor). See the module documentation.
pub fn materials() -> BTreeMap<String, Material> {
    let f_ghz = 60.0;
    let itu = |a: f64, c: f64, d: f64| {
        let sigma = c * f64::powf(f_ghz, d);
        let tan = sigma / (2.0 * PI * f_ghz * 1e9 * 8.854_187_8e-12 * a);
        Material {
            eps_r: a,
            loss_tangent: (tan * 1e4).round() / 1e4,
        }
    };
    let mut m = BTreeMap::new();
    m.insert("concrete".into(), itu(5.31, 0.0326, 0.8095));
    m.insert("plasterboard".into(), itu(2.94, 0.0116, 0.7076));
    m.insert("glass".into(), itu(6.27, 0.0043, 1.1925));
    m.insert("wood".into(), itu(1.99, 0.0047, 1.0718));
    m.insert(
        "metal".into(),
        Material {
            eps_r: 1e8,
            loss_tangent: 0.0,
        },
    );
    m
}

type P = [f64; 2];

/// An obstacle of the layout.
#[derive(Debug, Clone, PartialEq)]
struct Obstacle {
    name: String,
    material: &'static str,
    ring: Vec<P>,
}

/// Everything a zoo scene is made of (the texts are rendered from it).
#[derive(Debug, Clone, PartialEq)]
struct Spec {
    name: String,
    family: Family,
    seed: u64,
    perimeter: Vec<P>,
    perimeter_material: &'static str,
    obstacles: Vec<Obstacle>,
    poses: Vec<Pose>,
    elements: usize,
    one_bit: bool,
    step_deg: f64,
    pulses: usize,
    scene: SceneConfig,
    clutter: Option<ModelConfig>,
    description: String,
    layout_title: String,
}

/// One generated scene: a campaign manifest and its layout, as text.
#[derive(Debug, Clone, PartialEq)]
pub struct ZooScene {
    /// Scene name (the campaign name and the folder name), e.g. `z03-l-hall`.
    pub name: String,
    /// Its family.
    pub family: Family,
    /// One line: size, materials, obstacles, trajectory, N, step, pulses, clutter.
    pub description: String,
    /// The layout, GeoJSON text.
    pub layout: String,
    /// The manifest, TOML text (`layout = "layout.geojson"`, with `[scene]` and, except in
    /// a twin, `[clutter]`).
    pub manifest: String,
    spec: Spec,
}

impl ZooScene {
    fn from_spec(spec: Spec) -> ZooScene {
        ZooScene {
            name: spec.name.clone(),
            family: spec.family,
            description: spec.description.clone(),
            layout: render_layout(&spec),
            manifest: render_manifest(&spec),
            spec,
        }
    }

    /// The same campaign with nothing in it (`<name>-twin`): `[scene] walls = false`,
    /// `specular = false`, no targets, no `[clutter]`; the simulator then gives noise and
    /// the coupling only (which `processing.coupling = "gate"` removes), so its N0 is the
    /// true noise level of the scene.
    pub fn twin(&self) -> ZooScene {
        let mut s = self.spec.clone();
        s.name = format!("{}-twin", self.spec.name);
        s.scene.walls = false;
        s.scene.specular = false;
        s.scene.targets.clear();
        s.clutter = None;
        s.description = format!("noise-only twin of {}", self.spec.name);
        ZooScene::from_spec(s)
    }

    /// Realisation `k` of the same scene (same layout, poses and laws, another `seed`):
    /// k = 1 is the scene itself, k ≥ 2 is named `<name>-r<k>`.
    pub fn realisation(&self, k: u64) -> ZooScene {
        if k <= 1 {
            return self.clone();
        }
        let mut s = self.spec.clone();
        s.name = format!("{}-r{k}", self.spec.name);
        s.seed = self.spec.seed.wrapping_add((k - 1).wrapping_mul(1_000_003)) % 1_000_000_000;
        s.description = format!("realisation {k} of {} (seed {})", self.spec.name, s.seed);
        ZooScene::from_spec(s)
    }

    /// The manifest seed.
    pub fn seed(&self) -> u64 {
        self.spec.seed
    }

    /// Poses, directions and pulses: the sweeps `simulate` writes.
    pub fn sweeps(&self) -> usize {
        let d = (180.0 / self.spec.step_deg).round() as usize + 1;
        self.spec.poses.len() * d * self.spec.pulses
    }

    /// The array's element count.
    pub fn elements(&self) -> usize {
        self.spec.elements
    }

    /// The perimeter's material.
    pub fn perimeter_material(&self) -> &'static str {
        self.spec.perimeter_material
    }

    /// The bounding box of the perimeter, (width, height) in m (before any turn).
    pub fn extent_m(&self) -> (f64, f64) {
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in &self.spec.perimeter {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
        (x1 - x0, y1 - y0)
    }
}

/// `count` zoo scenes from `seed` (deterministic; see the module documentation).
pub fn generate(seed: u64, count: usize) -> Vec<ZooScene> {
    let mut master = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|i| {
            let key: u64 = master.gen();
            ZooScene::from_spec(draw_scene(i, key))
        })
        .collect()
}

/// Write every scene, its twin and its second realisation: `DIR/<name>/`,
/// `DIR/<name>-twin/`, `DIR/<name>-r2/`, each with `campaign.toml` and `layout.geojson`,
/// and `DIR/scenes.tsv` (name, family, sweeps, description). Returns the scene folders.
pub fn write(dir: &Path, scenes: &[ZooScene]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let mut out = Vec::new();
    let mut tsv = String::from("name\tfamily\tsweeps\tdescription\n");
    for s in scenes {
        for v in [s.clone(), s.twin(), s.realisation(2)] {
            let d = dir.join(&v.name);
            std::fs::create_dir_all(&d).map_err(|e| Error::io(&d, e))?;
            crate::io::write_bytes(&d.join("layout.geojson"), v.layout.as_bytes())?;
            crate::io::write_bytes(&d.join("campaign.toml"), v.manifest.as_bytes())?;
            out.push(d);
        }
        let _ = writeln!(
            tsv,
            "{}\t{}\t{}\t{}",
            s.name,
            s.family.name(),
            s.sweeps(),
            s.description
        );
    }
    crate::io::write_bytes(&dir.join("scenes.tsv"), tsv.as_bytes())?;
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// drawing

fn uni(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.gen::<f64>()
}

fn log_uni(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    (lo.ln() + (hi.ln() - lo.ln()) * rng.gen::<f64>()).exp()
}

/// Round to `step` (geometry to the centimetre, laws to three significant digits).
fn q(v: f64, step: f64) -> f64 {
    ((v / step).round() * step * 1e9).round() / 1e9
}

fn sig3(v: f64) -> f64 {
    if v == 0.0 {
        return 0.0;
    }
    let e = v.abs().log10().floor() as i32 - 2;
    q(v, 10f64.powi(e))
}

/// An axis-aligned rectangle (x0, y0, x1, y1).
#[derive(Debug, Clone, Copy)]
struct Rect([f64; 4]);

impl Rect {
    fn ring(&self) -> Vec<P> {
        let [x0, y0, x1, y1] = self.0;
        vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }
    fn grow(&self, m: f64) -> Rect {
        let [x0, y0, x1, y1] = self.0;
        Rect([x0 - m, y0 - m, x1 + m, y1 + m])
    }
    fn overlaps(&self, o: &Rect) -> bool {
        self.0[0] < o.0[2] && o.0[0] < self.0[2] && self.0[1] < o.0[3] && o.0[1] < self.0[3]
    }
    fn contains(&self, p: P) -> bool {
        p[0] >= self.0[0] && p[0] <= self.0[2] && p[1] >= self.0[1] && p[1] <= self.0[3]
    }
    /// Distance from the rectangle to a segment (0 when they touch), sampled finely.
    fn dist_segment(&self, a: P, b: P) -> f64 {
        let n = 200;
        (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                let p = [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
                let dx = (self.0[0] - p[0]).max(p[0] - self.0[2]).max(0.0);
                let dy = (self.0[1] - p[1]).max(p[1] - self.0[3]).max(0.0);
                dx.hypot(dy)
            })
            .fold(f64::MAX, f64::min)
    }
}

/// A shape: its perimeter, the rectangles it is made of (where obstacles may go), the
/// trajectory's route and a description.
struct Shape {
    perimeter: Vec<P>,
    rects: Vec<Rect>,
    route: Vec<P>,
    closed: bool,
    traj: &'static str,
    detail: String,
}

/// The kinds of obstacle.
#[derive(Clone, Copy)]
enum Kind {
    Desk,
    Cabinet,
    Pillar,
    Partition,
}

fn obstacle_size(rng: &mut ChaCha8Rng, k: Kind) -> (f64, f64, &'static str, &'static str) {
    let (w, h, m, n) = match k {
        Kind::Desk => (uni(rng, 1.2, 1.8), uni(rng, 0.6, 0.8), "wood", "desk"),
        Kind::Cabinet => (uni(rng, 0.4, 1.0), uni(rng, 0.4, 0.6), "metal", "cabinet"),
        Kind::Pillar => {
            let s = uni(rng, 0.3, 0.8);
            (s, s, "concrete", "pillar")
        }
        Kind::Partition => (uni(rng, 1.0, 2.0), 0.05, "glass", "partition"),
    };
    if rng.gen_bool(0.5) {
        (h, w, m, n)
    } else {
        (w, h, m, n)
    }
}

/// Place up to `n` obstacles of the given kinds in the shape's rectangles, 0.1 m inside,
/// 0.2 m apart and 0.4 m from the route (a few tries each; fewer when they do not fit).
fn place_obstacles(
    rng: &mut ChaCha8Rng,
    shape: &Shape,
    kinds: &[Kind],
    n: usize,
    out: &mut Vec<(Rect, &'static str, &'static str)>,
) {
    for _ in 0..n {
        let k = *kinds.choose(rng).expect("kinds");
        let (w, h, mat, name) = obstacle_size(rng, k);
        for _try in 0..30 {
            let r = *shape.rects.choose(rng).expect("rects");
            let [x0, y0, x1, y1] = r.0;
            if x1 - x0 < w + 0.2 || y1 - y0 < h + 0.2 {
                continue;
            }
            let x = q(uni(rng, x0 + 0.1, x1 - 0.1 - w), 0.01);
            let y = q(uni(rng, y0 + 0.1, y1 - 0.1 - h), 0.01);
            let cand = Rect([x, y, q(x + w, 0.01), q(y + h, 0.01)]);
            let clear_route = route_segments(shape)
                .iter()
                .all(|(a, b)| cand.dist_segment(*a, *b) >= 0.4);
            let clear_others = out.iter().all(|(o, _, _)| !o.grow(0.2).overlaps(&cand));
            if clear_route && clear_others {
                out.push((cand, mat, name));
                break;
            }
        }
    }
}

fn route_segments(shape: &Shape) -> Vec<(P, P)> {
    let mut v: Vec<(P, P)> = shape.route.windows(2).map(|w| (w[0], w[1])).collect();
    if shape.closed {
        v.push((*shape.route.last().expect("route"), shape.route[0]));
    }
    v
}

fn room_shape(rng: &mut ChaCha8Rng, w: f64, h: f64, alcove: bool, loop_ok: bool) -> Shape {
    let (w, h) = (q(w, 0.01), q(h, 0.01));
    let mut perimeter = vec![[0.0, 0.0], [w, 0.0], [w, h]];
    let mut detail = format!("{w:.2} x {h:.2} m");
    if alcove {
        let aw = q(uni(rng, 0.8, (w / 3.0).clamp(0.8, 2.0)), 0.01);
        let ad = q(uni(rng, 0.4, 1.2), 0.01);
        let ax = q(uni(rng, 0.3, w - aw - 0.3), 0.01);
        perimeter.extend([[ax + aw, h], [ax + aw, h + ad], [ax, h + ad], [ax, h]]);
        let _ = write!(detail, ", alcove {aw:.2} x {ad:.2} m");
    }
    perimeter.push([0.0, h]);
    let rect = Rect([0.0, 0.0, w, h]);
    let kind = if loop_ok && w.min(h) >= 3.0 && rng.gen_bool(0.5) {
        "loop"
    } else {
        "line"
    };
    let (route, closed) = if kind == "loop" {
        let m = (0.25 * w.min(h)).clamp(0.75, 2.0);
        (vec![[m, m], [w - m, m], [w - m, h - m], [m, h - m]], true)
    } else {
        let y = q(h * uni(rng, 0.35, 0.65), 0.01);
        let m = (0.15 * w).clamp(0.5, 1.0);
        (vec![[m, y], [w - m, y]], false)
    };
    Shape {
        perimeter,
        rects: vec![rect],
        route,
        closed,
        traj: kind,
        detail,
    }
}

fn corridor_shape(rng: &mut ChaCha8Rng) -> Shape {
    let l = q(uni(rng, 10.0, 60.0), 0.01);
    let w = q(uni(rng, 1.5, 3.5), 0.01);
    let slots = (l / 3.0).floor() as usize;
    let k = rng.gen_range(0..=4usize).min(slots);
    let mut chosen: Vec<usize> = (0..slots).collect();
    chosen.shuffle(rng);
    chosen.truncate(k);
    let mut bottom = Vec::new();
    let mut top = Vec::new();
    for s in chosen {
        let rw = q(uni(rng, 0.8, 1.2), 0.01);
        let rd = q(uni(rng, 0.2, 0.6), 0.01);
        let x = q(s as f64 * 3.0 + uni(rng, 0.3, 3.0 - rw - 0.3), 0.01);
        if rng.gen_bool(0.5) {
            bottom.push((x, rw, rd));
        } else {
            top.push((x, rw, rd));
        }
    }
    bottom.sort_by(|a, b| a.0.total_cmp(&b.0));
    top.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut perimeter = vec![[0.0, 0.0]];
    for (x, rw, rd) in &bottom {
        perimeter.extend([[*x, 0.0], [*x, -rd], [x + rw, -rd], [x + rw, 0.0]]);
    }
    perimeter.extend([[l, 0.0], [l, w]]);
    for (x, rw, rd) in &top {
        perimeter.extend([[x + rw, w], [x + rw, w + rd], [*x, w + rd], [*x, w]]);
    }
    perimeter.push([0.0, w]);
    let y = q(w / 2.0, 0.01);
    Shape {
        perimeter,
        rects: vec![Rect([0.0, 0.0, l, w])],
        route: vec![[0.5, y], [l - 0.5, y]],
        closed: false,
        traj: "line",
        detail: format!(
            "{l:.2} x {w:.2} m, {} door recesses",
            bottom.len() + top.len()
        ),
    }
}

fn l_shape(rng: &mut ChaCha8Rng) -> Shape {
    let a = q(uni(rng, 15.0, 70.0), 0.01);
    let b = q(uni(rng, 10.0, 70.0), 0.01);
    let wa = q(uni(rng, 2.0, 6.0), 0.01);
    let wb = q(uni(rng, 2.0, 6.0), 0.01);
    let perimeter = vec![
        [0.0, 0.0],
        [a, 0.0],
        [a, b],
        [a - wb, b],
        [a - wb, wa],
        [0.0, wa],
    ];
    let (ya, xb) = (q(wa / 2.0, 0.01), q(a - wb / 2.0, 0.01));
    let turn = rng.gen_bool(0.7);
    let route = if turn {
        vec![[1.0, ya], [xb, ya], [xb, b - 1.0]]
    } else {
        vec![[1.0, ya], [a - 1.0, ya]]
    };
    Shape {
        perimeter,
        rects: vec![Rect([0.0, 0.0, a, wa]), Rect([a - wb, 0.0, a, b])],
        route,
        closed: false,
        traj: if turn { "turn" } else { "line" },
        detail: format!("arms {a:.2} m x {wa:.2} m and {b:.2} m x {wb:.2} m"),
    }
}

fn t_shape(rng: &mut ChaCha8Rng) -> Shape {
    let a = q(uni(rng, 20.0, 70.0), 0.01);
    let w = q(uni(rng, 2.5, 6.0), 0.01);
    let ws = q(uni(rng, 2.0, 5.0), 0.01);
    let b = q(uni(rng, 8.0, 40.0), 0.01);
    let xs = q(uni(rng, 0.3 * a, 0.7 * a), 0.01);
    let (s0, s1) = (q(xs - ws / 2.0, 0.01), q(xs + ws / 2.0, 0.01));
    let perimeter = vec![
        [0.0, 0.0],
        [s0, 0.0],
        [s0, -b],
        [s1, -b],
        [s1, 0.0],
        [a, 0.0],
        [a, w],
        [0.0, w],
    ];
    let y = q(w / 2.0, 0.01);
    let turn = rng.gen_bool(0.7);
    let route = if turn {
        vec![[1.0, y], [xs, y], [xs, -b + 1.0]]
    } else {
        vec![[1.0, y], [a - 1.0, y]]
    };
    Shape {
        perimeter,
        rects: vec![Rect([0.0, 0.0, a, w]), Rect([s0, -b, s1, 0.0])],
        route,
        closed: false,
        traj: if turn { "turn" } else { "line" },
        detail: format!("bar {a:.2} x {w:.2} m, stem {b:.2} x {ws:.2} m"),
    }
}

fn u_shape(rng: &mut ChaCha8Rng) -> Shape {
    let a = q(uni(rng, 15.0, 50.0), 0.01);
    let b = q(uni(rng, 10.0, 40.0), 0.01);
    let w = q(uni(rng, 2.0, 5.0), 0.01);
    let perimeter = vec![
        [0.0, 0.0],
        [a, 0.0],
        [a, b],
        [a - w, b],
        [a - w, w],
        [w, w],
        [w, b],
        [0.0, b],
    ];
    let (c0, c1) = (q(w / 2.0, 0.01), q(a - w / 2.0, 0.01));
    let turn = rng.gen_bool(0.7);
    let route = if turn {
        vec![[c0, b - 1.0], [c0, c0], [c1, c0], [c1, b - 1.0]]
    } else {
        vec![[1.0, c0], [a - 1.0, c0]]
    };
    Shape {
        perimeter,
        rects: vec![
            Rect([0.0, 0.0, a, w]),
            Rect([0.0, 0.0, w, b]),
            Rect([a - w, 0.0, a, b]),
        ],
        route,
        closed: false,
        traj: if turn { "turn" } else { "line" },
        detail: format!("base {a:.2} m, legs {b:.2} m, {w:.2} m wide"),
    }
}

fn hall_shape(rng: &mut ChaCha8Rng) -> Shape {
    let w = q(uni(rng, 20.0, 70.0), 0.01);
    let h = q(uni(rng, 10.0, 25.0), 0.01);
    let loop_ = rng.gen_bool(0.5);
    let (route, closed) = if loop_ {
        let m = q(uni(rng, 2.0, 4.0), 0.01);
        (vec![[m, m], [w - m, m], [w - m, h - m], [m, h - m]], true)
    } else {
        let y = q(h * uni(rng, 0.3, 0.7), 0.01);
        (vec![[1.0, y], [w - 1.0, y]], false)
    };
    Shape {
        perimeter: vec![[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]],
        rects: vec![Rect([0.0, 0.0, w, h])],
        route,
        closed,
        traj: if loop_ { "loop" } else { "line" },
        detail: format!("{w:.2} x {h:.2} m"),
    }
}

/// Poses along the route: `n` at equal arc length (a closed route does not repeat its
/// start), heading by `mode`.
fn sample_route(rng: &mut ChaCha8Rng, shape: &Shape, n: usize, mode: &str) -> Vec<Pose> {
    let segs = route_segments(shape);
    let lens: Vec<f64> = segs
        .iter()
        .map(|(a, b)| (b[0] - a[0]).hypot(b[1] - a[1]))
        .collect();
    let total: f64 = lens.iter().sum();
    let spin = uni(rng, 15.0, 45.0) * if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
    let offsets = [0.0, 45.0, -45.0, 90.0, -90.0, 180.0];
    let mut offset = 0.0;
    let mut hold = 0usize;
    (0..n)
        .map(|i| {
            let s = if shape.closed {
                total * i as f64 / n as f64
            } else {
                total * i as f64 / (n - 1) as f64
            };
            let mut acc = 0.0;
            let mut at = (segs[segs.len() - 1].1, segs.len() - 1);
            for (k, (a, b)) in segs.iter().enumerate() {
                if s <= acc + lens[k] + 1e-9 {
                    let t = ((s - acc) / lens[k]).clamp(0.0, 1.0);
                    at = ([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t], k);
                    break;
                }
                acc += lens[k];
            }
            let (a, b) = segs[at.1];
            let travel = (b[1] - a[1]).atan2(b[0] - a[0]).to_degrees();
            let heading = match mode {
                "spin" => travel + spin * i as f64,
                "changes" => {
                    if hold == 0 {
                        offset = *offsets.choose(rng).expect("offsets");
                        hold = rng.gen_range(3..=6);
                    }
                    hold -= 1;
                    travel + offset
                }
                _ => travel,
            };
            Pose {
                x_m: q(at.0[0], 0.001),
                y_m: q(at.0[1], 0.001),
                heading_deg: q(wrap_deg(heading), 0.1),
            }
        })
        .collect()
}

fn wrap_deg(a: f64) -> f64 {
    let r = (a + 180.0).rem_euclid(360.0) - 180.0;
    if r == -180.0 {
        180.0
    } else {
        r
    }
}

fn quantity(value: f64, unit: &str, family: &str) -> Quantity {
    Quantity::new(sig3(value), unit, family)
}

/// The `[clutter]` law of a scene, drawn over the module's ranges.
fn draw_clutter(rng: &mut ChaCha8Rng) -> ModelConfig {
    let mut m = ModelConfig::table1_defaults();
    m.inter_cluster_rate = quantity(log_uni(rng, 0.1, 0.4), "1/ns", "exponential");
    m.intra_cluster_rate = quantity(log_uni(rng, 0.2, 1.0), "1/ns", "exponential");
    m.intra_cluster_aoa = quantity(log_uni(rng, 5.0, 30.0), "deg", "laplacian");
    m.perimeter_offset = quantity(log_uni(rng, 0.1, 0.8), "m", "exponential");
    let dc_family = if rng.gen_bool(0.25) {
        "gaussian"
    } else {
        "exponential"
    };
    m.perimeter_spacing = quantity(log_uni(rng, 0.75, 4.0), "m", dc_family);
    m.cluster_decay = quantity(log_uni(rng, 5.0, 25.0), "ns", "exponential");
    m.ray_decay = quantity(log_uni(rng, 2.0, 6.0), "ns", "exponential");
    m.rays_per_cluster = quantity(rng.gen_range(3..=10) as f64, "count", "poisson");
    m.cluster_rrcs = quantity(log_uni(rng, 0.003, 0.03), "m2", "lognormal");
    m
}

fn rotate(p: P, c: f64, s: f64) -> P {
    [q(p[0] * c - p[1] * s, 0.001), q(p[0] * s + p[1] * c, 0.001)]
}

fn draw_scene(i: usize, key: u64) -> Spec {
    let mut rng = ChaCha8Rng::seed_from_u64(key);
    let rng = &mut rng;
    let family = Family::ALL[i % Family::ALL.len()];
    let perimeter_material = MATERIALS[i % MATERIALS.len()];
    let elements = [16, 100, 400][i % 3];
    let (shape, kinds, n_obst): (Shape, &[Kind], usize) = match family {
        Family::Room => {
            let (w, h) = (uni(rng, 3.0, 12.0), uni(rng, 3.0, 12.0));
            let alcove = rng.gen_bool(0.6);
            let s = room_shape(rng, w, h, alcove, true);
            (
                s,
                &[Kind::Desk, Kind::Cabinet, Kind::Pillar],
                rng.gen_range(0..=2),
            )
        }
        Family::Office => {
            let (w, h) = (uni(rng, 6.0, 12.0), uni(rng, 6.0, 12.0));
            let alcove = rng.gen_bool(0.3);
            let s = room_shape(rng, w, h, alcove, true);
            (
                s,
                &[
                    Kind::Desk,
                    Kind::Desk,
                    Kind::Cabinet,
                    Kind::Pillar,
                    Kind::Partition,
                ],
                rng.gen_range(3..=8),
            )
        }
        Family::Corridor => (
            corridor_shape(rng),
            &[Kind::Cabinet, Kind::Pillar],
            rng.gen_range(0..=3),
        ),
        Family::LHall => (
            l_shape(rng),
            &[Kind::Cabinet, Kind::Pillar, Kind::Desk],
            rng.gen_range(0..=4),
        ),
        Family::THall => (
            t_shape(rng),
            &[Kind::Cabinet, Kind::Pillar, Kind::Partition],
            rng.gen_range(0..=4),
        ),
        Family::UHall => (
            u_shape(rng),
            &[Kind::Cabinet, Kind::Pillar, Kind::Desk],
            rng.gen_range(0..=4),
        ),
        Family::Hall => (hall_shape(rng), &[Kind::Cabinet], rng.gen_range(0..=3)),
    };
    let mut placed: Vec<(Rect, &'static str, &'static str)> = Vec::new();
    if family == Family::Hall {
        // the pillar grid, skipping pillars near the route
        let [_, _, w, h] = shape.rects[0].0;
        let sp = uni(rng, 5.0, 10.0);
        let size = q(uni(rng, 0.4, 0.8), 0.01);
        let (nx, ny) = ((w / sp).floor() as usize, (h / sp).floor() as usize);
        for gx in 1..=nx {
            for gy in 1..=ny {
                let (cx, cy) = (
                    w * gx as f64 / (nx + 1) as f64,
                    h * gy as f64 / (ny + 1) as f64,
                );
                let x = q(cx - size / 2.0, 0.01);
                let y = q(cy - size / 2.0, 0.01);
                let r = Rect([x, y, q(x + size, 0.01), q(y + size, 0.01)]);
                if route_segments(&shape)
                    .iter()
                    .all(|(a, b)| r.dist_segment(*a, *b) >= 0.6)
                {
                    placed.push((r, "concrete", "pillar"));
                }
            }
        }
    }
    place_obstacles(rng, &shape, kinds, n_obst, &mut placed);

    // acquisition
    let mut step_deg = *STEPS.choose(rng).expect("steps");
    let mut pulses = rng.gen_range(1..=4usize);
    let mut n_poses = rng.gen_range(12..=40usize);
    let dirs = |s: f64| (180.0 / s).round() as usize + 1;
    while n_poses * dirs(step_deg) * pulses > SWEEP_BUDGET {
        if n_poses > 12 {
            n_poses -= 1;
        } else if pulses > 1 {
            pulses -= 1;
        } else {
            step_deg = *STEPS.iter().find(|s| **s > step_deg).unwrap_or(&10.0);
        }
    }
    let mode = *["along", "changes", "spin"].choose(rng).expect("modes");
    let mut poses = sample_route(rng, &shape, n_poses, mode);

    // targets: free space away from the route and the obstacles
    let mut targets = Vec::new();
    if rng.gen_bool(0.4) {
        for _ in 0..rng.gen_range(1..=2) {
            for _try in 0..30 {
                let r = *shape.rects.choose(rng).expect("rects");
                let [x0, y0, x1, y1] = r.0;
                let p = [
                    q(uni(rng, x0 + 0.3, x1 - 0.3), 0.01),
                    q(uni(rng, y0 + 0.3, y1 - 0.3), 0.01),
                ];
                let pt = Rect([p[0], p[1], p[0], p[1]]);
                let free = placed.iter().all(|(o, _, _)| !o.grow(0.2).contains(p))
                    && route_segments(&shape)
                        .iter()
                        .all(|(a, b)| pt.dist_segment(*a, *b) >= 0.5);
                if free {
                    targets.push((p, q(uni(rng, 0.1, 0.7), 0.01)));
                    break;
                }
            }
        }
    }

    // an overall turn for about a third of the scenes
    let turn_deg = if rng.gen_bool(1.0 / 3.0) {
        q(uni(rng, 0.0, 360.0), 0.1)
    } else {
        0.0
    };
    let (c, s) = (turn_deg.to_radians().cos(), turn_deg.to_radians().sin());
    let perimeter: Vec<P> = shape.perimeter.iter().map(|p| rotate(*p, c, s)).collect();
    let obstacles: Vec<Obstacle> = placed
        .iter()
        .enumerate()
        .map(|(k, (r, mat, name))| Obstacle {
            name: format!("{name}{k}"),
            material: mat,
            ring: r.ring().iter().map(|p| rotate(*p, c, s)).collect(),
        })
        .collect();
    for p in &mut poses {
        let r = rotate([p.x_m, p.y_m], c, s);
        p.x_m = r[0];
        p.y_m = r[1];
        p.heading_deg = q(wrap_deg(p.heading_deg + turn_deg), 0.1);
    }
    let targets: Vec<PointTarget> = targets
        .iter()
        .map(|(p, rrcs)| {
            let r = rotate(*p, c, s);
            PointTarget {
                x_m: r[0],
                y_m: r[1],
                rrcs_m: *rrcs,
                via_m: None,
            }
        })
        .collect();

    let scene = SceneConfig {
        walls: true,
        wall_rcs_per_m: sig3(log_uni(rng, 0.005, 0.05)),
        scatterers_per_cell: 10.0,
        specular: true,
        corner_rcs_m2: sig3(log_uni(rng, 0.1, 1.0)),
        edge_rcs_m2: sig3(log_uni(rng, 0.01, 0.1)),
        coupling_db: -45.0,
        coupling_delay_ns: 0.25,
        pattern_knots: 0,
        materials: materials(),
        targets,
    };
    let clutter = draw_clutter(rng);
    let one_bit = rng.gen_bool(0.5);
    let seed = rng.gen_range(1..1_000_000_000u64);
    let name = format!("z{i:02}-{}", family.name());
    let mut mats: Vec<&str> = std::iter::once(perimeter_material)
        .chain(obstacles.iter().map(|o| o.material))
        .collect();
    mats.sort_unstable();
    mats.dedup();
    let description = format!(
        "{}: {}, {} walls, {} obstacles ({}), {} targets, turned {turn_deg}°; {} {} poses, heading {mode}; N {elements}{}, {step_deg}° steps, {pulses} pulses; λ {} /ns, AoA {}°, d_c {} m ({}), d_p {} m, σ_c {} m²",
        family.name(),
        shape.detail,
        perimeter_material,
        obstacles.len(),
        mats.join("/"),
        scene.targets.len(),
        shape.traj,
        poses.len(),
        if one_bit { " one-bit" } else { "" },
        clutter.intra_cluster_rate.value,
        clutter.intra_cluster_aoa.value,
        clutter.perimeter_spacing.value,
        clutter.perimeter_spacing.family,
        clutter.perimeter_offset.value,
        clutter.cluster_rrcs.value,
    );
    Spec {
        layout_title: format!("{name}, {}", shape.detail),
        name,
        family,
        seed,
        perimeter,
        perimeter_material,
        obstacles,
        poses,
        elements,
        one_bit,
        step_deg,
        pulses,
        scene,
        clutter: Some(clutter),
        description,
    }
}

// ---------------------------------------------------------------------------------------
// rendering

fn closed(ring: &[P]) -> Vec<P> {
    let mut v = ring.to_vec();
    v.push(ring[0]);
    v
}

fn render_layout(s: &Spec) -> String {
    let feature = |role: &str, name: &str, material: &str, ring: &[P]| {
        let coords: Vec<String> = closed(ring)
            .iter()
            .map(|p| format!("[{:?}, {:?}]", p[0], p[1]))
            .collect();
        format!(
            "    {{\n      \"type\": \"Feature\",\n      \"properties\": {{ \"role\": \"{role}\", \"name\": \"{name}\", \"material\": \"{material}\" }},\n      \"geometry\": {{ \"type\": \"Polygon\", \"coordinates\": [[{}]] }}\n    }}",
            coords.join(", ")
        )
    };
    let mut features = vec![feature(
        "perimeter",
        s.family.name(),
        s.perimeter_material,
        &s.perimeter,
    )];
    for o in &s.obstacles {
        features.push(feature("obstacle", &o.name, o.material, &o.ring));
    }
    format!(
        "{{\n  \"type\": \"FeatureCollection\",\n  \"name\": \"pradar scene zoo: {} (metres)\",\n  \"features\": [\n{}\n  ]\n}}\n",
        s.layout_title,
        features.join(",\n")
    )
}

#[derive(Serialize)]
struct SimSections<'a> {
    scene: &'a SceneConfig,
    #[serde(skip_serializing_if = "Option::is_none")]
    clutter: Option<&'a ModelConfig>,
}

fn render_manifest(s: &Spec) -> String {
    let m = Manifest {
        schema_version: SCHEMA_VERSION,
        name: s.name.clone(),
        layout: "layout.geojson".into(),
        seed: s.seed,
        pulses: s.pulses,
        band: Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points: 801,
        },
        array: ArrayConfig {
            elements: s.elements,
            one_bit: s.one_bit,
            element_q: 1.0,
            steering: Steering::Mechanical,
        },
        directions: Directions {
            start_deg: -90.0,
            stop_deg: 90.0,
            step_deg: s.step_deg,
        },
        noise: NoiseConfig {
            floor_dbm: -100.0,
            tx_power_dbm: 0.0,
        },
        processing: Processing {
            window: WindowKind::Hann,
            oversample: 5,
            coupling: CouplingRemoval::Gate,
            gate_ns: 3.0,
            max_delay_ns: 80.0,
            noise_from_ns: 100.0,
        },
        poses: s.poses.clone(),
        labels: vec![],
        sweeps: None,
        calibration: None,
    };
    let mut t = format!(
        "# pradar scene zoo (`pradar zoo`, src/simulate/zoo.rs): {}\n# {}\n",
        s.name, s.description
    );
    t.push_str(&toml::to_string(&m).expect("manifest serialises"));
    t.push('\n');
    t.push_str(
        &toml::to_string(&SimSections {
            scene: &s.scene,
            clutter: s.clutter.as_ref(),
        })
        .expect("scene serialises"),
    );
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::layout::Layout;
    use crate::campaign::manifest::Campaign;
    use crate::params::ParamGuard;
    use crate::simulate::{scene_sections, Scene};
    use geo::Coord;

    #[test]
    fn every_scene_loads_and_passes_the_simulators_checks() {
        let dir = tempfile::tempdir().unwrap();
        let scenes = generate(1, 21);
        let written = write(dir.path(), &scenes).unwrap();
        assert_eq!(written.len(), 3 * scenes.len());
        for d in &written {
            let c = Campaign::load(&d.join("campaign.toml"))
                .unwrap_or_else(|e| panic!("{}: {e}", d.display()));
            let (scene, clutter) = scene_sections(&c).unwrap();
            let layout = Layout::load(&c.layout_path()).unwrap();
            for (k, p) in c.manifest.poses.iter().enumerate() {
                assert!(
                    layout.is_free(Coord { x: p.x_m, y: p.y_m }),
                    "{}: pose {k} not in free space",
                    d.display()
                );
            }
            for t in &scene.targets {
                assert!(layout.is_free(Coord { x: t.x_m, y: t.y_m }));
            }
            let twin = d.to_string_lossy().ends_with("-twin");
            assert_eq!(clutter.is_none(), twin, "{}", d.display());
            assert_eq!(scene.walls, !twin);
            let n = c.manifest.poses.len();
            assert!((12..=40).contains(&n), "{}: {n} poses", d.display());
            assert!([16, 100, 400].contains(&c.manifest.array.elements));
            let st = c.manifest.directions.step_deg;
            assert!((2.5..=10.0).contains(&st));
            assert!((1..=4).contains(&c.manifest.pulses));
            assert!(n * c.manifest.directions.count() * c.manifest.pulses <= SWEEP_BUDGET);
            let p = &c.manifest.processing;
            assert_eq!(
                (p.max_delay_ns, p.noise_from_ns, p.coupling),
                (80.0, 100.0, CouplingRemoval::Gate)
            );
            for w in &layout.walls {
                assert!(
                    scene.materials.contains_key(&w.material),
                    "{}: material {} not in [scene.materials]",
                    d.display(),
                    w.material
                );
            }
        }
    }

    #[test]
    fn the_twin_simulates_noise_and_coupling_only() {
        let s = &generate(3, 7)[6];
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), std::slice::from_ref(s)).unwrap();
        let c = Campaign::load(&dir.path().join(format!("{}-twin/campaign.toml", s.name))).unwrap();
        let (cfg, clutter) = scene_sections(&c).unwrap();
        assert!(clutter.is_none() && !cfg.walls && !cfg.specular && cfg.targets.is_empty());
        let scene = Scene::build(
            Layout::load(&c.layout_path()).unwrap(),
            cfg,
            None,
            6e9,
            c.manifest.seed,
        );
        assert!(scene.scatterers.is_empty() && scene.clusters.is_empty());
        for p in &c.manifest.poses {
            assert!(scene.paths(Coord { x: p.x_m, y: p.y_m }).is_empty());
        }
        // the scene itself has paths
        let full = Campaign::load(&dir.path().join(format!("{}/campaign.toml", s.name))).unwrap();
        let (cfg, clutter) = scene_sections(&full).unwrap();
        let scene = Scene::build(
            Layout::load(&full.layout_path()).unwrap(),
            cfg,
            clutter.as_ref(),
            6e9,
            full.manifest.seed,
        );
        let p = full.manifest.poses[0];
        assert!(!scene.paths(Coord { x: p.x_m, y: p.y_m }).is_empty());
    }

    #[test]
    fn the_generator_is_deterministic_and_its_scenes_differ() {
        let a = generate(1, 21);
        assert_eq!(a, generate(1, 21));
        // a prefix of a larger zoo
        assert_eq!(a[..10], generate(1, 10)[..]);
        let b = generate(2, 21);
        assert!(a.iter().zip(&b).all(|(x, y)| x.manifest != y.manifest));
        let names: std::collections::BTreeSet<&str> = a.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names.len(), a.len());
        // every layout and manifest distinct; sizes, materials, N and families spread
        for (i, x) in a.iter().enumerate() {
            for y in &a[i + 1..] {
                assert_ne!(x.layout, y.layout);
                assert_ne!(x.extent_m(), y.extent_m());
            }
        }
        let mats: std::collections::BTreeSet<&str> =
            a.iter().map(|s| s.perimeter_material()).collect();
        assert_eq!(mats.len(), 5);
        let ns: std::collections::BTreeSet<usize> = a.iter().map(|s| s.elements()).collect();
        assert_eq!(ns.len(), 3);
        let fams: std::collections::BTreeSet<&str> = a.iter().map(|s| s.family.name()).collect();
        assert_eq!(fams.len(), 7);
        let longest = a.iter().map(|s| s.extent_m().0.max(s.extent_m().1));
        assert!(longest.clone().fold(0.0, f64::max) > 40.0);
        assert!(longest.fold(f64::MAX, f64::min) < 12.5);
        // realisations differ in the seed only
        let r = a[0].realisation(2);
        assert_ne!(r.seed(), a[0].seed());
        assert_eq!(r.layout, a[0].layout);
        assert_eq!(a[0].realisation(1), a[0]);
        // the twin keeps the campaign (poses, array, steps)
        let t = a[0].twin();
        assert_eq!(t.sweeps(), a[0].sweeps());
        assert!(!t.manifest.contains("[clutter"));
    }

    #[test]
    fn materials_are_itu_values_at_60_ghz() {
        let m = materials();
        let tan = |n: &str| m[n].loss_tangent;
        assert!(
            (tan("concrete") - 0.0506).abs() < 2e-3,
            "{}",
            tan("concrete")
        );
        assert!((tan("plasterboard") - 0.0214).abs() < 2e-3);
        assert!((tan("glass") - 0.0271).abs() < 2e-3);
        assert!((tan("wood") - 0.057).abs() < 2e-3);
        assert!(m["metal"].gamma().norm() > 0.999);
        // and the scene's sections take them
        let s = &generate(5, 1)[0];
        let t: toml::Table = toml::from_str(&s.manifest).unwrap();
        let cfg: SceneConfig = t["scene"].clone().try_into().unwrap();
        assert_eq!(cfg.materials, m);
        cfg.check().unwrap();
    }
}
