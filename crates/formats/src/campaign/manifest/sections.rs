//! The manifest's measurement sections: the band, the array, the directions, the noise
//! floor, a pose and the processing options, each with the `check` that validates it where
//! the manifest is read (errors name the manifest file and the dotted field).

use super::limits::*;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Swept frequency band of the VNA.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Band {
    /// First frequency, Hz.
    pub start_hz: f64,
    /// Last frequency, Hz.
    pub stop_hz: f64,
    /// Number of frequency points (inclusive of both ends).
    pub points: usize,
}

impl Band {
    /// Bandwidth B = stop - start, Hz.
    pub fn bandwidth_hz(&self) -> f64 {
        self.stop_hz - self.start_hz
    }
    /// Frequency step, Hz.
    pub fn step_hz(&self) -> f64 {
        self.bandwidth_hz() / (self.points - 1) as f64
    }
    /// Frequency of point `k`, Hz.
    pub fn freq(&self, k: usize) -> f64 {
        self.start_hz + k as f64 * self.step_hz()
    }
    /// Centre frequency, Hz.
    pub fn center_hz(&self) -> f64 {
        0.5 * (self.start_hz + self.stop_hz)
    }
    /// Validate; `prefix` names the table in errors.
    pub fn check(&self) -> Result<()> {
        if !(self.start_hz.is_finite() && self.start_hz > 0.0) {
            return Err(Error::param(
                "band.start_hz",
                "must be a positive frequency",
            ));
        }
        if !(self.stop_hz.is_finite() && self.stop_hz > self.start_hz) {
            return Err(Error::param("band.stop_hz", "must be above band.start_hz"));
        }
        if self.points < 8 {
            return Err(Error::param(
                "band.points",
                "need at least 8 frequency points",
            ));
        }
        if self.points > MAX_POINTS {
            return Err(Error::param(
                "band.points",
                format!(
                    "{} points exceeds {MAX_POINTS} (the largest VNA sweep)",
                    self.points
                ),
            ));
        }
        Ok(())
    }
}

/// Beam steering mode.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum Steering {
    /// The array is rotated: the broadside pattern turned to the direction (the campaign's case).
    #[default]
    Mechanical,
    /// Phase steering at the centre frequency; valid for |θs| ≤ 60°.
    Electronic,
}

/// `[array]`: the planar array of each side of the quasi-monostatic pair.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ArrayConfig {
    /// Number of elements, a perfect square (16, 100, 400 → 4x4, 10x10, 20x20).
    pub elements: usize,
    /// 1-bit transmitarray quantisation of the element phases.
    #[serde(default)]
    pub one_bit: bool,
    /// Element power pattern exponent q in cos^q(θ).
    #[serde(default = "default_q")]
    pub element_q: f64,
    /// Steering mode.
    #[serde(default)]
    pub steering: Steering,
}

fn default_q() -> f64 {
    1.0
}

impl ArrayConfig {
    /// Side length of the square array.
    pub fn side(&self) -> usize {
        (self.elements as f64).sqrt().round() as usize
    }
    /// Validate.
    pub fn check(&self) -> Result<()> {
        let s = self.side();
        if self.elements == 0 || s * s != self.elements {
            return Err(Error::param(
                "array.elements",
                format!(
                    "{} is not a perfect square (use 16, 100 or 400)",
                    self.elements
                ),
            ));
        }
        if !(self.element_q.is_finite() && self.element_q >= 0.0) {
            return Err(Error::param("array.element_q", "must be finite and >= 0"));
        }
        Ok(())
    }
    /// Short label, e.g. `20x20 one_bit mechanical q=1`.
    pub fn label(&self) -> String {
        let s = self.side();
        format!(
            "{s}x{s} {} {} q={}",
            if self.one_bit { "one_bit" } else { "ideal" },
            match self.steering {
                Steering::Mechanical => "mechanical",
                Steering::Electronic => "electronic",
            },
            self.element_q
        )
    }
}

/// `[directions]`: the steering directions relative to the device heading.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Directions {
    /// First direction, degrees.
    pub start_deg: f64,
    /// Last direction, degrees.
    pub stop_deg: f64,
    /// Step, degrees.
    pub step_deg: f64,
}

impl Directions {
    /// Width of the scanned sector, degrees: stop − start, at least one step (a single
    /// direction still sees a beam's width).
    pub fn width_deg(&self) -> f64 {
        (self.stop_deg - self.start_deg).max(self.step_deg)
    }
    /// Number of directions (checked manifests: the span is a whole number of steps, at
    /// most [`limits::MAX_DIRECTIONS`]).
    pub fn count(&self) -> usize {
        let n = ((self.stop_deg - self.start_deg) / self.step_deg).round();
        if n.is_finite() && n >= 0.0 {
            (n as usize).saturating_add(1)
        } else {
            1
        }
    }
    /// Angle of direction `d` relative to the heading, degrees.
    pub fn angle_deg(&self, d: usize) -> f64 {
        self.start_deg + d as f64 * self.step_deg
    }
    /// The index of the direction at `angle_deg` (within 1e-6 of a step of a grid
    /// angle), if the grid has one.
    pub fn index_of(&self, angle_deg: f64) -> Option<usize> {
        let x = (angle_deg - self.start_deg) / self.step_deg;
        let i = x.round();
        ((x - i).abs() <= 1e-6 && i >= 0.0 && (i as usize) < self.count()).then_some(i as usize)
    }

    /// All relative angles, degrees.
    pub fn angles_deg(&self) -> Vec<f64> {
        (0..self.count()).map(|d| self.angle_deg(d)).collect()
    }
    /// Validate.
    pub fn check(&self) -> Result<()> {
        if !(self.step_deg.is_finite() && self.step_deg > 0.0) {
            return Err(Error::param("directions.step_deg", "must be positive"));
        }
        if !(self.start_deg.is_finite()
            && self.stop_deg.is_finite()
            && self.stop_deg >= self.start_deg)
        {
            return Err(Error::param(
                "directions.stop_deg",
                "must be >= directions.start_deg",
            ));
        }
        if self.start_deg < -180.0 || self.stop_deg > 180.0 {
            return Err(Error::param(
                "directions",
                "angles must lie in [-180, 180] degrees",
            ));
        }
        let steps = (self.stop_deg - self.start_deg) / self.step_deg;
        if steps + 1.0 > MAX_DIRECTIONS as f64 {
            return Err(Error::param(
                "directions.step_deg",
                format!(
                    "{} gives {:.0} directions, more than {MAX_DIRECTIONS} (a 0.1° step over a full turn)",
                    self.step_deg,
                    steps.floor() + 1.0
                ),
            ));
        }
        if (steps - steps.round()).abs() > 1e-6 {
            let last = self.start_deg + steps.round() * self.step_deg;
            return Err(Error::param(
                "directions.step_deg",
                format!(
                    "{}° does not divide stop_deg − start_deg = {}° (the scan would end at {last}°, not at stop_deg = {}°)",
                    self.step_deg,
                    self.stop_deg - self.start_deg,
                    self.stop_deg
                ),
            ));
        }
        Ok(())
    }
}

/// `[noise]`: receiver noise floor and transmit power.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NoiseConfig {
    /// Complex white noise power per frequency point, dBm.
    pub floor_dbm: f64,
    /// VNA source power, dBm (S21 noise variance = floor / tx power).
    #[serde(default)]
    pub tx_power_dbm: f64,
}

impl NoiseConfig {
    /// Noise variance E|n|² of S21 per frequency point (dimensionless).
    pub fn s21_variance(&self) -> f64 {
        10f64.powf((self.floor_dbm - self.tx_power_dbm) / 10.0)
    }
}

/// A device pose in the global frame.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    /// x, m.
    pub x_m: f64,
    /// y, m.
    pub y_m: f64,
    /// Heading, degrees counter-clockwise from +x.
    pub heading_deg: f64,
}

/// Window applied to the sweep before the IFFT.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum WindowKind {
    /// Symmetric Hann window (default).
    #[default]
    Hann,
    /// No window.
    Rect,
}

/// How the direct Tx→Rx coupling is removed.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum CouplingRemoval {
    /// Keep it.
    None,
    /// Time gating: zero the CIR before `gate_ns`.
    #[default]
    Gate,
    /// Background subtraction: subtract the complex mean sweep over the directions of a
    /// position (the coupling does not rotate with the beam; echoes do).
    Mean,
}

/// `[processing]`: energy-stage options (all optional).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Processing {
    /// Window.
    pub window: WindowKind,
    /// IFFT samples per bin (odd, >= 3); Nfft = (points - 1) * oversample.
    pub oversample: usize,
    /// Coupling removal.
    pub coupling: CouplingRemoval,
    /// Gate length for `coupling = "gate"`, ns.
    pub gate_ns: f64,
    /// Largest delay kept, ns (bins 0..=max_delay/T_b).
    pub max_delay_ns: f64,
    /// Bins at or beyond this delay are taken as signal-free for the N0 estimate, ns.
    pub noise_from_ns: f64,
}

impl Default for Processing {
    fn default() -> Self {
        Processing {
            window: WindowKind::Hann,
            oversample: 5,
            coupling: CouplingRemoval::Gate,
            gate_ns: 3.0,
            max_delay_ns: 100.0,
            noise_from_ns: 80.0,
        }
    }
}

impl Processing {
    /// Validate.
    pub fn check(&self) -> Result<()> {
        if self.oversample < 3 || self.oversample.is_multiple_of(2) {
            return Err(Error::param(
                "processing.oversample",
                "must be an odd number >= 3",
            ));
        }
        if self.oversample > MAX_OVERSAMPLE {
            return Err(Error::param(
                "processing.oversample",
                format!(
                    "{} exceeds {MAX_OVERSAMPLE} (IFFT samples per bin)",
                    self.oversample
                ),
            ));
        }
        if !(self.gate_ns.is_finite() && self.gate_ns >= 0.0) {
            return Err(Error::param("processing.gate_ns", "must be >= 0"));
        }
        if !(self.max_delay_ns.is_finite() && self.max_delay_ns > 0.0) {
            return Err(Error::param("processing.max_delay_ns", "must be > 0"));
        }
        if !(self.noise_from_ns.is_finite() && self.noise_from_ns >= 0.0) {
            return Err(Error::param("processing.noise_from_ns", "must be >= 0"));
        }
        Ok(())
    }

    /// Validate against the band: the IFFT length (points − 1) · oversample is at most
    /// [`limits::MAX_NFFT`], and `max_delay_ns` lies within the alias-free span
    /// (points − 1)/B of the sweep (beyond it the delays wrap around).
    pub fn check_with(&self, band: &Band) -> Result<()> {
        self.check()?;
        let nfft = (band.points - 1).saturating_mul(self.oversample);
        if nfft > MAX_NFFT {
            return Err(Error::param(
                "processing.oversample",
                format!(
                    "(band.points − 1) × oversample = {nfft} exceeds the IFFT limit {MAX_NFFT}"
                ),
            ));
        }
        let span_ns = (band.points - 1) as f64 * 1e9 / band.bandwidth_hz();
        if self.max_delay_ns > span_ns {
            return Err(Error::param(
                "processing.max_delay_ns",
                format!(
                    "{} ns beyond the sweep's alias-free span (band.points − 1)/B = {span_ns:.1} ns (band.points = {})",
                    self.max_delay_ns, band.points
                ),
            ));
        }
        Ok(())
    }
}
