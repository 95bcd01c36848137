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
//! [0, R_u). An MPC at pose p, bearing θ̂, range r = c·τ/2 is **folded** when, for some
//! k ≥ 1, r + k·R_u lies within Δr of a far wall echo the layout predicts along the beam
//! θ̂ ± w (w as in [`diffuse`](super::diffuse): half the two-way half-power beamwidth or half
//! the direction step, whichever is larger; Δr = `range_bins` bins of c·T_b/2, the diffuse
//! stage's tolerance; the test is cyclic, an MPC just above 0 matches a fold just below
//! R_u). Two kinds of far echo count:
//!
//! 1. *compact* ([`Fold::far_points_m`]): a wall's specular point (the foot of the
//!    perpendicular from the pose, on the segment) and each wall end point (corners and
//!    edges), beyond R_u, their bearing within the beam and no wall nearer along it. These
//!    are point-like and strong (the specular return of a wall seen at normal incidence, a
//!    corner's dihedral), so they are labelled on the geometry alone. Vertices are cast
//!    apart from the walls' rays because a corner is a scatterer of its own, not only the
//!    end of its walls' curves.
//! 2. *continuum*: the wall's diffuse return. Along the rays θ ∈ θ̂ ± w (every 0.1°) the
//!    first hits ([`Layout::first_hit`]) beyond R_u give intervals of true range
//!    ([`Fold::far_ranges_m`]: a ray its own range, two neighbouring rays on the same wall
//!    the range between them; rays on different walls are not joined, so an occlusion edge
//!    does not become a band of every range behind it). An MPC with r + k·R_u in
//!    [lo − Δr, hi + Δr] of one of them is on the folded wall curve; it is folded when also
//!    at the diffuse level: E / E₁ᶠ ≤ σ̂·10^(`discrete_db`/10), E₁ᶠ the diffuse stage's
//!    unit-wall energy E₁ in the MPC's cell summed over the rays whose wall lies beyond
//!    R_u only, each at its delay folded to the copy nearest the MPC's, and σ̂ the diffuse
//!    level the diffuse stage read (without one — the stage off or no dense component —
//!    only the compact folds are labelled). The level test matters: a wall seen at grazing
//!    incidence spreads over more range within the beam than R_u, so its folded curve
//!    covers every range and, without the level, every MPC of such a beam (the room's own
//!    objects at 20–40 dB above the folded continuum) would be called folded.
//!
//! Not predicted: clutter and objects beyond R_u (the layout has neither their places nor
//! their levels) and multi-bounce paths (their range is not a first hit); they stay as the
//! earlier stages labelled them, and are clustered when discrete.
//!
//! Precedence: a folded echo is not at its true range, so neither its delay nor its power
//! belongs to a cluster at that range, nor to the diffuse continuum there. **Folded wins**
//! over both labels: a discrete or diffuse MPC that matches is relabelled folded (the
//! summary counts the diffuse ones moved, [`FoldSummary::from_diffuse`]); the diffuse level
//! σ̂ is read before the fold, the folded among its on-curve MPCs moving its median only by
//! their share. Its weakness: a true near echo within Δr of a compact fold is called
//! folded. Measurements against the simulator's per-path truth are in `tests/fold.rs` and
//! `docs/zoo.md` ("Fold").
//!
//! The stage runs only when the layout reaches beyond R_u from some pose ([`Fold::new`]:
//! the reach of [`Reach`], to the walls' end points through walls); otherwise it touches no
//! MPC, and the MPCs of a campaign within range are those of the chain without it.

use super::diffuse::{unit_wall_energy, Cell};
use super::footprint::Footprint;
use super::{Component, Mpc};
use crate::campaign::fold::{unambiguous_range_m, Reach};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, Manifest, Pose};
use crate::units::wrap_deg;
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

    /// The true ranges beyond R_u of the compact far echoes seen along the rays
    /// `deg ± w_deg` from `at`: each wall's specular point (the foot of the perpendicular
    /// from `at`, on the segment) and each wall end point, when its bearing lies within the
    /// beam and no wall hides it (module docs).
    pub fn far_points_m(&self, at: Coord<f64>, deg: f64, w_deg: f64) -> Vec<f64> {
        let ru = self.unambiguous_range_m;
        let mut out = Vec::new();
        let mut consider = |p: Coord<f64>| {
            let (dx, dy) = (p.x - at.x, p.y - at.y);
            let dist = dx.hypot(dy);
            if dist <= ru {
                return;
            }
            let bearing = dy.atan2(dx).to_degrees();
            if wrap_deg(bearing - deg).abs() > w_deg {
                return;
            }
            // visible: the first wall along the bearing is not nearer (a ray through a
            // vertex may slip past both of its walls to a farther one)
            let seen = (self.layout.first_hit(at, bearing.to_radians()))
                .is_none_or(|h| h.0 >= dist - 1e-6 * dist - 1e-3);
            if seen {
                out.push(dist);
            }
        };
        for w in &self.layout.walls {
            let (s, e) = (w.line.start, w.line.end);
            let d = e - s;
            let l2 = d.x * d.x + d.y * d.y;
            if l2 > 0.0 {
                let t = ((at.x - s.x) * d.x + (at.y - s.y) * d.y) / l2;
                if (0.0..=1.0).contains(&t) {
                    consider(Coord {
                        x: s.x + t * d.x,
                        y: s.y + t * d.y,
                    });
                }
            }
            consider(s);
            consider(e);
        }
        out
    }

    /// Label folded every MPC of `mpcs` (in place) that is a compact fold (a specular
    /// point or a wall end point beyond R_u within `w_deg` of its bearing, within
    /// `tolerance_m`), or a continuum fold (on the folded wall curve and at most `level`'s
    /// limit over the folded walls' unit energy); `poses` by position (module docs).
    pub(crate) fn label(
        &self,
        mpcs: &mut [Mpc],
        poses: &[Pose],
        w_deg: f64,
        tolerance_m: f64,
        level: Option<&FoldLevel>,
    ) -> FoldSummary {
        let period_ns = crate::units::delay_ns(self.unambiguous_range_m);
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
                let r = crate::units::range_m(x.delay_ns);
                let points: Vec<(f64, f64)> = (self.far_points_m(at, x.angle_global_deg, w_deg))
                    .into_iter()
                    .map(|p| (p, p))
                    .collect();
                if self.folds_onto(r, &points, tolerance_m) {
                    return true;
                }
                let Some(level) = level else {
                    return false;
                };
                let far = self.far_ranges_m(at, x.angle_global_deg, w_deg);
                if !self.folds_onto(r, &far, tolerance_m) {
                    return false;
                }
                let Some(&beam) = level.angles_rel_deg.get(x.direction) else {
                    return false;
                };
                let cell = Cell {
                    fp: level.fp,
                    x,
                    beam,
                    reach: level.reach_deg,
                    bin_width_ns: level.bin_width_ns,
                    gl: level.gl,
                };
                let e1 =
                    unit_wall_energy(&self.layout, at, pose.heading_deg, &cell, Some(period_ns));
                e1 > 0.0 && 10f64.powf(x.power_db / 10.0) / e1 <= level.limit_m2_per_m
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

/// The level test of the continuum folds: the diffuse stage's footprint, beams, bin width,
/// G₀²λ², rays' reach and limit σ̂·10^(`discrete_db`/10).
pub(crate) struct FoldLevel<'a> {
    /// The footprint (two-way pattern and window kernel).
    pub(crate) fp: &'a Footprint,
    /// The beams' angles relative to the heading, degrees.
    pub(crate) angles_rel_deg: &'a [f64],
    /// The energy table's bin width, ns.
    pub(crate) bin_width_ns: f64,
    /// G₀²λ².
    pub(crate) gl: f64,
    /// The rays summed, degrees either side of the beam.
    pub(crate) reach_deg: f64,
    /// σ̂·10^(`discrete_db`/10), m²/m.
    pub(crate) limit_m2_per_m: f64,
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
        let s = f.label(&mut mpcs, &m.poses, w_deg, tol_m, None);
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

    /// Without a diffuse level only the compact folds count: the hall's north-east corner
    /// (55.15 m at 4.16°) folds, the north wall's continuum at x = 50 m (45.18 m at 5.08°)
    /// does not, though it lies on the folded wall curve.
    #[test]
    fn a_far_corner_folds_and_the_continuum_needs_the_level() {
        let m = manifest();
        let f = Fold::new(&m, layout(HALL)).unwrap();
        let ru = f.unambiguous_range_m();
        let corner_m = 55f64.hypot(4.0);
        let corner_deg = 4f64.atan2(55.0).to_degrees();
        // the north wall at x = 50 m
        let wall_deg = 4f64.atan2(45.0).to_degrees();
        let wall_m = 45f64.hypot(4.0);
        let at = Coord { x: 5.0, y: 0.0 };
        let points = f.far_points_m(at, corner_deg, 1.0);
        assert!(
            points.iter().any(|p| (p - corner_m).abs() < 1e-9),
            "{points:?}"
        );
        let mut mpcs = vec![
            mpc(corner_m - 2.0 * ru, corner_deg),
            mpc(wall_m - 2.0 * ru, wall_deg),
        ];
        assert!(f.folds_onto(wall_m - 2.0 * ru, &f.far_ranges_m(at, wall_deg, 0.5), 0.05));
        let s = f.label(&mut mpcs, &m.poses, 0.5, 0.05, None);
        assert_eq!(mpcs[0].component, Component::Folded);
        assert_eq!(mpcs[1].component, Component::Discrete);
        assert_eq!(s.folded, 1);
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
