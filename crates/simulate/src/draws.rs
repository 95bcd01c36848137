//! Random draws shared by the simulator's scene and the synthetic channel model
//! ([`crate::model`]): distribution families of the model file, complex Gaussian RRCS,
//! ray counts, shadowing, Laplacian angles and the walk along the perimeter.
//!
//! Every function draws from the caller's ChaCha stream in a fixed order, so a scene (or a
//! synthetic channel) depends on the seed only; the order of the draws is part of the
//! contract (changing it changes every simulated byte).

use crate::campaign::layout::Layout;
use crate::model_file::ModelConfig;
use geo::Coord;
use num_complex::Complex64;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp, Normal, StandardNormal};

/// A draw of mean `mean` from a model-file family: `constant`, `gaussian` (30 % standard
/// deviation, floored at 5 % of the mean) or exponential (anything else).
pub(super) fn draw(rng: &mut ChaCha8Rng, family: &str, mean: f64) -> f64 {
    match family {
        "constant" => mean,
        "gaussian" => Normal::new(mean, 0.3 * mean)
            .expect("finite")
            .sample(rng)
            .max(0.05 * mean),
        _ => Exp::new(1.0 / mean).expect("positive").sample(rng),
    }
}

/// A circular complex Gaussian of unit variance: (a + jb)/√2, a, b ~ N(0, 1).
pub(super) fn cgauss(rng: &mut ChaCha8Rng) -> Complex64 {
    let a: f64 = StandardNormal.sample(rng);
    let b: f64 = StandardNormal.sample(rng);
    Complex64::new(a, b) * std::f64::consts::FRAC_1_SQRT_2
}

/// Rays of a cluster: 1 + Poisson(mean − 1).
pub fn draw_rays(rng: &mut ChaCha8Rng, mean: f64) -> usize {
    let mean_extra = (mean - 1.0).max(0.0);
    1 + rand_distr::Poisson::new(mean_extra.max(1e-9))
        .map(|d| d.sample(rng) as usize)
        .unwrap_or(0)
}

/// A cluster's σ: `mean` times log-normal shadowing of 0.69 neper (3 dB) standard deviation.
pub fn draw_shadowed(rng: &mut ChaCha8Rng, mean: f64) -> f64 {
    mean * Normal::<f64>::new(0.0, 0.69).expect("ok").sample(rng).exp()
}

/// A zero-mean Laplacian draw of scale `b` (inverse CDF).
pub fn laplace(rng: &mut ChaCha8Rng, b: f64) -> f64 {
    let u: f64 = rng.gen::<f64>() - 0.5;
    -b * u.signum() * (1.0 - 2.0 * u.abs()).ln()
}

/// Walk the layout perimeter placing cluster centres (DESIGN §2: clusters along the
/// perimeter): the first at an arc length uniform in [0, d_c), then spacings drawn from
/// `perimeter_spacing` (its family, at least 0.05 m); each centre offset into the room along
/// the inward normal by a draw from `perimeter_offset` (at most 1.5 m). `each(rng, arc,
/// offset, centre, normal)` is called per centre right after its offset draw, so it may draw
/// the cluster's contents from the same stream; it decides whether to keep the centre.
pub fn perimeter_walk(
    layout: &Layout,
    m: &ModelConfig,
    rng: &mut ChaCha8Rng,
    mut each: impl FnMut(&mut ChaCha8Rng, f64, f64, Coord<f64>, Coord<f64>),
) {
    let total = layout.perimeter_length();
    let mut s = rng.gen::<f64>() * m.perimeter_spacing.value;
    while s < total {
        let (p, nrm) = layout.perimeter_point(s);
        let off = draw(rng, &m.perimeter_offset.family, m.perimeter_offset.value).min(1.5);
        let centre = Coord {
            x: p.x + nrm.x * off,
            y: p.y + nrm.y * off,
        };
        each(rng, s, off, centre, nrm);
        s += draw(rng, &m.perimeter_spacing.family, m.perimeter_spacing.value).max(0.05);
    }
}
