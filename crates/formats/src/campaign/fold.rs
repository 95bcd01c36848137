//! The sweep's unambiguous range, and whether the building reaches beyond it.
//!
//! Takes a manifest (band, poses) and its layout; gives the largest distance from a pose to
//! the layout's walls ([`Reach`]) and, when it exceeds the unambiguous range, the warning
//! `import` and `energy` print and the report shows ([`fold_warning`]).
//!
//! A sweep of N points over bandwidth B steps by Δf = B/(N − 1); its (zero-padded) IFFT is
//! periodic in delay with period 1/Δf, so an echo from range d reads at range d mod R_u with
//!
//!   R_u = c / (2 Δf) = c (N − 1) / (2 B)            (801 points over 6 GHz: 19.99 m).
//!
//! A wall farther than R_u from some pose sends echoes that fold back into the delays the
//! chain keeps, at their folded range and the level of their true path loss. The points
//! that would cover the building are the fewest N with R_u ≥ the reach:
//! N = ⌈2 B · reach / c⌉ + 1. The reach is measured to the walls' end points (the farthest
//! point of a segment from a pose is one of its ends), through walls: an occluded far wall
//! still folds its diffracted and multi-bounce energy, and the layout cannot say which.

use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Band, Manifest};
use crate::units::C0;

/// The unambiguous range c/(2Δf) of a band's sweep, m.
pub fn unambiguous_range_m(band: &Band) -> f64 {
    C0 / (2.0 * band.step_hz())
}

/// The fewest sweep points over `band`'s bandwidth whose unambiguous range reaches `range_m`.
pub fn points_covering(band: &Band, range_m: f64) -> usize {
    (2.0 * band.bandwidth_hz() * range_m / C0).ceil() as usize + 1
}

/// How far the layout reaches from the campaign's poses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// The largest pose-to-wall distance, m.
    pub range_m: f64,
    /// The pose it is measured from (index).
    pub pose: usize,
}

impl Reach {
    /// The largest distance from any pose to any wall end point (`None` without poses or
    /// walls).
    pub fn of(manifest: &Manifest, layout: &Layout) -> Option<Reach> {
        let mut best: Option<Reach> = None;
        for (i, p) in manifest.poses.iter().enumerate() {
            for w in &layout.walls {
                for end in [w.line.start, w.line.end] {
                    let d = (end.x - p.x_m).hypot(end.y - p.y_m);
                    if best.is_none_or(|b| d > b.range_m) {
                        best = Some(Reach {
                            range_m: d,
                            pose: i,
                        });
                    }
                }
            }
        }
        best
    }
}

/// The warning for a campaign whose layout reaches beyond its sweep's unambiguous range:
/// it names the reach (and the pose), its round trip, R_u with the band and point count,
/// and the points that would cover the building. `None` when everything is within R_u.
pub fn fold_warning(manifest: &Manifest, layout: &Layout) -> Option<String> {
    let reach = Reach::of(manifest, layout)?;
    let band = &manifest.band;
    let ru = unambiguous_range_m(band);
    (reach.range_m > ru).then(|| {
        format!(
            "the layout reaches {:.1} m from position {} (round trip {:.0} ns), beyond the \
             sweep's unambiguous range {:.1} m (c/(2Δf): {} points over {:.2} GHz): echoes \
             from farther fold back into the kept delays at their range modulo {:.1} m; \
             {} points over the same band would cover the building",
            reach.range_m,
            manifest.label(reach.pose),
            2.0 * reach.range_m / C0 * 1e9,
            ru,
            band.points,
            band.bandwidth_hz() / 1e9,
            ru,
            points_covering(band, reach.range_m)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn band(points: usize) -> Band {
        Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points,
        }
    }

    #[test]
    fn the_unambiguous_range_of_801_points_over_6_ghz_is_20_m() {
        let ru = unambiguous_range_m(&band(801));
        assert!((ru - 299_792_458.0 * 800.0 / 12e9).abs() < 1e-9);
        assert!((ru - 19.986).abs() < 1e-3);
        // 3201 points: four times the range
        assert!((unambiguous_range_m(&band(3201)) - 4.0 * ru).abs() < 1e-9);
    }

    #[test]
    fn the_points_covering_a_range_are_the_fewest_that_reach_it() {
        for range in [5.0, 19.9, 20.1, 70.0, 133.0] {
            let b = band(801);
            let n = points_covering(&b, range);
            let with = |n: usize| unambiguous_range_m(&Band { points: n, ..b });
            assert!(with(n) >= range, "{range}: {n} points reach {}", with(n));
            assert!(with(n - 1) < range, "{range}: {} points suffice", n - 1);
        }
    }

    /// The long hall (120 m × 12 m) read at 801 and at 401 points from its centre: the
    /// warning names the reach (√(60² + 6²) = 60.3 m), the range and the points that cover
    /// it, and a room within the range gets none.
    #[test]
    fn a_layout_beyond_the_unambiguous_range_is_named_with_the_points_that_cover_it() {
        use crate::campaign::manifest::Campaign;
        let data = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/tests");
        let dir = tempfile::tempdir().unwrap();
        for f in ["long_hall.geojson", "room.geojson"] {
            std::fs::copy(format!("{data}/{f}"), dir.path().join(f)).unwrap();
        }
        let text = std::fs::read_to_string(format!("{data}/point_target.toml")).unwrap();
        let text = text.split("[scene]").next().unwrap().to_string();
        let load = |layout: &str, points: usize| {
            let t = text
                .replace("\"room.geojson\"", &format!("\"{layout}\""))
                .replace("points = 401", &format!("points = {points}"));
            let path = dir.path().join("campaign.toml");
            std::fs::write(&path, t).unwrap();
            let c = Campaign::load(&path).unwrap();
            let l = Layout::load(&c.layout_path()).unwrap();
            fold_warning(&c.manifest, &l)
        };
        let w = load("long_hall.geojson", 801).expect("60 m is beyond 20 m");
        let reach = 60f64.hypot(6.0);
        assert!(w.contains(&format!("reaches {reach:.1} m")), "{w}");
        assert!(w.contains("unambiguous range 20.0 m"), "{w}");
        assert!(w.contains("801 points over 6.00 GHz"), "{w}");
        let n = points_covering(
            &Band {
                start_hz: 57.5e9,
                stop_hz: 63.5e9,
                points: 801,
            },
            reach,
        );
        assert!(w.contains(&format!("{n} points over the same band")), "{w}");
        assert_eq!(n, (2.0 * 6e9 * reach / C0).ceil() as usize + 1);
        // at enough points the same hall is within range
        assert_eq!(load("long_hall.geojson", n), None);
        // the 20 m room seen from its centre: 14.1 m to a corner, within 20.0 m at 801 points
        // but not within 10.0 m at 401
        assert!(load("room.geojson", 801).is_none());
        assert!(load("room.geojson", 401).is_some());
    }
}
