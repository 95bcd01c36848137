//! What a scan can see: the occluder of every beam and the visibility of every cell from one
//! pose, shared by both mappers (DESIGN §2 "Mapping").
//!
//! Takes the run's [`ObservationModel`], the pose's energy profiles with their detections
//! and, optionally, the current binary map (the mapper's own belief, never the reference);
//! gives per direction the *occluder* bin (the first opaque surface the beam meets) and per
//! cell a [`Visibility`]: whether occupancy evidence may be credited to it and whether it
//! may be found free.
//!
//! Model (at 60 GHz walls and objects are opaque; a beam sees up to its first surface):
//! * side-lobe test: a detection in bin k of direction d is *explained by a side lobe* when
//!   E_d(k) < β_s·w_d(θ_d')·max_{|k'−k|≤1} E_d'(k') for some direction d' outside the main
//!   lobe of d (w_d(θ_d') the two-way weight of d towards the boresight of d');
//! * occluder of direction d: the strongest detection not explained by a side lobe (the
//!   first of equals), unless an earlier such detection lies on a *mapped surface* — an
//!   occupied cell of the current map on the boresight ray within ±g of the bin's range (g
//!   the guard below) — in which case the first of those. Why: the
//!   surface the main lobe meets first returns its echo at the full two-way gain, so without
//!   a map the strongest echo is the best guess of it (an earlier weaker one is more likely
//!   leakage the side-lobe test cannot reject); but a multi-bounce echo (the mirror image of
//!   a strong reflector through a wall) can be stronger than the wall's own diffuse echo,
//!   and once the map holds the wall the echo at the wall's range is the surface and the
//!   later stronger one is multipath. A false occupied cell the scan has no echo at does
//!   not become an occluder, so it can still be cleared; a mapped surface beyond the
//!   strongest echo does not move the occluder back (a new object in front of it);
//! * visibility polygon of the pose: per direction the occluder range R_d = k_d·c·T_b/2
//!   (the last bin's range when the direction has no occluder), interpolated between the
//!   boresights θ_d linearly in 1/R (for a straight wall 1/R(θ) = cos(θ − θ_n)/D, a
//!   cosine, so the interpolation is within h²/8 of it, 0.1 % at 5° steps however grazing
//!   the incidence; R itself grows without bound towards grazing and is not), held constant beyond the first and last boresight; bearings
//!   outside the −3 dB main lobe of every direction (behind the radar) are not seen at all:
//!   no main lobe looked there, so side- and back-lobe echoes are credited to none of them;
//! * a cell at range r and bearing θ has depth δ = r − R(θ); it may receive occupancy
//!   evidence when δ ≤ g and free evidence when δ < −g, with the guard
//!   g = cell·√2/2 + 2 bins (half a cell diagonal plus the window kernel's half-width:
//!   cells straddling the surface are neither cleared nor cut off);
//! * a detection of direction d in a bin more than g beyond its occluder is withheld
//!   (shadowed, not observed): it is multipath or an echo from behind the surface, and no
//!   cell it could be credited to is visible;
//! * silent directions ([`SilentBound`], chosen by the mapper; the OG's `bound_silent`): a
//!   direction with a sweep but no occluder (its detections, if any, all explained by side
//!   lobes) is at the maximum range with `off` (the EKF's default; the OG's is `nearer`,
//!   `OgParams::bound_silent`). Indoors every bearing ends at a
//!   surface, and a beam meeting a smooth wall obliquely sends its specular echo elsewhere,
//!   so its silence does not mean the space beyond is open. `leak` bounds it at its first
//!   detection (a leak says a surface lies at that range somewhere in the beam's lobes), or
//!   leaves it out of the polygon like a missing sweep when it has none; but a leak can lie
//!   beyond the wall the beam actually meets (the leak of a farther surface). `nearer`
//!   bounds it at the nearer of its first detection and R_int, the range interpolated
//!   linearly in 1/R between the nearest directions with an occluder on either side (held
//!   constant beyond the outermost; the polygon's own rule, exact within h²/8 for a straight
//!   wall through both neighbours' occluders); with neither, at the maximum range. Both
//!   only shrink the polygon: fewer cells cleared by that beam and fewer visible to the
//!   range rings of the others.
//!
//! Cost per pose: the side-lobe test O(directions² · detections), the polygon O(cells in
//! range), the mapped-surface test O(directions · range / cell).

use super::{bucket_of, ObservationModel, PoseGeometry, BUCKETS};
use crate::energy::EnergyMatrix;
use crate::units::C0;
use std::f64::consts::PI;

/// The constants of the occlusion model of one run (see the module docs).
#[derive(Debug, Clone)]
pub struct Occlusion {
    /// cross[d][d'] = two-way weight of direction d towards the boresight of direction d'.
    cross: Vec<Vec<f64>>,
    /// Side-lobe margin β_s (linear).
    side_margin: f64,
    /// Main-lobe two-way weight.
    main_w: f64,
    /// First usable bin.
    pub min_bin: usize,
    /// Range of one bin, m (c·T_b/2).
    pub bin_m: f64,
    /// Guard g, m.
    pub guard_m: f64,
    /// Per bearing bucket (relative to the heading): inside the −3 dB main lobe of some
    /// direction.
    covered: Vec<bool>,
}

/// How a direction without an occluder (no detection not explained by a side lobe: a
/// *silent* direction) bounds the visibility polygon (module docs, "silent directions").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SilentBound {
    /// At the maximum range, as if the beam had seen through everything.
    Off,
    /// At its first detection (a side-lobe-explained leak); without one, left out of the
    /// polygon like a missing sweep (its neighbours bound it).
    Leak,
    /// At the nearer of its first detection and the range interpolated (linear in 1/R)
    /// between the nearest directions with an occluder on either side.
    Nearer,
}

impl SilentBound {
    /// Every value, in the order the command line lists them.
    pub const ALL: [SilentBound; 3] = [SilentBound::Off, SilentBound::Leak, SilentBound::Nearer];

    /// Name (`off`, `leak`, `nearer`): the command-line value, the serde name and the
    /// `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            SilentBound::Off => "off",
            SilentBound::Leak => "leak",
            SilentBound::Nearer => "nearer",
        }
    }
}

impl std::fmt::Display for SilentBound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SilentBound {
    type Err = crate::error::Error;
    /// Parse a [`SilentBound::name`].
    fn from_str(s: &str) -> crate::error::Result<SilentBound> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "bound_silent", "silent bound")
    }
}

/// The detections of one pose's scan with their occluders.
#[derive(Debug, Clone, Default)]
pub struct ScanEchoes {
    /// Per direction: detected bins (true = detection).
    pub det: Vec<Vec<bool>>,
    /// Per direction: the occluder bin (None: nothing opaque detected).
    pub occluder: Vec<Option<usize>>,
    /// Per direction: the campaign has no sweep there (`[sweeps] missing`); its occluder is
    /// unknown, and the visible region is interpolated over it from its neighbours.
    pub missing: Vec<bool>,
    /// Per direction: the detections not explained by a side lobe, (bin, energy) by
    /// ascending bin — the candidates of the occluder.
    pub main: Vec<Vec<(u32, f64)>>,
}

impl ScanEchoes {
    /// The last observed bin of direction `d`: its occluder plus the guard (`guard_bins`),
    /// `bins` when nothing opaque was detected. Detections in later bins are withheld.
    pub fn last_observed(&self, d: usize, guard_bins: usize, bins: usize) -> usize {
        self.occluder[d].map_or(bins, |o| o + guard_bins)
    }

    /// Per direction the first detected bin at or after `min_bin` (None: no detection), the
    /// leak [`Occlusion::bound_silent`] bounds a silent direction at.
    pub fn first_detections(&self, min_bin: usize) -> Vec<Option<usize>> {
        self.det
            .iter()
            .map(|d| (min_bin..d.len()).find(|&k| d[k]))
            .collect()
    }
}

/// Per-cell visibility from one pose (grid-indexed; cells out of range are not visible).
#[derive(Debug, Clone)]
pub struct Visibility {
    /// Depth δ = r − R(θ) of each cell, m (+∞ out of range).
    pub depth: Vec<f32>,
    /// Guard g, m.
    pub guard_m: f32,
}

impl Visibility {
    /// Whether cell `c` may receive occupancy evidence (δ ≤ g).
    #[inline]
    pub fn visible(&self, c: u32) -> bool {
        self.depth[c as usize] <= self.guard_m
    }
    /// Whether cell `c` may be found free (δ < −g).
    #[inline]
    pub fn clearable(&self, c: u32) -> bool {
        self.depth[c as usize] < -self.guard_m
    }
}

impl Occlusion {
    /// The model of a run: `min_bin` the first usable bin, `side_db` the side-lobe margin.
    pub fn new(model: &ObservationModel, min_bin: usize, side_db: f64) -> Occlusion {
        let nd = model.directions();
        let bin_m = C0 * model.bin_width_s / 2.0;
        Occlusion {
            cross: (0..nd)
                .map(|d| {
                    (0..nd)
                        .map(|d2| model.weight(d, model.direction_rad(d2)))
                        .collect()
                })
                .collect(),
            side_margin: 10f64.powf(side_db / 10.0),
            main_w: model.params.main_weight(),
            min_bin,
            bin_m,
            guard_m: model.spec.cell_m * std::f64::consts::FRAC_1_SQRT_2 + 2.0 * bin_m,
            covered: (0..BUCKETS)
                .map(|b| {
                    let th = bucket_centre(b);
                    (0..nd).any(|d| model.weight(d, th) >= model.params.main_weight())
                })
                .collect(),
        }
    }

    /// The guard in bins (rounded up).
    pub fn guard_bins(&self) -> usize {
        (self.guard_m / self.bin_m).ceil() as usize
    }

    /// Per bin of direction `d` at pose `p`: true when the detection is explained by a side
    /// lobe of `d` towards another direction of the same scan (module docs).
    pub fn side_lobe_flags(
        &self,
        em: &EnergyMatrix,
        p: usize,
        d: usize,
        det: &[bool],
    ) -> Vec<bool> {
        let prof = em.profile(p, d);
        let n = prof.len();
        let mut side = vec![false; n];
        for k in 0..n {
            if !det[k] {
                continue;
            }
            let e = prof[k];
            side[k] = (0..self.cross.len()).any(|d2| {
                if d2 == d {
                    return false;
                }
                let w = self.cross[d][d2];
                if w <= 0.0 || w >= self.main_w {
                    return false;
                }
                let o = em.profile(p, d2);
                let lo = k.saturating_sub(1);
                let hi = (k + 2).min(n);
                let m = o[lo..hi].iter().cloned().fold(0.0, f64::max);
                e < self.side_margin * w * m
            });
        }
        side
    }

    /// The echoes of pose `p` from its detections `det` (per direction): the occluders (the
    /// side-lobe test, then the strongest echo or an earlier one confirmed against the
    /// binary map `occupied` when given; module docs).
    pub fn echoes(
        &self,
        model: &ObservationModel,
        em: &EnergyMatrix,
        p: usize,
        det: Vec<Vec<bool>>,
        occupied: Option<&[bool]>,
    ) -> ScanEchoes {
        use rayon::prelude::*;
        let nd = det.len();
        let side: Vec<Vec<bool>> = (0..nd)
            .into_par_iter()
            .map(|d| self.side_lobe_flags(em, p, d, &det[d]))
            .collect();
        let main: Vec<Vec<(u32, f64)>> = (0..nd)
            .map(|d| {
                let prof = em.profile(p, d);
                let bins = det[d].len().min(prof.len());
                (self.min_bin..bins)
                    .filter(|&k| det[d][k] && !side[d][k])
                    .map(|k| (k as u32, prof[k]))
                    .collect()
            })
            .collect();
        let occluder = (0..nd)
            .map(|d| self.occluder_of(model, p, d, &main[d], occupied))
            .collect();
        let missing = (0..nd).map(|d| !em.has(p, d)).collect();
        ScanEchoes {
            det,
            occluder,
            missing,
            main,
        }
    }

    /// The occluder of direction `d` at pose `p` from its main detections `main` (bin,
    /// energy; ascending bin): the strongest (the first of equals), or an earlier one on a
    /// surface of the binary map `occupied` when given (module docs).
    pub fn occluder_of(
        &self,
        model: &ObservationModel,
        p: usize,
        d: usize,
        main: &[(u32, f64)],
        occupied: Option<&[bool]>,
    ) -> Option<usize> {
        let mut best: Option<(u32, f64)> = None;
        for &(k, e) in main {
            if best.is_none_or(|b| e > b.1) {
                best = Some((k, e));
            }
        }
        let strongest = best?.0 as usize;
        let Some(occ) = occupied else {
            return Some(strongest);
        };
        let surfaces = self.mapped_surfaces(model, p, d, occ);
        let confirmed = main
            .iter()
            .map(|&(k, _)| k as usize)
            .take_while(|&k| k < strongest)
            .find(|&k| {
                let r = k as f64 * self.bin_m;
                surfaces.iter().any(|&s| (s - r).abs() <= self.guard_m)
            });
        Some(confirmed.unwrap_or(strongest))
    }

    /// Ranges (m, ascending) at which the boresight ray of (pose `p`, direction `d`) enters an
    /// occupied cell of `occupied`, sampled every cell/4 up to the last bin.
    fn mapped_surfaces(
        &self,
        model: &ObservationModel,
        p: usize,
        d: usize,
        occupied: &[bool],
    ) -> Vec<f64> {
        let pose = model.poses[p];
        let spec = &model.spec;
        let th = pose.heading_deg.to_radians() + model.direction_rad(d);
        let (ux, uy) = (th.cos(), th.sin());
        let step = spec.cell_m / 4.0;
        let rmax = model.max_range_m();
        let mut out = Vec::new();
        let mut prev_occ = false;
        let mut r = step;
        while r <= rmax {
            let pt = geo::Coord {
                x: pose.x_m + r * ux,
                y: pose.y_m + r * uy,
            };
            let occ = spec
                .cell_of(pt)
                .is_some_and(|(row, col)| occupied[row * spec.cols + col]);
            if occ && !prev_occ {
                out.push(r);
            }
            prev_occ = occ;
            r += step;
        }
        out
    }

    /// The occluders and missing directions of a scan with its silent directions bounded
    /// by `mode` (module docs, "silent directions"): `occluder` and `missing` per direction
    /// as in [`ScanEchoes`], `leak` the first detection of any kind per direction. A silent
    /// direction is one with no occluder and a sweep; the others are returned as they are.
    pub fn bound_silent(
        &self,
        model: &ObservationModel,
        occluder: &[Option<usize>],
        leak: &[Option<usize>],
        missing: &[bool],
        mode: SilentBound,
    ) -> (Vec<Option<usize>>, Vec<bool>) {
        let theta: Vec<f64> = (0..occluder.len())
            .map(|d| model.direction_rad(d))
            .collect();
        bound_silent_of(&theta, self.bin_m, occluder, leak, missing, mode)
    }

    /// The visibility polygon of a scan from its occluders (module docs): samples
    /// (θ_d, 1/R_d), ascending θ.
    pub fn polygon(&self, model: &ObservationModel, echoes: &ScanEchoes) -> Polygon {
        self.polygon_of(model, &echoes.occluder, &echoes.missing)
    }

    /// [`Occlusion::polygon`] from the occluders and the missing directions.
    pub fn polygon_of(
        &self,
        model: &ObservationModel,
        occluder: &[Option<usize>],
        missing: &[bool],
    ) -> Polygon {
        let rmax = model.max_range_m();
        let mut samples: Vec<(f64, f64)> = occluder
            .iter()
            .enumerate()
            // a direction without a sweep saw nothing: its neighbours bound the region
            .filter(|(d, _)| !missing.get(*d).copied().unwrap_or(false))
            .map(|(d, o)| {
                let r = o.map_or(rmax, |k| (k as f64 * self.bin_m).max(self.bin_m));
                (model.direction_rad(d), 1.0 / r)
            })
            .collect();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        Polygon { samples }
    }

    /// Depth δ = r − R(θ) of the cell at range `r` and bearing `theta` (relative to the
    /// heading) behind the polygon `poly`, m; +∞ where no main lobe looked.
    pub fn depth(&self, poly: &Polygon, r: f64, theta: f64) -> f64 {
        let b = bucket_of(theta);
        if !self.covered[b] {
            return f64::INFINITY;
        }
        let u = polygon_inverse_range(&poly.samples, bucket_centre(b));
        let lim = if u > 0.0 { 1.0 / u } else { f64::INFINITY };
        r - lim
    }

    /// [`Occlusion::visibility`] with the scan's silent directions bounded by `mode`
    /// ([`Occlusion::bound_silent`], the leaks being `echoes`' first detections at or after
    /// `min_bin`), on a copy: the scan's own occluders (a beam's free end, its withheld
    /// detections) stay as they are, only the polygon is bounded. `off`: the plain polygon.
    pub fn visibility_bounded(
        &self,
        model: &ObservationModel,
        geom: &PoseGeometry,
        echoes: &ScanEchoes,
        mode: SilentBound,
    ) -> Visibility {
        if mode == SilentBound::Off {
            return self.visibility(model, geom, echoes);
        }
        let mut pe = echoes.clone();
        let leak = echoes.first_detections(self.min_bin);
        (pe.occluder, pe.missing) =
            self.bound_silent(model, &echoes.occluder, &leak, &echoes.missing, mode);
        self.visibility(model, geom, &pe)
    }

    /// The visibility of every cell of a pose's geometry from its echoes (module docs).
    pub fn visibility(
        &self,
        model: &ObservationModel,
        geom: &PoseGeometry,
        echoes: &ScanEchoes,
    ) -> Visibility {
        let samples = self.polygon(model, echoes).samples;
        let mut depth = vec![f32::INFINITY; model.spec.len()];
        for b in 0..BUCKETS {
            let (lo, hi) = (geom.bucket[b] as usize, geom.bucket[b + 1] as usize);
            if lo == hi {
                continue;
            }
            let th = bucket_centre(b);
            if !self.covered[b] {
                // no main lobe looked here: the scan says nothing of these cells
                continue;
            }
            let u = polygon_inverse_range(&samples, th);
            let lim = if u > 0.0 { 1.0 / u } else { f64::INFINITY };
            for i in lo..hi {
                debug_assert_eq!(bucket_of(geom.theta[i]), b);
                depth[geom.cell[i] as usize] = (geom.range[i] - lim) as f32;
            }
        }
        Visibility {
            depth,
            guard_m: self.guard_m as f32,
        }
    }
}

/// A scan's visibility polygon: per direction with a sweep (θ_d, 1/R_d), ascending θ
/// (R_d the occluder's range, the last bin's without one).
#[derive(Debug, Clone, Default)]
pub struct Polygon {
    samples: Vec<(f64, f64)>,
}

/// [`Occlusion::bound_silent`] for directions of boresights `theta` (rad) and bins of
/// `bin_m` metres.
fn bound_silent_of(
    theta: &[f64],
    bin_m: f64,
    occluder: &[Option<usize>],
    leak: &[Option<usize>],
    missing: &[bool],
    mode: SilentBound,
) -> (Vec<Option<usize>>, Vec<bool>) {
    let nd = occluder.len();
    let mut occ = occluder.to_vec();
    let mut miss: Vec<bool> = (0..nd)
        .map(|d| missing.get(d).copied().unwrap_or(false))
        .collect();
    if mode == SilentBound::Off {
        return (occ, miss);
    }
    let inv = |k: usize| 1.0 / (k as f64 * bin_m).max(bin_m);
    // the directions with an occluder, by bearing: (θ, 1/R)
    let mut known: Vec<(f64, f64)> = (0..nd)
        .filter(|&d| !miss[d])
        .filter_map(|d| occluder[d].map(|k| (theta[d], inv(k))))
        .collect();
    known.sort_by(|a, b| a.0.total_cmp(&b.0));
    let silent: Vec<usize> = (0..nd)
        .filter(|&d| occluder[d].is_none() && !miss[d])
        .collect();
    for d in silent {
        let u_leak = leak.get(d).copied().flatten().map(inv);
        let u = match mode {
            SilentBound::Off => None,
            SilentBound::Leak => u_leak,
            SilentBound::Nearer => {
                // the nearer range is the larger 1/R; the interpolation is the polygon's own
                // rule over the known directions (constant beyond the outermost)
                let u_int = (!known.is_empty()).then(|| polygon_inverse_range(&known, theta[d]));
                match (u_leak, u_int) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                }
            }
        };
        match u {
            Some(u) if u > 0.0 => occ[d] = Some(((1.0 / u) / bin_m).round().max(1.0) as usize),
            // nothing bounds it: out of the polygon, its neighbours bound it (`leak`), or
            // no occluder anywhere in the scan (`nearer`: the polygon is empty too)
            _ => miss[d] = true,
        }
    }
    (occ, miss)
}

/// The bearing at the centre of bucket `b`, rad.
fn bucket_centre(b: usize) -> f64 {
    -PI + (b as f64 + 0.5) * 2.0 * PI / BUCKETS as f64
}

/// 1/R at bearing `th` from the polygon samples (θ_d, 1/R_d) sorted by θ: linear between
/// neighbours, constant beyond the ends.
fn polygon_inverse_range(samples: &[(f64, f64)], th: f64) -> f64 {
    match samples {
        [] => 0.0,
        [only] => only.1,
        _ => {
            let first = samples[0];
            let last = samples[samples.len() - 1];
            if th <= first.0 {
                return first.1;
            }
            if th >= last.0 {
                return last.1;
            }
            let j = samples.partition_point(|s| s.0 <= th);
            let (a, b) = (samples[j - 1], samples[j]);
            let t = if b.0 > a.0 {
                (th - a.0) / (b.0 - a.0)
            } else {
                0.0
            };
            a.1 + t * (b.1 - a.1)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// metrics.json names each mapping choice as its command-line value, so a user's
    /// script can pass a run's parameters back as flags (`"variant": "scalable"`, not
    /// `"Scalable"`).
    #[test]
    fn mapping_choices_serialise_as_their_flag_values() {
        use crate::ekf::{EkfUpdate, EkfVariant};
        fn same<T>(all: &[T])
        where
            T: std::fmt::Display
                + std::str::FromStr
                + serde::Serialize
                + PartialEq
                + std::fmt::Debug,
            T::Err: std::fmt::Debug,
        {
            for v in all {
                let flag = v.to_string();
                assert_eq!(serde_json::to_string(v).unwrap(), format!("\"{flag}\""));
                assert_eq!(&flag.parse::<T>().unwrap(), v);
            }
        }
        same(&EkfVariant::ALL);
        same(&EkfUpdate::ALL);
        same(&SilentBound::ALL);
        same(&crate::og::OgCredit::ALL);
        assert_eq!(
            SilentBound::ALL.map(|b| b.to_string()),
            ["off", "leak", "nearer"]
        );
    }

    #[test]
    fn inverse_range_interpolation_follows_a_straight_wall() {
        // wall at distance D = 2 m with its normal at bearing 0.3 rad: 1/R = cos(θ − 0.3)/D
        let d = 2.0;
        let inv = |th: f64| (th - 0.3f64).cos() / d;
        let samples: Vec<(f64, f64)> = (0..7)
            .map(|i| {
                let th = -0.6 + 0.2 * i as f64;
                (th, inv(th))
            })
            .collect();
        for th in [-0.55, -0.1, 0.05, 0.33, 0.59] {
            let got = 1.0 / polygon_inverse_range(&samples, th);
            let want = 1.0 / inv(th);
            // linear in 1/R between 0.2 rad samples of a cosine: within h²/8 = 0.5 % of the
            // range (1 % asserted)
            assert!((got / want - 1.0).abs() < 1e-2, "θ {th}: {got} vs {want}");
        }
        // held constant beyond the ends
        assert_eq!(polygon_inverse_range(&samples, -2.0), samples[0].1);
        assert_eq!(polygon_inverse_range(&samples, 2.0), samples[6].1);
    }

    #[test]
    fn a_silent_direction_is_bounded_at_the_nearer_of_its_leak_and_its_neighbours() {
        // five boresights 0.1 rad apart facing a straight wall 2 m away along the normal at
        // 0 rad (R(θ) = 2/cos θ); bins of 0.01 m; directions 1 and 3 silent, 4 missing
        let theta = [-0.2, -0.1, 0.0, 0.1, 0.2];
        let bin = |r: f64| (r / 0.01f64).round() as usize;
        let wall = |th: f64| 2.0 / f64::cos(th);
        let occluder = [
            Some(bin(wall(-0.2))),
            None,
            Some(bin(wall(0.0))),
            None,
            None,
        ];
        let missing = [false, false, false, false, true];
        // direction 1 leaks at 3 m (a surface beyond the wall), direction 3 at 1.5 m
        let leak = [None, Some(300), None, Some(150), None];
        let (o, m) = bound_silent_of(&theta, 0.01, &occluder, &leak, &missing, SilentBound::Off);
        assert_eq!(
            (o, m),
            (occluder.to_vec(), missing.to_vec()),
            "off: unchanged"
        );
        let (o, m) = bound_silent_of(&theta, 0.01, &occluder, &leak, &missing, SilentBound::Leak);
        assert_eq!(
            o,
            vec![occluder[0], Some(300), occluder[2], Some(150), None]
        );
        assert_eq!(m, missing.to_vec());
        let (o, m) = bound_silent_of(
            &theta,
            0.01,
            &occluder,
            &leak,
            &missing,
            SilentBound::Nearer,
        );
        // direction 1: the wall interpolated between directions 0 and 2 (linear in 1/R:
        // within h²/8 = 0.5 % of the wall's 2.010 m, plus half a bin), nearer than its leak;
        // direction 3: its leak, nearer than the wall held constant from direction 2 (2 m)
        let r1 = o[1].unwrap() as f64 * 0.01;
        assert!((r1 - wall(-0.1)).abs() <= 0.02, "{r1} vs {}", wall(-0.1));
        assert_eq!(o[3], Some(150));
        assert_eq!((o[0], o[2], o[4]), (occluder[0], occluder[2], None));
        assert_eq!(m, missing.to_vec());
        // without a leak: the interpolation alone; without any occluder: out of the polygon
        let (o, _) = bound_silent_of(
            &theta,
            0.01,
            &occluder,
            &[None; 5],
            &missing,
            SilentBound::Nearer,
        );
        assert_eq!(
            o[3], occluder[2],
            "held constant beyond the last known direction"
        );
        let (o, m) = bound_silent_of(
            &theta,
            0.01,
            &[None; 5],
            &[None; 5],
            &[false; 5],
            SilentBound::Nearer,
        );
        assert_eq!(o, vec![None; 5]);
        assert_eq!(m, vec![true; 5]);
    }

    #[test]
    fn the_last_observed_bin_is_the_occluder_plus_the_guard() {
        let e = ScanEchoes {
            det: vec![vec![false; 50]; 2],
            occluder: vec![Some(20), None],
            missing: vec![false; 2],
            main: vec![Vec::new(); 2],
        };
        assert_eq!(e.last_observed(0, 3, 50), 23);
        assert_eq!(
            e.last_observed(1, 3, 50),
            50,
            "no occluder: every bin observed"
        );
    }
}
