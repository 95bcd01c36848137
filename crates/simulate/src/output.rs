//! Where the simulator writes: the sweeps (one Parquet stream or Touchstone files per
//! position) and the output manifest.
//!
//! The output manifest is the input manifest's TOML with `layout = "layout.geojson"` (the
//! layout is copied beside it), `[array].elements` made explicit, the measurement fields
//! changed on the loaded campaign (seed, pulses, band, array, directions, noise) written
//! over the input's, and a `[sweeps]` section
//! naming what was written, so `pradar energy` reads the simulated campaign like a measured
//! one.

use crate::campaign::manifest::{one_line, ArrayConfig, Band, Campaign, SweepFormat, SweepsConfig};
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

/// The measurement fields a caller changed on the loaded campaign (`explore` changes the
/// seed, pulses, band, array, directions and noise) written over the input's: a field equal
/// to the input's is left as the input wrote it.
fn changed_sections(c: &Campaign, text: &str, t: &mut toml::Table) -> Result<()> {
    let m = &c.manifest;
    let orig = Campaign::from_str(text, &c.path)?.manifest;
    let val = |v: Result<toml::Value, toml::ser::Error>| {
        v.map_err(|e| Error::input(&c.path, one_line(&e.to_string())))
    };
    if m.seed != orig.seed {
        t.insert("seed".into(), toml::Value::Integer(m.seed as i64));
    }
    if m.pulses != orig.pulses {
        t.insert("pulses".into(), toml::Value::Integer(m.pulses as i64));
    }
    if m.band != orig.band {
        t.insert("band".into(), val(toml::Value::try_from(m.band))?);
    }
    // `elements` alone is already written by the caller
    let same_but_elements = ArrayConfig {
        elements: m.array.elements,
        ..orig.array
    } == m.array;
    if !same_but_elements {
        t.insert("array".into(), val(toml::Value::try_from(m.array))?);
    }
    if m.directions != orig.directions {
        t.insert(
            "directions".into(),
            val(toml::Value::try_from(m.directions))?,
        );
    }
    if m.noise != orig.noise {
        t.insert("noise".into(), val(toml::Value::try_from(m.noise))?);
    }
    Ok(())
}

/// Copy the layout beside the output and write `out_dir/campaign.toml`; returns its path.
pub(super) fn write_manifest(
    c: &Campaign,
    out_dir: &Path,
    format: Option<SweepFormat>,
) -> Result<PathBuf> {
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
    changed_sections(c, &text, &mut t)?;
    let sweeps = match format {
        None => {
            t.remove("sweeps");
            return finish_manifest(c, out_dir, &t);
        }
        Some(SweepFormat::Touchstone) => SweepsConfig {
            format: SweepFormat::Touchstone,
            pattern: Some(TOUCHSTONE_PATTERN.to_string()),
            files: vec![],
            path: None,
            parameter: None,
            ..Default::default()
        },
        Some(SweepFormat::Parquet) => SweepsConfig {
            format: SweepFormat::Parquet,
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
    finish_manifest(c, out_dir, &t)
}

/// Write `t` as `out_dir/campaign.toml` under its header line.
fn finish_manifest(c: &Campaign, out_dir: &Path, t: &toml::Table) -> Result<PathBuf> {
    let manifest_out = out_dir.join("campaign.toml");
    let body = toml::to_string(t).map_err(|e| Error::input(&manifest_out, e.to_string()))?;
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
