//! MPC extraction (DESIGN §2 "MPC extraction"): iterative 2-D CLEAN over each position's
//! delay × angle energy matrix, and a naive local-maximum picker kept as the baseline.
//!
//! Takes an [`EnergyMatrix`], the campaign (array, band, processing, poses) and checked
//! parameters ([`ExtractValid`]); gives one [`Mpc`] per extracted component: position,
//! delay_ns, angle_rel_deg, angle_global_deg, power_db, x_m, y_m (plus the grid cell and
//! the SNR).
//!
//! * [`clean`]: CLEAN per position on the residual, with the side-lobe guard, sub-cell
//!   refinement and footprint subtraction; [`footprint`]: the footprint model (two-way
//!   pattern × window kernel); [`edge`]: the angle of a peak near either end of a
//!   mechanical scan (possibly a source beyond the scanned sector).
//! * [`peaks`]: every cell that is a strict maximum of its 3×3 neighbourhood above
//!   F·10^(margin/10): no footprint, so side lobes and range side lobes become MPCs.
//! * [`diffuse`]: each MPC labelled discrete or diffuse from the layout's wall curve and
//!   level; [`fold`]: wall echoes the layout places beyond the unambiguous range c/(2Δf),
//!   folded into the span, labelled folded (both kept out of the clusters and Table 1).
//! * [`io`]: the MPC table (Parquet) and its metadata.
//!
//! Every MPC's delay is (b + δ_b)·T_b (clamped at 0), its relative angle the beam's plus
//! δ_d steps, its global angle the pose heading plus the relative angle wrapped into
//! (−180°, 180°], its position the pose plus the range r = c₀τ/2 along the global angle;
//! power_db = 10·log10 of the component's peak energy, snr_db the same over the floor F.
//! Delays below `min_delay_ns` (automatic: [`auto_min_delay_ns`]) are zeroed before
//! extraction. Positions are extracted in parallel, results in position order.
//! Measurements of the edge fit are in `docs/mpc.md`.
//!
//! ```no_run
//! use pradar_formats::campaign::manifest::Campaign;
//! use pradar_radar::energy::EnergyMatrix;
//! use pradar_channel::mpc::{extract, table_metadata, write_mpcs, ExtractParams};
//! use pradar_formats::params::ParamGuard;
//! let c = Campaign::load(std::path::Path::new("campaign.toml"))?;
//! let em = EnergyMatrix::read(std::path::Path::new("energy.parquet"))?;
//! let params = ExtractParams::default().check()?;
//! let mpcs = extract(&em, &c, &params)?;
//! write_mpcs(std::path::Path::new("mpcs.parquet"), &mpcs, table_metadata(&em, &c, &params))?;
//! # Ok::<(), pradar_formats::Error>(())
//! ```

pub mod clean;
pub mod diffuse;
pub mod edge;
pub mod fold;
pub mod footprint;
pub mod io;
pub mod params;
pub mod peaks;

pub use diffuse::{DiffuseParams, DiffuseSummary, DiffuseValid};
pub use fold::{Fold, FoldSummary};
pub use io::{mpc_frame, read_mpcs, read_sector_deg, table_metadata, write_mpcs, MPC_COLUMNS};
pub use params::{ExtractParams, ExtractValid, Method};

use crate::campaign::manifest::{Campaign, Pose};
use crate::energy::{EnergyMatrix, EnergySource};
use crate::error::{Error, Result};
use crate::units::{db, wrap_deg};
use footprint::Footprint;
use rayon::prelude::*;

/// One multipath component.
#[derive(Debug, Clone, PartialEq)]
pub struct Mpc {
    /// Position index.
    pub position: usize,
    /// Round-trip delay, ns.
    pub delay_ns: f64,
    /// Angle relative to the device heading, degrees.
    pub angle_rel_deg: f64,
    /// Global angle, degrees in (−180, 180].
    pub angle_global_deg: f64,
    /// Peak energy of the component, dB (10·log10 of the energy units).
    pub power_db: f64,
    /// Peak over the floor, dB.
    pub snr_db: f64,
    /// Scatterer x in the global frame, m.
    pub x_m: f64,
    /// Scatterer y in the global frame, m.
    pub y_m: f64,
    /// Direction index of the peak cell.
    pub direction: usize,
    /// Bin index of the peak cell.
    pub bin: usize,
    /// Discrete, diffuse (dense wall return) or folded (a wall echo from beyond the
    /// unambiguous range); [`Component::Discrete`] until labelled by [`diffuse`] and
    /// [`fold`].
    pub component: Component,
    /// The wall curve the MPC lies on, when it does ([`diffuse`]).
    pub wall: Option<WallCell>,
}

/// What the diffuse stage predicts for an MPC on a wall's curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallCell {
    /// E₁ in dB: the expected energy in the MPC's cell of a Lambertian wall of backscatter
    /// 1 m²/m (same units as `power_db`).
    pub unit_db: f64,
    /// Incidence angle on the wall along the MPC's bearing, from the wall normal, degrees.
    pub incidence_deg: f64,
}

/// The component an MPC belongs to (DESIGN §2 "Diffuse component").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Component {
    /// A discrete path (cluster ray, corner, edge, specular point, object).
    #[default]
    Discrete,
    /// A diffuse wall return (the dense component).
    Diffuse,
    /// A wall echo from beyond the sweep's unambiguous range, folded into the kept bins
    /// ([`fold`]): not at its true range, kept out of the clusters and the fits.
    Folded,
}

impl Component {
    /// The name in the MPC table's `component` column.
    pub fn name(self) -> &'static str {
        match self {
            Component::Discrete => "discrete",
            Component::Diffuse => "diffuse",
            Component::Folded => "folded",
        }
    }

    /// Parse a `component` cell.
    pub fn parse(s: &str) -> Option<Component> {
        match s {
            "discrete" => Some(Component::Discrete),
            "diffuse" => Some(Component::Diffuse),
            "folded" => Some(Component::Folded),
            _ => None,
        }
    }
}

/// One position's energy grid as the extractors see it: sizes, steps, pose, floor and
/// threshold.
pub(crate) struct PositionView<'a> {
    em: &'a EnergyMatrix,
    p: usize,
    /// Directions.
    pub(crate) nd: usize,
    /// Bins.
    pub(crate) nb: usize,
    /// Bin width, ns.
    tb: f64,
    /// Direction step, degrees (0 for a single direction).
    pub(crate) step: f64,
    pose: Pose,
    /// Energy floor F.
    pub(crate) floor: f64,
    /// Extraction threshold F·10^(margin/10).
    pub(crate) thr: f64,
}

impl<'a> PositionView<'a> {
    fn new(em: &'a EnergyMatrix, c: &Campaign, p: usize, margin_db: f64, floor: f64) -> Self {
        let nd = em.directions();
        PositionView {
            em,
            p,
            nd,
            nb: em.bins,
            tb: em.meta.bin_width_ns,
            step: if nd > 1 {
                em.angles_rel_deg[1] - em.angles_rel_deg[0]
            } else {
                0.0
            },
            pose: c.manifest.poses[p],
            floor,
            thr: floor * 10f64.powf(margin_db / 10.0),
        }
    }

    /// The beams' angles relative to the heading, degrees.
    pub(crate) fn angles(&self) -> &[f64] {
        &self.em.angles_rel_deg
    }

    /// The (original) energy of cell (d, b); 0 in a direction without a sweep (`[sweeps]
    /// missing`: nothing is extracted there, and no neighbour's refinement reads it).
    pub(crate) fn energy(&self, d: usize, b: usize) -> f64 {
        if !self.em.has(self.p, d) {
            return 0.0;
        }
        self.em.profile(self.p, d)[b]
    }

    /// The energy of cell (d + dd, b + bb), 0 outside the grid.
    pub(crate) fn energy_near(&self, d: usize, b: usize, dd: i64, bb: i64) -> f64 {
        let (x, y) = (d as i64 + dd, b as i64 + bb);
        if x < 0 || y < 0 || x as usize >= self.nd || y as usize >= self.nb {
            0.0
        } else {
            self.energy(x as usize, y as usize)
        }
    }

    /// An energy in dB, floored 30 dB below the floor F.
    pub(crate) fn log_energy(&self, e: f64) -> f64 {
        db(e.max(self.floor * 1e-3))
    }

    /// The energies with the bins below `min_delay_ns` zeroed: the initial residual,
    /// direction-major.
    fn residual(&self, min_delay_ns: f64) -> Vec<f64> {
        let b_min = ((min_delay_ns / self.tb).ceil() as usize).min(self.nb);
        (0..self.nd)
            .flat_map(|d| {
                let has = self.em.has(self.p, d);
                self.em
                    .profile(self.p, d)
                    .iter()
                    .enumerate()
                    .map(move |(b, &v)| if b < b_min || !has { 0.0 } else { v })
            })
            .collect()
    }

    /// The MPC of cell (d, b) with energy `e`, offset by `dd` directions and `db_` bins.
    pub(crate) fn mpc(&self, d: usize, b: usize, e: f64, dd: f64, db_: f64) -> Mpc {
        let delay_ns = ((b as f64 + db_) * self.tb).max(0.0);
        let angle_rel = self.em.angles_rel_deg[d] + dd * self.step;
        let glob = wrap_deg(self.pose.heading_deg + angle_rel);
        let r = crate::units::range_m(delay_ns);
        Mpc {
            position: self.p,
            delay_ns,
            angle_rel_deg: angle_rel,
            angle_global_deg: glob,
            power_db: db(e),
            snr_db: db(e / self.floor),
            x_m: self.pose.x_m + r * glob.to_radians().cos(),
            y_m: self.pose.y_m + r * glob.to_radians().sin(),
            direction: d,
            bin: b,
            component: Component::Discrete,
            wall: None,
        }
    }
}

/// Extract the MPCs of one position.
fn extract_position(
    em: &EnergyMatrix,
    c: &Campaign,
    fp: Option<&Footprint>,
    p: usize,
    params: &ExtractValid,
    floor: f64,
) -> Vec<Mpc> {
    let v = PositionView::new(em, c, p, params.margin_db, floor);
    let min_delay = params.min_delay_ns.unwrap_or_else(|| auto_min_delay_ns(em));
    let r = v.residual(min_delay);
    match (params.method, fp) {
        (Method::Peaks, _) | (Method::Clean, None) => peaks::local_maxima(&v, &r, params.max_mpcs),
        (Method::Clean, Some(fp)) => clean::clean(&v, r, fp, params),
    }
}

/// The automatic lower delay limit (see [`ExtractParams::min_delay_ns`]).
pub fn auto_min_delay_ns(em: &EnergyMatrix) -> f64 {
    if em.meta.coupling == "gate" {
        em.meta.gate_ns() + 4.0 * em.meta.bin_width_ns
    } else {
        0.0
    }
}

/// Extract MPCs from every position (positions in parallel, results in position order),
/// each labelled discrete or diffuse by [`diffuse`], then folded by [`fold`].
pub fn extract(em: &EnergyMatrix, c: &Campaign, params: &ExtractValid) -> Result<Vec<Mpc>> {
    extract_labelled(em, c, params).map(|x| x.0)
}

/// Positions loaded together from an [`EnergySource`]: a few row groups, and at least two
/// per thread so the positions of a run keep both cores busy.
fn load_positions(nd: usize, nb: usize) -> usize {
    (4 * crate::energy::writer::group_positions(nd, nb)).max(2 * rayon::current_num_threads())
}

/// What the labelling stages found ([`extract_labelled`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Labels {
    /// The diffuse stage's summary (its counts before the fold relabels some).
    pub diffuse: DiffuseSummary,
    /// The fold stage's summary ([`FoldSummary::none`] when nothing can fold).
    pub fold: FoldSummary,
}

impl Labels {
    /// MPCs labelled diffuse after the fold.
    pub fn diffuse(&self) -> usize {
        self.diffuse.diffuse - self.fold.from_diffuse
    }
}

/// [`extract`], with what the diffuse and fold stages found, from any [`EnergySource`] (a
/// whole matrix, or a table read a few positions at a time: the MPCs do not depend on
/// which).
pub fn extract_labelled(
    src: &dyn EnergySource,
    c: &Campaign,
    params: &ExtractValid,
) -> Result<(Vec<Mpc>, Labels)> {
    let em = src.header();
    crate::energy::check_campaign(c, em, &c.path)?;
    let floor = em.meta.noise_mean();
    if !(floor.is_finite() && floor > 0.0) {
        return Err(Error::param(
            "n0",
            "energy table has no positive noise estimate",
        ));
    }
    // the fold stage runs whatever `diffuse.enabled` says; it needs the beam's width
    let fold = Fold::of(c);
    let fp = if params.method == Method::Clean || params.diffuse.enabled || fold.is_some() {
        Some(Footprint::new(c, em, params.kernel_bins)?)
    } else {
        None
    };
    let clean_fp = fp.as_ref().filter(|_| params.method == Method::Clean);
    let step = load_positions(em.directions(), em.bins);
    let mut mpcs: Vec<Mpc> = Vec::new();
    for p0 in (0..em.positions).step_by(step) {
        let p1 = (p0 + step).min(em.positions);
        let part = src.load(p0, p1)?;
        let per: Vec<Vec<Mpc>> = (p0..p1)
            .into_par_iter()
            .map(|p| extract_position(&part, c, clean_fp, p, params, floor))
            .collect();
        mpcs.extend(per.into_iter().flatten());
    }
    // checked with the extraction parameters
    let diffuse_params = crate::params::Valid::new(params.diffuse);
    let summary = match &fp {
        Some(fp) => diffuse::label(
            &mut mpcs,
            c,
            &em.angles_rel_deg,
            em.meta.bin_width_ns,
            fp,
            &diffuse_params,
        )?,
        None => DiffuseSummary::none(),
    };
    let fold = match (&fold, &fp) {
        (Some(f), Some(fp)) if !mpcs.is_empty() => {
            // the continuum folds need the diffuse level; without it only the compact ones
            let m = &c.manifest;
            let level = if summary.level_m2_per_m.is_finite() {
                let pattern = crate::pattern::ArrayPattern::new(m.array, m.band.center_hz())?;
                let g0 = pattern.gain(0.0, 0.0, m.band.center_hz());
                let lc = crate::units::C0 / m.band.center_hz();
                Some(fold::FoldLevel {
                    fp,
                    angles_rel_deg: &em.angles_rel_deg,
                    bin_width_ns: em.meta.bin_width_ns,
                    gl: g0 * g0 * lc * lc,
                    reach_deg: fp.reach_deg(1e-3),
                    limit_m2_per_m: summary.level_m2_per_m
                        * 10f64.powf(params.diffuse.discrete_db / 10.0),
                })
            } else {
                None
            };
            f.label(
                &mut mpcs,
                &m.poses,
                diffuse::beam_half_width_deg(fp, &em.angles_rel_deg),
                params.diffuse.range_bins * crate::units::range_m(em.meta.bin_width_ns),
                level.as_ref(),
            )
        }
        _ => FoldSummary::none(),
    };
    Ok((
        mpcs,
        Labels {
            diffuse: summary,
            fold,
        },
    ))
}
