//! The write step of `import`: the manifest of a checked import, validated as `energy` will
//! read it, then written atomically.
//!
//! Takes the [`Inputs`], the [`Plan`] and the band read from the files; gives the outcome
//! naming what was written. The manifest keeps the labels beside the indices, writes out
//! every `[processing]` setting (the base's over the defaults), `[noise]` from the base or
//! `floor_dbm = -100`, `tx_power_dbm = 0`, and an explicit `[sweeps] files` list (paths
//! relative to the manifest) with what `allow_missing` left out; with `to_parquet` the
//! sweeps also become `sweeps.parquet` beside it, which the manifest then names. Refused:
//! no layout and no `[array] elements` from either the flags or the base.

use super::check::Plan;
use super::collect::Inputs;
use super::{out_dir, ImportOutcome, ImportParams};
use crate::campaign::manifest::Campaign;
use crate::campaign::sweeps::{parquet_batch, SweepReader};
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Build, validate and write the manifest (and the Parquet sweep table).
pub(super) fn write(
    p: &ImportParams,
    inputs: &Inputs,
    plan: &Plan,
    band: (f64, f64, usize),
    mut outcome: ImportOutcome,
) -> Result<ImportOutcome> {
    let out_dir = out_dir(p);
    let kept = plan.kept();
    let mut t = manifest_table(p, inputs, plan.nk, band, &kept)?;
    let mut sweeps = sweeps_table(inputs, plan, &kept, out_dir, &mut outcome);
    t.insert("sweeps".into(), sweeps.clone().into());
    let text = toml::to_string(&t).map_err(|e| Error::input(&p.out, e.to_string()))?;
    // validate as `energy` will read it (layout present, every field in range)
    let c = Campaign::from_str(&text, &p.out)?;
    let layout = crate::campaign::layout::Layout::load(&c.layout_path())?;
    outcome
        .warnings
        .extend(crate::campaign::fold::fold_warning(&c.manifest, &layout));
    if p.to_parquet {
        let pq = out_dir.join("sweeps.parquet");
        let reader = SweepReader::open(&c)?;
        let mut stream = crate::table::ParquetStream::create(&pq)?;
        for pos in 0..kept.len() {
            let sw = reader.read_position(pos)?;
            stream.write(&parquet_batch(&pq, &c.manifest.band, &sw)?)?;
        }
        stream.finish(None)?;
        // the Parquet table, with the files it was made from kept as its provenance
        sweeps.insert("format".into(), "parquet".into());
        sweeps.insert("path".into(), "sweeps.parquet".into());
        t.insert("sweeps".into(), sweeps.into());
        outcome.parquet = Some(pq);
    }
    let text = toml::to_string(&t).map_err(|e| Error::input(&p.out, e.to_string()))?;
    Campaign::from_str(&text, &p.out)?;
    crate::io::write_bytes(&p.out, text.as_bytes())?;
    outcome.manifest = Some(p.out.clone());
    Ok(outcome)
}

/// The manifest without `[sweeps]`: name, layout, seed, pulses, band, array, directions,
/// noise, processing, calibration, then the kept poses and their labels.
fn manifest_table(
    p: &ImportParams,
    inputs: &Inputs,
    nk: usize,
    band: (f64, f64, usize),
    kept: &[usize],
) -> Result<toml::Table> {
    let (base, out_dir) = (&inputs.base, out_dir(p));
    let mut t = toml::Table::new();
    t.insert("schema_version".into(), toml::Value::Integer(1));
    let name = p
        .name
        .clone()
        .or_else(|| base.get("name").and_then(|v| v.as_str()).map(String::from))
        .unwrap_or_else(|| {
            std::path::absolute(out_dir)
                .ok()
                .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
                .unwrap_or_else(|| "campaign".into())
        });
    t.insert("name".into(), name.into());
    let layout = match (&p.layout, base.get("layout").and_then(|v| v.as_str())) {
        (Some(l), _) => relative_to(l, out_dir),
        (None, Some(l)) => PathBuf::from(l),
        (None, None) => {
            return Err(Error::param(
                "--layout",
                "needed unless the base gives `layout`",
            ))
        }
    };
    t.insert(
        "layout".into(),
        layout.to_string_lossy().into_owned().into(),
    );
    t.insert(
        "seed".into(),
        base.get("seed").cloned().unwrap_or(toml::Value::Integer(1)),
    );
    t.insert("pulses".into(), toml::Value::Integer(nk as i64));
    let mut b = toml::Table::new();
    b.insert("start_hz".into(), band.0.into());
    b.insert("stop_hz".into(), band.1.into());
    b.insert("points".into(), toml::Value::Integer(band.2 as i64));
    t.insert("band".into(), b.into());
    let mut array = base
        .get("array")
        .and_then(|a| a.as_table())
        .cloned()
        .unwrap_or_default();
    if let Some(n) = p.elements {
        array.insert("elements".into(), toml::Value::Integer(n as i64));
    }
    if !array.contains_key("elements") {
        return Err(Error::param(
            "--elements",
            "needed unless the base gives [array] elements",
        ));
    }
    t.insert("array".into(), array.into());
    t.insert(
        "directions".into(),
        toml::Value::try_from(inputs.directions)
            .map_err(|e| Error::param("directions", e.to_string()))?,
    );
    settings(base, &mut t);
    let poses_toml: Vec<toml::Value> = kept
        .iter()
        .map(|&pi| &inputs.poses[pi])
        .map(|q| {
            let mut m = toml::Table::new();
            m.insert("x_m".into(), q.1.into());
            m.insert("y_m".into(), q.2.into());
            m.insert("heading_deg".into(), q.3.into());
            m.into()
        })
        .collect();
    t.insert("poses".into(), poses_toml.into());
    // the lab's labels beside the indices: every later message, table and plot names them
    let kept_labels: Vec<toml::Value> = kept
        .iter()
        .map(|&pi| inputs.labels[pi].clone().into())
        .collect();
    t.insert("labels".into(), kept_labels.into());
    Ok(t)
}

/// `[noise]`, `[processing]` and `[calibration]` into `t`: the base's, the noise else the
/// default floor, every processing setting written out (the base's over the defaults).
fn settings(base: &toml::Table, t: &mut toml::Table) {
    let noise = base.get("noise").cloned().unwrap_or_else(|| {
        let mut n = toml::Table::new();
        n.insert("floor_dbm".into(), (-100.0).into());
        n.insert("tx_power_dbm".into(), 0.0.into());
        n.into()
    });
    t.insert("noise".into(), noise);
    // every processing setting written out, the base's over the defaults, so the manifest
    // states what the energy stage will do (a default nobody wrote is still visible)
    let mut processing =
        match toml::Value::try_from(crate::campaign::manifest::Processing::default()) {
            Ok(toml::Value::Table(t)) => t,
            _ => toml::Table::new(),
        };
    if let Some(b) = base.get("processing").and_then(|v| v.as_table()) {
        for (k, v) in b {
            processing.insert(k.clone(), v.clone());
        }
    }
    t.insert("processing".into(), processing.into());
    if let Some(v) = base.get("calibration") {
        t.insert("calibration".into(), v.clone());
    }
}

/// `[sweeps]`: the Touchstone files of the used cells (manifest indices of the kept
/// positions), the (position, direction) sweeps recorded as missing and the labels of the
/// positions left out; the counts of both go into `outcome`.
fn sweeps_table(
    inputs: &Inputs,
    plan: &Plan,
    kept: &[usize],
    out_dir: &Path,
    outcome: &mut ImportOutcome,
) -> toml::Table {
    let (nd, nk, np) = (plan.nd, plan.nk, plan.dropped.len());
    let mut sweeps = toml::Table::new();
    sweeps.insert("format".into(), "touchstone".into());
    if let Some(par) = inputs.param {
        sweeps.insert("parameter".into(), par.to_string().into());
    }
    // manifest index of each kept position
    let new_index: Vec<Option<usize>> = {
        let mut v = vec![None; np];
        for (j, &pi) in kept.iter().enumerate() {
            v[pi] = Some(j);
        }
        v
    };
    let files: Vec<toml::Value> = plan
        .table
        .iter()
        .enumerate()
        .filter(|(i, _)| plan.used(*i))
        .map(|(i, f)| {
            let mut m = toml::Table::new();
            let pi = new_index[i / (nd * nk)].expect("a used sweep's position is kept");
            m.insert("position".into(), toml::Value::Integer(pi as i64));
            m.insert(
                "direction".into(),
                toml::Value::Integer(((i / nk) % nd) as i64),
            );
            m.insert("pulse".into(), toml::Value::Integer((i % nk) as i64));
            let rel = relative_to(f.as_ref().expect("no missing cells"), out_dir);
            m.insert("path".into(), rel.to_string_lossy().into_owned().into());
            m.into()
        })
        .collect();
    sweeps.insert("files".into(), files.into());
    let missing: Vec<toml::Value> = (0..np * nd)
        .filter(|&i| plan.missing_pd[i] && !plan.dropped[i / nd])
        .map(|i| {
            let mut m = toml::Table::new();
            let pi = new_index[i / nd].expect("kept");
            m.insert("position".into(), toml::Value::Integer(pi as i64));
            m.insert("direction".into(), toml::Value::Integer((i % nd) as i64));
            m.into()
        })
        .collect();
    outcome.missing = missing.len();
    outcome.dropped = plan.dropped.iter().filter(|&&x| x).count();
    if !missing.is_empty() {
        sweeps.insert("missing".into(), missing.into());
    }
    let dropped_labels: Vec<toml::Value> = (0..np)
        .filter(|&pi| plan.dropped[pi])
        .map(|pi| inputs.labels[pi].clone().into())
        .collect();
    if !dropped_labels.is_empty() {
        sweeps.insert("dropped_positions".into(), dropped_labels.into());
    }
    sweeps
}

/// `path` relative to `dir` when inside it, else absolute.
fn relative_to(path: &Path, dir: &Path) -> PathBuf {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, d) = (abs(path), abs(dir));
    p.strip_prefix(&d).map(Path::to_path_buf).unwrap_or(p)
}
