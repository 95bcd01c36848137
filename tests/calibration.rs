//! `[calibration]` sweeps (issue 18): a reference (thru) sweep divides out a simulated
//! system response — a cable delay plus ripple — and puts a point target back in its bin
//! at the radar equation's energy; a background sweep removes a static clutter term.

use crate::common::*;
use crate::physics::{argmax, radar_equation_energy};
use num_complex::Complex64;
use pradar::campaign::manifest::{Campaign, SweepFormat, C0};
use pradar::campaign::touchstone::{read_touchstone, write_s2p, SParam, TsFormat};
use pradar::energy::EnergyMatrix;
use std::f64::consts::PI;
use std::path::Path;

/// Multiply (`mul`) and add (`add`, per direction) a response to every sweep of the
/// simulated campaign in `dir` (files `sweeps/p000_dDD_k00.s2p`), in place.
fn alter_sweeps(dir: &Path, mul: &dyn Fn(f64) -> Complex64, add: &dyn Fn(usize, f64) -> Complex64) {
    for entry in std::fs::read_dir(dir.join("sweeps")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let d: usize = name[6..8].parse().unwrap();
        let net = read_touchstone(&path).unwrap();
        let v = net.param(SParam::S21, &path).unwrap();
        let new: Vec<Complex64> = v
            .iter()
            .zip(&net.freq_hz)
            .map(|(s, &f)| s * mul(f) + add(d, f))
            .collect();
        write_sweep(&path, &net.freq_hz, &new);
    }
}

/// Write an S21 sweep as the simulator does (RI, 12 digits, S12 = S21, S11 = S22 = 0).
fn write_sweep(path: &Path, f: &[f64], s21: &[Complex64]) {
    let z = Complex64::new(0.0, 0.0);
    let rows: Vec<[Complex64; 4]> = s21.iter().map(|&v| [z, v, v, z]).collect();
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let mut buf = Vec::new();
    write_s2p(&mut buf, f, &rows, TsFormat::Ri, 12, "calibration test").unwrap();
    std::fs::write(path, buf).unwrap();
}

/// Copy a simulated campaign folder (manifest, layout, sweeps/).
fn copy_campaign(from: &Path, to: &Path) {
    std::fs::create_dir_all(to.join("sweeps")).unwrap();
    for sub in ["", "sweeps"] {
        for entry in std::fs::read_dir(from.join(sub)).unwrap() {
            let p = entry.unwrap().path();
            if p.is_file() {
                std::fs::copy(&p, to.join(sub).join(p.file_name().unwrap())).unwrap();
            }
        }
    }
}

/// Energy of the campaign `dir/campaign.toml` with `[calibration]` set to `cal` (a TOML
/// table's text, or none), written as `dir/<tag>.toml`.
fn energy_with(
    dir: &Path,
    tag: &str,
    cal: Option<&str>,
) -> pradar::Result<(Campaign, EnergyMatrix)> {
    let mut t: toml::Table =
        toml::from_str(&std::fs::read_to_string(dir.join("campaign.toml")).unwrap()).unwrap();
    if let Some(cal) = cal {
        t.insert(
            "calibration".into(),
            toml::from_str::<toml::Table>(cal).unwrap().into(),
        );
    }
    let m = dir.join(format!("{tag}.toml"));
    std::fs::write(&m, toml::to_string(&t).unwrap()).unwrap();
    let c = Campaign::load(&m)?;
    let e = dir.join(format!("{tag}.parquet"));
    pradar::energy::run(&c, &e, &|_, _| {})?;
    Ok((c, EnergyMatrix::read(&e).unwrap()))
}

fn point_target(tmp: &Path) -> (Campaign, EnergyMatrix) {
    let mut t = fixture("tests/point_target.toml");
    set(&mut t, "array.elements", 100i64);
    chain(tmp, &t, SweepFormat::Touchstone)
}

#[test]
fn reference_sweep_removes_cable_delay_and_ripple() {
    let tmp = tempfile::tempdir().unwrap();
    let (range, angle_deg, rrcs) = (3.0f64, 20.0f64, 0.3f64);
    let (_, clean) = point_target(tmp.path());
    let dir = tmp.path().join("measured");
    copy_campaign(&tmp.path().join("sim"), &dir);
    // the system: 6 dB of cable loss, 5 ns of cable delay, a 30 % reflection 1.5 ns later
    // (ripple of 667 MHz period in |H|)
    let h = |f: f64| {
        0.5 * Complex64::from_polar(1.0, -2.0 * PI * f * 5e-9)
            * (1.0 + 0.3 * Complex64::from_polar(1.0, -2.0 * PI * f * 1.5e-9))
    };
    alter_sweeps(&dir, &h, &|_, _| Complex64::new(0.0, 0.0));
    let net = read_touchstone(&dir.join("sweeps/p000_d00_k00.s2p")).unwrap();
    let thru: Vec<Complex64> = net.freq_hz.iter().map(|&f| h(f)).collect();
    write_sweep(&dir.join("cal/thru.s2p"), &net.freq_hz, &thru);

    let want_bin = (2.0 * range / C0 * 1e9 / clean.meta.bin_width_ns).round() as usize;
    let (_, raw) = energy_with(&dir, "raw", None).unwrap();
    let (c, cal) = energy_with(&dir, "cal", Some("reference = \"cal/thru.s2p\"")).unwrap();
    for (tag, em) in [
        ("clean", &clean),
        ("uncalibrated", &raw),
        ("calibrated", &cal),
    ] {
        let (d, b, e) = argmax(em, 0);
        let (expect, _) =
            radar_equation_energy(&c, angle_deg, em.angles_rel_deg[d], range, rrcs, b);
        eprintln!(
            "{tag:>12}: peak bin {b} (radar equation: bin {want_bin}), direction {} deg, {:+.2} dB from the radar equation",
            em.angles_rel_deg[d],
            10.0 * (e / expect).log10()
        );
    }
    // the target's own direction in the uncalibrated table: moved by the cable delay
    let dt = raw
        .angles_rel_deg
        .iter()
        .position(|&a| (a - angle_deg).abs() < 1e-9)
        .unwrap();
    let prof = raw.profile(0, dt);
    let b_raw = (60..prof.len())
        .max_by(|&i, &j| prof[i].total_cmp(&prof[j]))
        .unwrap();
    let (expect, _) = radar_equation_energy(&c, angle_deg, angle_deg, range, rrcs, want_bin);
    eprintln!(
        "uncalibrated, {angle_deg} deg: target at bin {b_raw} ({:+.2} dB vs the radar equation at bin {want_bin}); the strongest cell is the coupling, moved behind the gate",
        10.0 * (prof[b_raw] / expect).log10()
    );
    assert!(
        b_raw.abs_diff(want_bin) >= 25,
        "the cable delay should move the peak: bin {b_raw}"
    );
    let (d, b, e) = argmax(&cal, 0);
    let (expect, _) = radar_equation_energy(&c, angle_deg, cal.angles_rel_deg[d], range, rrcs, b);
    let err_db = 10.0 * (e / expect).log10();
    assert!(
        b.abs_diff(want_bin) <= 1,
        "calibrated peak bin {b}, expected {want_bin}"
    );
    assert!(
        err_db.abs() <= 0.5,
        "calibrated peak {err_db:+.2} dB from the radar equation"
    );
    assert_eq!(
        cal.meta
            .all
            .iter()
            .find(|(k, _)| k == "calibration_reference")
            .map(|(_, v)| v.as_str()),
        Some("cal/thru.s2p")
    );
    // a reference that is zero somewhere cannot be divided out: refused before processing
    let mut zero = thru.clone();
    zero[7] = Complex64::new(0.0, 0.0);
    write_sweep(&dir.join("cal/bad.s2p"), &net.freq_hz, &zero);
    let e = energy_with(&dir, "bad", Some("reference = \"cal/bad.s2p\""))
        .unwrap_err()
        .to_string();
    assert!(e.contains("cal/bad.s2p") && e.contains("at point 7"), "{e}");
    assert!(!dir.join("bad.parquet").exists());
}

#[test]
fn background_sweep_removes_static_clutter() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, clean) = point_target(tmp.path());
    let dir = tmp.path().join("measured");
    copy_campaign(&tmp.path().join("sim"), &dir);
    // a static clutter return at 8 ns (1.2 m) that does not rotate with the beam but
    // differs per direction (so the `mean` coupling removal could not take it out)
    let tau_c = 8e-9;
    let clutter = |d: usize, f: f64| {
        Complex64::from_polar(2e-4 * (1.0 + 0.05 * d as f64), -2.0 * PI * f * tau_c)
    };
    alter_sweeps(&dir, &|_| Complex64::new(1.0, 0.0), &clutter);
    let net = read_touchstone(&dir.join("sweeps/p000_d00_k00.s2p")).unwrap();
    for d in 0..clean.directions() {
        let bg: Vec<Complex64> = net.freq_hz.iter().map(|&f| clutter(d, f)).collect();
        write_sweep(&dir.join(format!("cal/bg_d{d:02}.s2p")), &net.freq_hz, &bg);
    }
    let (_, before) = energy_with(&dir, "before", None).unwrap();
    let (_, after) = energy_with(
        &dir,
        "after",
        Some("background = \"cal/bg_d{direction:02}.s2p\""),
    )
    .unwrap();
    let bin = (tau_c * 1e9 / clean.meta.bin_width_ns).round() as usize;
    let max = (0..clean.directions())
        .flat_map(|d| clean.profile(0, d).to_vec())
        .fold(0.0f64, f64::max);
    let mut worst = 0.0f64;
    for d in 0..clean.directions() {
        let (c, b, a) = (
            clean.profile(0, d),
            before.profile(0, d),
            after.profile(0, d),
        );
        let rise_db = 10.0 * (b[bin] / c[bin]).log10();
        assert!(
            rise_db >= 20.0,
            "direction {d}: clutter only {rise_db:.1} dB above the clean bin"
        );
        let left_db = 10.0 * (a[bin] / c[bin]).log10();
        assert!(
            left_db.abs() <= 0.01,
            "direction {d}: {left_db:+.3} dB left after subtraction"
        );
        for (x, y) in a.iter().zip(c) {
            worst = worst.max((x - y).abs() / max);
        }
        if d == 0 {
            eprintln!("direction 0, bin {bin} (8 ns): clean {:.3e}, with clutter {:.3e} ({rise_db:+.1} dB), background subtracted {:.3e} ({left_db:+.4} dB)", c[bin], b[bin], a[bin]);
        }
    }
    eprintln!("after subtraction, max |E - E_clean| / max E_clean = {worst:.2e}");
    assert!(
        worst < 1e-6,
        "background subtraction left {worst:.2e} of the peak"
    );
    assert_eq!(
        after
            .meta
            .all
            .iter()
            .find(|(k, _)| k == "calibration_background")
            .map(|(_, v)| v.as_str()),
        Some("cal/bg_d{direction:02}.s2p")
    );
}
