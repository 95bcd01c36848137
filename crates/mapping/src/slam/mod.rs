//! Poses from the sweeps (issue 56): radar SLAM for a personal radar walked by hand.
//!
//! Built so far: [`graph`], the pose graph over SE(2) and its Levenberg–Marquardt
//! solution with the poses' marginal covariances (the back end the odometry, the
//! scan-to-map matches and the loop closures will feed). Not yet built: the odometry
//! model, the scan-to-map matching of a pose's energy matrix, loop closures, `pradar map
//! --poses-from sweeps` and `experiment slam`; nothing in the commands uses this module
//! yet.

pub mod graph;

pub use graph::{Edge, Pose2, PoseGraph, Solution, SolveParams, SolveValid};
