//! pradar's channel layer: from energy matrices to a fitted, checked channel model.
//!
//! [`mpc`] (2-D CLEAN or peaks, diffuse and folded wall returns labelled) → [`cluster`]
//! (K-means, K per position) → [`fit`] (Table 1: MLEs, block-bootstrap intervals, the
//! layout's levels) → [`model`] (the model file drawn: rays, walls, `synth`) → [`check`]
//! (the predictive check) and [`closed_loop`] (Table 1's "identifiable from this
//! campaign": the chain on draws of the written model); [`chain`] runs extraction,
//! clustering and the fit in memory, as every caller does; [`calibrate`] (ABC-SMC with
//! `synth`) fits the model by simulation.
//!
//! Takes the formats (`pradar-formats`), the processing (`pradar-radar`) and the simulator's
//! shared draws (`pradar-simulate`); used by the mappers and the `pradar` crate.
#![deny(missing_docs)]

pub mod calibrate;
pub mod chain;
pub mod check;
pub mod closed_loop;
pub mod cluster;
pub mod fit;
pub mod model;
pub mod mpc;
pub mod smm;

// the lower layers' modules under their old paths (`crate::campaign::…`)
use pradar_formats::{campaign, error, export, io, params, stats, table, units};
use pradar_radar::{energy, pattern};
use pradar_simulate as simulate;
