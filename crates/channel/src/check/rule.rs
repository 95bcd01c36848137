//! The check's rule (module docs of [`super`]): the Monte Carlo rank p-value, the draws'
//! leave-one-out distances and the Westfall–Young single-step max-T test.
//!
//! Takes distances (the measured table's and the draws', per statistic); gives p-values.

/// (1 + #{x ∈ null : x ≥ obs}) / (#null + 1): the Monte Carlo p-value of `obs` against
/// `null` (ties counted against `obs`).
pub fn rank_p(obs: f64, null: &[f64]) -> f64 {
    let k = null.iter().filter(|&&x| x >= obs).count();
    (1 + k) as f64 / (null.len() + 1) as f64
}

/// The leave-one-out distances of the R draws of one statistic: D_i = the median of draw
/// i's distances to the other draws (`pair(i, j)`, j ≠ i) and to the measured table
/// (`measured[i]`).
pub fn leave_one_out(measured: &[f64], pair: impl Fn(usize, usize) -> f64) -> Vec<f64> {
    let r = measured.len();
    (0..r)
        .map(|i| {
            let mut v: Vec<f64> = (0..r).filter(|&j| j != i).map(|j| pair(i, j)).collect();
            v.push(measured[i]);
            crate::stats::median(&v).unwrap_or(f64::NAN)
        })
        .collect()
}

/// The Westfall–Young single-step max-T test (module docs) of the measured table's
/// distances `obs` (one per statistic) against the draws' `draws` (per statistic, one per
/// draw): per statistic the adjusted p-value p̃_s, and the joint p = min_s p̃_s.
pub fn max_t(obs: &[f64], draws: &[Vec<f64>]) -> (Vec<f64>, f64) {
    let r = draws.first().map_or(0, Vec::len);
    let mut z_obs = Vec::with_capacity(obs.len());
    let mut t_draws = vec![f64::NEG_INFINITY; r];
    for (o, d) in obs.iter().zip(draws) {
        let all: Vec<f64> = std::iter::once(*o).chain(d.iter().copied()).collect();
        let centre = crate::stats::median(&all).unwrap_or(f64::NAN);
        let dev: Vec<f64> = all.iter().map(|v| (v - centre).abs()).collect();
        // the larger of 1.4826·MAD and the mean absolute deviation (a scale remains when
        // more than half of the tables tie and the MAD is 0)
        let scale = (1.4826 * crate::stats::median(&dev).unwrap_or(f64::NAN))
            .max(dev.iter().sum::<f64>() / dev.len() as f64)
            .max(1e-12);
        z_obs.push((o - centre) / scale);
        for (t, v) in t_draws.iter_mut().zip(d) {
            *t = t.max((v - centre) / scale);
        }
    }
    let adjusted: Vec<f64> = z_obs.iter().map(|&z| rank_p(z, &t_draws)).collect();
    let joint = adjusted.iter().copied().fold(1.0, f64::min);
    (adjusted, joint)
}
