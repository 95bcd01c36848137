//! The zoo's geometry and laws: random helpers, the families' shapes (room, corridor, L, T,
//! U, hall), obstacle placement, the trajectories along a shape's route and the clutter law
//! drawn per scene (module docs of [`super`]).

use super::*;

pub(super) fn uni(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.gen::<f64>()
}

pub(super) fn log_uni(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    (lo.ln() + (hi.ln() - lo.ln()) * rng.gen::<f64>()).exp()
}

/// Round to `step` (geometry to the centimetre, laws to three significant digits).
pub(super) fn q(v: f64, step: f64) -> f64 {
    ((v / step).round() * step * 1e9).round() / 1e9
}

pub(super) fn sig3(v: f64) -> f64 {
    if v == 0.0 {
        return 0.0;
    }
    let e = v.abs().log10().floor() as i32 - 2;
    q(v, 10f64.powi(e))
}

/// An axis-aligned rectangle (x0, y0, x1, y1).
#[derive(Debug, Clone, Copy)]
pub(super) struct Rect(pub(super) [f64; 4]);

impl Rect {
    pub(super) fn ring(&self) -> Vec<P> {
        let [x0, y0, x1, y1] = self.0;
        vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }
    pub(super) fn grow(&self, m: f64) -> Rect {
        let [x0, y0, x1, y1] = self.0;
        Rect([x0 - m, y0 - m, x1 + m, y1 + m])
    }
    pub(super) fn overlaps(&self, o: &Rect) -> bool {
        self.0[0] < o.0[2] && o.0[0] < self.0[2] && self.0[1] < o.0[3] && o.0[1] < self.0[3]
    }
    pub(super) fn contains(&self, p: P) -> bool {
        p[0] >= self.0[0] && p[0] <= self.0[2] && p[1] >= self.0[1] && p[1] <= self.0[3]
    }
    /// Distance from the rectangle to a segment (0 when they touch), sampled finely.
    pub(super) fn dist_segment(&self, a: P, b: P) -> f64 {
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
pub(super) struct Shape {
    pub(super) perimeter: Vec<P>,
    pub(super) rects: Vec<Rect>,
    pub(super) route: Vec<P>,
    pub(super) closed: bool,
    pub(super) traj: &'static str,
    pub(super) detail: String,
}

/// The kinds of obstacle.
#[derive(Clone, Copy)]
pub(super) enum Kind {
    Desk,
    Cabinet,
    Pillar,
    Partition,
}

pub(super) fn obstacle_size(
    rng: &mut ChaCha8Rng,
    k: Kind,
) -> (f64, f64, &'static str, &'static str) {
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
pub(super) fn place_obstacles(
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

pub(super) fn route_segments(shape: &Shape) -> Vec<(P, P)> {
    let mut v: Vec<(P, P)> = shape.route.windows(2).map(|w| (w[0], w[1])).collect();
    if shape.closed {
        v.push((*shape.route.last().expect("route"), shape.route[0]));
    }
    v
}

pub(super) fn room_shape(
    rng: &mut ChaCha8Rng,
    w: f64,
    h: f64,
    alcove: bool,
    loop_ok: bool,
) -> Shape {
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

pub(super) fn corridor_shape(rng: &mut ChaCha8Rng) -> Shape {
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

pub(super) fn l_shape(rng: &mut ChaCha8Rng) -> Shape {
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

pub(super) fn t_shape(rng: &mut ChaCha8Rng) -> Shape {
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

pub(super) fn u_shape(rng: &mut ChaCha8Rng) -> Shape {
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

pub(super) fn hall_shape(rng: &mut ChaCha8Rng) -> Shape {
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
pub(super) fn sample_route(rng: &mut ChaCha8Rng, shape: &Shape, n: usize, mode: &str) -> Vec<Pose> {
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

pub(super) fn wrap_deg(a: f64) -> f64 {
    let r = (a + 180.0).rem_euclid(360.0) - 180.0;
    if r == -180.0 {
        180.0
    } else {
        r
    }
}

pub(super) fn quantity(value: f64, unit: &str, family: &str) -> Quantity {
    Quantity::new(sig3(value), unit, family)
}

/// The `[clutter]` law of a scene, drawn over the module's ranges.
pub(super) fn draw_clutter(rng: &mut ChaCha8Rng) -> ModelConfig {
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

pub(super) fn rotate(p: P, c: f64, s: f64) -> P {
    [q(p[0] * c - p[1] * s, 0.001), q(p[0] * s + p[1] * c, 0.001)]
}
