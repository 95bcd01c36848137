//! The statistical backscatter channel model (DESIGN §2 "Statistical channel model"):
//! `pradar synth`.
//!
//! Takes a model file ([`ModelConfig`], fitted by `fit` or written by hand), a campaign (layout,
//! trajectory, directions, band, array, noise, processing; no `[sweeps]` needed) and a seed;
//! gives an energy table in the energy-matrix schema (the same columns and metadata as
//! `pradar energy`, plus `source = synth`) and its ground truth (`rays.parquet`,
//! `clusters.csv`, same schemas as `simulate`'s `truth/`, and `model.toml`: the model as
//! read, written back unchanged).
//!
//! The model, drawn once per run from the seed (so every pose sees the same clusters):
//! * **clusters along the perimeter** ([`perimeter_walk`], shared with the simulator's
//!   clutter): arc-length spacings ~ `perimeter_spacing` (d_c, its family), centroid offsets
//!   ~ `perimeter_offset` (d_p) into the room, capped at 1.5 m as the simulator's clutter
//!   (an exponential 0.4 m keeps a mean of 0.4·(1 − e^{−3.75}) = 0.391 m); Λ is not drawn
//!   — it follows from the geometry seen from each pose. A centre outside the free space
//!   is dropped;
//! * **rays per cluster**: 1 + Poisson(`rays_per_cluster` − 1); excess delays τ_k with
//!   exponential gaps of rate λ (`intra_cluster_rate`), τ_0 = 0; AoA offsets φ_k Laplacian
//!   with std `intra_cluster_aoa` (scale b = std/√2), φ_0 = 0 (the reference ray);
//!   pose-independent (a cluster is a fixed object);
//! * **where a cluster is**: the model's d_p is the offset of the cluster *centroid*, the
//!   point the fit measures (mean position of its MPCs); so seen from a pose at distance r,
//!   the first arrival is at range r − m, m = mean_k(c·τ_k/2) (the members' mean extra
//!   depth), and ray k arrives at T + τ_k, T = 2(r − m)/c, from θ + φ_k (θ the bearing of
//!   the centroid). A cluster is seen when the segment pose → centroid crosses no wall;
//! * **powers** (a Saleh–Valenzuela profile anchored by the radar equation): at each pose
//!   let T_0 be the first arrival of the first visible cluster in the scanned half-plane,
//!   at range d_0 = c·T_0/2. Ray k of cluster l has
//!   |A|² = σ_l · e^{−(T_l − T_0)/Γ} · e^{−τ_k/γ} / ((4π)³ d_0⁴), σ_l = `cluster_rrcs` ×
//!   log-normal shadowing (3 dB, as the simulator's clutter). So the first cluster follows
//!   the radar equation exactly (a single scatterer is `simulate`'s point target) and later
//!   clusters and rays decay with Γ and γ — the slopes `fit` measures, path loss included;
//! * **array**: each ray is seen through the campaign's array as
//!   a = ḡ(θ_arr)·|A|·e^{−j2πf_c(τ + τ_g)}, ḡ the window-weighted band average of |F|²λ
//!   (33 frequency knots) and τ_g the antenna group delay (slope of arg F² over the band,
//!   matters for the 1-bit transmitarray); mechanical or electronic steering as the campaign;
//! * **delay domain**: the windowed, zero-padded IFFT of a flat echo is the window kernel
//!   κ(t − τ) = e^{jπB(t−τ)}·r(t − τ) with r real (symmetric window), so the CIR on the
//!   energy stage's oversampled grid is h(t_n) = e^{jπBt_n}·Σ a·r(t_n − τ) (the common phase
//!   drops out of |h|²); r is tabulated at T_b/64 over ±16 bins. Rays add coherently (they
//!   interfere as in a measurement). Samples inside the coupling gate are zeroed like the
//!   energy stage's gate; the bin energy E_s is the mean of |h|² over the bin's L samples;
//! * **energy-detector noise**: each bin's energy (mean over N_p pulses) is drawn from the
//!   detector's law, a scaled non-central χ² with 2·TW·N_p degrees of freedom:
//!   E = N0/(2N_p)·[χ²(2TW·N_p − 1) + (Z + √(2N_p·E_s/N0))²], whose mean is N0·TW + E_s and
//!   variance (N0²·TW + 2·N0·E_s)/N_p (DESIGN §2). N0 comes from the campaign's `[noise]`
//!   floor through the window (as the energy stage's N0), TW from the window. Neighbouring
//!   bins are drawn independently (the window's bin-to-bin correlation is not modelled).
//!
//! Every draw comes from ChaCha streams keyed by the seed (the model) and by (seed,
//! position, direction) (the noise), so the bytes do not depend on the thread count.

use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, Steering, WindowKind};
use crate::campaign::modelfile::ModelConfig;
use crate::campaign::pattern::{ArrayPattern, PatternTable};
use crate::campaign::simulate::{
    draw_rays, draw_shadowed, laplace, perimeter_walk, truth_rays_frame, write_truth_clusters,
    TruthCluster, TruthRay,
};
use crate::energy::{self, EnergyProcessor};
use crate::error::{Error, Result};
use crate::table;
use crate::units::{wrap_rad, C0};
use geo::Coord;
use num_complex::Complex64;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp, Gamma, StandardNormal};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Frequency knots of the band-averaged pattern.
const KNOTS: usize = 33;
/// Kernel table: samples per bin and half-width in bins.
const KERNEL_FINE: usize = 64;
const KERNEL_BINS: usize = 16;

/// Options of a synth run (builder style; [`SynthParams::check`] validates).
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// Seed of the model and noise draws (default: the campaign seed).
    pub seed: Option<u64>,
    /// Ground-truth folder (default: `<out stem>_truth` beside the output).
    pub truth_dir: Option<PathBuf>,
    /// Rays weaker than this fraction of the mean noise-bin energy at their peak are skipped
    /// (default 1e-3, −30 dB).
    pub cull: f64,
}

impl Default for SynthParams {
    fn default() -> Self {
        SynthParams {
            seed: None,
            truth_dir: None,
            cull: 1e-3,
        }
    }
}

impl SynthParams {
    /// Set the seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = Some(seed);
        self
    }
    /// Set the truth folder.
    pub fn truth_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.truth_dir = Some(dir.into());
        self
    }
    /// Validate.
    pub fn check(&self) -> Result<()> {
        if !(self.cull.is_finite() && self.cull >= 0.0 && self.cull < 1.0) {
            return Err(Error::param("synth.cull", "must be in [0, 1)"));
        }
        Ok(())
    }
}

/// One ray of a model cluster (pose-independent).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelRay {
    /// Excess delay after the cluster's first arrival, ns.
    pub excess_ns: f64,
    /// AoA offset from the cluster bearing, rad.
    pub aoa_rad: f64,
}

/// A cluster of the statistical model.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelCluster {
    /// Centroid, m.
    pub centre: Coord<f64>,
    /// Arc length of its perimeter point, m.
    pub arc_m: f64,
    /// Offset from the wall (d_p), m.
    pub offset_m: f64,
    /// σ of its first ray, m².
    pub sigma_m2: f64,
    /// Rays, the reference first.
    pub rays: Vec<ModelRay>,
    /// Mean extra one-way depth of its rays, m.
    pub mean_depth_m: f64,
}

/// The drawn channel: clusters along the layout perimeter.
#[derive(Debug, Clone)]
pub struct ChannelModel {
    /// Model parameters.
    pub config: ModelConfig,
    /// Clusters.
    pub clusters: Vec<ModelCluster>,
}

impl ChannelModel {
    /// Draw the clusters of `config` along `layout`'s perimeter.
    pub fn draw(layout: &Layout, config: &ModelConfig, seed: u64) -> Result<ChannelModel> {
        config.check()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5379_6e74_6800_0000);
        let lambda = config.intra_cluster_rate.value;
        let b = config.intra_cluster_aoa.value.to_radians() / 2f64.sqrt();
        let gaps =
            Exp::new(lambda).map_err(|e| Error::param("intra_cluster_rate", e.to_string()))?;
        let mut clusters = Vec::new();
        perimeter_walk(layout, config, &mut rng, |rng, arc, off, centre, _| {
            let n = draw_rays(rng, config.rays_per_cluster.value);
            let sigma = draw_shadowed(rng, config.cluster_rrcs.value);
            let mut tau = 0.0;
            let rays: Vec<ModelRay> = (0..n)
                .map(|k| {
                    if k > 0 {
                        tau += gaps.sample(rng);
                    }
                    let phi = laplace(rng, b);
                    ModelRay {
                        excess_ns: tau,
                        aoa_rad: if k == 0 { 0.0 } else { phi },
                    }
                })
                .collect();
            if !layout.is_free(centre) {
                return;
            }
            let mean_depth_m = rays
                .iter()
                // c₀·τ/2 in the original operation order (bit-identical cluster locations)
                .map(|r| crate::units::C0 * r.excess_ns * 1e-9 / 2.0)
                .sum::<f64>()
                / n as f64;
            clusters.push(ModelCluster {
                centre,
                arc_m: arc,
                offset_m: off,
                sigma_m2: sigma,
                rays,
                mean_depth_m,
            });
        });
        Ok(ChannelModel {
            config: config.clone(),
            clusters,
        })
    }

    /// The rays seen from a pose (x, y, heading in degrees): every ray of every cluster whose
    /// centroid is in line of sight, with its complex amplitude factor before the array.
    pub fn rays_from(&self, layout: &Layout, at: Coord<f64>, heading_deg: f64) -> Vec<SeenRay> {
        let heading = heading_deg.to_radians();
        let mut seen: Vec<(usize, f64, f64)> = Vec::new(); // (cluster, first arrival s, bearing)
        for (l, c) in self.clusters.iter().enumerate() {
            let v = c.centre - at;
            let r = v.x.hypot(v.y);
            if r < 0.1 || layout.occluded(at, c.centre, 1e-3) {
                continue;
            }
            let first = (r - c.mean_depth_m).max(0.05);
            seen.push((l, crate::units::delay_s(first), v.y.atan2(v.x)));
        }
        let in_front = |th: f64| wrap_rad(th - heading).abs() < PI / 2.0;
        let Some(t0) = seen
            .iter()
            .filter(|s| in_front(s.2))
            .map(|s| s.1)
            .min_by(f64::total_cmp)
        else {
            return Vec::new();
        };
        let d0 = crate::units::range_from_delay_s(t0);
        let re = 1.0 / ((4.0 * PI).powi(3) * d0.powi(4));
        let gamma_c = self.config.cluster_decay.value * 1e-9;
        let gamma_r = self.config.ray_decay.value;
        let mut out = Vec::new();
        for (l, t, th) in seen {
            let c = &self.clusters[l];
            let pc = c.sigma_m2 * (-(t - t0).max(0.0) / gamma_c).exp() * re;
            for r in &c.rays {
                let tau = t + r.excess_ns * 1e-9;
                let theta = th + r.aoa_rad;
                let range = crate::units::range_from_delay_s(tau);
                out.push(SeenRay {
                    cluster: l,
                    tau_s: tau,
                    theta,
                    amp2: pc * (-r.excess_ns / gamma_r).exp(),
                    pos: Coord {
                        x: at.x + range * theta.cos(),
                        y: at.y + range * theta.sin(),
                    },
                });
            }
        }
        out
    }
}

/// A ray seen from a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenRay {
    /// Model cluster.
    pub cluster: usize,
    /// Round-trip delay, s.
    pub tau_s: f64,
    /// Global angle of arrival, rad.
    pub theta: f64,
    /// |A|² (received power = G²λ²|A|²).
    pub amp2: f64,
    /// Where the echo maps to, m.
    pub pos: Coord<f64>,
}

/// The band-averaged pattern of one steering table: ḡ(θ) = Σ w(f)|F(θ,f)|²λ(f) / Σ w(f) and
/// the group delay τ_g(θ) on the table's angle grid.
#[derive(Debug, Clone)]
pub struct BandPattern {
    step_deg: f64,
    g: Vec<f64>,
    tau_g: Vec<f64>,
}

impl BandPattern {
    /// Average a pattern table over its knots with `window` weights.
    pub fn new(table: &PatternTable, window: WindowKind) -> BandPattern {
        let nk = table.knots();
        let w: Vec<f64> = match window {
            WindowKind::Rect => vec![1.0; nk],
            WindowKind::Hann => (0..nk)
                .map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / (nk - 1) as f64).cos())
                .collect(),
        };
        let wsum: f64 = w.iter().sum();
        let f: Vec<f64> = (0..nk).map(|k| table.knot_hz(k)).collect();
        let mut g = Vec::with_capacity(table.angles());
        let mut tau_g = Vec::with_capacity(table.angles());
        for i in 0..table.angles() {
            let v = table.knots_at(i);
            let gi = v
                .iter()
                .zip(&w)
                .zip(&f)
                .map(|((x, w), f)| w * x.norm_sqr() * C0 / f)
                .sum::<f64>()
                / wsum;
            // weighted least-squares slope of the unwrapped phase of F² against frequency
            let (mut sw, mut sf, mut sp, mut sff, mut sfp) = (0.0, 0.0, 0.0, 0.0, 0.0);
            let mut prev: Option<f64> = None;
            let mut unwrap = 0.0;
            for ((x, wk), fk) in v.iter().zip(&w).zip(&f) {
                let ph = (x * x).arg();
                if let Some(p) = prev {
                    let d = ph - p;
                    unwrap -= 2.0 * PI * (d / (2.0 * PI)).round();
                }
                prev = Some(ph);
                let y = ph + unwrap;
                let wt = wk * x.norm_sqr();
                let fx = fk - f[0];
                sw += wt;
                sf += wt * fx;
                sp += wt * y;
                sff += wt * fx * fx;
                sfp += wt * fx * y;
            }
            let den = sw * sff - sf * sf;
            let slope = if sw > 0.0 && den > 0.0 {
                (sw * sfp - sf * sp) / den
            } else {
                0.0
            };
            tau_g.push((-slope / (2.0 * PI)).clamp(-1e-9, 1e-9));
            g.push(gi);
        }
        // the group delay is meaningless where there is no gain
        let gmax = g.iter().copied().fold(0.0, f64::max);
        for (t, gi) in tau_g.iter_mut().zip(&g) {
            if *gi < 1e-3 * gmax {
                *t = 0.0;
            }
        }
        BandPattern {
            step_deg: table.step_deg(),
            g,
            tau_g,
        }
    }

    /// (ḡ, τ_g) towards `theta` (rad, array frame), linear in angle; None behind the array.
    pub fn at(&self, theta: f64) -> Option<(f64, f64)> {
        let deg = theta.to_degrees();
        if !(-90.0..=90.0).contains(&deg) {
            return None;
        }
        let x = (deg + 90.0) / self.step_deg;
        let i = (x.floor() as usize).min(self.g.len() - 2);
        let t = x - i as f64;
        Some((
            self.g[i] * (1.0 - t) + self.g[i + 1] * t,
            self.tau_g[i] * (1.0 - t) + self.tau_g[i + 1] * t,
        ))
    }
}

/// What `synth` produced.
#[derive(Debug, Clone)]
pub struct SynthReport {
    /// Profiles written (positions × directions).
    pub profiles: usize,
    /// Clusters of the drawn model.
    pub clusters: usize,
    /// Mean rays seen per position (all angles).
    pub rays_per_position: f64,
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

/// The real window kernel r(t) of the energy stage, tabulated at T_b/64 over ±16 bins.
struct Kernel {
    step_s: f64,
    half: usize,
    r: Vec<f64>,
}

impl Kernel {
    fn new(proc: &EnergyProcessor) -> Kernel {
        let band = proc.band();
        let w = energy::window(proc.processing().window, band.points);
        let wsum: f64 = w.iter().sum();
        let df = band.step_hz();
        let mid = (band.points - 1) as f64 / 2.0;
        let step_s = proc.bin_width_ns() * 1e-9 / KERNEL_FINE as f64;
        let half = KERNEL_FINE * KERNEL_BINS;
        let r = (0..=2 * half)
            .map(|i| {
                let t = (i as f64 - half as f64) * step_s;
                w.iter()
                    .enumerate()
                    .map(|(k, wk)| wk * (2.0 * PI * (k as f64 - mid) * df * t).cos())
                    .sum::<f64>()
                    / wsum
            })
            .collect();
        Kernel { step_s, half, r }
    }

    #[inline]
    fn at(&self, t: f64) -> f64 {
        let x = t / self.step_s + self.half as f64;
        if x < 0.0 || x >= (self.r.len() - 1) as f64 {
            return 0.0;
        }
        let i = x as usize;
        let f = x - i as f64;
        self.r[i] * (1.0 - f) + self.r[i + 1] * f
    }
}

/// Run the statistical channel model over a campaign and write the energy table to `out`
/// and the truth beside it. `progress` is called after each position with (done, total).
pub fn synth(
    c: &Campaign,
    model: &ModelConfig,
    out: &Path,
    params: &SynthParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SynthReport> {
    params.check()?;
    let layout = Layout::load(&c.layout_path())?;
    let seed = params.seed.unwrap_or(c.manifest.seed);
    let channel = ChannelModel::draw(&layout, model, seed)?;
    synth_channel(c, &channel, out, params, progress)
}

/// [`synth`] for an already drawn (or hand-built) channel.
pub fn synth_channel(
    c: &Campaign,
    channel: &ChannelModel,
    out: &Path,
    params: &SynthParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SynthReport> {
    params.check()?;
    let m = &c.manifest;
    let layout = Layout::load(&c.layout_path())?;
    let seed = params.seed.unwrap_or(m.seed);
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
    let (np, nd, nb) = (m.positions(), angles.len(), proc.nbins());
    let l = m.processing.oversample;
    let half = (l - 1) as i64 / 2;
    let tb = proc.bin_width_ns() * 1e-9;
    let dt = tb / l as f64;
    let fc = m.band.center_hz();
    let gate = if m.processing.coupling == crate::campaign::manifest::CouplingRemoval::Gate {
        m.processing.gate_ns * 1e-9
    } else {
        0.0
    };
    let n0 = proc.noise_per_sample(m.noise.s21_variance()) / proc.tw();
    let noise_mean = n0 * proc.tw();
    let pulses = m.pulses as f64;
    let dof = 2.0 * proc.tw() * pulses - 1.0;
    let chi = Gamma::new(dof / 2.0, 2.0).map_err(|e| Error::input(&c.path, e.to_string()))?;
    let kernel_reach = KERNEL_BINS as f64 * tb;
    let truth_dir = params
        .truth_dir
        .clone()
        .unwrap_or_else(|| default_truth_dir(out));
    std::fs::create_dir_all(&truth_dir).map_err(|e| Error::io(&truth_dir, e))?;
    let rays_path = truth_dir.join("rays.parquet");
    let mut rays_out = table::ParquetStream::create(&rays_path)?;
    let g0 = pattern.gain(0.0, 0.0, fc);
    let lc = C0 / fc;
    let mut energies = vec![0.0; np * nd * nb];
    let mut seen_total = 0usize;
    for p in 0..np {
        let pose = m.poses[p];
        let at = Coord {
            x: pose.x_m,
            y: pose.y_m,
        };
        let heading = pose.heading_deg.to_radians();
        let rays = channel.rays_from(&layout, at, pose.heading_deg);
        seen_total += rays.len();
        energies[p * nd * nb..(p + 1) * nd * nb]
            .par_chunks_mut(nb)
            .enumerate()
            .for_each(|(d, prof)| {
                let bp = &bands[if bands.len() == 1 { 0 } else { d }];
                let theta_s = angles[d].to_radians();
                let mut h = vec![Complex64::new(0.0, 0.0); nb * l];
                for r in &rays {
                    let th = match m.array.steering {
                        Steering::Mechanical => r.theta - heading - theta_s,
                        Steering::Electronic => r.theta - heading,
                    };
                    let Some((g, tau_g)) = bp.at(wrap_rad(th)) else {
                        continue;
                    };
                    let a2 = g * g * r.amp2;
                    if a2 < params.cull * noise_mean {
                        continue;
                    }
                    let tau = r.tau_s + tau_g;
                    let a = Complex64::from_polar(a2.sqrt(), -2.0 * PI * (fc * tau).fract());
                    // samples n·dt within the kernel's reach, from bin 0 (sample −half)
                    let lo = ((tau - kernel_reach) / dt).ceil().max(-(half as f64)) as i64;
                    let hi = ((tau + kernel_reach) / dt).floor() as i64;
                    let hi = hi.min((nb * l) as i64 - half - 1);
                    for n in lo..=hi {
                        let t = n as f64 * dt;
                        if t.abs() < gate {
                            continue;
                        }
                        h[(n + half) as usize] += a * kernel.at(t - tau);
                    }
                }
                let mut rng = ChaCha8Rng::seed_from_u64(noise_seed(seed, p, d));
                for (b, e) in prof.iter_mut().enumerate() {
                    let es = h[b * l..(b + 1) * l]
                        .iter()
                        .map(|v| v.norm_sqr())
                        .sum::<f64>()
                        / l as f64;
                    let z: f64 = StandardNormal.sample(&mut rng);
                    let x = chi.sample(&mut rng);
                    let nc = (2.0 * pulses * es / n0).sqrt();
                    *e = n0 / (2.0 * pulses) * (x + (z + nc).powi(2));
                }
            });
        let rows: Vec<TruthRay> = rays
            .iter()
            .map(|r| TruthRay {
                scatterer_id: -1,
                kind: "clutter",
                cluster_id: r.cluster as i64,
                pos: r.pos,
                delay_ns: r.tau_s * 1e9,
                angle_global_deg: r.theta.to_degrees(),
                power_db: 10.0 * (g0 * g0 * lc * lc * r.amp2).log10(),
            })
            .collect();
        rays_out.write(&truth_rays_frame(&rays_path, p, pose.heading_deg, &rows)?)?;
        progress(p + 1, np);
    }
    rays_out.finish(None)?;
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
    write_truth_clusters(&truth_dir, &truth_clusters)?;
    channel.config.save(&truth_dir.join("model.toml"))?;
    let mut meta = energy::table_metadata(m, &proc, n0, noise_mean);
    meta.push(("source".into(), "synth".into()));
    meta.push(("seed".into(), seed.to_string()));
    energy::write_table(out, m, nb, &energies, meta)?;
    Ok(SynthReport {
        profiles: np * nd,
        clusters: channel.clusters.len(),
        rays_per_position: seen_total as f64 / np.max(1) as f64,
        truth_dir,
    })
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
    use crate::campaign::manifest::{Band, Processing};

    #[test]
    fn kernel_is_the_energy_stage_kernel() {
        let band = Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points: 401,
        };
        let proc = EnergyProcessor::new(band, Processing::default()).unwrap();
        let k = Kernel::new(&proc);
        assert!((k.at(0.0) - 1.0).abs() < 1e-12);
        // |κ(t)|² averaged over a bin equals the energy stage's point-echo energy
        let tau = 10.3e-9;
        for bin in 58..66 {
            let l = proc.processing().oversample;
            let dt = proc.bin_width_ns() * 1e-9 / l as f64;
            let half = (l as i64 - 1) / 2;
            let e: f64 = (-half..=half)
                .map(|j| k.at((bin as i64 * l as i64 + j) as f64 * dt - tau).powi(2))
                .sum::<f64>()
                / l as f64;
            let want = proc.point_echo_energy_at(1.0, tau, bin);
            assert!(
                (e - want).abs() < 1e-3 * want + 1e-7,
                "bin {bin}: {e} vs {want}"
            );
        }
    }

    #[test]
    fn params_check() {
        assert!(SynthParams::default().check().is_ok());
        let p = SynthParams {
            cull: f64::NAN,
            ..SynthParams::default()
        };
        assert!(p.check().is_err());
    }
}
