//! Campaign formats: the manifest, the layout geometry, array patterns and the sweep formats
//! (Touchstone, Parquet). The physics simulator is [`crate::simulate`], the model file's schema
//! [`crate::model_file`].

pub mod fold;
pub mod import;
pub mod layout;
pub mod manifest;
pub mod sweeps;
pub mod touchstone;

pub use layout::Layout;
pub use manifest::{Campaign, Manifest, Pose};
