//! Calibration sweeps (`[calibration]`), applied to every sweep before the window and IFFT.
//!
//! Takes the manifest's `[calibration]`: `background` and `reference`, each a Touchstone
//! file name relative to the manifest, or a name template with `{direction}` (and
//! `{position}`) expanded as in `[sweeps] pattern`, so there may be one sweep for the whole
//! campaign, one per direction, or one per (position, direction). Each is read like the
//! campaign's sweeps (same `[sweeps] parameter`, grid checked against `[band]`).
//! Gives, per sweep S(f) of position p, direction d and every pulse:
//!
//!   S_cal(f) = (S(f) − B_{p,d}(f)) / R_{p,d}(f)
//!
//! * B, the **background**: an empty-scene or absorber sweep, as channel engineers record
//!   it. Subtracted coherently (complex, before the IFFT), it removes every static term —
//!   the Tx→Rx coupling, the device's housing, a fixed clutter return — exactly, whatever
//!   its delay; gating (`[processing] coupling`) still runs afterwards as configured.
//! * R, the **reference**: a thru (the arrays replaced by a cable/attenuator of known unit
//!   response) or any measurement of the system response alone: cables, the VNA's
//!   frequency response, the arrays' group delay. Dividing by it leaves the scene's
//!   response, so delays are measured from the reference plane of the thru and amplitudes
//!   are relative to it (a thru of unit gain keeps the radar equation's scale). A reference
//!   with |R| = 0 (or not finite) at a point is refused, naming the file and the point: the
//!   division would be undefined there; a calibrated value that is not finite (a reference
//!   so small the division overflows) is refused naming the file, the step and the sweep
//!   ([`Calibration::apply`]).
//!
//! Every calibration file must be a regular file ([`crate::io::regular_input`]), and
//! `energy` refuses an `--out` that is one of them ([`Calibration::files`]).
//!
//! The order (subtract, then divide) follows the measurement model S = H·(scene) + B with
//! the background measured through the same system: (S − B)/R is the scene when R = H.
//! What was applied is recorded in the energy metadata (`calibration_background`,
//! `calibration_reference`: the templates as written); a campaign without `[calibration]`
//! adds no keys, so its energy table is unchanged.

use crate::campaign::manifest::{expand_pattern, Band, Campaign};
use crate::campaign::sweeps::{read_sweep, PositionSweeps};
use crate::error::{Error, Result};
use num_complex::Complex64;
use std::collections::BTreeMap;
use std::path::Path;

/// The files a calibration template names: one per (position, direction) key (position 0
/// when the template has no `{position}`, direction 0 without `{direction}`).
fn files(c: &Campaign, template: &str) -> Vec<((usize, usize), std::path::PathBuf)> {
    let m = &c.manifest;
    let np = if template.contains("{position") {
        m.positions()
    } else {
        1
    };
    let nd = if template.contains("{direction") {
        m.directions.count()
    } else {
        1
    };
    let dir = c.dir();
    (0..np)
        .flat_map(|p| (0..nd).map(move |d| (p, d)))
        .map(|(p, d)| ((p, d), dir.join(expand_pattern(template, p, d, 0))))
        .collect()
}

/// One kind of calibration sweep, loaded for every (position, direction) it applies to.
#[derive(Debug, Clone)]
struct CalSweeps {
    template: String,
    by_position: bool,
    by_direction: bool,
    /// Per (position, direction) key: the file and its sweep.
    sweeps: BTreeMap<(usize, usize), (std::path::PathBuf, Vec<Complex64>)>,
}

impl CalSweeps {
    fn key(&self, p: usize, d: usize) -> (usize, usize) {
        (
            if self.by_position { p } else { 0 },
            if self.by_direction { d } else { 0 },
        )
    }

    fn load(c: &Campaign, template: &str, field: &str, reference: bool) -> Result<CalSweeps> {
        let m = &c.manifest;
        let param = m.sweeps.as_ref().and_then(|s| s.parameter);
        let by_position = template.contains("{position");
        let by_direction = template.contains("{direction");
        if template.contains("{pulse") {
            return Err(Error::input(
                &c.path,
                format!("{field}: `{{pulse}}` is not allowed (one calibration sweep per position and direction)"),
            ));
        }
        let mut sweeps = BTreeMap::new();
        for ((p, d), path) in files(c, template) {
            crate::io::regular_input(
                &path,
                &format!("{field} sweep named in {}", c.path.display()),
            )?;
            let mut s = vec![Complex64::new(0.0, 0.0); m.band.points];
            read_sweep(&path, param, &m.band, &mut s)?;
            if reference {
                check_reference(&path, field, &s, &m.band)?;
            }
            sweeps.insert((p, d), (path, s));
        }
        Ok(CalSweeps {
            template: template.to_string(),
            by_position,
            by_direction,
            sweeps,
        })
    }
}

/// A reference sweep must have 0 < |R| < ∞ at every point: the division is undefined
/// otherwise (names the file and the point).
fn check_reference(path: &Path, field: &str, s: &[Complex64], band: &Band) -> Result<()> {
    if let Some(k) = s
        .iter()
        .position(|v| !(v.norm() > 0.0 && v.norm().is_finite()))
    {
        return Err(Error::input(
            path,
            format!(
                "{field}: |R| = {} at point {k} ({:.6} GHz): the system response cannot be divided out",
                s[k].norm(),
                band.freq(k) / 1e9
            ),
        ));
    }
    Ok(())
}

/// The loaded `[calibration]` of a campaign.
#[derive(Debug, Clone, Default)]
pub struct Calibration {
    background: Option<CalSweeps>,
    reference: Option<CalSweeps>,
}

impl Calibration {
    /// Load the sweeps named by `[calibration]` (none when the section is absent).
    pub fn load(c: &Campaign) -> Result<Calibration> {
        let Some(cfg) = &c.manifest.calibration else {
            return Ok(Calibration::default());
        };
        Ok(Calibration {
            background: cfg
                .background
                .as_deref()
                .map(|t| CalSweeps::load(c, t, "calibration.background", false))
                .transpose()?,
            reference: cfg
                .reference
                .as_deref()
                .map(|t| CalSweeps::load(c, t, "calibration.reference", true))
                .transpose()?,
        })
    }

    /// A calibration of one background and one reference sweep for the whole campaign
    /// (either may be absent), already read: each a file name (for errors) and its values
    /// on `band`'s grid. The reference is checked as [`Calibration::load`] checks it. What
    /// the fuzz harness of the calibration step builds (`crate::fuzz`, feature `fuzz`).
    #[cfg(feature = "fuzz")]
    pub fn from_sweeps(
        band: &Band,
        background: Option<(std::path::PathBuf, Vec<Complex64>)>,
        reference: Option<(std::path::PathBuf, Vec<Complex64>)>,
    ) -> Result<Calibration> {
        let one = |field: &str, (path, s): (std::path::PathBuf, Vec<Complex64>)| {
            if s.len() != band.points {
                return Err(Error::input(
                    &path,
                    format!("{field}: {} points, [band] has {}", s.len(), band.points),
                ));
            }
            if field == "calibration.reference" {
                check_reference(&path, field, &s, band)?;
            }
            Ok(CalSweeps {
                template: path.display().to_string(),
                by_position: false,
                by_direction: false,
                sweeps: BTreeMap::from([((0, 0), (path, s))]),
            })
        };
        Ok(Calibration {
            background: background
                .map(|b| one("calibration.background", b))
                .transpose()?,
            reference: reference
                .map(|r| one("calibration.reference", r))
                .transpose()?,
        })
    }

    /// Every file `[calibration]` names (background, then reference), with the field
    /// naming it; nothing is read.
    pub fn files(c: &Campaign) -> Vec<(std::path::PathBuf, &'static str)> {
        let Some(cfg) = &c.manifest.calibration else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (t, field) in [
            (&cfg.background, "calibration.background (of --campaign)"),
            (&cfg.reference, "calibration.reference (of --campaign)"),
        ] {
            if let Some(t) = t {
                out.extend(files(c, t).into_iter().map(|(_, p)| (p, field)));
            }
        }
        out
    }

    /// Whether anything is applied.
    pub fn is_empty(&self) -> bool {
        self.background.is_none() && self.reference.is_none()
    }

    /// S ← (S − B) / R for every sweep of one position. A value that is not finite
    /// afterwards (a reference so small the division overflows, a background of
    /// overflowing values) is an error naming the calibration file, the step and the
    /// sweep: the energies would be NaN.
    pub fn apply(&self, sw: &mut PositionSweeps) -> Result<()> {
        if self.is_empty() {
            return Ok(());
        }
        let nf = sw.points;
        for d in 0..sw.directions {
            if !sw.has(d) {
                continue; // a missing sweep stays NaN
            }
            let b = self
                .background
                .as_ref()
                .map(|c| &c.sweeps[&c.key(sw.position, d)]);
            let r = self
                .reference
                .as_ref()
                .map(|c| &c.sweeps[&c.key(sw.position, d)]);
            for k in 0..sw.pulses {
                let i = (d * sw.pulses + k) * nf;
                let s = &mut sw.s21[i..i + nf];
                if let Some((_, b)) = b {
                    s.iter_mut().zip(b).for_each(|(v, b)| *v -= b);
                }
                if let Some((_, r)) = r {
                    s.iter_mut().zip(r).for_each(|(v, r)| *v /= r);
                }
                if let Some(j) = s
                    .iter()
                    .position(|v| !(v.re.is_finite() && v.im.is_finite()))
                {
                    let (file, step) = match (r, b) {
                        (Some((f, _)), _) => (f, "calibration.reference: (S − B) / R"),
                        (None, Some((f, _))) => (f, "calibration.background: S − B"),
                        (None, None) => unreachable!("a calibration is applied"),
                    };
                    return Err(Error::input(
                        file,
                        format!(
                            "{step} is not finite at position {}, direction {d}, pulse {k}, point {j}: the calibration sweep is too small or too large to apply",
                            sw.position
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The background's template, as written (for errors naming the step).
    pub fn background_template(&self) -> Option<&str> {
        self.background.as_ref().map(|b| b.template.as_str())
    }

    /// The reference's template, as written (for errors naming the step).
    pub fn reference_template(&self) -> Option<&str> {
        self.reference.as_ref().map(|r| r.template.as_str())
    }

    /// Energy metadata of what was applied (empty when nothing was).
    pub fn metadata(&self) -> Vec<(String, String)> {
        let mut out = Vec::new();
        if let Some(b) = &self.background {
            out.push(("calibration_background".into(), b.template.clone()));
        }
        if let Some(r) = &self.reference {
            out.push(("calibration_reference".into(), r.template.clone()));
        }
        out
    }
}
