//! The samples of every quantity, per position ([`Samples`]): arrivals and gaps,
//! perimeter offsets and spacings, rays per cluster, the decays' pairs and σ of each
//! cluster's strongest ray.
//!
//! Takes the rays grouped by (position, cluster), the manifest, the layout and the
//! interior the pose observes; gives the per-position samples the quantities are fitted
//! from.

use super::rays::strongest_of;
use super::Ray;
use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Manifest, C0};
use crate::error::Result;
use crate::fit::geometry::{
    cluster_location, observed_stretches, perimeter_offset, stretch_spacings, Interior,
    OBSERVED_STEP_M,
};
use crate::fit::quantities::{Groups, PairGroups};
use crate::pattern::ArrayPattern;
use crate::units::range_m;
use std::collections::BTreeMap;

/// The samples of every quantity, per position.
pub(super) struct Samples {
    /// Each cluster's first arrival, ns.
    pub(super) first: Groups,
    /// Inter-arrival gaps inside clusters, ns (at least δ).
    pub(super) intra: Groups,
    /// Gaps between the clusters' first arrivals, ns (at least δ).
    pub(super) inter: Groups,
    /// Perimeter offsets folded at the wall (interior clusters), m.
    pub(super) dp: Groups,
    /// The same offsets signed (negative beyond the perimeter): the value's estimate.
    pub(super) dp_signed: Groups,
    /// Every cluster's arc-length coordinate on the perimeter, m.
    pub(super) arcs: Groups,
    /// Complete gaps along the observed perimeter, m.
    pub(super) dc: Groups,
    /// Per position: [observed perimeter length, clusters projected into it].
    pub(super) exposure: Groups,
    /// Rays per cluster.
    pub(super) members: Groups,
    /// (strongest ray's delay ns, its power dB + 40·log10 of its range) per cluster.
    pub(super) cl_power: PairGroups,
    /// (excess delay ns, power relative to the cluster's first ray dB) per ray.
    pub(super) ray_decay: PairGroups,
    /// σ of each cluster's strongest ray, m².
    pub(super) sigma: Groups,
}

impl Samples {
    /// Gather the per-cluster samples, then the per-position gaps and spacings.
    pub(super) fn gather(
        by_cluster: &BTreeMap<(usize, usize), Vec<Ray>>,
        m: &Manifest,
        layout: &Layout,
        region: &Interior,
        delta: f64,
    ) -> Result<Samples> {
        let np = m.positions();
        let mut s = Samples {
            first: vec![Vec::new(); np],
            intra: vec![Vec::new(); np],
            inter: vec![Vec::new(); np],
            dp: vec![Vec::new(); np],
            dp_signed: vec![Vec::new(); np],
            arcs: vec![Vec::new(); np],
            dc: vec![Vec::new(); np],
            exposure: vec![Vec::new(); np],
            members: vec![Vec::new(); np],
            cl_power: vec![Vec::new(); np],
            ray_decay: vec![Vec::new(); np],
            sigma: vec![Vec::new(); np],
        };
        let pattern = ArrayPattern::new(m.array, m.band.center_hz())?;
        let g0 = pattern.gain(0.0, 0.0, m.band.center_hz());
        let lc = C0 / m.band.center_hz();
        let gain_den = g0 * g0 * lc * lc;
        for rs in by_cluster.values() {
            s.add_cluster(rs, m, layout, region, delta, gain_den);
        }
        s.add_spacings(m, layout, region, delta);
        Ok(s)
    }

    /// The samples of one cluster `rs` (non-empty, one position); `gain_den` = G²λ² with G
    /// the array's broadside gain and λ the wavelength at the centre frequency (the radar
    /// equation's σ = E·(4π)³d⁴/(G²λ²)).
    fn add_cluster(
        &mut self,
        rs: &[Ray],
        m: &Manifest,
        layout: &Layout,
        region: &Interior,
        delta: f64,
        gain_den: f64,
    ) {
        let pos = rs[0].position;
        let mut d: Vec<f64> = rs.iter().map(|r| r.delay_ns).collect();
        d.sort_by(f64::total_cmp);
        self.first[pos].push(d[0]);
        self.intra[pos].extend(d.windows(2).map(|w| (w[1] - w[0]).max(delta)));
        let strongest = strongest_of(rs);
        let n = rs.len() as f64;
        let range = rs.iter().map(|r| range_m(r.delay_ns)).sum::<f64>() / n;
        let centroid = cluster_location(&m.poses[pos], range, strongest.angle_rel_deg);
        let off = perimeter_offset(layout, centroid);
        // d_c: every cluster's projection; the observed stretches decide which count
        self.arcs[pos].push(off.arc_m);
        if region.contains(strongest.angle_rel_deg, range) {
            self.dp_signed[pos].push(off.signed_m);
            self.dp[pos].push(off.folded_m);
        }
        self.members[pos].push(n);
        // the strongest ray (the law's first ray, σ_l), range-corrected: the model's own
        // r⁻⁴ at its range removed
        let r0 = range_m(strongest.delay_ns).max(1e-3);
        self.cl_power[pos].push((strongest.delay_ns, strongest.power_db + 40.0 * r0.log10()));
        let first_ray = rs
            .iter()
            .min_by(|a, b| a.delay_ns.total_cmp(&b.delay_ns))
            .expect("non-empty");
        for r in rs {
            if !std::ptr::eq(r, first_ray) {
                self.ray_decay[pos].push((
                    r.delay_ns - first_ray.delay_ns,
                    r.power_db - first_ray.power_db,
                ));
            }
        }
        let d = range_m(strongest.delay_ns);
        let e = 10f64.powf(strongest.power_db / 10.0);
        self.sigma[pos].push(e * (4.0 * std::f64::consts::PI).powi(3) * d.powi(4) / gain_den);
    }

    /// Per position: the gaps between the clusters' first arrivals, and the complete gaps
    /// and exposure along the perimeter observed in `region`.
    fn add_spacings(&mut self, m: &Manifest, layout: &Layout, region: &Interior, delta: f64) {
        let perim = layout.perimeter_length();
        for pos in 0..m.positions() {
            let mut f = self.first[pos].clone();
            f.sort_by(f64::total_cmp);
            self.inter[pos] = f.windows(2).map(|w| (w[1] - w[0]).max(delta)).collect();
            let stretches = observed_stretches(layout, &m.poses[pos], region, OBSERVED_STEP_M);
            let (gaps, length, count) = stretch_spacings(&self.arcs[pos], &stretches, perim);
            self.dc[pos] = gaps;
            self.exposure[pos] = vec![length, count as f64];
        }
    }

    /// The clusters' (strongest ray's delay, its range-corrected power) relative to the
    /// position's earliest.
    pub(super) fn cluster_pairs(&self) -> PairGroups {
        self.cl_power
            .iter()
            .map(|v| {
                let t0 = v.iter().map(|x| x.0).fold(f64::INFINITY, f64::min);
                let p0 = v.iter().find(|x| x.0 == t0).map(|x| x.1).unwrap_or(0.0);
                v.iter().map(|x| (x.0 - t0, x.1 - p0)).collect()
            })
            .collect()
    }
}
