//! The `pradar map --method ekf` job: the runs filtered in order by one EKF
//! ([`crate::ekf`]), its maps written and scored.
//!
//! Fusion = the same filter continued over the next run; the fusion table snapshots the map
//! after each run; with several runs each run is also mapped alone by a fresh filter.
//! Files: `ekf.*` (soft map p, YAML thresholds η and 1 − η), `ekf_binary.*`, `ekf_mean.*`
//! ([`mean_grey`]), `ekf_std.*` ([`std_grey`]), `ekf_rrcs.csv` (row, col, x_m, y_m, mean_m,
//! std_m, p, occupied, arcs, arc_poses, arc_share, explained_arcs, explained_poses: the arc
//! explanation's counts,
//! [`EkfMap::explain`]), `reference.*` and `metrics.json` (with the EKF section
//! [`EkfReport`]: parameters, η, kernel half-width, work statistics per run, covariance
//! bytes).

use super::{
    load_runs, runs_regions, write_metrics_json, write_reference, FusionRow, LoadedRun, MapReport,
    MapValid, RunSummary,
};
use crate::ekf::{
    ekf_run_with_arcs, mean_grey, new_filter, std_grey, truncate_kernel, EchoArcs, EkfMap,
    EkfReport, EkfStats, EkfValid, EkfVariant, NoiseModel, RrcsFilter, Sight,
};
use crate::energy::EnergySource;
use crate::error::{Error, Result};
use crate::grid::Occlusion;
use crate::output::{self, soft_grey, GREY_FREE, GREY_OCCUPIED};
use crate::reference::{GridSpec, ReferenceMap};
use crate::score::{score_binary, MetricsPair, Regions};
use std::path::Path;

/// The runs with their window kernels and noise models.
struct EkfInputs {
    loaded: Vec<LoadedRun>,
    reference: ReferenceMap,
    region: Regions,
    kernels: Vec<Vec<f64>>,
    noises: Vec<NoiseModel>,
    occlusions: Vec<Occlusion>,
}

impl EkfInputs {
    /// What run `i`'s filter can see.
    fn sight(&self, i: usize) -> Sight<'_> {
        Sight {
            detector: &self.loaded[i].detector,
            occlusion: &self.occlusions[i],
        }
    }
}

/// What filtering the runs gave: the fused filter, its statistics per run, the fusion
/// table and each run's figures alone.
struct Filtered {
    /// The fused map (the arc explanation applied).
    map: EkfMap,
    stats: Vec<EkfStats>,
    fusion: Vec<FusionRow>,
    alone: Vec<MetricsPair>,
}

/// `pradar map --method ekf` (see the module docs).
pub fn run_map_ekf(opts: &MapValid, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<MapReport> {
    let params = opts.ekf();
    let inputs = ekf_inputs(opts, &params)?;
    let spec = inputs.reference.spec;
    let f = filter_runs(&inputs, &params, progress)?;
    let map = f.map;
    let bin = map.binary();
    let metrics = score_binary(&bin, &inputs.reference, &inputs.region);
    let eta = params.eta();
    write_ekf_files(&opts.out, &spec, &map, &params)?;
    write_reference(&opts.out, &inputs.reference)?;
    let runs = inputs
        .loaded
        .iter()
        .zip(&f.alone)
        .map(|(l, m)| RunSummary {
            campaign: l.campaign.path.display().to_string(),
            energy: l.energy_path.display().to_string(),
            threshold: l.detector.threshold,
            stats: Default::default(),
            metrics: *m,
        })
        .collect();
    let report = MapReport {
        method: "ekf".into(),
        rows: spec.rows,
        cols: spec.cols,
        cell_m: spec.cell_m,
        eta,
        observable_cells: inputs.region.observable.iter().filter(|&&v| v).count(),
        metrics,
        runs,
        fusion: f.fusion,
        ekf: Some(EkfReport {
            params: *params.params(),
            eta,
            kernel_half_width: truncate_kernel(&inputs.kernels[0], params.kernel_floor_db).len()
                - 1,
            stats: f.stats,
            covariance_bytes: covariance_bytes(&params, &spec),
        }),
        pose_noise: opts.pose_noise,
        slam: super::slam_summaries(&opts.out, &inputs.loaded)?,
        binary: bin,
    };
    write_metrics_json(&opts.out, &report)?;
    Ok(report)
}

/// Load the runs, their observable region, window kernels and noise models.
fn ekf_inputs(opts: &MapValid, params: &EkfValid) -> Result<EkfInputs> {
    let (loaded, reference) = load_runs(opts)?;
    let region = runs_regions(&loaded, &reference)?;
    let mut kernels = Vec::new();
    let mut noises = Vec::new();
    let mut occlusions = Vec::new();
    for l in &loaded {
        occlusions.push(l.occlusion(&opts.og()));
        kernels.push(super::window_kernel(&l.campaign)?);
        noises.push(NoiseModel::new(
            &l.energy.header().meta,
            params.model_error,
            &l.energy_path,
        )?);
    }
    Ok(EkfInputs {
        loaded,
        reference,
        region,
        kernels,
        noises,
        occlusions,
    })
}

/// Filter the runs in order with one filter (scored after each run), then, with several
/// runs, each run alone.
fn filter_runs(
    inp: &EkfInputs,
    params: &EkfValid,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Filtered> {
    let spec = inp.reference.spec;
    let total: usize = inp.loaded.iter().map(|l| l.model.poses.len()).sum();
    let mut filter = new_filter(params, spec.rows, spec.cols)?;
    let mut arcs: Vec<EchoArcs> = Vec::new();
    let explained = |f: &dyn RrcsFilter, arcs: &[EchoArcs]| {
        let mut m = EkfMap::from_filter(f, spec.rows, spec.cols, params);
        m.explain(arcs, params.arc_explain);
        m
    };
    let mut done = 0;
    let mut stats = Vec::new();
    let mut fusion = Vec::new();
    let mut alone = Vec::new();
    for (i, l) in inp.loaded.iter().enumerate() {
        let base = done;
        let mut a = EchoArcs::default();
        let st = ekf_run_with_arcs(
            &l.model,
            &l.energy,
            &inp.kernels[i],
            params,
            &inp.noises[i],
            Some(inp.sight(i)),
            filter.as_mut(),
            Some(&mut a),
            &|d, _| progress(base + d, total),
        )?;
        arcs.push(a);
        done += l.model.poses.len();
        stats.push(st);
        let snap = explained(filter.as_ref(), &arcs);
        let m = score_binary(&snap.binary(), &inp.reference, &inp.region);
        fusion.push(FusionRow {
            runs: i + 1,
            metrics: m,
        });
        if inp.loaded.len() == 1 {
            alone.push(m);
        }
    }
    if inp.loaded.len() > 1 {
        for (i, l) in inp.loaded.iter().enumerate() {
            let mut f = new_filter(params, spec.rows, spec.cols)?;
            let mut a = EchoArcs::default();
            ekf_run_with_arcs(
                &l.model,
                &l.energy,
                &inp.kernels[i],
                params,
                &inp.noises[i],
                Some(inp.sight(i)),
                f.as_mut(),
                Some(&mut a),
                &|_, _| {},
            )?;
            let snap = explained(f.as_ref(), &[a]);
            alone.push(score_binary(&snap.binary(), &inp.reference, &inp.region));
        }
    }
    Ok(Filtered {
        map: explained(filter.as_ref(), &arcs),
        stats,
        fusion,
        alone,
    })
}

/// Write `ekf.*`, `ekf_binary.*`, `ekf_mean.*`, `ekf_std.*` and `ekf_rrcs.csv`.
fn write_ekf_files(out: &Path, spec: &GridSpec, map: &EkfMap, params: &EkfValid) -> Result<()> {
    let (probs, bin, eta) = (map.probs(), map.binary(), params.eta());
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let soft = soft_pixels(&probs, &bin);
    output::write_map_files(out, "ekf", spec, &soft, eta, 1.0 - eta)?;
    let bgrey: Vec<u8> = bin
        .iter()
        .map(|&o| if o { GREY_OCCUPIED } else { GREY_FREE })
        .collect();
    output::write_map_files(out, "ekf_binary", spec, &bgrey, 0.5, 0.45)?;
    let mg: Vec<u8> = map.mean.iter().map(|&x| mean_grey(x, params.mu0)).collect();
    output::write_map_files(out, "ekf_mean", spec, &mg, 0.65, 0.196)?;
    let sg: Vec<u8> = map
        .std
        .iter()
        .map(|&s| std_grey(s, params.sigma0))
        .collect();
    output::write_map_files(out, "ekf_std", spec, &sg, 0.65, 0.196)?;
    let mut csv =
        String::from("row,col,x_m,y_m,mean_m,std_m,p,occupied,arcs,arc_poses,arc_share,explained_arcs,explained_poses\n");
    for r in 0..spec.rows {
        for c in 0..spec.cols {
            let i = r * spec.cols + c;
            let ctr = spec.center(r, c);
            csv.push_str(&format!(
                "{r},{c},{:.4},{:.4},{:.6e},{:.6e},{:.6},{},{},{},{:.4e},{},{}\n",
                ctr.x,
                ctr.y,
                map.mean[i],
                map.std[i],
                probs[i],
                bin[i] as u8,
                map.arcs[i],
                map.arc_poses[i],
                map.arc_share[i],
                map.explained_arcs[i],
                map.explained_poses[i]
            ));
        }
    }
    crate::io::write_bytes(&out.join("ekf_rrcs.csv"), csv.as_bytes())
}

/// Peak covariance storage of the filter, bytes.
fn covariance_bytes(params: &EkfValid, spec: &GridSpec) -> usize {
    match params.variant {
        EkfVariant::Dense => spec.len() * spec.len() * 8,
        EkfVariant::Scalable => {
            let t = params.tile;
            spec.rows.div_ceil(t) * spec.cols.div_ceil(t) * t * t * t * t * 8
        }
    }
}

/// The soft map's pixels, consistent with the binary map under the YAML's
/// `occupied_thresh` = η: a reader takes pixel v as p = (255 − v)/255, so every p above
/// 1 − 0.5/255 rounds to v = 0 and reads as occupied. A cell the binary map does not
/// decide occupied (p ≤ η, e.g. capped at η by the arc explanation) is written no darker
/// than v = 1 (p = 254/255 < η: unknown to a trinary reader), never as occupied.
fn soft_pixels(probs: &[f64], occupied: &[bool]) -> Vec<u8> {
    probs
        .iter()
        .zip(occupied)
        .map(|(&p, &o)| if o { soft_grey(p) } else { soft_grey(p).max(1) })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_not_decided_occupied_never_reads_as_occupied() {
        let eta = 0.999;
        // p = η (an unexplained cell's cap), just below η, occupied, free
        let probs = [eta, 0.9985, 0.9999, 0.2];
        let occupied = [false, false, true, false];
        let v = soft_pixels(&probs, &occupied);
        let read = |v: u8| (255.0 - v as f64) / 255.0;
        assert!(read(v[0]) <= eta && read(v[1]) <= eta, "{v:?}");
        assert!(read(v[2]) > eta, "{v:?}");
        assert_eq!(v[3], soft_grey(0.2));
        // without the rule the cap would read as occupied
        assert!(read(soft_grey(eta)) > eta);
    }
}
