//! Indoor layout (DESIGN §3): GeoJSON polygons in metres, read with the georust crates.
//!
//! Takes a GeoJSON `FeatureCollection` whose features carry `properties.role`:
//! `"perimeter"` (exactly one polygon: the walls bounding the free space) or `"obstacle"`
//! (pillars, cabinets, door frames: polygons inside or touching the perimeter); optional
//! `properties.material` (a key of the simulator's material table) and `properties.name`.
//! Gives walls (segments), corners, occlusion tests, perimeter arc-length coordinates
//! (used by the clutter model and the perimeter statistics). The reference occupancy raster
//! the maps are scored on is [`crate::mapping::reference`].

use crate::error::{Error, Result};
use geo::{
    BoundingRect, Contains, Coord, Euclidean, InterpolatePoint, Line, LineLocatePoint, Point,
    Polygon, Rect, Winding,
};
use geojson::GeoJson;
use std::path::Path;

/// Which polygon a wall belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WallKind {
    /// The outer perimeter.
    Perimeter,
    /// Obstacle number `i`.
    Obstacle(usize),
}

/// One straight wall segment.
#[derive(Debug, Clone)]
pub struct Wall {
    /// The segment, m.
    pub line: Line<f64>,
    /// Material key.
    pub material: String,
    /// Owner.
    pub kind: WallKind,
}

impl Wall {
    /// Length, m.
    pub fn length(&self) -> f64 {
        let d = self.line.delta();
        d.x.hypot(d.y)
    }
    /// Unit normal pointing into the free space.
    pub fn normal(&self) -> Coord<f64> {
        let d = self.line.delta();
        let l = d.x.hypot(d.y);
        // perimeter is counter-clockwise: free space on the left; obstacles are made
        // counter-clockwise too, free space on their right (outside)
        match self.kind {
            WallKind::Perimeter => Coord {
                x: -d.y / l,
                y: d.x / l,
            },
            WallKind::Obstacle(_) => Coord {
                x: d.y / l,
                y: -d.x / l,
            },
        }
    }
}

/// An obstacle polygon.
#[derive(Debug, Clone)]
pub struct Obstacle {
    /// Name from the GeoJSON properties (or `obstacle<i>`).
    pub name: String,
    /// Material key.
    pub material: String,
    /// Polygon, counter-clockwise.
    pub polygon: Polygon<f64>,
}

/// An indoor layout.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Outer perimeter, counter-clockwise.
    pub perimeter: Polygon<f64>,
    /// Perimeter material key.
    pub perimeter_material: String,
    /// Obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Every wall segment (perimeter first, in ring order, then obstacles).
    pub walls: Vec<Wall>,
}

fn prop_str(f: &geojson::Feature, key: &str) -> Option<String> {
    f.property(key).and_then(|v| v.as_str()).map(str::to_string)
}

/// Largest |coordinate| of a layout, m: a building fits in 10 km; larger values are a
/// unit mistake (millimetres, degrees of latitude turned metres) and would make grids of
/// billions of cells.
pub const MAX_COORD_M: f64 = 1e4;

/// Every position of a (Multi)Polygon geometry has 2 or 3 finite numbers (x, y[, z]):
/// checked on the GeoJSON value, before geo's conversion, which assumes it.
fn check_positions(v: &geojson::GeometryValue, path: &Path, i: usize) -> Result<()> {
    let rings: Vec<&Vec<geojson::Position>> = match v {
        geojson::GeometryValue::Polygon { coordinates } => coordinates.iter().collect(),
        geojson::GeometryValue::MultiPolygon { coordinates } => {
            coordinates.iter().flatten().collect()
        }
        _ => return Ok(()),
    };
    for (r, ring) in rings.into_iter().enumerate() {
        for (k, pos) in ring.iter().enumerate() {
            if !(2..=3).contains(&pos.len()) {
                return Err(Error::input(
                    path,
                    format!(
                        "features[{i}].geometry.coordinates[{r}][{k}]: a position needs 2 numbers (x, y in m), got {}",
                        pos.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A layout polygon is usable: finite coordinates within ±[`MAX_COORD_M`], no holes (an
/// enclosed region is drawn as an obstacle feature), a simple ring (no self-intersection)
/// and a non-zero area.
fn check_polygon(poly: &Polygon<f64>, path: &Path, i: usize) -> Result<()> {
    use geo::{Area, Validation};
    let at = |msg: String| Error::input(path, format!("features[{i}].geometry: {msg}"));
    if let Some(c) = poly
        .exterior()
        .0
        .iter()
        .chain(poly.interiors().iter().flat_map(|r| r.0.iter()))
        .find(|c| !(c.x.abs() <= MAX_COORD_M && c.y.abs() <= MAX_COORD_M))
    {
        return Err(at(format!(
            "coordinate ({}, {}) beyond ±{MAX_COORD_M} m (coordinates are metres)",
            c.x, c.y
        )));
    }
    if !poly.interiors().is_empty() {
        return Err(at(
            "polygon with a hole: holes are not supported (draw the enclosed region as an obstacle feature)".into(),
        ));
    }
    if let Some(e) = poly.validation_errors().into_iter().next() {
        return Err(at(format!("not a simple polygon ({e})")));
    }
    let area = poly.unsigned_area();
    if area.is_nan() || area <= 1e-6 {
        return Err(at("polygon of zero area".into()));
    }
    Ok(())
}

/// A wall's normal-incidence point seen from a pose ([`Layout::feet`]): where a
/// monostatic radar sees that wall's mirror image of itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Foot {
    /// Wall index (into [`Layout::walls`]).
    pub wall: usize,
    /// The normal-incidence point, m.
    pub pos: Coord<f64>,
    /// Distance pose → foot, m.
    pub d_m: f64,
    /// Global bearing of the foot from the pose, rad.
    pub bearing: f64,
}

impl Layout {
    /// The walls whose normal-incidence point `at` sees, in wall order: the foot of the
    /// perpendicular from `at` onto the wall's line lies on the segment, `at` is on the
    /// wall's free side and at least 5 cm away, and the segment `at` → foot crosses no
    /// wall (1 mm slack). The image method's specular returns (the simulator's and the
    /// statistical model's) come from these.
    pub fn feet(&self, at: Coord<f64>) -> Vec<Foot> {
        let mut out = Vec::new();
        for (wi, w) in self.walls.iter().enumerate() {
            let dl = w.line.delta();
            let l2 = dl.x * dl.x + dl.y * dl.y;
            if l2 <= 0.0 {
                continue;
            }
            let t = ((at.x - w.line.start.x) * dl.x + (at.y - w.line.start.y) * dl.y) / l2;
            if !(0.0..=1.0).contains(&t) {
                continue;
            }
            let foot = w.line.start + dl * t;
            let n = w.normal();
            let v = at - foot;
            let d = v.x.hypot(v.y);
            if d < 0.05 || v.x * n.x + v.y * n.y <= 0.0 || self.occluded(at, foot, 1e-3) {
                continue;
            }
            out.push(Foot {
                wall: wi,
                pos: foot,
                d_m: d,
                bearing: (-v.y).atan2(-v.x),
            });
        }
        out
    }

    /// Read a layout GeoJSON file.
    pub fn load(path: &Path) -> Result<Layout> {
        let text = crate::io::read_text(path)?;
        Self::from_geojson(&text, path)
    }

    /// Parse GeoJSON text (`path` names the source in errors).
    pub fn from_geojson(text: &str, path: &Path) -> Result<Layout> {
        let gj: GeoJson = text
            .parse()
            .map_err(|e| Error::input(path, format!("not valid GeoJSON: {e}")))?;
        let fc = match gj {
            GeoJson::FeatureCollection(fc) => fc,
            _ => return Err(Error::input(path, "expected a GeoJSON FeatureCollection")),
        };
        let mut perimeter: Option<(Polygon<f64>, String)> = None;
        let mut obstacles = Vec::new();
        for (i, f) in fc.features.iter().enumerate() {
            let role = prop_str(f, "role").ok_or_else(|| {
                Error::input(
                    path,
                    format!("features[{i}].properties.role missing (perimeter|obstacle)"),
                )
            })?;
            let geom = f
                .geometry
                .as_ref()
                .ok_or_else(|| Error::input(path, format!("features[{i}].geometry missing")))?;
            check_positions(&geom.value, path, i)?;
            let mut poly: Polygon<f64> = Polygon::try_from(geom).map_err(|e| {
                Error::input(
                    path,
                    format!("features[{i}].geometry must be a Polygon: {e}"),
                )
            })?;
            if poly.exterior().0.len() < 4 {
                return Err(Error::input(
                    path,
                    format!("features[{i}].geometry: polygon needs at least 3 vertices"),
                ));
            }
            if poly
                .exterior()
                .0
                .iter()
                .any(|c| !c.x.is_finite() || !c.y.is_finite())
            {
                return Err(Error::input(
                    path,
                    format!("features[{i}].geometry: non-finite coordinate"),
                ));
            }
            check_polygon(&poly, path, i)?;
            poly.exterior_mut(|r| r.make_ccw_winding());
            let material = prop_str(f, "material").unwrap_or_else(|| "default".into());
            match role.as_str() {
                "perimeter" => {
                    if perimeter.is_some() {
                        return Err(Error::input(path, format!("features[{i}]: more than one perimeter")));
                    }
                    perimeter = Some((poly, material));
                }
                "obstacle" => obstacles.push(Obstacle {
                    name: prop_str(f, "name").unwrap_or_else(|| format!("obstacle{}", obstacles.len())),
                    material,
                    polygon: poly,
                }),
                other => {
                    return Err(Error::input(
                        path,
                        format!("features[{i}].properties.role: unknown role `{other}` (perimeter|obstacle)"),
                    ))
                }
            }
        }
        let (perimeter, perimeter_material) =
            perimeter.ok_or_else(|| Error::input(path, "no feature with role \"perimeter\""))?;
        let mut walls = Vec::new();
        for line in perimeter.exterior().lines() {
            walls.push(Wall {
                line,
                material: perimeter_material.clone(),
                kind: WallKind::Perimeter,
            });
        }
        for (i, o) in obstacles.iter().enumerate() {
            for line in o.polygon.exterior().lines() {
                walls.push(Wall {
                    line,
                    material: o.material.clone(),
                    kind: WallKind::Obstacle(i),
                });
            }
        }
        walls.retain(|w| w.length() > 1e-9);
        Ok(Layout {
            perimeter,
            perimeter_material,
            obstacles,
            walls,
        })
    }

    /// Bounding box of the perimeter and obstacles.
    pub fn bbox(&self) -> Rect<f64> {
        let mut r = self.perimeter.bounding_rect().expect("validated polygon");
        for o in &self.obstacles {
            if let Some(b) = o.polygon.bounding_rect() {
                r = Rect::new(
                    Coord {
                        x: r.min().x.min(b.min().x),
                        y: r.min().y.min(b.min().y),
                    },
                    Coord {
                        x: r.max().x.max(b.max().x),
                        y: r.max().y.max(b.max().y),
                    },
                );
            }
        }
        r
    }

    /// True if `p` lies inside the perimeter polygon (obstacles not considered).
    pub fn inside_perimeter(&self, p: Coord<f64>) -> bool {
        self.perimeter.contains(&Point::from(p))
    }

    /// True if `p` is in free space (inside the perimeter, outside every obstacle).
    pub fn is_free(&self, p: Coord<f64>) -> bool {
        let pt = Point::from(p);
        self.perimeter.contains(&pt) && !self.obstacles.iter().any(|o| o.polygon.contains(&pt))
    }

    /// Vertices of the perimeter and of the obstacles (corners, door frames, object edges),
    /// with the index of the owning obstacle (None for the perimeter).
    pub fn corners(&self) -> Vec<(Coord<f64>, Option<usize>)> {
        let mut v: Vec<(Coord<f64>, Option<usize>)> = Vec::new();
        let ring = &self.perimeter.exterior().0;
        for c in &ring[..ring.len() - 1] {
            v.push((*c, None));
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            let ring = &o.polygon.exterior().0;
            for c in &ring[..ring.len() - 1] {
                v.push((*c, Some(i)));
            }
        }
        v
    }

    /// True if the straight path from `from` to `to` is blocked by a wall before reaching
    /// within `tol_m` of `to` (so points on a wall are visible from its free side).
    pub fn occluded(&self, from: Coord<f64>, to: Coord<f64>, tol_m: f64) -> bool {
        let ray = Line::new(from, to);
        let d = to - from;
        let len = d.x.hypot(d.y);
        if len <= tol_m {
            return false;
        }
        self.walls.iter().any(
            |w| match geo::line_intersection::line_intersection(ray, w.line) {
                Some(geo::LineIntersection::SinglePoint { intersection, .. }) => {
                    let e = intersection - from;
                    e.x.hypot(e.y) < len - tol_m && e.x.hypot(e.y) > 1e-9
                }
                Some(geo::LineIntersection::Collinear { .. }) => false,
                None => false,
            },
        )
    }

    /// The first wall met by the ray from `from` along the global angle `angle_rad`, beyond
    /// 1 mm: (range m, index into [`Layout::walls`], |cos| of the incidence angle measured
    /// from the wall normal). None when the ray leaves the layout without meeting a wall.
    pub fn first_hit(&self, from: Coord<f64>, angle_rad: f64) -> Option<(f64, usize, f64)> {
        let u = Coord {
            x: angle_rad.cos(),
            y: angle_rad.sin(),
        };
        let mut best: Option<(f64, usize, f64)> = None;
        for (i, w) in self.walls.iter().enumerate() {
            let d = w.line.delta();
            let den = u.x * d.y - u.y * d.x;
            if den.abs() < 1e-12 {
                continue;
            }
            let q = w.line.start - from;
            let t = (q.x * d.y - q.y * d.x) / den;
            let s = (q.x * u.y - q.y * u.x) / den;
            if t > 1e-3 && (0.0..=1.0).contains(&s) && best.is_none_or(|b| t < b.0) {
                let l = d.x.hypot(d.y);
                best = Some((t, i, (den / l).abs()));
            }
        }
        best
    }

    /// Total perimeter length, m.
    pub fn perimeter_length(&self) -> f64 {
        self.walls
            .iter()
            .filter(|w| w.kind == WallKind::Perimeter)
            .map(Wall::length)
            .sum()
    }

    /// The perimeter walls in ring order (counter-clockwise).
    fn perimeter_walls(&self) -> impl Iterator<Item = &Wall> {
        self.walls.iter().filter(|w| w.kind == WallKind::Perimeter)
    }

    /// Point at arc length `s` (m, modulo the perimeter length) along the counter-clockwise
    /// perimeter, with the inward unit normal of that edge.
    ///
    /// Walks the walls to the one holding `s`, then interpolates on it with geo's Euclidean
    /// `point_at_ratio_between` (the successor of `LineInterpolatePoint`). Not the
    /// `LineString` form: it takes a fraction of the total length (`s/total·total` rounds,
    /// so the simulator's bytes would move) and does not say which edge, whose normal we need.
    pub fn perimeter_point(&self, s: f64) -> (Coord<f64>, Coord<f64>) {
        let total = self.perimeter_length();
        let mut s = s.rem_euclid(total);
        let mut last = None;
        for w in self.perimeter_walls() {
            let l = w.length();
            if s <= l {
                let p = Euclidean.point_at_ratio_between(
                    w.line.start_point(),
                    w.line.end_point(),
                    s / l,
                );
                return (p.0, w.normal());
            }
            s -= l;
            last = Some(w);
        }
        let w = last.expect("perimeter has walls");
        (w.line.end, w.normal())
    }

    /// Project a point onto the perimeter: (arc length of the closest point, distance).
    ///
    /// Per wall, geo's `LineLocatePoint` gives the clamped fraction t of the foot point; the
    /// arc length is accumulated here in metres (geo's `LineString` form returns a fraction
    /// of the total instead, with different rounding). A non-finite point matches no wall.
    pub fn project_to_perimeter(&self, p: Coord<f64>) -> (f64, f64) {
        let mut best = (0.0, f64::INFINITY);
        let mut s0 = 0.0;
        for w in self.perimeter_walls() {
            let d = w.line.delta();
            // √(dx² + dy²), not `Wall::length`'s hypot: the arc lengths stay bit-for-bit
            let l = (d.x * d.x + d.y * d.y).sqrt();
            if let Some(t) = w.line.line_locate_point(&Point::from(p)) {
                let q =
                    Euclidean.point_at_ratio_between(w.line.start_point(), w.line.end_point(), t);
                let dist = (p.x - q.x()).hypot(p.y - q.y());
                if dist < best.1 {
                    best = (s0 + t * l, dist);
                }
            }
            s0 += l;
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 2 m concrete room with a 0.2 m pillar (also the reference raster's tests').
    const SQUARE: &str = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/tests/square.geojson"
    ));

    #[test]
    fn parses_and_orients() {
        let l = Layout::from_geojson(SQUARE, Path::new("t.geojson")).unwrap();
        assert_eq!(l.walls.len(), 8);
        assert!((l.perimeter_length() - 12.0).abs() < 1e-12);
        // inward normal of every perimeter wall points to the centre
        for w in l.walls.iter().filter(|w| w.kind == WallKind::Perimeter) {
            let mid = w.line.start + w.line.delta() * 0.5;
            let n = w.normal();
            assert!(l.is_free(Coord {
                x: mid.x + 0.3 * n.x,
                y: mid.y + 0.3 * n.y
            }));
        }
    }

    #[test]
    fn occlusion_by_pillar() {
        let l = Layout::from_geojson(SQUARE, Path::new("t.geojson")).unwrap();
        assert!(l.occluded(Coord { x: 0.5, y: 1.0 }, Coord { x: 4.0, y: 1.0 }, 1e-3));
        assert!(!l.occluded(Coord { x: 0.5, y: 0.5 }, Coord { x: 4.0, y: 0.5 }, 1e-3));
    }

    #[test]
    fn projection_round_trip() {
        let l = Layout::from_geojson(SQUARE, Path::new("t.geojson")).unwrap();
        for s in [0.3, 2.5, 5.0, 7.7, 11.0] {
            let (p, n) = l.perimeter_point(s);
            let q = Coord {
                x: p.x + 0.2 * n.x,
                y: p.y + 0.2 * n.y,
            };
            let (s2, d) = l.project_to_perimeter(q);
            assert!(
                (s2 - s).abs() < 1e-9 && (d - 0.2).abs() < 1e-9,
                "{s}: {s2} {d}"
            );
        }
    }

    /// Values of the hand-written projection this module had before it used geo's
    /// `LineLocatePoint` / Euclidean interpolation, on a skewed pentagon and the corridor.
    #[test]
    #[allow(clippy::approx_constant)] // recorded values, not constants
    fn perimeter_matches_the_hand_written_projection() {
        const PENTAGON: &str = r#"{"type":"FeatureCollection","features":[
          {"type":"Feature","properties":{"role":"perimeter"},
           "geometry":{"type":"Polygon","coordinates":[[[0,0],[3.7,0.4],[4.2,2.9],[1.3,3.6],[-0.5,1.8],[0,0]]]}}]}"#;
        type Points = &'static [(f64, [f64; 4])];
        type Projections = &'static [([f64; 2], f64, f64)];
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
        let corridor =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/corridor/layout.geojson");
        let cases: [(Layout, f64, Points, Projections); 2] = [
            (
                Layout::from_geojson(PENTAGON, Path::new("t.geojson")).unwrap(),
                13.668093929515843,
                &[
                    (0.0, [0.0, 0.0, -0.10748184298009182, 0.9942070475658493]),
                    (
                        0.3,
                        [
                            0.29826211426975474,
                            0.03224455289402754,
                            -0.10748184298009182,
                            0.9942070475658493,
                        ],
                    ),
                    (
                        2.5,
                        [
                            2.4855176189146233,
                            0.26870460745022956,
                            -0.10748184298009182,
                            0.9942070475658493,
                        ],
                    ),
                    (
                        3.7185,
                        [
                            3.6969589063736104,
                            0.3996712331214714,
                            -0.10748184298009182,
                            0.9942070475658493,
                        ],
                    ),
                    (
                        5.0,
                        [
                            3.950722944559498,
                            1.6536147227974887,
                            -0.9805806756909202,
                            0.19611613513818404,
                        ],
                    ),
                    (
                        7.7,
                        [
                            2.8109611796083867,
                            3.2352852325083203,
                            -0.23464053310389685,
                            -0.9720822085732869,
                        ],
                    ),
                    (
                        11.0,
                        [
                            0.06564282904102381,
                            2.3656428290410236,
                            0.7071067811865476,
                            -0.7071067811865476,
                        ],
                    ),
                    (
                        13.9,
                        [
                            0.23056264964865203,
                            0.02492569185390833,
                            -0.10748184298009182,
                            0.9942070475658493,
                        ],
                    ),
                    (
                        -1.2,
                        [
                            -0.3211726365433132,
                            1.1562214915559275,
                            0.9635179096299405,
                            0.2676438637860946,
                        ],
                    ),
                ],
                &[
                    ([1.0, 1.0], 1.101688890545941, 0.8867252045857574),
                    ([2.0, 0.5], 2.0421550166217446, 0.282139837822741),
                    ([3.9, 2.0], 5.3297111213187875, 0.11766968108291044),
                    ([-1.0, -1.0], 0.0, 1.4142135623730951),
                    ([0.7, 3.0], 10.102883485441188, 1.1102230246251565e-16),
                    ([5.0, 5.0], 6.271068569982072, 2.247220505424423),
                ],
            ),
            (
                Layout::load(&corridor).unwrap(),
                31.700000000000003,
                &[
                    (0.0, [-1.0, -1.0, -0.0, 1.0]),
                    (0.3, [-0.7, -1.0, -0.0, 1.0]),
                    (2.5, [1.5, -1.0, -0.0, 1.0]),
                    (3.7185, [2.7185, -1.0, -0.0, 1.0]),
                    (5.0, [4.0, -1.0, -0.0, 1.0]),
                    (7.7, [6.7, -1.0, -0.0, 1.0]),
                    (11.0, [7.5, -3.5, -0.0, 1.0]),
                    (13.9, [8.6, -1.6999999999999993, -1.0, 0.0]),
                    (-1.2, [-1.0, 0.19999999999999396, 1.0, 0.0]),
                ],
                &[
                    ([1.0, 1.0], 27.700000000000003, 0.0),
                    ([2.0, 0.5], 26.700000000000003, 0.5),
                    ([3.9, 2.0], 24.450000000000003, 0.6499999999999999),
                    ([-1.0, -1.0], 0.0, 0.0),
                    ([0.7, 3.0], 28.000000000000004, 2.0),
                    ([5.0, 5.0], 24.450000000000003, 3.8121516234273787),
                ],
            ),
        ];
        for (l, total, points, projections) in cases {
            assert!(close(l.perimeter_length(), total));
            for &(s, [x, y, nx, ny]) in points {
                let (p, n) = l.perimeter_point(s);
                assert!(
                    close(p.x, x) && close(p.y, y) && close(n.x, nx) && close(n.y, ny),
                    "perimeter_point({s}) = {p:?}, {n:?}"
                );
            }
            for &([x, y], s, d) in projections {
                let (s2, d2) = l.project_to_perimeter(Coord { x, y });
                assert!(
                    close(s2, s) && close(d2, d),
                    "project({x}, {y}) = {s2}, {d2}"
                );
            }
        }
    }

    #[test]
    fn bad_geojson_names_field() {
        let e = Layout::from_geojson(r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":null}]}"#, Path::new("x.geojson")).unwrap_err();
        assert!(
            e.to_string().contains("x.geojson") && e.to_string().contains("role"),
            "{e}"
        );
    }
}
