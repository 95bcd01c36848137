//! The distance indices: mean silhouette and Calinski–Harabasz, measured on K's partition in
//! K's own metric (linfa has neither index).
//!
//! * Silhouette: s = mean_i (b_i − a_i)/max(a_i, b_i), a_i the mean distance of point i to
//!   its own cluster, b_i to the nearest other cluster; a singleton counts 0.
//! * Calinski–Harabasz: CH = [B/(K−1)] / [W/(n−K)], B and W the between- and
//!   within-cluster sums of squares (∞ when W = 0).
//!
//! Both are larger-is-better and undefined for K = 1 (0 there); the selection gives K = 1
//! when no K ≥ 2 reaches `min_silhouette` (0.25: Kaufman & Rousseeuw's "no substantial
//! structure" limit).

use crate::cluster::kmeans::{centroids, dist};

/// Mean silhouette of a labelling (singletons count 0).
///
/// ```
/// let x = [[0.0, 0.0], [0.1, 0.0], [5.0, 0.0], [5.1, 0.0]];
/// assert!(pradar_channel::cluster::silhouette(&x, &[0, 0, 1, 1], 2) > 0.9);
/// ```
pub fn silhouette(x: &[[f64; 2]], labels: &[usize], k: usize) -> f64 {
    let n = x.len();
    if k < 2 || n < 2 {
        return 0.0;
    }
    let mut size = vec![0usize; k];
    labels.iter().for_each(|&l| size[l] += 1);
    let mut total = 0.0;
    let mut sums = vec![0.0; k];
    for i in 0..n {
        sums.iter_mut().for_each(|s| *s = 0.0);
        for j in 0..n {
            if i != j {
                sums[labels[j]] += dist(&x[i], &x[j]);
            }
        }
        let li = labels[i];
        if size[li] <= 1 {
            continue;
        }
        let a = sums[li] / (size[li] - 1) as f64;
        let b = (0..k)
            .filter(|&c| c != li && size[c] > 0)
            .map(|c| sums[c] / size[c] as f64)
            .fold(f64::INFINITY, f64::min);
        if b.is_finite() {
            let m = a.max(b);
            if m > 0.0 {
                total += (b - a) / m;
            }
        }
    }
    total / n as f64
}

/// Calinski–Harabasz index of a labelling.
pub fn calinski_harabasz(x: &[[f64; 2]], labels: &[usize], k: usize) -> f64 {
    let n = x.len();
    if k < 2 || n <= k {
        return 0.0;
    }
    let mean = [
        x.iter().map(|p| p[0]).sum::<f64>() / n as f64,
        x.iter().map(|p| p[1]).sum::<f64>() / n as f64,
    ];
    let (c, size) = centroids(x, labels, k);
    let b: f64 = c
        .iter()
        .zip(&size)
        .map(|(ci, &s)| s as f64 * dist(ci, &mean).powi(2))
        .sum();
    let w: f64 = x
        .iter()
        .zip(labels)
        .map(|(p, &l)| dist(p, &c[l]).powi(2))
        .sum();
    if w <= 0.0 {
        return f64::INFINITY;
    }
    (b / (k - 1) as f64) / (w / (n - k) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn silhouette_and_ch_separate_blobs() {
        let x: Vec<[f64; 2]> = (0..20)
            .map(|i| {
                if i < 10 {
                    [i as f64 * 0.01, 0.0]
                } else {
                    [10.0 + i as f64 * 0.01, 0.0]
                }
            })
            .collect();
        let good: Vec<usize> = (0..20).map(|i| usize::from(i >= 10)).collect();
        let bad: Vec<usize> = (0..20).map(|i| i % 2).collect();
        assert!(silhouette(&x, &good, 2) > 0.95);
        assert!(silhouette(&x, &bad, 2) < 0.1);
        assert!(calinski_harabasz(&x, &good, 2) > 1e4 * calinski_harabasz(&x, &bad, 2).max(1e-9));
    }
}
