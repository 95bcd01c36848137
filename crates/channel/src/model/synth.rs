//! The synth run: the drawn channel seen from every pose, through the array and the
//! receiver the measurement has (the energy stage's window and zero-padded IFFT, with the
//! receiver's white noise), written as an energy table and its truth.
//!
//! Per pose: the seen rays ([`ChannelModel::rays_from`]; rays weaker than `cull` × the mean
//! noise-bin energy after the pattern skipped); per direction:
//! * the rays' CIR on the energy stage's oversampled grid t_n = n·T_b/L, added coherently
//!   through the periodic kernel ([`response`](super::response) docs):
//!   g(t_n) = Σ_rays a·e^{−j2πf_cτ} Σ_k ε^k·r̃(t_n − τ − kT), T = 1/Δf, ε = (−1)^{K−1},
//!   every image k that reaches the span, so an echo later than the span (a far wall of a
//!   hall) lands at τ mod T at the level its path loss gives, as the sweep folds it;
//! * per pulse, the receiver noise: complex white Gaussian n_k of variance σ² per frequency
//!   point ([`WhiteNoise`], the draw `simulate` makes), through the same window and
//!   zero-padded IFFT, with the rays' CIR added in the delay domain:
//!   h_n = Σ_k w_k n_k e^{j2πkn/N}/Σw + e^{jπn/L}·g(t_n), so the noise is coloured as the
//!   measurement's (neighbouring bins correlated through the window) and adds coherently to
//!   the echoes; the coupling gate zeroes h_n at |t_n| < gate (noise included, as in
//!   `energy`), `mean` coupling removal subtracts the mean over the directions of the rays'
//!   CIRs and of each pulse's noise spectra;
//! * bin b's energy is the mean of |h_n|² over its L samples n = bL − (L−1)/2 … bL + (L−1)/2,
//!   averaged over the N_p pulses: [`EnergyProcessor::receive_into`], the code `energy`
//!   runs on a sweep.
//!
//! A noise-only bin then has mean N0·TW, N0 = σ²·Σw²/(Σw)²/TW (variance N0²·TW/N_p, the
//! law of `energy::noise`): σ² is the campaign's `[noise]` floor (as `simulate` draws it)
//! unless [`SynthParams::n0`] gives N0 (`check` and `calibrate` give the measured table's:
//! [`EnergySimulator::for_table`]), then σ² = N0·TW·(Σw)²/Σw² ([`WhiteNoise::for_n0`];
//! over 1 − 1/D under `mean` removal over D directions). The noise streams are keyed by
//! (seed, position, direction), the pulses drawn in turn from one stream, so the bytes do
//! not depend on the thread count. The truth lists every seen ray at its true delay.

use super::channel::{ChannelModel, RaySource, SeenRay};
use super::diffuse::DiffuseWalls;
use super::params::{SynthParams, SynthValid};
use super::response::{BandPattern, Kernel};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, CouplingRemoval, Steering};
use crate::energy::{self, EnergyProcessor, WhiteNoise};
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
    let min_amp2 = resp.min_amp2;
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
    /// clusters' rays, those below the cull even at the pattern's peak left out (they are
    /// in no profile; a ray at any delay reaches the span through its images). They do not
    /// depend on the model's clusters: a caller drawing one seed at several cluster levels
    /// makes them once and hands them to [`EnergySimulator::energies_with`] or
    /// [`EnergySimulator::energy_quadratics`] (`model::levels`).
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
        let min_amp2 = resp.min_amp2;
        let per_pose = (self.poses.iter())
            .map(|&at| {
                let mut rays = Vec::new();
                if let Some(w) = &walls {
                    rays.extend(w.rays_from(&self.layout, at, min_amp2));
                }
                if let Some(w) = &model.walls {
                    rays.extend(super::walls::geometry_rays(&self.layout, at, w, seed));
                }
                rays.retain(|r| r.amp2 >= min_amp2);
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
        let channel = self.draw_for(model, seed, fixed)?;
        let resp = &self.resp;
        let (np, nd, nb) = self.shape();
        let mut energies = vec![0.0; np * nd * nb];
        for (p, profiles) in energies.chunks_mut(nd * nb).enumerate() {
            let at = self.poses[p];
            let heading = self.headings_deg[p];
            let mut rays = channel.rays_from(&self.layout, at, heading);
            rays.extend_from_slice(&fixed.per_pose[p]);
            resp.position(p, heading.to_radians(), &rays, seed, profiles);
        }
        Ok(energies)
    }
}

impl EnergySimulator {
    /// The clusters of `model` drawn with `seed`, once `fixed` is checked to be the
    /// layout's rays of the same seed, `[diffuse]` and `[walls]` (refused otherwise).
    fn draw_for(&self, model: &ModelConfig, seed: u64, fixed: &LayoutRays) -> Result<ChannelModel> {
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
        Ok(channel)
    }

    /// The energies of draws of `model` with `seed` as quadratics in the clusters'
    /// amplitude: with σ_ref the model's `cluster_rrcs` and σ = s²·σ_ref, the energy of
    /// (position, direction, bin) is A + 2B·s + C·s² for `[A, B, C]` (position-major, as
    /// [`EnergySimulator::energies`]), since the clusters' rays, the layout's and the noise
    /// add in the CIR and the clusters' amplitudes scale with √σ. Every stage is
    /// [`EnergySimulator::energies_with`]'s (the same noise streams, mean removal and
    /// gate); the clusters' rays are culled at σ_ref, so for σ < σ_ref these are its
    /// energies at σ plus the cluster rays its cull would leave out there (each below
    /// `cull` of the mean noise-bin energy). `fixed` as there. It lets `model::levels`
    /// read the draws' signal bins at every σ from one pass.
    pub fn energy_quadratics(
        &self,
        model: &ModelConfig,
        seed: u64,
        fixed: &LayoutRays,
    ) -> Result<Vec<[f64; 3]>> {
        let channel = self.draw_for(model, seed, fixed)?;
        let (np, nd, nb) = self.shape();
        let mut out = vec![[0.0; 3]; np * nd * nb];
        for (p, profiles) in out.chunks_mut(nd * nb).enumerate() {
            let heading = self.headings_deg[p];
            let clusters = channel.rays_from(&self.layout, self.poses[p], heading);
            let h = heading.to_radians();
            (self.resp).position_quadratic(p, h, &clusters, &fixed.per_pose[p], seed, profiles);
        }
        Ok(out)
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
/// grid, kernel and receiver.
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
    /// `mean` coupling removal: the mean over the directions subtracted, as `energy` does.
    mean_removal: bool,
    /// The noise level N0 the noise-only bins read and their mean N0·TW.
    n0: f64,
    noise_mean: f64,
    /// The receiver's white noise per frequency point and the pulses N_p.
    noise: WhiteNoise,
    pulses: usize,
    /// The kernel's half-width, s.
    kernel_reach: f64,
    /// Broadside gain and wavelength at the centre frequency (truth powers).
    g0: f64,
    lc: f64,
    cull: f64,
    /// |A|² below which a ray is under the cull even at the pattern's peak (ḡ's largest
    /// over every band pattern): such rays and diffuse points are in no profile.
    min_amp2: f64,
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
        // `mean` removal takes the mean over the directions away from each one's noise as
        // well: what remains is (1 − 1/D) of it
        let mean_removal = m.processing.coupling == CouplingRemoval::Mean;
        let kept = if mean_removal && angles.len() > 1 {
            1.0 - 1.0 / angles.len() as f64
        } else {
            1.0
        };
        let (noise, n0) = match n0 {
            Some(n0) => (WhiteNoise::for_n0(&proc, n0 / kept), n0),
            None => {
                let noise = WhiteNoise::new(m.noise.s21_variance());
                let n0 = proc.noise_per_sample(noise.variance()) * kept / proc.tw();
                (noise, n0)
            }
        };
        let noise_mean = n0 * proc.tw();
        let g_peak = bands.iter().map(BandPattern::peak).fold(0.0, f64::max);
        Ok(Response {
            steering: m.array.steering,
            angles,
            bands,
            l,
            half: (l - 1) as i64 / 2,
            dt: tb / l as f64,
            fc,
            gate,
            mean_removal,
            n0,
            noise_mean,
            noise,
            pulses: m.pulses,
            kernel_reach: kernel.half_width_s(),
            kernel,
            g0: pattern.gain(0.0, 0.0, fc),
            min_amp2: cull * noise_mean / (g_peak * g_peak),
            lc: C0 / fc,
            cull,
            proc,
        })
    }

    /// The energy profiles of position `p` (heading in rad), one per direction, into
    /// `out` (directions × bins), in parallel over directions: per direction the rays'
    /// CIR ([`Response::cir`]) and the receiver noise of each pulse
    /// ([`Response::noise_spectra`]), the means over the directions taken away under
    /// `mean` coupling removal, then each pulse through the energy stage
    /// ([`EnergyProcessor::receive_into`]) and the mean over the pulses.
    fn position(&self, p: usize, heading: f64, rays: &[SeenRay], seed: u64, out: &mut [f64]) {
        let nb = self.proc.nbins();
        // a ray below the cull even at the pattern's peak is in no profile
        let rays: Vec<SeenRay> = (rays.iter())
            .filter(|r| r.amp2 >= self.min_amp2)
            .copied()
            .collect();
        let mut parts: Vec<(Vec<Complex64>, Vec<Complex64>)> = (0..self.angles.len())
            .into_par_iter()
            .map(|d| (self.cir(d, heading, &rays), self.noise_spectra(seed, p, d)))
            .collect();
        if self.mean_removal {
            subtract_mean(parts.iter_mut().map(|(g, _)| g));
            subtract_mean(parts.iter_mut().map(|(_, n)| n));
        }
        let scale = 1.0 / self.pulses as f64;
        let k = self.proc.band().points;
        out.par_chunks_mut(nb).zip(parts.par_iter()).for_each_init(
            || self.proc.scratch(),
            |scratch, (prof, (g, spectra))| {
                prof.fill(0.0);
                for spectrum in spectra.chunks(k) {
                    self.proc
                        .receive_into(spectrum, -self.half, g, scratch, scale, prof);
                }
            },
        );
    }

    /// [`Response::position`] as quadratics in a scale s of the `clusters`' amplitudes
    /// ([`EnergySimulator::energy_quadratics`]): per direction the layout's CIR and the
    /// receiver noise make u, the clusters' CIR v, and each bin's energy at s is that of
    /// u + s·v ([`EnergyProcessor::bin_quadratics_into`]), averaged over the pulses.
    fn position_quadratic(
        &self,
        p: usize,
        heading: f64,
        clusters: &[SeenRay],
        layout: &[SeenRay],
        seed: u64,
        out: &mut [[f64; 3]],
    ) {
        let nb = self.proc.nbins();
        let kept = |rays: &[SeenRay]| -> Vec<SeenRay> {
            (rays.iter())
                .filter(|r| r.amp2 >= self.min_amp2)
                .copied()
                .collect()
        };
        let (clusters, layout) = (kept(clusters), kept(layout));
        let mut parts: Vec<(Vec<Complex64>, Vec<Complex64>, Vec<Complex64>)> =
            (0..self.angles.len())
                .into_par_iter()
                .map(|d| {
                    (
                        self.cir(d, heading, &layout),
                        self.cir(d, heading, &clusters),
                        self.noise_spectra(seed, p, d),
                    )
                })
                .collect();
        if self.mean_removal {
            subtract_mean(parts.iter_mut().map(|(g, _, _)| g));
            subtract_mean(parts.iter_mut().map(|(_, c, _)| c));
            subtract_mean(parts.iter_mut().map(|(_, _, n)| n));
        }
        let scale = 1.0 / self.pulses as f64;
        let k = self.proc.band().points;
        out.par_chunks_mut(nb).zip(parts.par_iter()).for_each_init(
            || (self.proc.scratch(), self.proc.scratch().0),
            |(scratch, v), (prof, (g, c, spectra))| {
                prof.fill([0.0; 3]);
                v.fill(Complex64::new(0.0, 0.0));
                self.proc.add_baseband(v, -self.half, c);
                self.proc.gate(v);
                for spectrum in spectra.chunks(k) {
                    self.proc.cir_into(spectrum, scratch);
                    self.proc.add_baseband(&mut scratch.0, -self.half, g);
                    self.proc.gate(&mut scratch.0);
                    self.proc.bin_quadratics_into(&scratch.0, v, scale, prof);
                }
            },
        );
    }

    /// The receiver noise of (position `p`, direction `d`): one spectrum of white noise per
    /// pulse (pulses × points), from the stream keyed by (seed, p, d), pulse after pulse.
    fn noise_spectra(&self, seed: u64, p: usize, d: usize) -> Vec<Complex64> {
        let mut rng = ChaCha8Rng::seed_from_u64(noise_seed(seed, p, d));
        let mut n = vec![Complex64::new(0.0, 0.0); self.pulses * self.proc.band().points];
        self.noise.draw(&mut n, &mut rng);
        n
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

    /// The first and last sample of the profiles' grid, s: bin 0's first (−half·dt) and the
    /// last bin's last.
    fn span(&self) -> (f64, f64) {
        let nb = self.proc.nbins() as i64;
        (
            -self.half as f64 * self.dt,
            (nb * self.l as i64 - self.half - 1) as f64 * self.dt,
        )
    }

    /// The samples n·dt (index from bin 0, sample −half; and t) within `reach` of `tau`,
    /// outside the coupling gate.
    fn samples(&self, tau: f64, reach: f64) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (half, dt) = (self.half, self.dt);
        let (lo, hi) = self.sample_range(tau, reach);
        (lo..=hi).filter_map(move |n| {
            let t = n as f64 * dt;
            (t.abs() >= self.gate).then_some(((n + half) as usize, t))
        })
    }

    /// The sample indices n (from sample −half of bin 0) of [`Response::samples`], gate
    /// not applied: n·dt within `reach` of `tau` and on the grid (empty when lo > hi).
    fn sample_range(&self, tau: f64, reach: f64) -> (i64, i64) {
        let (l, half, dt) = (self.l, self.half, self.dt);
        let nb = self.proc.nbins();
        let lo = ((tau - reach) / dt).ceil().max(-(half as f64)) as i64;
        let hi = ((tau + reach) / dt).floor() as i64;
        (lo, hi.min((nb * l) as i64 - half - 1))
    }

    /// The baseband CIR g(t_n) = Σ a·e^{−j2πf_cτ}·r(t_n − τ) of direction `d` on the
    /// oversampled grid (from bin 0, sample −half), every ray through its images
    /// τ + kT ([`Kernel::images`]) with their signs.
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
            self.add_ray(&mut h, Complex64::from_polar(a2.sqrt(), phase), tau, reach);
        }
        h
    }

    /// Add to the baseband CIR `h` ([`Response::cir`]) an echo of complex amplitude `a`
    /// (carrier phase included) at delay `tau`: a·ε^k·r̃(t_n − τ − kT) on the samples within
    /// `reach` of each image τ + kT that reaches the span.
    fn add_ray(&self, h: &mut [Complex64], a: Complex64, tau: f64, reach: f64) {
        let (lo, hi) = self.span();
        for (tm, sign) in self.kernel.images(tau, lo, hi, reach) {
            let am = a * sign;
            let (n_lo, n_hi) = self.sample_range(tm, reach);
            self.kernel
                .accumulate(h, am, tm, n_lo, n_hi, self.dt, self.half, self.gate);
        }
    }

    /// The CIR's expected power |h(t_n)|² of direction `d` with the rays added in power
    /// (grid and images as [`Response::cir`], no cull).
    fn power(&self, d: usize, heading: f64, rays: &[SeenRay]) -> Vec<f64> {
        let mut h = vec![0.0; self.proc.nbins() * self.l];
        let (lo, hi) = self.span();
        for (_, a2, tau) in self.seen(d, heading, rays, f64::MIN_POSITIVE) {
            for (tm, _) in self.kernel.images(tau, lo, hi, self.kernel_reach) {
                for (i, t) in self.samples(tm, self.kernel_reach) {
                    h[i] += a2 * self.kernel.at(t - tm).powi(2);
                }
            }
        }
        h
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

/// Subtract from each of `rows` (equal lengths) their mean: the `mean` coupling removal,
/// which is linear, so on the CIRs as on the spectra.
fn subtract_mean<'a>(rows: impl Iterator<Item = &'a mut Vec<Complex64>>) {
    let mut rows: Vec<&mut Vec<Complex64>> = rows.collect();
    let Some(n) = rows.first().map(|r| r.len()) else {
        return;
    };
    let mut mean = vec![Complex64::new(0.0, 0.0); n];
    for r in rows.iter() {
        for (m, v) in mean.iter_mut().zip(r.iter()) {
            *m += v;
        }
    }
    let inv = 1.0 / rows.len() as f64;
    for r in rows.iter_mut() {
        for (v, m) in r.iter_mut().zip(&mean) {
            *v -= m * inv;
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn campaign(points: usize, coupling: CouplingRemoval) -> Campaign {
        let p = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/tests/point_target.toml"
        );
        let mut c = Campaign::load(Path::new(p)).unwrap();
        c.set_elements(16).unwrap();
        c.manifest.band.points = points;
        c.manifest.processing.coupling = coupling;
        c.manifest.processing.max_delay_ns = 60.0;
        c
    }

    /// Echoes in the span and one, 2.4 and 3 periods later, interfering: synth's CIR (the
    /// folded kernel) through the receiver without noise gives the energies the energy
    /// stage computes from their exact spectrum Σ a·e^{−j2πfτ}, for an odd and an even
    /// number of points (where the images alternate in sign).
    #[test]
    fn folded_rays_give_the_energy_stage_s_energies_of_their_spectrum() {
        for points in [401usize, 400] {
            for coupling in [CouplingRemoval::Gate, CouplingRemoval::None] {
                let c = campaign(points, coupling);
                let resp = Response::new(&c, 1e-3, None).unwrap();
                let proc = &resp.proc;
                let band = *proc.band();
                let t_per = 1.0 / band.step_hz();
                let echoes = [
                    (Complex64::from_polar(1.0, 0.3), 20.0e-9),
                    (Complex64::from_polar(0.8, 1.0), 20.27e-9 + t_per),
                    (Complex64::from_polar(0.5, -2.0), 2.4 * t_per),
                    (Complex64::from_polar(0.3, 2.5), 13.1e-9 + 3.0 * t_per),
                    (Complex64::from_polar(0.4, 0.0), 1.0e-9 + t_per),
                ];
                let spectrum: Vec<Complex64> = (0..band.points)
                    .map(|k| {
                        let f = band.freq(k);
                        (echoes.iter())
                            .map(|(a, tau)| {
                                a * Complex64::from_polar(1.0, -2.0 * PI * (f * tau).fract())
                            })
                            .sum()
                    })
                    .collect();
                let nb = proc.nbins();
                let mut want = vec![0.0; proc.nbins_full()];
                proc.profile_into(&spectrum, &mut proc.scratch(), 1.0, &mut want);
                let mut g = vec![Complex64::new(0.0, 0.0); nb * resp.l];
                for (a, tau) in echoes {
                    let carrier = Complex64::from_polar(1.0, -2.0 * PI * (resp.fc * tau).fract());
                    resp.add_ray(&mut g, a * carrier, tau, resp.kernel_reach);
                }
                let zero = vec![Complex64::new(0.0, 0.0); band.points];
                let mut got = vec![0.0; nb];
                proc.receive_into(&zero, -resp.half, &g, &mut proc.scratch(), 1.0, &mut got);
                let peak = want[..nb].iter().copied().fold(0.0, f64::max);
                let worst = (0..nb)
                    .map(|b| (got[b] - want[b]).abs())
                    .fold(0.0, f64::max);
                eprintln!(
                    "K = {points} {coupling:?}: worst |synth − energy| = {:.2e} of the peak",
                    worst / peak
                );
                assert!(
                    worst < 5e-4 * peak,
                    "K = {points} {coupling:?}: {worst:e} vs peak {peak:e}"
                );
                // and the folded echoes are there: the one at 2.4 T lands at 0.4 T
                let b = (0.4 * t_per * 1e9 / proc.bin_width_ns()).round() as usize;
                assert!(
                    got[b] > 0.1 * peak,
                    "K = {points}: bin {b} holds {:e}",
                    got[b]
                );
            }
        }
    }

    /// The noise-only bins read the N0 asked for (N0·TW on average) with and without `mean`
    /// coupling removal, and the profiles' bytes do not depend on the thread count.
    #[test]
    fn receiver_noise_reads_the_given_n0() {
        for coupling in [CouplingRemoval::Gate, CouplingRemoval::Mean] {
            let mut c = campaign(401, coupling);
            c.manifest.pulses = 2;
            let n0 = 2.5e-13;
            let resp = Response::new(&c, 1e-3, Some(n0)).unwrap();
            let (nd, nb) = (resp.angles.len(), resp.proc.nbins());
            let first =
                ((c.manifest.processing.gate_ns + 2.0) / resp.proc.bin_width_ns()).ceil() as usize;
            let (mut sum, mut count) = (0.0, 0usize);
            for p in 0..20 {
                let mut out = vec![0.0; nd * nb];
                resp.position(p, 0.0, &[], 7, &mut out);
                for prof in out.chunks(nb) {
                    sum += prof[first..].iter().sum::<f64>();
                    count += nb - first;
                }
            }
            let ratio = sum / count as f64 / (n0 * resp.proc.tw());
            eprintln!("{coupling:?}: noise bins' mean {ratio:.4} × N0·TW");
            assert!((ratio - 1.0).abs() < 0.01, "{coupling:?}: {ratio}");
            assert_eq!(resp.noise_mean, n0 * resp.proc.tw());
        }
        let c = campaign(401, CouplingRemoval::Gate);
        let resp = Response::new(&c, 1e-3, None).unwrap();
        let n = resp.angles.len() * resp.proc.nbins();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut out = vec![0.0; n];
            pool.install(|| resp.position(3, 0.1, &[], 9, &mut out));
            out
        };
        assert_eq!(run(1), run(3));
    }

    /// The energies as quadratics in the clusters' amplitude
    /// ([`Response::position_quadratic`]) are the energies: at any cluster scale without
    /// noise (nothing culled), and with the receiver's noise (two pulses, both coupling
    /// removals) at the scale they were made for, to rounding.
    #[test]
    fn quadratics_in_the_clusters_amplitude_are_the_energies() {
        let ray = |source, tau_ns: f64, deg: f64, amp2: f64, phase| SeenRay {
            source,
            tau_s: tau_ns * 1e-9,
            theta: deg.to_radians(),
            amp2,
            pos: Coord { x: 0.0, y: 0.0 },
            phase,
        };
        let clusters = [
            ray(RaySource::Cluster(0), 14.2, 3.0, 3e-9, 0.0),
            ray(RaySource::Cluster(0), 15.1, -8.0, 1e-9, 0.0),
            ray(RaySource::Cluster(1), 33.7, 40.0, 4e-10, 0.0),
            ray(RaySource::Cluster(2), 170.0, -20.0, 2e-9, 0.0),
        ];
        let layout = [
            ray(RaySource::Specular(0), 14.6, 0.0, 5e-9, 0.4),
            ray(RaySource::Wall(1), 20.3, 12.0, 8e-10, 2.1),
            ray(RaySource::Vertex(2), 41.0, -33.0, 2e-10, -1.0),
        ];
        let scaled = |f: f64| -> Vec<SeenRay> {
            (clusters.iter().map(|r| SeenRay {
                amp2: r.amp2 * f,
                ..*r
            }))
            .chain(layout.iter().copied())
            .collect()
        };
        let worst = |resp: &Response, f: f64| -> f64 {
            let n = resp.angles.len() * resp.proc.nbins();
            let (mut e, mut q) = (vec![0.0; n], vec![[0.0; 3]; n]);
            resp.position(2, 0.2, &scaled(f), 5, &mut e);
            resp.position_quadratic(2, 0.2, &clusters, &layout, 5, &mut q);
            let peak = e.iter().copied().fold(0.0, f64::max);
            assert!(peak > 0.0);
            let s = f.sqrt();
            (e.iter().zip(&q))
                .map(|(e, [a, b, c])| (e - (a + 2.0 * b * s + c * s * s)).abs() / peak)
                .fold(0.0, f64::max)
        };
        for coupling in [CouplingRemoval::Gate, CouplingRemoval::Mean] {
            let mut c = campaign(401, coupling);
            c.manifest.pulses = 2;
            // no noise to speak of: nothing is culled at any scale
            let quiet = Response::new(&c, 1e-3, Some(1e-40)).unwrap();
            for f in [1.0, 0.2, 1e-3] {
                let w = worst(&quiet, f);
                assert!(w < 1e-12, "{coupling:?}, scale {f}: {w:e}");
            }
            // with the receiver's noise at the scale the quadratics were made for
            let noisy = Response::new(&c, 1e-3, Some(2.5e-16)).unwrap();
            let w = worst(&noisy, 1.0);
            assert!(w < 1e-12, "{coupling:?}, noise: {w:e}");
        }
    }
}
