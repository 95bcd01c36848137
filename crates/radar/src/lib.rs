//! pradar's radar layer: the array pattern ([`pattern`]: the planar array's far field, the
//! 1-bit transmitarray, the tabulated pattern) and the sweep processing ([`energy`]: sweeps to
//! energy matrices, calibration, coupling removal, the noise floor).
//!
//! Takes the formats of `pradar-formats`; used by the simulator, the channel and the mappers.
#![deny(missing_docs)]

pub mod energy;
pub mod pattern;

// the lower layer's modules under their old paths (`crate::campaign::…`)
use pradar_formats::{campaign, error, io, stats, table, units};
