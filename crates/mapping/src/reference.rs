//! The reference map a layout gives the mappers: the grid geometry ([`GridSpec`]) and the
//! layout rasterised on it ([`ReferenceMap`]), with the band of cells a wall only touches.
//!
//! Takes a [`Layout`] and a cell size (0.1 m by default, over the bounding box plus a margin).
//! A cell is `Occupied` if any wall segment passes through it (half-open cells: a wall on a
//! grid line belongs to the cell above or to the right) or its centre lies inside an
//! obstacle, `Free` if its centre is inside the perimeter (and not occupied), and `Outside`
//! otherwise (beyond the walls: never observable, reported separately by the metrics).

use crate::campaign::layout::Layout;
use geo::{Contains, Coord, Intersects, Line, Point, Rect};

/// Class of a reference-map cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellClass {
    /// Free space inside the perimeter.
    Free,
    /// A wall or obstacle passes through the cell.
    Occupied,
    /// Beyond the perimeter.
    Outside,
}

/// A regular grid over the plane: cell (row, col) spans
/// [x0 + col·cell, x0 + (col+1)·cell) × [y0 + row·cell, y0 + (row+1)·cell); row 0 is the
/// southern (lowest y) row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridSpec {
    /// x of the grid's lower-left corner, m.
    pub x0_m: f64,
    /// y of the grid's lower-left corner, m.
    pub y0_m: f64,
    /// Cell side, m.
    pub cell_m: f64,
    /// Columns (x).
    pub cols: usize,
    /// Rows (y).
    pub rows: usize,
}

impl GridSpec {
    /// Grid over `rect` plus `margin_m` on every side. Cells are half-open, so the
    /// rectangle's upper edges must lie strictly inside the grid: with no margin a wall on
    /// the bounding box's right or top edge would otherwise fall just outside it (one
    /// column or row is added there; any margin above 1e-9 of a cell leaves the grid as
    /// it was).
    pub fn covering(rect: Rect<f64>, cell_m: f64, margin_m: f64) -> GridSpec {
        let x0 = rect.min().x - margin_m;
        let y0 = rect.min().y - margin_m;
        // n·cell ≥ extent + 2·margin − 1e-9·cell, so one added cell is always enough
        let count = |extent: f64, lo: f64, hi: f64| {
            let n = ((extent + 2.0 * margin_m) / cell_m - 1e-9).ceil() as usize;
            n.saturating_add(usize::from(lo + n as f64 * cell_m <= hi))
        };
        let cols = count(rect.width(), x0, rect.max().x);
        let rows = count(rect.height(), y0, rect.max().y);
        GridSpec {
            x0_m: x0,
            y0_m: y0,
            cell_m,
            cols,
            rows,
        }
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.rows * self.cols
    }
    /// True for an empty grid.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Centre of cell `(row, col)`.
    pub fn center(&self, row: usize, col: usize) -> Coord<f64> {
        Coord {
            x: self.x0_m + (col as f64 + 0.5) * self.cell_m,
            y: self.y0_m + (row as f64 + 0.5) * self.cell_m,
        }
    }
    /// Cell containing a point, if inside the grid.
    pub fn cell_of(&self, p: Coord<f64>) -> Option<(usize, usize)> {
        let c = ((p.x - self.x0_m) / self.cell_m).floor();
        let r = ((p.y - self.y0_m) / self.cell_m).floor();
        if c < 0.0 || r < 0.0 || c as usize >= self.cols || r as usize >= self.rows {
            None
        } else {
            Some((r as usize, c as usize))
        }
    }
}

/// The reference map rasterised from a layout.
#[derive(Debug, Clone)]
pub struct ReferenceMap {
    /// Grid geometry.
    pub spec: GridSpec,
    /// Row-major classes (row 0 = lowest y).
    pub cells: Vec<CellClass>,
}

impl ReferenceMap {
    /// Count of cells of a class.
    pub fn count(&self, class: CellClass) -> usize {
        self.cells.iter().filter(|c| **c == class).count()
    }
}

/// The reference map of a layout (the layout is a format of the layer below; its raster
/// belongs to the mappers, so it is a trait here).
pub trait LayoutRaster {
    /// Rasterise to the reference map over the bounding box plus `margin_m`.
    fn rasterize(&self, cell_m: f64, margin_m: f64) -> ReferenceMap;
    /// Rasterise on a given grid: a cell is occupied when a wall crosses it or its centre
    /// lies in an obstacle, free when its centre is inside the perimeter, outside otherwise.
    fn rasterize_on(&self, spec: GridSpec) -> ReferenceMap;
    /// The cells a wall touches only along their edge or at a corner (the boundary band;
    /// the implementation's docs say which).
    fn edge_band(&self, reference: &ReferenceMap) -> Vec<bool>;
}

impl LayoutRaster for Layout {
    fn rasterize(&self, cell_m: f64, margin_m: f64) -> ReferenceMap {
        self.rasterize_on(GridSpec::covering(self.bbox(), cell_m, margin_m))
    }

    fn rasterize_on(&self, spec: GridSpec) -> ReferenceMap {
        let cell_m = spec.cell_m;
        let lines: Vec<Line<f64>> = self.walls.iter().map(|w| w.line).collect();
        let mut cells = vec![CellClass::Outside; spec.len()];
        for r in 0..spec.rows {
            for c in 0..spec.cols {
                let lo = Coord {
                    x: spec.x0_m + c as f64 * cell_m,
                    y: spec.y0_m + r as f64 * cell_m,
                };
                // half-open cells: a wall exactly on a grid line belongs to the cell above/right
                let eps = 1e-9 * cell_m.max(1.0);
                let rect = Rect::new(
                    Coord {
                        x: lo.x - eps,
                        y: lo.y - eps,
                    },
                    Coord {
                        x: lo.x + cell_m - eps,
                        y: lo.y + cell_m - eps,
                    },
                )
                .to_polygon();
                let centre = spec.center(r, c);
                let occupied = lines.iter().any(|l| rect.intersects(l))
                    || self
                        .obstacles
                        .iter()
                        .any(|o| o.polygon.contains(&Point::from(centre)));
                cells[r * spec.cols + c] = if occupied {
                    CellClass::Occupied
                } else if self.perimeter.contains(&Point::from(centre)) {
                    CellClass::Free
                } else {
                    CellClass::Outside
                };
            }
        }
        ReferenceMap { spec, cells }
    }

    /// The cells a wall touches only along their edge or at a corner (the boundary band):
    /// a cell whose closed square meets a wall that its half-open square (the
    /// [`LayoutRaster::rasterize_on`] rule) does not cross. A wall lying exactly on a grid line is
    /// as near to the cell on either side of it; the rasteriser gives it to the cell above
    /// or to the right, and this band is the cell on the other side. The three-class scoring
    /// ([`crate::metrics::evaluate_three_class`]) treats the two alike, so its
    /// figures do not depend on that tie-break along a wall (at a convex corner the cell
    /// the corner point is given to keeps a wall cell, not a band cell, across each
    /// line: there the tie-break still counts). Only cells with a reference wall cell among
    /// their 8 neighbours can be in the band; `reference` is this layout rasterised on
    /// `reference.spec`.
    fn edge_band(&self, reference: &ReferenceMap) -> Vec<bool> {
        let spec = reference.spec;
        let cell_m = spec.cell_m;
        let eps = 1e-9 * cell_m.max(1.0);
        let lines: Vec<Line<f64>> = self.walls.iter().map(|w| w.line).collect();
        let occupied =
            |r: usize, c: usize| reference.cells[r * spec.cols + c] == CellClass::Occupied;
        let mut band = vec![false; spec.len()];
        for r in 0..spec.rows {
            for c in 0..spec.cols {
                if occupied(r, c) {
                    continue;
                }
                let near_wall = (r.saturating_sub(1)..(r + 2).min(spec.rows)).any(|rr| {
                    (c.saturating_sub(1)..(c + 2).min(spec.cols)).any(|cc| occupied(rr, cc))
                });
                if !near_wall {
                    continue;
                }
                let lo = Coord {
                    x: spec.x0_m + c as f64 * cell_m,
                    y: spec.y0_m + r as f64 * cell_m,
                };
                let closed = Rect::new(
                    Coord {
                        x: lo.x - eps,
                        y: lo.y - eps,
                    },
                    Coord {
                        x: lo.x + cell_m + eps,
                        y: lo.y + cell_m + eps,
                    },
                )
                .to_polygon();
                band[r * spec.cols + c] = lines.iter().any(|l| closed.intersects(l));
            }
        }
        band
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A 4 × 2 m concrete room with a 0.2 m pillar (the layout's tests use it too).
    const SQUARE: &str = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/tests/square.geojson"
    ));

    #[test]
    fn raster_classes() {
        let l = Layout::from_geojson(SQUARE, Path::new("t.geojson")).unwrap();
        let m = l.rasterize(0.1, 0.3);
        assert_eq!(m.spec.cols, 46);
        let at = |x: f64, y: f64| {
            let (r, c) = m.spec.cell_of(Coord { x, y }).unwrap();
            m.cells[r * m.spec.cols + c]
        };
        assert_eq!(at(1.0, 1.0), CellClass::Free);
        assert_eq!(at(2.0, 1.0), CellClass::Occupied);
        assert_eq!(at(0.05, 1.0), CellClass::Occupied);
        assert_eq!(at(-0.2, 1.0), CellClass::Outside);
    }

    /// Without a margin the walls on the bounding box's right and top edges are still
    /// rasterised: the same wall cells as with a margin (which only adds outside cells).
    #[test]
    fn a_grid_without_margin_keeps_the_outer_walls() {
        let l = Layout::from_geojson(SQUARE, Path::new("t.geojson")).unwrap();
        let walls = |m: &ReferenceMap| {
            let mut v: Vec<(i64, i64)> = (0..m.spec.len())
                .filter(|&i| m.cells[i] == CellClass::Occupied)
                .map(|i| {
                    let c = m.spec.center(i / m.spec.cols, i % m.spec.cols);
                    ((c.x * 1e3).round() as i64, (c.y * 1e3).round() as i64)
                })
                .collect();
            v.sort();
            v
        };
        let (bare, wide) = (l.rasterize(0.1, 0.0), l.rasterize(0.1, 0.3));
        let b = l.bbox();
        assert!(
            bare.spec.cell_of(b.max()).is_some(),
            "top-right corner off the grid"
        );
        assert_eq!(walls(&bare), walls(&wide));
        // the margin of the other tests is unchanged: 4 m + 2 × 0.3 m in 0.1 m cells
        assert_eq!(wide.spec.cols, 46);
        assert_eq!(bare.spec.cols, 41);
    }
}
