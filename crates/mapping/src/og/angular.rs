//! Echo bearings within a scan: one pose's energies at a bin, across its directions,
//! decomposed into point echoes ("CLEAN across directions"), so a detection credits the
//! cells at its echo's bearing instead of its whole range ring.
//!
//! Takes a pose's energy profiles, its detections, the mapper's two-way pattern
//! ([`ObservationModel::broadside_weight`]) and the detector's threshold η_E; gives per bin
//! the components (bearing θ_c, power P_c, bearing spread σ_c). Bearings are in the device
//! frame (relative to the pose's heading), as [`crate::grid::PoseGeometry::theta`].
//!
//! Equations and choices:
//! * at bin k the energies across directions are modelled as incoherent point echoes,
//!   E_d = Σ_c P_c·w_d(θ_c) (+ noise), w_d the two-way pattern of direction d referred to
//!   the broadside gain (electronic steering's scan loss included; the direction's own
//!   normalised pattern for mechanical steering);
//! * greedy deconvolution (Högbom's CLEAN over the directions): among the directions that
//!   detect at k and are not used yet, take the one with the largest residual r_d1; stop when
//!   it is ≤ η_E (what is left is not an echo the detector would report). Its bearing is the
//!   least-squares fit of P·w_d(θ) to the residuals of d1 and its two neighbours over θ within
//!   half a direction step of θ_d1 on a 0.05° grid (amplitude comparison between adjacent
//!   beams, as sequential lobing does), P = Σ r_d w_d(θ)/Σ w_d(θ)², a tie going to the
//!   bearing nearer θ_d1; neighbours without a sweep are left out, and with fewer than two
//!   directions the bearing is θ_d1 and P = r_d1 (nothing to compare). Neighbours are
//!   adjacent in the direction list: a full turn's first and last directions are not. The
//!   component's P·w_d(θ_c) is then subtracted from every direction's residual (floored at
//!   0);
//! * bearing spread: the amplitude-comparison standard error σ_c = θ_3dB/(k_m·√(2·SNR)),
//!   k_m = 1.6 (the monopulse slope, Skolnik, *Radar Handbook* ch. 9), θ_3dB the direction's
//!   two-way main-lobe width (at `main_lobe_db`, −3 dB by default), SNR = P_c/η_E (the threshold stands for the noise: a lower bound
//!   on the SNR, so a wider spread), at least the 0.05° grid step;
//! * a detection of direction d at bin k is explained by the components fitted from d
//!   (whose residual peaked in d): each echo is credited once per scan, by the direction
//!   that looks at it best, even when it falls between two main lobes. A detection that
//!   fitted none (leakage of an echo another direction fitted, or a residual below η_E once
//!   the stronger echoes are subtracted) credits nothing. The credit of its range ring goes
//!   to the cells near its components' bearings, weighted by exp(−½(Δθ/σ_c)²), Δθ the gap
//!   between the cell's angular extent and θ_c ([`Components::affinity`]); when no cell
//!   the ring may credit (visible, within the credit depth) lies within 2σ_c of a
//!   component (its echo is behind the visibility polygon), the detection is withheld
//!   rather than its credit moved to a cell far from the bearing.

use crate::energy::EnergyMatrix;
use crate::grid::ObservationModel;
use crate::units::wrap_rad;

/// Amplitude-comparison slope k_m of the bearing error.
const K_M: f64 = 1.6;
/// Bearing grid of the fit, rad (0.05°, the gain tables' step).
const STEP_RAD: f64 = 0.05 * std::f64::consts::PI / 180.0;

/// The affinity of a cell 2σ_c from a component's bearing, e^−2: below it on every cell
/// the ring may credit, the detection is withheld (module docs).
pub const MIN_AFFINITY: f64 = 0.135_335_283_236_612_7;

/// One point echo of a bin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Component {
    /// Bearing in the device frame (relative to the heading), rad.
    pub theta: f64,
    /// Power P_c (energy at the peak of its pattern).
    pub power: f64,
    /// Bearing spread σ_c, rad.
    pub sigma: f64,
    /// The direction it was fitted from (its peak), whose detection it explains.
    pub owner: usize,
}

/// The components of one pose, per bin.
#[derive(Debug, Clone, Default)]
pub struct Components {
    /// `by_bin[k]`: the components of bin k (empty where nothing was detected).
    pub by_bin: Vec<Vec<Component>>,
}

/// What the deconvolution needs of the run: the pattern across directions and the
/// main-lobe widths.
#[derive(Debug, Clone)]
pub struct AngularModel {
    /// Steering angle of each direction, rad.
    theta_d: Vec<f64>,
    /// Two-way −3 dB width of each direction, rad.
    width: Vec<f64>,
    /// Half the spacing to the neighbouring directions, rad (the bearing search range).
    half_step: Vec<f64>,
}

impl AngularModel {
    /// From the observation model.
    pub fn new(model: &ObservationModel) -> AngularModel {
        let nd = model.directions();
        let theta_d: Vec<f64> = (0..nd).map(|d| model.direction_rad(d)).collect();
        let main_w = model.params.main_weight();
        let width = (0..nd)
            .map(|d| {
                // walk out from the peak on the 0.05° grid until the weight drops below main_w
                let edge = |sign: f64| {
                    let mut x = 0.0;
                    while x < std::f64::consts::PI
                        && model.weight(d, theta_d[d] + sign * x) >= main_w
                    {
                        x += STEP_RAD;
                    }
                    x
                };
                (edge(1.0) + edge(-1.0)).max(STEP_RAD)
            })
            .collect();
        let half_step = (0..nd)
            .map(|d| {
                let gap = |o: usize| wrap_rad(theta_d[o] - theta_d[d]).abs();
                let mut g = f64::INFINITY;
                if d > 0 {
                    g = g.min(gap(d - 1));
                }
                if d + 1 < nd {
                    g = g.min(gap(d + 1));
                }
                if g.is_finite() {
                    g / 2.0
                } else {
                    std::f64::consts::PI / 2.0
                }
            })
            .collect();
        AngularModel {
            theta_d,
            width,
            half_step,
        }
    }

    /// The components of pose `p` from its energies and detections `det[d][k]` at
    /// threshold `eta` (module docs).
    pub fn components(
        &self,
        model: &ObservationModel,
        em: &EnergyMatrix,
        p: usize,
        det: &[Vec<bool>],
        eta: f64,
    ) -> Components {
        let nd = det.len();
        let bins = det.iter().map(|d| d.len()).min().unwrap_or(0);
        let mut by_bin = vec![Vec::new(); bins];
        let profiles: Vec<Option<&[f64]>> = (0..nd)
            .map(|d| em.has(p, d).then(|| em.profile(p, d)))
            .collect();
        let has: Vec<bool> = profiles.iter().map(Option::is_some).collect();
        let mut resid = vec![0.0f64; nd];
        let mut used = vec![false; nd];
        for (k, out) in by_bin.iter_mut().enumerate() {
            if !(0..nd).any(|d| det[d][k]) {
                continue;
            }
            for d in 0..nd {
                resid[d] = profiles[d].map_or(0.0, |pr| pr[k]);
                used[d] = false;
            }
            loop {
                let d1 = (0..nd)
                    .filter(|&d| det[d][k] && !used[d])
                    .max_by(|&a, &b| resid[a].total_cmp(&resid[b]).then(b.cmp(&a)));
                let Some(d1) = d1 else { break };
                used[d1] = true;
                if resid[d1] <= eta {
                    break;
                }
                let c = self.fit_one(model, &resid, &has, d1, eta);
                for (d, r) in resid.iter_mut().enumerate() {
                    if has[d] {
                        *r = (*r - c.power * model.broadside_weight(d, c.theta)).max(0.0);
                    }
                }
                out.push(c);
            }
        }
        Components { by_bin }
    }

    /// The bearing and power of one echo peaking in direction `d1` (module docs); `has[d]`:
    /// direction d has a sweep.
    fn fit_one(
        &self,
        model: &ObservationModel,
        resid: &[f64],
        has: &[bool],
        d1: usize,
        eta: f64,
    ) -> Component {
        let nd = resid.len();
        let near: Vec<usize> = (d1.saturating_sub(1)..(d1 + 2).min(nd))
            .filter(|&d| has[d])
            .collect();
        let span = self.half_step[d1];
        let steps = (span / STEP_RAD + 1e-9).floor() as i64;
        // with one direction the bearing is not identifiable: its boresight, its energy
        let mut best = (f64::INFINITY, self.theta_d[d1], resid[d1]);
        if near.len() >= 2 {
            // 0, +1, −1, +2, …: a tie goes to the bearing nearer the boresight
            for j in (0..=2 * steps).map(|i| if i % 2 == 1 { (i + 1) / 2 } else { -(i / 2) }) {
                let th = self.theta_d[d1] + j as f64 * STEP_RAD;
                let w: Vec<f64> = near
                    .iter()
                    .map(|&d| model.broadside_weight(d, th))
                    .collect();
                let (mut num, mut den) = (0.0, 0.0);
                for (&d, &wd) in near.iter().zip(&w) {
                    num += resid[d] * wd;
                    den += wd * wd;
                }
                if den <= 0.0 {
                    continue;
                }
                let pw = num / den;
                let cost: f64 = near
                    .iter()
                    .zip(&w)
                    .map(|(&d, &wd)| (resid[d] - pw * wd).powi(2))
                    .sum();
                if cost < best.0 {
                    best = (cost, th, pw);
                }
            }
        }
        let (_, theta, power) = best;
        let snr = (power / eta).max(1e-12);
        let sigma = (self.width[d1] / (K_M * (2.0 * snr).sqrt())).max(STEP_RAD);
        Component {
            theta: wrap_rad(theta),
            power,
            sigma,
            owner: d1,
        }
    }
}

impl Components {
    /// The components of bin `k` that direction `d` explains (fitted from it).
    pub fn of_direction(&self, d: usize, k: usize) -> Vec<&Component> {
        self.by_bin
            .get(k)
            .map(|cs| cs.iter().filter(|c| c.owner == d).collect())
            .unwrap_or_default()
    }

    /// Affinity in [0, 1] of a cell of bearing `theta` and angular half-extent `half` (rad)
    /// with the components `cs`: exp(−½(Δθ/σ_c)²) of the nearest, Δθ the gap between the
    /// cell's extent and θ_c (0 when the cell spans it).
    pub fn affinity(cs: &[&Component], theta: f64, half: f64) -> f64 {
        cs.iter()
            .map(|c| {
                let gap = (wrap_rad(theta - c.theta).abs() - half).max(0.0);
                (-0.5 * (gap / c.sigma).powi(2)).exp()
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::Campaign;
    use crate::energy::EnergyMeta;
    use crate::params::ParamGuard;
    use crate::GridParams;
    use std::path::Path;

    /// The built-in corridor's manifest (5° directions, N = 400), 480 bins.
    fn model() -> ObservationModel {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/corridor");
        let c = Campaign::load(&Path::new(dir).join("campaign.toml")).unwrap();
        let grid = GridParams::default().check().unwrap();
        let spec = crate::reference::GridSpec {
            x0_m: -1.0,
            y0_m: -6.0,
            rows: 120,
            cols: 120,
            cell_m: grid.cell_m,
        };
        ObservationModel::new(spec, &grid, &c.manifest, 480, 1.0 / 6.0, 20).unwrap()
    }

    /// One pose whose bin `k` holds point echoes (bearing rad, power) seen through the
    /// mapper's pattern, plus `floor` in every bin.
    fn pose(model: &ObservationModel, k: usize, echoes: &[(f64, f64)], floor: f64) -> EnergyMatrix {
        let nd = model.directions();
        let bins = model.bins;
        let mut data = vec![floor; nd * bins];
        for d in 0..nd {
            for &(th, pw) in echoes {
                data[d * bins + k] += pw * model.broadside_weight(d, th);
            }
        }
        EnergyMatrix {
            meta: EnergyMeta {
                schema_version: 1,
                bin_width_ns: 1.0 / 6.0,
                pulses: 1,
                n0: floor,
                enbw: 1.0,
                tw: 1.0,
                array: String::new(),
                coupling: String::new(),
                all: Vec::new(),
                missing: Vec::new(),
            },
            positions: 1,
            angles_rel_deg: (0..nd)
                .map(|d| model.direction_rad(d).to_degrees())
                .collect(),
            headings_deg: vec![0.0],
            bins,
            first: 0,
            data,
        }
    }

    /// Every direction above `eta` at bin `k` detects there.
    fn detections(em: &EnergyMatrix, k: usize, eta: f64) -> Vec<Vec<bool>> {
        (0..em.directions())
            .map(|d| {
                let mut v = vec![false; em.bins];
                v[k] = em.profile(0, d)[k] > eta;
                v
            })
            .collect()
    }

    #[test]
    fn clean_resolves_echoes_between_directions_and_withholds_their_leakage() {
        let m = model();
        let am = AngularModel::new(&m);
        let (k, eta) = (200, 1.0);
        // a strong echo 2.3° off a boresight, a weaker one 30° away: both within
        // ~0.1° at their powers (±5 %); their side lobes detect in other directions too
        let (t1, t2) = (7.3f64.to_radians(), (-23.0f64).to_radians());
        let em = pose(&m, k, &[(t1, 1e4), (t2, 300.0)], 0.01);
        let det = detections(&em, k, eta);
        let leaking = det.iter().filter(|d| d[k]).count();
        assert!(leaking > 4, "{leaking} directions detect");
        let cs = am.components(&m, &em, 0, &det, eta);
        let got = &cs.by_bin[k];
        assert!(got.len() >= 2, "{got:?}");
        for (th, pw) in [(t1, 1e4), (t2, 300.0)] {
            let c = got
                .iter()
                .min_by(|a, b| (a.theta - th).abs().total_cmp(&(b.theta - th).abs()))
                .unwrap();
            assert!((c.theta - th).abs() < 0.1f64.to_radians(), "{c:?} for {th}");
            assert!((c.power / pw - 1.0).abs() < 0.05, "{c:?} for {pw}");
            assert!(c.sigma < 1f64.to_radians() && c.sigma >= STEP_RAD, "{c:?}");
        }
        // the stronger echo has the narrower spread
        let s = |th: f64| {
            got.iter()
                .min_by(|a, b| (a.theta - th).abs().total_cmp(&(b.theta - th).abs()))
                .unwrap()
                .sigma
        };
        assert!(s(t1) < s(t2));
        // the weak echo's spread is the amplitude-comparison error at its SNR
        let weak = got
            .iter()
            .min_by(|a, b| (a.theta - t2).abs().total_cmp(&(b.theta - t2).abs()))
            .unwrap();
        let want = am.width[weak.owner] / (K_M * (2.0 * weak.power / eta).sqrt());
        assert!(
            want > STEP_RAD && (weak.sigma - want).abs() < 1e-12,
            "{weak:?} {want}"
        );
        assert!((MIN_AFFINITY - (-2.0f64).exp()).abs() < 1e-15);
        // each echo is credited by one direction, the one it peaks in; its neighbour, which
        // detects its skirt, explains nothing
        let nearest = |th: f64| {
            (0..m.directions())
                .min_by(|&a, &b| {
                    (m.direction_rad(a) - th)
                        .abs()
                        .total_cmp(&(m.direction_rad(b) - th).abs())
                })
                .unwrap()
        };
        assert_eq!(cs.of_direction(nearest(t1), k).len(), 1);
        assert_eq!(cs.of_direction(nearest(t2), k).len(), 1);
        let skirt = nearest(t1) + 1;
        assert!(det[skirt][k], "the skirt detected at {skirt}");
        assert!(cs.of_direction(skirt, k).is_empty());
        // bins without a detection have no components
        assert!(cs.by_bin[k - 1].is_empty() && cs.by_bin[k + 1].is_empty());
    }

    #[test]
    fn a_neighbour_without_a_sweep_is_left_out_of_the_fit() {
        let m = model();
        let am = AngularModel::new(&m);
        let (k, eta) = (200, 1.0);
        let t1 = 7.3f64.to_radians();
        let mut em = pose(&m, k, &[(t1, 1e4)], 0.01);
        let d = (0..m.directions())
            .min_by(|&a, &b| {
                (m.direction_rad(a) - t1)
                    .abs()
                    .total_cmp(&(m.direction_rad(b) - t1).abs())
            })
            .unwrap();
        // the neighbour on the echo's side has no sweep (NaN profile, listed missing)
        em.meta.missing.push((0, d + 1));
        for v in &mut em.data[(d + 1) * em.bins..(d + 2) * em.bins] {
            *v = f64::NAN;
        }
        let mut det = detections(&em, k, eta);
        det[d + 1][k] = false;
        let cs = am.components(&m, &em, 0, &det, eta);
        let c = cs.of_direction(d, k);
        assert_eq!(c.len(), 1, "{:?}", cs.by_bin[k]);
        // d and d − 1 still compare: the bearing within 0.1°, the power within 5 %
        assert!((c[0].theta - t1).abs() < 0.1f64.to_radians(), "{:?}", c[0]);
        assert!((c[0].power / 1e4 - 1.0).abs() < 0.05, "{:?}", c[0]);
    }

    #[test]
    fn affinity_is_one_across_the_cell_and_falls_with_the_spread() {
        let c = Component {
            theta: 0.1,
            power: 1.0,
            sigma: 0.01,
            owner: 0,
        };
        let cs = [&c];
        assert_eq!(Components::affinity(&cs, 0.1, 0.0), 1.0);
        assert_eq!(Components::affinity(&cs, 0.104, 0.005), 1.0);
        let one_sigma = Components::affinity(&cs, 0.12, 0.01);
        assert!((one_sigma - (-0.5f64).exp()).abs() < 1e-12, "{one_sigma}");
        assert!(Components::affinity(&cs, 0.2, 0.0) < 1e-10);
        assert_eq!(Components::affinity(&[], 0.1, 0.0), 0.0);
    }
}
