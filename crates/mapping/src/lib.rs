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
//! * [`score`]: a map's figures against the reference map on the observable region, the
//!   building and the whole map, and the report's metrics table; [`objects`]: the truth's
//!   objects for the three-class figures; [`detectable`]: the cells some beam could detect;
//! * [`output`]: PNG, PGM + YAML (ROS map_server);
//! * [`slam`]: poses from the sweeps (issue 56, started): the odometry, scan-to-map
//!   matching and the pose graph (`map --poses-from odometry|sweeps`).
//!
//! * [`job`]: the map job (runs, fusion, the map files, `metrics.json`) that the `pradar map`
//!   command, the experiments, the explorer and the report run.
//!
//! Parameters are checked once, by type ([`crate::params::ParamGuard`]): [`GridParams`] →
//! [`GridValid`], [`OgParams`] → [`OgValid`], [`EkfParams`] → [`EkfValid`]; the algorithms
//! take only the checked types. The report page of the maps is `report::maps`.
//! Measurements: `docs/mapping.md`.
#![deny(missing_docs)]

pub mod explore;
pub mod job;

// the lower layers' modules under their old paths (`crate::campaign::…`)
use pradar_channel::model;
use pradar_formats::{campaign, error, export, io, params, progress, table, units};
use pradar_radar::{energy, pattern};
use pradar_simulate as simulate;

pub mod detectable;
pub mod ekf;
pub mod experiment;
pub mod grid;
pub mod memo;
pub mod metrics;
pub mod objects;
pub mod og;
pub mod output;
pub mod pose_noise;
pub mod reference;
pub mod score;
pub mod slam;

pub use ekf::{EkfParams, EkfUpdate, EkfValid, EkfVariant};
pub use grid::{Beam, GridParams, GridValid, ObservationModel};
pub use og::{fuse, og_map, LogOddsMap, Method, OgParams, OgValid};
