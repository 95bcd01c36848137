//! The energy and time of one scan (all directions × pulses from one pose) of a radar
//! configuration: [`EnergyModel`] (constants, a TOML file a user edits; defaults and their
//! sources in docs/explore.md), checked into [`EnergyModelValid`]; [`EnergyModel::scan`]
//! gives a [`ScanCost`].
//!
//! A configuration is N elements per array (one Tx, one Rx), D directions, P pulses per
//! direction, K frequency points (ADC samples) per pulse and a transmit power P_tx. With
//! T_c the time of one pulse (sweep or chirp) and T_s the beam switching time per pulse:
//! * scan time T = D · P · (T_c + T_s);
//! * front end: N · (p_tx,el + p_rx,el) + p_radio while the scan runs (T);
//! * power amplifier: P_tx / η_PA while a pulse is on (D · P · T_c);
//! * receiver/ADC: e_ADC per sample, D · P · K samples;
//! * processing: the energy stage's work per sample and the mapper's per direction,
//!   t_proc = D · P · K · t_sample + D · t_direction, at a stated power per core:
//!   E_proc = p_core · t_proc.
//!
//! So the radio part (front end, PA, ADC) is exactly proportional to D · P (a test), and the
//! processing share is E_proc / E. The processing constants are a cost model (its defaults
//! are this machine's measured CPU time per sample and per direction, docs/explore.md), so a
//! configuration's figures are the same bytes on every run; `pradar explore` also writes
//! the measured time of each configuration beside them (`timing.csv`).

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The per-scan energy and time constants (defaults: docs/explore.md, "Energy model").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnergyModel {
    /// Power of one transmit element's front end (phase shifter / driver), mW.
    pub tx_element_mw: f64,
    /// Power of one receive element's front end (LNA / phase shifter), mW.
    pub rx_element_mw: f64,
    /// Power of the shared radio (synthesiser, mixers, baseband) while scanning, mW.
    pub radio_mw: f64,
    /// Power-amplifier efficiency η_PA (radiated / DC power), in (0, 1].
    pub pa_efficiency: f64,
    /// Duration of one pulse (one sweep or chirp), µs.
    pub pulse_us: f64,
    /// Beam switching (settling) time per pulse, µs.
    pub switch_us: f64,
    /// Receiver/ADC energy per sample, pJ.
    pub adc_pj_per_sample: f64,
    /// Power of one busy processor core, W.
    pub core_power_w: f64,
    /// CPU time of the energy stage per sample (window, IFFT, bin energies), ns.
    pub energy_stage_ns_per_sample: f64,
    /// CPU time of the mapper per direction of a scan, µs.
    pub mapper_us_per_direction: f64,
}

/// [`EnergyModel`] that passed its check.
pub type EnergyModelValid = Valid<EnergyModel>;

impl Default for EnergyModel {
    fn default() -> Self {
        EnergyModel {
            tx_element_mw: 20.0,
            rx_element_mw: 20.0,
            radio_mw: 300.0,
            pa_efficiency: 0.1,
            pulse_us: 50.0,
            switch_us: 1.0,
            adc_pj_per_sample: 20.0,
            core_power_w: 2.0,
            energy_stage_ns_per_sample: 450.0,
            mapper_us_per_direction: 750.0,
        }
    }
}

impl EnergyModel {
    /// Read a TOML file of constants (`[energy_model]` or top level; a missing key keeps
    /// its default, an unknown key is an error naming the file).
    pub fn load(path: &Path) -> Result<EnergyModel> {
        let text = crate::io::read_text(path)?;
        let mut t: toml::Table = toml::from_str(&text)
            .map_err(|e| Error::input(path, crate::campaign::manifest::one_line(&e.to_string())))?;
        let v = match t.remove("energy_model") {
            Some(v) => v,
            None => toml::Value::Table(t),
        };
        v.try_into().map_err(|e: toml::de::Error| {
            Error::input(path, crate::campaign::manifest::one_line(&e.to_string()))
        })
    }

    /// The defaults as a TOML file (what `explore` writes into its output folder).
    pub fn to_toml(&self) -> String {
        let body = toml::to_string(self).unwrap_or_default();
        format!("[energy_model]\n{body}")
    }
}

impl ParamGuard for EnergyModel {
    type Checked = EnergyModelValid;

    /// Every constant finite and ≥ 0; the PA efficiency in (0, 1]; the pulse longer than 0.
    fn check(&self) -> Result<EnergyModelValid> {
        let fields = [
            ("tx_element_mw", self.tx_element_mw),
            ("rx_element_mw", self.rx_element_mw),
            ("radio_mw", self.radio_mw),
            ("switch_us", self.switch_us),
            ("adc_pj_per_sample", self.adc_pj_per_sample),
            ("core_power_w", self.core_power_w),
            (
                "energy_stage_ns_per_sample",
                self.energy_stage_ns_per_sample,
            ),
            ("mapper_us_per_direction", self.mapper_us_per_direction),
        ];
        for (name, v) in fields {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::param(name, "must be finite and >= 0"));
            }
        }
        if !(self.pa_efficiency > 0.0 && self.pa_efficiency <= 1.0) {
            return Err(Error::param("pa_efficiency", "must be in (0, 1]"));
        }
        if !(self.pulse_us.is_finite() && self.pulse_us > 0.0) {
            return Err(Error::param("pulse_us", "must be finite and > 0"));
        }
        Ok(Valid::new(self.clone()))
    }
}

/// What one scan asks of the radar: elements per array, directions, pulses per direction,
/// samples (frequency points) per pulse and the transmit power.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanShape {
    /// Elements per array N.
    pub elements: usize,
    /// Directions D.
    pub directions: usize,
    /// Pulses per direction P.
    pub pulses: usize,
    /// Samples per pulse K.
    pub samples: usize,
    /// Transmit power, dBm.
    pub tx_power_dbm: f64,
}

/// Energy and time of one scan (the terms of the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ScanCost {
    /// Scan time T, s.
    pub scan_time_s: f64,
    /// Front-end energy (elements and radio over T), J.
    pub front_end_j: f64,
    /// Power-amplifier energy, J.
    pub pa_j: f64,
    /// Receiver/ADC energy, J.
    pub adc_j: f64,
    /// Processing time t_proc (model), s.
    pub processing_s: f64,
    /// Processing energy, J.
    pub processing_j: f64,
    /// Total energy per scan, J.
    pub energy_j: f64,
}

impl ScanCost {
    /// The radio part (front end, PA, ADC), J.
    pub fn radio_j(&self) -> f64 {
        self.front_end_j + self.pa_j + self.adc_j
    }
    /// The processing share E_proc / E (0 for a zero-energy scan).
    pub fn processing_share(&self) -> f64 {
        if self.energy_j > 0.0 {
            self.processing_j / self.energy_j
        } else {
            0.0
        }
    }
}

impl EnergyModel {
    /// The energy and time of one scan of this shape (module docs); called on the checked
    /// [`EnergyModelValid`] (which derefs to the model).
    pub fn scan(&self, s: &ScanShape) -> ScanCost {
        let pulses_total = (s.directions * s.pulses) as f64;
        let scan_time_s = pulses_total * (self.pulse_us + self.switch_us) * 1e-6;
        let front_w =
            (s.elements as f64 * (self.tx_element_mw + self.rx_element_mw) + self.radio_mw) * 1e-3;
        let front_end_j = front_w * scan_time_s;
        let tx_w = 10f64.powf(s.tx_power_dbm / 10.0) * 1e-3;
        let pa_j = tx_w / self.pa_efficiency * pulses_total * self.pulse_us * 1e-6;
        let samples = pulses_total * s.samples as f64;
        let adc_j = samples * self.adc_pj_per_sample * 1e-12;
        let processing_s = samples * self.energy_stage_ns_per_sample * 1e-9
            + s.directions as f64 * self.mapper_us_per_direction * 1e-6;
        let processing_j = processing_s * self.core_power_w;
        ScanCost {
            scan_time_s,
            front_end_j,
            pa_j,
            adc_j,
            processing_s,
            processing_j,
            energy_j: front_end_j + pa_j + adc_j + processing_j,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(directions: usize, pulses: usize) -> ScanShape {
        ScanShape {
            elements: 100,
            directions,
            pulses,
            samples: 801,
            tx_power_dbm: 10.0,
        }
    }

    #[test]
    fn radio_energy_and_time_grow_linearly_with_directions_times_pulses() {
        let m = EnergyModel::default().check().unwrap();
        let base = m.scan(&shape(37, 1));
        // 10 dBm = 10 mW / 0.1 = 0.1 W over 37 × 50 µs: 0.185 mJ
        assert!((base.pa_j - 0.1 * 37.0 * 50e-6).abs() < 1e-12);
        // front end: (100 × 40 mW + 0.3 W) over 37 × 51 µs
        assert!((base.front_end_j - 4.3 * 37.0 * 51e-6).abs() < 1e-12);
        for (d, p) in [(37, 4), (73, 1), (73, 8), (19, 2)] {
            let c = m.scan(&shape(d, p));
            let k = (d * p) as f64 / 37.0;
            assert!((c.radio_j() - k * base.radio_j()).abs() < 1e-12 * k);
            assert!((c.scan_time_s - k * base.scan_time_s).abs() < 1e-15 * k);
        }
        // the same D · P in either order costs the same radio energy
        assert!((m.scan(&shape(20, 4)).radio_j() - m.scan(&shape(40, 2)).radio_j()).abs() < 1e-15);
    }

    #[test]
    fn processing_share_is_processing_over_total() {
        let m = EnergyModel::default().check().unwrap();
        let c = m.scan(&shape(37, 2));
        // 37 · 2 · 801 samples × 450 ns + 37 × 0.75 ms, at 2 W
        let t = 37.0 * 2.0 * 801.0 * 450e-9 + 37.0 * 0.75e-3;
        assert!((c.processing_s - t).abs() < 1e-12);
        assert!((c.processing_j - 2.0 * t).abs() < 1e-12);
        let share = c.processing_j / (c.radio_j() + c.processing_j);
        assert!((c.processing_share() - share).abs() < 1e-15);
        let free = EnergyModel {
            core_power_w: 0.0,
            ..Default::default()
        };
        assert_eq!(
            free.check().unwrap().scan(&shape(37, 2)).processing_share(),
            0.0
        );
    }

    #[test]
    fn bad_constants_are_named_and_files_round_trip() {
        let e = EnergyModel {
            pa_efficiency: 0.0,
            ..Default::default()
        };
        assert!(e.check().unwrap_err().to_string().contains("pa_efficiency"));
        let e = EnergyModel {
            radio_mw: f64::NAN,
            ..Default::default()
        };
        assert!(e.check().unwrap_err().to_string().contains("radio_mw"));
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.toml");
        std::fs::write(&p, EnergyModel::default().to_toml()).unwrap();
        assert_eq!(EnergyModel::load(&p).unwrap(), EnergyModel::default());
        std::fs::write(&p, "[energy_model]\nradio_mw = 150.0\n").unwrap();
        assert_eq!(EnergyModel::load(&p).unwrap().radio_mw, 150.0);
        std::fs::write(&p, "[energy_model]\nradio_w = 1.0\n").unwrap();
        let err = EnergyModel::load(&p).unwrap_err().to_string();
        assert!(err.contains("radio_w"), "{err}");
    }
}
