//! Geometry of the perimeter statistics (d_p, d_c): where a cluster is, how far it lies
//! from the perimeter and where along it, which part of the perimeter a pose observes, and
//! the spacings along the observed part.
//!
//! Takes the layout, the poses, the scan (sector and delay window) and per-cluster ranges
//! and bearings; gives cluster locations ([`cluster_location`]), their arc-length
//! coordinate and signed offset ([`perimeter_offset`]), the scan's [`Interior`], the
//! observed stretches of perimeter ([`observed_stretches`]), the spacings along them
//! ([`stretch_spacings`]) and the block length of the position bootstrap
//! ([`bootstrap_block`]).
//!
//! * Location: the members' mean range c·τ/2 along the reference (strongest) ray's
//!   bearing. The reference ray defines the cluster's direction (the AoA offsets are
//!   measured from it) and the mean range is the members' mean depth. The members' own mean
//!   bearing is not used: with a Laplacian spread of std σ_φ over n rays it scatters by
//!   about σ_φ/√n, with half of the spread outside a scanned half-plane unseen; the
//!   reference bearing puts the location on the true centre whenever every member is seen.
//! * Offset: distance to the closest perimeter edge (projection onto the layout
//!   perimeter), negative for a location beyond the perimeter. A location is a noisy
//!   estimate, so the signed offset is kept for the mean (folding or flooring the noise at
//!   the wall biases it up, errors-in-variables) and the folded one, counted as on the
//!   wall, for the families.
//! * Interior: the scanned sector less max(20°, 2·b̂₀) at each edge (the AoA's margin, at
//!   most a quarter of the sector) and the detection range c·max_delay/2 less 1.5 m (at
//!   most half of it). A cluster straddling the sector edge or the end of the delay window
//!   is seen in part and its location is off, so the perimeter statistics keep the
//!   clusters located in it and cut the observed perimeter the same way.
//! * Observed stretches: the perimeter sampled every 0.1 m, the runs of samples in the
//!   interior and in line of sight. DESIGN §2 drops the largest gap as the unobserved one;
//!   that holds in a convex room seen as one stretch, but a pose in a corridor sees two
//!   stretches (one per wall).
//! * Spacings: gaps between neighbours inside one stretch are complete; the gaps at the
//!   stretch ends are censored, so the mean spacing is the censored exponential MLE
//!   Σ L / Σ k (observed length over the clusters in it).
//!
//! Measurements behind these choices: `docs/fit.md`.

use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Manifest, Pose};
use crate::units::range_m;
use geo::Coord;

/// Arc-length step (m) at which the perimeter's visibility from a pose is sampled.
pub const OBSERVED_STEP_M: f64 = 0.1;

/// A cluster's location seen from `pose`: the mean range `range` (m) of its members along
/// the bearing `reference_rel_deg` (degrees relative to the heading) of its reference
/// (strongest) ray.
pub fn cluster_location(pose: &Pose, range: f64, reference_rel_deg: f64) -> Coord<f64> {
    let th = (pose.heading_deg + reference_rel_deg).to_radians();
    Coord {
        x: pose.x_m + range * th.cos(),
        y: pose.y_m + range * th.sin(),
    }
}

/// Where a location lies with respect to the perimeter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerimeterOffset {
    /// Arc-length coordinate of its projection on the perimeter, m.
    pub arc_m: f64,
    /// Distance to the perimeter, m, negative beyond it.
    pub signed_m: f64,
    /// The offset with a location beyond the perimeter counted as on the wall (0), floored
    /// at 1 mm (for the positive families).
    pub folded_m: f64,
}

/// The projection of `at` on the perimeter of `layout` and its signed and folded offsets.
/// A location estimated beyond the perimeter is a noisy estimate of a cluster at the wall
/// (nothing is seen through it): its folded offset is 0, not the distance.
pub fn perimeter_offset(layout: &Layout, at: Coord<f64>) -> PerimeterOffset {
    let (arc_m, dist) = layout.project_to_perimeter(at);
    let inside = layout.inside_perimeter(at);
    PerimeterOffset {
        arc_m,
        signed_m: if inside { dist } else { -dist },
        folded_m: if inside { dist } else { 0.0 }.max(1e-3),
    }
}

/// Block length of the position bootstrap: consecutive positions of a walk see the same
/// clusters (a cluster's rays are one object's), so whole positions are resampled in
/// circular blocks of consecutive positions. L = the mean, over positions, of the run of
/// positions from it onward (itself included) that stay within twice the detection range
/// r = c·max_delay/2 of it (two poses 2r apart can both see a cluster between them), at
/// most a third of the positions (at least 1). Poses in random order in a space much larger
/// than 2r give L ≈ 1, the ordinary bootstrap of positions; in a room smaller than 2r every
/// pose is within reach of every other and L is a third of the positions.
pub fn bootstrap_block(m: &Manifest) -> usize {
    let r_max = range_m(m.processing.max_delay_ns);
    let n = m.poses.len();
    if n == 0 {
        return 1;
    }
    let runs: usize = (0..n)
        .map(|i| {
            let a = &m.poses[i];
            m.poses[i..]
                .iter()
                .take_while(|b| (b.x_m - a.x_m).hypot(b.y_m - a.y_m) <= 2.0 * r_max)
                .count()
        })
        .sum();
    let mean = (runs as f64 / n as f64).round() as usize;
    mean.clamp(1, (n / 3).max(1))
}

/// The interior of what a pose observes, for the perimeter statistics (d_p, d_c): the
/// scanned sector shrunk at each edge by max(20°, 2·b̂₀) (20°: the zone where CLEAN fits
/// edge signatures; 2·b̂₀: the AoA's margin; at most a quarter of the sector) and the
/// detection range c·max_delay/2 shrunk by 1.5 m (10 ns of delay; at most half the range).
/// A cluster straddling the sector edge or the end of the delay window is seen only in
/// part: its reference ray and mean range, hence its location, are off. Clusters located
/// outside the interior are left out of d_p and d_c, and the observed perimeter is cut the
/// same way.
///
/// Why the AoA's margin: a cluster whose own reference ray lies beyond the sector edge is
/// seen through its other rays, and the strongest of those sits at a Laplacian offset from
/// the cluster's bearing, so the location along it is off. The margin is estimated from
/// each fit's own clusters, so the chain and `fit --truth` (the "same estimators" of
/// Table 1's truth column) cut their interiors where their own AoA spreads put them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interior {
    /// Lower edge of the sector, degrees relative to the heading.
    pub lo_deg: f64,
    /// Upper edge of the sector, degrees relative to the heading.
    pub hi_deg: f64,
    /// Range, m.
    pub range_m: f64,
}

impl Interior {
    /// The interior with the sector shrunk by max(20°, `aoa_margin_deg`) at each edge (at
    /// most a quarter of the sector).
    pub fn of(m: &Manifest, aoa_margin_deg: f64) -> Interior {
        let (lo, hi) = (m.directions.start_deg, m.directions.stop_deg);
        let g = 20f64.max(aoa_margin_deg).min((hi - lo) / 4.0);
        let r_max = range_m(m.processing.max_delay_ns);
        Interior {
            lo_deg: lo + g,
            hi_deg: hi - g,
            range_m: r_max - 1.5f64.min(r_max / 2.0),
        }
    }

    /// Whether a bearing (degrees relative to the heading) and range (m) lie inside.
    pub fn contains(&self, rel_deg: f64, range_m: f64) -> bool {
        rel_deg >= self.lo_deg && rel_deg <= self.hi_deg && range_m <= self.range_m
    }
}

/// The stretches of the perimeter observed from `pose`: maximal runs of arc-length samples
/// (every `step_m`) that lie in the [`Interior`] of the scan (sector and range) and in line
/// of sight. Each stretch is (start, end) in arc length with end ≥ start. The scan starts at
/// an unseen sample, so both ends of a run may lie in [P, 2P) (a run through the origin
/// ends beyond it and stays one stretch); callers unwrap the arcs into [start, start + P).
/// The whole perimeter seen is (0, P).
pub fn observed_stretches(
    layout: &Layout,
    pose: &Pose,
    region: &Interior,
    step_m: f64,
) -> Vec<(f64, f64)> {
    let total = layout.perimeter_length();
    let n = (total / step_m).ceil().max(1.0) as usize;
    let ds = total / n as f64;
    let from = Coord {
        x: pose.x_m,
        y: pose.y_m,
    };
    let seen: Vec<bool> = (0..n)
        .map(|i| {
            let (q, _) = layout.perimeter_point((i as f64 + 0.5) * ds);
            let d = q - from;
            let rel = crate::units::wrap_deg(d.y.atan2(d.x).to_degrees() - pose.heading_deg);
            region.contains(rel, d.x.hypot(d.y)) && !layout.occluded(from, q, 0.05)
        })
        .collect();
    if seen.iter().all(|&v| v) {
        return vec![(0.0, total)];
    }
    // start the scan at an unseen sample, so no run is cut by the origin
    let first_unseen = seen.iter().position(|&v| !v).unwrap_or(0);
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for j in 1..=n {
        let i = first_unseen + j;
        if seen[i % n] {
            start.get_or_insert(i);
        } else if let Some(a) = start.take() {
            out.push((a as f64 * ds, i as f64 * ds));
        }
    }
    out
}

/// Spacings along the observed perimeter: the clusters' arc-length coordinates `arcs`
/// falling in each stretch, sorted; the gaps between neighbours in one stretch are complete
/// (returned as samples); the stretch ends cut the gaps beyond its first and last cluster
/// (censored). Returns (complete gaps, Σ stretch length, clusters in the stretches). An
/// empty stretch is exposure without an arrival. For spacings that are exponential,
/// Σ L / Σ k is the censored MLE of the mean spacing: each stretch is an exposure of
/// length L holding k arrivals.
pub fn stretch_spacings(
    arcs: &[f64],
    stretches: &[(f64, f64)],
    total: f64,
) -> (Vec<f64>, f64, usize) {
    let mut gaps = Vec::new();
    let (mut length, mut count) = (0.0, 0);
    for &(a, b) in stretches {
        let mut inside: Vec<f64> = arcs
            .iter()
            .map(|&s| if s < a { s + total } else { s })
            .filter(|&s| s >= a && s <= b)
            .collect();
        length += b - a;
        inside.sort_by(f64::total_cmp);
        gaps.extend(inside.windows(2).map(|w| w[1] - w[0]).filter(|g| *g > 1e-6));
        // the whole perimeter seen: the gap through the origin is complete too
        if b - a >= total && inside.len() >= 2 {
            gaps.push(inside[0] + total - inside[inside.len() - 1]);
        }
        count += inside.len();
    }
    (gaps, length, count)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::campaign::manifest::Campaign;

    /// The 16 m × 10 m hall (`data/tests/hall.geojson`), half-plane scan in 2° steps,
    /// 80 ns of delay, `poses` poses at the centre facing +x; the folder keeps the files.
    pub(crate) fn hall_at_centre(poses: usize) -> (tempfile::TempDir, Campaign) {
        let dir = tempfile::tempdir().unwrap();
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        std::fs::copy(
            root.join("../../data/tests/hall.geojson"),
            dir.path().join("hall.geojson"),
        )
        .unwrap();
        let toml = "schema_version = 1\nname = \"hall\"\nlayout = \"hall.geojson\"\nseed = 1\n\
                    [band]\nstart_hz = 57.5e9\nstop_hz = 63.5e9\npoints = 801\n\
                    [array]\nelements = 16\n\
                    [directions]\nstart_deg = -90.0\nstop_deg = 90.0\nstep_deg = 2.0\n\
                    [noise]\nfloor_dbm = -100.0\n\
                    [processing]\nmax_delay_ns = 80.0\n"
            .to_string()
            + &"[[poses]]\nx_m = 0.0\ny_m = 0.0\nheading_deg = 0.0\n".repeat(poses);
        std::fs::write(dir.path().join("campaign.toml"), toml).unwrap();
        let c = Campaign::load(&dir.path().join("campaign.toml")).unwrap();
        (dir, c)
    }

    #[test]
    fn censored_spacing_recovers_the_mean_where_complete_gaps_do_not() {
        use rand::{Rng, SeedableRng};
        // clusters at exponential spacings (mean 5 m) along a 5 km perimeter, observed
        // through 300 windows of 12 m: the complete gaps are short-biased, Σ L / Σ k is not
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let total = 5000.0;
        let mut arcs = Vec::new();
        let mut s = 0.0;
        loop {
            s += -5.0 * (1.0 - rng.gen::<f64>()).ln();
            if s >= total {
                break;
            }
            arcs.push(s);
        }
        let stretches: Vec<(f64, f64)> = (0..300)
            .map(|i| (i as f64 * 16.0, i as f64 * 16.0 + 12.0))
            .collect();
        let (gaps, l, k) = stretch_spacings(&arcs, &stretches, total);
        let censored = l / k as f64;
        let complete = gaps.iter().sum::<f64>() / gaps.len() as f64;
        assert!(
            (censored - 5.0).abs() < 0.5,
            "censored mean spacing {censored}"
        );
        assert!(complete < 4.2, "complete gaps are short-biased: {complete}");
        // a stretch through the origin, and the whole perimeter (its wrap gap complete)
        let (g, l, k) = stretch_spacings(&[9.0, 2.0], &[(7.0, 15.0)], 10.0);
        assert_eq!((g.len(), l, k), (1, 8.0, 2));
        assert!((g[0] - 3.0).abs() < 1e-12);
        let (mut g, l, k) = stretch_spacings(&[1.0, 4.0], &[(0.0, 10.0)], 10.0);
        g.sort_by(f64::total_cmp);
        assert_eq!((g, l, k), (vec![3.0, 7.0], 10.0, 2));
    }

    #[test]
    fn interior_margin_is_the_larger_of_20_degrees_and_the_aoa_margin_capped() {
        // half-plane scan: 20° wins below it, the AoA margin above it, a quarter of the
        // sector (45°) at most; the range margin is 1.5 m of the 12 m detection range
        let (_dir, c) = hall_at_centre(1);
        for (margin, edge) in [(0.0, 70.0), (12.0, 70.0), (31.5, 58.5), (80.0, 45.0)] {
            let i = Interior::of(&c.manifest, margin);
            assert!((i.lo_deg + edge).abs() < 1e-12 && (i.hi_deg - edge).abs() < 1e-12);
            assert!(i.contains(edge - 0.1, 10.0) && !i.contains(edge + 0.1, 10.0));
        }
        let i = Interior::of(&c.manifest, 0.0);
        assert!((i.range_m - (range_m(c.manifest.processing.max_delay_ns) - 1.5)).abs() < 1e-12);
    }

    #[test]
    fn observed_perimeter_of_a_pose_in_the_hall() {
        // 16 m × 10 m hall, pose at the centre facing +x, half-plane scan, 12 m range: the
        // interior (±70°, 10.5 m) sees the right wall (10 m) and x ≥ 5/tan 70° of the top
        // and bottom walls (2 × 6.18 m), as one stretch
        let (_dir, c) = hall_at_centre(1);
        let layout = Layout::load(&c.layout_path()).unwrap();
        let st = observed_stretches(
            &layout,
            &c.manifest.poses[0],
            &Interior::of(&c.manifest, 0.0),
            0.1,
        );
        assert_eq!(st.len(), 1, "{st:?}");
        let want = 10.0 + 2.0 * (8.0 - 5.0 / 70f64.to_radians().tan());
        let got = st[0].1 - st[0].0;
        assert!((got - want).abs() < 0.3, "observed {got} m, want {want} m");
        // facing the right wall from 1 m: the ±70° interior sees 2·tan 70° of it, and none
        // of the side walls
        let mut m = c.manifest.clone();
        m.poses[0].x_m = 7.0;
        let st = observed_stretches(&layout, &m.poses[0], &Interior::of(&m, 0.0), 0.1);
        let got: f64 = st.iter().map(|s| s.1 - s.0).sum();
        let want = 2.0 * 70f64.to_radians().tan();
        assert!(
            (got - want).abs() < 0.3,
            "observed {got} m from 1 m off the wall, want {want}"
        );
    }
}
