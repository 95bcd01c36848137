//! The simulated-minimum-distance refinement (`pradar::smm`) on synth data of a known model.

use crate::common;
use pradar::campaign::Campaign;
use pradar::check::CheckParams;
use pradar::energy::EnergyMatrix;
use pradar::model::file::ModelConfig;
use pradar::params::ParamGuard;
use pradar::smm::{refine, SmmParams};

/// On the corridor's table drawn from Table 1's defaults (clusters only), a start whose
/// cluster RRCS σ is 10× the generating value and whose intra-cluster rate λ is half of it:
/// the start fails the plug-in check against the table (39 draws; measured: its noise
/// floor −1.2 dB from the draws', the statistics at max-T p 0.200 — the nine statistics,
/// each table thresholded at its own noise, hardly see σ); the refinement lowers its distance D by at least a fifth, its model passes
/// the same check, it moves nothing it was not given (Λ and the schema copied), drops the
/// moved quantities' intervals, records itself in `[calibration]`, and gives the same
/// model on a second run on one thread (common random numbers: D is a deterministic
/// function of θ, whatever the thread count).
///
/// Not identifiable here, printed and not asserted: σ, the rays per cluster and λ trade
/// off (a cluster's energy is about its rays times σ). Measured with σ 3× (40 iterations,
/// R = 4): D 1.171 → 0.715 with σ 0.030 → 0.037 (generating 0.010), rays 6 → 3.95, λ
/// 0.215 → 0.356 (0.43); D at the generating model itself is 0.816, above the refined
/// model's, and 168 iterations (converged) end at D 0.691 with σ 0.036: the statistics on
/// 12 poses do not tell these models apart, so the refinement is judged by the check, not
/// by σ. With σ 10×: D 1.289 → 0.767 (108 evaluations).
#[test]
fn refinement_makes_a_wrong_start_pass_its_check() {
    let tmp = tempfile::tempdir().unwrap();
    let cpath = common::write_campaign(&tmp.path().join("in"), &common::corridor());
    let truth = ModelConfig::table1_defaults();
    let e = common::synth(&tmp.path().join("s"), &cpath, &truth, 11);
    let c = Campaign::load(&cpath).unwrap();
    let em = EnergyMatrix::read(&e).unwrap();
    let mut start = truth.clone();
    start.cluster_rrcs.value *= 10.0;
    start.intra_cluster_rate.value *= 0.5;
    start.cluster_rrcs.interval = Some([0.02, 0.05]);
    let params = SmmParams {
        draws: 4,
        iterations: 40,
        ..Default::default()
    }
    .check()
    .unwrap();
    let t0 = std::time::Instant::now();
    let r = refine(&c, &em, &e, &start, &params, &|_| {}).unwrap();
    let m = &r.model;
    println!(
        "D {:.3} -> {:.3} in {} evaluations, {} iterations ({:.1} s)",
        r.start_distance,
        r.distance,
        r.evaluations,
        r.iterations,
        t0.elapsed().as_secs_f64()
    );
    for (k, n) in r.free.iter().enumerate() {
        println!(
            "{n}: start {:.4}, refined {:.4}, generating {:.4}",
            r.start[k],
            r.refined[k],
            truth.quantity(n).unwrap().value
        );
    }
    assert_eq!(r.free.len(), 8, "{:?}", r.free);
    assert!(r.distance < 0.8 * r.start_distance, "{r:?}");
    let check = CheckParams {
        draws: pradar::check::DEFAULT_DRAWS,
        ..Default::default()
    }
    .check()
    .unwrap();
    let before = pradar::check::check(&c, &em, &e, &start, &check, &|_, _| {}).unwrap();
    let after = pradar::check::check(&c, &em, &e, m, &check, &|_, _| {}).unwrap();
    println!("start: {}\nrefined: {}", before.verdict(), after.verdict());
    assert!(!before.passes(), "{}", before.verdict());
    assert!(after.passes(), "{}", after.verdict());
    assert_eq!(m.inter_cluster_rate, truth.inter_cluster_rate);
    assert_eq!(m.schema_version, truth.schema_version);
    assert_eq!(m.cluster_rrcs.interval, None);
    let cal = m.calibration.as_ref().unwrap();
    assert!(cal.method.starts_with("smm"), "{}", cal.method);
    assert_eq!(cal.free, r.free);
    assert_eq!(cal.simulations, r.simulations);
    assert!(r.simulations >= 4 * (r.evaluations - 1) / 2, "{r:?}");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let again = one
        .install(|| refine(&c, &em, &e, &start, &params, &|_| {}))
        .unwrap();
    assert_eq!(&again.model, m);
}
