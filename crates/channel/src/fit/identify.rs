//! Which Table 1 quantities a campaign identifies: the rule of Table 1's closed-loop
//! column ("not identifiable from this campaign").
//!
//! Takes, per quantity, the written value with the campaign's 95 % position-bootstrap
//! interval, and the chain's readings of the same quantity on R campaigns drawn from the
//! written model over the campaign's own poses (`closed_loop`, the layer above: `synth`
//! → `extract` → `cluster` → the fit's estimators, each draw with its own interval);
//! gives an [`Identification`]: the readings' median, how many draws the chain read it
//! in, how many of their intervals cover the written value, and the verdict.
//!
//! **The rule** (one, stated; no constant): the campaign identifies a quantity when the
//! chain, given the written model as the truth, reads it back inside the campaign's own
//! 95 % interval [lo, hi] on the median of the draws:
//!
//!   identifiable ⇔ lo ≤ median_r(θ̃_r) ≤ hi,
//!
//! θ̃_r the chain's reading on draw r (θ̃ = ∞, a Γ read as "no excess decay", sorts above
//! every number: it is inside only an interval reaching ∞). Otherwise the chain's own bias
//! at this model and on these poses (the median's distance from the written value) is
//! larger than what the campaign resolves, and the value is a reading of the chain, not of
//! the channel: "not identifiable from this campaign". A quantity without an interval is not
//! identifiable (but a written Γ = ∞ without one, every resample having read no excess
//! decay, has the interval [∞, ∞]), nor is one the chain read in fewer than half the draws.
//! The text names how many readings fell beyond that end.
//!
//! What "identifiable" does and does not say: that the chain's bias at this model fits
//! inside the campaign's interval, not that the interval is narrow; a wide interval passes
//! more easily, so Table 1 shows the median reading beside the interval.
//!
//! Why this rule and not DESIGN's "posterior narrower than the prior": the estimator the
//! held-out check chose is the chain (docs/zoo.md, "Estimators held out"), which has no
//! prior; its failure mode, measured by the closed-loop coverage (docs/fit.md), is bias
//! (clusters merged), not spread, and the position bootstrap's interval measures only the
//! spread. The median of R draws decides, not each draw, so the verdict follows the bias;
//! where the bias sits near an end of the interval it can move with the draws' seed
//! (measured on the corridor: the median of 4 draws of the AoA std moved between 12.8° and
//! 21.8° with the seed, across the interval's lower end 13.1°; of 6 draws, between 13.8°
//! and 19.4°), so the median is shown beside the verdict. A sign test on the draws beyond
//! an end (measured, not kept; docs/fit.md) needs every one of 6 draws beyond it at
//! α = 0.05 and called "identifiable" a d_p read 48× above its interval's top on the zoo.
//! The interval count is shown beside, not used.

use crate::model::file::Quantity;

/// One draw's reading of a quantity: the chain's value and its 95 % interval (`None`
/// when the chain could not estimate it on that draw).
pub type Reading = Option<(f64, Option<[f64; 2]>)>;

/// Why a quantity is or is not identifiable (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// The draws' median reading lies inside the campaign's interval.
    ReadBack,
    /// It lies beyond one end: above it (else below), `count` readings beyond that end.
    Beyond {
        /// Above the interval's upper end (else below its lower end).
        above: bool,
        /// Readings beyond that end.
        count: usize,
    },
    /// The campaign's fit gave no 95 % interval.
    NoInterval,
    /// The chain read it in fewer than half the draws.
    FewReadings,
}

/// The closed loop's verdict on one quantity (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Identification {
    /// Draws R.
    pub draws: usize,
    /// Draws in which the chain estimated the quantity.
    pub read: usize,
    /// Draws whose 95 % interval covers the written value.
    pub covered: usize,
    /// Median of the readings (NaN when none).
    pub median: f64,
    /// The rule's verdict and its reason.
    pub verdict: Verdict,
}

impl Identification {
    /// Whether the campaign identifies it (the chain reads it back inside the interval).
    pub fn identifiable(&self) -> bool {
        self.verdict == Verdict::ReadBack
    }

    /// The verdict as Table 1 shows it, values in `unit`.
    pub fn shown(&self, unit: &str) -> String {
        let (r, c) = (self.draws, self.covered);
        let median = match self.median {
            m if m.is_infinite() => "∞".to_string(),
            m => format!("{m:.3} {unit}"),
        };
        let cover = format!("{c}/{r} of their own intervals cover the written value");
        match self.verdict {
            Verdict::ReadBack => format!(
                "read back: {r} draws of the written model read {median} (median), inside the interval; {cover}"
            ),
            Verdict::Beyond { above, count } => {
                let end = if above { "above" } else { "below" };
                format!(
                    "not identifiable from this campaign: {r} draws of the written model read {median} (median), {end} the interval ({count} of {} {end}); {cover}",
                    self.read
                )
            }
            Verdict::NoInterval => {
                "not identifiable from this campaign: the position bootstrap gave no 95 % interval"
                    .to_string()
            }
            Verdict::FewReadings => format!(
                "not identifiable from this campaign: the chain read it in {} of {r} draws of the written model",
                self.read
            ),
        }
    }
}

/// The rule (module docs) for the written quantity `q` and the chain's readings on the
/// draws of the written model; `None` when `q` was not estimated (its row already says
/// why). A written Γ = ∞ without an interval (every resample read no excess decay:
/// `fit::quantities`) has the interval [∞, ∞].
pub fn identify(q: &Quantity, readings: &[Reading]) -> Option<Identification> {
    if !q.is_estimable() || q.value.is_nan() {
        return None;
    }
    let draws = readings.len();
    let mut values: Vec<f64> = readings.iter().flatten().map(|r| r.0).collect();
    values.retain(|v| !v.is_nan());
    values.sort_by(f64::total_cmp);
    let read = values.len();
    // ∞ is inside only an interval reaching ∞
    let inside = |v: f64, [lo, hi]: [f64; 2]| lo <= v && v <= hi;
    let covered = (readings.iter().flatten())
        .filter(|r| r.1.is_some_and(|iv| inside(q.value, iv)))
        .count();
    let median = match read {
        0 => f64::NAN,
        n if n % 2 == 1 => values[n / 2],
        // the mean of ∞ and a number is ∞; of −∞ and ∞ it is not a number
        n if values[n / 2 - 1].is_infinite() || values[n / 2].is_infinite() => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    };
    let interval = match q.interval {
        None if q.value == f64::INFINITY => Some([f64::INFINITY; 2]),
        iv => iv,
    };
    let verdict = match interval {
        None => Verdict::NoInterval,
        Some(_) if 2 * read < draws || read == 0 => Verdict::FewReadings,
        Some([_, hi]) if median > hi => Verdict::Beyond {
            above: true,
            count: values.iter().filter(|&&v| v > hi).count(),
        },
        Some([lo, _]) if median < lo => Verdict::Beyond {
            above: false,
            count: values.iter().filter(|&&v| v < lo).count(),
        },
        Some(_) => Verdict::ReadBack,
    };
    Some(Identification {
        draws,
        read,
        covered,
        median,
        verdict,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(value: f64, iv: Option<[f64; 2]>) -> Quantity {
        Quantity {
            interval: iv,
            ..Quantity::new(value, "1/ns", "exponential")
        }
    }

    fn plain(values: &[f64]) -> Vec<Reading> {
        values.iter().map(|&v| Some((v, None))).collect()
    }

    #[test]
    fn the_median_reading_inside_the_interval_decides() {
        let written = q(0.5, Some([0.4, 0.6]));
        // biased draws, one of whose intervals still covers 0.5: not identifiable
        let mut biased = plain(&[0.8, 0.85, 0.9, 0.5]);
        biased[1] = Some((0.85, Some([0.45, 0.95])));
        biased.push(None);
        let id = identify(&written, &biased).unwrap();
        assert_eq!((id.draws, id.read, id.covered), (5, 4, 1));
        assert!((id.median - 0.825).abs() < 1e-12);
        assert!(!id.identifiable());
        assert_eq!(
            id.verdict,
            Verdict::Beyond {
                above: true,
                count: 3
            }
        );
        let shown = id.shown("1/ns");
        assert!(
            shown.starts_with("not identifiable from this campaign: 5 draws of the written model read 0.825 1/ns (median), above the interval (3 of 4 above); 1/5"),
            "{shown}"
        );
        // below the lower end, the same
        let id = identify(&written, &plain(&[0.1, 0.2, 0.45])).unwrap();
        assert_eq!(
            id.verdict,
            Verdict::Beyond {
                above: false,
                count: 2
            }
        );
        // the ends are inside
        assert!(identify(&written, &plain(&[0.6, 0.6, 0.9]))
            .unwrap()
            .identifiable());
        // readings around the written value: identifiable even where no interval covers
        let near = [
            Some((0.45, Some([0.44, 0.46]))),
            Some((0.55, Some([0.54, 0.56]))),
            Some((0.5, None)),
        ];
        let id = identify(&written, &near).unwrap();
        assert!(id.identifiable());
        assert_eq!((id.covered, id.median), (0, 0.5));
        assert!(id.shown("1/ns").starts_with("read back: 3 draws of the written model read 0.500 1/ns (median), inside the interval; 0/3"));
    }

    #[test]
    fn too_few_readings_no_interval_infinity_and_stated_values() {
        let written = q(0.5, Some([0.4, 0.6]));
        let id = identify(&written, &[Some((0.5, None)), None, None]).unwrap();
        assert_eq!(id.verdict, Verdict::FewReadings);
        assert!(id.shown("1/ns").contains("read it in 1 of 3"));
        let id = identify(&q(0.5, None), &plain(&[0.5])).unwrap();
        assert_eq!(id.verdict, Verdict::NoInterval);
        // Γ = ∞ inside an interval reaching ∞, and without an interval (every resample
        // read ∞); above a finite one
        let inf = plain(&[f64::INFINITY; 3]);
        let gamma = q(f64::INFINITY, Some([30.0, f64::INFINITY]));
        assert!(identify(&gamma, &inf).unwrap().identifiable());
        let gamma = q(f64::INFINITY, None);
        assert!(identify(&gamma, &inf).unwrap().identifiable());
        assert_eq!(
            identify(&gamma, &plain(&[40.0, 50.0, 60.0]))
                .unwrap()
                .verdict,
            Verdict::Beyond {
                above: false,
                count: 3
            }
        );
        let finite = q(40.0, Some([30.0, 60.0]));
        let id = identify(&finite, &inf).unwrap();
        assert!(!id.identifiable() && id.median.is_infinite());
        assert!(id.shown("ns").contains("read ∞ (median)"));
        // even counts: the mean of the middle two, ∞ when one is
        assert_eq!(
            identify(&finite, &plain(&[35.0, 45.0])).unwrap().median,
            40.0
        );
        let id = identify(&finite, &plain(&[35.0, f64::INFINITY])).unwrap();
        assert!(id.median.is_infinite());
        // a stated (not estimated) value has no verdict
        let mut stated = q(0.5, None);
        stated.not_estimable = Some("no clusters".into());
        assert!(identify(&stated, &inf).is_none());
    }
}
