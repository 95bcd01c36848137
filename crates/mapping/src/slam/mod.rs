//! Poses from the sweeps (issue 56): radar SLAM for a personal radar walked by hand.
//!
//! Built so far: [`odometry`], the steps a walk's dead reckoning reports (simulated from
//! the campaign's poses with a stated σ per step) and their pose graph; [`matching`], the
//! correlative scan-to-map matching of a pose's detections; [`run`], the incremental
//! estimate (odometry and matches into the graph); [`graph`], the pose graph over SE(2)
//! and its Levenberg–Marquardt solution with the poses' marginal covariances. `pradar map
//! --poses-from odometry|sweeps` maps with them (`job::load`). Not yet built: loop
//! closures, the page, `experiment slam`. Measurements: `docs/slam.md`.

pub mod graph;
pub mod matching;
pub mod odometry;
pub mod run;

pub use graph::{Edge, Pose2, PoseGraph, Solution, SolveParams, SolveValid};
pub use matching::{match_scan, Field, Match, Scan};
pub use odometry::{Odometry, OdometryNoise, OdometryNoiseValid, PosesFrom};
pub use run::{estimate, Estimate};
