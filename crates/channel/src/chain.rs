//! The analysis chain in memory, the one every caller runs: an energy table → MPCs (2-D
//! CLEAN, default parameters) → clusters (K-means, default criterion, the campaign's
//! angular sector) → Table 1 and the model file (the fit's estimators).
//!
//! Takes an energy table and its campaign; gives the MPCs and their clustering
//! ([`extract_and_cluster`]) and the fit on that clustering
//! ([`fit_clustering`](crate::fit::channel::fit_clustering)). `report` (through
//! `pipeline::analyse`, which also writes the tables) and its K_max refits both run these,
//! so their chains cannot drift apart.
//! The stages' defaults are the commands' defaults, so the chain here is what
//! `extract`, `cluster` and `fit` run one command at a time.

use crate::campaign::manifest::Campaign;
use crate::cluster::{self, ClusterParams, ClusterValid, Clustering};
use crate::energy::EnergyMatrix;
use crate::error::Result;
use crate::mpc::{self, ExtractParams, ExtractValid, Mpc};
use crate::params::ParamGuard;

/// The chain's checked parameters: the extraction's and the clustering's.
#[derive(Debug, Clone)]
pub struct ChainParams {
    /// CLEAN (or peaks) and the diffuse labelling.
    pub extract: ExtractValid,
    /// K-means and its criterion.
    pub cluster: ClusterValid,
}

impl ChainParams {
    /// The commands' defaults, the clustering's sector the campaign's steering width.
    pub fn for_campaign(c: &Campaign) -> Result<ChainParams> {
        let width = c.manifest.directions.width_deg();
        Ok(ChainParams {
            extract: ExtractParams::default().check()?,
            cluster: ClusterParams::default().sector_deg(width).check()?,
        })
    }
}

/// The MPCs of energy table `em` (of campaign `c`) and their clustering.
pub fn extract_and_cluster(
    em: &EnergyMatrix,
    c: &Campaign,
    p: &ChainParams,
) -> Result<(Vec<Mpc>, Clustering)> {
    let mpcs = mpc::extract(em, c, &p.extract)?;
    let clustering = cluster::cluster(&mpcs, &headings_deg(c), &p.cluster)?;
    Ok((mpcs, clustering))
}

/// The poses' headings, degrees (what the clustering takes to place MPCs globally).
pub fn headings_deg(c: &Campaign) -> Vec<f64> {
    c.manifest.poses.iter().map(|p| p.heading_deg).collect()
}
