//! The analysis chain on one energy table: CLEAN → K-means → channel fit ([`analyse`]),
//! the channel layer's in-memory chain ([`crate::chain`]) with its tables written to `work/`.
//!
//! Every stage runs with its defaults (the clustering with the campaign's angular sector),
//! so `reproduce`, its geometry-only table and the experiments' model fit are the same
//! chain. A failed fit (too few clusters, say) is kept as a value, not raised, so the report
//! can say why.

use crate::campaign::manifest::Campaign;
use crate::chain::{headings_deg, ChainParams};
use crate::energy::EnergyMatrix;
use crate::error::Result;
use crate::fit::channel::fit_clustering;
use crate::{cluster, mpc};
use std::path::Path;
use std::time::Instant;

/// What the analysis chain (CLEAN → K-means → fit) gave for one energy table.
pub struct Analysis {
    /// Extracted MPCs.
    pub mpcs: Vec<mpc::Mpc>,
    /// Their clustering.
    pub clustering: cluster::Clustering,
    /// The clustering parameters used.
    pub cluster_params: cluster::ClusterParams,
    /// The channel fit (Table 1, model file), or why it failed (too few clusters, say).
    pub fit: Result<crate::fit::channel::ChannelFit>,
    /// Why the levels (`model::levels`) could not be read from the energy table, if so
    /// (the fit's model is then the cluster chain's).
    pub levels_error: Option<String>,
    /// Stage timings, s.
    pub timings: Vec<(String, f64)>,
}

/// Run CLEAN (default parameters), K-means (default criterion, the campaign's sector) and
/// the channel fit (default bootstrap) on an energy table `em` of campaign `sc` (read from
/// `energy`), writing `work/clusters.parquet` and `work/clusters_summary.parquet` (and
/// `work/mpcs.parquet` when `keep_mpcs`); both tables name `energy` in their metadata, as
/// `extract` and `cluster` do, so `fit` on them finds the levels' table. Extraction or
/// clustering errors are returned; a failed fit is kept in [`Analysis::fit`].
///
/// ```no_run
/// use pradar::campaign::manifest::Campaign;
/// use pradar::energy::EnergyMatrix;
/// use std::path::Path;
/// let sc = Campaign::load(Path::new("work/simulated/campaign.toml"))?;
/// let energy = Path::new("work/energy.parquet");
/// let em = EnergyMatrix::read(energy)?;
/// let a = pradar::pipeline::analyse(&sc, &em, energy, Path::new("work"), true)?;
/// println!("{} MPCs in {} clusters", a.mpcs.len(), a.clustering.summary.len());
/// # Ok::<(), pradar::error::Error>(())
/// ```
pub fn analyse(
    sc: &Campaign,
    em: &EnergyMatrix,
    energy: &Path,
    work: &Path,
    keep_mpcs: bool,
) -> Result<Analysis> {
    let mut timings = Vec::new();
    let t = Instant::now();
    let chain = ChainParams::for_campaign(sc)?;
    let xp = chain.extract.params();
    let mpcs = mpc::extract(em, sc, &chain.extract)?;
    if keep_mpcs {
        // `fit` (through `cluster`) reads the levels from the energy table the MPCs name
        let mp = work.join("mpcs.parquet");
        let mut meta = mpc::table_metadata(em, sc, xp);
        meta.extend(cluster::io::energy_entry(&mp, energy));
        mpc::write_mpcs(&mp, &mpcs, meta)?;
    }
    timings.push(("extract (CLEAN)".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let clustering = cluster::cluster(&mpcs, &headings_deg(sc), &chain.cluster)?;
    let cp = work.join("clusters.parquet");
    cluster::io::write_with(&cp, &clustering, Some(energy))?;
    timings.push(("cluster (K-means)".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let fit = fit_clustering(&cp, &clustering, sc, &Default::default());
    timings.push(("fit (Table 1)".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    // the levels refine a fitted model; when they cannot be read the chain's model stays
    let mut levels_error = None;
    let fit = fit.map(|mut f| {
        match crate::model::levels::fit_levels(sc, em, &f.model) {
            Ok((m, _)) => f.model = m,
            Err(e) => levels_error = Some(e.to_string()),
        }
        f
    });
    timings.push((
        "levels (walls, diffuse, clusters)".into(),
        t.elapsed().as_secs_f64(),
    ));
    Ok(Analysis {
        mpcs,
        clustering,
        cluster_params: *chain.cluster.params(),
        fit,
        levels_error,
        timings,
    })
}
