//! Parameters checked once, by type (after linfa's `ParamGuard`).
//!
//! Every stage's parameter struct (`XParams`, plain data a user or the CLI fills in)
//! implements [`ParamGuard`]: `check` validates every field once and returns a
//! [`Valid<XParams>`] (aliased `XValid` in each module). Algorithms take only the checked
//! type, so they never re-check and never see an out-of-range value; a [`Valid`] can only
//! be made by `check` (its constructor is private to the crate) and is read-only (it
//! derefs to the parameters).
//!
//! ```
//! use pradar::params::ParamGuard;
//! let p = pradar::cluster::ClusterParams { k_max: 0, ..Default::default() };
//! assert!(p.check().is_err());
//! ```

use crate::error::Result;
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

impl<P> Valid<P> {
    /// Wrap parameters that were just checked (only `check` implementations call this).
    pub(crate) fn new(p: P) -> Valid<P> {
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
