//! Mapping benchmark (issue 5): cell updates per second, the time to map the built-in
//! corridor (12 poses x 37 directions, 400 elements, simulated), and a 20 m x 20 m floor
//! (200 x 200 = 40,000 cells of 0.1 m, no margin) with 1,000 poses x 37 directions from
//! synthetic energy (noise + the wall echo on boresight + a few point echoes, drawn from a
//! seeded RNG), with 1 and 2 rayon threads (maps compared bit for bit).
//!
//! Targets: >= 1e7 cell updates/s per core; the floor in <= 30 s on both cores.
//! Run with `cargo bench --bench mapping` (or `scripts/bench-map`).

use criterion::Criterion;
use pradar::campaign::manifest::{Campaign, SweepFormat};
use pradar::energy::{EnergyMatrix, EnergyMeta, EnergyProcessor};
use pradar::mapping::grid::{GridParams, ObservationModel};
use pradar::mapping::job::{load_run, MapRun};
use pradar::mapping::og::{og_map_stats, Detector, LogOddsMap, Method, OgParams, OgStats};
use pradar::params::ParamGuard;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Gamma};
use std::path::Path;
use std::time::Instant;

/// Floor poses (1,000; `PRADAR_BENCH_POSES` overrides for quick runs).
fn floor_poses() -> usize {
    std::env::var("PRADAR_BENCH_POSES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000)
}

fn floor_manifest(dir: &Path) -> Campaign {
    std::fs::create_dir_all(dir).unwrap();
    let layout = r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"role":"perimeter"},"geometry":{"type":"Polygon","coordinates":[[[0,0],[20,0],[20,20],[0,20],[0,0]]]}}]}"#;
    std::fs::write(dir.join("floor.geojson"), layout).unwrap();
    let mut t = String::from(
        r#"schema_version = 1
name = "floor"
layout = "floor.geojson"
seed = 5
[band]
start_hz = 57.5e9
stop_hz = 63.5e9
points = 801
[array]
elements = 400
one_bit = true
[directions]
start_deg = -90.0
stop_deg = 90.0
step_deg = 5.0
[noise]
floor_dbm = -100.0
[processing]
max_delay_ns = 80.0
noise_from_ns = 100.0
"#,
    );
    // a lawn-mower trajectory: 20 lanes x 50 poses, heading along the lane (and a 30° turn
    // every other pose so the beams cover different bearings)
    for i in 0..floor_poses() {
        let lane = i / 50;
        let k = i % 50;
        let y = 0.5 + lane as f64; // 20 lanes, 1 m apart
        let (x, h) = if lane % 2 == 0 {
            (0.5 + k as f64 * 0.38, 0.0)
        } else {
            (19.5 - k as f64 * 0.38, 180.0)
        };
        let h = h + if k % 2 == 0 { 30.0 } else { -30.0 };
        t.push_str(&format!(
            "[[poses]]\nx_m = {x}\ny_m = {y}\nheading_deg = {h}\n"
        ));
    }
    let p = dir.join("campaign.toml");
    std::fs::write(&p, &t).unwrap();
    Campaign::load(&p).unwrap()
}

/// Synthetic energy: Gamma noise (shape TW, mean N0·TW) + the window kernel of the wall
/// echo along boresight (30 dB above the noise mean) + 20 point echoes.
fn floor_energy(c: &Campaign) -> EnergyMatrix {
    let m = &c.manifest;
    let proc = EnergyProcessor::new(m.band, m.processing).unwrap();
    let nb = proc.nbins();
    let tb = proc.bin_width_ns();
    let (n0, tw) = (1e-12, proc.tw());
    let kernel: Vec<f64> = {
        let e = proc.point_echo_energy(1.0, 100.0 * tb * 1e-9);
        (0..8).map(|j| e[100 + j].max(e[100 - j])).collect()
    };
    let nd = m.directions.count();
    let np = m.poses.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let noise = Gamma::new(tw, n0).unwrap();
    let targets: Vec<(f64, f64)> = (0..20)
        .map(|_| (rng.gen_range(1.0..19.0), rng.gen_range(1.0..19.0)))
        .collect();
    let mut data = vec![0.0; np * nd * nb];
    for (p, pose) in m.poses.iter().enumerate() {
        for d in 0..nd {
            let th = (pose.heading_deg + m.directions.angle_deg(d)).to_radians();
            let (ux, uy) = (th.cos(), th.sin());
            let prof = &mut data[(p * nd + d) * nb..(p * nd + d + 1) * nb];
            for v in prof.iter_mut() {
                *v = noise.sample(&mut rng);
            }
            let mut add = |r: f64, snr: f64| {
                let k0 = (pradar::units::delay_ns(r) / tb).round() as i64;
                for (j, kv) in kernel.iter().enumerate() {
                    for s in [k0 - j as i64, k0 + j as i64] {
                        if s >= 0 && (s as usize) < nb {
                            prof[s as usize] += snr * n0 * tw * kv;
                        }
                    }
                }
            };
            // distance to the square's boundary along boresight
            let mut r = f64::INFINITY;
            for (u, x, lo, hi) in [(ux, pose.x_m, 0.0, 20.0), (uy, pose.y_m, 0.0, 20.0)] {
                if u > 1e-12 {
                    r = r.min((hi - x) / u);
                } else if u < -1e-12 {
                    r = r.min((lo - x) / u);
                }
            }
            add(r, 1e3);
            for &(tx, ty) in &targets {
                let (dx, dy) = (tx - pose.x_m, ty - pose.y_m);
                let rr = dx.hypot(dy);
                let off = (dy.atan2(dx) - th).sin().abs();
                if off < 0.05 {
                    add(rr, 1e2);
                }
            }
        }
    }
    EnergyMatrix {
        meta: EnergyMeta {
            schema_version: 1,
            bin_width_ns: tb,
            pulses: 1,
            n0,
            enbw: proc.enbw(),
            tw,
            array: m.array.label(),
            coupling: "gate".into(),
            all: vec![("gate_ns".into(), m.processing.gate_ns.to_string())],
            missing: vec![],
        },
        positions: np,
        angles_rel_deg: m.directions.angles_deg(),
        headings_deg: m.poses.iter().map(|p| p.heading_deg).collect(),
        bins: nb,
        first: 0,
        data,
    }
}

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

fn run(
    model: &ObservationModel,
    em: &dyn pradar::energy::EnergySource,
    det: &Detector,
    method: Method,
) -> (LogOddsMap, OgStats) {
    run_with(model, em, det, method, &OgParams::default())
}

/// The OG's rules before 5 Dec 2026 (no silent bound, credit to every visible cell): the
/// baseline the default is timed against in the same run.
fn before() -> OgParams {
    OgParams {
        bound_silent: pradar::mapping::grid::SilentBound::Off,
        credit_depth_m: None,
        ..Default::default()
    }
}

fn run_with(
    model: &ObservationModel,
    em: &dyn pradar::energy::EnergySource,
    det: &Detector,
    method: Method,
    params: &OgParams,
) -> (LogOddsMap, OgStats) {
    og_map_stats(model, em, &params.check().unwrap(), method, det, &|_, _| {}).unwrap()
}

fn main() {
    let tmp = tempfile::tempdir().unwrap();
    let mut crit = Criterion::default().sample_size(10).configure_from_args();
    if std::env::var("PRADAR_BENCH_FLOOR_ONLY").is_err() {
        corridor(&tmp.path().join("corridor"), &mut crit);
    }
    floor(tmp.path());
    crit.final_summary();
}

fn corridor(dir: &Path, crit: &mut Criterion) {
    // ---- corridor (simulated once, 400 elements)
    let m = pradar::pipeline::write_builtin_corridor(&dir.join("in")).unwrap();
    let c = Campaign::load(&m).unwrap();
    let t = Instant::now();
    let sim =
        pradar::simulate::simulate(&c, &dir.join("sim"), SweepFormat::Parquet, &|_, _| {}).unwrap();
    let sc = Campaign::load(&sim.manifest).unwrap();
    let e = dir.join("energy.parquet");
    pradar::energy::run(&sc, &e, &|_, _| {}).unwrap();
    eprintln!(
        "corridor simulated + energy in {:.1} s",
        t.elapsed().as_secs_f64()
    );
    let l = load_run(
        &MapRun {
            campaign: sim.manifest.clone(),
            energy: e.clone(),
        },
        None,
        &GridParams::default().check().unwrap(),
        &OgParams::default().check().unwrap(),
        None,
    )
    .unwrap();
    for method in [Method::Og, Method::OgBoresight] {
        crit.bench_function(&format!("map corridor {}", method.name()), |b| {
            b.iter(|| run(&l.model, &l.energy, &l.detector, method))
        });
    }
    let echo = OgParams {
        credit: pradar::mapping::og::OgCredit::Echo,
        ..Default::default()
    };
    crit.bench_function("map corridor og --og-credit echo", |b| {
        b.iter(|| run_with(&l.model, &l.energy, &l.detector, Method::Og, &echo))
    });
    crit.bench_function("map corridor og (rules before 5 Dec 2026)", |b| {
        b.iter(|| run_with(&l.model, &l.energy, &l.detector, Method::Og, &before()))
    });
    for threads in [1, 2] {
        let (_, st) = pool(threads).install(|| run(&l.model, &l.energy, &l.detector, Method::Og));
        println!(
            "corridor og ({} cells, 12 x 37 scans), {threads} thread(s): {:.3} s, {} increments ({:.3e}/s), {} entries evaluated ({:.3e}/s)",
            l.model.spec.len(),
            st.seconds,
            st.cell_updates,
            st.cell_updates as f64 / st.seconds,
            st.entries,
            st.entries as f64 / st.seconds
        );
    }
}

fn floor(dir: &Path) {
    // ---- 20 m x 20 m floor, 1,000 poses
    let fc = floor_manifest(&dir.join("floor"));
    let t = Instant::now();
    let em = floor_energy(&fc);
    eprintln!(
        "floor synthetic energy ({} x {} x {} bins) in {:.1} s",
        em.positions,
        em.directions(),
        em.bins,
        t.elapsed().as_secs_f64()
    );
    let grid = GridParams {
        margin_m: 0.0,
        ..Default::default()
    };
    let layout = pradar::campaign::layout::Layout::load(&fc.layout_path()).unwrap();
    // exactly 200 x 200 cells over the 20 m box (`GridSpec::covering` would add a column
    // and a row for the walls on its upper edges; the floor's timings are per 40,000 cells)
    let bbox = layout.bbox();
    let spec = pradar::mapping::reference::GridSpec {
        x0_m: bbox.min().x,
        y0_m: bbox.min().y,
        cell_m: 0.1,
        cols: 200,
        rows: 200,
    };
    let model = ObservationModel::new(
        spec,
        &grid.check().unwrap(),
        &fc.manifest,
        em.bins,
        em.meta.bin_width_ns,
        pradar::mapping::job::min_bin(&em),
    )
    .unwrap();
    let thr =
        pradar::mapping::og::detection_threshold(&em.meta, 1e-3, Path::new("synthetic")).unwrap();
    let kernel = pradar::mapping::job::window_kernel(&fc).unwrap();
    let det = Detector::new(thr, &kernel, 10.0, model.min_bin);
    let mut maps = Vec::new();
    for method in [Method::Og, Method::OgBoresight] {
        for threads in [1, 2] {
            let (m, st) = pool(threads).install(|| run(&model, &em, &det, method));
            println!(
                "floor {} ({} cells, {} x 37 scans), {threads} thread(s): {:.2} s, {} increments ({:.3e}/s), {} entries evaluated ({:.3e}/s, {:.3e}/s per thread)",
                method.name(),
                spec.len(),
                floor_poses(),
                st.seconds,
                st.cell_updates,
                st.cell_updates as f64 / st.seconds,
                st.entries,
                st.entries as f64 / st.seconds,
                st.entries as f64 / st.seconds / threads as f64,
            );
            maps.push(m);
        }
    }
    for threads in [1, 2] {
        let (_, st) = pool(threads).install(|| run_with(&model, &em, &det, Method::Og, &before()));
        println!(
            "floor og (rules before 5 Dec 2026), {threads} thread(s): {:.2} s, {} increments",
            st.seconds, st.cell_updates,
        );
    }
    let same = |a: &LogOddsMap, b: &LogOddsMap| {
        a.logodds
            .iter()
            .zip(&b.logodds)
            .all(|(x, y)| x.to_bits() == y.to_bits())
    };
    println!(
        "floor maps identical with 1 and 2 threads: og {}, og-boresight {}",
        same(&maps[0], &maps[1]),
        same(&maps[2], &maps[3])
    );
}
