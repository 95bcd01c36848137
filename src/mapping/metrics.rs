//! Map metrics against the reference map (DESIGN §2 "Mapping").
//!
//! Takes a binary map (occupied / free per cell), the binary reference (occupied / free) and
//! a region mask (the cells that count); gives [`MapMetrics`]:
//! * ψ, the image similarity of Birk & Carpin (2006): for each class c ∈ {occupied, free},
//!   d_c(A→B) = mean over the cells of class c in A of the Manhattan distance (in cells) to
//!   the nearest cell of class c in B; ψ = Σ_c [d_c(A→B) + d_c(B→A)]; when class c is absent
//!   from either map (inside the region) its term counts as the grid's Manhattan diameter
//!   rows + cols. Nearest distances come from an exact two-pass L1 distance transform
//!   (O(cells)); only region cells are sources and targets;
//! * wrong-cell rate: fraction of region cells whose class differs from the reference;
//! * occupied precision / recall / F1, exact and "within one cell": a predicted occupied cell
//!   is a hit if a reference occupied cell lies in its 8-neighbourhood (itself included), and
//!   a reference occupied cell is found if a predicted occupied cell lies in its
//!   8-neighbourhood. With no predicted occupied cell the precision is 0 (so the all-free
//!   map's F1 is 0); with no reference occupied cell the recall is 0.
//!
//! The caller maps the reference's `Outside` cells to free for the whole-map figures and
//! builds the region masks ([`crate::mapping::job`] states the observable region).

use serde::Serialize;

/// Figures of one map on one region.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MapMetrics {
    /// Image similarity ψ, cells (lower is better).
    pub psi: f64,
    /// Occupied-class term of ψ.
    pub psi_occupied: f64,
    /// Free-class term of ψ.
    pub psi_free: f64,
    /// Fraction of cells of the wrong class.
    pub wrong_cell_rate: f64,
    /// Occupied precision (exact).
    pub precision: f64,
    /// Occupied recall (exact).
    pub recall: f64,
    /// Occupied F1 (exact).
    pub f1: f64,
    /// Occupied precision within one cell.
    pub precision_1: f64,
    /// Occupied recall within one cell.
    pub recall_1: f64,
    /// Occupied F1 within one cell.
    pub f1_1: f64,
    /// Cells in the region.
    pub cells: usize,
    /// Reference occupied cells in the region.
    pub reference_occupied: usize,
    /// Map occupied cells in the region.
    pub map_occupied: usize,
}

const INF: u32 = u32::MAX / 4;

/// Exact Manhattan distance (cells) from every cell to the nearest source cell (two passes);
/// `INF` when there is none.
pub fn manhattan_transform(src: &[bool], rows: usize, cols: usize) -> Vec<u32> {
    let mut d: Vec<u32> = src.iter().map(|&s| if s { 0 } else { INF }).collect();
    for r in 0..rows {
        for c in 0..cols {
            let i = r * cols + c;
            let mut v = d[i];
            if r > 0 {
                v = v.min(d[i - cols] + 1);
            }
            if c > 0 {
                v = v.min(d[i - 1] + 1);
            }
            d[i] = v;
        }
    }
    for r in (0..rows).rev() {
        for c in (0..cols).rev() {
            let i = r * cols + c;
            let mut v = d[i];
            if r + 1 < rows {
                v = v.min(d[i + cols] + 1);
            }
            if c + 1 < cols {
                v = v.min(d[i + 1] + 1);
            }
            d[i] = v;
        }
    }
    d
}

/// ψ of two binary maps on a region: (total, occupied term, free term).
pub fn psi(a: &[bool], b: &[bool], region: &[bool], rows: usize, cols: usize) -> (f64, f64, f64) {
    let diameter = (rows + cols) as f64;
    let term = |class: bool| -> f64 {
        let sa: Vec<bool> = a
            .iter()
            .zip(region)
            .map(|(&v, &r)| r && v == class)
            .collect();
        let sb: Vec<bool> = b
            .iter()
            .zip(region)
            .map(|(&v, &r)| r && v == class)
            .collect();
        let (na, nb) = (
            sa.iter().filter(|&&v| v).count(),
            sb.iter().filter(|&&v| v).count(),
        );
        if na == 0 || nb == 0 {
            return diameter;
        }
        let db = manhattan_transform(&sb, rows, cols);
        let da = manhattan_transform(&sa, rows, cols);
        let ab: f64 = sa
            .iter()
            .zip(&db)
            .filter(|(s, _)| **s)
            .map(|(_, &d)| d as f64)
            .sum::<f64>()
            / na as f64;
        let ba: f64 = sb
            .iter()
            .zip(&da)
            .filter(|(s, _)| **s)
            .map(|(_, &d)| d as f64)
            .sum::<f64>()
            / nb as f64;
        ab + ba
    };
    let (o, f) = (term(true), term(false));
    (o + f, o, f)
}

fn any_in_3x3(m: &[bool], rows: usize, cols: usize, i: usize) -> bool {
    let (r, c) = ((i / cols) as isize, (i % cols) as isize);
    for dr in -1..=1 {
        for dc in -1..=1 {
            let (rr, cc) = (r + dr, c + dc);
            if rr >= 0
                && cc >= 0
                && (rr as usize) < rows
                && (cc as usize) < cols
                && m[rr as usize * cols + cc as usize]
            {
                return true;
            }
        }
    }
    false
}

fn f1(p: f64, r: f64) -> f64 {
    if p + r > 0.0 {
        2.0 * p * r / (p + r)
    } else {
        0.0
    }
}

/// All figures of `map` against `reference` on `region` (all slices row-major, same grid).
pub fn evaluate(
    map: &[bool],
    reference: &[bool],
    region: &[bool],
    rows: usize,
    cols: usize,
) -> MapMetrics {
    let (psi_total, psi_occ, psi_free) = psi(map, reference, region, rows, cols);
    let mut cells = 0usize;
    let (mut wrong, mut tp, mut pred, mut refo, mut hit_p, mut hit_r) = (0, 0, 0, 0, 0, 0);
    for i in 0..map.len() {
        if !region[i] {
            continue;
        }
        cells += 1;
        if map[i] != reference[i] {
            wrong += 1;
        }
        if map[i] {
            pred += 1;
            if reference[i] {
                tp += 1;
            }
            if any_in_3x3(reference, rows, cols, i) {
                hit_p += 1;
            }
        }
        if reference[i] {
            refo += 1;
            if any_in_3x3(map, rows, cols, i) {
                hit_r += 1;
            }
        }
    }
    let ratio = |a: usize, b: usize| if b > 0 { a as f64 / b as f64 } else { 0.0 };
    let (precision, recall) = (ratio(tp, pred), ratio(tp, refo));
    let (precision_1, recall_1) = (ratio(hit_p, pred), ratio(hit_r, refo));
    MapMetrics {
        psi: psi_total,
        psi_occupied: psi_occ,
        psi_free,
        wrong_cell_rate: ratio(wrong, cells),
        precision,
        recall,
        f1: f1(precision, recall),
        precision_1,
        recall_1,
        f1_1: f1(precision_1, recall_1),
        cells,
        reference_occupied: refo,
        map_occupied: pred,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transform_is_exact_l1() {
        let (rows, cols) = (7, 9);
        let mut src = vec![false; rows * cols];
        src[2 * cols + 3] = true;
        src[6 * cols + 8] = true;
        let d = manhattan_transform(&src, rows, cols);
        for r in 0..rows {
            for c in 0..cols {
                let want = (r.abs_diff(2) + c.abs_diff(3)).min(r.abs_diff(6) + c.abs_diff(8));
                assert_eq!(d[r * cols + c] as usize, want);
            }
        }
    }
}
