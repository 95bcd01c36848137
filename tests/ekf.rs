//! EKF mapper (issue 6 parts 1-2): the prediction against the simulator on a single
//! scatterer, the dense update against a textbook EKF, covariance symmetry and PSD through a
//! corridor run, scalable vs dense, and the corridor map against the all-free and a random
//! map. Every figure asserted is printed.

#![allow(clippy::needless_range_loop)] // the textbook EKF is written with indices on purpose

use crate::common;

use common::*;
use pradar::campaign::manifest::SweepFormat;
use pradar::energy::EnergySource;
use pradar::mapping::ekf::{
    ekf_run, DenseEkf, EkfMap, EkfParams, EkfVariant, Linearized, NoiseModel, Observation,
    RrcsFilter, TiledEkf,
};
use pradar::mapping::grid::{GridParams, ObservationModel};
use pradar::mapping::job::{load_run, window_kernel, MapRun};
use pradar::mapping::metrics::evaluate;
use pradar::mapping::reference::{CellClass, GridSpec, LayoutRaster};
use pradar::mapping::score::{observable_region, score_binary};
use pradar::params::ParamGuard;
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

// ---------------------------------------------------------------- helpers

/// Simulated corridor at N = 100 (manifest, energy), once per test binary.
fn corridor100() -> &'static (PathBuf, PathBuf) {
    static RUN: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    RUN.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("ekf_corridor100");
        let mut t = corridor();
        set(&mut t, "array.elements", 100);
        let (c, _) = chain(&dir, &t, SweepFormat::Parquet);
        (c.path.clone(), dir.join("energy.parquet"))
    })
}

fn load(c: &Path, e: &Path, cell_m: f64) -> pradar::mapping::job::LoadedRun {
    let run = MapRun {
        campaign: c.to_path_buf(),
        energy: e.to_path_buf(),
    };
    let grid = GridParams {
        cell_m,
        ..Default::default()
    };
    load_run(
        &run,
        None,
        &grid.check().unwrap(),
        &pradar::mapping::OgParams::default().check().unwrap(),
        None,
    )
    .unwrap()
}

fn noise_of(l: &pradar::mapping::job::LoadedRun, p: &EkfParams) -> NoiseModel {
    NoiseModel::new(&l.energy.header().meta, p.model_error, &l.energy_path).unwrap()
}

/// Min and max eigenvalue of a symmetric matrix (cyclic Jacobi).
fn jacobi_eig_range(a: &[f64], n: usize) -> (f64, f64) {
    let mut a = a.to_vec();
    for _sweep in 0..50 {
        let mut off = 0.0;
        for i in 0..n {
            for j in 0..n {
                if i != j {
                    off += a[i * n + j] * a[i * n + j];
                }
            }
        }
        let diag: f64 = (0..n).map(|i| a[i * n + i] * a[i * n + i]).sum();
        if off <= 1e-26 * diag.max(1e-300) {
            break;
        }
        for p in 0..n {
            for q in (p + 1)..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let akp = a[k * n + p];
                    let akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let apk = a[p * n + k];
                    let aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
            }
        }
    }
    let d: Vec<f64> = (0..n).map(|i| a[i * n + i]).collect();
    (
        d.iter().cloned().fold(f64::INFINITY, f64::min),
        d.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
    )
}

/// Textbook EKF step with plain dense matrices: S = HPHᵀ + R, K = PHᵀS⁻¹ (Gauss-Jordan
/// inverse), x += Kν, P = (I − KH)P. Returns (x, P, K).
fn textbook(
    x: &[f64],
    p: &[f64],
    obs: &Observation,
    noise: &NoiseModel,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = x.len();
    let m = obs.rows();
    let mut h = vec![vec![0.0; n]; m];
    let mut pred = vec![0.0; m];
    let mut r = vec![0.0; m];
    for j in 0..m {
        let mut es = 0.0;
        for e in obs.ptr[j]..obs.ptr[j + 1] {
            let c = obs.cell[e] as usize;
            h[j][c] += 2.0 * obs.coef[e] * x[c];
            es += obs.coef[e] * x[c] * x[c];
        }
        pred[j] = es + noise.n0 * noise.tw;
        r[j] = (noise.n0 * noise.n0 * noise.tw + 2.0 * noise.n0 * es) / noise.pulses
            + (noise.model_error * es).powi(2);
    }
    let pm = |i: usize, j: usize| p[i * n + j];
    // PHᵀ (n × m)
    let mut pht = vec![vec![0.0; m]; n];
    for i in 0..n {
        for j in 0..m {
            pht[i][j] = (0..n).map(|k| pm(i, k) * h[j][k]).sum();
        }
    }
    let mut s = vec![vec![0.0; m]; m];
    for a in 0..m {
        for b in 0..m {
            s[a][b] =
                (0..n).map(|k| h[a][k] * pht[k][b]).sum::<f64>() + if a == b { r[a] } else { 0.0 };
        }
    }
    // inverse by Gauss-Jordan with partial pivoting, on the equilibrated matrix
    // D^-1/2 S D^-1/2 (D = diag S; the energies span decades), S^-1 = D^-1/2 (..)^-1 D^-1/2
    let dsq: Vec<f64> = (0..m).map(|i| s[i][i].sqrt()).collect();
    for a in 0..m {
        for b in 0..m {
            s[a][b] /= dsq[a] * dsq[b];
        }
    }
    let mut aug: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            let mut row = s[i].clone();
            row.extend((0..m).map(|j| if i == j { 1.0 } else { 0.0 }));
            row
        })
        .collect();
    for col in 0..m {
        let piv = (col..m)
            .max_by(|&a, &b| aug[a][col].abs().total_cmp(&aug[b][col].abs()))
            .unwrap();
        aug.swap(col, piv);
        let d = aug[col][col];
        for v in aug[col].iter_mut() {
            *v /= d;
        }
        for row in 0..m {
            if row != col {
                let f = aug[row][col];
                if f != 0.0 {
                    let pr = aug[col].clone();
                    for (v, pv) in aug[row].iter_mut().zip(pr) {
                        *v -= f * pv;
                    }
                }
            }
        }
    }
    let sinv: Vec<Vec<f64>> = aug
        .iter()
        .enumerate()
        .map(|(a, r)| {
            r[m..]
                .iter()
                .enumerate()
                .map(|(b, v)| v / (dsq[a] * dsq[b]))
                .collect()
        })
        .collect();
    let mut k = vec![0.0; n * m];
    for i in 0..n {
        for j in 0..m {
            k[i * m + j] = (0..m).map(|l| pht[i][l] * sinv[l][j]).sum();
        }
    }
    let mut xn = x.to_vec();
    for i in 0..n {
        xn[i] += (0..m)
            .map(|j| k[i * m + j] * (obs.z[j] - pred[j]))
            .sum::<f64>();
    }
    let mut ikh = vec![0.0; n * n];
    for i in 0..n {
        for c in 0..n {
            let kh: f64 = (0..m).map(|j| k[i * m + j] * h[j][c]).sum();
            ikh[i * n + c] = if i == c { 1.0 } else { 0.0 } - kh;
        }
    }
    let mut pn = vec![0.0; n * n];
    for i in 0..n {
        for c in 0..n {
            pn[i * n + c] = (0..n).map(|l| ikh[i * n + l] * pm(l, c)).sum();
        }
    }
    (xn, pn, k)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, b| a.max(b.abs()))
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = max_abs(b).max(1e-300);
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() / scale))
}

/// A random observation over `n` cells, rows using only cells `< active`.
fn random_obs(
    rng: &mut rand_chacha::ChaCha8Rng,
    n: usize,
    rows: usize,
    active: usize,
) -> Observation {
    let mut o = Observation {
        ptr: vec![0],
        ..Default::default()
    };
    for j in 0..rows {
        for c in 0..active.min(n) {
            if rng.gen::<f64>() < 0.4 {
                o.cell.push(c as u32);
                o.coef.push(1e-3 * (0.05 + rng.gen::<f64>()));
            }
        }
        if o.cell.len() == *o.ptr.last().unwrap() {
            o.cell.push((j % active) as u32);
            o.coef.push(1e-3);
        }
        o.bin.push(j as u32);
        o.z.push(1e-7 * (0.2 + 3.0 * rng.gen::<f64>()));
        o.ptr.push(o.cell.len());
    }
    o
}

// ---------------------------------------------------------------- tests

#[test]
fn prediction_matches_the_simulated_point_echo() {
    // point target (RRCS 0.3 m, 3 m at 20°, ideal 400-element array) simulated through the
    // frequency-dependent pattern; the mapper's prediction on a fine grid centred on it
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("ekf_point");
    let t = fixture("tests/point_target.toml");
    let (c, em) = chain(&tmp, &t, SweepFormat::Parquet);
    let (tx, ty) = (2.8190778623577253, 1.0260604299770062);
    let cell = 0.02;
    let spec = GridSpec {
        x0_m: tx - 5.5 * cell,
        y0_m: ty - 5.5 * cell,
        cell_m: cell,
        cols: 11,
        rows: 11,
    };
    let gp = GridParams {
        cell_m: cell,
        margin_m: 0.0,
        subsamples: 8,
        ..Default::default()
    };
    let mb = pradar::mapping::job::min_bin(&em);
    let model = ObservationModel::new(
        spec,
        &gp.check().unwrap(),
        &c.manifest,
        em.bins,
        em.meta.bin_width_ns,
        mb,
    )
    .unwrap();
    let geom = model.pose_geometry(0);
    let d = 22; // 20°
    let beam = model.beam(&geom, d);
    let params = EkfParams::default().check().unwrap();
    let kernel =
        pradar::mapping::ekf::truncate_kernel(&window_kernel(&c).unwrap(), params.kernel_floor_db);
    let prof = em.profile(0, d);
    let mut scratch = vec![0.0; spec.len()];
    let obs = Observation::build(&beam, &prof[..model.bins], &kernel, mb, &mut scratch);
    let mut x = vec![0.0; spec.len()];
    x[5 * 11 + 5] = 0.3;
    let noise = NoiseModel::new(&em.meta, 0.0, Path::new("e")).unwrap();
    let lin = Linearized::new(&obs, &x, &noise);
    // the echo's bins: predicted signal vs measured minus the noise mean
    let (mut pred, mut meas) = (0.0, 0.0);
    let (mut pk_pred, mut pk_meas) = ((0usize, 0.0f64), (0usize, 0.0f64));
    for j in 0..obs.rows() {
        let p = lin.h[j] - noise.mean();
        let z = obs.z[j] - noise.mean();
        pred += p;
        meas += z;
        if p > pk_pred.1 {
            pk_pred = (obs.bin[j] as usize, p);
        }
        if z > pk_meas.1 {
            pk_meas = (obs.bin[j] as usize, z);
        }
    }
    let full: f64 = prof.iter().map(|v| v - noise.mean()).sum();
    let db = 10.0 * (pred / meas).log10();
    eprintln!(
        "point echo: predicted {pred:.4e}, measured {meas:.4e} ({db:+.3} dB) over the {} observed bins (whole profile {full:.4e}); peak bin predicted {} ({:.4e}) measured {} ({:.4e}); kernel half-width {}",
        obs.rows(),
        pk_pred.0,
        pk_pred.1,
        pk_meas.0,
        pk_meas.1,
        kernel.len() - 1
    );
    assert!(db.abs() < 1.0, "prediction off by {db} dB");
    assert!(pk_pred.0.abs_diff(pk_meas.0) <= 1);
    let pdb = 10.0 * (pk_pred.1 / pk_meas.1).log10();
    eprintln!("peak energy predicted/measured {pdb:+.3} dB");
    assert!(pdb.abs() < 1.5);
}

#[test]
fn dense_update_equals_a_textbook_ekf_on_a_tiny_grid() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let n = 49; // 7 × 7
    let params = EkfParams::default().check().unwrap();
    let noise = NoiseModel {
        n0: 1e-10,
        tw: 1.3,
        pulses: 2.0,
        model_error: 0.5,
    };
    let mut f = DenseEkf::new(n, &params).unwrap();
    // three updates: m < na (rank-m form), m > na (rank-na form), and m < na again on the
    // now correlated covariance
    for (step, (rows, active)) in [(8usize, 49usize), (30, 12), (10, 40)]
        .into_iter()
        .enumerate()
    {
        let o = random_obs(&mut rng, n, rows, active);
        let x0 = f.mean().to_vec();
        let p0 = f.covariance_matrix().to_vec();
        let (xt, pt, kt) = textbook(&x0, &p0, &o, &noise);
        let lin = Linearized::new(&o, &x0, &noise);
        let k = f.gain(&o, &lin).unwrap();
        f.update(&o, &lin).unwrap();
        let (ex, ep, ek) = (
            max_rel_diff(f.mean(), &xt),
            max_rel_diff(f.covariance_matrix(), &pt),
            max_rel_diff(&k, &kt),
        );
        let dx = max_rel_diff(&xt, &x0);
        eprintln!(
            "update {step} ({rows} bins, {active} cells): max relative difference x {ex:.2e} P {ep:.2e} K {ek:.2e} (x moved by {dx:.2e})"
        );
        assert!(ex < 1e-9 && ep < 1e-9 && ek < 1e-9);
        assert!(dx > 1e-6, "the update must move the mean");
    }
}

#[test]
fn dense_update_equals_a_textbook_ekf_on_a_real_beam() {
    // 7 × 7 cells of 0.05 m around the point target, the real observation of direction 20°
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("ekf_point_tb");
    let t = fixture("tests/point_target.toml");
    let (c, em) = chain(&tmp, &t, SweepFormat::Parquet);
    let cell = 0.05;
    let spec = GridSpec {
        x0_m: 2.819 - 3.5 * cell,
        y0_m: 1.026 - 3.5 * cell,
        cell_m: cell,
        cols: 7,
        rows: 7,
    };
    let gp = GridParams {
        cell_m: cell,
        margin_m: 0.0,
        ..Default::default()
    };
    let mb = pradar::mapping::job::min_bin(&em);
    let model = ObservationModel::new(
        spec,
        &gp.check().unwrap(),
        &c.manifest,
        em.bins,
        em.meta.bin_width_ns,
        mb,
    )
    .unwrap();
    let params = EkfParams::default().check().unwrap();
    let kernel =
        pradar::mapping::ekf::truncate_kernel(&window_kernel(&c).unwrap(), params.kernel_floor_db);
    let noise = NoiseModel::new(&em.meta, params.model_error, Path::new("e")).unwrap();
    let mut f = DenseEkf::new(spec.len(), &params).unwrap();
    let geom = model.pose_geometry(0);
    for d in [22, 21] {
        let beam = model.beam(&geom, d);
        let mut scratch = vec![0.0; spec.len()];
        let o = Observation::build(
            &beam,
            &em.profile(0, d)[..model.bins],
            &kernel,
            mb,
            &mut scratch,
        );
        let x0 = f.mean().to_vec();
        let p0 = f.covariance_matrix().to_vec();
        let (xt, pt, kt) = textbook(&x0, &p0, &o, &noise);
        let lin = Linearized::new(&o, &x0, &noise);
        let k = f.gain(&o, &lin).unwrap();
        f.update(&o, &lin).unwrap();
        let (ex, ep, ek) = (
            max_rel_diff(f.mean(), &xt),
            max_rel_diff(f.covariance_matrix(), &pt),
            max_rel_diff(&k, &kt),
        );
        eprintln!(
            "real beam d={d}: {} bins x {} entries; max relative difference x {ex:.2e} P {ep:.2e} K {ek:.2e}",
            o.rows(),
            o.cell.len()
        );
        assert!(o.rows() > 3);
        assert!(ex < 1e-9 && ep < 1e-9 && ek < 1e-9);
    }
}

/// Run a filter over a loaded run.
fn run_filter(
    l: &pradar::mapping::job::LoadedRun,
    params: &pradar::mapping::EkfValid,
    f: &mut dyn RrcsFilter,
) -> pradar::mapping::ekf::EkfStats {
    let kernel = window_kernel(&l.campaign).unwrap();
    let occlusion = l.occlusion(&pradar::mapping::OgParams::default().check().unwrap());
    ekf_run(
        &l.model,
        &l.energy,
        &kernel,
        params,
        &noise_of(l, params),
        Some(pradar::mapping::ekf::Sight {
            detector: &l.detector,
            occlusion: &occlusion,
        }),
        f,
        &|_, _| {},
    )
    .unwrap()
}

#[test]
fn covariance_stays_symmetric_psd_through_a_corridor_run() {
    let (c, e) = corridor100();
    let l = load(c, e, 0.5);
    let n = l.model.spec.len();
    let params = EkfParams {
        variant: EkfVariant::Dense,
        ..Default::default()
    }
    .check()
    .unwrap();
    let mut f = DenseEkf::new(n, &params).unwrap();
    let kernel = window_kernel(&l.campaign).unwrap();
    let noise = noise_of(&l, &params);
    let mut worst: f64 = f64::INFINITY;
    // pose by pose (a sub-run per pose through an observation model of that pose)
    let np = l.model.poses.len();
    for p in 0..np {
        let geom = l.model.pose_geometry(p);
        let kern = pradar::mapping::ekf::truncate_kernel(&kernel, params.kernel_floor_db);
        let part = l.energy.load(p, p + 1).unwrap();
        for d in 0..l.model.directions() {
            let beam = l.model.beam(&geom, d);
            let mut scratch = vec![0.0; n];
            let prof = part.profile(p, d);
            let o = Observation::build(
                &beam,
                &prof[..l.model.bins],
                &kern,
                l.model.min_bin,
                &mut scratch,
            );
            let lin = Linearized::new(&o, f.mean(), &noise);
            f.update(&o, &lin).unwrap();
            f.project_positive(params.x_min());
        }
        if p % 4 == 3 || p == np - 1 {
            let pm = f.covariance_matrix();
            for i in 0..n {
                for j in 0..i {
                    assert_eq!(pm[i * n + j], pm[j * n + i], "asymmetric at {i},{j}");
                }
            }
            let (lo, hi) = jacobi_eig_range(pm, n);
            eprintln!(
                "after pose {}: {n} cells, eigenvalues of P in [{lo:.3e}, {hi:.3e}]",
                p + 1
            );
            worst = worst.min(lo);
            assert!(lo >= -1e-9, "min eigenvalue {lo}");
        }
    }
    eprintln!(
        "min eigenvalue over the run {worst:.3e} (prior variance {:.1e})",
        params.sigma0.powi(2)
    );
}

/// Item 4 of issue 17: the scalable EKF against the dense one on a grid where the dense one
/// runs (the corridor at 0.3 m cells).
#[test]
fn scalable_matches_dense_on_a_coarse_corridor() {
    scalable_against_dense(false, pradar::mapping::EkfUpdate::FirstOrder);
}

/// The scalable filter against the dense one; `strict` asserts item 4 in full.
fn scalable_against_dense(strict: bool, update: pradar::mapping::EkfUpdate) {
    let (c, e) = corridor100();
    let l = load(c, e, 0.3);
    let spec = l.model.spec;
    let n = spec.len();
    let reference = l.layout.rasterize(0.3, GridParams::default().margin_m);
    let region = pradar::mapping::score::Regions {
        observable: observable_region(&[&l.model], &l.layout),
        building: pradar::mapping::score::building_region(&l.layout, &reference),
        objects: None,
        edge_band: Vec::new(),
        detectable: None,
    };
    let dp = EkfParams {
        variant: EkfVariant::Dense,
        update,
        ..Default::default()
    }
    .check()
    .unwrap();
    let sp = EkfParams {
        update,
        ..Default::default()
    }
    .check()
    .unwrap();
    let mut dense = DenseEkf::new(n, &dp).unwrap();
    let t0 = std::time::Instant::now();
    run_filter(&l, &dp, &mut dense);
    let td = t0.elapsed().as_secs_f64();
    let mut tiled = TiledEkf::new(spec.rows, spec.cols, sp.tile, &sp).unwrap();
    let t1 = std::time::Instant::now();
    run_filter(&l, &sp, &mut tiled);
    let ts = t1.elapsed().as_secs_f64();
    let md = EkfMap::from_filter(&dense, spec.rows, spec.cols, &dp);
    let ms = EkfMap::from_filter(&tiled, spec.rows, spec.cols, &sp);
    let fd = score_binary(&md.binary(), &reference, &region).observable;
    let fs = score_binary(&ms.binary(), &reference, &region).observable;
    let rel_psi = (fs.psi - fd.psi).abs() / fd.psi;
    // kept cross-covariances (pairs in one tile) against the dense ones
    let (mut worst_corr, mut worst_rel, mut sum_rel, mut pairs) = (0.0f64, 0.0f64, 0.0, 0usize);
    let scale = (0..n)
        .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
        .filter_map(|(i, j)| {
            tiled
                .covariance(i, j)
                .map(|_| dense.covariance(i, j).unwrap().abs())
        })
        .fold(0.0f64, f64::max);
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            if let Some(s) = tiled.covariance(i, j) {
                let d = dense.covariance(i, j).unwrap();
                let norm =
                    (dense.covariance(i, i).unwrap() * dense.covariance(j, j).unwrap()).sqrt();
                worst_corr = worst_corr.max((s - d).abs() / norm);
                worst_rel = worst_rel.max((s - d).abs() / scale);
                sum_rel += (s - d).abs() / scale;
                pairs += 1;
            }
        }
    }
    let var_rel = (0..n)
        .map(|i| {
            (tiled.covariance(i, i).unwrap() - dense.covariance(i, i).unwrap()).abs()
                / dense.covariance(i, i).unwrap()
        })
        .fold(0.0f64, f64::max);
    eprintln!(
        "coarse corridor ({} x {} = {n} cells of 0.3 m): dense psi {:.3} F1 {:.3} ({:.1} s), scalable (tile {}) psi {:.3} F1 {:.3} ({:.2} s): psi differs by {:.1}%",
        spec.rows, spec.cols, fd.psi, fd.f1, td, sp.tile, fs.psi, fs.f1, ts, 100.0 * rel_psi
    );
    eprintln!(
        "kept cross-covariances ({pairs} ordered pairs): max |ΔP_ij|/sqrt(P_ii P_jj) {:.2e}, max |ΔP_ij|/max|P_ij| {:.2e}, mean {:.2e}; variances max relative difference {:.2e}",
        worst_corr, worst_rel, sum_rel / pairs as f64, var_rel
    );
    // the acceptance criterion of the scalable filter (issue 17): psi within 10 % of the
    // dense map's, per-cell means within 10 % (RMS relative over the updated cells) and
    // never over-confident (std >= 0.9x the dense std in >= 99 % of the updated cells)
    let updated: Vec<usize> = (0..n)
        .filter(|&i| dense.covariance(i, i).unwrap() < dp.sigma0 * dp.sigma0 * (1.0 - 1e-9))
        .collect();
    // RMS relative: ‖x̂_scalable − x̂_dense‖ / ‖x̂_dense‖ over the updated cells (a per-cell
    // ratio would divide by means the data drove to ~0)
    let rms_mean = (updated
        .iter()
        .map(|&i| (ms.mean[i] - md.mean[i]).powi(2))
        .sum::<f64>()
        / updated.iter().map(|&i| md.mean[i].powi(2)).sum::<f64>())
    .sqrt();
    let confident = updated
        .iter()
        .filter(|&&i| ms.std[i] >= 0.9 * md.std[i])
        .count() as f64
        / updated.len() as f64;
    let worst_std = updated
        .iter()
        .map(|&i| ms.std[i] / md.std[i])
        .fold(f64::INFINITY, f64::min);
    eprintln!(
        "criterion over {} updated cells: psi within {:.1}% (<= 10%), means RMS relative {:.2}% (<= 10%), std >= 0.9x dense in {:.2}% of cells (>= 99%; lowest ratio {worst_std:.3})",
        updated.len(),
        100.0 * rel_psi,
        100.0 * rms_mean,
        100.0 * confident
    );
    assert!(updated.len() > 50, "too few updated cells");
    // what holds: the scalable map is no worse than the dense one by more than 10 % on psi
    assert!(
        fs.psi <= 1.1 * fd.psi,
        "scalable psi {} vs dense {}",
        fs.psi,
        fd.psi
    );
    if strict {
        assert!(rel_psi <= 0.10, "psi differs by {rel_psi}");
        assert!(rms_mean <= 0.10, "means differ by {rms_mean} RMS relative");
        assert!(
            confident >= 0.99,
            "std >= 0.9x dense in only {confident} of the cells"
        );
    }
}

/// Item 4 of issue 17 in full: psi within 10 %, means within 10 % RMS relative and the
/// std at least 0.9x the dense std in at least 99 % of the updated cells. Unmet, with the
/// information split of issue 31 as without it (figures printed by
/// `scalable_matches_dense_on_a_coarse_corridor`; `docs/mapping.md`): psi 18.3 % apart (the
/// scalable map's the lower), means 51.7 % RMS relative, std >= 0.9x dense in 55.7 % of the
/// cells (plain tiled update: 16.6 %, 43.9 %, 56.7 %). The cause measured is the
/// nonlinearity, not the tiling: in the default prior regime the dense filter itself has a
/// NEES 97–220 times its expectation (`nees_in_the_default_prior_regime`), so two
/// overconfident filters are compared, and small differences are amplified by the
/// relinearisation (and the occluders confirmed against each filter's own map): dropping
/// only the covariance between the grid's two halves (two 20 x 20 tiles) leaves std >= 0.9x
/// dense in 77.5 % of the cells, means 27.5 % apart, and a dense filter kept exact within
/// each pose and block-diagonal between poses 86.2 %; in the near-linear regime of the NEES
/// test the split tiled filter's std is >= the dense filter's in every cell. Run with
/// `--ignored`.
#[test]
#[ignore = "unmet by the tiled approximation: psi 18.3 % apart, means 51.7 % RMS, std >= 0.9x dense in 55.7 % of cells (information split; plain update 16.6 %, 43.9 %, 56.7 %); the dense filter itself is inconsistent in this nonlinear regime"]
fn scalable_meets_the_dense_criterion() {
    scalable_against_dense(true, pradar::mapping::EkfUpdate::FirstOrder);
}

/// [`scalable_meets_the_dense_criterion`] with both filters on the second-order update
/// (issue 48; its dense filter is 44 times nearer consistency than the first order's, not
/// consistent: NEES 2.2). Unmet: psi 10.3 % apart, means 92.5 % RMS relative, std >= 0.9x
/// dense in 72.3 % of the updated cells (lowest ratio 0.047). About 4 s; run with
/// `--ignored`.
#[test]
#[ignore = "unmet: psi 10.3 % apart, means 92.5 % RMS, std >= 0.9x dense in 72.3 % of cells (second-order update)"]
fn scalable_meets_the_dense_criterion_with_the_second_order_update() {
    scalable_against_dense(true, pradar::mapping::EkfUpdate::SecondOrder);
}

#[test]
fn ekf_corridor_map_beats_all_free_and_random() {
    let (c, e) = corridor100();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ekf");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_pradar"))
        .args(["map", "--method", "ekf", "--campaign"])
        .arg(c)
        .arg("--energy")
        .arg(e)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "ekf.png",
        "ekf.pgm",
        "ekf.yaml",
        "ekf_binary.pgm",
        "ekf_binary.yaml",
        "ekf_mean.pgm",
        "ekf_std.pgm",
        "ekf_rrcs.csv",
        "reference.pgm",
        "metrics.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let g = |r: &str, k: &str| j["metrics"][r][k].as_f64().unwrap();
    // random maps of equal occupancy on the observable region (5 seeds) from the CSV
    let l = load(c, e, 0.1);
    let reference = l.layout.rasterize(0.1, 0.5);
    let region = observable_region(&[&l.model], &l.layout);
    let refo: Vec<bool> = reference
        .cells
        .iter()
        .map(|c| *c == CellClass::Occupied)
        .collect();
    let occupied = g("observable", "map_occupied") as usize;
    let cells: Vec<usize> = (0..region.len()).filter(|&i| region[i]).collect();
    let (rows, cols) = (reference.spec.rows, reference.spec.cols);
    let mut rnd_psi = Vec::new();
    let mut rnd_f1 = Vec::new();
    for seed in 0..5u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut pick = cells.clone();
        for i in 0..occupied.min(pick.len()) {
            let k = rng.gen_range(i..pick.len());
            pick.swap(i, k);
        }
        let mut map = vec![false; region.len()];
        for &i in &pick[..occupied.min(pick.len())] {
            map[i] = true;
        }
        let m = evaluate(&map, &refo, &region, rows, cols);
        rnd_psi.push(m.psi);
        rnd_f1.push(m.f1);
    }
    let best_rnd_psi = rnd_psi.iter().cloned().fold(f64::INFINITY, f64::min);
    let best_rnd_f1 = rnd_f1.iter().cloned().fold(0.0, f64::max);
    eprintln!(
        "EKF corridor N=100 (scalable, 0.1 m): observable psi {:.3} F1 {:.3} F1(1 cell) {:.3} wrong {:.3} occupied {occupied} | all-free psi {:.3} F1 {:.3} wrong {:.3} | random (equal occupancy, 5 seeds) psi {:?} F1 {:?} || whole psi {:.3} F1 {:.3} | all-free whole psi {:.3}",
        g("observable", "psi"),
        g("observable", "f1"),
        g("observable", "f1_1"),
        g("observable", "wrong_cell_rate"),
        g("observable_all_free", "psi"),
        g("observable_all_free", "f1"),
        g("observable_all_free", "wrong_cell_rate"),
        rnd_psi.iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>(),
        rnd_f1.iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>(),
        g("whole", "psi"),
        g("whole", "f1"),
        g("whole_all_free", "psi"),
    );
    assert!(occupied > 0);
    assert!(g("observable", "psi") < g("observable_all_free", "psi"));
    assert!(g("observable", "f1") > g("observable_all_free", "f1"));
    assert!(g("observable", "psi") < best_rnd_psi);
    assert!(g("observable", "f1") > best_rnd_f1);
}

#[test]
fn ekf_map_is_identical_with_one_and_two_threads() {
    let (c, e) = corridor100();
    let tmp = tempfile::tempdir().unwrap();
    let mut csv = Vec::new();
    for threads in ["1", "2"] {
        let out = tmp.path().join(threads);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_pradar"))
            .args([
                "map",
                "--method",
                "ekf",
                "--ekf",
                "dense",
                "--cell-m",
                "0.4",
                "--campaign",
            ])
            .arg(c)
            .arg("--energy")
            .arg(e)
            .arg("--out")
            .arg(&out)
            .arg("--quiet")
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        csv.push(std::fs::read(out.join("ekf_rrcs.csv")).unwrap());
    }
    eprintln!(
        "dense EKF at 0.4 m: ekf_rrcs.csv {} bytes, identical with 1 and 2 threads",
        csv[0].len()
    );
    assert_eq!(csv[0], csv[1]);
}

#[test]
fn bad_ekf_parameters_give_one_clear_error() {
    let (c, e) = corridor100();
    let tmp = tempfile::tempdir().unwrap();
    for (args, name) in [
        (vec!["--mu0", "0"], "mu0"),
        (vec!["--sigma0=-1"], "sigma0"),
        (vec!["--ekf", "fast"], "ekf"),
        (vec!["--ekf", "dense"], "dense EKF"), // 0.1 m corridor grid exceeds nothing? see below
    ] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_pradar"))
            .args(["map", "--method", "ekf", "--campaign"])
            .arg(c)
            .arg("--energy")
            .arg(e)
            .arg("--out")
            .arg(tmp.path().join("x"))
            .args(&args)
            .args(if name == "dense EKF" {
                vec!["--cell-m", "0.03"]
            } else {
                vec![]
            })
            .arg("--quiet")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        eprintln!("{args:?}: {}", err.trim());
        assert!(!o.status.success());
        assert!(err.contains(name), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!err.contains("panicked"));
    }
}

// ---------------------------------------------------------------- NEES (issue 31, item 3)

/// A NEES regime: the filter's prior N(μ0, σ0²·I), which is also the truth's distribution,
/// and the relative model error ε of the noise model (the other EKF parameters at their
/// defaults).
#[derive(Clone, Copy)]
struct Regime {
    mu0: f64,
    sigma0: f64,
    model_error: f64,
    /// The truth is |x| (the model sees x², so only |x| is identifiable; for a prior that
    /// reaches below zero).
    fold: bool,
}

/// The figures of [`nees`]: updated cells n, runs N, the two-sided 95 % band of the
/// summed NEES (χ²(N·n)) and the summed NEES of the dense and the tiled (information
/// split) filter; the smallest ratio of tiled to dense std over the cells and runs.
struct Nees {
    n: usize,
    runs: usize,
    band: (f64, f64),
    dense: f64,
    tiled: f64,
    min_std_ratio: f64,
}

impl Nees {
    fn anees(&self, sum: f64) -> f64 {
        sum / (self.n * self.runs) as f64
    }
    fn inside(&self, sum: f64) -> bool {
        sum >= self.band.0 && sum <= self.band.1
    }
    fn print(&self, what: &str) {
        let (lo, hi) = (self.anees(self.band.0), self.anees(self.band.1));
        eprintln!(
            "NEES {what}: {} updated cells x {} runs, 95 % band of the average NEES / n [{lo:.3}, {hi:.3}]: dense {:.3}, tiled (split) {:.3}; tiled (split) std >= {:.3}x dense",
            self.n,
            self.runs,
            self.anees(self.dense),
            self.anees(self.tiled),
            self.min_std_ratio
        );
    }
}

/// The NEES scene: `side` x `side` cells of `cell_m` centred in the room, directions in
/// `step_deg` steps.
#[derive(Clone, Copy)]
struct Scene {
    cell_m: f64,
    side: usize,
    step_deg: f64,
}

/// NEES of the dense and the tiled filter over `runs` Monte Carlo runs (issue 31 item 3).
///
/// Scene: a grid of `scene.side`² cells at the centre of a 6 m room ([`SMALL`]: 10 x 10
/// cells of 0.3 m, [`DENSE_SCAN`]: 12 x 12 of 0.25 m; 4 x 4 tiles) seen from 8 poses around
/// it (16-element array, whose wide beams make each bin's range ring cross several tiles;
/// the half-plane in `scene.step_deg` steps; 57.5–63.5 GHz). Each run draws a truth map x from the
/// filter's own prior N(μ0, σ0²·I) and simulates every (pose, direction) observation
/// from the filter's own model: z_k = h_k(x) + √R_k(x)·w, w ~ N(0, 1), h and R the
/// kernel-folded prediction and noise model of [`Linearized::new`] evaluated at the truth
/// (N0 = 1e-12, TW of the band, one pulse). No sight model and no free-space evidence: this
/// tests the filters' update, not the pipeline's choice of rows. The dense and the tiled
/// (information split) filter run over the same observations.
///
/// NEES of a run: ε = (x̂ − x)ᵀ P⁻¹ (x̂ − x) over the updated cells (P_ii below σ0²), with
/// the dense filter's full covariance, and for a tiled filter the sum of the same form over
/// its blocks (what it holds). Summed over the N runs it is χ²(N·n) for a consistent
/// filter; the band is its 2.5 % and 97.5 % quantiles.
fn nees(scene: Scene, reg: Regime, runs: usize, seed0: u64) -> Nees {
    nees_with(scene, reg, runs, seed0, Update::Ekf)
}

/// The update under test in [`nees_with`].
#[derive(Clone, Copy, Debug)]
enum Update {
    /// The EKF: linearised once at the mean.
    Ekf,
    /// The Gaussian second-order filter ([`Linearized::second_order`]).
    SecondOrder,
}

/// One update of `f` by `o` under `upd`.
fn apply<F: RrcsFilter>(f: &mut F, o: &Observation, noise: &NoiseModel, upd: Update) {
    match upd {
        Update::Ekf => {
            let lin = Linearized::new(o, f.mean(), noise);
            f.update(o, &lin).unwrap();
        }
        Update::SecondOrder => {
            let lin = f.linearize_second_order(o, noise);
            f.update(o, &lin).unwrap();
        }
    }
}

/// [`nees`] with the update `upd` for both filters.
fn nees_with(scene: Scene, reg: Regime, runs: usize, seed0: u64, upd: Update) -> Nees {
    use rayon::prelude::*;
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let tmp = tempfile::tempdir().unwrap();
    let c = nees_room(tmp.path(), scene);
    let setup = NeesSetup::new(&c, scene, reg);
    let per_run: Vec<(usize, f64, f64, f64)> = (0..runs)
        .into_par_iter()
        .map(|r| setup.run(seed0 + r as u64, upd))
        .collect();
    let nu = per_run[0].0;
    assert!(
        per_run.iter().all(|r| r.0 == nu),
        "the updated cells depend on the geometry only"
    );
    let dof = (nu * runs) as f64;
    let chi = ChiSquared::new(dof).unwrap();
    Nees {
        n: nu,
        runs,
        band: (chi.inverse_cdf(0.025), chi.inverse_cdf(0.975)),
        dense: per_run.iter().map(|r| r.1).sum(),
        tiled: per_run.iter().map(|r| r.2).sum(),
        min_std_ratio: per_run.iter().map(|r| r.3).fold(f64::INFINITY, f64::min),
    }
}

/// Takes a folder and the scene; writes the 6 m room's layout and campaign (8 poses
/// around the centre, the scene's direction step) into it and gives the campaign.
fn nees_room(dir: &Path, scene: Scene) -> pradar::campaign::Campaign {
    std::fs::write(
        dir.join("room.geojson"),
        r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"role":"perimeter"},"geometry":{"type":"Polygon","coordinates":[[[0,0],[6,0],[6,6],[0,6],[0,0]]]}}]}"#,
    )
    .unwrap();
    let t = String::from(
        "schema_version = 1\nname = \"room\"\nlayout = \"room.geojson\"\nseed = 1\n[band]\nstart_hz = 57.5e9\nstop_hz = 63.5e9\npoints = 801\n[array]\nelements = 16\n[directions]\nstart_deg = -90.0\nstop_deg = 90.0\nstep_deg = STEP\n[noise]\nfloor_dbm = -100.0\n[processing]\ncoupling = \"gate\"\ngate_ns = 3.0\nmax_delay_ns = 40.0\nnoise_from_ns = 60.0\n",
    );
    let mut t = t.replace("STEP", &format!("{:?}", scene.step_deg));
    for (x, y, h) in [
        (3.0, 0.5, 90.0),
        (1.0, 0.8, 60.0),
        (5.0, 0.8, 120.0),
        (0.5, 3.0, 0.0),
        (5.5, 3.0, 180.0),
        (3.0, 5.5, 270.0),
        (1.0, 5.2, 300.0),
        (5.0, 5.2, 240.0),
    ] {
        t.push_str(&format!(
            "[[poses]]\nx_m = {x}\ny_m = {y}\nheading_deg = {h}\n"
        ));
    }
    std::fs::write(dir.join("campaign.toml"), t).unwrap();
    pradar::campaign::Campaign::load(&dir.join("campaign.toml")).unwrap()
}

/// What every NEES run shares: the regime, the filters' parameters, the noise model, the
/// observations' rows and coefficients (the truth only sets z), the grid's size and the
/// prior variance.
struct NeesSetup {
    /// The prior and model error.
    reg: Regime,
    /// The dense filter's parameters.
    pd: pradar::mapping::EkfValid,
    /// The tiled filter's (the same).
    ps: pradar::mapping::EkfValid,
    /// The noise model.
    noise: NoiseModel,
    /// Every (pose, direction) observation with rows, z unset.
    rows: Vec<Observation>,
    /// Cells.
    n: usize,
    /// Grid side, cells.
    side: usize,
    /// Prior variance σ0².
    v0: f64,
}

impl NeesSetup {
    /// Takes the room's campaign, the scene and the regime; gives the grid at the room's
    /// centre, its observation model's rows and the filters' parameters.
    fn new(c: &pradar::campaign::Campaign, scene: Scene, reg: Regime) -> NeesSetup {
        let m = &c.manifest;
        let proc = pradar::energy::EnergyProcessor::new(m.band, m.processing).unwrap();
        let tb = proc.bin_width_ns();
        let min_bin = 2 + (m.processing.gate_ns / tb).ceil() as usize;
        let (cell, side) = (scene.cell_m, scene.side);
        let spec = GridSpec {
            x0_m: 3.0 - cell * side as f64 / 2.0,
            y0_m: 3.0 - cell * side as f64 / 2.0,
            cell_m: cell,
            cols: side,
            rows: side,
        };
        let gp = GridParams {
            cell_m: cell,
            margin_m: 0.0,
            ..Default::default()
        };
        let model = ObservationModel::new(spec, &gp.check().unwrap(), m, proc.nbins(), tb, min_bin)
            .unwrap();
        // dense and tiled share the parameters
        let pd = EkfParams {
            mu0: reg.mu0,
            sigma0: reg.sigma0,
            model_error: reg.model_error,
            ..Default::default()
        }
        .check()
        .unwrap();
        let ps = pd.clone();
        let kern =
            pradar::mapping::ekf::truncate_kernel(&window_kernel(c).unwrap(), pd.kernel_floor_db);
        let noise = NoiseModel {
            n0: 1e-12,
            tw: proc.tw(),
            pulses: 1.0,
            model_error: reg.model_error,
        };
        let n = spec.len();
        // the observations' rows and coefficients (the truth only sets z)
        let mut rows = Vec::new();
        for p in 0..model.poses.len() {
            let geom = model.pose_geometry(p);
            for d in 0..model.directions() {
                let mut scratch = vec![0.0; n];
                let o = Observation::build(
                    &model.beam(&geom, d),
                    &vec![0.0; model.bins],
                    &kern,
                    model.min_bin,
                    &mut scratch,
                );
                if o.rows() > 0 {
                    rows.push(o);
                }
            }
        }
        let v0 = reg.sigma0 * reg.sigma0;
        NeesSetup {
            reg,
            pd,
            ps,
            noise,
            rows,
            n,
            side,
            v0,
        }
    }

    /// One run at `seed`: takes the seed and the update; draws a truth from the prior and
    /// the observations from the model at it, runs the dense and the tiled filter, and
    /// gives (updated cells, dense NEES, tiled NEES, smallest tiled/dense std ratio).
    fn run(&self, seed: u64, upd: Update) -> (usize, f64, f64, f64) {
        use rand_distr::{Distribution, StandardNormal};
        let (reg, pd, ps, noise) = (self.reg, &self.pd, &self.ps, &self.noise);
        let (rows, n, side, v0) = (&self.rows, self.n, self.side, self.v0);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let x: Vec<f64> = (0..n)
            .map(|_| {
                let w: f64 = StandardNormal.sample(&mut rng);
                let v = reg.mu0 + reg.sigma0 * w;
                if reg.fold {
                    v.abs()
                } else {
                    v
                }
            })
            .collect();
        let obs: Vec<Observation> = rows
            .iter()
            .map(|o| {
                let mut o = o.clone();
                let at_truth = Linearized::new(&o, &x, noise);
                for j in 0..o.rows() {
                    let w: f64 = StandardNormal.sample(&mut rng);
                    o.z[j] = at_truth.h[j] + at_truth.r[j].sqrt() * w;
                }
                o
            })
            .collect();
        let mut dense = DenseEkf::new(n, pd).unwrap();
        run_updates(&mut dense, &obs, pd, noise, upd);
        let mut tiled = TiledEkf::new(side, side, ps.tile, ps).unwrap();
        run_updates(&mut tiled, &obs, ps, noise, upd);
        let upd: Vec<usize> = (0..n)
            .filter(|&i| dense.variances()[i] < v0 * (1.0 - 1e-9))
            .collect();
        let (vd, vt) = (dense.variances(), tiled.variances());
        let ratio = upd
            .iter()
            .map(|&i| (vt[i] / vd[i]).sqrt())
            .fold(f64::INFINITY, f64::min);
        (
            upd.len(),
            nees_of(&dense, &x, &upd),
            nees_of(&tiled, &x, &upd),
            ratio,
        )
    }
}

/// Takes a filter, the truth and the updated cells; gives the filter's NEES over those
/// cells, block by block of what it holds.
fn nees_of(f: &dyn RrcsFilter, x: &[f64], upd: &[usize]) -> f64 {
    let mut blocks: Vec<Vec<usize>> = Vec::new();
    for &i in upd {
        match blocks.iter_mut().find(|b| f.covariance(b[0], i).is_some()) {
            Some(b) => b.push(i),
            None => blocks.push(vec![i]),
        }
    }
    blocks
        .iter()
        .map(|b| {
            let k = b.len();
            let pm = nalgebra::DMatrix::from_fn(k, k, |a, c| f.covariance(b[a], b[c]).unwrap());
            let e = nalgebra::DVector::from_fn(k, |a, _| f.mean()[b[a]] - x[b[a]]);
            e.dot(
                &nalgebra::Cholesky::new(pm)
                    .expect("P positive definite")
                    .solve(&e),
            )
        })
        .sum()
}

/// Takes a filter, the observations, its parameters, the noise model and the update;
/// applies every observation in order, each followed by the positivity step.
fn run_updates<F: RrcsFilter>(
    f: &mut F,
    obs: &[Observation],
    p: &pradar::mapping::EkfValid,
    noise: &NoiseModel,
    upd: Update,
) {
    for o in obs {
        apply(f, o, noise, upd);
        f.project_positive(p.x_min());
    }
}

/// The near-linear regime: prior mean 10 prior standard deviations above zero (μ0 = 1 m,
/// σ0 = 0.1 m), so the neglected term c̃·δ² of h = c̃·x² is at most 3σ0/(2μ0) = 15 % of the
/// linear term 2c̃·x̂·δ at three prior standard deviations, less once the first updates
/// have shrunk δ, and no mean comes near zero (no reflection); ε = 0.1 (each bin's energy
/// known to 10 %: the posterior std ends at 2–16 % of the prior's, where the plain tiled
/// filter's overconfidence shows).
const NEAR_LINEAR: Regime = Regime {
    mu0: 1.0,
    sigma0: 0.1,
    model_error: 0.1,
    fold: false,
};

/// The default suite's scene: 10 x 10 cells of 0.3 m (100 cells, 9 tiles), 10° steps
/// (19 directions per pose): a few seconds for 20 runs of the dense filter.
const SMALL: Scene = Scene {
    cell_m: 0.3,
    side: 10,
    step_deg: 10.0,
};

/// A denser scene: 12 x 12 cells of 0.25 m, 5° steps (neighbouring beams overlap more, so
/// each range ring is seen more often within a pose).
const DENSE_SCAN: Scene = Scene {
    cell_m: 0.25,
    side: 12,
    step_deg: 5.0,
};

/// Over 20 Monte Carlo runs in the near-linear regime the NEES of the dense filter and of
/// the tiled filter (information split) lie in the two-sided 95 % χ² band. Figures
/// (`docs/mapping.md`, with the plain tiled update's, above the band in every seed set;
/// that update can be rerun from commit b50404a): average NEES per cell dense 0.982, split 0.986 against
/// the band [0.939, 1.063] (the five seed sets of the pooled test: dense 0.965–1.020 and
/// split 0.973–1.028 inside in 5 of 5). Pooled over 100 runs, and in a denser scan or at
/// the default model error, the split is not inside
/// (`nees_pooled_over_100_runs_in_four_configurations`). The second-order update of issue 48
/// is inside too (dense 0.977, tiled 0.981).
#[test]
fn nees_of_the_dense_and_the_tiled_filter_is_inside_the_chi2_band() {
    let t0 = std::time::Instant::now();
    let r = nees(SMALL, NEAR_LINEAR, 20, 1000);
    r.print(&format!(
        "10 x 10 cells, 10° steps, near-linear regime, ε = 0.1 ({:.1} s)",
        t0.elapsed().as_secs_f64()
    ));
    assert!(r.n >= 100, "too few updated cells");
    assert!(r.inside(r.dense), "dense filter inconsistent");
    assert!(r.inside(r.tiled), "tiled filter inconsistent");
    assert!(r.min_std_ratio >= 0.9, "tiled std below 0.9x dense");
    // the second-order update (`--ekf-update second-order`) stays consistent where the
    // first order is: its extra terms are small when the prior is far from zero
    let t0 = std::time::Instant::now();
    let s = nees_with(SMALL, NEAR_LINEAR, 20, 1000, Update::SecondOrder);
    s.print(&format!(
        "10 x 10 cells, 10° steps, near-linear regime, ε = 0.1, second order ({:.1} s)",
        t0.elapsed().as_secs_f64()
    ));
    assert!(s.inside(s.dense), "second-order dense filter inconsistent");
    assert!(s.inside(s.tiled), "second-order tiled filter inconsistent");
}

/// [`nees`] over `sets` sets of 20 runs (seeds 1000·k + run, k = 1..=sets), pooled: the
/// sums add and the band is χ²(n·20·sets)'s.
fn nees_pooled(scene: Scene, reg: Regime, sets: u64) -> Nees {
    let all: Vec<Nees> = (1..=sets).map(|k| nees(scene, reg, 20, 1000 * k)).collect();
    let n = all[0].n;
    let runs = 20 * sets as usize;
    let chi = statrs::distribution::ChiSquared::new((n * runs) as f64).unwrap();
    use statrs::distribution::ContinuousCDF;
    Nees {
        n,
        runs,
        band: (chi.inverse_cdf(0.025), chi.inverse_cdf(0.975)),
        dense: all.iter().map(|r| r.dense).sum(),
        tiled: all.iter().map(|r| r.tiled).sum(),
        min_std_ratio: all
            .iter()
            .map(|r| r.min_std_ratio)
            .fold(f64::INFINITY, f64::min),
    }
}

/// The same test pooled over 100 runs (five seed sets) in four near-linear configurations
/// (the default suite's scene and the 12 x 12 scene at 5° steps, each at ε = 0.1 and at
/// the default ε = 0.5), where the band is ±2–3 %: the dense filter is inside in all four,
/// the tiled filter with the information split only in the default suite's (pooled average
/// NEES per cell 0.996; 1.057 in the denser scan at ε = 0.1, above the band; 0.967–0.969
/// at ε = 0.5, below it), the plain tiled update in none (1.07–1.60). The split is a
/// heuristic, not a bound (`mapping::ekf::tiled`): its discount is right on average, not
/// for every amount of repetition of a ring within a pose. Run with `--ignored` (about
/// 4 min on 2 cores).
#[test]
#[ignore = "unmet by the tiled filter: pooled average NEES per cell 1.057 (12 x 12, 5° steps, ε = 0.1), 0.969 and 0.967 (ε = 0.5) against bands of ±2–3 %"]
fn nees_pooled_over_100_runs_in_four_configurations() {
    let mut fails = Vec::new();
    for (scene, name) in [
        (SMALL, "10 x 10, 10° steps"),
        (DENSE_SCAN, "12 x 12, 5° steps"),
    ] {
        for eps in [0.1, 0.5] {
            let reg = Regime {
                model_error: eps,
                ..NEAR_LINEAR
            };
            let r = nees_pooled(scene, reg, 5);
            r.print(&format!("{name}, near-linear regime, ε = {eps}, pooled"));
            for (filter, v) in [("dense", r.dense), ("tiled", r.tiled)] {
                if !r.inside(v) {
                    fails.push(format!("{name}, ε = {eps}: {filter} {:.3}", r.anees(v)));
                }
            }
        }
    }
    assert!(fails.is_empty(), "outside the band: {}", fails.join("; "));
}

/// The default prior (μ0 = 0.01 m, σ0 = 0.1 m: the prior reaches far below zero, the
/// truth is |x|) and the default ε = 0.5, far from linear: issue 48's must-show is the
/// dense filter's NEES inside the band here. The EKF (first order) is at 96.8 times its
/// expectation (97–220 over five seed sets; the tiled filter 91–211): it splits a ring's
/// energy between its cells at the first linearisations and keeps a tight, wrong split. The
/// Gaussian second-order filter (`--ekf-update second-order`) brings the dense filter to
/// 2.20 and the tiled one to 2.51 against [0.949, 1.052]; with the quadratic term's
/// covariance between rows as well (a textbook dense update, measured at commit c7e1523)
/// 1.56; the iterated EKF (5 iterations) 3.63 / 3.09 (`docs/mapping.md`, "Issue 48"). About
/// 25 s; run with `--ignored`.
#[test]
#[ignore = "unmet: average NEES per cell, dense / tiled, second-order 2.20 / 2.51, first-order 96.8 / 90.9, against [0.949, 1.052]"]
fn nees_in_the_default_prior_regime() {
    let d = EkfParams::default();
    let reg = Regime {
        mu0: d.mu0,
        sigma0: d.sigma0,
        model_error: d.model_error,
        fold: true,
    };
    let first = nees_with(DENSE_SCAN, reg, 20, 1000, Update::Ekf);
    first.print("12 x 12 cells, 5° steps, default prior and ε, first order");
    let second = nees_with(DENSE_SCAN, reg, 20, 1000, Update::SecondOrder);
    second.print("12 x 12 cells, 5° steps, default prior and ε, second order");
    // the second-order filter's confidence is far nearer its claim than the EKF's
    assert!(second.anees(second.dense) < first.anees(first.dense) / 10.0);
    assert!(
        second.inside(second.dense) && second.inside(second.tiled),
        "second-order NEES outside the band"
    );
}
