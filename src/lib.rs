//! pradar — millimetre-wave personal radar campaigns: simulate or ingest backscatter sweeps,
//! compute energy matrices, characterise the channel and map.
//!
//! Data flows one way: [`campaign`] (manifest, formats) and [`simulate`] (the physics simulator) → [`energy`] →
//! [`mpc`] → [`cluster`] → [`fit`] → [`model`] → [`check`] → [`mapping`] → [`report`].
//!
//! The layers are the workspace's crates (README, "Layout"): `pradar-formats` →
//! `pradar-radar` → `pradar-simulate` → `pradar-channel` → `pradar-mapping` → this crate
//! (the pipeline glue, the report and the CLI). This crate re-exports their modules under the
//! paths above, so `pradar::campaign::…` names the same item as `pradar_formats::campaign::…`.
#![deny(missing_docs)]

pub use pradar_channel::{calibrate, chain, check, closed_loop, cluster, fit, model, mpc, smm};
pub use pradar_formats::{
    campaign, error, export, io, model_file, params, progress, stats, table, units,
};
pub use pradar_mapping as mapping;
pub use pradar_mapping::explore;
pub use pradar_radar::{energy, pattern};
pub use pradar_simulate as simulate;

#[cfg(feature = "fuzz")]
pub mod fuzz;
pub mod pipeline;
pub mod report;

pub use error::{Error, Result};
