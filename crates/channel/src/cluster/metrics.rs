//! Agreement between two labellings: the adjusted Rand index (Hubert & Arabie 1985),
//! ARI = (Σ_ij C(n_ij, 2) − E) / (½[Σ_i C(a_i, 2) + Σ_j C(b_j, 2)] − E) with
//! E = Σ_i C(a_i, 2) · Σ_j C(b_j, 2) / C(n, 2); 1 for identical partitions (up to the
//! labels' names), about 0 for chance agreement. Used by the tests and the closed loop to
//! score clusterings against synth's truth.

use std::collections::BTreeMap;

/// Adjusted Rand index between two labellings (Hubert & Arabie 1985).
///
/// ```
/// let ari = pradar_channel::cluster::adjusted_rand_index(&[0, 0, 1, 1], &[1, 1, 0, 0]);
/// assert!((ari - 1.0).abs() < 1e-12);
/// ```
pub fn adjusted_rand_index(a: &[usize], b: &[usize]) -> f64 {
    let n = a.len();
    if n < 2 {
        return 1.0;
    }
    let mut table: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    let mut ra: BTreeMap<usize, f64> = BTreeMap::new();
    let mut rb: BTreeMap<usize, f64> = BTreeMap::new();
    for (&x, &y) in a.iter().zip(b) {
        *table.entry((x, y)).or_default() += 1.0;
        *ra.entry(x).or_default() += 1.0;
        *rb.entry(y).or_default() += 1.0;
    }
    let c2 = |v: f64| v * (v - 1.0) / 2.0;
    let index: f64 = table.values().map(|&v| c2(v)).sum();
    let sa: f64 = ra.values().map(|&v| c2(v)).sum();
    let sb: f64 = rb.values().map(|&v| c2(v)).sum();
    let expected = sa * sb / c2(n as f64);
    let max = 0.5 * (sa + sb);
    if (max - expected).abs() < 1e-12 {
        return 1.0;
    }
    (index - expected) / (max - expected)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ari_known_values() {
        assert!((adjusted_rand_index(&[0, 0, 1, 1], &[1, 1, 0, 0]) - 1.0).abs() < 1e-12);
        // sklearn.metrics.adjusted_rand_score([0,0,1,1],[0,0,1,2]) = 0.5714285714285715
        assert!(
            (adjusted_rand_index(&[0, 0, 1, 1], &[0, 0, 1, 2]) - 0.5714285714285715).abs() < 1e-12
        );
    }
}
