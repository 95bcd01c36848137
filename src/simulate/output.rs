//! Where the simulator writes: the sweeps (one Parquet stream or Touchstone files per
//! position) and the output manifest.
//!
//! The output manifest is the input manifest's TOML with `layout = "layout.geojson"` (the
//! layout is copied beside it), `[array].elements` made explicit and a `[sweeps]` section
//! naming what was written, so `pradar energy` reads the simulated campaign like a measured
//! one.

use crate::campaign::manifest::{one_line, Band, Campaign, SweepFormat, SweepsConfig};
use crate::campaign::sweeps::{parquet_batch, write_touchstone_position, PositionSweeps};
use crate::error::{Error, Result};
use crate::table;
use std::path::{Path, PathBuf};

/// File-name pattern of the Touchstone sweeps, relative to the campaign folder.
const TOUCHSTONE_PATTERN: &str = "sweeps/p{position:03}_d{direction:02}_k{pulse:02}.s2p";

/// The sweep writer of one run.
pub(super) struct SweepSink {
    out_dir: PathBuf,
    parquet: Option<(PathBuf, table::ParquetStream)>,
}

impl SweepSink {
    /// Open the writer for `format` under `out_dir` (the Parquet stream is created now).
    pub(super) fn create(out_dir: &Path, format: SweepFormat) -> Result<SweepSink> {
        let sweeps_pq = out_dir.join("sweeps.parquet");
        let parquet = match format {
            SweepFormat::Parquet => {
                let w = table::ParquetStream::create(&sweeps_pq)?;
                Some((sweeps_pq, w))
            }
            SweepFormat::Touchstone => None,
        };
        Ok(SweepSink {
            out_dir: out_dir.to_path_buf(),
            parquet,
        })
    }

    /// Write one position's sweeps.
    pub(super) fn write(&mut self, band: &Band, sw: &PositionSweeps, campaign: &str) -> Result<()> {
        match self.parquet.as_mut() {
            Some((path, w)) => w.write(&parquet_batch(path, band, sw)?),
            None => write_touchstone_position(
                &self.out_dir,
                TOUCHSTONE_PATTERN,
                band,
                sw,
                &format!(
                    "pradar simulate: campaign {campaign} position {}\nS21 = backscatter channel (Tx port 1, Rx port 2); S11, S22 not simulated",
                    sw.position
                ),
            ),
        }
    }

    /// Close the Parquet stream (nothing to do for Touchstone).
    pub(super) fn finish(self) -> Result<()> {
        if let Some((_, w)) = self.parquet {
            w.finish(None)?;
        }
        Ok(())
    }
}

/// Copy the layout beside the output and write `out_dir/campaign.toml`; returns its path.
pub(super) fn write_manifest(c: &Campaign, out_dir: &Path, format: SweepFormat) -> Result<PathBuf> {
    let layout_out = out_dir.join("layout.geojson");
    let layout_text = crate::io::read_text(&c.layout_path())?;
    crate::io::write_bytes(&layout_out, layout_text.as_bytes())?;
    let text = crate::io::read_text(&c.path)?;
    let mut t: toml::Table =
        toml::from_str(&text).map_err(|e| Error::input(&c.path, one_line(&e.to_string())))?;
    t.insert(
        "layout".into(),
        toml::Value::String("layout.geojson".into()),
    );
    if let Some(toml::Value::Table(a)) = t.get_mut("array") {
        a.insert(
            "elements".into(),
            toml::Value::Integer(c.manifest.array.elements as i64),
        );
    }
    let sweeps = match format {
        SweepFormat::Touchstone => SweepsConfig {
            format,
            pattern: Some(TOUCHSTONE_PATTERN.to_string()),
            files: vec![],
            path: None,
            parameter: None,
            ..Default::default()
        },
        SweepFormat::Parquet => SweepsConfig {
            format,
            pattern: None,
            files: vec![],
            path: Some("sweeps.parquet".into()),
            parameter: None,
            ..Default::default()
        },
    };
    t.insert(
        "sweeps".into(),
        toml::Value::try_from(&sweeps).map_err(|e| Error::input(&c.path, e.to_string()))?,
    );
    let manifest_out = out_dir.join("campaign.toml");
    let body = toml::to_string(&t).map_err(|e| Error::input(&manifest_out, e.to_string()))?;
    crate::io::write_bytes(
        &manifest_out,
        format!(
            "# written by pradar simulate from {}\n{body}",
            c.path.display()
        )
        .as_bytes(),
    )?;
    Ok(manifest_out)
}
