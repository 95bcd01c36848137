//! The baseline picker: every cell that is a strict maximum of its 3×3 neighbourhood and at
//! or above the threshold F·10^(margin/10), strongest first, at most `max_mpcs`. No
//! footprint is subtracted, so side lobes and range side lobes become MPCs.

use super::{Mpc, PositionView};

/// Whether cell (d, b) of the residual `r` is a strict maximum of its 3×3 neighbourhood.
fn is_local_max(v: &PositionView, r: &[f64], d: usize, b: usize) -> bool {
    let (nd, nb) = (v.nd, v.nb);
    let e = r[d * nb + b];
    for dd in -1i64..=1 {
        for db2 in -1i64..=1 {
            if dd == 0 && db2 == 0 {
                continue;
            }
            let (x, y) = (d as i64 + dd, b as i64 + db2);
            if x >= 0
                && y >= 0
                && (x as usize) < nd
                && (y as usize) < nb
                && r[x as usize * nb + y as usize] >= e
            {
                return false;
            }
        }
    }
    true
}

/// The local maxima of the energies `r` above the threshold, strongest first.
pub(crate) fn local_maxima(v: &PositionView, r: &[f64], max_mpcs: usize) -> Vec<Mpc> {
    let mut out = Vec::new();
    for d in 0..v.nd {
        for b in 0..v.nb {
            let e = r[d * v.nb + b];
            if e < v.thr {
                continue;
            }
            if is_local_max(v, r, d, b) {
                out.push(v.mpc(d, b, e, 0.0, 0.0));
            }
        }
    }
    out.sort_by(|a, b| b.power_db.total_cmp(&a.power_db));
    out.truncate(max_mpcs);
    out
}
