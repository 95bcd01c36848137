//! Issue 16's diffuse stage and K, scored against the simulator's per-path truth
//! (`truth/rays.parquet`) on the built-in corridor (as shipped, and without `[clutter]`).
//!
//! The truth label of an MPC is the source class carrying most of the truth rays' power in
//! its resolution cell: rays of the same position within half the direction step (or half
//! the two-way beamwidth) in angle and one bin in delay, summed linearly by class (diffuse
//! against every other kind). An MPC with no truth ray in its cell (a CLEAN residue or
//! noise) has no truth label and is counted apart.

use crate::common;
use pradar::campaign::manifest::SweepFormat;
use pradar::campaign::Campaign;
use pradar::mpc::{Component, ExtractParams, Mpc};
use pradar::params::ParamGuard;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The truth rays of one position: (angle_rel_deg, delay_ns, linear power, diffuse?).
type TruthCell = Vec<(f64, f64, f64, bool)>;

/// The truth rays of `rays.parquet`, by position.
fn truth_rays(path: &Path, positions: usize) -> Vec<TruthCell> {
    let df = pradar::table::read_parquet(path, None).unwrap();
    let pos = pradar::table::i64_column(path, &df, "position").unwrap();
    let a = pradar::table::f64_column(path, &df, "angle_rel_deg").unwrap();
    let d = pradar::table::f64_column(path, &df, "delay_ns").unwrap();
    let pw = pradar::table::f64_column_or_nan(path, &df, "power_db")
        .unwrap()
        .unwrap();
    let kind = pradar::table::str_column(path, &df, "kind")
        .unwrap()
        .unwrap();
    let mut out = vec![Vec::new(); positions];
    for i in 0..pos.len() {
        if pw[i].is_finite() {
            out[pos[i] as usize].push((a[i], d[i], 10f64.powf(pw[i] / 10.0), kind[i] == "diffuse"));
        }
    }
    out
}

/// The median delay of the MPCs after the strongest truth ray within `half_angle_deg` and
/// 0.5 ns of them, ns: the chain's systematic delay offset (the transmitarray's feed paths,
/// which the simulator keeps and the analysis does not model).
pub fn delay_offset_ns(mpcs: &[Mpc], rays: &[TruthCell], half_angle_deg: f64) -> f64 {
    let mut d: Vec<f64> = mpcs
        .iter()
        .filter_map(|m| {
            rays[m.position]
                .iter()
                .filter(|r| {
                    (r.0 - m.angle_rel_deg).abs() <= half_angle_deg
                        && (r.1 - m.delay_ns).abs() <= 0.5
                })
                .max_by(|a, b| a.2.total_cmp(&b.2))
                .map(|r| m.delay_ns - r.1)
        })
        .collect();
    d.sort_by(f64::total_cmp);
    d.get(d.len() / 2).copied().unwrap_or(0.0)
}

/// The truth component of each MPC (None: no truth ray in its cell), the MPC's delay
/// corrected by `offset_ns`.
pub fn truth_components(
    mpcs: &[Mpc],
    rays: &[TruthCell],
    half_angle_deg: f64,
    half_delay_ns: f64,
    offset_ns: f64,
) -> Vec<Option<Component>> {
    mpcs.iter()
        .map(|m| {
            let (mut dif, mut dis) = (0.0, 0.0);
            for &(a, d, p, is_diffuse) in &rays[m.position] {
                if (a - m.angle_rel_deg).abs() <= half_angle_deg
                    && (d - (m.delay_ns - offset_ns)).abs() <= half_delay_ns
                {
                    if is_diffuse {
                        dif += p;
                    } else {
                        dis += p;
                    }
                }
            }
            if dif + dis == 0.0 {
                None
            } else if dif > dis {
                Some(Component::Diffuse)
            } else {
                Some(Component::Discrete)
            }
        })
        .collect()
}

/// Precision and recall of "diffuse", and (labelled, without truth) counts.
pub fn diffuse_scores(got: &[Mpc], truth: &[Option<Component>]) -> (f64, f64, usize, usize) {
    let (mut tp, mut fp, mut fneg, mut none) = (0usize, 0usize, 0usize, 0usize);
    for (m, t) in got.iter().zip(truth) {
        match (m.component, t) {
            (_, None) => none += 1,
            (Component::Diffuse, Some(Component::Diffuse)) => tp += 1,
            (Component::Diffuse, Some(Component::Discrete)) => fp += 1,
            (Component::Discrete, Some(Component::Diffuse)) => fneg += 1,
            _ => {}
        }
    }
    let precision = tp as f64 / (tp + fp).max(1) as f64;
    let recall = tp as f64 / (tp + fneg).max(1) as f64;
    (precision, recall, got.len() - none, none)
}

/// The corridor simulated (as shipped, or without `[clutter]`): the output manifest and
/// energy table, once per test binary.
fn corridor_run(clutter: bool) -> &'static (PathBuf, PathBuf) {
    static WITH: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    static WITHOUT: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    let cell = if clutter { &WITH } else { &WITHOUT };
    cell.get_or_init(|| {
        let name = if clutter {
            "diffuse_corridor"
        } else {
            "diffuse_geometry"
        };
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
        let mut t = common::corridor();
        if !clutter {
            t.remove("clutter");
        }
        let (c, _) = common::chain(&dir, &t, SweepFormat::Parquet);
        (c.path.clone(), dir.join("energy.parquet"))
    })
}

/// Extract the run's MPCs with the default parameters.
fn extract(run: &(PathBuf, PathBuf)) -> (Campaign, Vec<Mpc>) {
    let c = Campaign::load(&run.0).unwrap();
    let em = pradar::energy::EnergyMatrix::read(&run.1).unwrap();
    let mpcs = pradar::mpc::extract(&em, &c, &ExtractParams::default().check().unwrap()).unwrap();
    (c, mpcs)
}

#[test]
fn corridor_diffuse_labels_match_the_per_path_truth() {
    for clutter in [true, false] {
        let run = corridor_run(clutter);
        let (c, mpcs) = extract(run);
        let truth_path = run.0.parent().unwrap().join("truth/rays.parquet");
        let rays = truth_rays(&truth_path, c.manifest.positions());
        let step = c.manifest.directions.step_deg;
        let tb = 1e9 / c.manifest.band.bandwidth_hz();
        let offset = delay_offset_ns(&mpcs, &rays, step / 2.0);
        let truth = truth_components(&mpcs, &rays, step / 2.0, tb, offset);
        let (p, r, scored, none) = diffuse_scores(&mpcs, &truth);
        if std::env::var("DIFFUSE_DEBUG").is_ok() {
            for (m, t) in mpcs.iter().zip(&truth).filter(|x| x.1.is_none()).take(40) {
                let near = rays[m.position]
                    .iter()
                    .filter(|r| (r.0 - m.angle_rel_deg).abs() <= step / 2.0)
                    .min_by(|a, b| {
                        (a.1 - m.delay_ns)
                            .abs()
                            .total_cmp(&(b.1 - m.delay_ns).abs())
                    });
                eprintln!(
                    "p{} a{:.1} d{:.2} pw{:.1} {:?} {:?} near {:?}",
                    m.position, m.angle_rel_deg, m.delay_ns, m.power_db, m.component, t, near
                );
            }
        }
        let diffuse = mpcs
            .iter()
            .filter(|m| m.component == Component::Diffuse)
            .count();
        eprintln!(
            "corridor{}: {} MPCs, {diffuse} labelled diffuse; delays {offset:+.3} ns after the truth; scored {scored} ({none} without a truth ray in their cell): precision {p:.3}, recall {r:.3}",
            if clutter { "" } else { " without [clutter]" },
            mpcs.len()
        );
        assert!(p >= 0.9 && r >= 0.9, "precision {p:.3}, recall {r:.3}");
    }
}
