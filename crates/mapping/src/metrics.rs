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
//! builds the region masks ([`crate::score`] states the observable region).
//!
//! **Three-class reference** ([`evaluate_three_class`], a simulated scene: DESIGN §2). The
//! classes: *structure* S = the layout's wall cells (the reference's occupied cells: a wall
//! crosses the half-open cell, so a wall lying exactly on a grid line is given to the cell
//! above it or to its right); *objects*, each a set of cells (the truth's clutter clusters
//! and targets, never read by a mapper), whose *zone* Z is their cells and the 8-neighbours
//! of them that are not structure; the *boundary band* B = the cells a wall touches only
//! along their edge or at a corner (the cell on the other side of a wall on a grid line,
//! [`crate::reference::LayoutRaster::edge_band`]); *free* F = every other cell, split into
//! the room's (reference free) and those beyond the walls (reference outside). M is the
//! map's occupied cells; every count is restricted to the region R. Then:
//! * walls found within one cell = |{s ∈ S : M ∩ N₈(s) ≠ ∅}| / |S|;
//! * precision within one cell = |{m ∈ M : (S ∪ O) ∩ N₈(m) ≠ ∅}| / |M| (O the object cells:
//!   an occupied cell next to a wall or an object is right);
//! * F1 within one cell = their harmonic mean;
//! * wrong cells = |{s ∈ S \ M : no 4-neighbour of s in B ∩ M}| + |M ∩ F| (exact, as the
//!   layout-only rate; the zone Z and the band B are ignore regions: neither an occupied
//!   nor a free cell there counts). A wall on a grid line is at distance zero from the
//!   cells on both sides of the line, and either of them marked is that wall found: with
//!   the rasteriser's tie-break alone the same map scores 0 or 2 wrong cells per cell of
//!   such a wall depending on which side of the line the room is (`docs/mapping.md`);
//! * free cells marked occupied = |M ∩ F_room| / |F_room|; beyond the walls marked occupied
//!   = |M ∩ F_beyond| / |F_beyond|;
//! * objects found = objects with a cell of M in their zone, of the objects with a cell in R;
//! * ψ (three-class) = ψ of M against S on R \ Z: the object zones are left out of both
//!   maps' classes, so a marked object is neither a false occupied cell nor a missing free
//!   one (DESIGN §2: objects are not counted as wrong). The band stays in: ψ is a distance,
//!   and a wall placed one cell off costs one cell per cell whichever side it is on.
//!
//! The all-free map (M = ∅) has wrong cells |S|, and 0 for the rest (its ψ: the occupied
//! term is the grid's diameter).

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

/// Whether a 4-neighbour of cell `i` is a band cell marked occupied (the cell on the other
/// side of the grid line a wall lies on).
fn band_partner_marked(map: &[bool], band: &[bool], rows: usize, cols: usize, i: usize) -> bool {
    let (r, c) = (i / cols, i % cols);
    let mut n = [None; 4];
    if r > 0 {
        n[0] = Some(i - cols);
    }
    if r + 1 < rows {
        n[1] = Some(i + cols);
    }
    if c > 0 {
        n[2] = Some(i - 1);
    }
    if c + 1 < cols {
        n[3] = Some(i + 1);
    }
    n.into_iter().flatten().any(|j| band[j] && map[j])
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

/// Figures of one map on one region against the three-class reference (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ThreeClassMetrics {
    /// Structure cells found within one cell (recall against the walls).
    pub walls_found_1: f64,
    /// Map occupied cells within one cell of structure or an object.
    pub precision_1: f64,
    /// F1 of the two.
    pub f1_1: f64,
    /// Wrong cells: structure not marked (and without a marked 4-neighbour in the boundary
    /// band) plus free cells (outside the object zones and the band) marked occupied.
    pub wrong: usize,
    /// Cells scored for `wrong` (the region less the object zones and the boundary band).
    pub scored_cells: usize,
    /// Fraction of the room's free cells (outside every object zone and the boundary band)
    /// marked occupied.
    pub free_marked_occupied: f64,
    /// Room free cells.
    pub free_cells: usize,
    /// Fraction of the cells beyond the walls (outside every object zone and the boundary
    /// band) marked occupied.
    pub beyond_marked_occupied: f64,
    /// Cells beyond the walls.
    pub beyond_cells: usize,
    /// Objects with a map occupied cell in their zone.
    pub objects_found: usize,
    /// Objects with a cell in the region.
    pub objects: usize,
    /// Structure cells.
    pub structure_cells: usize,
    /// Map occupied cells.
    pub map_occupied: usize,
    /// ψ against the structure on the region less the object zones (module docs).
    pub psi: f64,
}

/// Figures of `map` against the three-class reference on `region`: `reference` the layout's
/// classes (occupied = structure), `band` the cells a wall touches only along an edge or at
/// a corner ([`crate::reference::LayoutRaster::edge_band`]; all false for none), `objects`
/// each object's cells (module docs).
pub fn evaluate_three_class(
    map: &[bool],
    reference: &[crate::reference::CellClass],
    band: &[bool],
    objects: &[Vec<usize>],
    region: &[bool],
    rows: usize,
    cols: usize,
) -> ThreeClassMetrics {
    use crate::reference::CellClass;
    let n = map.len();
    debug_assert_eq!(band.len(), n, "the boundary band is on the map's grid");
    let structure = structure_cells(reference);
    let mut object = vec![false; n];
    for o in objects {
        for &c in o {
            object[c] = true;
        }
    }
    let zones: Vec<Vec<usize>> = objects
        .iter()
        .map(|o| object_zone(o, &structure, rows, cols))
        .collect();
    let mut zone = vec![false; n];
    for z in &zones {
        for &c in z {
            zone[c] = true;
        }
    }
    let target: Vec<bool> = structure
        .iter()
        .zip(&object)
        .map(|(&s, &o)| s || o)
        .collect();
    let (mut s_n, mut s_found, mut m_n, mut m_hit) = (0usize, 0usize, 0usize, 0usize);
    let (mut wrong, mut scored) = (0usize, 0usize);
    let (mut free_n, mut free_occ, mut beyond_n, mut beyond_occ) = (0usize, 0usize, 0usize, 0usize);
    for i in 0..n {
        if !region[i] {
            continue;
        }
        if map[i] {
            m_n += 1;
            if any_in_3x3(&target, rows, cols, i) {
                m_hit += 1;
            }
        }
        if structure[i] {
            s_n += 1;
            scored += 1;
            if any_in_3x3(map, rows, cols, i) {
                s_found += 1;
            }
            if !map[i] && !band_partner_marked(map, band, rows, cols, i) {
                wrong += 1;
            }
            continue;
        }
        if zone[i] || band[i] {
            continue;
        }
        scored += 1;
        wrong += map[i] as usize;
        if reference[i] == CellClass::Outside {
            beyond_n += 1;
            beyond_occ += map[i] as usize;
        } else {
            free_n += 1;
            free_occ += map[i] as usize;
        }
    }
    let (mut found, mut present) = (0usize, 0usize);
    for (o, z) in objects.iter().zip(&zones) {
        if o.iter().any(|&c| region[c]) {
            present += 1;
            if z.iter().any(|&c| map[c]) {
                found += 1;
            }
        }
    }
    let ratio = |a: usize, b: usize| if b > 0 { a as f64 / b as f64 } else { 0.0 };
    let (p, r) = (ratio(m_hit, m_n), ratio(s_found, s_n));
    let outside_zones: Vec<bool> = region.iter().zip(&zone).map(|(&r, &z)| r && !z).collect();
    let (psi3, _, _) = psi(map, &structure, &outside_zones, rows, cols);
    ThreeClassMetrics {
        walls_found_1: r,
        precision_1: p,
        f1_1: f1(p, r),
        wrong,
        scored_cells: scored,
        free_marked_occupied: ratio(free_occ, free_n),
        free_cells: free_n,
        beyond_marked_occupied: ratio(beyond_occ, beyond_n),
        beyond_cells: beyond_n,
        objects_found: found,
        objects: present,
        structure_cells: s_n,
        map_occupied: m_n,
        psi: psi3,
    }
}

/// The structure of a reference: true where a wall or obstacle occupies the cell.
pub fn structure_cells(reference: &[crate::reference::CellClass]) -> Vec<bool> {
    reference
        .iter()
        .map(|c| *c == crate::reference::CellClass::Occupied)
        .collect()
}

/// An object's zone: its cells and the 8-neighbours of them that are not structure.
fn object_zone(cells: &[usize], structure: &[bool], rows: usize, cols: usize) -> Vec<usize> {
    let mut z = Vec::new();
    for &c in cells {
        let (r, k) = ((c / cols) as isize, (c % cols) as isize);
        for dr in -1..=1 {
            for dc in -1..=1 {
                let (rr, cc) = (r + dr, k + dc);
                if rr >= 0 && cc >= 0 && (rr as usize) < rows && (cc as usize) < cols {
                    let j = rr as usize * cols + cc as usize;
                    if !structure[j] && !z.contains(&j) {
                        z.push(j);
                    }
                }
            }
        }
    }
    z
}

/// Figures of one map against the detectable reference ([`crate::detectable`]): the wall
/// cells and objects some pose and direction could have detected, on the whole grid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DetectableMetrics {
    /// Wall cells holding a detectable return.
    pub wall_cells: usize,
    /// Of those, the share with a map occupied cell within one cell (8-neighbourhood):
    /// walls found against what the sweeps could detect.
    pub walls_found_1: f64,
    /// Wall cells in the observable region.
    pub observable_wall_cells: usize,
    /// Share of the observable region's wall cells that hold a detectable return.
    pub detectable_share_of_observable: f64,
    /// Objects with a cell holding a detectable return.
    pub objects: usize,
    /// Of those, objects with a map occupied cell in their zone (their cells and the
    /// 8-neighbours that are not structure, as the three-class figures).
    pub objects_found: usize,
}

impl DetectableMetrics {
    /// The all-free map's figures (nothing found).
    pub fn all_free(&self) -> DetectableMetrics {
        DetectableMetrics {
            walls_found_1: 0.0,
            objects_found: 0,
            ..*self
        }
    }
}

/// Figures of `map` against the detectable reference: `walls` the wall cells holding a
/// detectable return, `object_returns` the cells holding a detectable object return,
/// `objects` each object's cells, `reference` the layout's classes, `observable` the
/// observable region.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_detectable(
    map: &[bool],
    reference: &[crate::reference::CellClass],
    walls: &[bool],
    object_returns: &[bool],
    objects: &[Vec<usize>],
    observable: &[bool],
    rows: usize,
    cols: usize,
) -> DetectableMetrics {
    let structure = structure_cells(reference);
    let (mut n, mut found, mut obs, mut obs_det) = (0usize, 0usize, 0usize, 0usize);
    for i in 0..map.len() {
        if walls[i] {
            n += 1;
            found += any_in_3x3(map, rows, cols, i) as usize;
        }
        if structure[i] && observable[i] {
            obs += 1;
            obs_det += walls[i] as usize;
        }
    }
    let (mut det_objects, mut det_found) = (0usize, 0usize);
    for o in objects {
        if o.iter().any(|&c| object_returns[c]) {
            det_objects += 1;
            if object_zone(o, &structure, rows, cols)
                .iter()
                .any(|&c| map[c])
            {
                det_found += 1;
            }
        }
    }
    let ratio = |a: usize, b: usize| if b > 0 { a as f64 / b as f64 } else { 0.0 };
    DetectableMetrics {
        wall_cells: n,
        walls_found_1: ratio(found, n),
        observable_wall_cells: obs,
        detectable_share_of_observable: ratio(obs_det, obs),
        objects: det_objects,
        objects_found: det_found,
    }
}

/// A map's false cells by cause ([`crate::detectable::FalseCause`]): the free cells (room
/// or beyond the walls, outside the object zones and the boundary band, as the wrong
/// cells) marked occupied, on the whole grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct FalseCells {
    /// Free cells marked occupied.
    pub total: usize,
    /// Explained by a path in the main lobe at the cell's range, elsewhere on the arc.
    pub main_lobe_arc: usize,
    /// Explained by a path seen through a side lobe.
    pub side_lobe: usize,
    /// Explained by a path from beyond the unambiguous range, folded.
    pub folded: usize,
    /// Explained by a path whose reflection point lies beyond the walls.
    pub image: usize,
    /// Explained by no single path: noise (or weak paths adding up).
    pub noise: usize,
}

/// The false cells of `map` by cause: `reference` the layout's classes, `band` the
/// boundary band, `objects` each object's cells, `cause` each cell's cause.
pub fn false_cells_by_cause(
    map: &[bool],
    reference: &[crate::reference::CellClass],
    band: &[bool],
    objects: &[Vec<usize>],
    cause: &[crate::detectable::FalseCause],
    rows: usize,
    cols: usize,
) -> FalseCells {
    use crate::detectable::FalseCause;
    let structure = structure_cells(reference);
    let mut zone = vec![false; map.len()];
    for o in objects {
        for c in object_zone(o, &structure, rows, cols) {
            zone[c] = true;
        }
    }
    let mut f = FalseCells::default();
    for i in 0..map.len() {
        if !map[i] || structure[i] || zone[i] || band[i] {
            continue;
        }
        f.total += 1;
        match cause[i] {
            FalseCause::MainLobeArc => f.main_lobe_arc += 1,
            FalseCause::SideLobe => f.side_lobe += 1,
            FalseCause::Folded => f.folded += 1,
            FalseCause::Image => f.image += 1,
            FalseCause::Noise => f.noise += 1,
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::LayoutRaster;

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

    /// A 6 × 8 grid by hand: walls on row 0 (8 cells), one object at (3, 4), rows 4–5
    /// beyond the walls. The map marks 5 wall cells, one cell beside the object, one room
    /// cell far from both, one cell beyond the walls and the object's zone corner.
    #[test]
    fn three_class_counts_a_hand_made_grid() {
        use crate::reference::CellClass;
        let (rows, cols) = (6, 8);
        let mut reference = vec![CellClass::Free; rows * cols];
        for c in 0..cols {
            reference[c] = CellClass::Occupied;
            reference[4 * cols + c] = CellClass::Outside;
            reference[5 * cols + c] = CellClass::Outside;
        }
        let at = |r: usize, c: usize| r * cols + c;
        let objects = vec![vec![at(3, 4)]];
        let mut map = vec![false; rows * cols];
        for c in 0..5 {
            map[at(0, c)] = true; // walls 0..4 marked: found within one cell 0..5 (6 of 8)
        }
        map[at(3, 5)] = true; // beside the object: in its zone, right, not wrong
        map[at(2, 1)] = true; // room cell, 2 rows from the wall: wrong
        map[at(5, 7)] = true; // beyond the walls: wrong
        let all = vec![true; rows * cols];
        let none = vec![false; rows * cols];
        let m = evaluate_three_class(&map, &reference, &none, &objects, &all, rows, cols);
        assert_eq!(m.structure_cells, 8);
        assert!((m.walls_found_1 - 6.0 / 8.0).abs() < 1e-12);
        assert_eq!(m.map_occupied, 8);
        // right: the 5 wall cells and the cell beside the object
        assert!((m.precision_1 - 6.0 / 8.0).abs() < 1e-12);
        assert!((m.f1_1 - 0.75).abs() < 1e-12);
        // wrong: 3 walls missed + the room cell + the beyond cell; the zone (9 cells, row 4
        // beyond the walls included) is not scored
        assert_eq!(m.wrong, 5);
        assert_eq!(m.scored_cells, 48 - 9);
        // room free cells: rows 1–3 (24) less the zone's 6 there
        assert_eq!(m.free_cells, 18);
        assert!((m.free_marked_occupied - 1.0 / 18.0).abs() < 1e-12);
        // beyond: rows 4–5 (16) less the zone's 3 on row 4
        assert_eq!(m.beyond_cells, 13);
        assert!((m.beyond_marked_occupied - 1.0 / 13.0).abs() < 1e-12);
        assert_eq!((m.objects_found, m.objects), (1, 1));
        // the all-free map: every wall wrong, nothing else
        let free = vec![false; rows * cols];
        let f = evaluate_three_class(&free, &reference, &none, &objects, &all, rows, cols);
        assert_eq!((f.wrong, f.objects_found, f.map_occupied), (8, 0, 0));
        assert_eq!(f.f1_1, 0.0);
        // a region without the object's cell: the object is not counted
        let mut top = vec![false; rows * cols];
        for c in 0..cols {
            top[at(0, c)] = true;
            top[at(1, c)] = true;
        }
        let t = evaluate_three_class(&map, &reference, &none, &objects, &top, rows, cols);
        assert_eq!((t.objects, t.objects_found), (0, 0));
        assert_eq!(t.wrong, 3);
        // ψ: the walls marked exactly plus the object — zero with the object's zone left
        // out (three-class), not zero when the object counts as a false occupied cell
        let structure = structure_cells(&reference);
        let mut exact = structure.clone();
        exact[at(3, 4)] = true;
        let e = evaluate_three_class(&exact, &reference, &none, &objects, &all, rows, cols);
        assert_eq!(e.psi, 0.0);
        let (layout_only, _, _) = psi(&exact, &structure, &all, rows, cols);
        assert!(layout_only > 0.3, "{layout_only}");
        // a false room cell raises the three-class ψ too; the all-free map's occupied term
        // is the diameter
        exact[at(2, 1)] = true;
        let w = evaluate_three_class(&exact, &reference, &none, &objects, &all, rows, cols);
        // occupied: 8 wall cells at 0 and the false cell 2 rows from the wall (the object's
        // zone left out), 2/9; free: the false cell's own is 1 from the map's nearest free
        // cell, over the 31 reference free cells outside the zone
        assert!(
            (w.psi - (2.0 / 9.0 + 1.0 / 31.0)).abs() < 1e-12,
            "{}",
            w.psi
        );
    }

    /// The boundary band: a 4 m × 2 m room whose walls lie on the grid lines of a 0.1 m grid.
    /// The rasteriser gives the top and right walls to the cells beyond them, the bottom and
    /// left walls to the room's cells. A map of the room's rim (the cells just inside every
    /// wall) and a map of the cells just outside every wall are both the walls found
    /// exactly (the room's rim misses 3 of the 4 convex corner cells: the rasteriser gives
    /// the corner point to the cell above or to the right of it, and that cell's neighbour
    /// across the line is itself a wall cell, not band); without the band the rim scores
    /// each top and right wall cell twice (missed, and its room neighbour marked): 118 and
    /// 122 wrong cells of 120.
    #[test]
    fn a_wall_on_a_grid_line_is_found_by_either_cell_beside_it() {
        use crate::campaign::layout::Layout;
        use crate::reference::CellClass;
        let room = r#"{"type":"FeatureCollection","features":[
          {"type":"Feature","properties":{"role":"perimeter","material":"concrete"},
           "geometry":{"type":"Polygon","coordinates":[[[0,0],[4,0],[4,2],[0,2],[0,0]]]}}]}"#;
        let layout = Layout::from_geojson(room, std::path::Path::new("room.geojson")).unwrap();
        let reference = layout.rasterize(0.1, 0.5);
        let spec = reference.spec;
        let (rows, cols) = (spec.rows, spec.cols);
        let band = layout.edge_band(&reference);
        // the band: one row or column beside each wall and the corner cells the walls
        // touch at a point, less the cells two walls share (120 in all)
        let nb = band.iter().filter(|b| **b).count();
        assert_eq!(nb, 120, "band cells");
        let structure = reference.count(CellClass::Occupied);
        // rim cells: centre inside the room within 0.1 m of a wall, or outside it within
        // 0.1 m of the room's rectangle
        let rim = |inside: bool| -> Vec<bool> {
            (0..rows * cols)
                .map(|i| {
                    let p = spec.center(i / cols, i % cols);
                    let is_in = p.x > 0.0 && p.x < 4.0 && p.y > 0.0 && p.y < 2.0;
                    let near = if is_in {
                        p.x.min(4.0 - p.x).min(p.y).min(2.0 - p.y) < 0.1
                    } else {
                        p.x > -0.1 && p.x < 4.1 && p.y > -0.1 && p.y < 2.1
                    };
                    is_in == inside && near
                })
                .collect()
        };
        let all = vec![true; rows * cols];
        let none = vec![false; rows * cols];
        let objects: Vec<Vec<usize>> = Vec::new();
        for inside in [true, false] {
            let map = rim(inside);
            let with =
                evaluate_three_class(&map, &reference.cells, &band, &objects, &all, rows, cols);
            let without =
                evaluate_three_class(&map, &reference.cells, &none, &objects, &all, rows, cols);
            eprintln!(
                "rim inside={inside}: wrong {} with the band, {} without; structure {structure}, band {nb}",
                with.wrong, without.wrong
            );
            assert_eq!(
                with.wrong,
                if inside { 3 } else { 0 },
                "rim inside={inside}: {} wrong with the band",
                with.wrong
            );
            assert!(
                without.wrong >= 2 * 55,
                "rim inside={inside}: {} wrong without the band",
                without.wrong
            );
            assert_eq!(with.walls_found_1, 1.0);
            assert_eq!(with.free_marked_occupied, 0.0);
            assert_eq!(with.beyond_marked_occupied, 0.0);
        }
        // the all-free map: every structure cell wrong, band or not
        let free = vec![false; rows * cols];
        let f = evaluate_three_class(&free, &reference.cells, &band, &objects, &all, rows, cols);
        assert_eq!(f.wrong, structure);
        assert_eq!(f.structure_cells, structure);
    }
}
