//! The energy stage's floor: the same number of inverse FFTs of the stage's transform size
//! (rustfft, in place, buffers reused, both threads), nothing else — no decoding, windowing,
//! binning or writing. `scripts/bench-energy` runs it beside `pradar energy` on the same
//! campaign size and reports the stage's throughput as a share of this one.
//!
//! ```text
//! cargo run --release --example fft_limit -- SWEEPS [POINTS=801]
//! ```
//! Prints `fft_limit nfft=N sweeps=S seconds=T sweeps_per_s=R`.

use num_complex::Complex64;
use pradar::campaign::manifest::{Band, Processing};
use pradar::energy::EnergyProcessor;
use rayon::prelude::*;
use rustfft::FftPlanner;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let sweeps: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(10_000);
    let points: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(801);
    let band = Band {
        start_hz: 57.5e9,
        stop_hz: 63.5e9,
        points,
    };
    // the stage's transform size, from its own processor (default processing)
    let proc = EnergyProcessor::new(band, Processing::default()).expect("processor");
    let nfft = proc.scratch().0.len();
    let fft = FftPlanner::<f64>::new().plan_fft_inverse(nfft);
    let input: Vec<Complex64> = (0..nfft)
        .map(|k| {
            if k < points {
                Complex64::from_polar(1e-3, k as f64 * 0.1)
            } else {
                Complex64::new(0.0, 0.0)
            }
        })
        .collect();
    let t0 = Instant::now();
    let threads = rayon::current_num_threads();
    let per = sweeps.div_ceil(threads);
    let total: f64 = (0..threads)
        .into_par_iter()
        .map(|t| {
            let mut buf = vec![Complex64::new(0.0, 0.0); nfft];
            let mut scratch = vec![Complex64::new(0.0, 0.0); fft.get_inplace_scratch_len()];
            let mut acc = 0.0;
            for s in t * per..((t + 1) * per).min(sweeps) {
                buf.copy_from_slice(&input);
                fft.process_with_scratch(&mut buf, &mut scratch);
                acc += buf[s % nfft].re;
            }
            acc
        })
        .sum();
    let secs = t0.elapsed().as_secs_f64();
    // (the sum keeps the transforms from being optimised away)
    eprintln!("checksum {total:e}");
    println!(
        "fft_limit nfft={nfft} sweeps={sweeps} seconds={secs:.3} sweeps_per_s={:.1}",
        sweeps as f64 / secs
    );
}
