//! Criterion benchmarks of the energy kernel (one sweep: window, IFFT, bins) and of the
//! array-pattern tabulation used by the simulator.

use criterion::{criterion_group, criterion_main, Criterion};
use num_complex::Complex64;
use pradar::campaign::manifest::{ArrayConfig, Band, Processing, Steering};
use pradar::energy::EnergyProcessor;
use pradar::pattern::{ArrayPattern, TABLE_STEP_DEG};
use std::f64::consts::PI;

fn bench(c: &mut Criterion) {
    let band = Band {
        start_hz: 57.5e9,
        stop_hz: 63.5e9,
        points: 801,
    };
    let proc = EnergyProcessor::new(band, Processing::default()).unwrap();
    let s21: Vec<Complex64> = (0..band.points)
        .map(|k| Complex64::from_polar(0.01, -2.0 * PI * band.freq(k) * 20e-9))
        .collect();
    let mut scratch = proc.scratch();
    let mut out = vec![0.0; proc.nbins_full()];
    c.bench_function("energy profile, 801 points", |b| {
        b.iter(|| proc.profile_into(&s21, &mut scratch, 1.0, &mut out))
    });
    let p = ArrayPattern::new(
        ArrayConfig {
            elements: 400,
            one_bit: true,
            element_q: 1.0,
            steering: Steering::Mechanical,
        },
        band.center_hz(),
    )
    .unwrap();
    c.bench_function("pattern table 20x20 1-bit, 17 knots", |b| {
        b.iter(|| p.table(0.0, &band, 17, TABLE_STEP_DEG))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
