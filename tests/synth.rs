//! `pradar synth` (the statistical channel model): agreement with `simulate` on a single
//! scatterer, energy-detector statistics, determinism, model-file round trip and errors.

use crate::common;

use common::{fixture, set, write_campaign};
use geo::Coord;
use pradar::campaign::manifest::SweepFormat;
use pradar::campaign::Campaign;
use pradar::energy::EnergyMatrix;
use pradar::model::file::ModelConfig;
use pradar::model::{
    synth, synth_channel, ChannelModel, ModelCluster, ModelRay, SynthParams, SynthValid,
};
use pradar::params::ParamGuard;
use std::process::Command;

fn pradar() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pradar"))
}

/// One scatterer at `at` with σ = `sigma`, one ray.
fn single(at: Coord<f64>, sigma: f64) -> ChannelModel {
    ChannelModel {
        config: ModelConfig::table1_defaults(),
        clusters: vec![ModelCluster {
            centre: at,
            arc_m: 0.0,
            offset_m: 0.0,
            sigma_m2: sigma,
            rays: vec![ModelRay {
                excess_ns: 0.0,
                aoa_rad: 0.0,
            }],
            mean_depth_m: 0.0,
        }],
    }
}

#[test]
fn synth_agrees_with_simulate_on_a_single_scatterer() {
    let tmp = tempfile::tempdir().unwrap();
    // the point-target fixture: 3 m at 20°, RRCS 0.3 m
    let base = fixture("tests/point_target.toml");
    let tx = base["scene"]["targets"][0]["x_m"].as_float().unwrap();
    let ty = base["scene"]["targets"][0]["y_m"].as_float().unwrap();
    let rrcs = base["scene"]["targets"][0]["rrcs_m"].as_float().unwrap();
    let mut worst: f64 = 0.0;
    for (n, one_bit) in [
        (16, false),
        (100, false),
        (400, false),
        (100, true),
        (400, true),
    ] {
        let mut t = base.clone();
        set(&mut t, "array.elements", n as i64);
        set(&mut t, "array.one_bit", one_bit);
        let dir = tmp.path().join(format!("n{n}_{one_bit}"));
        let (_, sim) = common::chain(&dir, &t, SweepFormat::Parquet);
        let c = Campaign::load(&dir.join("in/campaign.toml")).unwrap();
        let out = dir.join("synth.parquet");
        synth_channel(
            &c,
            &single(Coord { x: tx, y: ty }, rrcs * rrcs),
            &out,
            &SynthParams::default().check().unwrap(),
            &|_, _| {},
        )
        .unwrap();
        let syn = EnergyMatrix::read(&out).unwrap();
        assert_eq!(syn.bins, sim.bins);
        // compare at the peak of the simulated matrix and in the directions around it
        let (mut pd, mut pb, mut pe) = (0, 0, 0.0);
        for d in 0..sim.directions() {
            for (b, &e) in sim.profile(0, d).iter().enumerate() {
                if e > pe {
                    (pd, pb, pe) = (d, b, e);
                }
            }
        }
        let floor = sim.meta.noise_mean();
        let mut line = format!("N={n} one_bit={one_bit}: peak dir {pd} bin {pb}");
        for dd in [-2i64, -1, 0, 1, 2] {
            let d = pd as i64 + dd;
            if d < 0 || d >= sim.directions() as i64 {
                continue;
            }
            let d = d as usize;
            // energy around the echo (±3 bins) with the noise mean removed
            let sum = |em: &EnergyMatrix| -> f64 {
                em.profile(0, d)[pb - 3..=pb + 3]
                    .iter()
                    .map(|e| e - em.meta.noise_mean())
                    .sum()
            };
            let (a, b) = (sum(&sim), sum(&syn));
            if a < 1e3 * floor {
                continue;
            }
            let db = 10.0 * (b / a).log10();
            line += &format!("  d{dd:+}: {db:+.2} dB");
            worst = worst.max(db.abs());
        }
        let peak_syn = syn.profile(0, pd)[pb];
        let db_peak = 10.0 * (peak_syn / pe).log10();
        line += &format!("  peak bin {db_peak:+.2} dB");
        worst = worst.max(db_peak.abs());
        // the noise floors agree too (synth's N0 from the [noise] floor, energy's estimated)
        let nf = 10.0 * (syn.meta.noise_mean() / floor).log10();
        line += &format!("  noise mean {nf:+.2} dB");
        assert!(nf.abs() < 0.2, "{line}");
        eprintln!("{line}");
    }
    eprintln!("worst |synth − simulate| = {worst:.2} dB");
    assert!(worst < 1.0, "synth and simulate differ by {worst:.2} dB");
}

#[test]
fn energy_detector_noise_has_the_detector_mean_and_variance() {
    // no clusters at all: every bin after the coupling gate is noise, with mean N0·TW and
    // variance N0²TW/Np, N0 the [noise] floor's through the window or the one given
    // (`check` and `calibrate` give the measured table's). The bins inside the gate are
    // left out: the gate zeroes the noise there as `energy` does (synth drew every bin's
    // noise independently of the gate before its noise became the receiver's, and this
    // test took every bin)
    let tmp = tempfile::tempdir().unwrap();
    let mut t = fixture("tests/point_target.toml");
    set(&mut t, "pulses", 4i64);
    let mut poses = Vec::new();
    for i in 0..40 {
        let mut p = toml::Table::new();
        p.insert("x_m".into(), (0.01 * i as f64).into());
        p.insert("y_m".into(), 0.0.into());
        p.insert("heading_deg".into(), 0.0.into());
        poses.push(toml::Value::Table(p));
    }
    t.insert("poses".into(), toml::Value::Array(poses));
    let path = write_campaign(tmp.path(), &t);
    let c = Campaign::load(&path).unwrap();
    let empty = ChannelModel {
        config: ModelConfig::table1_defaults(),
        clusters: vec![],
    };
    let out = tmp.path().join("noise.parquet");
    let mut floor_n0 = f64::NAN;
    for given in [None, Some(3.0)] {
        let mut params = SynthParams::default();
        if let Some(x) = given {
            params = params.n0(x * floor_n0);
        }
        synth_channel(&c, &empty, &out, &params.check().unwrap(), &|_, _| {}).unwrap();
        let em = EnergyMatrix::read(&out).unwrap();
        let mu = em.meta.noise_mean();
        let n0 = em.meta.n0;
        match given {
            None => floor_n0 = n0,
            Some(x) => assert!((n0 / floor_n0 / x - 1.0).abs() < 1e-12),
        }
        let np = em.meta.pulses as f64;
        let first = ((c.manifest.processing.gate_ns + 2.0) / em.meta.bin_width_ns).ceil() as usize;
        let xs: Vec<f64> = (0..em.positions)
            .flat_map(|p| {
                (0..em.directions()).flat_map(move |d| (first..em.bins).map(move |b| (p, d, b)))
            })
            .map(|(p, d, b)| em.profile(p, d)[b])
            .collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let want_var = n0 * n0 * em.meta.tw / np;
        eprintln!(
            "noise-only (N0 {}): mean {:.4}× N0·TW, variance {:.4}× N0²TW/Np over {n} bins",
            if given.is_some() {
                "given"
            } else {
                "of the floor"
            },
            mean / mu,
            var / want_var
        );
        assert!((mean / mu - 1.0).abs() < 0.01);
        assert!((var / want_var - 1.0).abs() < 0.03);
    }
}

#[test]
fn synth_cli_is_deterministic_and_writes_truth() {
    let tmp = tempfile::tempdir().unwrap();
    let root = common::root();
    let model = tmp.path().join("model.toml");
    ModelConfig::table1_defaults().save(&model).unwrap();
    let campaign = root.join("data/corridor/campaign.toml");
    let mut outs = Vec::new();
    for (i, threads) in ["1", "2"].iter().enumerate() {
        let out = tmp.path().join(format!("e{i}.parquet"));
        let st = pradar()
            .args(["synth", "--quiet", "--model"])
            .arg(&model)
            .arg("--campaign")
            .arg(&campaign)
            .arg("--out")
            .arg(&out)
            .args(["--elements", "100"])
            .env("RAYON_NUM_THREADS", threads)
            .status()
            .unwrap();
        assert!(st.success());
        outs.push(std::fs::read(&out).unwrap());
        let truth = tmp.path().join(format!("e{i}_truth"));
        assert!(truth.join("rays.parquet").is_file());
        assert!(truth.join("clusters.csv").is_file());
    }
    assert!(
        outs[0] == outs[1],
        "same seed, 1 vs 2 threads: different bytes"
    );
    // the table is an energy table of the campaign (extract accepts it with --elements 100)
    let em = EnergyMatrix::read(&tmp.path().join("e0.parquet")).unwrap();
    assert_eq!(em.meta.array, "10x10 one_bit mechanical q=1");
    assert!(em
        .meta
        .all
        .iter()
        .any(|(k, v)| k == "source" && v == "synth"));
    // another seed gives another channel
    let out = tmp.path().join("e_seed.parquet");
    let st = pradar()
        .args(["synth", "--quiet", "--seed", "7", "--model"])
        .arg(&model)
        .arg("--campaign")
        .arg(&campaign)
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    assert!(std::fs::read(&out).unwrap() != outs[0]);
}

#[test]
fn synth_rejects_bad_models_with_the_field_named() {
    let tmp = tempfile::tempdir().unwrap();
    let root = common::root();
    let campaign = root.join("data/corridor/campaign.toml");
    let good = toml::to_string(&ModelConfig::table1_defaults()).unwrap();
    let cases = [
        (
            good.replace("value = 0.43", "value = -0.43"),
            "intra_cluster_rate.value",
        ),
        (
            good.replace("unit = \"deg\"", "unit = \"rad\""),
            "intra_cluster_aoa.unit",
        ),
        (
            good.replace("[perimeter_spacing]", "[perimeter_spacin]"),
            "perimeter_spacing",
        ),
        (good[..good.len() / 2].to_string(), "model"),
        ("value = nan".to_string(), "model"),
    ];
    for (i, (text, field)) in cases.iter().enumerate() {
        let model = tmp.path().join(format!("bad{i}.toml"));
        std::fs::write(&model, text).unwrap();
        let out = tmp.path().join(format!("bad{i}.parquet"));
        let o = pradar()
            .args(["synth", "--quiet", "--model"])
            .arg(&model)
            .arg("--campaign")
            .arg(&campaign)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "case {i}: {err}");
        assert!(
            err.starts_with("error:") && err.lines().count() == 1,
            "case {i}: {err}"
        );
        assert!(err.contains(&format!("bad{i}.toml")), "case {i}: {err}");
        if *field != "model" {
            assert!(err.contains(field), "case {i}: {err} lacks {field}");
        }
        assert!(!out.exists(), "case {i}: output written");
        assert!(!err.contains("panicked"));
    }
}

#[test]
fn synth_draw_follows_the_model_geometry() {
    // many clusters along a long perimeter: spacing and offset means follow the model
    let root = common::root();
    let layout =
        pradar::campaign::layout::Layout::load(&root.join("data/corridor/layout.geojson")).unwrap();
    let mut m = ModelConfig::table1_defaults();
    m.perimeter_spacing.value = 0.5;
    m.perimeter_offset.value = 0.2;
    let mut spacing = Vec::new();
    let mut offsets = Vec::new();
    let mut rays = 0usize;
    let mut gaps = Vec::new();
    let mut aoa = Vec::new();
    for seed in 0..20 {
        let ch = ChannelModel::draw(&layout, &m, seed).unwrap();
        let mut arcs: Vec<f64> = ch.clusters.iter().map(|c| c.arc_m).collect();
        arcs.sort_by(f64::total_cmp);
        spacing.extend(arcs.windows(2).map(|w| w[1] - w[0]));
        offsets.extend(ch.clusters.iter().map(|c| c.offset_m));
        for c in &ch.clusters {
            rays += c.rays.len();
            gaps.extend(c.rays.windows(2).map(|w| w[1].excess_ns - w[0].excess_ns));
            aoa.extend(c.rays[1..].iter().map(|r| r.aoa_rad.to_degrees()));
        }
        let n = ch.clusters.len();
        assert!(n > 30, "seed {seed}: {n} clusters");
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let std_aoa = (aoa.iter().map(|a| a * a).sum::<f64>() / aoa.len() as f64).sqrt();
    let clusters = offsets.len() as f64;
    eprintln!(
        "spacing mean {:.3} m (model 0.5, clusters in walls dropped), offset mean {:.3} m (model 0.2, capped 1.5 m), rays/cluster {:.2} (6), gap {:.3} ns (1/0.43 = 2.326), AoA std {std_aoa:.2}° (16.9)",
        mean(&spacing),
        mean(&offsets),
        rays as f64 / clusters,
        mean(&gaps)
    );
    assert!((mean(&offsets) - 0.2).abs() < 0.02);
    assert!((rays as f64 / clusters - 6.0).abs() < 0.3);
    assert!((mean(&gaps) - 1.0 / 0.43).abs() < 0.1);
    assert!((std_aoa - 16.9).abs() < 1.0);
    // some centres fall in obstacles and are dropped: spacing ≥ the model's, within 15 %
    assert!(mean(&spacing) >= 0.49 && mean(&spacing) < 0.5 * 1.15);
}

#[test]
fn synth_library_seed_changes_the_draw() {
    let root = common::root();
    let c = Campaign::load(&root.join("data/corridor/campaign.toml")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let m = ModelConfig::table1_defaults();
    let a = synth(
        &c,
        &m,
        &tmp.path().join("a.parquet"),
        &SynthParams::default().seed(3).check().unwrap(),
        &|_, _| {},
    )
    .unwrap();
    assert!(a.clusters > 5 && a.rays_per_position > 5.0);
    assert_eq!(
        a.profiles,
        c.manifest.positions() * c.manifest.directions.count()
    );
}

/// FNV-1a over the bits of every energy value and every truth-ray column of a synth run.
fn synth_digest(em: &EnergyMatrix, truth_rays: &std::path::Path) -> (u64, usize) {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: f64| {
        for b in x.to_bits().to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for p in 0..em.positions {
        for d in 0..em.directions() {
            em.profile(p, d).iter().for_each(|&e| eat(e));
        }
    }
    let df = pradar::table::read_parquet(truth_rays, None).unwrap();
    for name in ["delay_ns", "angle_global_deg", "power_db", "x_m", "y_m"] {
        let col = df.column(name).unwrap().f64().unwrap().clone();
        col.into_no_null_iter().for_each(&mut eat);
    }
    (h, df.height())
}

#[test]
fn synth_without_diffuse_is_unchanged() {
    // a model without [diffuse] gives the values it gave before the diffuse walls existed
    // (digest recorded from the code before issue 16: corridor, N = 100, seed 3), and a
    // schema-1 file keeps its cluster law (every cluster at the first cluster's range).
    // Re-recorded with issue 54 item 1 (synth through the measurement): the receiver's
    // noise (white per frequency point through the window and IFFT, zeroed in the gate)
    // replaced the per-bin χ² draws and far rays fold into the span, so every energy
    // moved (was 0xd4f1_a1e3_97ff_83e2); the draw and its 1225 truth rays did not (the
    // truth tables of the corridor's fitted model compared byte for byte before/after)
    let root = common::root();
    let mut c = Campaign::load(&root.join("data/corridor/campaign.toml")).unwrap();
    c.set_elements(100).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("a.parquet");
    let m = ModelConfig {
        schema_version: 1,
        ..ModelConfig::table1_defaults()
    };
    assert!(m.diffuse.is_none());
    synth(
        &c,
        &m,
        &out,
        &SynthParams::default().seed(3).check().unwrap(),
        &|_, _| {},
    )
    .unwrap();
    let em = EnergyMatrix::read(&out).unwrap();
    let (h, rows) = synth_digest(&em, &tmp.path().join("a_truth/rays.parquet"));
    eprintln!("digest {h:#018x}, {rows} truth rays");
    assert_eq!((h, rows), (0xc275_de73_4a93_ce97, 1225));
}

/// A model with `[diffuse]` (σ' m²/m, Lambert exponent n) and almost no clusters.
fn diffuse_model(per_m: f64, n: f64) -> ModelConfig {
    use pradar::model::file::{DiffuseModel, Quantity};
    let mut m = ModelConfig::table1_defaults();
    m.perimeter_spacing.value = 200.0; // at most one cluster along the room
    m.cluster_rrcs.value = 1e-12; // and far below the walls
    m.diffuse = Some(DiffuseModel {
        wall_rcs_per_m: Quantity::new(per_m, "m2/m", "constant"),
        lambert_exponent: Quantity::new(n, "1", "constant"),
        power_share: Quantity::new(0.5, "1", "constant"),
        decay: Quantity::new(10.0, "ns", "exponential"),
    });
    m
}

#[test]
fn synth_diffuse_walls_follow_the_radar_equation() {
    // the 20 m × 20 m room, poses 6 m from the east wall looking at it, 400 elements: the
    // energy along the wall's (delay, angle) curve, summed over a delay window, against
    // Σ_walls ∫ σ'·cos^n ψ·ḡ²(θ − θ_d) / ((4π)³ d⁴) · K(τ) ds (K a unit echo's energy in
    // the window), in a near-normal and an oblique group of directions
    let tmp = tempfile::tempdir().unwrap();
    let ys = [-3.0, -1.5, 0.0, 1.5, 3.0];
    let c = east_wall_campaign(tmp.path(), &ys);
    let m = &c.manifest;
    let (per_m, n_exp) = (0.02, 2.0);
    let (pred, lo, hi) = diffuse_wall_prediction(&c, &ys, per_m, n_exp);
    let angles = m.directions.angles_deg();
    let model = diffuse_model(per_m, n_exp);
    // (sum measured, sum predicted, Σ dB ratio, count) per group: |θ| ≤ 15°, 30° ≤ |θ| ≤ 45°
    let mut groups = [(0.0, 0.0, 0.0, 0usize); 2];
    let mut diffuse_rows = 0usize;
    for seed in [1u64, 2] {
        let out = tmp.path().join(format!("walls{seed}.parquet"));
        let truth = tmp.path().join(format!("walls{seed}_truth"));
        let r = synth(
            &c,
            &model,
            &out,
            &SynthParams::default().seed(seed).check().unwrap(),
            &|_, _| {},
        )
        .unwrap();
        assert!(r.clusters <= 1, "{} clusters", r.clusters);
        assert!(r.diffuse_points > 3000, "{} points", r.diffuse_points);
        let em = EnergyMatrix::read(&out).unwrap();
        let mu = em.meta.noise_mean();
        for p in 0..ys.len() {
            for (di, a) in angles.iter().enumerate() {
                let g = if a.abs() <= 15.0 {
                    0
                } else if (30.0..=45.0).contains(&a.abs()) {
                    1
                } else {
                    continue;
                };
                let meas: f64 = em.profile(p, di)[lo..=hi].iter().map(|e| e - mu).sum();
                let want = pred[p * angles.len() + di];
                assert!(
                    want > 10.0 * mu * (hi - lo) as f64,
                    "weak prediction {want:e} vs noise {:e}",
                    mu * (hi - lo) as f64
                );
                groups[g].0 += meas;
                groups[g].1 += want;
                groups[g].2 += 10.0 * (meas / want).log10();
                groups[g].3 += 1;
            }
        }
        diffuse_rows += diffuse_truth_rows(&truth, r.diffuse_per_position, ys.len());
    }
    assert!(diffuse_rows > 1000);
    for (name, (meas, want, db, n)) in ["|θ| ≤ 15°", "30° ≤ |θ| ≤ 45°"].iter().zip(groups)
    {
        let pooled = 10.0 * (meas / want).log10();
        let mean_db = db / n as f64;
        eprintln!(
            "diffuse walls, {name}: pooled {pooled:+.2} dB, mean {mean_db:+.2} dB over {n} (pose, direction) curves"
        );
        assert!(
            pooled.abs() < 1.5 && mean_db.abs() < 1.5,
            "{name}: {pooled:+.2} dB"
        );
    }
}

/// Takes a folder and the poses' y (m); writes the point-target room's campaign with
/// those poses at x = 4 m looking east, −50° to 50°, the delay span to 60 ns, and gives
/// it.
fn east_wall_campaign(dir: &std::path::Path, ys: &[f64]) -> Campaign {
    let mut t = fixture("tests/point_target.toml");
    set(&mut t, "processing.max_delay_ns", 60.0);
    set(&mut t, "processing.noise_from_ns", 70.0);
    set(&mut t, "directions.start_deg", -50.0);
    set(&mut t, "directions.stop_deg", 50.0);
    let poses: Vec<toml::Value> = ys
        .iter()
        .map(|y| {
            let mut p = toml::Table::new();
            p.insert("x_m".into(), 4.0.into());
            p.insert("y_m".into(), (*y).into());
            p.insert("heading_deg".into(), 0.0.into());
            toml::Value::Table(p)
        })
        .collect();
    t.insert("poses".into(), toml::Value::Array(poses));
    let path = write_campaign(dir, &t);
    Campaign::load(&path).unwrap()
}

/// Takes the campaign, the poses' y, and the diffuse walls' σ′ (m²/m) and Lambert
/// exponent; gives the predicted energy in the delay window per (pose, direction), every
/// wall integrated at 2 mm, and the window's bins (30..58 ns).
fn diffuse_wall_prediction(
    c: &Campaign,
    ys: &[f64],
    per_m: f64,
    n_exp: f64,
) -> (Vec<f64>, usize, usize) {
    use pradar::campaign::layout::Layout;
    use pradar::energy::EnergyProcessor;
    use pradar::model::BandPattern;
    use pradar::pattern::ArrayPattern;
    use std::f64::consts::PI;
    let m = &c.manifest;
    let layout = Layout::load(&c.layout_path()).unwrap();
    let proc = EnergyProcessor::new(m.band, m.processing).unwrap();
    let tb = proc.bin_width_ns() * 1e-9;
    let pattern = ArrayPattern::new(m.array, m.band.center_hz()).unwrap();
    let bp = BandPattern::new(&pattern.tables(&[0.0], &m.band, 33)[0], m.processing.window);
    // delay window 30..58 ns; K(τ) = Σ_{b in window} e_b(τ), exact near its edges
    let (lo, hi) = ((30e-9 / tb).round() as usize, (58e-9 / tb).round() as usize);
    let k_of = |tau: f64| -> f64 {
        let b0 = (tau / tb).round() as i64;
        (b0 - 24..=b0 + 24)
            .filter(|b| *b >= lo as i64 && *b <= hi as i64)
            .map(|b| proc.point_echo_energy_at(1.0, tau, b as usize))
            .sum()
    };
    let k_mid = k_of((lo + hi) as f64 / 2.0 * tb);
    let grid = tb / 16.0;
    let mut k_cache = std::collections::HashMap::new();
    let mut k_at = |tau: f64| -> f64 {
        let near = tau < (lo as f64 + 25.0) * tb || tau > (hi as f64 - 25.0) * tb;
        if !near {
            return k_mid;
        }
        let i = (tau / grid).round() as i64;
        *k_cache.entry(i).or_insert_with(|| k_of(i as f64 * grid))
    };
    let angles = m.directions.angles_deg();
    // prediction per (pose, direction), the wall integrated at 2 mm
    let ds = 2e-3;
    let mut pred = vec![0.0; ys.len() * angles.len()];
    for w in &layout.walls {
        let nrm = w.normal();
        let steps = (w.length() / ds).round() as usize;
        for i in 0..steps {
            let s = w.line.start + w.line.delta() * ((i as f64 + 0.5) / steps as f64);
            for (p, y) in ys.iter().enumerate() {
                let v = Coord { x: 4.0, y: *y } - s;
                let d = v.x.hypot(v.y);
                let cos = (v.x * nrm.x + v.y * nrm.y) / d;
                let tau = 2.0 * d / pradar::units::C0;
                if cos <= 0.0 || tau < (lo as f64 - 24.0) * tb || tau > (hi as f64 + 24.0) * tb {
                    continue;
                }
                let th = (-v.y).atan2(-v.x);
                let e = per_m * ds * cos.powf(n_exp) / ((4.0 * PI).powi(3) * d.powi(4));
                let k = k_at(tau);
                for (di, a) in angles.iter().enumerate() {
                    let rel = pradar::units::wrap_rad(th - a.to_radians());
                    if let Some((g, _)) = bp.at(rel) {
                        pred[p * angles.len() + di] += g * g * e * k;
                    }
                }
            }
        }
    }
    (pred, lo, hi)
}

/// Takes a synth truth folder, the diffuse points seen per position and the positions;
/// checks that the truth carries the walls' points as kind diffuse, cluster −1, on the
/// walls, as many as seen, and gives their count.
fn diffuse_truth_rows(truth: &std::path::Path, per_position: f64, positions: usize) -> usize {
    // the truth carries the walls' points as kind diffuse, cluster −1, on the walls
    let df = pradar::table::read_parquet(&truth.join("rays.parquet"), None).unwrap();
    let kind = df.column("kind").unwrap().str().unwrap().clone();
    let cl = df.column("cluster_id").unwrap().i64().unwrap().clone();
    let x = df.column("x_m").unwrap().f64().unwrap().clone();
    let yy = df.column("y_m").unwrap().f64().unwrap().clone();
    let mut rows = 0usize;
    for i in 0..df.height() {
        if kind.get(i) == Some("diffuse") {
            rows += 1;
            assert_eq!(cl.get(i), Some(-1));
            let (px, py) = (x.get(i).unwrap(), yy.get(i).unwrap());
            assert!(
                (px.abs() - 10.0).abs() < 1e-9 || (py.abs() - 10.0).abs() < 1e-9,
                "({px}, {py}) is not on a wall"
            );
        }
    }
    assert!(
        (rows as f64 - per_position * positions as f64).abs() < 0.5,
        "{rows} truth rows vs {} seen",
        per_position * positions as f64
    );
    rows
}

#[test]
fn synth_cli_refuses_a_not_estimable_quantity_unless_set() {
    use pradar::model::file::Quantity;
    let tmp = tempfile::tempdir().unwrap();
    let root = common::root();
    let campaign = root.join("data/corridor/campaign.toml");
    let mut m = diffuse_model(0.02, 1.0);
    m.diffuse.as_mut().unwrap().decay = Quantity::not_estimable("ns", "exponential", "no trend");
    let model = tmp.path().join("model.toml");
    m.save(&model).unwrap();
    let out = tmp.path().join("e.parquet");
    let run = |extra: &[&str]| {
        pradar()
            .args(["synth", "--quiet", "--elements", "16", "--model"])
            .arg(&model)
            .arg("--campaign")
            .arg(&campaign)
            .arg("--out")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(1));
    common::assert_one_line_error(&o, "diffuse.decay");
    assert!(String::from_utf8_lossy(&o.stderr).contains("--set diffuse.decay=VALUE"));
    assert!(!out.exists());
    // a value for another quantity does not help; a bad name is named
    let o = run(&["--set", "ray_decay=3"]);
    common::assert_one_line_error(&o, "diffuse.decay");
    let o = run(&["--set", "diffuse.decai=3"]);
    assert_eq!(o.status.code(), Some(1));
    common::assert_one_line_error(&o, "diffuse.decai");
    let o = run(&["--set", "diffuse.decay"]);
    assert_eq!(o.status.code(), Some(1));
    common::assert_one_line_error(&o, "--set");
    // with the value it runs, and draws the walls
    let o = run(&["--set", "diffuse.decay=10"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = pradar::table::read_parquet(&tmp.path().join("e_truth/rays.parquet"), None).unwrap();
    let kind = df.column("kind").unwrap().str().unwrap().clone();
    assert!((0..kind.len()).any(|i| kind.get(i) == Some("diffuse")));
    // the library refuses it too
    let c = Campaign::load(&campaign).unwrap();
    let e = synth(&c, &m, &out, &SynthValid::default(), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("diffuse.decay"), "{e}");
}

/// A point target beyond the unambiguous range c/(2Δf) (10 m at 401 points over 6 GHz, 20 m
/// at 801): the sweep folds its echo to τ mod T, T = 1/Δf, at the level its path loss gives.
/// Through `simulate` → `energy` and through `synth` of the same scatterer (a one-ray
/// cluster), at 1.3× and 2.4× that range, an odd and an even number of points: the same
/// peak bin (±1) at the same level (±0.5 dB). Synth before the fold dropped both echoes.
#[test]
fn synth_folds_a_target_beyond_the_unambiguous_range_as_simulate_does() {
    use pradar::campaign::manifest::C0;
    let tmp = tempfile::tempdir().unwrap();
    let mut worst: f64 = 0.0;
    for (points, elements, one_bit) in [(401usize, 100i64, false), (800, 400, true)] {
        let mut t = fixture("tests/point_target.toml");
        // a 120 m × 12 m hall: the pose at its west end sees both targets (synth needs an
        // unoccluded line of sight; `simulate` with walls = false draws no walls)
        set(&mut t, "layout", "long_hall.geojson");
        set(&mut t, "band.points", points as i64);
        set(&mut t, "array.elements", elements);
        set(&mut t, "array.one_bit", one_bit);
        set(&mut t, "noise.floor_dbm", -160.0);
        let df = 6.0e9 / (points - 1) as f64;
        let (r_u, period) = (C0 / (2.0 * df), 1.0 / df);
        // the echoes fold to 0.3 T and 0.4 T
        set(&mut t, "processing.max_delay_ns", 0.6e9 * period);
        set(&mut t, "processing.noise_from_ns", 0.65e9 * period);
        let (x0, y0) = (-55.0, 0.0);
        let pose = t["poses"].as_array_mut().unwrap()[0]
            .as_table_mut()
            .unwrap();
        pose.insert("x_m".into(), x0.into());
        pose.insert("y_m".into(), y0.into());
        // (range factor, bearing deg); RRCS 10 m (σ = 100 m²)
        let targets = [(1.3, 10.0f64), (2.4, -5.0f64)];
        let rrcs = 10.0;
        let mut arr = toml::value::Array::new();
        let mut at = Vec::new();
        for (f, deg) in targets {
            let r = f * r_u;
            let (x, y) = (
                x0 + r * deg.to_radians().cos(),
                y0 + r * deg.to_radians().sin(),
            );
            let mut tt = toml::Table::new();
            tt.insert("x_m".into(), x.into());
            tt.insert("y_m".into(), y.into());
            tt.insert("rrcs_m".into(), rrcs.into());
            arr.push(tt.into());
            at.push((r, deg, Coord { x, y }));
        }
        t["scene"]
            .as_table_mut()
            .unwrap()
            .insert("targets".into(), arr.into());
        let dir = tmp.path().join(format!("k{points}"));
        let (_, sim) = common::chain(&dir, &t, SweepFormat::Parquet);
        let c = Campaign::load(&dir.join("in/campaign.toml")).unwrap();
        // two one-ray clusters, each at the radar equation of its own range (no excess
        // decay Γ: the second is not weaker for arriving later)
        let mut model = single(at[0].2, rrcs * rrcs);
        model
            .clusters
            .push(single(at[1].2, rrcs * rrcs).clusters.remove(0));
        model.config.cluster_decay.value = f64::INFINITY;
        let out = dir.join("synth.parquet");
        synth_channel(
            &c,
            &model,
            &out,
            &SynthParams::default().check().unwrap(),
            &|_, _| {},
        )
        .unwrap();
        let syn = EnergyMatrix::read(&out).unwrap();
        assert_eq!(syn.bins, sim.bins);
        for (r, deg, _) in at {
            let d = (0..sim.directions())
                .min_by(|&a, &b| {
                    (sim.angles_rel_deg[a] - deg)
                        .abs()
                        .total_cmp(&(sim.angles_rel_deg[b] - deg).abs())
                })
                .unwrap();
            let tau = 2.0 * r / C0;
            let folded = tau - (tau / period).floor() * period;
            let want = (folded * 1e9 / sim.meta.bin_width_ns).round() as usize;
            let peak = |em: &EnergyMatrix| -> (usize, f64) {
                let prof = em.profile(0, d);
                (want - 4..=want + 4)
                    .map(|b| (b, prof[b]))
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .unwrap()
            };
            let ((bs, es), (by, ey)) = (peak(&sim), peak(&syn));
            let db = 10.0 * (ey / es).log10();
            let snr = 10.0 * (es / sim.meta.noise_mean()).log10();
            eprintln!(
                "K = {points}, {r:.1} m ({:.1}× c/2Δf) at {deg}°: folded to {:.2} ns (bin {want}); simulate bin {bs}, synth bin {by}; synth − simulate {db:+.2} dB (SNR {snr:.0} dB)",
                r / r_u,
                folded * 1e9
            );
            assert!(snr > 30.0, "the echo should stand out: SNR {snr:.1} dB");
            assert!(bs.abs_diff(want) <= 1, "simulate's peak bin {bs} vs {want}");
            assert!(by.abs_diff(bs) <= 1, "synth bin {by} vs simulate's {bs}");
            worst = worst.max(db.abs());
        }
    }
    eprintln!("worst |synth − simulate| at the folded peaks: {worst:.2} dB");
    assert!(worst <= 0.5, "{worst:.2} dB");
}

/// Per-profile lag-k correlation of the energies over bins `first..` (pooled mean and
/// variance over every profile of `em`).
fn lag_correlation(em: &EnergyMatrix, first: usize, lag: usize) -> f64 {
    let profiles: Vec<&[f64]> = (0..em.positions)
        .flat_map(|p| (0..em.directions()).map(move |d| (p, d)))
        .map(|(p, d)| &em.profile(p, d)[first..])
        .collect();
    let n: usize = profiles.iter().map(|p| p.len()).sum();
    let mu = profiles.iter().flat_map(|p| p.iter()).sum::<f64>() / n as f64;
    let var = profiles
        .iter()
        .flat_map(|p| p.iter())
        .map(|e| (e - mu).powi(2))
        .sum::<f64>()
        / n as f64;
    let (mut s, mut k) = (0.0, 0usize);
    for p in &profiles {
        for w in p.windows(lag + 1) {
            s += (w[0] - mu) * (w[lag] - mu);
            k += 1;
        }
    }
    s / k as f64 / var
}

/// The energies of bins `first..` of positions `ps` of `em`, ascending.
fn noise_bins(em: &EnergyMatrix, first: usize, ps: std::ops::Range<usize>) -> Vec<f64> {
    let mut v: Vec<f64> = ps
        .flat_map(|p| (0..em.directions()).map(move |d| (p, d)))
        .flat_map(|(p, d)| em.profile(p, d)[first..].to_vec())
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

/// Noise only: `synth` of an empty channel against the physics twin (the same band and
/// processing simulated with walls = false and no target, through `energy`). The noise after
/// the window and the zero-padded IFFT is correlated over neighbouring bins; synth's must
/// be the measurement's: lag-1…5 correlations of the profiles within ±0.05 of the twin's,
/// and the KS distance of the signal-free bins (synth ↔ twin) within 1.5× the one between
/// two twins of different seeds (per block of 4 positions, averaged over the 6 blocks, and
/// over all bins at once, printed). Synth's independent per-bin draws gave lag
/// correlations of 0.
#[test]
fn synth_noise_is_coloured_as_the_measurement_s() {
    use pradar::check::stats::ks_two_sample;
    let tmp = tempfile::tempdir().unwrap();
    let mut t = fixture("tests/point_target.toml");
    t["scene"].as_table_mut().unwrap().remove("targets");
    set(&mut t, "band.points", 801i64);
    set(&mut t, "array.elements", 16i64);
    set(&mut t, "processing.max_delay_ns", 80.0);
    set(&mut t, "processing.noise_from_ns", 100.0);
    let np = 24;
    let mut poses = toml::value::Array::new();
    for i in 0..np {
        let mut p = toml::Table::new();
        p.insert("x_m".into(), (0.2 * i as f64 - 2.0).into());
        p.insert("y_m".into(), 0.0.into());
        p.insert("heading_deg".into(), (7.0 * i as f64).into());
        poses.push(p.into());
    }
    t.insert("poses".into(), poses.into());
    let twin = |seed: i64| {
        let mut t = t.clone();
        set(&mut t, "seed", seed);
        common::chain(
            &tmp.path().join(format!("twin{seed}")),
            &t,
            SweepFormat::Parquet,
        )
        .1
    };
    let (a, b) = (twin(1), twin(2));
    let c = Campaign::load(&tmp.path().join("twin1/in/campaign.toml")).unwrap();
    let empty = ChannelModel {
        config: ModelConfig::table1_defaults(),
        clusters: vec![],
    };
    let out = tmp.path().join("synth.parquet");
    synth_channel(
        &c,
        &empty,
        &out,
        &SynthParams::default().seed(3).check().unwrap(),
        &|_, _| {},
    )
    .unwrap();
    let s = EnergyMatrix::read(&out).unwrap();
    assert_eq!((s.positions, s.bins), (a.positions, a.bins));
    // the signal-free bins: from the gate + 2 ns (the coupling's kernel tail) on
    let first = ((3.0 + 2.0) / a.meta.bin_width_ns).ceil() as usize;
    let mut line = String::from("lag correlation (twin 1 / twin 2 / synth):");
    for lag in 1..=5 {
        let (ra, rb, rs) = (
            lag_correlation(&a, first, lag),
            lag_correlation(&b, first, lag),
            lag_correlation(&s, first, lag),
        );
        line += &format!("  {lag}: {ra:.3} / {rb:.3} / {rs:.3}");
        assert!(
            (rs - ra).abs() <= 0.05,
            "lag {lag}: synth {rs:.3}, twin {ra:.3}"
        );
    }
    eprintln!("{line}");
    let whole = 0..np;
    let (xa, xb, xs) = (
        noise_bins(&a, first, whole.clone()),
        noise_bins(&b, first, whole.clone()),
        noise_bins(&s, first, whole),
    );
    let (ks_tt, ks_st) = (ks_two_sample(&xb, &xa), ks_two_sample(&xs, &xa));
    let blocks = np / 4;
    let (mut bt, mut bs) = (0.0, 0.0);
    for k in 0..blocks {
        let r = 4 * k..4 * (k + 1);
        let xa = noise_bins(&a, first, r.clone());
        bt += ks_two_sample(&noise_bins(&b, first, r.clone()), &xa) / blocks as f64;
        bs += ks_two_sample(&noise_bins(&s, first, r), &xa) / blocks as f64;
    }
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    eprintln!(
        "KS synth↔twin {ks_st:.4}, twin↔twin {ks_tt:.4} (ratio {:.2}); per block of 4 positions: {bs:.4} vs {bt:.4} (ratio {:.2}); mean noise bin synth / twin {:.4}, N0·TW (synth's metadata) / twin's mean {:.4}",
        ks_st / ks_tt,
        bs / bt,
        mean(&xs) / mean(&xa),
        s.meta.noise_mean() / mean(&xa)
    );
    assert!(
        bs <= 1.5 * bt,
        "KS per block: synth↔twin {bs:.4} vs twin↔twin {bt:.4}"
    );
}
