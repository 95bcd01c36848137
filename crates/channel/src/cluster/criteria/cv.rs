//! The cross-validated criteria, CrossValidated (the default) and CrossValidatedShared:
//! −2 × the leave-one-out predictive log-likelihood (Smyth 2000) of a mixture with a
//! Gaussian delay × Laplacian angle component.
//!
//! Each MPC i is scored by the mixture fitted to K's partition without it, plus a "new
//! cluster" term as in the Chinese-restaurant predictive:
//!
//! ln[Σ_k n_k^{(−i)}/(n − 1 + α) · f_k^{(−i)}(τ_i, θ_i) + α/(n − 1 + α) · g],
//!
//! g uniform over the position's delay span (at least 1 ns) × the scanned sector
//! (`sector_deg`, 180° by default, from the MPC table's metadata), α = `new_cluster_weight`
//! (1, the usual default, not tuned). The largest total wins, K = 1 included. There is no
//! penalty term: the held-out MPC pays for over-fitting itself. Without g, the MPC of a
//! cluster of one or two (a single echo, a far object) would be scored by the distant other
//! clusters alone, far below any cluster's density, so every partition that isolated it
//! would lose to merging it.
//!
//! * Per-cluster scales (`CrossValidated`): a cluster left with fewer than 2 members drops
//!   out and its MPC is scored by the others and g.
//! * Shared scales (`CrossValidatedShared`, `--criterion cv-shared`): the delay standard
//!   deviation and the angular Laplacian scale are pooled within-cluster MLEs over the
//!   clusters of two or more members, each cluster keeping its own location and weight (the
//!   channel model's clusters share λ and the AoA law). The held-out MPC leaves its own
//!   cluster's sums (taken about the component already fitted to the cluster without it),
//!   and its cluster stays a component while it keeps one member, as every singleton does,
//!   since the pooled scales define it.
//!
//! An MPC with no component at all (its own cluster too small, no other cluster, no
//! new-cluster term) scores ln 1e-300, so such partitions lose.

use super::mixture::{fit_component, log_density, log_sum_exp, Component, Family};
use crate::cluster::params::ClusterValid;

/// Within-cluster sums of one cluster for the shared scales about its fitted component `c`
/// (mean delay, median angle): [Σ (τ − mean τ)², Σ |θ − median θ|, members], zero for a
/// cluster of fewer than two (it has no spread).
fn spread_sums(raw: &[[f64; 2]], m: &[usize], c: Option<&Component>) -> [f64; 3] {
    let Some(c) = c.filter(|_| m.len() >= 2) else {
        return [0.0; 3];
    };
    let ss = m.iter().map(|&i| (raw[i][0] - c.delay.0).powi(2)).sum();
    let sa = m.iter().map(|&i| (raw[i][1] - c.angle.0).abs()).sum();
    [ss, sa, m.len() as f64]
}

/// The pooled delay standard deviation and angular Laplacian scale from summed
/// [`spread_sums`], floored at the resolutions (the floors when no cluster has two members).
fn pooled_scales(t: [f64; 3], res: [f64; 2]) -> (f64, f64) {
    if t[2] <= 0.0 {
        return (res[0], res[1]);
    }
    (
        (t[0].max(0.0) / t[2]).sqrt().max(res[0]),
        (t[1].max(0.0) / t[2]).max(res[1]),
    )
}

/// A partition's fitted mixture and the constants of its leave-one-out score.
struct LeaveOneOut<'a> {
    raw: &'a [[f64; 2]],
    labels: &'a [usize],
    members: &'a [Vec<usize>],
    comps: &'a [Option<Component>],
    fam: Family,
    res: [f64; 2],
    shared: bool,
    /// n − 1 + α: the predictive weights' denominator.
    norm: f64,
    /// Whether the new-cluster term enters (α > 0).
    with_new: bool,
    /// ln[α/(n − 1 + α) · g].
    ln_new: f64,
    /// Shared scales: each cluster's [`spread_sums`] (empty otherwise) and their total.
    csums: Vec<[f64; 3]>,
    total_sums: [f64; 3],
}

impl LeaveOneOut<'_> {
    /// The component of MPC i's own cluster fitted without it (per-cluster scales need two
    /// members; shared scales give one member a component too: its location, the pooled
    /// scales, as every other singleton).
    fn held_out(&self, own: &[usize]) -> Option<Component> {
        if own.len() >= if self.shared { 1 } else { 2 } {
            fit_component(self.raw, own, self.fam, self.res)
        } else {
            None
        }
    }

    /// The pooled scales without MPC i: its cluster's full sums out, the sums without it in.
    fn shared_scales_without(
        &self,
        i: usize,
        own: &[usize],
        held: Option<&Component>,
    ) -> (f64, f64) {
        let b = spread_sums(self.raw, own, held);
        let a = &self.csums[self.labels[i]];
        pooled_scales(
            [0, 1, 2].map(|j| self.total_sums[j] - a[j] + b[j]),
            self.res,
        )
    }

    /// ln of MPC i's leave-one-out predictive density.
    fn log_predictive(&self, i: usize) -> f64 {
        let p = &self.raw[i];
        let own: Vec<usize> = self.members[self.labels[i]]
            .iter()
            .copied()
            .filter(|&j| j != i)
            .collect();
        let held = self.held_out(&own);
        let scales = self
            .shared
            .then(|| self.shared_scales_without(i, &own, held.as_ref()));
        let k = self.members.len();
        log_sum_exp(
            (0..k)
                .filter_map(|c| {
                    let comp = if c == self.labels[i] {
                        held
                    } else {
                        self.comps[c]
                    };
                    let comp = match scales {
                        Some((sd, b)) => comp.map(|q| Component {
                            delay: (q.delay.0, sd),
                            angle: (q.angle.0, b),
                            ..q
                        }),
                        None => comp,
                    };
                    comp.map(|q| (q.members / self.norm).ln() + log_density(&q, p, self.fam))
                })
                .chain(self.with_new.then_some(self.ln_new)),
        )
    }
}

/// −2 × the leave-one-out log-likelihood of the partition `labels` (clusters `members`,
/// fitted components `comps`), with per-cluster or `shared` scales.
pub(crate) fn cross_validated(
    raw: &[[f64; 2]],
    labels: &[usize],
    members: &[Vec<usize>],
    comps: &[Option<Component>],
    fam: Family,
    params: &ClusterValid,
    shared: bool,
) -> f64 {
    let n = raw.len();
    let res = [params.delay_res_ns, params.angle_res_deg];
    // the "new cluster" density g: uniform over the position's delay span (at least
    // 1 ns) × the scanned sector, entered with the Chinese-restaurant weight α/(n − 1 + α)
    let (lo, hi) = raw
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[0]), b.max(p[0]))
        });
    let alpha = params.new_cluster_weight;
    let norm = (n - 1) as f64 + alpha;
    let ln_new = (alpha / norm).ln() - ((hi - lo).max(1.0) * params.sector_deg).ln();
    // shared scales: each cluster's within sums and their total
    let csums: Vec<[f64; 3]> = if shared {
        members
            .iter()
            .zip(comps)
            .map(|(m, c)| spread_sums(raw, m, c.as_ref()))
            .collect()
    } else {
        Vec::new()
    };
    let total_sums = csums
        .iter()
        .fold([0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
    let loo = LeaveOneOut {
        raw,
        labels,
        members,
        comps,
        fam,
        res,
        shared,
        norm,
        with_new: alpha > 0.0,
        ln_new,
        csums,
        total_sums,
    };
    let mut total = 0.0;
    for i in 0..n {
        let l = loo.log_predictive(i);
        total += if l.is_finite() { l } else { (1e-300f64).ln() };
    }
    -2.0 * total
}

#[cfg(test)]
mod tests {
    use super::super::likelihood_criterion;
    use super::super::mixture::median;
    use super::*;
    use crate::cluster::params::{ClusterParams, Criterion};
    use crate::params::ParamGuard;

    /// The shared-scale leave-one-out score against a brute-force recomputation: for each
    /// MPC, remove it, refit every cluster's location (mean delay, median angle) and the
    /// pooled scales (over clusters of two or more) from scratch, score it.
    #[test]
    fn shared_scale_score_equals_brute_force_leave_one_out() {
        let raw = [
            [10.0, -20.0],
            [11.0, -18.0],
            [12.5, -25.0],
            [10.5, -15.0],
            [30.0, 40.0],
            [31.5, 44.0],
            [55.0, 0.0],
        ];
        let labels = [0, 0, 0, 0, 1, 1, 2];
        let p = ClusterParams::default().sector_deg(120.0).check().unwrap();
        let got = likelihood_criterion(&raw, &labels, Criterion::CrossValidatedShared, &p);
        let (n, res) = (raw.len(), [p.delay_res_ns, p.angle_res_deg]);
        let norm = (n - 1) as f64 + p.new_cluster_weight;
        let (lo, hi) = (10.0f64, 55.0f64);
        let ln_new = (p.new_cluster_weight / norm).ln() - ((hi - lo) * 120.0).ln();
        let mut total = 0.0;
        for i in 0..n {
            let groups: Vec<Vec<usize>> = (0..3)
                .map(|c| (0..n).filter(|&j| j != i && labels[j] == c).collect())
                .collect();
            let (mut ss, mut sa, mut m) = (0.0, 0.0, 0.0);
            let mut locs = Vec::new();
            for g in &groups {
                if g.is_empty() {
                    continue;
                }
                let mean = g.iter().map(|&j| raw[j][0]).sum::<f64>() / g.len() as f64;
                let mut a: Vec<f64> = g.iter().map(|&j| raw[j][1]).collect();
                let med = median(&mut a);
                if g.len() >= 2 {
                    ss += g.iter().map(|&j| (raw[j][0] - mean).powi(2)).sum::<f64>();
                    sa += g.iter().map(|&j| (raw[j][1] - med).abs()).sum::<f64>();
                    m += g.len() as f64;
                }
                locs.push((g.len() as f64, mean, med));
            }
            let (sd, b) = ((ss / m).sqrt().max(res[0]), (sa / m).max(res[1]));
            let mut terms: Vec<f64> = locs
                .iter()
                .map(|&(w, mu, med)| {
                    (w / norm).ln()
                        - 0.5 * (2.0 * std::f64::consts::PI).ln()
                        - sd.ln()
                        - 0.5 * ((raw[i][0] - mu) / sd).powi(2)
                        - (2.0 * b).ln()
                        - (raw[i][1] - med).abs() / b
                })
                .collect();
            terms.push(ln_new);
            total += log_sum_exp(terms.into_iter());
        }
        let want = -2.0 * total;
        assert!((got - want).abs() < 1e-9 * want.abs(), "{got} vs {want}");
    }

    #[test]
    fn new_cluster_density_spreads_over_the_scanned_sector() {
        let x = [
            [10.0, 0.0],
            [10.5, 2.0],
            [11.0, -1.0],
            [11.5, 1.0],
            [40.0, 30.0],
        ];
        let one = [0; 5];
        let cv = |w: f64| {
            let p = ClusterParams::default().sector_deg(w).check().unwrap();
            likelihood_criterion(&x, &one, Criterion::CrossValidated, &p)
        };
        // half the sector doubles g: each MPC's leave-one-out density gains between 0 and
        // ln 2, so −2·ln L drops, by at most 2·5·ln 2
        let (wide, narrow) = (cv(180.0), cv(90.0));
        assert!(narrow < wide && wide - narrow <= 10.0 * 2f64.ln() + 1e-9);
        for bad in [0.0, 400.0, f64::NAN] {
            assert!(ClusterParams::default().sector_deg(bad).check().is_err());
        }
    }
}
