//! MPC extraction against the simulator's ground truth (issue: MPC extraction & clustering).

use crate::common;

use common::*;
use pradar::campaign::manifest::{Campaign, SweepFormat, C0};
use pradar::energy::{EnergyMatrix, EnergyProcessor};
use pradar::mpc::{extract, ExtractParams, ExtractValid, Method, Mpc};
use pradar::params::ParamGuard;
use pradar::pattern::{beam_metrics, ArrayPattern};

/// Checked extraction parameters.
fn checked(p: ExtractParams) -> ExtractValid {
    p.check().unwrap()
}

/// Simulate a point-target scene (targets as (range m, angle deg, rrcs m)) and compute its
/// energy matrix.
fn scene(
    dir: &std::path::Path,
    n: usize,
    one_bit: bool,
    targets: &[(f64, f64, f64)],
    floor_dbm: f64,
) -> (Campaign, EnergyMatrix) {
    let mut t = fixture("tests/point_target.toml");
    set(&mut t, "array.elements", n as i64);
    set(&mut t, "array.one_bit", one_bit);
    set(&mut t, "noise.floor_dbm", floor_dbm);
    let arr: Vec<toml::Value> = targets
        .iter()
        .map(|&(r, a, x)| {
            let mut tt = toml::Table::new();
            tt.insert("x_m".into(), (r * a.to_radians().cos()).into());
            tt.insert("y_m".into(), (r * a.to_radians().sin()).into());
            tt.insert("rrcs_m".into(), x.into());
            tt.into()
        })
        .collect();
    t["scene"]
        .as_table_mut()
        .unwrap()
        .insert("targets".into(), arr.into());
    chain(dir, &t, SweepFormat::Parquet)
}

/// (recall, precision) by count within (2 bins, 5°).
fn score(mpcs: &[Mpc], targets: &[(f64, f64, f64)], tb: f64) -> (f64, f64) {
    let hit = |m: &Mpc, t: &(f64, f64, f64)| {
        let bins = (m.delay_ns - 2.0 * t.0 / C0 * 1e9).abs() / tb;
        bins <= 2.0 && (m.angle_rel_deg - t.1).abs() <= 5.0
    };
    let found = targets
        .iter()
        .filter(|t| mpcs.iter().any(|m| hit(m, t)))
        .count();
    let good = mpcs
        .iter()
        .filter(|m| targets.iter().any(|t| hit(m, t)))
        .count();
    (
        found as f64 / targets.len() as f64,
        if mpcs.is_empty() {
            0.0
        } else {
            good as f64 / mpcs.len() as f64
        },
    )
}

#[test]
fn clean_recall_and_precision_on_point_scenes() {
    let tmp = tempfile::tempdir().unwrap();
    let targets = [
        (2.0, -40.0, 0.2),
        (3.0, 20.0, 0.3),
        (4.5, 0.0, 0.15),
        (2.5, 60.0, 0.25),
        (5.5, -15.0, 0.4),
    ];
    for n in [16usize, 100, 400] {
        for one_bit in [false, true] {
            let (c, em) = scene(
                &tmp.path().join(format!("{n}{one_bit}")),
                n,
                one_bit,
                &targets,
                -110.0,
            );
            let clean = extract(&em, &c, &checked(ExtractParams::default())).unwrap();
            let peaks = checked(ExtractParams::default().method(Method::Peaks));
            let peaks = extract(&em, &c, &peaks).unwrap();
            let (rc, pc) = score(&clean, &targets, em.meta.bin_width_ns);
            let (rp, pp) = score(&peaks, &targets, em.meta.bin_width_ns);
            eprintln!("N={n} one_bit={one_bit}: CLEAN {} MPCs recall {rc:.2} precision {pc:.2}; peaks {} MPCs recall {rp:.2} precision {pp:.2}", clean.len(), peaks.len());
            assert!(
                rc >= 0.9 && pc >= 0.9,
                "N={n} one_bit={one_bit}: CLEAN recall {rc} precision {pc}"
            );
        }
    }
}

#[test]
fn two_equal_targets_one_and_a_half_beamwidths_apart_are_both_found() {
    let tmp = tempfile::tempdir().unwrap();
    for n in [16usize, 100, 400] {
        let c0 = fixture("tests/point_target.toml");
        let _ = c0;
        let arr = pradar::campaign::manifest::ArrayConfig {
            elements: n,
            one_bit: false,
            element_q: 1.0,
            steering: pradar::campaign::manifest::Steering::Mechanical,
        };
        let p = ArrayPattern::new(arr, 60.5e9).unwrap();
        let (hpbw, _) = beam_metrics(|t| p.gain(t, 0.0, 60.5e9), 0.0);
        let a1 = 10.0;
        let a2 = a1 + 1.5 * hpbw;
        let targets = [(3.0, a1, 0.3), (3.0, a2, 0.3)];
        let (c, em) = scene(&tmp.path().join(format!("{n}")), n, false, &targets, -110.0);
        let clean = extract(&em, &c, &checked(ExtractParams::default())).unwrap();
        let (r, pr) = score(&clean, &targets, em.meta.bin_width_ns);
        eprintln!("N={n}: HPBW {hpbw:.1} deg, targets at {a1} and {a2:.1} deg: {} MPCs, recall {r:.2} precision {pr:.2}", clean.len());
        for m in &clean {
            eprintln!(
                "   MPC delay {:.2} ns angle {:.1} deg snr {:.1} dB",
                m.delay_ns, m.angle_rel_deg, m.snr_db
            );
        }
        assert_eq!(r, 1.0, "N={n}: both targets must be found");
    }
}

#[test]
fn single_strong_target_n16_one_mpc_where_peaks_gives_more() {
    let tmp = tempfile::tempdir().unwrap();
    let targets = [(3.0, 20.0, 1.0)];
    let (c, em) = scene(tmp.path(), 16, false, &targets, -110.0);
    let clean = extract(&em, &c, &checked(ExtractParams::default())).unwrap();
    let peaks = checked(ExtractParams::default().method(Method::Peaks));
    let peaks = extract(&em, &c, &peaks).unwrap();
    eprintln!(
        "N=16 strong target (SNR {:.1} dB): CLEAN {} MPC(s), peaks {} MPCs",
        clean.first().map(|m| m.snr_db).unwrap_or(0.0),
        clean.len(),
        peaks.len()
    );
    assert_eq!(clean.len(), 1);
    assert!(peaks.len() > 1, "peaks found {}", peaks.len());
    let (r, _) = score(&clean, &targets, em.meta.bin_width_ns);
    assert_eq!(r, 1.0);
}

#[test]
fn floor_tracks_the_configured_noise_floor() {
    let tmp = tempfile::tempdir().unwrap();
    for floor_dbm in [-115.0, -100.0, -85.0] {
        let (c, em) = scene(
            &tmp.path().join(format!("{}", -floor_dbm)),
            100,
            false,
            &[(3.0, 20.0, 0.3)],
            floor_dbm,
        );
        let m = &c.manifest;
        let proc = EnergyProcessor::new(m.band, m.processing).unwrap();
        let want = proc.noise_per_sample(m.noise.s21_variance());
        let got = em.meta.noise_mean();
        let err = 10.0 * (got / want).log10();
        eprintln!(
            "floor {floor_dbm} dBm: estimated {:.2} dB, configured {:.2} dB ({err:+.2} dB)",
            10.0 * got.log10(),
            10.0 * want.log10()
        );
        assert!(err.abs() <= 1.0);
        // and CLEAN keeps nothing from noise alone
        let clean = extract(&em, &c, &checked(ExtractParams::default())).unwrap();
        assert!(clean.len() <= 2, "floor {floor_dbm}: {} MPCs", clean.len());
    }
}

#[test]
fn corridor_strong_scatterer_recall_is_printed() {
    let tmp = tempfile::tempdir().unwrap();
    for n in [16usize, 100, 400] {
        let mut t = corridor();
        set(&mut t, "array.elements", n as i64);
        let dir = tmp.path().join(format!("c{n}"));
        let (sc, em) = chain(&dir, &t, SweepFormat::Parquet);
        let mpcs = extract(&em, &sc, &checked(ExtractParams::default())).unwrap();
        let rays = pradar::table::read_parquet(&dir.join("sim/truth/rays.parquet"), None).unwrap();
        let path = std::path::Path::new("rays");
        let pos = pradar::table::i64_column(path, &rays, "position").unwrap();
        let delay = pradar::table::f64_column(path, &rays, "delay_ns").unwrap();
        let ang = pradar::table::f64_column(path, &rays, "angle_rel_deg").unwrap();
        let pw = pradar::table::f64_column(path, &rays, "power_db").unwrap();
        let kind: Vec<String> = rays
            .column("kind")
            .unwrap()
            .str()
            .unwrap()
            .iter()
            .map(|s| s.unwrap_or("").to_string())
            .collect();
        let floor_db = 10.0 * em.meta.noise_mean().log10();
        let tb = em.meta.bin_width_ns;
        let mut line = format!(
            "N={n}: {} MPCs over {} positions;",
            mpcs.len(),
            em.positions
        );
        for k in ["corner", "edge", "specular"] {
            let strong: Vec<usize> = (0..pos.len())
                .filter(|&i| {
                    kind[i] == k
                        && pw[i] > floor_db + 20.0
                        && ang[i].abs() <= 90.0
                        && delay[i] < 0.95 * em.bins as f64 * tb
                })
                .collect();
            let found = strong
                .iter()
                .filter(|&&i| {
                    mpcs.iter().any(|m| {
                        m.position == pos[i] as usize
                            && (m.delay_ns - delay[i]).abs() / tb <= 2.0
                            && (m.angle_rel_deg - ang[i]).abs() <= 5.0
                    })
                })
                .count();
            line.push_str(&format!(" {k} recall {found}/{}", strong.len()));
        }
        eprintln!("{line}");
        assert!(!mpcs.is_empty());
    }
}
