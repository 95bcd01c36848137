//! The fold stage: the MPCs that the layout predicts to be wall echoes from beyond the
//! sweep's unambiguous range, folded back into the kept bins, labelled
//! [`Component::Folded`] and kept out of the clusters, Table 1 and the diffuse level.
//!
//! Takes the extracted (and diffuse-labelled) MPCs, the campaign's poses and band, the
//! layout the manifest names (an input, never the simulator's truth), the beam's half
//! extent w and the range tolerance Δr of the diffuse stage; gives each folded MPC its
//! label and a [`FoldSummary`].
//!
//! A sweep of N points stepping by Δf has the unambiguous range R_u = c/(2Δf)
//! ([`unambiguous_range_m`]): its delay profile is periodic in delay with period 1/Δf, so a
//! wall echo at range r_w > R_u reads at r_w − k·R_u, the k ≥ 1 that brings it into
//! [0, R_u). Along an MPC's bearing θ̂ the layout predicts the first-hit wall ranges
//! r_w(θ) ([`Layout::first_hit`]) over the rays θ ∈ θ̂ ± w (every 0.1°, w as in
//! [`diffuse`](super::diffuse): half the two-way half-power beamwidth or half the direction
//! step, whichever is larger). The rays beyond R_u give intervals of true range: a single
//! ray its own range, two neighbouring rays on the same wall the range between them (a
//! wall is a straight segment, its range continuous between two rays 0.1° apart; rays on
//! different walls are not joined, so an occlusion edge does not become a band of all the
//! ranges behind it). An MPC at range r = c·τ/2 is **folded** when, for some k ≥ 1,
//!
//!   r + k·R_u ∈ [lo − Δr, hi + Δr]     for one such interval [lo, hi], hi > R_u,
//!
//! (lo taken at least R_u: only the part of a wall beyond R_u folds), Δr = `range_bins`
//! bins of c·T_b/2, the diffuse stage's tolerance. The test is cyclic: an MPC just above 0
//! matches a fold just below R_u.
//!
//! Wall vertices are not cast apart: a visible corner is the end of a wall segment whose
//! rays reach it within the 0.1° ray step, so its folded range is already inside its wall's
//! interval; an occluded one sends no first-order echo. Multi-bounce paths and objects
//! beyond R_u are not predicted (the layout has no objects' levels and a multi-bounce
//! path's range is not a first hit); they stay as the earlier stages labelled them.
//!
//! Precedence: a folded echo is not at its true range, so neither its delay nor its power
//! belongs to a cluster at that range, nor to the diffuse continuum there. **Folded wins**
//! over both labels: a discrete or diffuse MPC that matches is relabelled folded (the
//! summary counts the diffuse ones moved, [`FoldSummary::from_diffuse`]); the diffuse level
//! σ̂ is read before the fold, the folded among its on-curve MPCs moving its median only by
//! their share. Its weakness: a true near echo (a corner, an object) within Δr of a
//! predicted fold is called folded.
//!
//! The stage runs only when the layout reaches beyond R_u from some pose ([`Fold::new`]:
//! the reach of [`Reach`], to the walls' end points through walls); otherwise it touches no
//! MPC, and the MPCs of a campaign within range are those of the chain without it.

use super::{Component, Mpc};
use crate::campaign::fold::{unambiguous_range_m, Reach};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, Manifest, Pose};
use geo::Coord;
use rayon::prelude::*;

/// Step of the rays cast across a beam, degrees (as the diffuse stage's).
const RAY_STEP_DEG: f64 = 0.1;

/// What the fold stage found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoldSummary {
    /// The sweep's unambiguous range c/(2Δf), m (NaN when the stage did not run).
    pub unambiguous_range_m: f64,
    /// MPCs labelled folded.
    pub folded: usize,
    /// Of which the diffuse stage had labelled diffuse.
    pub from_diffuse: usize,
}

impl FoldSummary {
    /// Nothing labelled (the layout within R_u, or no layout).
    pub fn none() -> FoldSummary {
        FoldSummary {
            unambiguous_range_m: f64::NAN,
            folded: 0,
            from_diffuse: 0,
        }
    }
}

/// The fold geometry of a campaign whose layout reaches beyond its unambiguous range.
#[derive(Debug, Clone)]
pub struct Fold {
    layout: Layout,
    unambiguous_range_m: f64,
}

impl Fold {
    /// The fold of `manifest`'s band and poses in `layout`; `None` when no wall end point
    /// lies beyond R_u from any pose (nothing can fold).
    pub fn new(manifest: &Manifest, layout: Layout) -> Option<Fold> {
        let ru = unambiguous_range_m(&manifest.band);
        let reach = Reach::of(manifest, &layout)?;
        (reach.range_m > ru).then_some(Fold {
            layout,
            unambiguous_range_m: ru,
        })
    }

    /// [`Fold::new`] with the layout the campaign names; `None` also when it cannot be read
    /// (the stages that need it refuse it by name).
    pub fn of(c: &Campaign) -> Option<Fold> {
        let layout = Layout::load(&c.layout_path()).ok()?;
        Fold::new(&c.manifest, layout)
    }

    /// The unambiguous range R_u, m.
    pub fn unambiguous_range_m(&self) -> f64 {
        self.unambiguous_range_m
    }

    /// The intervals [lo, hi] of first-hit wall range beyond R_u (lo ≥ R_u) along the rays
    /// `deg ± w_deg` (global angles) from `at` (module docs).
    pub fn far_ranges_m(&self, at: Coord<f64>, deg: f64, w_deg: f64) -> Vec<(f64, f64)> {
        let ru = self.unambiguous_range_m;
        let n = (2.0 * w_deg / RAY_STEP_DEG).ceil().max(1.0) as usize;
        let hits: Vec<Option<(f64, usize)>> = (0..=n)
            .map(|i| {
                let a = deg - w_deg + 2.0 * w_deg * i as f64 / n as f64;
                self.layout
                    .first_hit(at, a.to_radians())
                    .map(|(r, wall, _)| (r, wall))
            })
            .collect();
        let mut out = Vec::new();
        let mut push = |lo: f64, hi: f64| {
            if hi > ru {
                out.push((lo.max(ru), hi));
            }
        };
        for (i, h) in hits.iter().enumerate() {
            let Some((r, wall)) = *h else { continue };
            push(r, r);
            if let Some(Some((r2, w2))) = hits.get(i + 1) {
                if *w2 == wall {
                    push(r.min(*r2), r.max(*r2));
                }
            }
        }
        out
    }

    /// Whether an echo at `range_m` is the fold of a true range in one of `far` (intervals
    /// of [`Fold::far_ranges_m`]) within `tolerance_m`: r + k·R_u ∈ [lo − Δr, hi + Δr] for
    /// some k ≥ 1.
    pub fn folds_onto(&self, range_m: f64, far: &[(f64, f64)], tolerance_m: f64) -> bool {
        let ru = self.unambiguous_range_m;
        far.iter().any(|&(lo, hi)| {
            let k_min = ((lo - tolerance_m - range_m) / ru).ceil().max(1.0);
            let k_max = ((hi + tolerance_m - range_m) / ru).floor();
            k_min <= k_max
        })
    }

    /// Label folded every MPC of `mpcs` (in place) whose range folds from a wall beyond R_u
    /// along its bearing ± `w_deg`, within `tolerance_m` (module docs); `poses` by position.
    pub fn label(
        &self,
        mpcs: &mut [Mpc],
        poses: &[Pose],
        w_deg: f64,
        tolerance_m: f64,
    ) -> FoldSummary {
        let folded: Vec<bool> = mpcs
            .par_iter()
            .map(|x| {
                let Some(pose) = poses.get(x.position) else {
                    return false;
                };
                let at = Coord {
                    x: pose.x_m,
                    y: pose.y_m,
                };
                let far = self.far_ranges_m(at, x.angle_global_deg, w_deg);
                self.folds_onto(crate::units::range_m(x.delay_ns), &far, tolerance_m)
            })
            .collect();
        let mut out = FoldSummary {
            unambiguous_range_m: self.unambiguous_range_m,
            folded: 0,
            from_diffuse: 0,
        };
        for (x, f) in mpcs.iter_mut().zip(folded) {
            if f {
                out.folded += 1;
                if x.component == Component::Diffuse {
                    out.from_diffuse += 1;
                }
                x.component = Component::Folded;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::delay_ns;
    use std::path::Path;

    /// A 60 m × 8 m hall, the pose 5 m from its west wall on the axis.
    const HALL: &str = r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
        "properties": {"role": "perimeter", "material": "concrete"},
        "geometry": {"type": "Polygon", "coordinates":
        [[[0, -4], [60, -4], [60, 4], [0, 4], [0, -4]]]}}]}"#;

    /// A 12 m × 8 m room, the same pose: every wall within 20 m.
    const ROOM: &str = r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
        "properties": {"role": "perimeter", "material": "concrete"},
        "geometry": {"type": "Polygon", "coordinates":
        [[[0, -4], [12, -4], [12, 4], [0, 4], [0, -4]]]}}]}"#;

    /// The point-target manifest at 801 points over 6 GHz (R_u = 19.99 m), one pose at
    /// (5, 0) heading east.
    fn manifest() -> Manifest {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/tests/point_target.toml"
        );
        let text = std::fs::read_to_string(path).unwrap();
        let text = text.split("[scene]").next().unwrap();
        let text = text
            .replace("points = 401", "points = 801")
            .replace("x_m = 0.0\ny_m = 0.0", "x_m = 5.0\ny_m = 0.0");
        Campaign::from_str(&text, Path::new(path)).unwrap().manifest
    }

    fn layout(text: &str) -> Layout {
        Layout::from_geojson(text, Path::new("test.geojson")).unwrap()
    }

    fn mpc(range_m: f64, angle_deg: f64) -> Mpc {
        Mpc {
            position: 0,
            delay_ns: delay_ns(range_m),
            angle_rel_deg: angle_deg,
            angle_global_deg: angle_deg,
            power_db: 0.0,
            snr_db: 30.0,
            x_m: 0.0,
            y_m: 0.0,
            direction: 0,
            bin: 0,
            component: Component::Discrete,
            wall: None,
        }
    }

    /// The east wall 55 m from the pose folds to 55 − 2·R_u = 15.03 m at 801 points: an MPC
    /// there, looking east, is folded (a diffuse one too); one 5 bins away (bins of
    /// c/(2B) = 2.5 cm, the tolerance 2 bins) is not, nor one at the folded range looking
    /// at the near west wall.
    #[test]
    fn an_mpc_at_the_folded_range_of_a_far_wall_is_folded_and_one_5_bins_off_is_not() {
        let m = manifest();
        let ru = unambiguous_range_m(&m.band);
        assert!((ru - 19.986).abs() < 1e-3);
        let f = Fold::new(&m, layout(HALL)).expect("55 m is beyond 20 m");
        let folded_m = 55.0 - 2.0 * ru;
        let bin_m = crate::units::C0 / (2.0 * m.band.bandwidth_hz());
        let tol_m = 2.0 * bin_m;
        let w_deg = 2.0;
        let mut mpcs = vec![
            mpc(folded_m, 0.0),
            mpc(folded_m + 0.5 * bin_m, 1.0),
            mpc(folded_m + 5.0 * bin_m, 0.0),
            mpc(folded_m - 5.0 * bin_m, 0.0),
            mpc(folded_m, 180.0),
            mpc(folded_m, 0.0),
        ];
        mpcs[5].component = Component::Diffuse;
        let s = f.label(&mut mpcs, &m.poses, w_deg, tol_m);
        let got: Vec<Component> = mpcs.iter().map(|x| x.component).collect();
        use Component::*;
        assert_eq!(
            got,
            [Folded, Folded, Discrete, Discrete, Discrete, Folded],
            "fold at {folded_m} m"
        );
        assert_eq!((s.folded, s.from_diffuse), (3, 1));
        assert_eq!(s.unambiguous_range_m, ru);
    }

    /// An oblique bearing meets the side wall beyond R_u: its range along the beam spreads,
    /// and an MPC anywhere within that spread (folded) is labelled; the cyclic test matches
    /// an echo just above 0 to a fold just below R_u.
    #[test]
    fn the_range_spread_within_the_beam_and_the_wrap_at_the_span_end_are_matched() {
        let m = manifest();
        let f = Fold::new(&m, layout(HALL)).unwrap();
        let ru = f.unambiguous_range_m();
        let at = Coord { x: 5.0, y: 0.0 };
        // 8° north of east meets y = 4 at 4/sin(8°) = 28.7 m; ±2° spreads it over 24–38 m
        let far = f.far_ranges_m(at, 8.0, 2.0);
        let lo = far.iter().map(|x| x.0).fold(f64::INFINITY, f64::min);
        let hi = far.iter().map(|x| x.1).fold(0.0, f64::max);
        assert!((lo - 4.0 / 10f64.to_radians().sin()).abs() < 0.01, "{lo}");
        assert!((hi - 4.0 / 6f64.to_radians().sin()).abs() < 0.01, "{hi}");
        for r in [lo, 0.5 * (lo + hi), hi] {
            assert!(f.folds_onto(r - ru, &far, 0.01), "{r}");
        }
        assert!(!f.folds_onto(lo - ru - 0.1, &far, 0.01));
        // a fold just below R_u read just above 0
        let edge = [(2.0 * ru - 0.005, 2.0 * ru - 0.005)];
        assert!(f.folds_onto(0.004, &edge, 0.01));
        assert!(!f.folds_onto(0.02, &edge, 0.01));
    }

    /// A room within R_u from every pose: no fold, and nothing labelled.
    #[test]
    fn a_layout_within_the_unambiguous_range_folds_nothing() {
        let m = manifest();
        assert!(Fold::new(&m, layout(ROOM)).is_none());
        // the west wall of the hall is near, the folds are all of the east
        let f = Fold::new(&m, layout(HALL)).unwrap();
        assert!(f
            .far_ranges_m(Coord { x: 5.0, y: 0.0 }, 180.0, 2.0)
            .is_empty());
    }
}
