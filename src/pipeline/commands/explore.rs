//! The `explore` command: the design-space grid ([`crate::explore::run`]) into one
//! folder — `explore.csv|.md`, `summary.csv|.md`, `timing.csv`, `energy_model.toml`, the
//! plots, `index.html` and `report_section.html` (the section `report --explore` shows). Takes its command struct and gives a summary whose `Display` is
//! printed.

use crate::error::{Error, Result};
use crate::explore::summary::{
    rows_table, summarize, summary_table, timing_table, verdict_text, verdicts,
};
use crate::explore::{run_grid, ExploreInputs};
use crate::explore::{DataKind, EnergyModel, ExploreParams};
use crate::params::ParamGuard;
use crate::pipeline::Progress;
use std::fmt;
use std::path::PathBuf;

/// `pradar explore`: map quality, energy per scan and scan time over a grid of radar
/// configurations.
#[derive(Debug, Clone)]
pub struct Explore {
    /// Campaign manifest (default: the built-in corridor).
    pub campaign: Option<PathBuf>,
    /// Physics sweeps or `synth` of a model file.
    pub data: DataKind,
    /// Energy-model constants (TOML; default: the built-in ones).
    pub energy_model: Option<PathBuf>,
    /// The grid and what runs on it.
    pub params: ExploreParams,
    /// Keep every job's data and maps in `out/work/`.
    pub keep_work: bool,
    /// Output folder.
    pub out: PathBuf,
}

/// What `explore` wrote.
#[derive(Debug, Clone)]
pub struct ExploreSummary {
    /// Configurations × seeds run.
    pub jobs: usize,
    /// The estimate the grid was admitted with, minutes.
    pub estimate_minutes: f64,
    /// One verdict sentence per mapper.
    pub verdicts: Vec<String>,
    /// The index page.
    pub index: PathBuf,
}

impl fmt::Display for ExploreSummary {
    /// The verdicts, then the page.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} jobs (estimated {:.1} min)",
            self.jobs, self.estimate_minutes
        )?;
        for v in &self.verdicts {
            writeln!(f, "{v}")?;
        }
        write!(f, "report: {}", self.index.display())
    }
}

/// The flag of each [`ExploreParams`] field the command line sets.
const FLAGS: [(&str, &str); 8] = [
    ("elements", "--elements"),
    ("pulses", "--pulses"),
    ("step_deg", "--step-deg"),
    ("bandwidth_ghz", "--bandwidth-ghz"),
    ("tx_power_dbm", "--tx-power-dbm"),
    ("mappers", "--mapper"),
    ("seeds", "--seeds"),
    ("max_minutes", "--max-minutes"),
];

/// An error of [`ExploreParams`]'s check naming the flag instead of the field (the map
/// parameters' errors, whose fields are no flag of `explore`, as they are).
fn flag_named(e: Error) -> Error {
    match e {
        Error::Param { field, msg } => match FLAGS.iter().find(|(f, _)| *f == field) {
            Some((_, flag)) => Error::param(*flag, msg),
            None => Error::Param { field, msg },
        },
        e => e,
    }
}

/// Run `pradar explore`.
pub fn explore(cmd: &Explore, progress: Progress) -> Result<ExploreSummary> {
    let params = cmd.params.check().map_err(flag_named)?;
    // a constant out of range names the file it came from
    let model = match &cmd.energy_model {
        Some(p) => EnergyModel::load(p)?
            .check()
            .map_err(|e| crate::error::Error::input(p, e.to_string()))?,
        None => EnergyModel::default().check()?,
    };
    std::fs::create_dir_all(&cmd.out).map_err(|e| crate::error::Error::io(&cmd.out, e))?;
    let campaign = match &cmd.campaign {
        Some(c) => c.clone(),
        None => crate::pipeline::write_builtin_corridor(&cmd.out.join("work").join("input"))?,
    };
    let inputs = ExploreInputs {
        campaign,
        data: cmd.data.clone(),
        keep_work: cmd.keep_work,
    };
    let out = run_grid(&inputs, &params, &model, &cmd.out, progress)?;
    let s = summarize(&out);
    let v = verdicts(&s, &out.paper);
    let write =
        |name: &str, text: String| crate::io::write_bytes(&cmd.out.join(name), text.as_bytes());
    let rows = rows_table(&out);
    let table = summary_table(&s);
    write("explore.csv", rows.to_csv())?;
    write("explore.md", rows.to_markdown())?;
    write("summary.csv", table.to_csv())?;
    write("summary.md", table.to_markdown())?;
    write("timing.csv", timing_table(&out).to_csv())?;
    write("energy_model.toml", model.to_toml())?;
    crate::report::explore::write_plots(&cmd.out, &s, out.slice)?;
    let join = |v: Vec<String>| v.join(", ");
    let listed = vec![
        ("campaign".to_string(), out.campaign.display().to_string()),
        ("data".into(), out.data.clone()),
        (
            "elements".into(),
            join(params.elements.iter().map(|x| x.to_string()).collect()),
        ),
        (
            "pulses".into(),
            join(params.pulses.iter().map(|x| x.to_string()).collect()),
        ),
        (
            "step (°)".into(),
            join(params.step_deg.iter().map(|x| x.to_string()).collect()),
        ),
        (
            "bandwidth (GHz)".into(),
            join(
                out.configs
                    .iter()
                    .map(|c| c.bandwidth_ghz.to_string())
                    .fold(Vec::new(), |mut a, x| {
                        if !a.contains(&x) {
                            a.push(x)
                        }
                        a
                    }),
            ),
        ),
        (
            "transmit power (dBm)".into(),
            join(out.configs.iter().map(|c| c.tx_power_dbm.to_string()).fold(
                Vec::new(),
                |mut a, x| {
                    if !a.contains(&x) {
                        a.push(x)
                    }
                    a
                },
            )),
        ),
        (
            "mappers".into(),
            join(
                params
                    .mappers
                    .iter()
                    .map(|m| m.name().to_string())
                    .collect(),
            ),
        ),
        (
            "seeds".into(),
            join(params.seeds.iter().map(|x| x.to_string()).collect()),
        ),
    ];
    let section = crate::report::explore::section("", &listed, &s, &v, &model);
    crate::report::explore::write_index(&cmd.out, &section)?;
    // the same section for `report --explore DIR`, its links under `explore/`
    let linked = crate::report::explore::section("explore/", &listed, &s, &v, &model);
    write(crate::pipeline::EXPLORE_SECTION, linked.html)?;
    Ok(ExploreSummary {
        jobs: out.timings.len(),
        estimate_minutes: out.estimate_minutes,
        verdicts: v.iter().map(|x| verdict_text(&s, x)).collect(),
        index: cmd.out.join("index.html"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each list's error names the flag the user gave it with.
    #[test]
    fn check_errors_name_the_flags() {
        let d = ExploreParams::default();
        let cases = [
            (
                ExploreParams {
                    elements: vec![20],
                    ..d.clone()
                },
                "`--elements`",
            ),
            (
                ExploreParams {
                    pulses: vec![0],
                    ..d.clone()
                },
                "`--pulses`",
            ),
            (
                ExploreParams {
                    step_deg: vec![-5.0],
                    ..d.clone()
                },
                "`--step-deg`",
            ),
            (
                ExploreParams {
                    bandwidth_ghz: vec![7.0],
                    ..d.clone()
                },
                "`--bandwidth-ghz`",
            ),
            (
                ExploreParams {
                    tx_power_dbm: vec![f64::NAN],
                    ..d.clone()
                },
                "`--tx-power-dbm`",
            ),
            (
                ExploreParams {
                    mappers: vec![crate::mapping::Method::OgBoresight],
                    ..d.clone()
                },
                "`--mapper`",
            ),
            (
                ExploreParams {
                    seeds: vec![1, 1],
                    ..d.clone()
                },
                "`--seeds`",
            ),
            (
                ExploreParams {
                    max_minutes: 0.0,
                    ..d.clone()
                },
                "`--max-minutes`",
            ),
        ];
        for (p, flag) in cases {
            let e = flag_named(p.check().unwrap_err()).to_string();
            assert!(e.contains(flag), "{e}");
        }
    }
}
