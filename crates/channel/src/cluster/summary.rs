//! Per-cluster summaries: members, centroid delay and angles (member means), first arrival
//! (smallest delay), reference ray (strongest member) delay and angle, total power
//! (10·log10 Σ 10^{p/10}), centroid x/y in the global frame (member mean). The global
//! centroid angle is the pose heading plus the members' mean relative angle, wrapped into
//! (−180°, 180°].

use crate::mpc::Mpc;
use crate::units::{db, wrap_deg};

/// A cluster summary row.
#[derive(Debug, Clone, PartialEq)]
pub struct ClusterSummary {
    /// Position.
    pub position: usize,
    /// Campaign-wide cluster id.
    pub cluster_id: usize,
    /// Members.
    pub members: usize,
    /// Mean delay, ns.
    pub centroid_delay_ns: f64,
    /// Mean relative angle, deg.
    pub centroid_angle_rel_deg: f64,
    /// Mean global angle (members' mean offset added to the pose heading), deg.
    pub centroid_angle_global_deg: f64,
    /// Smallest delay, ns.
    pub first_arrival_ns: f64,
    /// Strongest member's delay, ns.
    pub ref_delay_ns: f64,
    /// Strongest member's relative angle, deg.
    pub ref_angle_rel_deg: f64,
    /// Total power, dB.
    pub power_db: f64,
    /// Centroid x, m.
    pub centroid_x_m: f64,
    /// Centroid y, m.
    pub centroid_y_m: f64,
}

impl ClusterSummary {
    /// The summary of cluster `cluster_id` at `position` from its (non-empty) `members`;
    /// `heading_deg` is the pose heading (None: taken from the first member's angles).
    pub(crate) fn of(
        position: usize,
        cluster_id: usize,
        members: &[&Mpc],
        heading_deg: Option<f64>,
    ) -> ClusterSummary {
        let n = members.len() as f64;
        let mean = |g: &dyn Fn(&Mpc) -> f64| members.iter().map(|m| g(m)).sum::<f64>() / n;
        let strongest = members
            .iter()
            .max_by(|a, b| a.power_db.total_cmp(&b.power_db))
            .expect("non-empty");
        let arel = mean(&|m| m.angle_rel_deg);
        let heading = heading_deg.unwrap_or(members[0].angle_global_deg - members[0].angle_rel_deg);
        ClusterSummary {
            position,
            cluster_id,
            members: members.len(),
            centroid_delay_ns: mean(&|m| m.delay_ns),
            centroid_angle_rel_deg: arel,
            centroid_angle_global_deg: wrap_deg(heading + arel),
            first_arrival_ns: members
                .iter()
                .map(|m| m.delay_ns)
                .fold(f64::INFINITY, f64::min),
            ref_delay_ns: strongest.delay_ns,
            ref_angle_rel_deg: strongest.angle_rel_deg,
            power_db: db(members
                .iter()
                .map(|m| 10f64.powf(m.power_db / 10.0))
                .sum::<f64>()),
            centroid_x_m: mean(&|m| m.x_m),
            centroid_y_m: mean(&|m| m.y_m),
        }
    }
}
