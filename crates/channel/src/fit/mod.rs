//! Channel fitting (DESIGN §2 "Fitting"): from clustered MPCs to the fitted model file and
//! Table 1.
//!
//! * [`estimators`] — maximum-likelihood fits of the candidate families, AIC, KS with its
//!   parametric-bootstrap p-value, the resampling of whole position groups
//!   (`bootstrap_groups`; the block length comes from [`geometry`]);
//! * [`params`] — [`FitParams`] and its checked form [`FitValid`];
//! * [`geometry`] — cluster locations, perimeter offsets and spacings, the observed
//!   stretches of perimeter, the scan's interior and the bootstrap's block length;
//! * [`quantities`] — each quantity from its samples: value, interval, KS, AIC ranking;
//! * [`diffuse`] — the dense component's quantities (`[diffuse]`) from the diffuse MPCs;
//! * [`channel`] — the campaign fit ([`channel::fit_channel`], [`channel::fit_truth`]);
//! * [`identify`] — the rule of Table 1's closed-loop column ("not identifiable from this
//!   campaign"), on the readings the layer above draws;
//! * [`table1`] — Table 1 as one [`Table`](crate::export::Table) (Markdown, CSV, HTML).

pub mod channel;
pub mod diffuse;
pub mod estimators;
pub mod geometry;
pub mod identify;
pub mod params;
pub mod quantities;
pub mod table1;

pub use estimators::*;
pub use params::{FitParams, FitValid};
