//! Extraction parameters ([`ExtractParams`]), the [`Method`] and their check.
//!
//! Takes the values a user or the CLI fills in; gives, through [`ParamGuard::check`], an
//! [`ExtractValid`] that [`super::extract`] takes. Every field is checked once there and an
//! out-of-range value is one [`Error::Param`] naming the field (and the CLI flag where
//! there is one) and the allowed range.

use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};

/// Extraction method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Iterative 2-D CLEAN.
    Clean,
    /// Local maxima (baseline).
    Peaks,
}

impl Method {
    /// Every value, in the order the command line lists them.
    pub const ALL: [Method; 2] = [Method::Clean, Method::Peaks];

    /// Name (`clean`, `peaks`): the command-line value and the `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Clean => "clean",
            Method::Peaks => "peaks",
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = Error;
    /// Parse a [`Method::name`].
    fn from_str(s: &str) -> Result<Method> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "method", "extraction method")
    }
}

/// Extraction parameters (unchecked; [`ParamGuard::check`] gives the [`ExtractValid`] the
/// extractors take).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtractParams {
    /// Method.
    pub method: Method,
    /// Keep components above floor + margin, dB.
    pub margin_db: f64,
    /// Side-lobe guard, dB above the kept components' predicted energy.
    pub guard_db: f64,
    /// Dynamic range: stop at components this far below the position's strongest, dB.
    pub dynamic_range_db: f64,
    /// Components per position at most.
    pub max_mpcs: usize,
    /// Half-width of the delay window of a footprint, bins.
    pub kernel_bins: usize,
    /// Ignore delays below this, ns; `None` = automatic: for gated coupling removal the gate
    /// plus the window kernel's null-to-null width (4/B), where the gate and the coupling's
    /// kernel tail corrupt the profile; 0 otherwise.
    pub min_delay_ns: Option<f64>,
    /// The diffuse stage ([`super::diffuse`]).
    pub diffuse: super::diffuse::DiffuseParams,
}

/// Extraction parameters that passed [`ParamGuard::check`].
pub type ExtractValid = Valid<ExtractParams>;

impl Default for ExtractParams {
    fn default() -> Self {
        ExtractParams {
            method: Method::Clean,
            margin_db: 13.0,
            guard_db: 10.0,
            dynamic_range_db: 70.0,
            max_mpcs: 200,
            kernel_bins: 12,
            min_delay_ns: None,
            diffuse: super::diffuse::DiffuseParams::default(),
        }
    }
}

impl ExtractParams {
    /// Builder: method.
    pub fn method(mut self, m: Method) -> Self {
        self.method = m;
        self
    }
    /// Builder: dynamic range.
    pub fn dynamic_range_db(mut self, v: f64) -> Self {
        self.dynamic_range_db = v;
        self
    }
    /// Builder: margin.
    pub fn margin_db(mut self, v: f64) -> Self {
        self.margin_db = v;
        self
    }
}

impl ParamGuard for ExtractParams {
    type Checked = ExtractValid;

    /// Every field in range, or one error naming the first field that is not.
    fn check(&self) -> Result<ExtractValid> {
        if !(self.margin_db.is_finite() && self.margin_db >= 0.0) {
            return Err(Error::param(
                "margin_db",
                format!(
                    "must be finite and >= 0 dB (--margin-db), got {}",
                    self.margin_db
                ),
            ));
        }
        if self.dynamic_range_db.is_nan() || self.dynamic_range_db <= 0.0 {
            return Err(Error::param(
                "dynamic_range_db",
                format!(
                    "must be > 0 dB (--dynamic-range-db), got {}",
                    self.dynamic_range_db
                ),
            ));
        }
        if !(self.guard_db.is_finite() && self.guard_db >= 0.0) {
            return Err(Error::param(
                "guard_db",
                format!("must be finite and >= 0 dB, got {}", self.guard_db),
            ));
        }
        if self.max_mpcs == 0 {
            return Err(Error::param("max_mpcs", "must be >= 1, got 0"));
        }
        if self.kernel_bins == 0 {
            return Err(Error::param("kernel_bins", "must be >= 1, got 0"));
        }
        if let Some(m) = self.min_delay_ns {
            if m.is_nan() {
                return Err(Error::param(
                    "min_delay_ns",
                    "must be a number of ns (or absent for automatic), got NaN",
                ));
            }
        }
        self.diffuse.check()?;
        Ok(Valid::new(*self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every out-of-range field is one error naming that field (and its range), no panic.
    #[test]
    fn out_of_range_fields_are_one_clear_error() {
        assert!(ExtractParams::default().check().is_ok());
        let d = ExtractParams::default();
        let cases: Vec<(ExtractParams, &str, &str)> = vec![
            (d.margin_db(-1.0), "margin_db", ">= 0"),
            (d.margin_db(f64::INFINITY), "margin_db", ">= 0"),
            (d.dynamic_range_db(0.0), "dynamic_range_db", "> 0"),
            (d.dynamic_range_db(f64::NAN), "dynamic_range_db", "> 0"),
            (
                ExtractParams {
                    guard_db: -3.0,
                    ..d
                },
                "guard_db",
                ">= 0",
            ),
            (ExtractParams { max_mpcs: 0, ..d }, "max_mpcs", ">= 1"),
            (
                ExtractParams {
                    kernel_bins: 0,
                    ..d
                },
                "kernel_bins",
                ">= 1",
            ),
            (
                ExtractParams {
                    min_delay_ns: Some(f64::NAN),
                    ..d
                },
                "min_delay_ns",
                "ns",
            ),
        ];
        for (p, field, range) in cases {
            let e = p.check().unwrap_err().to_string();
            assert!(e.contains(field) && e.contains(range), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
    }

    /// Each value reads back from its name, the command-line spelling.
    #[test]
    fn method_names_round_trip() {
        assert_eq!(Method::ALL.map(|v| v.to_string()), ["clean", "peaks"]);
        for v in Method::ALL {
            assert_eq!(v.to_string().parse::<Method>().unwrap(), v);
        }
        let e = "x".parse::<Method>().unwrap_err().to_string();
        assert!(e.contains("(clean|peaks)"), "{e}");
    }
}
