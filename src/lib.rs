//! pradar — millimetre-wave personal radar campaigns: simulate or ingest backscatter sweeps,
//! compute energy matrices, characterise the channel and map.
//!
//! Data flows one way: [`campaign`] (manifest, formats) and [`simulate`] (the physics simulator) → [`energy`] →
//! [`mpc`] → [`cluster`] → [`fit`] → [`model`] → [`check`] → [`mapping`] → [`report`].
#![deny(missing_docs)]

pub mod calibrate;
pub mod campaign;
pub mod check;
pub mod cluster;
pub mod correction;
pub mod energy;
pub mod error;
pub mod explore;
pub mod export;
pub mod fit;
#[cfg(feature = "fuzz")]
pub mod fuzz;
pub mod io;
pub mod mapping;
pub mod model;
pub mod mpc;
pub mod params;
pub mod pipeline;
pub mod report;
pub mod simulate;
pub mod stats;
pub mod table;
pub mod units;

pub use error::{Error, Result};
