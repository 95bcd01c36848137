//! Ghosts across poses: evidence a pose could not have had, judged again once the map is
//! built, shared by both mappers.
//!
//! Takes, per pose of a run, its echoes ([`ScanEchoes`]: the detections not explained by a
//! side lobe, the missing directions) and the occupancy evidence the mapper took from it
//! (OG: every log-odds increment in order; EKF: the rise of each cell's mean in the pose's
//! energy updates), then the mapper's final binary map; gives the evidence each rule keeps.
//!
//! Why: online, a beam's occluder is its strongest echo unless an earlier echo lies on a
//! surface the map already holds ([`crate::mapping::grid::visibility`]). A multi-bounce
//! image seen through a wall (the image of a strong reflector in a plane mirror, the image
//! method) is often stronger than the wall's own diffuse echo, so the poses that see it
//! before the wall is mapped take it for the surface: they credit the image and clear the
//! wall in front of it. Two rules, selected by [`GhostRule`]:
//! * `mirror`: an image through a wall lies behind that wall from every pose in front of it
//!   (the image of a point P through the plane W is the mirror of P through W, on the far
//!   side of W from the radar). So once the map holds the walls, each pose's scan is
//!   judged again: its occluders are chosen with the *final* binary map as the mapped
//!   surfaces (the online rule: the strongest echo, or an earlier one on a mapped surface),
//!   its visibility polygon rebuilt (its silent directions bounded as the mapper bounded
//!   them online, [`GhostJudge::with_silent_bound`]), and the evidence it gave is kept only
//!   where that polygon allows it — an occupancy increment to a cell of depth δ ≤ g, a free
//!   increment to a cell of δ < −g (g the occlusion guard: the same test as online). The
//!   occupancy grid is then replayed from the prior with the kept increments in their
//!   original order (exactly the online map when nothing is dropped); the EKF, whose
//!   updates cannot be replayed, subtracts from each cell's mean the rises the poses that
//!   cannot see it gave (first order: x' = x̂ − Σ_{p: δ_p > g} Δx⁺_p, Δx⁺ the positive
//!   change of the mean in that pose's energy updates, per direction) and decides
//!   x' − κ·σ̂ > μ0. For the OG the wall must survive the poses that saw the image first: with `hold_echoes`
//!   ([`crate::mapping::og::OgParams`]) a beam gives no free evidence within g of a
//!   main-lobe echo before its occluder (the EKF's free-space evidence already skips bins
//!   near a detection). The mirror image itself is not predicted: that needs the reflector
//!   mapped in front of the wall, and a reflector seen only by its image (the test's ghost)
//!   is not; the rule uses only the image method's geometric consequence, which needs no
//!   threshold beyond the occlusion model's own.
//! * `aspect`: a real surface is where it is from every pose, while an image that moves
//!   with the radar (a double bounce, whose apparent position depends on the pose) lands in
//!   a cell from one viewpoint only. A cell the mapper calls occupied stays occupied only
//!   when the poses that support it (OG: the pose's summed increments to the cell reach
//!   |l_free|, so they outweigh one free look; EKF: the pose raised the cell's mean by at
//!   least μ0, the prior mean the decision is measured from) view it from world bearings
//!   spanning at least A_min = `aspect_lobes` × θ₃, θ₃ the two-way −3 dB main-lobe width of
//!   the direction nearest broadside (two views closer than a main lobe do not localise a
//!   cell independently); rejected cells go back to the prior. It cannot reject an image
//!   fixed in the world — the image of a fixed reflector in a plane mirror is fixed, seen
//!   over the same aspect as a wall — and it rejects every wall cell only one pose
//!   supports.
//!
//! Default: `none` for both mappers (and `hold_echoes` off). Measured on the ghost scene
//! and the four must-show scenes (`docs/mapping.md`, "Item 4"; with the earlier OG rules and
//! EKF): `mirror` removes the ghost (OG with `hold_echoes` 13 → 2 of
//! 90 cells, EKF 19 → 4) but on the corridor and the office it lowers walls found for both
//! mappers in every scene (office N = 16, OG 0.549 → 0.464; corridor N = 100, EKF 0.582 →
//! 0.459), raises the OG's wrong building cells in all four and lowers the EKF's in three:
//! the final map's objects in front of a wall (clutter, the pillar) become occluders too,
//! and the polygon interpolated between boresights 5° apart widens their shadow over wall
//! cells; `aspect` removes the ghost too, but loses a third to two thirds of the walls
//! found. Neither wins, so neither is on by default.
//!
//! Nothing here reads the reference or the simulator's truth. Cost: the OG keeps every
//! increment of a run (12 bytes each: 105,000 on the corridor at N = 100), the EKF the
//! rises of each pose; the judgement is one occluder choice and one polygon per pose.

use super::visibility::{Occlusion, Polygon, ScanEchoes, SilentBound};
use super::ObservationModel;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use crate::units::wrap_rad;

/// Which ghost rule (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum GhostRule {
    /// No rule: the online map as it is.
    #[value(name = "none", help = None::<&str>)]
    None,
    /// Occupancy needs support from poses spanning a minimum aspect.
    #[value(name = "aspect", help = None::<&str>)]
    Aspect,
    /// Each pose's evidence judged again against the final map's surfaces.
    #[value(name = "mirror", help = None::<&str>)]
    Mirror,
}

impl GhostRule {
    /// Name (`none`, `aspect`, `mirror`).
    pub fn name(&self) -> &'static str {
        match self {
            GhostRule::None => "none",
            GhostRule::Aspect => "aspect",
            GhostRule::Mirror => "mirror",
        }
    }
}

/// Ghost-rule parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GhostParams {
    /// The rule (`none`: neither rule won on the must-show scenes, module docs).
    pub rule: GhostRule,
    /// Minimum aspect of the `aspect` rule in main-lobe widths θ₃ (1).
    pub aspect_lobes: f64,
}

impl Default for GhostParams {
    fn default() -> Self {
        GhostParams {
            rule: GhostRule::None,
            aspect_lobes: 1.0,
        }
    }
}

/// Ghost-rule parameters that passed [`ParamGuard::check`].
pub type GhostValid = Valid<GhostParams>;

impl ParamGuard for GhostParams {
    type Checked = GhostValid;

    /// `aspect_lobes` finite and in [0, 36].
    fn check(&self) -> Result<GhostValid> {
        if !(self.aspect_lobes.is_finite() && (0.0..=36.0).contains(&self.aspect_lobes)) {
            return Err(Error::param("aspect_lobes", "must be in [0, 36]"));
        }
        Ok(Valid::new(*self))
    }
}

/// What a pose gave: its main detections per direction (bin, energy), its missing
/// directions, and its evidence (cell, amount) in the order the mapper applied it.
#[derive(Debug, Clone, Default)]
struct PoseRecord {
    pose: usize,
    main: Vec<Vec<(u32, f64)>>,
    missing: Vec<bool>,
    /// Per direction: the first detection (recorded when a silent bound is set).
    leak: Vec<Option<usize>>,
    /// Per direction: (cell, amount) in the order the mapper applied them.
    evidence: Vec<Vec<(u32, f32)>>,
}

/// The poses of a run recorded for a ghost rule (module docs).
#[derive(Debug)]
pub struct GhostJudge<'a> {
    model: &'a ObservationModel,
    occlusion: &'a Occlusion,
    params: GhostValid,
    /// How the rebuilt polygons bound the silent directions (as the mapper's online ones).
    silent: SilentBound,
    records: Vec<PoseRecord>,
}

impl<'a> GhostJudge<'a> {
    /// A judge for one run.
    pub fn new(model: &'a ObservationModel, occlusion: &'a Occlusion, params: GhostValid) -> Self {
        GhostJudge {
            model,
            occlusion,
            params,
            silent: SilentBound::Off,
            records: Vec::new(),
        }
    }

    /// The judge with the silent directions of the rebuilt polygons bounded by `mode`
    /// ([`Occlusion::bound_silent`]; `off` unless set), as the mapper bounded them online.
    pub fn with_silent_bound(mut self, mode: SilentBound) -> Self {
        self.silent = mode;
        self
    }

    /// The rule.
    pub fn rule(&self) -> GhostRule {
        self.params.rule
    }

    /// Record pose `p`: its echoes and the evidence the mapper took from it (OG: every
    /// increment in order; EKF: the mean rises).
    pub fn record(&mut self, p: usize, echoes: &ScanEchoes, evidence: Vec<Vec<(u32, f32)>>) {
        self.records.push(PoseRecord {
            pose: p,
            main: echoes.main.clone(),
            missing: echoes.missing.clone(),
            leak: if self.silent == SilentBound::Off {
                Vec::new()
            } else {
                echoes.first_detections(self.occlusion.min_bin)
            },
            evidence,
        });
    }

    /// Range and bearing (relative to the heading) of cell `c` from pose `p`.
    fn range_bearing(&self, p: usize, c: u32) -> (f64, f64, f64) {
        let spec = &self.model.spec;
        let pose = self.model.poses[p];
        let c = c as usize;
        let ctr = spec.center(c / spec.cols, c % spec.cols);
        let (dx, dy) = (ctr.x - pose.x_m, ctr.y - pose.y_m);
        let world = dy.atan2(dx);
        (
            dx.hypot(dy),
            wrap_rad(world - pose.heading_deg.to_radians()),
            world,
        )
    }

    /// The visibility polygon of a recorded pose with the binary map `occupied` as the
    /// mapped surfaces.
    fn final_polygon(&self, r: &PoseRecord, occupied: &[bool]) -> Polygon {
        let occluder: Vec<Option<usize>> = (0..r.main.len())
            .map(|d| {
                self.occlusion
                    .occluder_of(self.model, r.pose, d, &r.main[d], Some(occupied))
            })
            .collect();
        if self.silent == SilentBound::Off {
            return self.occlusion.polygon_of(self.model, &occluder, &r.missing);
        }
        let (occluder, missing) =
            self.occlusion
                .bound_silent(self.model, &occluder, &r.leak, &r.missing, self.silent);
        self.occlusion.polygon_of(self.model, &occluder, &missing)
    }

    /// Whether evidence `amount` of pose record `r` to cell `c` stands under polygon
    /// `poly`: occupancy (amount > 0) where δ ≤ g, free (amount < 0) where δ < −g.
    fn stands(&self, r: &PoseRecord, poly: &Polygon, c: u32, amount: f32) -> bool {
        let (range, theta, _) = self.range_bearing(r.pose, c);
        let depth = self.occlusion.depth(poly, range, theta);
        let g = self.occlusion.guard_m;
        if amount > 0.0 {
            depth <= g
        } else {
            depth < -g
        }
    }

    /// `mirror`, occupancy grid: the log-odds replayed from the prior `l0` with the kept
    /// increments in order (clamped to ±`clamp` after each, as online) and the cells that
    /// got evidence; `occupied` is the online map's binary map.
    pub fn replay(
        &self,
        n: usize,
        l0: f64,
        clamp: f64,
        occupied: &[bool],
    ) -> (Vec<f64>, Vec<bool>) {
        let keep = self.verdicts(occupied);
        let mut l = vec![l0; n];
        let mut observed = vec![false; n];
        for (r, k) in self.records.iter().zip(&keep) {
            for (&(c, a), &kept) in r.evidence.iter().flatten().zip(k) {
                if kept {
                    let c = c as usize;
                    l[c] = (l[c] + a as f64).clamp(-clamp, clamp);
                    observed[c] = true;
                }
            }
        }
        (l, observed)
    }

    /// `mirror`, EKF: per cell the evidence (mean rises) of the poses that cannot see it
    /// under the final map `occupied`.
    pub fn explained(&self, n: usize, occupied: &[bool]) -> Vec<f64> {
        let keep = self.verdicts(occupied);
        let mut out = vec![0.0; n];
        for (r, k) in self.records.iter().zip(&keep) {
            for (&(c, a), &kept) in r.evidence.iter().flatten().zip(k) {
                if a > 0.0 && !kept {
                    out[c as usize] += a as f64;
                }
            }
        }
        out
    }

    /// Per pose record, per piece of evidence (in order): whether it stands under the
    /// pose's polygon rebuilt against the final map `occupied` ([`Self::stands`]).
    fn verdicts(&self, occupied: &[bool]) -> Vec<Vec<bool>> {
        use rayon::prelude::*;
        self.records
            .par_iter()
            .map(|r| {
                let poly = self.final_polygon(r, occupied);
                r.evidence
                    .iter()
                    .flatten()
                    .map(|&(c, a)| self.stands(r, &poly, c, a))
                    .collect()
            })
            .collect()
    }

    /// The two-way −3 dB main-lobe width θ₃ of the direction nearest broadside, rad.
    pub fn main_lobe_width(&self) -> f64 {
        let m = self.model;
        let nd = m.directions();
        let d = (0..nd)
            .min_by(|&a, &b| {
                m.direction_rad(a)
                    .abs()
                    .total_cmp(&m.direction_rad(b).abs())
            })
            .unwrap_or(0);
        let th0 = m.direction_rad(d);
        let main = m.params.main_weight();
        let step = 0.01f64.to_radians();
        let half = |sign: f64| {
            let mut t = 0.0;
            while t < std::f64::consts::PI && m.weight(d, th0 + sign * t) >= main {
                t += step;
            }
            t
        };
        half(1.0) + half(-1.0)
    }

    /// The minimum aspect A_min of the `aspect` rule, rad.
    pub fn min_aspect(&self) -> f64 {
        self.params.aspect_lobes * self.main_lobe_width()
    }

    /// `aspect`: per cell of `cells`, whether the poses whose summed evidence to it is at
    /// least `min_support` view it from directions spanning at least [`Self::min_aspect`]
    /// (cells not in `cells`: true).
    pub fn aspect_ok(&self, cells: &[bool], min_support: f64) -> Vec<bool> {
        let a_min = self.min_aspect();
        // per cell: (first bearing, lowest and highest bearing relative to it)
        let mut span: Vec<Option<(f64, f64, f64)>> = vec![None; cells.len()];
        for r in &self.records {
            let mut sum: std::collections::BTreeMap<u32, f64> = Default::default();
            for &(c, a) in r.evidence.iter().flatten() {
                if a > 0.0 && cells[c as usize] {
                    *sum.entry(c).or_default() += a as f64;
                }
            }
            for (c, s) in sum {
                if s < min_support {
                    continue;
                }
                let (_, _, world) = self.range_bearing(r.pose, c);
                let e = &mut span[c as usize];
                match e {
                    None => *e = Some((world, 0.0, 0.0)),
                    Some((first, lo, hi)) => {
                        let rel = wrap_rad(world - *first);
                        *lo = lo.min(rel);
                        *hi = hi.max(rel);
                    }
                }
            }
        }
        cells
            .iter()
            .zip(&span)
            .map(|(&c, s)| !c || s.is_some_and(|(_, lo, hi)| hi - lo >= a_min))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ghost_params_are_checked() {
        assert!(GhostParams::default().check().is_ok());
        let bad = GhostParams {
            aspect_lobes: -1.0,
            ..Default::default()
        };
        let e = bad.check().unwrap_err().to_string();
        assert!(e.contains("`aspect_lobes`") && e.contains("must be"), "{e}");
        assert_eq!(GhostRule::Mirror.name(), "mirror");
    }

    /// metrics.json names each mapping choice as its command-line value, so a user's
    /// script can pass a run's parameters back as flags (`"rule": "mirror"`, not `"Mirror"`).
    #[test]
    fn mapping_choices_serialise_as_their_flag_values() {
        use crate::mapping::ekf::EkfVariant;
        use clap::ValueEnum;
        fn same<T: ValueEnum + serde::Serialize>() {
            for v in T::value_variants() {
                let flag = v.to_possible_value().unwrap().get_name().to_string();
                assert_eq!(serde_json::to_string(v).unwrap(), format!("\"{flag}\""));
            }
        }
        same::<GhostRule>();
        same::<EkfVariant>();
        same::<SilentBound>();
        assert_eq!(GhostRule::None.name(), "none");
    }
}
