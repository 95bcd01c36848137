//! Energy matrices (DESIGN §2 "Energy matrix"): from S21 sweeps to `E[position][direction][bin]`.
//!
//! Takes a campaign with `[sweeps]` (Touchstone or Parquet); gives the energy Parquet long
//! table `position, direction, angle_rel_deg, angle_global_deg, bin, delay_ns, energy` with
//! key-value metadata `schema_version, bin_width_ns, pulses, n0, enbw, array` (plus `tw`,
//! `window`, `coupling`, `gate_ns`, `oversample`, `noise_bin_mean`, `band`).
//!
//! Per sweep S_k (k = 0..K−1, K points, step Δf, B = (K−1)Δf):
//! * coupling removal, recorded in the metadata: `mean` subtracts the complex mean sweep over
//!   the directions of the same position and pulse (the coupling does not rotate with the
//!   beam), `gate` zeroes the CIR at signed delays in [−gate, gate), `none` keeps it;
//! * window w_k (symmetric Hann by default), zero-padded IFFT of length N = (K−1)·L (L odd,
//!   `oversample`), normalised so a flat unit S21 gives |h(0)| = 1:
//!   h_n = Σ_k w_k S_k e^{j2πkn/N} / Σ_k w_k, sample spacing dt = 1/(NΔf) = T_b/L;
//! * bin b is centred at delay b·T_b, T_b = 1/B, and its energy is the mean of |h_n|² over
//!   its L samples (|h|² integrated over the bin divided by T_b);
//! * energy = mean over the N_p pulses (repeated sweeps or independent noise draws).
//!
//! Noise statistics: complex white noise of variance σ² per point gives per-sample mean
//! N0_h = σ²·Σw²/(Σw)²; the L samples of a bin are correlated through the window, with
//! ρ(Δ) = Σ w_k² e^{j2πkΔ/N} / Σ w_k². The equivalent number of independent samples of a bin
//! TW = L² / Σ_{n,m∈bin} |ρ(n−m)|² (from the window, like its ENBW = K·Σw²/(Σw)² which is
//! also recorded), and N0 = N0_h / TW, so a bin of signal energy E_s (averaged over N_p
//! pulses) has mean N0·TW + E_s and variance (N0²·TW + 2·N0·E_s)/N_p (DESIGN's energy
//! detector formulas divided by N_p, N_p² since we store the mean). N0 is estimated from
//! the bins at delays ≥ `noise_from_ns` (signal-free by assumption) over the whole campaign,
//! stopping `gate_ns` + 2 ns before the end of the span (those bins hold negative delays of
//! the circular IFFT, where the coupling's kernel tail wraps to).
//! The window kernel's null-to-null width (≈ 4/B for Hann) is the "pulse" duration.

use crate::campaign::manifest::{
    Band, Campaign, CouplingRemoval, Manifest, Processing, WindowKind, SCHEMA_VERSION,
};
use crate::campaign::sweeps::{PositionSweeps, SweepReader};
use crate::error::{Error, Result};
use crate::table;
use num_complex::Complex64;
use rayon::prelude::*;
use rustfft::{Fft, FftPlanner};
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// Window coefficients.
pub fn window(kind: WindowKind, points: usize) -> Vec<f64> {
    match kind {
        WindowKind::Rect => vec![1.0; points],
        WindowKind::Hann => (0..points)
            .map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / (points - 1) as f64).cos())
            .collect(),
    }
}

/// The per-sweep processor (window, IFFT, bins).
#[derive(Clone)]
pub struct EnergyProcessor {
    band: Band,
    proc: Processing,
    win: Vec<f64>,
    wsum: f64,
    nfft: usize,
    fft: Arc<dyn Fft<f64>>,
    nbins_full: usize,
    nbins: usize,
    tw: f64,
    enbw: f64,
}

impl std::fmt::Debug for EnergyProcessor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnergyProcessor")
            .field("nfft", &self.nfft)
            .field("nbins", &self.nbins)
            .field("tw", &self.tw)
            .finish()
    }
}

impl EnergyProcessor {
    /// Build for a band and processing options.
    pub fn new(band: Band, proc: Processing) -> Result<Self> {
        band.check()?;
        proc.check()?;
        let win = window(proc.window, band.points);
        let wsum: f64 = win.iter().sum();
        let w2: f64 = win.iter().map(|w| w * w).sum();
        let l = proc.oversample;
        let nfft = (band.points - 1) * l;
        let fft = FftPlanner::new().plan_fft_inverse(nfft);
        let nbins_full = band.points - 1;
        let tb_ns = 1e9 / band.bandwidth_hz();
        let nbins = ((proc.max_delay_ns / tb_ns).floor() as usize + 1).min(nbins_full);
        // equivalent number of independent samples per bin
        let rho = |d: i64| -> f64 {
            let z: Complex64 = win
                .iter()
                .enumerate()
                .map(|(k, w)| {
                    Complex64::from_polar(w * w, 2.0 * PI * k as f64 * d as f64 / nfft as f64)
                })
                .sum();
            z.norm() / w2
        };
        let mut s = 0.0;
        for n in 0..l as i64 {
            for m in 0..l as i64 {
                s += rho(n - m).powi(2);
            }
        }
        let tw = (l * l) as f64 / s;
        let enbw = band.points as f64 * w2 / (wsum * wsum);
        Ok(EnergyProcessor {
            band,
            proc,
            win,
            wsum,
            nfft,
            fft,
            nbins_full,
            nbins,
            tw,
            enbw,
        })
    }

    /// Bin width T_b, ns.
    pub fn bin_width_ns(&self) -> f64 {
        1e9 / self.band.bandwidth_hz()
    }
    /// Bins written (0..=max_delay).
    pub fn nbins(&self) -> usize {
        self.nbins
    }
    /// Bins computed (the whole unambiguous delay span).
    pub fn nbins_full(&self) -> usize {
        self.nbins_full
    }
    /// Equivalent independent samples per bin.
    pub fn tw(&self) -> f64 {
        self.tw
    }
    /// Equivalent noise bandwidth of the window, in frequency steps.
    pub fn enbw(&self) -> f64 {
        self.enbw
    }
    /// Per-sample CIR noise mean N0_h for S21 noise variance `sigma2`.
    pub fn noise_per_sample(&self, sigma2: f64) -> f64 {
        sigma2 * self.win.iter().map(|w| w * w).sum::<f64>() / (self.wsum * self.wsum)
    }
    /// Processing options.
    pub fn processing(&self) -> &Processing {
        &self.proc
    }
    /// The band.
    pub fn band(&self) -> &Band {
        &self.band
    }

    /// Scratch buffer for [`Self::profile_into`].
    pub fn scratch(&self) -> (Vec<Complex64>, Vec<Complex64>) {
        (
            vec![Complex64::new(0.0, 0.0); self.nfft],
            vec![Complex64::new(0.0, 0.0); self.fft.get_inplace_scratch_len()],
        )
    }

    /// Energy of every bin (`nbins_full` of them) of one sweep, added with weight `scale` to
    /// `out`.
    pub fn profile_into(
        &self,
        s21: &[Complex64],
        scratch: &mut (Vec<Complex64>, Vec<Complex64>),
        scale: f64,
        out: &mut [f64],
    ) {
        let (buf, fft_scratch) = scratch;
        let inv = 1.0 / self.wsum;
        for (b, (s, w)) in buf.iter_mut().zip(s21.iter().zip(&self.win)) {
            *b = s * (w * inv);
        }
        for b in buf[s21.len()..].iter_mut() {
            *b = Complex64::new(0.0, 0.0);
        }
        self.fft.process_with_scratch(buf, fft_scratch);
        let l = self.proc.oversample;
        let half = (l - 1) / 2;
        if self.proc.coupling == CouplingRemoval::Gate {
            let dt_ns = self.bin_width_ns() / l as f64;
            let g = (self.proc.gate_ns / dt_ns).ceil() as usize;
            let g = g.min(self.nfft / 2);
            for b in buf[..g].iter_mut() {
                *b = Complex64::new(0.0, 0.0);
            }
            for b in buf[self.nfft - g..].iter_mut() {
                *b = Complex64::new(0.0, 0.0);
            }
        }
        let norm = scale / l as f64;
        for (bin, o) in out.iter_mut().enumerate().take(self.nbins_full) {
            let start = (bin * l + self.nfft - half) % self.nfft;
            let mut e = 0.0;
            for j in 0..l {
                e += buf[(start + j) % self.nfft].norm_sqr();
            }
            *o += e * norm;
        }
    }

    /// Expected bin energies (noise-free) of a point echo of complex amplitude spectrum
    /// `a(f)` = `amp`·e^{−j2πfτ} (flat magnitude) at delay `tau_s`: the window kernel
    /// averaged over each bin. Returns `nbins` values.
    pub fn point_echo_energy(&self, amp2: f64, tau_s: f64) -> Vec<f64> {
        (0..self.nbins)
            .map(|b| self.point_echo_energy_at(amp2, tau_s, b))
            .collect()
    }

    /// Expected energy of bin `bin` for a point echo of power `amp2` at delay `tau_s`.
    pub fn point_echo_energy_at(&self, amp2: f64, tau_s: f64, bin: usize) -> f64 {
        let df = self.band.step_hz();
        let l = self.proc.oversample;
        let dt = 1.0 / (self.nfft as f64 * df);
        let half = ((l - 1) / 2) as i64;
        let mut e = 0.0;
        for j in -half..=half {
            let t = (bin as i64 * l as i64 + j) as f64 * dt;
            let k: Complex64 = self
                .win
                .iter()
                .enumerate()
                .map(|(k, w)| Complex64::from_polar(*w, 2.0 * PI * k as f64 * df * (t - tau_s)))
                .sum();
            e += (k / self.wsum).norm_sqr();
        }
        amp2 * e / l as f64
    }

    /// Energies of one position: `[direction][bin]` (nbins_full per direction), mean over
    /// pulses, coupling removed as configured.
    pub fn position_energy(&self, sw: &PositionSweeps) -> Vec<f64> {
        let nf = sw.points;
        let nd = sw.directions;
        let nk = sw.pulses;
        let mean: Option<Vec<Complex64>> =
            (self.proc.coupling == CouplingRemoval::Mean).then(|| {
                let mut m = vec![Complex64::new(0.0, 0.0); nk * nf];
                for d in 0..nd {
                    for k in 0..nk {
                        for (acc, v) in m[k * nf..(k + 1) * nf].iter_mut().zip(sw.sweep(d, k)) {
                            *acc += v;
                        }
                    }
                }
                m.iter_mut().for_each(|v| *v /= nd as f64);
                m
            });
        let nb = self.nbins_full;
        let mut out = vec![0.0; nd * nb];
        out.par_chunks_mut(nb).enumerate().for_each_init(
            || (self.scratch(), vec![Complex64::new(0.0, 0.0); nf]),
            |(scratch, tmp), (d, o)| {
                for k in 0..nk {
                    let s = sw.sweep(d, k);
                    let s: &[Complex64] = match &mean {
                        Some(m) => {
                            for ((t, v), mv) in tmp.iter_mut().zip(s).zip(&m[k * nf..(k + 1) * nf])
                            {
                                *t = v - mv;
                            }
                            tmp
                        }
                        None => s,
                    };
                    self.profile_into(s, scratch, 1.0 / nk as f64, o);
                }
            },
        );
        out
    }
}

/// Metadata of an energy table.
#[derive(Debug, Clone, PartialEq)]
pub struct EnergyMeta {
    /// Schema version.
    pub schema_version: u32,
    /// Bin width T_b, ns.
    pub bin_width_ns: f64,
    /// Pulses averaged.
    pub pulses: usize,
    /// Noise spectral level N0 (mean noise bin energy = N0·TW).
    pub n0: f64,
    /// Window ENBW in frequency steps.
    pub enbw: f64,
    /// Equivalent independent samples per bin.
    pub tw: f64,
    /// Array label.
    pub array: String,
    /// Coupling removal used.
    pub coupling: String,
    /// Every key-value pair as stored.
    pub all: Vec<(String, String)>,
}

impl EnergyMeta {
    /// The coupling gate applied, ns (0 unless `coupling = "gate"`).
    pub fn gate_ns(&self) -> f64 {
        if self.coupling != "gate" {
            return 0.0;
        }
        self.all
            .iter()
            .find(|(k, _)| k == "gate_ns")
            .and_then(|(_, v)| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    }

    /// Mean energy of a noise-only bin, N0·TW.
    pub fn noise_mean(&self) -> f64 {
        self.n0 * self.tw
    }
}

/// An energy matrix `E[position][direction][bin]` with its axes.
#[derive(Debug, Clone)]
pub struct EnergyMatrix {
    /// Metadata.
    pub meta: EnergyMeta,
    /// Positions.
    pub positions: usize,
    /// Relative direction angles, degrees.
    pub angles_rel_deg: Vec<f64>,
    /// Pose headings, degrees (one per position).
    pub headings_deg: Vec<f64>,
    /// Bins per profile.
    pub bins: usize,
    /// Energies, position-major.
    pub data: Vec<f64>,
}

impl EnergyMatrix {
    /// Directions.
    pub fn directions(&self) -> usize {
        self.angles_rel_deg.len()
    }
    /// The profile of one (position, direction).
    pub fn profile(&self, p: usize, d: usize) -> &[f64] {
        let i = (p * self.directions() + d) * self.bins;
        &self.data[i..i + self.bins]
    }
    /// Delay of a bin centre, ns.
    pub fn delay_ns(&self, bin: usize) -> f64 {
        bin as f64 * self.meta.bin_width_ns
    }
    /// Global angle of direction `d` at position `p`, degrees in (−180, 180].
    pub fn angle_global_deg(&self, p: usize, d: usize) -> f64 {
        wrap_deg(self.headings_deg[p] + self.angles_rel_deg[d])
    }

    /// Read an energy Parquet file; `headings_deg` may be empty (then recovered from the
    /// table's angle columns).
    pub fn read(path: &Path) -> Result<EnergyMatrix> {
        let kv = table::parquet_metadata(path)?;
        let get = |k: &str| -> Result<String> {
            kv.iter()
                .find(|(key, _)| key == k)
                .map(|(_, v)| v.clone())
                .ok_or_else(|| {
                    Error::input(
                        path,
                        format!("metadata key `{k}` missing (not an energy table?)"),
                    )
                })
        };
        let num = |k: &str| -> Result<f64> {
            get(k)?
                .parse::<f64>()
                .map_err(|_| Error::input(path, format!("metadata `{k}` is not a number")))
        };
        let meta = EnergyMeta {
            schema_version: num("schema_version")? as u32,
            bin_width_ns: num("bin_width_ns")?,
            pulses: num("pulses")? as usize,
            n0: num("n0")?,
            enbw: num("enbw")?,
            tw: num("tw").unwrap_or(1.0),
            array: get("array")?,
            coupling: get("coupling").unwrap_or_default(),
            all: kv.clone(),
        };
        if meta.schema_version != SCHEMA_VERSION {
            return Err(Error::input(
                path,
                format!(
                    "metadata schema_version {} unsupported",
                    meta.schema_version
                ),
            ));
        }
        let df = table::read_parquet(path, None)?;
        if df.height() == 0 {
            return Err(Error::input(path, "energy table has no rows"));
        }
        let pos = table::i64_column(path, &df, "position")?;
        let dir = table::i64_column(path, &df, "direction")?;
        let bin = table::i64_column(path, &df, "bin")?;
        let arel = table::f64_column(path, &df, "angle_rel_deg")?;
        let aglob = table::f64_column(path, &df, "angle_global_deg")?;
        let energy = table::f64_column(path, &df, "energy")?;
        let np = *pos.iter().max().unwrap_or(&-1) as usize + 1;
        let nd = *dir.iter().max().unwrap_or(&-1) as usize + 1;
        let nb = *bin.iter().max().unwrap_or(&-1) as usize + 1;
        if pos.iter().chain(&dir).chain(&bin).any(|v| *v < 0) {
            return Err(Error::input(path, "negative position/direction/bin index"));
        }
        if np * nd * nb != df.height() {
            return Err(Error::input(
                path,
                format!(
                    "{} rows but {np} positions x {nd} directions x {nb} bins",
                    df.height()
                ),
            ));
        }
        let mut data = vec![f64::NAN; np * nd * nb];
        let mut angles = vec![f64::NAN; nd];
        let mut headings = vec![f64::NAN; np];
        for i in 0..df.height() {
            let (p, d, b) = (pos[i] as usize, dir[i] as usize, bin[i] as usize);
            let idx = (p * nd + d) * nb + b;
            if !data[idx].is_nan() {
                return Err(Error::input(
                    path,
                    format!("row {i}: duplicate (position {p}, direction {d}, bin {b})"),
                ));
            }
            if energy[i] < 0.0 {
                return Err(Error::input(path, format!("row {i}: negative energy")));
            }
            data[idx] = energy[i];
            angles[d] = arel[i];
            headings[p] = wrap_deg(aglob[i] - arel[i]);
        }
        Ok(EnergyMatrix {
            meta,
            positions: np,
            angles_rel_deg: angles,
            headings_deg: headings,
            bins: nb,
            data,
        })
    }
}

/// Check that an energy table belongs to a campaign (file named in every error).
pub fn check_campaign(c: &Campaign, em: &EnergyMatrix, path: &Path) -> Result<()> {
    let m = &c.manifest;
    let (np, nd) = (m.poses.len(), m.directions.count());
    if em.positions != np || em.directions() != nd {
        return Err(Error::input(
            path,
            format!(
                "{} positions x {} directions, but campaign {} has {np} poses x {nd} directions (energy table from another campaign?)",
                em.positions,
                em.directions(),
                c.path.display()
            ),
        ));
    }
    for d in 0..nd {
        if (em.angles_rel_deg[d] - m.directions.angle_deg(d)).abs() > 1e-6 {
            return Err(Error::input(
                path,
                format!(
                    "direction {d} at {}°, campaign {} has {}° (energy table from another campaign?)",
                    em.angles_rel_deg[d],
                    c.path.display(),
                    m.directions.angle_deg(d)
                ),
            ));
        }
    }
    for (p, pose) in m.poses.iter().enumerate() {
        let diff = wrap_deg(em.headings_deg[p] - pose.heading_deg).abs();
        if diff.is_nan() || diff >= 1e-6 {
            return Err(Error::input(
                path,
                format!(
                    "position {p} heading {}°, campaign {} has {}° (energy table from another campaign?)",
                    em.headings_deg[p],
                    c.path.display(),
                    pose.heading_deg
                ),
            ));
        }
    }
    let tb = 1e9 / m.band.bandwidth_hz();
    if (em.meta.bin_width_ns - tb).abs() > 1e-6 * tb || !em.meta.bin_width_ns.is_finite() {
        return Err(Error::input(
            path,
            format!(
                "bin_width_ns {} but campaign {} has 1/B = {tb} ns",
                em.meta.bin_width_ns,
                c.path.display()
            ),
        ));
    }
    if let Some((_, v)) = em.meta.all.iter().find(|(k, _)| k == "elements") {
        if v.parse::<usize>().ok() != Some(m.array.elements) {
            return Err(Error::input(
                path,
                format!(
                    "metadata elements = {v}, but the campaign's array has {} elements (pass --elements {v}?)",
                    m.array.elements
                ),
            ));
        }
    }
    Ok(())
}

pub use crate::units::wrap_deg;

/// Summary of an energy run.
#[derive(Debug, Clone)]
pub struct EnergyReport {
    /// Sweeps processed (positions × directions × pulses).
    pub sweeps: usize,
    /// Rows written.
    pub rows: usize,
    /// Estimated N0.
    pub n0: f64,
    /// Mean noise-bin energy.
    pub noise_bin_mean: f64,
}

/// Compute the energy matrices of a campaign and write the energy Parquet table.
/// `progress` is called after each position with (done, total).
pub fn run(
    campaign: &Campaign,
    out: &Path,
    progress: &dyn Fn(usize, usize),
) -> Result<EnergyReport> {
    let m = &campaign.manifest;
    let reader = SweepReader::open(campaign)?;
    let proc = EnergyProcessor::new(m.band, m.processing)
        .map_err(|e| Error::input(&campaign.path, e.to_string()))?;
    let np = m.positions();
    let nd = m.directions.count();
    let nb = proc.nbins();
    let nbf = proc.nbins_full();
    let tb = proc.bin_width_ns();
    let noise_from = (m.processing.noise_from_ns / tb).ceil() as usize;
    // the last bins hold negative delays (circular IFFT): the coupling's kernel tail lives
    // there, so the noise region stops `gate_ns + 2 ns` before the end of the span
    let tail = ((m.processing.gate_ns + 2.0) / tb).ceil() as usize;
    let noise_to = nbf.saturating_sub(tail);
    if noise_from >= noise_to {
        return Err(Error::input(
            &campaign.path,
            format!(
                "processing.noise_from_ns = {} ns leaves no signal-free bins (span {:.1} ns)",
                m.processing.noise_from_ns,
                nbf as f64 * tb
            ),
        ));
    }
    let mut energies = Vec::with_capacity(np * nd * nb);
    let (mut noise_sum, mut noise_n) = (0.0, 0usize);
    let chunk = reader.chunk_positions();
    let mut p0 = 0;
    while p0 < np {
        for sw in reader.read_positions(p0, chunk)? {
            let e = proc.position_energy(&sw);
            for d in 0..nd {
                let prof = &e[d * nbf..(d + 1) * nbf];
                energies.extend_from_slice(&prof[..nb]);
                noise_sum += prof[noise_from..noise_to].iter().sum::<f64>();
                noise_n += noise_to - noise_from;
            }
            progress(sw.position + 1, np);
        }
        p0 += chunk;
    }
    let noise_bin_mean = noise_sum / noise_n as f64;
    let n0 = noise_bin_mean / proc.tw();
    let meta = table_metadata(m, &proc, n0, noise_bin_mean);
    write_table(out, m, nb, &energies, meta)?;
    Ok(EnergyReport {
        sweeps: np * nd * m.pulses,
        rows: np * nd * nb,
        n0,
        noise_bin_mean,
    })
}

/// The key-value metadata of an energy table (DESIGN §3 plus `tw`, `window`, `coupling`,
/// `gate_ns`, `oversample`, `noise_from_ns`, `noise_bin_mean`, `campaign`, `band`).
pub fn table_metadata(
    m: &Manifest,
    proc: &EnergyProcessor,
    n0: f64,
    noise_bin_mean: f64,
) -> Vec<(String, String)> {
    vec![
        ("schema_version".to_string(), SCHEMA_VERSION.to_string()),
        (
            "bin_width_ns".into(),
            format!("{:.17e}", proc.bin_width_ns()),
        ),
        ("pulses".into(), m.pulses.to_string()),
        ("n0".into(), format!("{n0:.17e}")),
        ("enbw".into(), format!("{:.17e}", proc.enbw())),
        ("tw".into(), format!("{:.17e}", proc.tw())),
        ("array".into(), m.array.label()),
        ("elements".into(), m.array.elements.to_string()),
        (
            "window".into(),
            format!("{:?}", m.processing.window).to_lowercase(),
        ),
        (
            "coupling".into(),
            format!("{:?}", m.processing.coupling).to_lowercase(),
        ),
        ("gate_ns".into(), m.processing.gate_ns.to_string()),
        ("oversample".into(), m.processing.oversample.to_string()),
        (
            "noise_from_ns".into(),
            m.processing.noise_from_ns.to_string(),
        ),
        ("noise_bin_mean".into(), format!("{noise_bin_mean:.17e}")),
        ("campaign".into(), m.name.clone()),
        (
            "band".into(),
            format!("{} {} {}", m.band.start_hz, m.band.stop_hz, m.band.points),
        ),
    ]
}

/// Write an energy table (`energies` as `[position][direction][bin]`, `nb` bins per
/// profile) with its metadata, atomically, about 2^20 rows per row group.
pub fn write_table(
    out: &Path,
    m: &Manifest,
    nb: usize,
    energies: &[f64],
    meta: Vec<(String, String)>,
) -> Result<()> {
    let np = m.positions();
    let nd = m.directions.count();
    let tb = 1e9 / m.band.bandwidth_hz();
    if energies.len() != np * nd * nb {
        return Err(Error::input(
            out,
            format!(
                "energy table: {} values for {np} positions x {nd} directions x {nb} bins",
                energies.len()
            ),
        ));
    }
    let mut stream = table::ParquetStream::create(out)?;
    stream.set_metadata(meta);
    let angles = m.directions.angles_deg();
    // about 2^20 rows per row group
    let group = ((1usize << 20) / (nd * nb).max(1)).max(1);
    for g0 in (0..np).step_by(group) {
        let ps = g0..(g0 + group).min(np);
        let n = ps.len() * nd * nb;
        let mut pos = Vec::with_capacity(n);
        let mut dir = Vec::with_capacity(n);
        let mut arel = Vec::with_capacity(n);
        let mut aglob = Vec::with_capacity(n);
        let mut bin = Vec::with_capacity(n);
        let mut delay = Vec::with_capacity(n);
        for p in ps.clone() {
            for (d, a) in angles.iter().enumerate() {
                let g = wrap_deg(m.poses[p].heading_deg + a);
                for b in 0..nb {
                    pos.push(p as i32);
                    dir.push(d as i32);
                    arel.push(*a);
                    aglob.push(g);
                    bin.push(b as i32);
                    delay.push(b as f64 * tb);
                }
            }
        }
        let df = table::frame(
            out,
            vec![
                table::col("position", pos),
                table::col("direction", dir),
                table::col("angle_rel_deg", arel),
                table::col("angle_global_deg", aglob),
                table::col("bin", bin),
                table::col("delay_ns", delay),
                table::col(
                    "energy",
                    energies[ps.start * nd * nb..ps.end * nd * nb].to_vec(),
                ),
            ],
        )?;
        stream.write(&df)?;
    }
    stream.finish(None)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn band() -> Band {
        Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points: 401,
        }
    }

    #[test]
    fn point_echo_lands_in_its_bin_with_kernel_energy() {
        let b = band();
        let proc = Processing {
            coupling: CouplingRemoval::None,
            max_delay_ns: 60.0,
            ..Processing::default()
        };
        let p = EnergyProcessor::new(b, proc).unwrap();
        let tau = 20.0e-9;
        let a = 0.01;
        let s: Vec<Complex64> = (0..b.points)
            .map(|k| Complex64::from_polar(a, -2.0 * PI * b.freq(k) * tau))
            .collect();
        let mut out = vec![0.0; p.nbins_full()];
        p.profile_into(&s, &mut p.scratch(), 1.0, &mut out);
        let peak = (0..p.nbins())
            .max_by(|&i, &j| out[i].total_cmp(&out[j]))
            .unwrap();
        assert_eq!(peak, (20.0 / p.bin_width_ns()).round() as usize);
        let expect = p.point_echo_energy(a * a, tau);
        for bi in peak - 3..=peak + 3 {
            assert!(
                (out[bi] - expect[bi]).abs() < 1e-6 * expect[peak],
                "bin {bi}: {} vs {}",
                out[bi],
                expect[bi]
            );
        }
    }

    #[test]
    fn hann_enbw_and_tw() {
        let p = EnergyProcessor::new(band(), Processing::default()).unwrap();
        assert!((p.enbw() - 1.5).abs() < 0.01, "enbw {}", p.enbw());
        assert!(p.tw() > 1.0 && p.tw() < 1.5, "tw {}", p.tw());
    }

    #[test]
    fn wrap() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(45.0), 45.0);
    }
}
