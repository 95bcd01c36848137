//! The campaign fit: Table 1 quantities from clustered MPCs (DESIGN §2 "Fitting").
//!
//! Takes the clustered MPC table (`cluster`) and the campaign (analysis view only: poses,
//! band, array, layout — never `[scene]`/`[clutter]`) and checked [`FitValid`] parameters;
//! gives a [`ChannelFit`]: the fitted model file ([`ModelConfig`]) and the diagnostics of
//! each quantity, from which [`table1`](super::table1) renders the Table 1 comparison.
//!
//! Per position p and cluster c (MPC rows grouped by `cluster_id`):
//! * resolution δ = T_b = 1/B: arrivals closer than one bin merge in CLEAN, so gaps are
//!   δ + Exp(rate); gaps below δ (arrivals in other directions) are counted as δ. The
//!   detection window is the energy table's delay span beyond the coupling gate.
//! * Λ: gaps between the sorted first arrivals of the clusters of a position,
//!   shifted-exponential MLE;
//! * λ: gaps between the sorted ray delays inside each cluster, shifted-exponential MLE;
//! * AoA: ray angle minus the cluster's reference (strongest) ray angle, that ray left out;
//!   Laplacian MLE, reported as std = √2·b, over the clusters whose reference lies 2·b̂₀
//!   inside the sector (`aoa_groups`: near an edge the rays beyond it are lost and the
//!   offsets read narrow);
//! * perimeter statistics look at the interior of what the pose observes
//!   ([`Interior`]): d_p uses the clusters located in it, d_c the
//!   clusters whose projections fall on the perimeter observed in it
//!   ([`geometry`](super::geometry) has the locations, offsets and stretches);
//! * d_p: the mean *signed* offset of the cluster locations from the perimeter (negative
//!   beyond it), floored at 1 mm, with its position-bootstrap interval (the signed mean is
//!   free of the errors-in-variables bias that folding the noise at the wall adds); the
//!   families, KS and plots use the offsets folded at the wall (floored at 1 mm);
//! * d_c: the censored exponential MLE of the mean spacing along the observed perimeter,
//!   Σ L / Σ k (observed length over clusters in it, summed over positions; its bootstrap
//!   resamples positions); the complete gaps inside one observed stretch are the samples
//!   for the families, the KS test, the plots and the std. Reported in m and as ns one-way
//!   (m/c) and round-trip (2m/c);
//! * Γ, γ: decay = −10·log10(e)/slope of power (dB) against delay.
//!   - Γ, the *excess* cluster decay (model schema 2: each cluster at its own range):
//!     least-squares line of the clusters' range-corrected strongest-ray power
//!     P_l + 40·log10 r_l (P_l, T_l the power and delay of the cluster's strongest ray,
//!     r_l = c·T_l/2) against T_l, both relative to the position's earliest cluster. The
//!     radar equation's r⁻⁴ is the model's own, so what is left is the decay beyond it;
//!     no decaying trend is Γ = ∞ (a value, not a refusal). The strongest ray is the law's
//!     own quantity (σ_l is the first ray's σ, the strongest in expectation); a cluster's
//!     total power also carries its ray count and γ, and grows where the partition merges
//!     two clusters (more often far from the pose, where they subtend smaller angles),
//!     which flattened the slope (Γ +20 to +57 % against the same estimator on the true
//!     clusters in the closed loop; docs/fit.md). Powers scatter both ways (log-normal σ),
//!     so least squares.
//!   - γ: least-absolute-deviation line through the origin of the rays' power relative to
//!     their cluster's first ray against excess delay (the x-weighted median of y/x). The
//!     line passes through the first ray by construction, and the errors are one-sided:
//!     where clustering merges two clusters, the second cluster's strong first rays sit
//!     far above the first cluster's decay, which pulls a least-squares line up;
//! * rays per cluster (mean) and σ of a cluster's strongest ray from the radar equation
//!   σ = E·(4π)³d⁴/(G²λ²) at d = c·τ/2 with the array's broadside gain.
//!
//! Every quantity: estimate, 95 % bootstrap interval resampling whole positions in blocks
//! ([`bootstrap_block`], seeded), KS statistic with its
//! parametric-bootstrap p-value, and the candidate families ranked by AIC.
//!
//! Partial fits. A quantity these data cannot give is marked not estimable, with the
//! reason in one short line, in the model file (`not_estimable = "<reason>"` beside the
//! stated value synth draws, [`ModelConfig::with_stated_values`]) and in Table 1 ("not
//! estimable: <reason>; drawn at <value>"), and the others are fitted and written:
//! * what marks a quantity: fewer than 2 samples (Λ with fewer than 2 clusters at every
//!   position, λ and the AoA with single-ray clusters, d_p with fewer than 2 clusters in
//!   the interior), a family that does not fit the samples or a value that is not finite
//!   and positive, no cluster on the observed perimeter (d_c), no decaying trend or fewer
//!   than 3 powers (γ), fewer than 3 powers (Γ), no clusters (the means). Too few positions for the bootstrap
//!   only leave the interval out; too few complete gaps only d_c's families and KS.
//! * what stays an error: bad input — an unreadable or malformed table, negative position
//!   or cluster ids, a position outside the campaign, a delay or angle that is not finite,
//!   a NaN power, a bad manifest or layout — and a fit where not one quantity can be
//!   estimated (one line with every reason).
//!
//! Every entry of [`ChannelFit::details`] is present, a not-estimable one with no samples.
//!
//! Measurements behind these choices (closed-loop and coverage figures): `docs/fit.md`.
//!
//! Layout: this module holds the entry points and the fit's steps (`fit_rays`); `rays`
//! reads, checks and groups the input rays, `aoa` gives the AoA offsets, margin and
//! samples, `samples` gathers every quantity's samples per position.

mod aoa;
mod rays;
mod samples;

use crate::campaign::layout::Layout;
use crate::campaign::manifest::Campaign;
use crate::error::{Error, Result};
use crate::fit::geometry::{bootstrap_block, Interior};
use crate::fit::identify::Identification;
use crate::fit::quantities::{
    excess_decay_quantity, fit_arrivals, fit_offset, fit_spacing, mean_quantity,
    ray_decay_quantity, Resampling,
};
use crate::model::file::{BinSettings, ModelConfig};
use aoa::{aoa_groups, aoa_margin, aoa_offsets};
use rays::{group_clusters, read_rays};
use samples::Samples;
use std::collections::BTreeMap;
use std::path::Path;

pub use crate::fit::params::{FitParams, FitValid};
pub use crate::fit::quantities::FittedQuantity;
pub use crate::fit::table1::write_table1;

/// One discrete ray (MPC, or a simulator's true ray) with its cluster: the fit's input
/// row (a clustering's: [`clustered_rays`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClusteredRay {
    /// Position index in the campaign.
    pub position: usize,
    /// Cluster id (unique within the position; a truth id may name one object seen from
    /// many positions).
    pub cluster: usize,
    /// Round-trip delay, ns.
    pub delay_ns: f64,
    /// Angle of arrival relative to the pose's heading, degrees.
    pub angle_rel_deg: f64,
    /// Power, dB.
    pub power_db: f64,
}

type Ray = ClusteredRay;

/// The result of a campaign fit.
#[derive(Debug, Clone)]
pub struct ChannelFit {
    /// The model file.
    pub model: ModelConfig,
    /// Diagnostics per quantity name.
    pub details: BTreeMap<String, FittedQuantity>,
    /// d_c samples (m), for the Table 1 ns conversions.
    pub dc_m: Vec<f64>,
    /// The closed loop's verdict per quantity key (`inter_cluster_rate`, …; Table 1's
    /// closed-loop column, [`crate::fit::identify`]): empty until the layer above runs it
    /// (`crate::closed_loop`), as `report` does.
    pub identified: BTreeMap<String, Identification>,
}

/// Fit the channel model from a clustered MPC table.
///
/// ```no_run
/// use pradar_formats::campaign::manifest::Campaign;
/// use pradar_channel::fit::channel::{fit_channel, FitParams};
/// use pradar_formats::params::ParamGuard;
/// use std::path::Path;
/// # fn main() -> pradar_formats::error::Result<()> {
/// let c = Campaign::load(Path::new("campaign.toml"))?;
/// let p = FitParams { bootstrap: 200, seed: 1 }.check()?;
/// let f = fit_channel(Path::new("clusters.parquet"), &c, &p)?;
/// f.model.save(Path::new("fitted_model.toml"))?;
/// pradar_channel::fit::table1::write_table1(Path::new("table1.md"), &c.manifest.name, &f, None)?;
/// # Ok(())
/// # }
/// ```
pub fn fit_channel(clusters: &Path, c: &Campaign, p: &FitValid) -> Result<ChannelFit> {
    let mut f = fit_rays(clusters, read_rays(clusters, false)?, c, p)?;
    let r = crate::fit::diffuse::Resample {
        bootstrap: p.bootstrap,
        seed: p.seed,
        block: bootstrap_block(&c.manifest),
    };
    f.model.diffuse = crate::fit::diffuse::fit_diffuse_table(clusters, c.manifest.positions(), &r)?;
    f.model = f.model.with_stated_values();
    f.model.check()?;
    Ok(f)
}

/// [`fit_channel`] on a clustering in memory (the chain's own, not read back from the table
/// `cluster` writes of it; `name` is what errors name): the same discrete rays
/// ([`clustered_rays`]) and the same diffuse MPCs, so the same Table 1 and model file.
pub fn fit_clustering(
    name: &Path,
    clustering: &crate::cluster::Clustering,
    c: &Campaign,
    p: &FitValid,
) -> Result<ChannelFit> {
    let mut f = fit_rays(name, clustered_rays(clustering), c, p)?;
    let r = crate::fit::diffuse::Resample {
        bootstrap: p.bootstrap,
        seed: p.seed,
        block: bootstrap_block(&c.manifest),
    };
    f.model.diffuse =
        crate::fit::diffuse::fit_diffuse(&clustering.mpcs, c.manifest.positions(), &r);
    f.model = f.model.with_stated_values();
    f.model.check()?;
    Ok(f)
}

/// The same estimators applied to the simulator's true clusters (`truth_dir/rays.parquet`
/// grouped by `truth_cluster`, defined in `docs/campaign.md`, "True clusters of a
/// simulated scene"; the diffuse rows, −1, are dropped), seen from each position in the half-plane
/// and within the energy table's delay span — the reference the chain is scored against.
/// An older `rays.parquet` without `truth_cluster` falls back to `cluster_id` (clutter
/// clusters only).
pub fn fit_truth(truth_dir: &Path, c: &Campaign, p: &FitValid) -> Result<ChannelFit> {
    let path = truth_dir.join("rays.parquet");
    let max = c.manifest.processing.max_delay_ns;
    let rays: Vec<Ray> = read_rays(&path, true)?
        .into_iter()
        .filter(|r| r.angle_rel_deg.abs() <= 90.0 && r.delay_ns <= max)
        .collect();
    fit_rays(&path, rays, c, p)
}

/// The discrete rays of a clustering (its MPCs with their campaign-wide cluster ids, as
/// `cluster::io` writes them); the diffuse MPCs (no id) are left out.
pub fn clustered_rays(clustering: &crate::cluster::Clustering) -> Vec<ClusteredRay> {
    (clustering.mpcs.iter().zip(&clustering.cluster_id))
        .filter_map(|(m, id)| {
            id.map(|id| ClusteredRay {
                position: m.position,
                cluster: id,
                delay_ns: m.delay_ns,
                angle_rel_deg: m.angle_rel_deg,
                power_db: m.power_db,
            })
        })
        .collect()
}

/// Read and check a clustered MPC table as `fit` does (before any fitting); returns its
/// number of discrete rays. The fuzz harness's entry for the cluster table (`crate::fuzz`,
/// feature `fuzz`).
#[cfg(feature = "fuzz")]
pub fn read_clustered(path: &Path) -> Result<usize> {
    Ok(read_rays(path, false)?.len())
}

/// The campaign fit on rays read from `clusters` (named in errors), in steps: group the
/// rays by (position, cluster), take the AoA offsets and their sector margin, gather the
/// per-position samples, fit each quantity, assemble the model file.
fn fit_rays(clusters: &Path, rays: Vec<Ray>, c: &Campaign, p: &FitValid) -> Result<ChannelFit> {
    let m = &c.manifest;
    let layout = Layout::load(&c.layout_path())?;
    let delta = 1e9 / m.band.bandwidth_hz();
    let by_cluster = group_clusters(clusters, &rays, m.positions())?;
    // the offsets' Laplacian scale sets the sector margin of the AoA (`aoa_groups`) and of
    // the perimeter statistics
    let aoa_by_cluster = aoa_offsets(&by_cluster);
    let margin = aoa_margin(&aoa_by_cluster);
    let region = Interior::of(m, margin);
    let s = Samples::gather(&by_cluster, m, &layout, &region, delta)?;
    let aoa = aoa_groups(
        &aoa_by_cluster,
        m.positions(),
        m.directions.start_deg,
        m.directions.stop_deg,
        margin,
    );
    let r = Resampling {
        bootstrap: p.bootstrap,
        seed: p.seed,
        block: bootstrap_block(m),
    };
    let mut details = BTreeMap::new();
    for (name, q) in fit_arrivals(&s.inter, &s.intra, &aoa, delta, &r) {
        details.insert(name.to_string(), q);
    }
    details.insert(
        "perimeter_offset".to_string(),
        fit_offset(&s.dp, &s.dp_signed, &r),
    );
    details.insert(
        "perimeter_spacing".to_string(),
        fit_spacing(&s.dc, &s.exposure, &r),
    );
    let cluster_decay = excess_decay_quantity(&s.cluster_pairs(), 6, &r);
    let ray_decay = ray_decay_quantity(&s.ray_decay, 9, &r);
    let rays_per_cluster = mean_quantity(&s.members, "count", "poisson", 7, &r);
    let cluster_rrcs = mean_quantity(&s.sigma, "m2", "lognormal", 8, &r);
    let q = |k: &str| details[k].q.clone();
    let model = ModelConfig {
        schema_version: crate::model::file::SCHEMA_VERSION,
        array: Some(m.array),
        band: Some(m.band),
        bins: Some(BinSettings {
            bin_width_ns: delta,
            window: format!("{:?}", m.processing.window).to_lowercase(),
        }),
        inter_cluster_rate: q("inter_cluster_rate"),
        intra_cluster_rate: q("intra_cluster_rate"),
        intra_cluster_aoa: q("intra_cluster_aoa"),
        perimeter_offset: q("perimeter_offset"),
        perimeter_spacing: q("perimeter_spacing"),
        cluster_decay,
        ray_decay,
        rays_per_cluster,
        cluster_rrcs,
        diffuse: None,
        walls: None,
        calibration: None,
        legacy_correction: None,
    };
    model.check()?;
    nothing_estimable(clusters, rays.len(), &model)?;
    let model = model.with_stated_values();
    Ok(ChannelFit {
        model,
        dc_m: details
            .get("perimeter_spacing")
            .map(|d| d.samples.clone())
            .unwrap_or_default(),
        details,
        identified: BTreeMap::new(),
    })
}

/// The error when not one quantity of `model` could be estimated (from `n` rays of
/// `clusters`): one line with each quantity's reason.
fn nothing_estimable(clusters: &Path, n: usize, model: &ModelConfig) -> Result<()> {
    let m = model;
    let all = [
        &m.inter_cluster_rate,
        &m.intra_cluster_rate,
        &m.intra_cluster_aoa,
        &m.perimeter_offset,
        &m.perimeter_spacing,
        &m.cluster_decay,
        &m.ray_decay,
        &m.rays_per_cluster,
        &m.cluster_rrcs,
    ];
    if all.iter().any(|q| q.is_estimable()) {
        return Ok(());
    }
    let why: Vec<String> = (m.not_estimable().iter())
        .map(|(q, r)| format!("{q}: {r}"))
        .collect();
    Err(Error::input(
        clusters,
        format!(
            "no quantity can be estimated from {n} rays ({})",
            why.join("; ")
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::geometry::tests::hall_at_centre;
    use crate::params::ParamGuard;
    use crate::table;
    use crate::units::range_m;

    #[test]
    fn spacing_without_two_complete_gaps_keeps_the_censored_value() {
        // two poses at the centre of the 16 m × 10 m hall facing +x (each observes 22.4 m of
        // perimeter, see `geometry`'s tests); pose 0 sees clusters A, B on the right wall
        // (one complete gap), pose 1 sees C there and D on the top wall outside the
        // interior: one complete gap in all, so d_c has no families, KS or std, but its
        // value is Σ L / Σ k = 2 · 22.36 m / 3 clusters
        let (_dir, c) = hall_at_centre(2);
        let mut rays = Vec::new();
        // (position, cluster, centroid x, y, first ray power dB)
        for (position, cluster, x, y, p0) in [
            (0, 0, 7.6, -1.0, -100.0),
            (0, 1, 7.6, 2.0, -103.0),
            (1, 2, 7.6, 0.0, -104.0),
            (1, 3, 0.5, 4.6, -95.0),
        ] {
            let (r, bearing) = (f64::hypot(x, y), f64::atan2(y, x).to_degrees());
            let excess = [0.0, 1.5, 3.2];
            let depth = excess.iter().map(|t| range_m(*t)).sum::<f64>() / 3.0;
            let t0 = crate::units::delay_ns(r - depth);
            for (t, a, dp) in [(0.0, 0.0, 0.0), (1.5, 5.0, -3.0), (3.2, -4.0, -7.0)] {
                rays.push(Ray {
                    position,
                    cluster,
                    delay_ns: t0 + t,
                    angle_rel_deg: bearing + a,
                    power_db: p0 + dp,
                });
            }
        }
        let f = fit_rays(
            Path::new("clusters.parquet"),
            rays,
            &c,
            &FitParams::default().check().unwrap(),
        )
        .unwrap();
        let d = &f.details["perimeter_spacing"];
        assert!(d.q.ks.is_none() && d.aic.is_empty() && d.samples.len() == 1);
        let want = 2.0 * (10.0 + 2.0 * (8.0 - 5.0 / 70f64.to_radians().tan())) / 3.0;
        let got = f.model.perimeter_spacing.value;
        assert!((got - want).abs() < 0.3, "d_c {got} m, want {want} m");
        let row = &crate::fit::table1::rows(&f, None)[1];
        assert!(
            row.value_shown
                .contains("std — (fewer than 2 complete gaps)"),
            "{}",
            row.value_shown
        );
        assert_eq!(row.ks_p, None);
        // the table: "—" shown, the CSV's ks_p empty, the value a number
        let t = crate::fit::table1::table(&f, None);
        let md = t.to_markdown();
        let line = md.lines().nth(3).unwrap();
        assert!(line.contains("| exponential | — |"), "{line}");
        let csv = t.to_csv();
        assert!(csv.starts_with("parameter,value,unit,lo,hi,family,ks_p,best_aic,paper\n"));
        let dc = csv.lines().nth(2).unwrap();
        assert!(
            dc.starts_with(&format!("inter-cluster perimeter distance d_c,{got},m,")),
            "{dc}"
        );
        assert!(dc.contains(",exponential,,,"), "{dc}");
    }

    #[test]
    fn bad_input_stays_an_error_and_no_data_estimate_nothing() {
        let (_dir, c) = hall_at_centre(2);
        let p = FitParams::default().check().unwrap();
        let ray = |delay_ns: f64| Ray {
            position: 0,
            cluster: 0,
            delay_ns,
            angle_rel_deg: 0.0,
            power_db: -90.0,
        };
        let path = Path::new("clusters.parquet");
        let e = fit_rays(path, vec![ray(f64::NAN)], &c, &p)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("clusters.parquet") && e.contains("finite"),
            "{e}"
        );
        let e = fit_rays(
            path,
            vec![Ray {
                position: 5,
                ..ray(10.0)
            }],
            &c,
            &p,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("outside the campaign"), "{e}");
        let e = fit_rays(path, Vec::new(), &c, &p).unwrap_err().to_string();
        assert!(
            e.contains("no quantity can be estimated from 0 rays")
                && e.contains("rays_per_cluster: no clusters")
                && !e.contains('\n'),
            "{e}"
        );
        // a single ray: the means are fitted, the rest marked with their reasons, and every
        // entry of `details` is there (the not-estimable ones without samples)
        let f = fit_rays(path, vec![ray(10.0)], &c, &p).unwrap();
        assert_eq!(f.model.rays_per_cluster.value, 1.0);
        assert_eq!(f.details.len(), 5);
        let ne = f.model.not_estimable();
        assert!(ne.iter().any(|(q, r)| q == "intra_cluster_rate"
            && r == "no intra-cluster gaps (every cluster has a single ray)"));
        assert!(f.details["inter_cluster_rate"].samples.is_empty());
        let rows = crate::fit::table1::rows(&f, Some(&f));
        // flagged, with the stated value synth draws (the paper's Λ) in the text only
        assert!(rows[0].value.is_nan());
        assert_eq!(f.model.inter_cluster_rate.value, 0.21);
        assert!(
            rows[0].value_shown.starts_with("not estimable: ")
                && rows[0]
                    .value_shown
                    .ends_with("drawn at 0.210 1/ns (stated)"),
            "{}",
            rows[0].value_shown
        );
        f.model.require_estimable(&Default::default()).unwrap();
        assert_eq!(rows[0].truth_shown(), rows[0].value_shown);
    }

    #[test]
    fn truth_rays_group_by_truth_cluster_else_cluster_id() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rays.parquet");
        let cols = |with_truth: bool| {
            let mut v = vec![
                table::col("position", vec![0i32, 0, 1, 1]),
                table::col("cluster_id", vec![0i64, -1, -1, 1]),
                table::col("delay_ns", vec![10.0, 11.0, 12.0, 13.0]),
                table::col("angle_rel_deg", vec![0.0; 4]),
                table::col("power_db", vec![-60.0; 4]),
            ];
            if with_truth {
                // a clutter ray, a diffuse row (−1), a corner (one-ray cluster 2), clutter
                v.push(table::col("truth_cluster", vec![0i64, -1, 2, 1]));
            }
            table::frame(&path, v).unwrap()
        };
        let clusters = |truth: bool| {
            read_rays(&path, truth)
                .unwrap()
                .iter()
                .map(|r| (r.position, r.cluster))
                .collect::<Vec<_>>()
        };
        table::write_parquet(&path, &cols(true), vec![]).unwrap();
        assert_eq!(clusters(true), [(0, 0), (1, 2), (1, 1)]);
        // an older truth file: the clutter clusters of `cluster_id`
        table::write_parquet(&path, &cols(false), vec![]).unwrap();
        assert_eq!(clusters(true), [(0, 0), (1, 1)]);
        // a clustered MPC table never has −1
        let e = read_rays(&path, false).unwrap_err().to_string();
        assert!(e.contains("cluster_id"), "{e}");
    }
}
