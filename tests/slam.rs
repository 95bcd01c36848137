//! Issue 56: the poses of the built-in corridor's walk from its odometry and its sweeps
//! (`mapping::slam`), against the odometry's dead reckoning.

use crate::common;
use pradar::campaign::manifest::SweepFormat;
use pradar::mapping::job::{min_bin, window_kernel};
use pradar::mapping::og::{detection_threshold, Detector};
use pradar::mapping::slam::matching::steering_step_rad;
use pradar::mapping::slam::odometry::{pose2, position_rmse};
use pradar::mapping::slam::{estimate, Odometry, OdometryNoise, Scan, SolveParams};
use pradar::params::ParamGuard;

/// The corridor (12 poses, N = 400, 5° steps), odometry σ 0.1 m and 3° per step, 10 seeds:
/// the scans matched to the map so far bring the position RMSE well below the dead
/// reckoning's.
#[test]
fn corridor_scans_correct_the_odometry() {
    let tmp = tempfile::tempdir().unwrap();
    let (c, em) = common::chain(tmp.path(), &common::corridor(), SweepFormat::Parquet);
    let e = tmp.path().join("energy.parquet");
    let threshold = detection_threshold(&em.meta, 1e-3, &e).unwrap();
    let det = Detector::new(threshold, &window_kernel(&c).unwrap(), 10.0, min_bin(&em));
    let scans: Vec<Scan> = (0..em.positions)
        .map(|p| Scan::from_detections(&em, &det.detect_pose(&em, p)))
        .collect();
    let truth: Vec<_> = c.manifest.poses.iter().map(pose2).collect();
    let step = steering_step_rad(&em.angles_rel_deg);
    let solve = SolveParams::default().check().unwrap();
    let (mut dead, mut est) = (0.0, 0.0);
    for seed in 1..=10 {
        let noise = OdometryNoise {
            step_m: 0.1,
            step_deg: 3.0,
            seed,
        };
        let odo = Odometry::simulate(&truth, &noise.check().unwrap());
        let t = std::time::Instant::now();
        let r = estimate(&odo, &scans, 0.05, step, &solve).unwrap();
        let (d, s) = (
            position_rmse(&r.dead_reckoning, &truth),
            position_rmse(&r.poses, &truth),
        );
        eprintln!(
            "seed {seed}: RMSE dead reckoning {d:.3} m, estimated {s:.3} m ({} of {} matched, {:.2} s)",
            r.matched.iter().filter(|m| **m).count(),
            r.matched.len(),
            t.elapsed().as_secs_f64()
        );
        dead += d / 10.0;
        est += s / 10.0;
    }
    eprintln!("mean RMSE: dead reckoning {dead:.3} m, estimated {est:.3} m");
    assert!(est < dead / 3.0, "{est} vs {dead}");
}
