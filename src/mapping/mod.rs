//! Grid mapping (DESIGN §2 "Mapping", §3 "Maps").
//!
//! Takes campaigns (poses, directions, array, band, layout) and their energy matrices; gives
//! occupancy maps, map files and metrics against the reference map rasterised from the
//! layout.
//!
//! * [`grid`]: the grid and the shared observation model (per (pose, direction) the sparse
//!   illuminated cells by range bin with two-way pattern weight w and radar-equation
//!   coefficient c_{k,i});
//! * [`og`]: log-odds occupancy grids — side-lobe-aware (`og`) and boresight-only
//!   (`og-boresight`) inverse sensor models, energy detector, fusion of runs;
//! * [`ekf`]: the EKF mapper over the RRCS per cell (exact dense and scalable tiled
//!   covariance);
//! * [`metrics`]: ψ (Birk & Carpin 2006), wrong-cell rate, occupied precision/recall/F1
//!   (exact and within one cell);
//! * [`output`]: PNG, PGM + YAML (ROS map_server);
//! * [`job`]: the `pradar map` command (runs, fusion, observable region, metrics.json).

pub mod ekf;
pub mod grid;
pub mod job;
pub mod metrics;
pub mod og;
pub mod output;

pub use ekf::{EkfParams, EkfVariant};
pub use grid::{Beam, GridParams, ObservationModel};
pub use job::{run_map, MapOptions, MapReport, MapRun};
pub use og::{fuse, og_map, LogOddsMap, Method, OgParams};
