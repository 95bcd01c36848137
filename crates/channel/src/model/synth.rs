//! The synth run: the drawn channel seen from every pose, through the array and the
//! energy stage's kernel, with the energy detector's noise, written as an energy table
//! and its truth.
//!
//! Per pose: the seen rays ([`ChannelModel::rays_from`]); per direction: the CIR on the
//! energy stage's oversampled grid (rays add coherently; samples inside the coupling gate
//! zeroed; rays weaker than `cull` × the mean noise-bin energy skipped), the bin energy
//! E_s (mean of |h|² over the bin's L samples), and the detector's draw
//! E = N0/(2N_p)·[χ²(2TW·N_p − 1) + (Z + √(2N_p·E_s/N0))²] (mean N0·TW + E_s, variance
//! (N0²·TW + 2·N0·E_s)/N_p, DESIGN §2). N0 comes from the campaign's `[noise]` floor
//! through the window (as the energy stage's N0) unless [`SynthParams::n0`] gives it (`check`
//! and `calibrate` give the measured table's: [`EnergySimulator::for_table`]), TW from the
//! window; neighbouring bins are drawn independently. The noise streams are keyed by (seed, position, direction), so the
//! bytes do not depend on the thread count.

use super::channel::{ChannelModel, RaySource, SeenRay};
use super::diffuse::DiffuseWalls;
use super::params::{SynthParams, SynthValid};
use super::response::{BandPattern, Kernel, KERNEL_BINS};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, CouplingRemoval, Steering};
use crate::energy::{self, EnergyProcessor};
use crate::error::{Error, Result};
use crate::model::file::ModelConfig;
use crate::params::ParamGuard;
use crate::pattern::ArrayPattern;
use crate::simulate::{truth_rays_frame, write_truth_clusters, TruthCluster, TruthRay};
use crate::table;
use crate::units::{wrap_rad, C0};
use geo::Coord;
use num_complex::Complex64;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Gamma, StandardNormal};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Frequency knots of the band-averaged pattern.
const KNOTS: usize = 33;

/// What `synth` produced.
#[derive(Debug, Clone)]
pub struct SynthReport {
    /// Profiles written (positions × directions).
    pub profiles: usize,
    /// Clusters of the drawn model.
    pub clusters: usize,
    /// Mean cluster rays seen per position (all angles).
    pub rays_per_position: f64,
    /// Diffuse wall points drawn (0 without `[diffuse]`).
    pub diffuse_points: usize,
    /// Mean diffuse points seen per position above the cull.
    pub diffuse_per_position: f64,
    /// The truth folder.
    pub truth_dir: PathBuf,
}

/// Default truth folder for an output table: `<stem>_truth` beside it.
pub fn default_truth_dir(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "synth".into());
    out.with_file_name(format!("{stem}_truth"))
}

/// Run the statistical channel model over a campaign and write the energy table to `out`
/// and the truth beside it. `progress` is called after each position with (done, total).
///
/// ```no_run
/// use pradar_formats::campaign::manifest::Campaign;
/// use pradar_channel::model::file::ModelConfig;
/// use pradar_channel::model::{synth, SynthParams};
/// use pradar_formats::params::ParamGuard;
/// use std::path::Path;
/// # fn main() -> pradar_formats::error::Result<()> {
/// let c = Campaign::load(Path::new("campaign.toml"))?;
/// let model = ModelConfig::load(Path::new("fitted_model.toml"))?;
/// let p = SynthParams::default().seed(7).check()?;
/// let r = synth(&c, &model, Path::new("synth.parquet"), &p, &|_, _| {})?;
/// println!("{} profiles, truth in {}", r.profiles, r.truth_dir.display());
/// # Ok(())
/// # }
/// ```
pub fn synth(
    c: &Campaign,
    model: &ModelConfig,
    out: &Path,
    params: &SynthValid,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SynthReport> {
    let model = model.require_estimable(&Default::default())?;
    let layout = Layout::load(&c.layout_path())?;
    let seed = params.seed.unwrap_or(c.manifest.seed);
    let channel = ChannelModel::draw(&layout, &model, seed)?;
    synth_channel(c, &channel, out, params, progress)
}

/// [`synth`] for an already drawn (or hand-built) channel, in steps: set up the response
/// and detector (`Response::new`), draw the diffuse walls when the channel's model has
/// `[diffuse]` ([`DiffuseWalls::draw`], cells of c/(2B) of the campaign's band), then per
/// pose the seen rays (clusters, then diffuse points), their energy profiles
/// (`Response::position`) and their truth rows; last the truth clusters, the model and
/// the energy table.
pub fn synth_channel(
    c: &Campaign,
    channel: &ChannelModel,
    out: &Path,
    params: &SynthValid,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SynthReport> {
    let m = &c.manifest;
    let layout = Layout::load(&c.layout_path())?;
    let seed = params.seed.unwrap_or(m.seed);
    let resp = Response::new(c, params.cull, params.n0)?;
    let walls = match &channel.config.diffuse {
        Some(d) => Some(DiffuseWalls::draw(&layout, d, m.band.bandwidth_hz(), seed)?),
        None => None,
    };
    // a point weaker than the cull even at the pattern's peak is never in a profile
    let min_amp2 = resp.cull * resp.noise_mean / (resp.g_peak * resp.g_peak);
    let truth_dir = params
        .truth_dir
        .clone()
        .unwrap_or_else(|| default_truth_dir(out));
    std::fs::create_dir_all(&truth_dir).map_err(|e| Error::io(&truth_dir, e))?;
    let rays_path = truth_dir.join("rays.parquet");
    let mut rays_out = table::ParquetStream::create(&rays_path)?;
    let (np, nd, nb) = (m.positions(), resp.angles.len(), resp.proc.nbins());
    let mut energies = vec![0.0; np * nd * nb];
    let mut seen_total = 0usize;
    let mut diffuse_total = 0usize;
    for p in 0..np {
        let pose = m.poses[p];
        let at = Coord {
            x: pose.x_m,
            y: pose.y_m,
        };
        let mut rays = channel.rays_from(&layout, at, pose.heading_deg);
        seen_total += rays.len();
        if let Some(w) = &walls {
            let diffuse = w.rays_from(&layout, at, min_amp2);
            diffuse_total += diffuse.len();
            rays.extend(diffuse);
        }
        if let Some(w) = &channel.config.walls {
            rays.extend(super::walls::geometry_rays(&layout, at, w, seed));
        }
        let profiles = &mut energies[p * nd * nb..(p + 1) * nd * nb];
        resp.position(p, pose.heading_deg.to_radians(), &rays, seed, profiles);
        let rows = resp.truth_rows(&rays);
        rays_out.write(&truth_rays_frame(&rays_path, p, pose.heading_deg, &rows)?)?;
        progress(p + 1, np);
    }
    rays_out.finish(None)?;
    write_truth(&truth_dir, channel)?;
    let noise = energy::noise::NoiseEstimate::of_law(resp.n0, resp.proc.tw(), m.pulses);
    let mut meta = energy::table_metadata(m, &resp.proc, &noise);
    // the model gives every profile, also where the measured campaign has no sweep
    meta.retain(|(k, _)| k != "missing");
    meta.push(("source".into(), "synth".into()));
    meta.push(("seed".into(), seed.to_string()));
    energy::write_table(out, m, nb, &energies, meta)?;
    Ok(SynthReport {
        profiles: np * nd,
        clusters: channel.clusters.len(),
        rays_per_position: seen_total as f64 / np.max(1) as f64,
        diffuse_points: walls.as_ref().map_or(0, |w| w.points.len()),
        diffuse_per_position: diffuse_total as f64 / np.max(1) as f64,
        truth_dir,
    })
}

/// The statistical model's energy matrices in memory, for the calibration's inner loop
/// (`pradar calibrate`): the campaign's response, detector and layout set up once, then
/// per call a model drawn and its energies computed exactly as [`synth`] does (same
/// streams keyed by the seed, same order), without the truth or any file. For a model and
/// seed, [`EnergySimulator::energies`] equals the `energy` column [`synth`] writes with
/// that seed (position-major, then direction, then bin).
pub struct EnergySimulator {
    layout: Layout,
    resp: Response,
    headings_deg: Vec<f64>,
    poses: Vec<Coord<f64>>,
    bandwidth_hz: f64,
}

impl EnergySimulator {
    /// Set up the campaign's response (array pattern, kernel, detector) and layout; `cull`
    /// as [`SynthParams::cull`](super::SynthParams).
    pub fn new(c: &Campaign, params: &SynthValid) -> Result<EnergySimulator> {
        let m = &c.manifest;
        Ok(EnergySimulator {
            layout: Layout::load(&c.layout_path())?,
            resp: Response::new(c, params.cull, params.n0)?,
            headings_deg: m.poses.iter().map(|p| p.heading_deg).collect(),
            poses: m
                .poses
                .iter()
                .map(|p| Coord { x: p.x_m, y: p.y_m })
                .collect(),
            bandwidth_hz: m.band.bandwidth_hz(),
        })
    }

    /// The campaign's layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// (positions, directions, bins) of the energies.
    pub fn shape(&self) -> (usize, usize, usize) {
        (
            self.poses.len(),
            self.resp.angles.len(),
            self.resp.proc.nbins(),
        )
    }

    /// Mean noise-bin energy N0·TW and TW of the detector.
    pub fn noise(&self) -> (f64, f64) {
        (self.resp.noise_mean, self.resp.proc.tw())
    }

    /// Draw `model` (checked, every quantity with a value) with `seed` and return its
    /// energies, position-major (as [`synth`] with that seed).
    pub fn energies(&self, model: &ModelConfig, seed: u64) -> Result<Vec<f64>> {
        self.energies_with(model, seed, &self.layout_rays(model, seed)?)
    }

    /// The rays every pose sees from the layout's own parts for draws of `model` with
    /// `seed`: the diffuse wall points (`[diffuse]`) and the specular walls and vertices
    /// (`[walls]`), in the order [`EnergySimulator::energies`] adds them after the
    /// clusters' rays, those arriving too late for any profile left out. They do not
    /// depend on the model's clusters, so a search over the cluster level (`model::levels`)
    /// makes them once per seed and hands them to [`EnergySimulator::energies_with`].
    pub fn layout_rays(&self, model: &ModelConfig, seed: u64) -> Result<LayoutRays> {
        model.check()?;
        let walls = match &model.diffuse {
            Some(d) => Some(DiffuseWalls::draw(
                &self.layout,
                d,
                self.bandwidth_hz,
                seed,
            )?),
            None => None,
        };
        let resp = &self.resp;
        let min_amp2 = resp.cull * resp.noise_mean / (resp.g_peak * resp.g_peak);
        let last = self.last_arrival();
        let per_pose = (self.poses.iter())
            .map(|&at| {
                let mut rays = Vec::new();
                if let Some(w) = &walls {
                    rays.extend(w.rays_from(&self.layout, at, min_amp2));
                }
                if let Some(w) = &model.walls {
                    rays.extend(super::walls::geometry_rays(&self.layout, at, w, seed));
                }
                rays.retain(|r| r.tau_s <= last);
                rays
            })
            .collect();
        Ok(LayoutRays {
            parts: layout_parts(model),
            seed,
            per_pose,
        })
    }

    /// [`EnergySimulator::energies`] with the layout's rays made beforehand by
    /// [`EnergySimulator::layout_rays`] for a model with the same `[diffuse]` and `[walls]`
    /// and the same `seed` (refused otherwise): the same energies, bit for bit.
    pub fn energies_with(
        &self,
        model: &ModelConfig,
        seed: u64,
        fixed: &LayoutRays,
    ) -> Result<Vec<f64>> {
        let channel = ChannelModel::draw(&self.layout, model, seed)?;
        if fixed.seed != seed
            || fixed.parts != layout_parts(&channel.config)
            || fixed.per_pose.len() != self.poses.len()
        {
            return Err(Error::param(
                "layout_rays",
                "made for another seed, [diffuse] or [walls]",
            ));
        }
        let resp = &self.resp;
        let (np, nd, nb) = self.shape();
        let last = self.last_arrival();
        let mut energies = vec![0.0; np * nd * nb];
        for (p, profiles) in energies.chunks_mut(nd * nb).enumerate() {
            let at = self.poses[p];
            let heading = self.headings_deg[p];
            let mut rays = channel.rays_from(&self.layout, at, heading);
            // a ray arriving after the last sample plus the kernel's reach (and the group
            // delay, clamped to ±1 ns) adds nothing to any profile: dropped before the
            // per-direction loop (the same energies, far fewer pattern look-ups in a
            // large hall); the layout's rays were filtered alike
            rays.retain(|r| r.tau_s <= last);
            rays.extend_from_slice(&fixed.per_pose[p]);
            resp.position(p, heading.to_radians(), &rays, seed, profiles);
        }
        Ok(energies)
    }

    /// The latest delay, s, a ray can have and still reach a profile: the last sample plus
    /// the kernel's reach and 5 ns (the group delay is clamped to ±1 ns).
    fn last_arrival(&self) -> f64 {
        let resp = &self.resp;
        (resp.proc.nbins() * resp.l) as f64 * resp.dt + resp.kernel_reach + 5e-9
    }
}

/// The rays of the layout's own parts per pose for one seed and one `[diffuse]` and
/// `[walls]` ([`EnergySimulator::layout_rays`]).
pub struct LayoutRays {
    /// The model's `[diffuse]` and `[walls]` they were made for ([`layout_parts`]).
    parts: String,
    seed: u64,
    per_pose: Vec<Vec<SeenRay>>,
}

/// A model's `[diffuse]` and `[walls]` as text (NaN compares equal to itself there).
fn layout_parts(model: &ModelConfig) -> String {
    format!("{:?} {:?}", model.diffuse, model.walls)
}

impl EnergySimulator {
    /// The simulator to compare with the measured table `energy` (read from
    /// `energy_path`) of campaign `c`, at ray cull `cull`: the table is first checked
    /// against the campaign (poses, directions, noise) and then refused when its shape is
    /// not the one this simulator draws (other processing settings). Its draws carry the
    /// table's recorded noise level N0 (metadata `n0`), not the manifest's `[noise]` floor:
    /// the model is a model of this campaign's system. What `check` and `calibrate` set up
    /// before drawing.
    pub fn for_table(
        c: &Campaign,
        energy: &crate::energy::EnergyMatrix,
        energy_path: &Path,
        cull: f64,
    ) -> Result<EnergySimulator> {
        crate::energy::matrix::check_campaign(c, energy, energy_path)?;
        energy.meta.check_noise(energy_path)?;
        let sim = EnergySimulator::new(
            c,
            &SynthParams {
                cull,
                n0: Some(energy.meta.n0),
                ..Default::default()
            }
            .check()?,
        )?;
        let (np, nd, nb) = sim.shape();
        if (np, nd, nb) == (energy.positions, energy.directions(), energy.bins) {
            return Ok(sim);
        }
        Err(Error::input(
            energy_path,
            format!(
                "{} x {} x {} bins, but campaign {} gives {np} x {nd} x {nb} (other processing settings?)",
                energy.positions,
                energy.directions(),
                energy.bins,
                c.path.display()
            ),
        ))
    }

    /// Pose `p`'s position and heading (deg).
    pub fn pose(&self, p: usize) -> (Coord<f64>, f64) {
        (self.poses[p], self.headings_deg[p])
    }

    /// The expected noise-free signal energy E_s of every (direction, bin) of pose `p`
    /// (directions × bins) from `rays` added in power (the mean over their phases: exact
    /// for one ray, the mean of a Rayleigh sum for many), through the same pattern, kernel
    /// and gate as [`EnergySimulator::energies`]; no cull.
    pub fn expected_profiles(&self, p: usize, rays: &[SeenRay]) -> Vec<f64> {
        let nb = self.resp.proc.nbins();
        let mut out = vec![0.0; self.resp.angles.len() * nb];
        out.par_chunks_mut(nb)
            .enumerate()
            .for_each(|(d, prof)| prof.copy_from_slice(&self.expected_profile(p, d, rays)));
        out
    }

    /// [`EnergySimulator::expected_profiles`] of direction `d` alone (bins).
    pub fn expected_profile(&self, p: usize, d: usize, rays: &[SeenRay]) -> Vec<f64> {
        let resp = &self.resp;
        let heading = self.headings_deg[p].to_radians();
        let h = resp.power(d, heading, rays);
        (0..resp.proc.nbins())
            .map(|b| h[b * resp.l..(b + 1) * resp.l].iter().sum::<f64>() / resp.l as f64)
            .collect()
    }
}

/// The truth clusters (`clusters.csv`) and the model as read (`model.toml`).
fn write_truth(truth_dir: &Path, channel: &ChannelModel) -> Result<()> {
    let truth_clusters: Vec<TruthCluster> = channel
        .clusters
        .iter()
        .map(|c| TruthCluster {
            centre: c.centre,
            arc_m: c.arc_m,
            offset_m: c.offset_m,
            rays: c.rays.len(),
            sigma_m2: c.sigma_m2,
        })
        .collect();
    write_truth_clusters(truth_dir, &truth_clusters)?;
    channel.config.save(&truth_dir.join("model.toml"))
}

/// Everything a profile needs beyond the rays: the campaign's scan, array response, delay
/// grid, kernel and detector.
struct Response {
    proc: EnergyProcessor,
    kernel: Kernel,
    steering: Steering,
    /// Scan directions, degrees.
    angles: Vec<f64>,
    /// One band pattern (mechanical steering) or one per direction (electronic).
    bands: Vec<BandPattern>,
    /// Oversampling L and the sample offset of bin 0, (L − 1)/2.
    l: usize,
    half: i64,
    /// Sample step T_b/L, s.
    dt: f64,
    /// Centre frequency, Hz.
    fc: f64,
    /// Coupling gate, s (0 without one).
    gate: f64,
    /// Noise per sample and the mean noise-bin energy N0·TW.
    n0: f64,
    noise_mean: f64,
    /// Pulses N_p and the χ² law of 2TW·N_p − 1 degrees of freedom.
    pulses: f64,
    chi: Gamma<f64>,
    /// The kernel's half-width, s.
    kernel_reach: f64,
    /// Broadside gain and wavelength at the centre frequency (truth powers).
    g0: f64,
    lc: f64,
    cull: f64,
    /// Peak of ḡ over every band pattern (the diffuse points' pre-cull).
    g_peak: f64,
}

impl Response {
    /// The campaign's response; `n0` overrides the noise level of its `[noise]` floor.
    fn new(c: &Campaign, cull: f64, n0: Option<f64>) -> Result<Response> {
        let m = &c.manifest;
        let proc = EnergyProcessor::new(m.band, m.processing)
            .map_err(|e| Error::input(&c.path, e.to_string()))?;
        let kernel = Kernel::new(&proc);
        let pattern = ArrayPattern::new(m.array, m.band.center_hz())?;
        let angles = m.directions.angles_deg();
        let bands: Vec<BandPattern> = match m.array.steering {
            Steering::Mechanical => {
                let t = &pattern.tables(&[0.0], &m.band, KNOTS)[0];
                vec![BandPattern::new(t, m.processing.window)]
            }
            Steering::Electronic => pattern
                .tables(&angles, &m.band, KNOTS)
                .iter()
                .map(|t| BandPattern::new(t, m.processing.window))
                .collect(),
        };
        let l = m.processing.oversample;
        let tb = proc.bin_width_ns() * 1e-9;
        let fc = m.band.center_hz();
        let gate = if m.processing.coupling == CouplingRemoval::Gate {
            m.processing.gate_ns * 1e-9
        } else {
            0.0
        };
        let n0 = n0.unwrap_or_else(|| proc.noise_per_sample(m.noise.s21_variance()) / proc.tw());
        let noise_mean = n0 * proc.tw();
        let pulses = m.pulses as f64;
        let dof = 2.0 * proc.tw() * pulses - 1.0;
        let chi = Gamma::new(dof / 2.0, 2.0).map_err(|e| Error::input(&c.path, e.to_string()))?;
        let g_peak = bands.iter().map(BandPattern::peak).fold(0.0, f64::max);
        Ok(Response {
            kernel,
            steering: m.array.steering,
            angles,
            bands,
            l,
            half: (l - 1) as i64 / 2,
            dt: tb / l as f64,
            fc,
            gate,
            n0,
            noise_mean,
            pulses,
            chi,
            kernel_reach: KERNEL_BINS as f64 * tb,
            g0: pattern.gain(0.0, 0.0, fc),
            g_peak,
            lc: C0 / fc,
            cull,
            proc,
        })
    }

    /// The energy profiles of position `p` (heading in rad), one per direction, into
    /// `out` (directions × bins), in parallel over directions.
    fn position(&self, p: usize, heading: f64, rays: &[SeenRay], seed: u64, out: &mut [f64]) {
        out.par_chunks_mut(self.proc.nbins())
            .enumerate()
            .for_each(|(d, prof)| {
                let h = self.cir(d, heading, rays);
                let mut rng = ChaCha8Rng::seed_from_u64(noise_seed(seed, p, d));
                self.detect(&h, prof, &mut rng);
            });
    }

    /// The rays direction `d` sees through the pattern with a received |amplitude|²
    /// a2 = g²|A|² of at least `min_a2`: (ray, a2, delay with the pattern's group delay).
    fn seen<'a>(
        &'a self,
        d: usize,
        heading: f64,
        rays: &'a [SeenRay],
        min_a2: f64,
    ) -> impl Iterator<Item = (&'a SeenRay, f64, f64)> + 'a {
        let bp = &self.bands[if self.bands.len() == 1 { 0 } else { d }];
        let theta_s = self.angles[d].to_radians();
        rays.iter().filter_map(move |r| {
            let th = match self.steering {
                Steering::Mechanical => r.theta - heading - theta_s,
                Steering::Electronic => r.theta - heading,
            };
            let (g, tau_g) = bp.at(wrap_rad(th))?;
            let a2 = g * g * r.amp2;
            (a2 >= min_a2).then_some((r, a2, r.tau_s + tau_g))
        })
    }

    /// The samples n·dt (index from bin 0, sample −half; and t) within `reach` of `tau`,
    /// outside the coupling gate.
    fn samples(&self, tau: f64, reach: f64) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (l, half, dt) = (self.l, self.half, self.dt);
        let nb = self.proc.nbins();
        let lo = ((tau - reach) / dt).ceil().max(-(half as f64)) as i64;
        let hi = ((tau + reach) / dt).floor() as i64;
        let hi = hi.min((nb * l) as i64 - half - 1);
        (lo..=hi).filter_map(move |n| {
            let t = n as f64 * dt;
            (t.abs() >= self.gate).then_some(((n + half) as usize, t))
        })
    }

    /// The CIR h(t_n) of direction `d` on the oversampled grid (from bin 0, sample −half).
    fn cir(&self, d: usize, heading: f64, rays: &[SeenRay]) -> Vec<Complex64> {
        let mut h = vec![Complex64::new(0.0, 0.0); self.proc.nbins() * self.l];
        for (r, a2, tau) in self.seen(d, heading, rays, self.cull * self.noise_mean) {
            let (phase, reach) = match r.source {
                RaySource::Cluster(_) => (-2.0 * PI * (self.fc * tau).fract(), self.kernel_reach),
                RaySource::Specular(_) | RaySource::Vertex(_) => (
                    r.phase - 2.0 * PI * (self.fc * tau).fract(),
                    self.kernel_reach,
                ),
                // a diffuse point: its own phase, and its kernel only where it matters
                RaySource::Wall(_) => (
                    r.phase - 2.0 * PI * (self.fc * tau).fract(),
                    self.kernel.reach_s(self.cull * self.noise_mean / a2),
                ),
            };
            let a = Complex64::from_polar(a2.sqrt(), phase);
            for (i, t) in self.samples(tau, reach) {
                h[i] += a * self.kernel.at(t - tau);
            }
        }
        h
    }

    /// The CIR's expected power |h(t_n)|² of direction `d` with the rays added in power
    /// (grid as [`Response::cir`], no cull).
    fn power(&self, d: usize, heading: f64, rays: &[SeenRay]) -> Vec<f64> {
        let mut h = vec![0.0; self.proc.nbins() * self.l];
        for (_, a2, tau) in self.seen(d, heading, rays, f64::MIN_POSITIVE) {
            for (i, t) in self.samples(tau, self.kernel_reach) {
                h[i] += a2 * self.kernel.at(t - tau).powi(2);
            }
        }
        h
    }

    /// Each bin's detector energy: E_s the mean |h|² over its L samples, then the scaled
    /// non-central χ² draw.
    fn detect(&self, h: &[Complex64], prof: &mut [f64], rng: &mut ChaCha8Rng) {
        let (l, pulses, n0) = (self.l, self.pulses, self.n0);
        for (b, e) in prof.iter_mut().enumerate() {
            let es = h[b * l..(b + 1) * l]
                .iter()
                .map(|v| v.norm_sqr())
                .sum::<f64>()
                / l as f64;
            let z: f64 = StandardNormal.sample(rng);
            let x = self.chi.sample(rng);
            let nc = (2.0 * pulses * es / n0).sqrt();
            *e = n0 / (2.0 * pulses) * (x + (z + nc).powi(2));
        }
    }

    /// The truth rows of the seen rays (power through the broadside gain): cluster rays
    /// as `clutter` of their cluster, diffuse points through [`diffuse_truth_row`].
    fn truth_rows(&self, rays: &[SeenRay]) -> Vec<TruthRay> {
        let (g0, lc) = (self.g0, self.lc);
        rays.iter()
            .map(|r| {
                let power_db = 10.0 * (g0 * g0 * lc * lc * r.amp2).log10();
                let (delay_ns, angle) = (r.tau_s * 1e9, r.theta.to_degrees());
                match r.source {
                    RaySource::Cluster(l) => {
                        TruthRay::model_cluster(l, r.pos, delay_ns, angle, power_db)
                    }
                    RaySource::Wall(w) => {
                        TruthRay::diffuse_wall(w, r.pos, delay_ns, angle, power_db)
                    }
                    RaySource::Specular(w) => {
                        TruthRay::specular_wall(w, r.pos, delay_ns, angle, power_db)
                    }
                    RaySource::Vertex(i) => TruthRay::vertex(i, r.pos, delay_ns, angle, power_db),
                }
            })
            .collect()
    }
}

fn noise_seed(seed: u64, p: usize, d: usize) -> u64 {
    let mut x = seed ^ 0x9e37_79b9_7f4a_7c15;
    for v in [p as u64, d as u64, 0x73796e] {
        x = (x ^ v).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        x ^= x >> 31;
    }
    x
}
