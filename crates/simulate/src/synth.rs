//! Sweep synthesis: from a pose's paths to the noisy S21 of every (direction, pulse).
//!
//! S21(f) for one (position, direction, pulse) is the coherent sum over paths
//! S21 = Σ F(θ_p, f)² · λ(f) · A_p · e^{−j2πf τ_p} + coupling + noise:
//! * θ_p is the path's angle relative to the beam (mechanical steering: to the heading plus
//!   the direction; electronic: to the heading, the table being steered), wrapped into
//!   (−π, π]; paths behind the array (|θ| ≥ π/2) are skipped;
//! * F is read from the direction's [`PatternTable`]: at every frequency point when it has
//!   one knot per point (exact), else linearly interpolated in frequency between knots;
//! * a path whose largest |F²·λ·A| (five sample frequencies in the exact case, with 20 dB
//!   slack) is below `cull` = 10⁻⁵·σ_noise is skipped;
//! * the phase e^{−j2πfτ} is advanced by a constant step per frequency point, started from
//!   the fractional part of f·τ (keeps the rotation accurate at large f·τ);
//! * coupling: amplitude 10^{−|coupling_db|/20}·(1 + 0.1·cos(2π(f − f₀)/2 GHz)) at
//!   `coupling_delay_ns` (the ripple gives replicas at ±0.5 ns);
//! * noise: complex white of variance σ² per point (the receiver's [`WhiteNoise`], which
//!   `synth` draws too), from a ChaCha stream per (position, direction, pulse) seeded by a
//!   splitmix64 hash of the indices, so the bytes do not depend on the thread count.

use super::binned::BinnedTables;
use super::paths::Path1;
use super::scene::SceneConfig;
use crate::campaign::manifest::{ArrayConfig, Band, Manifest, Steering, C0};
use crate::pattern::PatternTable;
use num_complex::Complex64;
use pradar_radar::energy::WhiteNoise;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, Weak};

/// The frequency grid of one sweep and the pattern's knot segments on it.
struct Grid {
    nf: usize,
    df: f64,
    exact: bool,
    lambdas: Vec<f64>,
    /// Frequency index range [a, b) of each knot segment.
    seg: Vec<(usize, usize)>,
}

impl Grid {
    fn new(table: &PatternTable, band: &Band) -> Grid {
        let nk = table.knots();
        let nf = band.points;
        let df = band.step_hz();
        let lambdas: Vec<f64> = (0..nf).map(|k| C0 / band.freq(k)).collect();
        let seg: Vec<(usize, usize)> = (0..nk - 1)
            .map(|i| {
                let a = ((table.knot_hz(i) - band.start_hz) / df).ceil() as usize;
                let b = if i == nk - 2 {
                    nf
                } else {
                    ((table.knot_hz(i + 1) - band.start_hz) / df).ceil() as usize
                };
                (a.min(nf), b.min(nf))
            })
            .collect();
        Grid {
            nf,
            df,
            exact: nk == nf,
            lambdas,
            seg,
        }
    }
}

/// Synthesise the noise-free S21 of one (pose, direction) from its paths into `acc`.
#[allow(clippy::too_many_arguments)]
pub fn synth_sweep(
    paths: &[Path1],
    table: &PatternTable,
    heading: f64,
    theta_s: f64,
    steering: Steering,
    band: &Band,
    cull: f64,
    acc: &mut [Complex64],
) {
    let grid = Grid::new(table, band);
    let mut g = vec![Complex64::new(0.0, 0.0); table.knots()];
    for p in paths {
        let th = match steering {
            Steering::Mechanical => p.theta - heading - theta_s,
            Steering::Electronic => p.theta - heading,
        };
        let th = crate::units::wrap_rad(th);
        if th.abs() >= PI / 2.0 {
            continue;
        }
        if grid.exact {
            add_path_exact(p, th, table, band, &grid, cull, acc);
        } else {
            add_path_interpolated(p, th, table, band, &grid, cull, &mut g, acc);
        }
    }
}

/// Add one path with the pattern at every frequency point (no interpolation in frequency).
fn add_path_exact(
    p: &Path1,
    th: f64,
    table: &PatternTable,
    band: &Band,
    grid: &Grid,
    cull: f64,
    acc: &mut [Complex64],
) {
    let nf = grid.nf;
    let Some((ai, t)) = table.angle_cell(th) else {
        return;
    };
    let (r0, r1) = (table.knots_at(ai), table.knots_at(ai + 1));
    // cull paths far below the noise (checked at five frequencies, with 20 dB slack)
    let est = [0, nf / 4, nf / 2, 3 * nf / 4, nf - 1]
        .iter()
        .map(|&k| (r0[k] * (1.0 - t) + r1[k] * t).norm_sqr() * grid.lambdas[k] * p.amp.norm())
        .fold(0.0, f64::max);
    if est < 0.1 * cull {
        return;
    }
    let mut ph = Complex64::from_polar(1.0, -2.0 * PI * (band.start_hz * p.tau_s).fract());
    let step = Complex64::from_polar(1.0, -2.0 * PI * (grid.df * p.tau_s).fract());
    for ((v, (a, b)), lam) in acc.iter_mut().zip(r0.iter().zip(r1)).zip(&grid.lambdas) {
        let f = a * (1.0 - t) + b * t;
        *v += f * f * (lam * p.amp) * ph;
        ph *= step;
    }
}

/// Add one path with F²·λ·A computed at the knots (`g`, scratch) and interpolated linearly
/// in frequency over each knot segment.
#[allow(clippy::too_many_arguments)]
fn add_path_interpolated(
    p: &Path1,
    th: f64,
    table: &PatternTable,
    band: &Band,
    grid: &Grid,
    cull: f64,
    g: &mut [Complex64],
    acc: &mut [Complex64],
) {
    let mut gmax = 0.0f64;
    for (ki, gk) in g.iter_mut().enumerate() {
        let f = table.at_knot(th, ki);
        let lambda = C0 / table.knot_hz(ki);
        *gk = f * f * lambda * p.amp;
        gmax = gmax.max(gk.norm());
    }
    if gmax < cull {
        return;
    }
    let df = grid.df;
    for (i, &(a, b)) in grid.seg.iter().enumerate() {
        if a >= b {
            continue;
        }
        let (fa, fb) = (table.knot_hz(i), table.knot_hz(i + 1));
        let (ga, gb) = (g[i], g[i + 1]);
        let f0 = band.freq(a);
        let mut ph = Complex64::from_polar(1.0, -2.0 * PI * (f0 * p.tau_s).fract());
        let step = Complex64::from_polar(1.0, -2.0 * PI * (df * p.tau_s).fract());
        let dg = (gb - ga) * (df / (fb - fa));
        let mut gv = ga + (gb - ga) * ((f0 - fa) / (fb - fa));
        for v in acc[a..b].iter_mut() {
            *v += gv * ph;
            ph *= step;
            gv += dg;
        }
    }
}

/// The seed of the noise stream of sweep (position `p`, direction `d`, pulse `k`).
fn noise_seed(seed: u64, p: usize, d: usize, k: usize) -> u64 {
    // splitmix64 over the indices: independent streams per sweep
    let mut z =
        seed ^ ((p as u64) << 40 ^ (d as u64) << 20 ^ k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Everything the sweeps of a campaign share: pattern tables, coupling, noise level.
pub(super) struct SweepSynth<'a> {
    m: &'a Manifest,
    tables: Vec<Arc<PatternTable>>,
    angles_deg: Vec<f64>,
    coupling: Vec<Complex64>,
    noise: WhiteNoise,
    cull: f64,
    /// The regrouped sum ([`super::binned`]) when it applies (mechanical steering, the
    /// pattern at every point, directions whole table cells apart); the tables are then
    /// dropped. Shared with the other simulations of this process that use the same
    /// array, band and directions while any of them runs ([`shared_binned`]).
    binned: Option<Arc<BinnedTables>>,
}

/// What the binned products depend on besides the pattern step: the array, the band and
/// the directions.
#[derive(PartialEq)]
struct BinnedKey {
    array: ArrayConfig,
    band: Band,
    angles_deg: Vec<f64>,
}

/// The binned products in use in this process: `reproduce` simulates the corridor and its
/// geometry-only copy at once, and they share one (93 MB at 801 points).
static SHARED_BINNED: Mutex<Vec<(BinnedKey, Weak<BinnedTables>)>> = Mutex::new(Vec::new());

/// The binned products of `m` (built from `tables()` when no running simulation holds
/// them), or the tables themselves when the binned sum does not apply. Built under the lock,
/// so a second simulation of the same array waits and shares them; the values are the same
/// either way. (`simulate` runs on plain threads, never inside a rayon task, so waiting on
/// the lock cannot hold up the pool that builds the tables.)
fn shared_binned(
    m: &Manifest,
    angles_deg: &[f64],
    tables: &dyn Fn() -> Vec<Arc<PatternTable>>,
) -> std::result::Result<Arc<BinnedTables>, Vec<Arc<PatternTable>>> {
    let key = BinnedKey {
        array: m.array,
        band: m.band,
        angles_deg: angles_deg.to_vec(),
    };
    let mut shared = SHARED_BINNED.lock().unwrap_or_else(|e| e.into_inner());
    shared.retain(|(_, w)| w.strong_count() > 0);
    if let Some(b) = shared
        .iter()
        .find(|(k, _)| *k == key)
        .and_then(|(_, w)| w.upgrade())
    {
        return Ok(b);
    }
    let t = tables();
    let lambdas: Vec<f64> = (0..m.band.points).map(|k| C0 / m.band.freq(k)).collect();
    let band = &m.band;
    let built = (t.first())
        .and_then(|t0| BinnedTables::new(t0, &lambdas, band.start_hz, band.step_hz(), angles_deg));
    match built {
        Some(b) => {
            let b = Arc::new(b);
            shared.push((key, Arc::downgrade(&b)));
            Ok(b)
        }
        None => Err(t),
    }
}

impl<'a> SweepSynth<'a> {
    /// Set up for manifest `m` with the direction tables of `angles_deg` (made by `tables`,
    /// with `knots` frequency knots, when needed).
    pub(super) fn new(
        m: &'a Manifest,
        scene: &SceneConfig,
        knots: usize,
        tables: &dyn Fn() -> Vec<Arc<PatternTable>>,
        angles_deg: Vec<f64>,
    ) -> SweepSynth<'a> {
        let sigma2 = m.noise.s21_variance();
        let coupling_amp = 10f64.powf(-scene.coupling_db.abs() / 20.0);
        let tau_c = scene.coupling_delay_ns * 1e-9;
        let coupling: Vec<Complex64> = (0..m.band.points)
            .map(|k| {
                let f = m.band.freq(k);
                let ripple = 1.0 + 0.1 * (2.0 * PI * (f - m.band.start_hz) / 2.0e9).cos();
                Complex64::from_polar(coupling_amp * ripple, -2.0 * PI * (f * tau_c).fract())
            })
            .collect();
        let (binned, tables) = match m.array.steering {
            Steering::Mechanical if knots == m.band.points => {
                match shared_binned(m, &angles_deg, tables) {
                    Ok(b) => (Some(b), Vec::new()),
                    Err(t) => (None, t),
                }
            }
            _ => (None, tables()),
        };
        SweepSynth {
            m,
            tables,
            binned,
            angles_deg,
            coupling,
            noise: WhiteNoise::new(sigma2),
            cull: 1e-5 * sigma2.sqrt(),
        }
    }

    /// Directions per position.
    pub(super) fn directions(&self) -> usize {
        self.angles_deg.len()
    }

    /// The S21 of position `p` (heading `heading` rad, paths `paths`) as
    /// `[direction][pulse][point]`, directions in parallel.
    pub(super) fn position(&self, p: usize, heading: f64, paths: &[Path1]) -> Vec<Complex64> {
        let m = self.m;
        let (nd, nk, nf) = (self.directions(), m.pulses, m.band.points);
        let mut s21 = vec![Complex64::new(0.0, 0.0); nd * nk * nf];
        let binned = (self.binned.as_ref()).map(|b| b.position(heading, paths, self.cull));
        s21.par_chunks_mut(nk * nf)
            .enumerate()
            .for_each(|(d, chunk)| {
                let mut clean = self.coupling.clone();
                match &binned {
                    Some(b) => {
                        for (c, v) in clean.iter_mut().zip(&b[d * nf..(d + 1) * nf]) {
                            *c += v;
                        }
                    }
                    None => synth_sweep(
                        paths,
                        &self.tables[d],
                        heading,
                        self.angles_deg[d].to_radians(),
                        m.array.steering,
                        &m.band,
                        self.cull,
                        &mut clean,
                    ),
                }
                for k in 0..nk {
                    let mut rng = ChaCha8Rng::seed_from_u64(noise_seed(m.seed, p, d, k));
                    self.noise
                        .add(&clean, &mut chunk[k * nf..(k + 1) * nf], &mut rng);
                }
            });
        s21
    }
}
