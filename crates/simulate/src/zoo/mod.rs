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
//!   and channel modeling", IEEE TAP 62(3), 2014); drawn (it keeps the scenes' random
//!   streams) but not read by the physics simulator, whose clusters are point targets at
//!   their own range: no excess decay, Γ = ∞ in the model's schema-2 meaning;
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
use crate::model_file::{ModelConfig, Quantity};
use crate::{Material, PointTarget, SceneConfig};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

mod shapes;
use shapes::*;

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

/// Takes the scene's index `i` (its family, perimeter material and element count cycle
/// with it) and its key (the seed of every draw); gives the scene: the shape and its
/// obstacles, the acquisition, the targets, an overall turn, the scene's levels and the
/// clutter, drawn in that order.
fn draw_scene(i: usize, key: u64) -> Spec {
    let mut rng = ChaCha8Rng::seed_from_u64(key);
    let rng = &mut rng;
    let family = Family::ALL[i % Family::ALL.len()];
    let perimeter_material = MATERIALS[i % MATERIALS.len()];
    let elements = [16, 100, 400][i % 3];
    let (shape, kinds, n_obst) = draw_shape(rng, family);
    let mut placed: Vec<(Rect, &'static str, &'static str)> = Vec::new();
    if family == Family::Hall {
        place_pillars(rng, &shape, &mut placed);
    }
    place_obstacles(rng, &shape, kinds, n_obst, &mut placed);

    // acquisition
    let (step_deg, pulses, mode, mut poses) = draw_acquisition(rng, &shape);

    // targets: free space away from the route and the obstacles
    let targets = draw_targets(rng, &shape, &placed);

    // an overall turn for about a third of the scenes
    let turn_deg = if rng.gen_bool(1.0 / 3.0) {
        q(uni(rng, 0.0, 360.0), 0.1)
    } else {
        0.0
    };
    let (perimeter, obstacles, targets) = turn(turn_deg, &shape, &placed, &mut poses, &targets);

    let scene = draw_scene_levels(rng, targets);
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

/// Takes the generator and the scene's family; gives its shape, the kinds of obstacle it
/// may hold and how many to place.
fn draw_shape(rng: &mut ChaCha8Rng, family: Family) -> (Shape, &'static [Kind], usize) {
    match family {
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
    }
}

/// Takes the generator and a hall's shape; adds the hall's pillar grid to `placed`,
/// skipping pillars near the route.
fn place_pillars(
    rng: &mut ChaCha8Rng,
    shape: &Shape,
    placed: &mut Vec<(Rect, &'static str, &'static str)>,
) {
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
            if route_segments(shape)
                .iter()
                .all(|(a, b)| r.dist_segment(*a, *b) >= 0.6)
            {
                placed.push((r, "concrete", "pillar"));
            }
        }
    }
}

/// Takes the generator and the shape; gives the acquisition within [`SWEEP_BUDGET`]: the
/// direction step (degrees), the pulses, the heading mode and the poses along the route.
fn draw_acquisition(rng: &mut ChaCha8Rng, shape: &Shape) -> (f64, usize, &'static str, Vec<Pose>) {
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
    let poses = sample_route(rng, shape, n_poses, mode);
    (step_deg, pulses, mode, poses)
}

/// Takes the generator, the shape and the placed obstacles; gives the point targets
/// (position, RRCS) for about two scenes in five, in free space away from the route and
/// the obstacles.
fn draw_targets(
    rng: &mut ChaCha8Rng,
    shape: &Shape,
    placed: &[(Rect, &'static str, &'static str)],
) -> Vec<(P, f64)> {
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
                    && route_segments(shape)
                        .iter()
                        .all(|(a, b)| pt.dist_segment(*a, *b) >= 0.5);
                if free {
                    targets.push((p, q(uni(rng, 0.1, 0.7), 0.01)));
                    break;
                }
            }
        }
    }
    targets
}

/// Takes the overall turn (degrees), the shape, the placed obstacles, the poses (turned
/// in place) and the targets; gives the turned perimeter, obstacles and point targets.
fn turn(
    turn_deg: f64,
    shape: &Shape,
    placed: &[(Rect, &'static str, &'static str)],
    poses: &mut [Pose],
    targets: &[(P, f64)],
) -> (Vec<P>, Vec<Obstacle>, Vec<PointTarget>) {
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
    for p in poses.iter_mut() {
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
    (perimeter, obstacles, targets)
}

/// Takes the generator and the point targets; gives the scene's section with the walls'
/// diffuse σ′ and the corners' and edges' σ drawn (in that order).
fn draw_scene_levels(rng: &mut ChaCha8Rng, targets: Vec<PointTarget>) -> SceneConfig {
    SceneConfig {
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
mod tests;
