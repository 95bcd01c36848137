//! Order statistics of samples: the median and quantiles, with one contract for an empty
//! input — it has none (`None`), and the caller says what stands in for it.
//!
//! Takes samples as `f64` slices; gives the value at a probability. Values are ordered by
//! [`f64::total_cmp`] (a NaN sorts to the end its sign bit gives; callers leave out the
//! non-finite values that must not count). The definitions, each bit for bit the one its
//! callers used:
//! - [`median`]: the middle value, the mean `0.5·(a + b)` of the middle pair for an even
//!   count;
//! - [`upper_median`]: the middle value, the upper of the middle pair for an even count
//!   (the sorted value at index ⌊n/2⌋);
//! - [`quantile`]: linear interpolation between the order statistics around position
//!   q·(n − 1) (Hyndman & Fan's type 7): `v[i]·(1 − f) + v[i+1]·f` with i = ⌊q·(n − 1)⌋,
//!   f its fraction;
//! - [`quantile_nearest`]: the order statistic at position round(q·(n − 1)), halves away
//!   from zero (at q = ½ the [`upper_median`]);
//! - [`weighted_quantile`]: the first value, in ascending order (ties by index), at which
//!   the cumulative normalised weight reaches q.
//!
//! The free functions sort a copy; [`sorted`] holds the same statistics of a slice already
//! sorted, so that several quantiles of one sample sort it once (or a caller that needs the
//! sample sorted anyway sorts it in place).

/// A sorted copy of `xs` (by [`f64::total_cmp`]).
fn sorted_copy(xs: &[f64]) -> Vec<f64> {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    v
}

/// The median of `xs`: the mean of the middle pair for an even count; None when empty.
pub fn median(xs: &[f64]) -> Option<f64> {
    sorted::median(&sorted_copy(xs))
}

/// The upper median of `xs`: the upper of the middle pair for an even count; None when
/// empty.
pub fn upper_median(xs: &[f64]) -> Option<f64> {
    sorted::upper_median(&sorted_copy(xs))
}

/// The q-quantile (`q` in [0, 1]) of `xs`, interpolated linearly between order
/// statistics; None when empty.
pub fn quantile(xs: &[f64], q: f64) -> Option<f64> {
    sorted::quantile(&sorted_copy(xs), q)
}

/// The q-quantile (`q` in [0, 1]) of `xs` as the nearest order statistic; None when empty.
pub fn quantile_nearest(xs: &[f64], q: f64) -> Option<f64> {
    sorted::quantile_nearest(&sorted_copy(xs), q)
}

/// The weighted q-quantile (`q` in [0, 1]) of `x` with weights `w` (one per value, not
/// necessarily normalised): the first value in ascending order (ties by index) at which
/// the cumulative normalised weight reaches `q`, the largest when rounding keeps the sum
/// below it; None when empty.
pub fn weighted_quantile(x: &[f64], w: &[f64], q: f64) -> Option<f64> {
    let mut idx: Vec<usize> = (0..x.len()).collect();
    idx.sort_by(|&a, &b| x[a].total_cmp(&x[b]).then(a.cmp(&b)));
    let tw: f64 = w.iter().sum();
    let mut acc = 0.0;
    for &i in &idx {
        acc += w[i] / tw;
        if acc >= q {
            return Some(x[i]);
        }
    }
    idx.last().map(|&i| x[i])
}

/// The statistics of a slice already sorted by [`f64::total_cmp`] (ascending); None when
/// empty.
pub mod sorted {
    /// Whether `v` is sorted (checked in debug builds).
    fn is_sorted(v: &[f64]) -> bool {
        v.windows(2).all(|w| w[0].total_cmp(&w[1]).is_le())
    }

    /// The median of sorted `v` (the mean of the middle pair for an even count).
    pub fn median(v: &[f64]) -> Option<f64> {
        debug_assert!(is_sorted(v));
        let n = v.len();
        if n == 0 {
            None
        } else if n % 2 == 1 {
            Some(v[n / 2])
        } else {
            Some(0.5 * (v[n / 2 - 1] + v[n / 2]))
        }
    }

    /// The upper median of sorted `v` (the upper of the middle pair for an even count).
    pub fn upper_median(v: &[f64]) -> Option<f64> {
        debug_assert!(is_sorted(v));
        v.get(v.len() / 2).copied()
    }

    /// The q-quantile of sorted `v`, interpolated linearly between order statistics.
    pub fn quantile(v: &[f64], q: f64) -> Option<f64> {
        debug_assert!(is_sorted(v));
        let n = v.len();
        if n == 0 {
            return None;
        }
        let pos = q * (n - 1) as f64;
        let (i, f) = (pos.floor() as usize, pos.fract());
        Some(if i + 1 < n {
            v[i] * (1.0 - f) + v[i + 1] * f
        } else {
            v[i.min(n - 1)]
        })
    }

    /// The q-quantile of sorted `v` as the order statistic at round(q·(n − 1)).
    pub fn quantile_nearest(v: &[f64], q: f64) -> Option<f64> {
        debug_assert!(is_sorted(v));
        let n = v.len();
        if n == 0 {
            return None;
        }
        Some(v[((q * (n - 1) as f64).round() as usize).min(n - 1)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_sample_has_no_statistic() {
        assert_eq!(median(&[]), None);
        assert_eq!(upper_median(&[]), None);
        assert_eq!(quantile(&[], 0.5), None);
        assert_eq!(quantile_nearest(&[], 0.5), None);
        assert_eq!(weighted_quantile(&[], &[], 0.5), None);
        assert_eq!(sorted::median(&[]), None);
        assert_eq!(sorted::upper_median(&[]), None);
        assert_eq!(sorted::quantile(&[], 0.0), None);
        assert_eq!(sorted::quantile_nearest(&[], 1.0), None);
    }

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(upper_median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(upper_median(&[4.0, 1.0, 3.0, 2.0]), Some(3.0));
        assert_eq!(median(&[7.0]), Some(7.0));
        // a positive NaN sorts last, a negative one first
        assert_eq!(median(&[f64::NAN, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[-f64::NAN, 1.0, 2.0]), Some(1.0));
    }

    #[test]
    fn quantiles_interpolate_or_take_the_nearest() {
        let v = [10.0, 0.0, 30.0, 20.0];
        // position q·3
        assert_eq!(quantile(&v, 0.0), Some(0.0));
        assert_eq!(quantile(&v, 1.0), Some(30.0));
        assert!((quantile(&v, 0.5).unwrap() - 15.0).abs() < 1e-12);
        assert!((quantile(&v, 0.1).unwrap() - 3.0).abs() < 1e-12);
        assert_eq!(quantile_nearest(&v, 0.1), Some(0.0));
        assert_eq!(quantile_nearest(&v, 0.5), Some(20.0));
        assert_eq!(quantile_nearest(&v, 0.9), Some(30.0));
        // the interpolated median is the median
        for n in 1..40 {
            let v: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 * 0.3).collect();
            assert_eq!(quantile(&v, 0.5), median(&v), "n = {n}");
        }
    }

    #[test]
    fn the_nearest_median_is_the_upper_median() {
        for n in 1..60 {
            let v: Vec<f64> = (0..n).map(|i| ((i * 13) % 7) as f64 + i as f64).collect();
            assert_eq!(quantile_nearest(&v, 0.5), upper_median(&v), "n = {n}");
        }
    }

    #[test]
    fn weighted_quantiles_step_at_the_cumulative_weight() {
        let x = [3.0, 1.0, 2.0];
        let w = [1.0, 1.0, 2.0];
        // cumulative normalised weight: 1 → ¼, 2 → ¾, 3 → 1
        assert_eq!(weighted_quantile(&x, &w, 0.2), Some(1.0));
        assert_eq!(weighted_quantile(&x, &w, 0.5), Some(2.0));
        assert_eq!(weighted_quantile(&x, &w, 0.8), Some(3.0));
        assert_eq!(weighted_quantile(&x, &w, 1.0), Some(3.0));
    }
}
