//! Channel fitting (DESIGN §2 "Fitting"): estimators ([`estimators`]) and the campaign fit
//! ([`channel`]): Table 1 quantities from clustered MPCs, the fitted model file and the
//! Table 1 comparison.

pub mod channel;
pub mod estimators;

pub use estimators::*;
