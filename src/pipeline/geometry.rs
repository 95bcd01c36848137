//! Table 1 of a campaign with its `[clutter]` section removed ([`geometry_only_table`]):
//! walls (diffuse and specular), corners, edges and objects only.
//!
//! What the chain calls clusters there is the layout's own structure; the table says how
//! much of Table 1 the geometry alone gives. The campaign is rewritten (same array, same
//! layout file beside it) and run through the whole chain simulate → energy → CLEAN →
//! K-means → fit.

use super::{analyse, table1_html_rows, Progress};
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::energy::{self, EnergyMatrix};
use crate::error::{Error, Result};
use crate::report;
use crate::simulate::simulate;
use std::path::{Path, PathBuf};

/// Simulate the campaign `c` with its `[clutter]` section removed into `dir`, run energy →
/// CLEAN → K-means → fit, write `out/table1_geometry.md` and return the report's HTML.
pub(crate) fn geometry_only_table(
    c: &Campaign,
    dir: &Path,
    out: &Path,
    progress: Progress,
) -> Result<String> {
    let manifest = write_geometry_manifest(c, &dir.join("input"))?;
    let gc = Campaign::load(&manifest)?;
    let np = gc.manifest.positions();
    let cb = progress("simulate (geometry only)", np);
    let sim = simulate(&gc, &dir.join("simulated"), SweepFormat::Parquet, &*cb)?;
    let sc = Campaign::load(&sim.manifest)?;
    let e = dir.join("energy.parquet");
    let cb = progress("energy (geometry only)", np);
    energy::run(&sc, &e, &*cb)?;
    let em = EnergyMatrix::read(&e)?;
    let a = analyse(&sc, &em, &e, dir, false)?;
    let note = report::reproduce::k_cap_note(&a.clustering, a.cluster_params.k_max);
    let (mpcs, clustering, f) = (a.mpcs, a.clustering, a.fit?);
    let name = format!("{} without clutter (geometry only)", c.manifest.name);
    crate::fit::channel::write_table1(&out.join("table1_geometry.md"), &name, &f, None)?;
    Ok(report::reproduce::geometry_html(
        &table1_html_rows(&f, None),
        mpcs.len(),
        clustering.summary.len(),
        np,
        &note,
    ))
}

/// Write `c`'s manifest without `[clutter]` (its array size kept, its layout copied beside
/// it) into `input`; returns the manifest's path.
fn write_geometry_manifest(c: &Campaign, input: &Path) -> Result<PathBuf> {
    let text = crate::io::read_text(&c.path)?;
    let mut t: toml::Table =
        toml::from_str(&text).map_err(|e| Error::input(&c.path, e.to_string()))?;
    t.remove("clutter");
    if let Some(toml::Value::Table(a)) = t.get_mut("array") {
        a.insert(
            "elements".into(),
            toml::Value::Integer(c.manifest.array.elements as i64),
        );
    }
    std::fs::create_dir_all(input).map_err(|e| Error::io(input, e))?;
    let layout = c.layout_path();
    let layout_name = layout
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "layout.geojson".into());
    crate::io::write_bytes(
        &input.join(&layout_name),
        crate::io::read_text(&layout)?.as_bytes(),
    )?;
    t.insert("layout".into(), toml::Value::String(layout_name));
    let manifest = input.join("campaign.toml");
    let body = toml::to_string(&t).map_err(|e| Error::input(&manifest, e.to_string()))?;
    crate::io::write_bytes(&manifest, body.as_bytes())?;
    Ok(manifest)
}
