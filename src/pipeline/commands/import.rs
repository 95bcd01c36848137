//! The `pradar import` command: a lab's files checked and written as a campaign manifest by
//! the formats layer's import ([`crate::campaign::import`], which holds the readers, the
//! name pattern, the collection, the checks and the writer). The CLI prints its problems and
//! exits 1 on any (`main.rs`).

pub use crate::campaign::import::{
    import, ImportOutcome, ImportParams, SweepFiles, MAX_INDEX_ROWS, MAX_POSES, SHOWN_PROBLEMS,
};
