//! pradar's bottom layer: what every stage reads and writes. Errors ([`error`]), checked
//! parameters ([`params`]), units ([`units`]), atomic output ([`io`]), Parquet tables
//! ([`table`]), tables rendered to Markdown/CSV ([`export`]), shared statistics ([`stats`]),
//! the campaign formats — Touchstone, manifest, layout, sweeps ([`campaign`]) — and the model
//! file's schema ([`model_file`]).
//!
//! It imports no other pradar crate; every other crate imports it.
#![deny(missing_docs)]

pub mod campaign;
pub mod error;
pub mod export;
pub mod io;
pub mod model_file;
pub mod params;
pub mod stats;
pub mod table;
pub mod units;

pub use error::{Error, Result};
