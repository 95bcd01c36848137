//! Iterative 2-D CLEAN over one position's delay × angle residual `R[d][b]` (initially the
//! energies).
//!
//! 1. floor F = N0·TW, the mean energy of a signal-free bin, from the energy table's
//!    metadata (estimated by `energy` from the bins beyond `noise_from_ns`);
//! 2. take the strongest cell (d*, b*) not yet rejected; stop if R < F·10^(margin/10), if R
//!    is more than `dynamic_range_db` below the position's strongest cell, or at
//!    `max_mpcs`;
//! 3. reject the cell as a side-lobe replica if R ≤ 10^(guard/10) × (the largest energy that
//!    the components already kept predict at the cell or ±1 bin): model mismatch of a
//!    strong component's footprint must not become new components;
//! 4. refine delay and angle to sub-cell precision by a parabola through the log energies of
//!    the neighbouring bins/directions (clamped to ±½ cell); near either end of a
//!    mechanical scan, fit the angle to the beam-space signature instead ([`super::edge`]);
//! 5. keep it (unless it lies beyond the scanned sector) and subtract its footprint
//!    A·W(θ_d − θ̂)·K(b − b̂) ([`super::footprint`]), A chosen so the footprint equals R at
//!    (d*, b*); the footprint covers every direction and ±`kernel_bins` bins (the
//!    delay-angle window); residuals are clamped at 0;
//! 6. repeat.

use super::edge::edge_angle;
use super::footprint::Footprint;
use super::{ExtractValid, Mpc, PositionView};

/// Parabolic peak offset (in cells, clamped to ±½) through three log energies.
pub(crate) fn parabola(lm: f64, l0: f64, lp: f64) -> f64 {
    let den = lm - 2.0 * l0 + lp;
    if den.abs() < 1e-12 || !den.is_finite() {
        0.0
    } else {
        (0.5 * (lm - lp) / den).clamp(-0.5, 0.5)
    }
}

/// The strongest residual cell not yet rejected, as (index, energy); None when every
/// remaining cell is rejected or zero.
fn strongest_open(r: &[f64], rejected: &[bool]) -> Option<(usize, f64)> {
    let (mut best, mut bi) = (0.0, usize::MAX);
    for (i, &v) in r.iter().enumerate() {
        if !rejected[i] && v > best {
            best = v;
            bi = i;
        }
    }
    (bi != usize::MAX).then_some((bi, best))
}

/// The largest energy the kept components predict at (d, b) and its delay neighbours (the
/// footprint model's delays are only approximately right).
fn predicted_near(predicted: &[f64], d: usize, b: usize, nb: usize) -> f64 {
    let mut pred = 0.0f64;
    for y in b.saturating_sub(1)..(b + 2).min(nb) {
        pred = pred.max(predicted[d * nb + y]);
    }
    pred
}

/// Sub-cell offsets of the peak at (d, b): (bins, directions), from parabolas through the
/// log energies of the neighbouring bins and directions.
fn refine(v: &PositionView, d: usize, b: usize) -> (f64, f64) {
    let e0 = v.log_energy(v.energy(d, b));
    let lg_at = |dd: i64, bb: i64| v.log_energy(v.energy_near(d, b, dd, bb));
    let off_b = parabola(lg_at(0, -1), e0, lg_at(0, 1));
    let off_d = if v.nd > 1 {
        parabola(lg_at(-1, 0), e0, lg_at(1, 0))
    } else {
        0.0
    };
    (off_b, off_d)
}

/// A kept component at angle `theta` and bin b + `off_b`, amplitude `amp`: subtract its
/// footprint from the residual `r` (clamped at 0) and add it to the prediction.
fn subtract(
    v: &PositionView,
    fp: &Footprint,
    r: &mut [f64],
    predicted: &mut [f64],
    (theta, b, off_b): (f64, usize, f64),
    amp: f64,
    kernel_bins: usize,
) {
    let (nb, kb) = (v.nb, kernel_bins as i64);
    let ws: Vec<f64> = v
        .angles()
        .iter()
        .enumerate()
        .map(|(dd, &beam)| fp.w(theta, dd, beam))
        .collect();
    for (dd, &w) in ws.iter().enumerate() {
        if w < 1e-9 {
            continue;
        }
        for bb in (b as i64 - kb).max(0)..=(b as i64 + kb).min(nb as i64 - 1) {
            let f = amp * w * fp.k(bb as f64 - (b as f64 + off_b));
            let i = dd * nb + bb as usize;
            r[i] = (r[i] - f).max(0.0);
            predicted[i] += f;
        }
    }
}

/// CLEAN on the residual `r` of one position.
pub(crate) fn clean(
    v: &PositionView,
    mut r: Vec<f64>,
    fp: &Footprint,
    params: &ExtractValid,
) -> Vec<Mpc> {
    let (nd, nb) = (v.nd, v.nb);
    let guard = 10f64.powf(params.guard_db / 10.0);
    let mut predicted = vec![0.0f64; nd * nb];
    let mut rejected = vec![false; nd * nb];
    let strongest = r.iter().cloned().fold(0.0, f64::max);
    let dr_floor = strongest * 10f64.powf(-params.dynamic_range_db / 10.0);
    let mut out = Vec::new();
    while out.len() < params.max_mpcs {
        let Some((bi, best)) = strongest_open(&r, &rejected) else {
            break;
        };
        if best < v.thr || best < dr_floor {
            break;
        }
        let (d, b) = (bi / nb, bi % nb);
        if best <= guard * predicted_near(&predicted, d, b, nb) {
            rejected[bi] = true;
            continue;
        }
        let (off_b, off_d) = refine(v, d, b);
        let beam = v.angles()[d];
        let (theta, outside) = edge_angle(v, fp, d, b, beam + off_d * v.step);
        let norm = fp.w(theta, d, beam) * fp.k(-off_b);
        let amp = if norm > 0.0 { best / norm } else { best };
        subtract(
            v,
            fp,
            &mut r,
            &mut predicted,
            (theta, b, off_b),
            amp,
            params.kernel_bins,
        );
        if !outside {
            out.push(v.mpc(d, b, amp, (theta - beam) / v.step, off_b));
        }
    }
    out
}
