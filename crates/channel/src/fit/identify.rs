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
//! the channel: "not identifiable from this campaign". A quantity without an interval (too
//! few positions to resample) is not identifiable, nor is one the chain read in fewer than
//! half the draws. The reason names how many readings fell beyond that end.
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
    /// The rule's verdict.
    pub identifiable: bool,
    /// Why not identifiable (`None` when identifiable).
    pub reason: Option<String>,
}

impl Identification {
    /// The verdict as Table 1 shows it.
    pub fn shown(&self, unit: &str) -> String {
        let read = match self.median {
            m if m.is_nan() => "read in no draw".to_string(),
            m if m.is_infinite() => "reads ∞".to_string(),
            m => format!("reads {m:.3} {unit}"),
        };
        let tail = format!("{read}; {}/{} intervals cover it", self.covered, self.draws);
        match &self.reason {
            None => format!("identifiable ({tail})"),
            Some(r) => format!("not identifiable from this campaign: {r} ({tail})"),
        }
    }
}

/// The rule (module docs) for the written quantity `q` and the chain's readings on the
/// draws of the written model; `None` when `q` was not estimated (its row already says
/// why).
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
        n if values[n / 2 - 1].is_infinite() || values[n / 2].is_infinite() => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    };
    let reason = match q.interval {
        None => Some("no 95 % interval (too few positions to resample)".to_string()),
        Some(_) if 2 * read < draws || read == 0 => Some(format!(
            "the chain read it in {read} of {draws} draws of this model"
        )),
        Some([lo, hi]) if !(lo <= median && median <= hi) => {
            let (end, k) = if median > hi {
                ("above", values.iter().filter(|&&v| v > hi).count())
            } else {
                ("below", values.iter().filter(|&&v| v < lo).count())
            };
            Some(format!(
                "the chain reads it {end} this campaign's interval [{lo:.3}, {hi:.3}] on this model's draws (median {}, {k} of {read} {end})",
                if median.is_infinite() {
                    "∞".to_string()
                } else {
                    format!("{median:.3}")
                }
            ))
        }
        Some(_) => None,
    };
    Some(Identification {
        draws,
        read,
        covered,
        median,
        identifiable: reason.is_none(),
        reason,
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
        assert!(!id.identifiable);
        let why = id.reason.unwrap();
        assert!(
            why.contains("above") && why.contains("median 0.825, 3 of 4 above"),
            "{why}"
        );
        // below the lower end, the same
        let id = identify(&written, &plain(&[0.1, 0.2, 0.45])).unwrap();
        assert!(id.reason.unwrap().contains("below"));
        // the ends are inside
        assert!(
            identify(&written, &plain(&[0.6, 0.6, 0.9]))
                .unwrap()
                .identifiable
        );
        // readings around the written value: identifiable even where no interval covers
        let near = [
            Some((0.45, Some([0.44, 0.46]))),
            Some((0.55, Some([0.54, 0.56]))),
            Some((0.5, None)),
        ];
        let id = identify(&written, &near).unwrap();
        assert!(id.identifiable && id.reason.is_none());
        assert_eq!((id.covered, id.median), (0, 0.5));
        assert!(id
            .shown("1/ns")
            .starts_with("identifiable (reads 0.500 1/ns; 0/3"));
    }

    #[test]
    fn too_few_readings_no_interval_infinity_and_stated_values() {
        let written = q(0.5, Some([0.4, 0.6]));
        let id = identify(&written, &[Some((0.5, None)), None, None]).unwrap();
        assert!(id.reason.unwrap().contains("read it in 1 of 3"));
        let id = identify(&q(0.5, None), &plain(&[0.5])).unwrap();
        assert!(!id.identifiable);
        // Γ = ∞ inside an interval reaching ∞, above a finite one
        let gamma = q(f64::INFINITY, Some([30.0, f64::INFINITY]));
        let inf = plain(&[f64::INFINITY; 3]);
        assert!(identify(&gamma, &inf).unwrap().identifiable);
        let finite = q(40.0, Some([30.0, 60.0]));
        let id = identify(&finite, &inf).unwrap();
        assert!(!id.identifiable && id.median.is_infinite());
        assert!(id.shown("ns").contains("reads ∞"));
        // a stated (not estimated) value has no verdict
        let mut stated = q(0.5, None);
        stated.not_estimable = Some("no clusters".into());
        assert!(identify(&stated, &inf).is_none());
    }
}
