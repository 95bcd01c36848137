//! pradar's bottom layer: what every stage reads and writes. Errors ([`error`]), checked
//! parameters ([`params`]), units ([`units`]), atomic output ([`io`]), Parquet tables
//! ([`table`]), tables rendered to Markdown/CSV ([`export`]), shared statistics ([`stats`]),
//! the campaign formats — Touchstone, manifest, layout, sweeps, and `import` of a lab's files
//! ([`campaign`]) — the model file's schema ([`model_file`]) and the progress callback
//! ([`progress`]).
//!
//! It imports no other pradar crate; every other crate imports it.
#![deny(missing_docs)]

pub mod campaign;
pub mod error;
pub mod export;
pub mod io;
pub mod model_file;
pub mod params;
pub mod progress;
pub mod stats;
pub mod table;
pub mod units;

pub use error::{Error, Result};
