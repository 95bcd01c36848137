//! Energy matrices (DESIGN §2 "Energy matrix"): from S21 sweeps to `E[position][direction][bin]`.
//!
//! Takes a campaign with `[sweeps]` (Touchstone or Parquet); gives the energy Parquet long
//! table `position, direction, angle_rel_deg, angle_global_deg, bin, delay_ns, energy` with
//! key-value metadata `schema_version, bin_width_ns, pulses, n0, enbw, array` (plus `tw`,
//! `window`, `coupling`, `gate_ns`, `oversample`, `noise_bin_mean`, `band`).
//!
//! Per sweep S_k (k = 0..K−1, K points, step Δf, B = (K−1)Δf):
//! * `[calibration]` ([`calibration`]): S ← (S − background) / reference, recorded in the
//!   metadata (`calibration_background`, `calibration_reference`) when present;
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
//! detector formulas divided by N_p, N_p² since we store the mean). N0 is estimated
//! ([`noise`]) from the median of the bins at delays ≥ `noise_from_ns` over the whole
//! campaign under that law, so echoes that alias or arrive late into those bins do not
//! move it; the bins stop `gate_ns` + 2 ns before the end of the span (those bins hold
//! negative delays of the circular IFFT, where the coupling's kernel tail wraps to). When
//! the manifest's `[noise]` floor implies an N0 more than 3 dB from the data's, `energy`
//! warns with both values ([`EnergyReport::warnings`]; `report` and `reproduce` print the
//! same line and show it on the page beside N0). When the layout reaches beyond the sweep's
//! unambiguous range c/(2Δf) it warns too, naming the reach and the points that would cover
//! the building (`campaign::fold`): echoes from farther fold back into the kept delays.
//! The window kernel's null-to-null width (≈ 4/B for Hann) is the "pulse" duration.
//!
//! Refused, naming the manifest and the step: an energy that is not finite (a calibration
//! or sweep value that overflows), and an N0 of 0 or not finite (nothing in the noise bins:
//! e.g. a `[calibration] background` that is the measurement itself leaves an all-zero
//! table).
//!
//! Layout: [`processor`] (window, IFFT, bins, TW/ENBW), [`receiver`] (the white noise per
//! frequency point the simulator and `synth` draw), [`matrix`] (the table read back,
//! campaign check), [`writer`] (table and metadata), [`restrict`] (a matrix of some of its
//! positions); [`run`] streams a campaign through them and estimates N0.

pub mod calibration;
pub mod matrix;
pub mod noise;
pub mod processor;
pub mod receiver;
pub mod restrict;
pub mod writer;

pub use matrix::{check_campaign, EnergyMatrix, EnergyMeta, EnergySource, EnergyTable};
pub use processor::{window, EnergyProcessor};
pub use receiver::WhiteNoise;
pub use writer::{table_metadata, write_table, EnergyWriter};

use crate::campaign::manifest::Campaign;
use crate::campaign::sweeps::SweepReader;
use crate::error::{Error, Result};
use calibration::Calibration;
use std::path::Path;

/// Angle wrapping into (−180°, 180°] (re-exported from [`crate::units`]).
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
    /// What the user should know (the manifest's `[noise]` floor far from the data's).
    pub warnings: Vec<String>,
}

/// How far (dB) the data's N0 may be from the one the manifest's `[noise]` floor implies
/// before `energy` warns.
pub const NOISE_MISMATCH_DB: f64 = 3.0;

/// The warning when the manifest's `[noise]` floor implies an N0 more than
/// [`NOISE_MISMATCH_DB`] from the data's: the floor σ² per frequency point gives
/// N0 = σ²·Σw²/(Σw)² / TW. Not compared when a calibration reference rescales the sweeps.
fn manifest_noise_warning(
    c: &Campaign,
    proc: &EnergyProcessor,
    cal: &Calibration,
    n0: f64,
) -> Option<String> {
    if cal.reference_template().is_some() {
        return None;
    }
    let noise = c.manifest.noise;
    let expected = proc.noise_per_sample(noise.s21_variance()) / proc.tw();
    let db = 10.0 * (n0 / expected).log10();
    (db.abs() > NOISE_MISMATCH_DB).then(|| {
        format!(
            "{}: the data's noise level N0 = {n0:.3e} is {db:+.1} dB from the {expected:.3e} that [noise] floor_dbm = {} (tx_power_dbm = {}) implies",
            c.path.display(),
            noise.floor_dbm,
            noise.tx_power_dbm
        )
    })
}

/// Compute the energy matrices of a campaign and write the energy Parquet table.
/// `progress` is called after each position with (done, total).
///
/// Steps: open the sweeps, build the [`EnergyProcessor`], stream the positions (energies of
/// bins 0..=max_delay written as they come by an [`EnergyWriter`], the noise region
/// sampled), N0 from the noise bins' median ([`noise`]), then the metadata
/// ([`table_metadata`]) at the end.
///
/// ```no_run
/// use pradar_formats::campaign::Campaign;
/// use std::path::Path;
///
/// let c = Campaign::load(Path::new("/tmp/sim/campaign.toml"))?;
/// let r = pradar_radar::energy::run(&c, Path::new("/tmp/sim/energy.parquet"), &|_, _| {})?;
/// println!("{} sweeps, N0 = {:e}", r.sweeps, r.n0);
/// # Ok::<(), pradar_formats::error::Error>(())
/// ```
pub fn run(
    campaign: &Campaign,
    out: &Path,
    progress: &dyn Fn(usize, usize),
) -> Result<EnergyReport> {
    let m = &campaign.manifest;
    let reader = SweepReader::open(campaign)?;
    let cal = Calibration::load(campaign)?;
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
    let writer = EnergyWriter::create(out, m, nb)?;
    let mut noise = noise::NoiseSampler::new(np * nd * (noise_to - noise_from));
    let chunk = reader.chunk_positions();
    // three stages in flight: the next chunk of sweeps is read on one thread and the
    // previous positions' rows encoded on another while this one computes (bounded
    // channels: at most two chunks read ahead, four positions queued for writing); the
    // rows go to the writer in position order, so the file is the same
    let (writer, computed) = std::thread::scope(|scope| -> Result<_> {
        let (to_main, chunks) = std::sync::mpsc::sync_channel(1);
        let reading = scope.spawn(move || {
            let mut p0 = 0;
            while p0 < np {
                let r = reader.read_positions(p0, chunk);
                let failed = r.is_err();
                if to_main.send(r).is_err() || failed {
                    break;
                }
                p0 += chunk;
            }
        });
        let (to_writer, rows) = std::sync::mpsc::sync_channel::<Vec<f64>>(4);
        let writing = scope.spawn(move || -> Result<EnergyWriter> {
            let mut writer = writer;
            for energies in rows {
                writer.push(&energies)?;
            }
            Ok(writer)
        });
        let computed = (|| -> Result<()> {
            for sweeps in chunks {
                for mut sw in sweeps? {
                    cal.apply(&mut sw)?;
                    let e = proc.position_energy(&sw);
                    let mut energies = Vec::with_capacity(nd * nb);
                    for d in 0..nd {
                        if !sw.has(d) {
                            // a missing sweep: NaN in the table, listed in its metadata
                            energies.extend(std::iter::repeat_n(f64::NAN, nb));
                            continue;
                        }
                        let prof = &e[d * nbf..(d + 1) * nbf];
                        if let Some(b) = prof.iter().position(|v| !v.is_finite()) {
                            return Err(not_finite(campaign, &cal, sw.position, d, b));
                        }
                        energies.extend_from_slice(&prof[..nb]);
                        noise.push(&prof[noise_from..noise_to]);
                    }
                    if to_writer.send(energies).is_err() {
                        return Ok(()); // the writer stopped: its error is reported below
                    }
                    progress(sw.position + 1, np);
                }
            }
            Ok(())
        })();
        drop(to_writer);
        let writer = writing.join().expect("energy writer thread");
        reading.join().expect("sweep reader thread");
        Ok((writer, computed))
    })?;
    computed?;
    let writer = writer?;
    let est = noise.estimate(proc.tw(), m.pulses, noise::bin_law_median(&proc, m.pulses));
    let n0 = est.map_or(f64::NAN, |e| e.n0);
    if !(n0 > 0.0 && n0.is_finite()) {
        // the bins read as signal-free hold nothing: every energy is zero too, or the
        // background removed the noise with the signal (a background that is the
        // measurement itself)
        let why = match cal.background_template() {
            Some(t) => {
                format!(" after calibration.background = \"{t}\" (is it the measurement itself?)")
            }
            None => String::new(),
        };
        return Err(Error::input(
            &campaign.path,
            format!("energy: the noise estimate N0 = {n0:e}{why}: the bins from processing.noise_from_ns hold no noise, so no detection threshold can be set"),
        ));
    }
    let est = est.expect("a finite N0 comes from an estimate");
    let mut meta = table_metadata(m, &proc, &est);
    meta.extend(cal.metadata());
    writer.finish(meta)?;
    // the layout is optional to the processing: a campaign whose layout cannot be read
    // gets no fold warning here (the chain's later stages refuse it by name)
    let fold = crate::campaign::layout::Layout::load(&campaign.layout_path())
        .ok()
        .and_then(|l| crate::campaign::fold::fold_warning(m, &l));
    let warnings = (manifest_noise_warning(campaign, &proc, &cal, n0).into_iter())
        .chain(fold)
        .collect();
    Ok(EnergyReport {
        sweeps: (np * nd - m.missing().len()) * m.pulses,
        rows: np * nd * nb,
        n0,
        noise_bin_mean: est.bin_mean,
        warnings,
    })
}

/// The error of an energy that is not finite: naming the calibration reference (or the
/// background) when one is applied — the division or subtraction that made it overflow —
/// else the manifest.
fn not_finite(c: &Campaign, cal: &Calibration, p: usize, d: usize, b: usize) -> Error {
    let step = match (cal.reference_template(), cal.background_template()) {
        (Some(t), _) => format!("after calibration.reference = \"{t}\" (S − B) / R"),
        (None, Some(t)) => format!("after calibration.background = \"{t}\" S − B"),
        (None, None) => "from the sweeps".into(),
    };
    Error::input(
        &c.path,
        format!(
            "energy: not finite at position {}, direction {}, bin {b} {step}: a sweep or calibration value overflows",
            c.manifest.label(p),
            c.manifest.direction_name(d)
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(45.0), 45.0);
    }
}
