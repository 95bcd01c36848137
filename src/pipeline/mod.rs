//! The report of a campaign (`pradar report`) and the main job (`pradar reproduce`: simulate
//! the built-in corridor into a work folder, then the same report): compute its energy matrices, extract and cluster MPCs, fit Table 1 (also on the corridor
//! without clutter), map it (OG, boresight OG, EKF), run the mapping experiments
//! ([`experiment`]) and write the report: campaign summary, per-position heat maps, MPC
//! clusters, Table 1, maps, every experiment's table and panel, and stage timings.
//!
//! Layout: [`report()`] (the page's one code path, its options), [`reproduce()`] (simulate,
//! then that path), [`analyse`] (the chain
//! CLEAN → K-means → fit on one energy table), `kmax` (Table 1 against the clustering cap),
//! `geometry` (Table 1 without clutter), [`experiment`] (the mapping experiments). The
//! report's HTML is built in [`crate::report::reproduce`] and [`crate::report::experiments`].

use crate::error::Result;
use crate::report;
use std::path::{Path, PathBuf};

mod analysis;
mod campaign_report;
pub mod commands;
pub mod experiment;
mod geometry;
mod kmax;
mod reproduce;

pub use analysis::{analyse, Analysis};
pub use campaign_report::{
    report, ReportOptions, ReportOutput, ReportValid, DEFAULT_REPORT_OUT, EXPLORE_SECTION,
};
pub use reproduce::{reproduce, ReproduceOptions, ReproduceValid, DEFAULT_REPRODUCE_OUT};

/// The built-in corridor manifest.
pub const CORRIDOR_MANIFEST: &str = include_str!("../../data/corridor/campaign.toml");
/// The built-in corridor layout.
pub const CORRIDOR_LAYOUT: &str = include_str!("../../data/corridor/layout.geojson");

/// Progress callback factory: (stage label, total steps) → per-step callback (the bottom
/// layer's [`crate::progress::Bars`]).
pub use crate::progress::Bars as Progress;

/// Write the built-in corridor campaign (manifest + layout) into `dir`.
///
/// ```no_run
/// let manifest = pradar::pipeline::write_builtin_corridor(std::path::Path::new("corridor"))?;
/// let c = pradar::campaign::manifest::Campaign::load(&manifest)?;
/// assert_eq!(c.manifest.positions(), 12);
/// # Ok::<(), pradar::error::Error>(())
/// ```
pub fn write_builtin_corridor(dir: &Path) -> Result<PathBuf> {
    let m = dir.join("campaign.toml");
    crate::io::write_bytes(&m, CORRIDOR_MANIFEST.as_bytes())?;
    crate::io::write_bytes(&dir.join("layout.geojson"), CORRIDOR_LAYOUT.as_bytes())?;
    Ok(m)
}

/// Table 1 as HTML rows (ours, interval, family, KS p, AIC, paper, truth).
fn table1_html_rows(
    f: &crate::fit::channel::ChannelFit,
    truth: Option<&crate::fit::channel::ChannelFit>,
) -> String {
    report::html_table(&crate::fit::table1::table(f, truth))
}
