//! The analysis commands: `extract` (an energy table and its campaign into an MPC table),
//! `cluster` (an MPC table into clustered MPCs and a cluster summary, with the K = K_max
//! warning) and `fit` (clustered MPCs into the channel model file and Table 1, optionally
//! beside the simulator's truth). Each takes its command struct and gives a summary whose
//! `Display` is printed.

use super::{campaign_inputs, refuse};
use crate::campaign::manifest::Campaign;
use crate::cluster::ClusterParams;
use crate::energy::{EnergySource, EnergyTable};
use crate::error::Result;
use crate::fit::channel::{ChannelFit, FitParams};
use crate::mpc::{ExtractParams, Mpc};
use crate::params::ParamGuard;
use std::fmt;
use std::path::PathBuf;

/// `pradar extract`: MPCs of an energy table.
#[derive(Debug, Clone)]
pub struct Extract {
    /// Energy Parquet.
    pub energy: PathBuf,
    /// The campaign the energy came from.
    pub campaign: PathBuf,
    /// Output MPC Parquet.
    pub out: PathBuf,
    /// Method, margin and dynamic range.
    pub params: ExtractParams,
}

/// What `extract` wrote.
#[derive(Debug, Clone)]
pub struct ExtractSummary {
    /// MPCs written.
    pub mpcs: usize,
    /// Of which diffuse.
    pub diffuse: usize,
    /// Of which folded (wall echoes from beyond the unambiguous range).
    pub folded: usize,
    /// Positions of the energy table.
    pub positions: usize,
    /// The MPC Parquet written.
    pub out: PathBuf,
}

impl fmt::Display for ExtractSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // the folded count only when the fold stage labelled some (outputs within range
        // read as before)
        let folded = if self.folded > 0 {
            format!(", {} folded", self.folded)
        } else {
            String::new()
        };
        write!(
            f,
            "{} MPCs ({} diffuse{folded}) from {} positions -> {}",
            self.mpcs,
            self.diffuse,
            self.positions,
            self.out.display()
        )
    }
}

/// Run `pradar extract` ([`crate::mpc::extract`]), writing the table with its metadata.
pub fn extract(cmd: &Extract) -> Result<ExtractSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.push((cmd.energy.clone(), "--energy"));
    refuse(&[(cmd.out.clone(), "--out")], &inputs)?;
    // read a few positions at a time: memory does not grow with the number of poses
    let table = EnergyTable::open(&cmd.energy)?;
    let em = table.header();
    // checked here, where the energy file's name is known, so a mismatch names it
    crate::energy::check_campaign(&c, em, &cmd.energy)?;
    em.meta.check_noise(&cmd.energy)?;
    let (mpcs, labels) = crate::mpc::extract_labelled(&table, &c, &cmd.params.check()?)?;
    let mut meta = crate::mpc::table_metadata(em, &c, &cmd.params);
    meta.push((
        "diffuse_level_m2_per_m".into(),
        format!("{:.17e}", labels.diffuse.level_m2_per_m),
    ));
    // the energy table, for `fit`'s levels (through `cluster`), relative to the output's folder
    meta.extend(crate::cluster::io::energy_entry(&cmd.out, &cmd.energy));
    crate::mpc::write_mpcs(&cmd.out, &mpcs, meta)?;
    Ok(ExtractSummary {
        mpcs: mpcs.len(),
        diffuse: labels.diffuse(),
        folded: labels.fold.folded,
        positions: em.positions,
        out: cmd.out.clone(),
    })
}

/// `pradar cluster`: K-means clusters of an MPC table, per position.
#[derive(Debug, Clone)]
pub struct Cluster {
    /// MPC Parquet from `extract`.
    pub mpcs: PathBuf,
    /// Output clustered MPC Parquet (the summary goes to `<stem>_summary.parquet`).
    pub out: PathBuf,
    /// K_max, seed and criterion; the sector is read from the MPC table (180° when absent).
    pub params: ClusterParams,
}

/// What `cluster` wrote.
#[derive(Debug, Clone)]
pub struct ClusterSummary {
    /// Clusters over the campaign.
    pub clusters: usize,
    /// Positions.
    pub positions: usize,
    /// The clustered MPC Parquet.
    pub out: PathBuf,
    /// The cluster summary Parquet.
    pub summary: PathBuf,
    /// The K_max used.
    pub k_max: usize,
    /// Positions whose K is the cap while the criterion still preferred more.
    pub capped: Vec<usize>,
}

impl ClusterSummary {
    /// The K = K_max warning, when some position hit the cap.
    pub fn warning(&self) -> Option<String> {
        (!self.capped.is_empty()).then(|| {
            format!(
                "K = K_max = {} at {} of {} positions (the criterion still preferred more clusters there; the counts are set by --k-max)",
                self.k_max,
                self.capped.len(),
                self.positions
            )
        })
    }
}

impl fmt::Display for ClusterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} clusters over {} positions -> {} and {}",
            self.clusters,
            self.positions,
            self.out.display(),
            self.summary.display()
        )
    }
}

/// The pose heading of every position of an MPC table, degrees: global − relative angle
/// of the position's first MPC (0 for a position without MPCs; not wrapped). An MPC table
/// carries no poses, and every MPC of a position shares its pose's heading.
pub fn pose_headings(mpcs: &[Mpc]) -> Vec<f64> {
    let np = mpcs.iter().map(|x| x.position + 1).max().unwrap_or(0);
    let mut headings: Vec<Option<f64>> = vec![None; np];
    for x in mpcs {
        headings[x.position].get_or_insert(x.angle_global_deg - x.angle_rel_deg);
    }
    headings.into_iter().map(|h| h.unwrap_or(0.0)).collect()
}

/// Run `pradar cluster` ([`crate::cluster::cluster`]) and write both tables.
pub fn cluster(cmd: &Cluster) -> Result<ClusterSummary> {
    refuse(
        &[
            (cmd.out.clone(), "--out"),
            (
                crate::cluster::summary_path(&cmd.out),
                "--out (its summary)",
            ),
        ],
        &[(cmd.mpcs.clone(), "--mpcs")],
    )?;
    let m = crate::mpc::read_mpcs(&cmd.mpcs)?;
    let sector = crate::mpc::read_sector_deg(&cmd.mpcs)?.unwrap_or(180.0);
    let params = cmd.params.sector_deg(sector);
    let c = crate::cluster::cluster(&m, &pose_headings(&m), &params.check()?)?;
    // the energy table the MPCs came from goes on to `fit`
    let energy = crate::cluster::io::energy_of(&cmd.mpcs)?;
    let summary = crate::cluster::io::write_with(&cmd.out, &c, energy.as_deref())?;
    Ok(ClusterSummary {
        clusters: c.summary.len(),
        positions: c.positions.len(),
        out: cmd.out.clone(),
        summary,
        k_max: params.k_max,
        capped: c.positions_at_k_max(params.k_max),
    })
}

/// `pradar fit`: the channel model (Table 1) of clustered MPCs.
#[derive(Debug, Clone)]
pub struct Fit {
    /// Clustered MPC Parquet from `cluster`.
    pub clusters: PathBuf,
    /// The campaign (analysis view: `[scene]`/`[clutter]` are never read).
    pub campaign: PathBuf,
    /// Output model file.
    pub out: PathBuf,
    /// Table 1 Markdown (a CSV is written beside it).
    pub table: PathBuf,
    /// A simulator's `truth/` folder: the same estimators on its true clusters.
    pub truth: Option<PathBuf>,
    /// The campaign's energy table: the model's levels (`[walls]`, σ′, σ) are read from it
    /// ([`crate::model::levels`]). Without it, the table the clusters file names in its
    /// metadata (`energy`, written by `extract` and passed on by `cluster`); without either
    /// `fit` refuses (the cluster chain's own levels, read from CLEAN peaks, fail the
    /// predictive check), unless the model is partial (then it is written without levels:
    /// `synth` and `check` refuse it anyway).
    pub energy: Option<PathBuf>,
    /// Bootstrap resamples and seed.
    pub params: FitParams,
    /// Draws of the closed loop (Table 1's identifiability column,
    /// [`crate::closed_loop`]); 0: not run.
    pub closed_loop: usize,
}

/// The fits `fit` wrote.
#[derive(Debug, Clone)]
pub struct FitSummary {
    /// The fit of the clustered MPCs.
    pub fit: ChannelFit,
    /// The same estimators on the simulator's truth, when given.
    pub truth: Option<ChannelFit>,
}

impl FitSummary {
    /// One line per quantity of the fit that is not estimable (the command line prints each
    /// after `warning: `): "`<quantity>` not estimable: `<reason>`; drawn at its stated
    /// value `<v>`".
    pub fn warnings(&self) -> Vec<String> {
        let m = &self.fit.model;
        (m.not_estimable().into_iter())
            .map(|(q, r)| match m.quantity(&q).map(|x| x.value) {
                Some(v) if !v.is_nan() => format!(
                    "{q} not estimable: {r}; drawn at its stated value {}",
                    crate::error::short(v)
                ),
                _ => format!("{q} not estimable: {r}"),
            })
            .collect()
    }
}

impl fmt::Display for FitSummary {
    /// One line per Table 1 row: parameter, value, interval, truth, and the closed loop's
    /// verdict when it ran (`--closed-loop`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rows = crate::fit::table1::rows(&self.fit, self.truth.as_ref());
        for (i, r) in rows.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(
                f,
                "{:<38} {:<60} {:<20} truth {}",
                r.parameter,
                r.value_shown,
                r.interval_shown(),
                r.truth_shown()
            )?;
            if let Some(id) = &r.identified {
                write!(f, "  {}", id.shown(&r.unit))?;
            }
        }
        Ok(())
    }
}

/// Run `pradar fit` ([`crate::fit::channel::fit_channel`], and
/// [`crate::fit::channel::fit_truth`] with a truth folder); writes the model file and
/// Table 1. A partial fit is written with its not-estimable quantities marked
/// ([`FitSummary::warnings`] lists them); a fit where no quantity can be estimated is an
/// error and writes nothing.
pub fn fit(cmd: &Fit) -> Result<FitSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.push((cmd.clusters.clone(), "--clusters"));
    if let Some(dir) = &cmd.truth {
        inputs.push((dir.join("rays.parquet"), "--truth"));
    }
    // the energy table: --energy, else the one the clusters file names
    let energy = cmd.energy.clone().or_else(|| {
        crate::cluster::io::energy_of(&cmd.clusters)
            .ok()
            .flatten()
            .filter(|e| e.is_file())
    });
    if let Some(e) = &energy {
        inputs.push((e.clone(), "--energy"));
    }
    refuse(
        &[
            (cmd.table.clone(), "--table"),
            (cmd.table.with_extension("csv"), "--table (its CSV)"),
            (cmd.out.clone(), "--out"),
        ],
        &inputs,
    )?;
    let params = cmd.params.check()?;
    let mut fit = crate::fit::channel::fit_channel(&cmd.clusters, &c, &params)?;
    match energy {
        Some(energy) => {
            let em = crate::energy::EnergyMatrix::read(&energy)?;
            crate::energy::matrix::check_campaign(&c, &em, &energy)?;
            fit.model = crate::model::levels::fit_levels(&c, &em, &fit.model)?.0;
            if cmd.closed_loop > 0 {
                let cl = crate::closed_loop::ClosedLoopParams {
                    draws: cmd.closed_loop,
                    ..Default::default()
                }
                .check()?;
                let written = fit.model.require_estimable(&Default::default())?;
                fit.identified = crate::closed_loop::closed_loop(
                    &c,
                    &em,
                    &energy,
                    &written,
                    &params,
                    &cl,
                    &|_, _| {},
                )?;
            }
        }
        None => {
            return Err(crate::error::Error::param(
                "--energy",
                format!(
                    "needed: the model's levels ([walls], σ′, σ) are read from the campaign's energy table, and {} names none that exists",
                    cmd.clusters.display()
                ),
            ))
        }
    }
    let truth = match &cmd.truth {
        Some(dir) => Some(crate::fit::channel::fit_truth(dir, &c, &params)?),
        None => None,
    };
    // the table first, the model last: a model file on disk means the run completed
    fit.model.check()?;
    crate::fit::channel::write_table1(&cmd.table, &c.manifest.name, &fit, truth.as_ref())?;
    fit.model.save(&cmd.out)?;
    Ok(FitSummary { fit, truth })
}
