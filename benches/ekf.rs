//! EKF benchmark (issue 6): time per (pose, direction) update and campaign time for the
//! dense and the scalable EKF on the 20 m x 20 m floor of `benches/mapping.rs` (1,000
//! poses x 37 directions, synthetic energy) at 1k, 4k, 16k and 40k cells (cells of 0.632,
//! 0.316, 0.158 and 0.1 m), with the peak memory of the process (VmHWM), and the dense
//! update beside `scripts/ekf_numpy.py` (a straightforward NumPy EKF update with a dense
//! H) on the same update.
//!
//! One configuration per process (so VmHWM is its own peak):
//!   ekf scalable CELLS [POSES]    scalable campaign
//!   ekf dense CELLS [POSES]       dense campaign over POSES poses (default 20)
//!   ekf numpy CELLS DIR           dense filter over 10 poses, then one representative
//!                                 update dumped to DIR as .npy and timed (best of 3)
//! `scripts/bench-ekf` runs them all.

use pradar::campaign::manifest::Campaign;
use pradar::energy::{EnergyMatrix, EnergyMeta, EnergyProcessor};
use pradar::mapping::ekf::{
    ekf_run, truncate_kernel, DenseEkf, EkfParams, EkfVariant, Linearized, NoiseModel, Observation,
    RrcsFilter, TiledEkf,
};
use pradar::mapping::grid::{GridParams, ObservationModel, PoseGeometry};
use pradar::mapping::reference::GridSpec;
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

fn peak_mb() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map(|kb| kb / 1024.0)
        .unwrap_or(f64::NAN)
}

fn write_npy(path: &Path, shape: &[usize], data: &[f64]) {
    let shape_s = match shape.len() {
        1 => format!("({},)", shape[0]),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape_s}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + data.len() * 8);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, out).unwrap();
}

/// The floor campaign, its energy and the observation model at `cells` cells, shared by
/// the three modes.
struct Bench {
    _tmp: tempfile::TempDir,
    em: EnergyMatrix,
    spec: GridSpec,
    model: ObservationModel,
    kernel: Vec<f64>,
    n: usize,
    cell_m: f64,
    base: f64,
}

fn bench(cells: usize) -> Bench {
    let tmp = tempfile::tempdir().unwrap();
    let c = floor_manifest(tmp.path());
    let em = floor_energy(&c);
    let side = (cells as f64).sqrt().round() as usize;
    let cell_m = 20.0 / side as f64;
    let spec = GridSpec {
        x0_m: 0.0,
        y0_m: 0.0,
        cell_m,
        cols: side,
        rows: side,
    };
    let gp = GridParams {
        cell_m,
        margin_m: 0.0,
        ..Default::default()
    };
    let min_bin = 2 + (c.manifest.processing.gate_ns / em.meta.bin_width_ns).ceil() as usize;
    let model = ObservationModel::new(
        spec,
        &gp.check().unwrap(),
        &c.manifest,
        em.bins,
        em.meta.bin_width_ns,
        min_bin,
    )
    .unwrap();
    let kernel = pradar::mapping::job::window_kernel(&c).unwrap();
    let n = spec.len();
    let base = peak_mb();
    Bench {
        _tmp: tmp,
        em,
        spec,
        model,
        kernel,
        n,
        cell_m,
        base,
    }
}

/// The observation of (pose `pi`, direction `d`) with the truncated kernel `kern`.
fn observe(b: &Bench, kern: &[f64], g: &PoseGeometry, pi: usize, d: usize) -> Observation {
    let beam = b.model.beam(g, d);
    let mut scratch = vec![0.0; b.n];
    Observation::build(
        &beam,
        &b.em.profile(pi, d)[..b.model.bins],
        kern,
        b.model.min_bin,
        &mut scratch,
    )
}

/// The scalable (tiled) filter over the whole campaign.
fn scalable(b: &Bench) {
    let Bench {
        em,
        spec,
        model,
        kernel,
        n,
        cell_m,
        base,
        ..
    } = b;
    let (n, cell_m, base) = (*n, *cell_m, *base);
    let p = EkfParams::default().check().unwrap();
    let noise = NoiseModel::new(&em.meta, p.model_error, Path::new("floor")).unwrap();
    let mut f = TiledEkf::new(spec.rows, spec.cols, p.tile, &p).unwrap();
    // the map job's sight: the OG's detector (P_fa 1e-3, 10 dB mask) and occlusion model
    let og = pradar::mapping::OgParams::default().check().unwrap();
    let thr =
        pradar::mapping::og::detection_threshold(&em.meta, og.pfa, Path::new("floor")).unwrap();
    let det = pradar::mapping::og::Detector::new(thr, kernel, og.mask_db, model.min_bin);
    let occlusion = pradar::mapping::grid::Occlusion::new(model, model.min_bin, og.side_db);
    let sight = pradar::mapping::ekf::Sight {
        detector: &det,
        occlusion: &occlusion,
    };
    let st = ekf_run(
        model,
        em,
        kernel,
        &p,
        &noise,
        Some(sight),
        &mut f,
        &|_, _| {},
    )
    .unwrap();
    println!(
            "scalable cells={n} cell_m={cell_m:.3} poses={} updates={} campaign_s={:.2} build_s={:.2} update_s={:.2} per_update_ms={:.3} rows/update={:.0} entries/update={:.0} cov_MB={:.1} peak_MB={:.0} (before filter {base:.0})",
            model.poses.len(),
            st.updates,
            st.seconds,
            st.build_seconds,
            st.update_seconds,
            1e3 * st.update_seconds / st.updates as f64,
            st.rows as f64 / st.updates as f64,
            st.entries as f64 / st.updates as f64,
            f.covariance_bytes() as f64 / 1e6,
            peak_mb()
        );
}

/// The dense filter over the first `poses` poses, timing the updates.
fn dense(b: &Bench, poses: usize) {
    let Bench {
        em,
        model,
        kernel,
        n,
        cell_m,
        ..
    } = b;
    let (n, cell_m) = (*n, *cell_m);
    let p = EkfParams {
        variant: EkfVariant::Dense,
        ..Default::default()
    }
    .check()
    .unwrap();
    let noise = NoiseModel::new(&em.meta, p.model_error, Path::new("floor")).unwrap();
    let mut f = match DenseEkf::new(n, &p) {
        Ok(f) => f,
        Err(e) => {
            println!("dense cells={n}: {e}");
            return;
        }
    };
    let kern = truncate_kernel(kernel, p.kernel_floor_db);
    let t0 = Instant::now();
    let (mut upd, mut count, mut rows) = (0.0, 0usize, 0usize);
    for pi in 0..poses.min(model.poses.len()) {
        let g = model.pose_geometry(pi);
        for d in 0..model.directions() {
            let o = observe(b, &kern, &g, pi, d);
            let lin = Linearized::new(&o, f.mean(), &noise);
            let t = Instant::now();
            f.update(&o, &lin).unwrap();
            f.project_positive(p.x_min());
            upd += t.elapsed().as_secs_f64();
            count += 1;
            rows += o.rows();
        }
    }
    let total = t0.elapsed().as_secs_f64();
    let per = upd / count as f64;
    println!(
            "dense cells={n} cell_m={cell_m:.3} poses={poses} updates={count} seconds={total:.2} per_update_ms={:.2} rows/update={:.0} campaign_1000_poses_est_s={:.0} cov_MB={:.0} peak_MB={:.0}",
            1e3 * per,
            rows as f64 / count as f64,
            total / poses as f64 * model.poses.len() as f64,
            (n * n * 8) as f64 / 1e6,
            peak_mb()
        );
}

/// One dense update written out for `scripts/ekf_numpy.py` (x, P, H, ν, R before; x, P
/// after) and timed.
fn numpy(b: &Bench, dir: &Path) {
    let Bench {
        em,
        model,
        kernel,
        n,
        ..
    } = b;
    let n = *n;
    std::fs::create_dir_all(dir).unwrap();
    let p = EkfParams {
        variant: EkfVariant::Dense,
        ..Default::default()
    }
    .check()
    .unwrap();
    let noise = NoiseModel::new(&em.meta, p.model_error, Path::new("floor")).unwrap();
    let mut f = DenseEkf::new(n, &p).unwrap();
    let kern = truncate_kernel(kernel, p.kernel_floor_db);
    let warm = 10;
    let mut pick = None;
    for pi in 0..=warm {
        let g = model.pose_geometry(pi);
        for d in 0..model.directions() {
            let o = observe(b, &kern, &g, pi, d);
            if pi == warm && d == 18 {
                pick = Some(o);
                break;
            }
            let lin = Linearized::new(&o, f.mean(), &noise);
            f.update(&o, &lin).unwrap();
            f.project_positive(p.x_min());
        }
    }
    let o = pick.unwrap();
    let lin = Linearized::new(&o, f.mean(), &noise);
    let m = o.rows();
    let mut h = vec![0.0; m * n];
    for j in 0..m {
        for e in o.ptr[j]..o.ptr[j + 1] {
            h[j * n + o.cell[e] as usize] += lin.hval[e];
        }
    }
    write_npy(&dir.join("x.npy"), &[n], f.mean());
    write_npy(&dir.join("P.npy"), &[n, n], f.covariance_matrix());
    write_npy(&dir.join("H.npy"), &[m, n], &h);
    write_npy(&dir.join("nu.npy"), &[m], &lin.nu);
    write_npy(&dir.join("R.npy"), &[m], &lin.r);
    let mut best = f64::INFINITY;
    let mut after = None;
    for _ in 0..3 {
        let mut g = f.clone();
        let t = Instant::now();
        g.update(&o, &lin).unwrap();
        best = best.min(t.elapsed().as_secs_f64());
        after = Some(g);
    }
    let g = after.unwrap();
    write_npy(&dir.join("x_rust.npy"), &[n], g.mean());
    write_npy(&dir.join("P_rust.npy"), &[n, n], g.covariance_matrix());
    let na = {
        let mut c = o.cell.clone();
        c.sort_unstable();
        c.dedup();
        c.len()
    };
    println!(
        "rust_dense_update cells={n} bins={m} active={na} nnz={} seconds={best:.4} peak_MB={:.0}",
        o.cell.len(),
        peak_mb()
    );
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    if args.len() < 2 {
        eprintln!("usage: ekf (scalable|dense|numpy) CELLS [POSES|DIR]");
        return;
    }
    let mode = args[0].as_str();
    let cells: usize = args[1].parse().unwrap();
    let b = bench(cells);
    match mode {
        "scalable" => scalable(&b),
        "dense" => dense(&b, args.get(2).and_then(|v| v.parse().ok()).unwrap_or(20)),
        "numpy" => numpy(&b, Path::new(&args[2])),
        _ => eprintln!("unknown mode {mode}"),
    }
}
