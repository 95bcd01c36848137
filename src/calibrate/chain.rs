//! The cluster chain's estimates as raw summaries (`--distance summaries-chain`, issue 30):
//! indirect inference (Drovandi, Pettitt & Faddy, JRSS-C 2011: the parameters of an
//! auxiliary model fitted to the data as ABC summaries).
//!
//! Takes an energy matrix of the campaign (the measured one or a simulation); gives
//! [`NAMES`]: ln(1 + discrete MPCs), ln(1 + clusters), the number of Table-1 quantities the
//! fit could not estimate, and the ln of the chain's estimate of each of the nine Table-1
//! quantities (Λ, λ, AoA std, d_p, d_c, Γ, γ, rays per cluster, σ). The chain is the
//! analysis's own (CLEAN with default parameters → K-means with the default criterion over
//! the campaign's sector → the Table-1 estimators, `pipeline::analyse`), without the
//! diffuse component's fit and with the fewest bootstrap resamples (40: the summaries use
//! the point estimates only).
//!
//! Why: the pooled and per-profile statistics ([`super::summaries`]) summarise clusters;
//! what tells λ from the rays per cluster, or d_c from Γ, is the arrangement of individual
//! clusters across poses, which is what the chain estimates. Its estimates are biased
//! (clusters merged, members beyond the sector), which does not matter here: the
//! calibration regresses the parameters on the summaries (semi-automatic ABC) and compares
//! the data's chain with the simulations' chain, so a bias common to both cancels.
//!
//! A quantity the fit cannot estimate (too few clusters), or a failed extraction or fit,
//! takes the fallback ln value of the geometric middle of the default prior's range
//! (Λ: 1/ns), counted in the third summary; estimates are clamped to that range widened by
//! e² on each side, so one wild estimate cannot dominate the regression.

use crate::campaign::manifest::Campaign;
use crate::cluster::{ClusterParams, ClusterValid};
use crate::energy::EnergyMatrix;
use crate::error::Result;
use crate::fit::channel::fit_clustering;
use crate::fit::params::{FitParams, FitValid};
use crate::mpc::{Component, ExtractParams, ExtractValid};
use crate::params::ParamGuard;

/// The chain summaries' names, in order.
pub const NAMES: [&str; 12] = [
    "chain ln(1 + MPCs)",
    "chain ln(1 + clusters)",
    "chain quantities not estimable",
    "chain ln inter_cluster_rate",
    "chain ln intra_cluster_rate",
    "chain ln intra_cluster_aoa",
    "chain ln perimeter_offset",
    "chain ln perimeter_spacing",
    "chain ln cluster_decay",
    "chain ln ray_decay",
    "chain ln rays_per_cluster",
    "chain ln cluster_rrcs",
];

/// The nine quantities in [`NAMES`]' order with their fallback ranges (the default prior's,
/// Λ 0.1–10 /ns).
const QUANTITIES: [(&str, f64, f64); 9] = [
    ("inter_cluster_rate", 0.1, 10.0),
    ("intra_cluster_rate", 0.05, 3.0),
    ("intra_cluster_aoa", 2.0, 60.0),
    ("perimeter_offset", 0.05, 1.5),
    ("perimeter_spacing", 0.3, 20.0),
    ("cluster_decay", 2.0, 60.0),
    ("ray_decay", 0.5, 20.0),
    ("rays_per_cluster", 1.0, 20.0),
    ("cluster_rrcs", 1e-4, 1.0),
];

/// What the chain needs besides the energies: the campaign, a matrix with the measured
/// table's metadata and axes (its data replaced per call) and the stages' checked
/// parameters.
pub struct ChainContext<'a> {
    campaign: &'a Campaign,
    template: EnergyMatrix,
    extract: ExtractValid,
    cluster: ClusterValid,
    fit: FitValid,
}

impl<'a> ChainContext<'a> {
    /// The chain of campaign `c` on matrices shaped as `energy` (a whole matrix).
    pub fn new(c: &'a Campaign, energy: &EnergyMatrix) -> Result<ChainContext<'a>> {
        let sector = c.manifest.directions.width_deg();
        Ok(ChainContext {
            campaign: c,
            template: EnergyMatrix {
                meta: energy.meta.clone(),
                positions: energy.positions,
                angles_rel_deg: energy.angles_rel_deg.clone(),
                headings_deg: energy.headings_deg.clone(),
                bins: energy.bins,
                first: 0,
                data: Vec::new(),
            },
            extract: ExtractParams::default().check()?,
            cluster: ClusterParams::default().sector_deg(sector).check()?,
            fit: FitParams {
                bootstrap: crate::fit::params::MIN_BOOTSTRAP,
                seed: 1,
            }
            .check()?,
        })
    }

    /// The chain summaries ([`NAMES`]) of the energies `e` (position-major, the template's
    /// shape).
    pub fn summaries(&self, e: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; NAMES.len()];
        let fallback = |k: usize| {
            let (_, lo, hi) = QUANTITIES[k];
            0.5 * (lo.ln() + hi.ln())
        };
        for k in 0..QUANTITIES.len() {
            out[3 + k] = fallback(k);
        }
        out[2] = QUANTITIES.len() as f64;
        let em = EnergyMatrix {
            data: e.to_vec(),
            ..self.template.clone()
        };
        let Ok(mpcs) = crate::mpc::extract(&em, self.campaign, &self.extract) else {
            return out;
        };
        let discrete = mpcs
            .iter()
            .filter(|m| m.component != Component::Diffuse)
            .count();
        out[0] = (1.0 + discrete as f64).ln();
        let headings = &em.headings_deg;
        let Ok(cl) = crate::cluster::cluster(&mpcs, headings, &self.cluster) else {
            return out;
        };
        out[1] = (1.0 + cl.summary.len() as f64).ln();
        let Ok(f) = fit_clustering(&cl, self.campaign, &self.fit) else {
            return out;
        };
        for (k, (name, lo, hi)) in QUANTITIES.iter().enumerate() {
            let Some(q) = f.model.quantity(name) else {
                continue;
            };
            if q.is_estimable() && q.value.is_finite() && q.value > 0.0 {
                out[3 + k] = q.value.ln().clamp(lo.ln() - 2.0, hi.ln() + 2.0);
                out[2] -= 1.0;
            }
        }
        out
    }
}
