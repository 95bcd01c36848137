//! Campaign stage: manifest, layout, array patterns, sweep formats (Touchstone, Parquet),
//! model-file schema and the physics-based simulator. (`import`, a manifest from a folder of
//! measured sweeps, is a command: `pipeline::commands::import`.)

pub mod layout;
pub mod manifest;
pub mod modelfile;
pub mod pattern;
pub mod simulate;
pub mod sweeps;
pub mod touchstone;

pub use layout::Layout;
pub use manifest::{Campaign, Manifest, Pose};
pub use pattern::ArrayPattern;
