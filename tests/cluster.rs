//! K-means clustering of MPCs: K recovery on clusters drawn with the Table 1 rates,
//! determinism across thread counts, edge cases.

use pradar::cluster::{adjusted_rand_index, cluster, ClusterParams, ClusterValid};
use pradar::mpc::Mpc;
use pradar::params::ParamGuard;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp, Poisson};

/// Checked clustering parameters.
fn ok(p: ClusterParams) -> ClusterValid {
    p.check().unwrap()
}

fn mpc(p: usize, delay_ns: f64, angle: f64, power_db: f64) -> Mpc {
    let r = delay_ns * 0.299_792_458 / 2.0;
    Mpc {
        position: p,
        delay_ns,
        angle_rel_deg: angle,
        angle_global_deg: angle,
        power_db,
        snr_db: power_db + 100.0,
        x_m: r * angle.to_radians().cos(),
        y_m: r * angle.to_radians().sin(),
        direction: 0,
        bin: 0,
        component: pradar::mpc::Component::Discrete,
        wall: None,
    }
}

/// Clusters drawn with the Table 1 rates: first arrivals at Λ = 0.21/ns (so clusters overlap
/// in delay), rays at λ = 0.43/ns, Laplacian AoA with std 16.9° around cluster angles drawn
/// over the half-plane at least 40° apart (clusters must be resolvable for K to be
/// identifiable at all); returns MPCs, true labels and true K per position.
fn table1_scene(positions: usize, seed: u64) -> (Vec<Mpc>, Vec<usize>, Vec<usize>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (big, small) = (Exp::new(0.21).unwrap(), Exp::new(0.43).unwrap());
    let b = 16.9 / 2f64.sqrt();
    let mut mpcs = Vec::new();
    let mut truth = Vec::new();
    let mut k_true = Vec::new();
    let mut next = 0;
    for p in 0..positions {
        let k = rng.gen_range(1..=4);
        k_true.push(k);
        // resolvable clusters: centre angles at least 40° (≈ 2.4 AoA std) apart
        let slack = 150.0 - 40.0 * (k - 1) as f64;
        let mut u: Vec<f64> = (0..k).map(|_| rng.gen_range(0.0..slack)).collect();
        u.sort_by(f64::total_cmp);
        let centres: Vec<f64> = u
            .iter()
            .enumerate()
            .map(|(i, v)| -75.0 + v + 40.0 * i as f64)
            .collect();
        let mut t = 3.0;
        for &centre in &centres {
            t += big.sample(&mut rng);
            let rays = 1 + Poisson::new(5.0).unwrap().sample(&mut rng) as usize;
            let mut tau = t;
            for r in 0..rays {
                if r > 0 {
                    tau += small.sample(&mut rng);
                }
                let u: f64 = rng.gen::<f64>() - 0.5;
                let off = if r == 0 {
                    0.0
                } else {
                    -b * u.signum() * (1.0 - 2.0 * u.abs()).ln()
                };
                mpcs.push(mpc(
                    p,
                    tau,
                    (centre + off).clamp(-90.0, 90.0),
                    -60.0 - (tau - t) / 3.0 * 4.34,
                ));
                truth.push(next);
            }
            next += 1;
        }
    }
    (mpcs, truth, k_true)
}

#[test]
fn k_recovered_on_table1_clusters() {
    use pradar::cluster::Criterion;
    let (mpcs, truth, k_true) = table1_scene(60, 7);
    let mut fracs = Vec::new();
    let mut k1_exact = Vec::new();
    eprintln!("criterion        | K within ±1 | exact K | ARI");
    for crit in [
        Criterion::Silhouette,
        Criterion::CalinskiHarabasz,
        Criterion::Gap,
        Criterion::ChannelBic,
        Criterion::GaussBic,
        Criterion::CrossValidated,
        Criterion::CrossValidatedShared,
    ] {
        let c = cluster(
            &mpcs,
            &[0.0; 60],
            &ok(ClusterParams::default().criterion(crit)),
        )
        .unwrap();
        let within = k_true
            .iter()
            .zip(&c.positions)
            .filter(|(t, pc)| (pc.k as i64 - **t as i64).abs() <= 1)
            .count();
        let exact = k_true
            .iter()
            .zip(&c.positions)
            .filter(|(t, pc)| pc.k == **t)
            .count();
        let frac = within as f64 / k_true.len() as f64;
        // every MPC here is discrete, so every one has an id
        let ids: Vec<usize> = c.cluster_id.iter().map(|i| i.unwrap()).collect();
        let ari = adjusted_rand_index(&truth, &ids);
        eprintln!(
            "{:16} | {within}/{} ({frac:.2}) | {exact}/{} | {ari:.3}",
            format!("{crit:?}"),
            k_true.len(),
            k_true.len()
        );
        fracs.push(frac);
        let mut conf = [[0usize; 9]; 5];
        for (t, pc) in k_true.iter().zip(&c.positions) {
            conf[*t][pc.k.min(8)] += 1;
        }
        eprintln!("  true K -> chosen K counts (K = 0..8): {:?}", &conf[1..]);
        k1_exact.push(conf[1][1] as f64 / conf[1].iter().sum::<usize>() as f64);
    }
    // The target, with the default criterion (cv): K within ±1 at >= 80 % of the
    // positions; the silhouette (0.67 since the refits are warm-started, 0.72 before) is
    // kept as a regression guard.
    assert!(fracs[0] >= 0.65, "silhouette: K within ±1 at {}", fracs[0]);
    let within = |seed: u64| {
        let (mpcs, _, k_true) = table1_scene(60, seed);
        let c = cluster(&mpcs, &[0.0; 60], &ok(ClusterParams::default())).unwrap();
        k_true
            .iter()
            .zip(&c.positions)
            .filter(|(t, pc)| (pc.k as i64 - **t as i64).abs() <= 1)
            .count() as f64
            / k_true.len() as f64
    };
    assert_eq!(within(7), fracs[5], "the default is the cv criterion");
    // The likelihood criteria decide K = 1 themselves: the cross-validated likelihood
    // finds the single clusters (the silhouette rule never does).
    assert!(k1_exact[5] >= 0.8, "cv: K = 1 found at {}", k1_exact[5]);
    assert!(fracs[5] >= 0.8, "cv: K within ±1 at {}", fracs[5]);
    // and not by luck of one draw: two more scenes
    for seed in [1, 2] {
        let w = within(seed);
        eprintln!("cv, scene seed {seed}: K within ±1 at {w:.2}");
        assert!(w >= 0.8, "cv, scene seed {seed}: K within ±1 at {w}");
    }
}

#[test]
fn same_labels_with_one_and_two_threads() {
    let (mpcs, _, _) = table1_scene(20, 3);
    let run = |t: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap();
        pool.install(|| cluster(&mpcs, &[0.0; 20], &ok(ClusterParams::default())).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.cluster_id, b.cluster_id);
    assert_eq!(a.summary, b.summary);
    // and another seed may differ but stays a valid labelling
    let c = cluster(&mpcs, &[0.0; 20], &ok(ClusterParams::default().seed(99))).unwrap();
    assert_eq!(c.cluster_id.len(), mpcs.len());
}

#[test]
fn edge_cases_never_panic() {
    // no MPCs at all
    let c = cluster(&[], &[0.0; 3], &ok(ClusterParams::default())).unwrap();
    assert!(c.summary.is_empty() && c.positions.iter().all(|p| p.k == 0));
    // position 0 empty, position 1 one MPC, position 2 three MPCs with K_max 10
    let m = vec![
        mpc(1, 10.0, 5.0, -50.0),
        mpc(2, 10.0, -40.0, -50.0),
        mpc(2, 11.0, -41.0, -52.0),
        mpc(2, 30.0, 50.0, -55.0),
    ];
    let c = cluster(&m, &[0.0; 3], &ok(ClusterParams::default().k_max(10))).unwrap();
    assert_eq!(c.positions[0].k, 0);
    assert_eq!(c.positions[1].k, 1);
    assert!(c.positions[2].k >= 1 && c.positions[2].k <= 2);
    assert_eq!(c.summary.iter().filter(|s| s.position == 1).count(), 1);
    // invalid parameters are an error, not a panic
    let e = ClusterParams::default().k_max(0).check().unwrap_err();
    assert!(e.to_string().contains("k_max"), "{e}");
}

/// `positions_at_k_max` names the positions where the cap bound: three separated blobs at
/// position 0 and one at position 1; K_max = 2 caps position 0 only, K_max = 8 none (the
/// criterion finds 3 and 1). Positions with too few MPCs for more than K_max clusters (two
/// MPCs; three MPCs at K_max = 2) are never capped.
#[test]
fn positions_at_k_max_names_where_the_cap_bound() {
    let mut mpcs = Vec::new();
    for (t0, a0) in [(10.0, -60.0), (40.0, 0.0), (70.0, 60.0)] {
        for i in 0..10 {
            let t = t0 + i as f64 * 0.7;
            let a = a0 + ((i * 7) % 10) as f64 * 1.5 - 7.0;
            mpcs.push(mpc(0, t, a, -60.0 - i as f64));
        }
    }
    for i in 0..10 {
        mpcs.push(mpc(
            1,
            20.0 + i as f64 * 0.7,
            ((i * 3) % 10) as f64 - 5.0,
            -60.0,
        ));
    }
    mpcs.push(mpc(2, 30.0, 0.0, -60.0));
    mpcs.push(mpc(2, 50.0, 40.0, -60.0));
    // a pair and a far MPC: K = 2 is all n − 1 allows, so K_max = 2 is not what bound
    for (t, a) in [(15.0, -70.0), (15.5, -69.0), (75.0, 70.0)] {
        mpcs.push(mpc(3, t, a, -60.0));
    }
    let headings = [0.0; 4];
    let capped = cluster(&mpcs, &headings, &ok(ClusterParams::default().k_max(2))).unwrap();
    assert_eq!(capped.positions[0].k, 2);
    assert_eq!(capped.positions_at_k_max(2), vec![0]);
    let sil = ClusterParams::default()
        .k_max(2)
        .criterion(pradar::cluster::Criterion::Silhouette);
    let by_silhouette = cluster(&mpcs, &headings, &ok(sil)).unwrap();
    assert_eq!(by_silhouette.positions[3].k_tried, 2);
    assert!(!by_silhouette.positions_at_k_max(2).contains(&3));
    let free = cluster(&mpcs, &headings, &ok(ClusterParams::default())).unwrap();
    assert_eq!(free.positions[0].k, 3);
    assert_eq!(free.positions[1].k, 1);
    assert!(free.positions_at_k_max(8).is_empty());
}

/// `pradar cluster --k-max 0`: one clear line naming the flag and its range, exit 1, no
/// panic.
#[test]
fn k_max_0_on_the_command_line_is_one_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let mpcs = tmp.path().join("mpcs.parquet");
    let m = vec![mpc(0, 10.0, 5.0, -50.0), mpc(0, 30.0, -40.0, -52.0)];
    pradar::mpc::write_mpcs(&mpcs, &m, vec![]).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_pradar"))
        .args(["cluster", "--k-max", "0", "--mpcs"])
        .arg(&mpcs)
        .arg("--out")
        .arg(tmp.path().join("clusters.parquet"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("--k-max") && stderr.contains("[1, 64]"),
        "{stderr}"
    );
    assert!(!tmp.path().join("clusters.parquet").exists());
}
