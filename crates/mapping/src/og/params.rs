//! Occupancy-grid parameters ([`OgParams`], checked once into [`OgValid`]) and the
//! log-odds helpers.
//!
//! Log-odds l = ln(p/(1−p)): prior l0 from p0, increments l_occ from p_occ and l_free from
//! p_free; the inverse is the logistic function [`sigmoid`].

use crate::error::{Error, Result};
use crate::grid::SilentBound;
use crate::params::{ParamGuard, Valid};

/// Occupancy-grid parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OgParams {
    /// Prior occupancy probability p0 (0.5).
    pub prior: f64,
    /// Detector false-alarm probability per bin (1e-3).
    pub pfa: f64,
    /// Inverse-sensor occupancy probability of a detection (0.9 → l_occ = 2.20).
    pub p_occ: f64,
    /// Inverse-sensor probability of a cell in front of the first detection (0.35 →
    /// l_free = −0.62).
    pub p_free: f64,
    /// Log-odds clamp (±10).
    pub clamp: f64,
    /// Range-side-lobe masking margin β of the detector, dB (10).
    pub mask_db: f64,
    /// Margin of the side-lobe explanation test, dB (0): a detection is explained by a side
    /// lobe when E_d < 10^(side_db/10)·w_d(θ_d')·E_d'.
    pub side_db: f64,
    /// Lowest two-way weight of a cell that gets free evidence, dB (−10); the evidence is
    /// l_free·s·w (weighted by the two-way pattern).
    pub free_db: f64,
    /// How a direction without an occluder bounds the visibility polygon
    /// ([`SilentBound`]; `nearer` by default, `off`: at the maximum range).
    pub bound_silent: SilentBound,
    /// Deepest a cell's centre may lie behind the visibility polygon and still get
    /// occupancy credit from a range ring, m (0.05 m by default: half a cell of the
    /// default 0.1 m grid; None: the occlusion guard g, every visible cell). A cell whose
    /// centre lies more than half a cell beyond the surface along the ray does not hold it
    /// there; the guard's extra two bins (the window kernel's half-width) keep the cells
    /// behind the surface visible, and a wall found where it was missed comes with a rim of
    /// credited cells beyond it.
    pub credit_depth_m: Option<f64>,
    /// Which cells of a detection's range ring get its occupancy credit ([`OgCredit`];
    /// `ring` by default).
    pub credit: OgCredit,
}

/// Which cells of a detection's range ring get its occupancy credit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum OgCredit {
    /// Every visible cell of the ring, by responsibility (pattern × share × belief).
    #[default]
    Ring,
    /// The cells at the bearings of the echoes the scan's energies resolve at that bin
    /// ([`super::angular`]); a detection that resolved no echo credits nothing.
    Echo,
}

impl OgCredit {
    /// Every value, in the order the command line lists them.
    pub const ALL: [OgCredit; 2] = [OgCredit::Ring, OgCredit::Echo];

    /// Name (`ring`, `echo`): the command-line value and the `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            OgCredit::Ring => "ring",
            OgCredit::Echo => "echo",
        }
    }
}

impl std::fmt::Display for OgCredit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for OgCredit {
    type Err = Error;
    /// Parse an [`OgCredit::name`].
    fn from_str(s: &str) -> Result<OgCredit> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "credit", "credit")
    }
}

impl Default for OgParams {
    fn default() -> Self {
        OgParams {
            prior: 0.5,
            pfa: 1e-3,
            p_occ: 0.9,
            p_free: 0.35,
            clamp: 10.0,
            mask_db: 10.0,
            side_db: 0.0,
            free_db: -10.0,
            bound_silent: SilentBound::Nearer,
            credit_depth_m: Some(0.05),
            credit: OgCredit::Ring,
        }
    }
}

fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

/// Logistic function p = 1/(1 + e^{−l}).
pub fn sigmoid(l: f64) -> f64 {
    1.0 / (1.0 + (-l).exp())
}

/// Occupancy-grid parameters that passed [`ParamGuard::check`].
pub type OgValid = Valid<OgParams>;

impl ParamGuard for OgParams {
    type Checked = OgValid;

    /// Prior in (0, 1) with log-odds inside the clamp, P_fa in (0, 0.5], p_occ in
    /// (0.5, 1), p_free in (0, 0.5), clamp > 0, masking margin ≥ 0 dB, free level ≤ 0 dB,
    /// side-lobe margin finite, credit depth ≥ 0 m, the prior's log-odds inside the clamp.
    fn check(&self) -> Result<OgValid> {
        let open01 = |v: f64| v.is_finite() && v > 0.0 && v < 1.0;
        if !open01(self.prior) {
            return Err(Error::param("prior", "must be in (0, 1)"));
        }
        if !(open01(self.pfa) && self.pfa <= 0.5) {
            return Err(Error::param("pfa", "must be in (0, 0.5]"));
        }
        if !(open01(self.p_occ) && self.p_occ > 0.5) {
            return Err(Error::param("p_occ", "must be in (0.5, 1)"));
        }
        if !(open01(self.p_free) && self.p_free < 0.5) {
            return Err(Error::param("p_free", "must be in (0, 0.5)"));
        }
        if !(self.clamp.is_finite() && self.clamp > 0.0) {
            return Err(Error::param("clamp", "must be > 0"));
        }
        if !(self.mask_db.is_finite() && self.mask_db >= 0.0) {
            return Err(Error::param("mask_db", "must be >= 0 dB"));
        }
        if !(self.free_db.is_finite() && self.free_db <= 0.0) {
            return Err(Error::param("free_db", "must be <= 0 dB"));
        }
        if !self.side_db.is_finite() {
            return Err(Error::param("side_db", "must be finite"));
        }
        if let Some(x) = self.credit_depth_m {
            if !(x.is_finite() && x >= 0.0) {
                return Err(Error::param("credit_depth_m", "must be >= 0 m"));
            }
        }
        if logit(self.prior).abs() >= self.clamp {
            return Err(Error::param("prior", "prior log-odds beyond the clamp"));
        }
        Ok(Valid::new(*self))
    }
}

impl OgParams {
    /// Prior log-odds l0.
    pub fn l0(&self) -> f64 {
        logit(self.prior)
    }
    /// Occupied increment l_occ.
    pub fn l_occ(&self) -> f64 {
        logit(self.p_occ)
    }
    /// Free increment l_free (negative).
    pub fn l_free(&self) -> f64 {
        logit(self.p_free)
    }
}
