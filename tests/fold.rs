//! Issue 54 item 2, "the chain knows the fold": the wall echoes the layout predicts to fold
//! into the kept bins are labelled folded and kept out of the clusters.
//!
//! The built-in corridor's physics scene (its `[clutter]` included) moved into the long
//! hall (`data/tests/long_hall.geojson`, 120 m × 12 m) at 801 points over 6 GHz
//! (R_u = 19.99 m): four poses 10 m from its west wall near the axis, looking east, so the
//! east wall (110 m away) and the side walls seen at less than 17.5° from the axis lie
//! beyond R_u while the kept span (80 ns, 12 m) lies within it.
//!
//! Measured (release build): 800 MPCs, 29 folded, 450 diffuse, 321 discrete; the east
//! wall's echo found 3.2 cm beyond its predicted fold (the chain's delay offset) at every
//! pose; against the per-path truth 29 folded and far, 0 folded but near, 3 far wall echoes
//! not folded, 62 far clutter echoes not folded (the layout cannot predict them). The
//! bounds asserted (precision ≥ 0.8, recall of the far wall echoes ≥ 0.5) are the issue's
//! "most", not these figures.

use crate::common::{chain, corridor, set};
use pradar::campaign::fold::unambiguous_range_m;
use pradar::campaign::manifest::SweepFormat;
use pradar::cluster::{cluster, ClusterParams};
use pradar::mpc::{Component, ExtractParams};
use pradar::params::ParamGuard;
use pradar::units::range_m;
use std::path::PathBuf;

#[test]
fn wall_echoes_from_beyond_the_unambiguous_range_are_labelled_folded_and_not_clustered() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fold_long_hall_clutter");
    let mut t = corridor();
    set(&mut t, "layout", "long_hall.geojson");
    let poses: Vec<toml::Value> = [-50.0, -49.6, -49.2, -48.8]
        .iter()
        .map(|x: &f64| {
            let mut p = toml::Table::new();
            p.insert("x_m".into(), (*x).into());
            p.insert("y_m".into(), 0.3.into());
            p.insert("heading_deg".into(), 0.0.into());
            toml::Value::Table(p)
        })
        .collect();
    t.insert("poses".into(), toml::Value::Array(poses));
    let (c, em) = chain(&dir, &t, SweepFormat::Parquet);
    let m = &c.manifest;
    let ru = unambiguous_range_m(&m.band);
    let span_m = range_m(em.delay_ns(em.bins - 1));
    assert!(span_m < ru, "the kept span {span_m} m within R_u {ru} m");
    let (mpcs, labels) =
        pradar::mpc::extract_labelled(&em, &c, &ExtractParams::default().check().unwrap()).unwrap();
    let count = |k: Component| mpcs.iter().filter(|x| x.component == k).count();
    let (folded, diffuse, discrete) = (
        count(Component::Folded),
        count(Component::Diffuse),
        count(Component::Discrete),
    );
    eprintln!(
        "long hall at {} points (R_u {ru:.2} m, span {span_m:.2} m): {} MPCs, {folded} folded, \
         {diffuse} diffuse, {discrete} discrete; {} of the folded were labelled diffuse first",
        m.band.points,
        mpcs.len(),
        labels.fold.from_diffuse
    );
    assert_eq!(labels.fold.folded, folded);
    assert_eq!(labels.diffuse(), diffuse);
    assert_eq!(labels.fold.unambiguous_range_m, ru);
    assert!(folded >= 4, "{folded} folded MPCs");

    // the east wall along the axis (normal incidence, the strongest far echo): its fold
    // predicted at (60 − x) − k·R_u, independently of the stage's rays; the strongest MPC of
    // the beam within ±5° of east near it is there and folded
    let tol_m = 2.0 * range_m(em.meta.bin_width_ns);
    for (p, pose) in m.poses.iter().enumerate() {
        let true_m = 60.0 - pose.x_m;
        let fold_m = true_m - (true_m / ru).floor() * ru;
        let near: Vec<_> = mpcs
            .iter()
            .filter(|x| x.position == p && x.angle_global_deg.abs() <= 5.0)
            .filter(|x| (range_m(x.delay_ns) - fold_m).abs() <= 3.0 * tol_m)
            .collect();
        let best = near
            .iter()
            .max_by(|a, b| a.power_db.total_cmp(&b.power_db))
            .unwrap_or_else(|| panic!("pose {p}: no MPC near the east wall's fold {fold_m:.3} m"));
        eprintln!(
            "pose {p}: east wall {true_m:.2} m folds to {fold_m:.3} m; strongest MPC there at \
             {:.3} m, {:.1}°, {:.1} dB SNR, {:?}",
            range_m(best.delay_ns),
            best.angle_global_deg,
            best.snr_db,
            best.component
        );
        assert!(
            (range_m(best.delay_ns) - fold_m).abs() <= tol_m,
            "pose {p}: {} m against {fold_m} m",
            range_m(best.delay_ns)
        );
        assert_eq!(best.component, Component::Folded, "pose {p}");
    }

    // every folded MPC sits near the fold of a wall beyond R_u along its bearing: some ray
    // within ±3° (every 0.01°: an oblique wall's range moves 2 cm between them) meets a wall
    // at r + k·R_u (k ≥ 1) within the tolerance and 3 cm (the chain's delay offset)
    let layout = pradar::campaign::Layout::load(&c.layout_path()).unwrap();
    for x in mpcs.iter().filter(|x| x.component == Component::Folded) {
        let pose = m.poses[x.position];
        let at = geo::Coord {
            x: pose.x_m,
            y: pose.y_m,
        };
        let r = range_m(x.delay_ns);
        let near = (-300..=300).any(|i| {
            let a = (x.angle_global_deg + 0.01 * i as f64).to_radians();
            layout.first_hit(at, a).is_some_and(|(rw, _, _)| {
                let k = ((rw - r) / ru).round();
                rw > ru && k >= 1.0 && (r + k * ru - rw).abs() <= tol_m + 0.03
            })
        });
        assert!(near, "{x:?} is not near a folded wall range");
    }

    // against the simulator's per-path truth: the strongest truth ray in each MPC's cell
    // (same position, within half the direction step in angle and 0.5 ns in delay once the
    // truth delay is folded modulo T = 1/Δf; the chain's delay offset is 0.2 ns) is from
    // beyond R_u (`far`) or not
    let (tp, fp, fneg, fneg_other, near_ok, unseen) =
        score_against_truth(&dir.join("sim/truth/rays.parquet"), &mpcs, m);
    eprintln!(
        "truth: folded and far {tp}, folded but near {fp}, far wall echo not folded {fneg}, \
         far clutter not folded {fneg_other}, neither {near_ok}, no truth ray in the cell \
         {unseen}"
    );
    assert!(
        tp as f64 >= 0.8 * (tp + fp) as f64,
        "precision {tp}/{}",
        tp + fp
    );
    assert!(
        tp as f64 >= 0.5 * (tp + fneg) as f64,
        "recall {tp}/{}",
        tp + fneg
    );

    // the clusters contain none of them
    let headings: Vec<f64> = m.poses.iter().map(|p| p.heading_deg).collect();
    let cl = cluster(&mpcs, &headings, &ClusterParams::default().check().unwrap()).unwrap();
    for (x, id) in cl.mpcs.iter().zip(&cl.cluster_id) {
        assert_eq!(
            id.is_some(),
            x.component == Component::Discrete,
            "{:?} in cluster {id:?}",
            x.component
        );
    }
    let clustered: usize = cl.positions.iter().map(|p| p.labels.len()).sum();
    assert_eq!(clustered, discrete);
}

/// Score the fold labels against `rays.parquet`: (folded and far, folded but near, far wall
/// echo (diffuse, specular, corner, edge) not folded, other far echo (clutter, target: the
/// layout cannot predict them) not folded, neither, no truth ray in the cell), the cell as
/// in the test.
fn score_against_truth(
    path: &std::path::Path,
    mpcs: &[pradar::mpc::Mpc],
    m: &pradar::campaign::manifest::Manifest,
) -> (usize, usize, usize, usize, usize, usize) {
    let crate::common::TruthRays {
        pos,
        a,
        d,
        pw,
        kind,
        ..
    } = crate::common::truth_rays(path);
    let wall = |i: usize| ["diffuse", "specular", "corner", "edge"].contains(&kind[i].as_str());
    let period_ns = 1e9 / m.band.step_hz();
    let half_deg = m.directions.step_deg / 2.0;
    let mut out = (0, 0, 0, 0, 0, 0);
    for x in mpcs {
        let best = (0..pos.len())
            .filter(|&i| pos[i] as usize == x.position && pw[i].is_finite())
            .filter(|&i| (a[i] - x.angle_rel_deg).abs() <= half_deg)
            .filter(|&i| {
                let f = d[i] - (d[i] / period_ns).floor() * period_ns;
                let e = (f - x.delay_ns).abs();
                e.min(period_ns - e) <= 0.5
            })
            .max_by(|&i, &j| pw[i].total_cmp(&pw[j]));
        let Some(i) = best else {
            out.5 += 1;
            continue;
        };
        match (x.component == Component::Folded, d[i] >= period_ns) {
            (true, true) => out.0 += 1,
            (true, false) => out.1 += 1,
            (false, true) if wall(i) => out.2 += 1,
            (false, true) => out.3 += 1,
            (false, false) => out.4 += 1,
        }
    }
    out
}
