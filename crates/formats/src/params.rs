//! Parameters checked once, by type (after linfa's `ParamGuard`).
//!
//! Every stage's parameter struct (`XParams`, plain data a user or the CLI fills in)
//! implements [`ParamGuard`]: `check` validates every field once and returns a
//! [`Valid<XParams>`] (aliased `XValid` in each module). Algorithms take only the checked
//! type, so they never re-check and never see an out-of-range value; a [`Valid`] can only
//! be made by `check` (only `check` implementations call its constructor, [`Valid::new`]) and is read-only (it
//! derefs to the parameters).
//!
//! ```
//! use pradar_formats::error::{Error, Result};
//! use pradar_formats::params::{ParamGuard, Valid};
//! #[derive(Debug, Clone, Copy)]
//! struct Gate { gate_ns: f64 }
//! impl ParamGuard for Gate {
//!     type Checked = Valid<Gate>;
//!     fn check(&self) -> Result<Valid<Gate>> {
//!         if self.gate_ns > 0.0 { Ok(Valid::new(*self)) } else {
//!             Err(Error::param("gate_ns", format!("must be > 0, got {}", self.gate_ns)))
//!         }
//!     }
//! }
//! assert!(Gate { gate_ns: 0.0 }.check().is_err());
//! assert_eq!(Gate { gate_ns: 3.0 }.check().unwrap().gate_ns, 3.0);
//! ```

use crate::error::{Error, Result};
use std::ops::Deref;

/// A parameter set that validates itself once.
pub trait ParamGuard {
    /// The checked type algorithms take.
    type Checked;
    /// Validate every field; the error names the field and the allowed range.
    fn check(&self) -> Result<Self::Checked>;
}

/// Parameters that passed their [`ParamGuard::check`]: read-only.
#[derive(Debug, Clone, PartialEq)]
pub struct Valid<P>(P);

impl<P> Default for Valid<P>
where
    P: ParamGuard<Checked = Valid<P>> + Default,
{
    /// The default parameters, checked (every stage's defaults pass their own check).
    fn default() -> Self {
        P::default()
            .check()
            .expect("the default parameters pass their check")
    }
}

impl<P> Valid<P> {
    /// Wrap parameters that were just checked (only `check` implementations call this).
    pub fn new(p: P) -> Valid<P> {
        Valid(p)
    }

    /// The parameters.
    pub fn params(&self) -> &P {
        &self.0
    }

    /// Back to plain (editable, unchecked) parameters.
    pub fn into_inner(self) -> P {
        self.0
    }
}

impl<P> Deref for Valid<P> {
    type Target = P;
    fn deref(&self) -> &P {
        &self.0
    }
}

/// The value of `all` whose name (`name`) is `s`: the `FromStr` of an enumerated parameter,
/// whose `name` is its one spelling (its `Display`, its command-line value and, where it
/// has one, its serde name). Otherwise an [`Error::Param`] for `field`:
/// ``unknown {what} `s` (a|b|c)``, listing the names.
pub fn parse_name<T: Copy>(
    s: &str,
    all: &[T],
    name: fn(&T) -> &'static str,
    field: &str,
    what: &str,
) -> Result<T> {
    all.iter().copied().find(|v| name(v) == s).ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(name).collect();
        Error::param(field, format!("unknown {what} `{s}` ({})", names.join("|")))
    })
}
