//! A manifest restricted to some of its positions ([`Manifest::restrict`],
//! [`Campaign::restrict`]): what the held-out check fits and checks on (the channel crate's
//! `check::holdout`).
//!
//! Takes a manifest and the positions to keep, by their index in the manifest, strictly
//! increasing (the walk order stays, and with it the fit's position-bootstrap blocks); gives
//! the manifest of those positions alone, position i of the result being position `keep[i]`
//! of the original:
//! * `poses`: the kept poses, in order;
//! * `labels`: the kept labels. A manifest without labels names its positions by index, so
//!   the restriction gets the original indices as labels (`"6"`, `"7"`, …): messages,
//!   tables and plots of a half still name each position as the whole campaign does;
//! * `[sweeps] missing`: the pairs of kept positions, remapped; the others' dropped;
//! * `[sweeps] files`: the files of kept positions, remapped (paths unchanged);
//! * `[sweeps] pattern` (Touchstone): expanded into `files` for the kept positions (the
//!   template names positions by their original index, which the new indices would
//!   misread), no file for a sweep `missing` lists;
//! * `[sweeps] dropped_positions`: unchanged (labels of positions `import` left out of the
//!   campaign, not indices);
//! * everything else unchanged: name, layout, seed, pulses, band, array, directions, noise,
//!   processing, `[sweeps]` format and parameter; a [`Campaign`]'s path too, so the layout
//!   resolves and errors name the file.
//!
//! Not remapped: a Parquet sweep table (`[sweeps] path`: its `position` column counts the
//! whole campaign's positions) and `[calibration]` templates with `{position}` name
//! positions by the original index, and the manifest cannot say otherwise. The restriction
//! is an analysis view, used with the energy table restricted alike (the radar crate's
//! `EnergyMatrix::restrict`); the energy stage is not to be run on it.

use super::{expand_pattern, Campaign, Manifest, MissingSweep, SweepFile, SweepFormat};
use crate::error::{Error, Result};

/// Refuse a `keep` list that is empty, out of `0..n` or not strictly increasing (one line
/// naming the first offending entry).
pub fn check_keep(keep: &[usize], n: usize) -> Result<()> {
    if keep.is_empty() {
        return Err(Error::param("positions", "no position to keep"));
    }
    for (i, &p) in keep.iter().enumerate() {
        if p >= n {
            return Err(Error::param(
                "positions",
                format!("keep[{i}] = {p} outside the campaign's {n} positions"),
            ));
        }
        if i > 0 && p <= keep[i - 1] {
            return Err(Error::param(
                "positions",
                format!(
                    "keep[{i}] = {p} after {}: positions are kept in walk order, each once",
                    keep[i - 1]
                ),
            ));
        }
    }
    Ok(())
}

impl Manifest {
    /// The manifest of positions `keep` alone (module docs: what is remapped, what is not);
    /// refused when `keep` is empty, out of range or not strictly increasing.
    pub fn restrict(&self, keep: &[usize]) -> Result<Manifest> {
        let n = self.poses.len();
        check_keep(keep, n)?;
        // new index of an original position
        let mut new = vec![None; n];
        for (i, &p) in keep.iter().enumerate() {
            new[p] = Some(i);
        }
        let mut m = self.clone();
        m.poses = keep.iter().map(|&p| self.poses[p]).collect();
        m.labels = keep.iter().map(|&p| self.label(p)).collect();
        if let Some(s) = m.sweeps.as_mut() {
            s.missing = (s.missing.iter())
                .filter_map(|x| {
                    new[x.position].map(|position| MissingSweep {
                        position,
                        direction: x.direction,
                    })
                })
                .collect();
            let files: Vec<SweepFile> = match (&s.pattern, s.format) {
                (Some(pat), SweepFormat::Touchstone) => {
                    let (nd, nk) = (self.directions.count(), self.pulses);
                    let missing = self.missing();
                    let mut v = Vec::with_capacity(keep.len() * nd * nk);
                    for (i, &p) in keep.iter().enumerate() {
                        for d in 0..nd {
                            if missing.binary_search(&(p, d)).is_ok() {
                                continue;
                            }
                            for k in 0..nk {
                                v.push(SweepFile {
                                    position: i,
                                    direction: d,
                                    pulse: k,
                                    path: expand_pattern(pat, p, d, k).into(),
                                });
                            }
                        }
                    }
                    s.pattern = None;
                    v
                }
                _ => (s.files.iter())
                    .filter_map(|f| {
                        new[f.position].map(|position| SweepFile {
                            position,
                            ..f.clone()
                        })
                    })
                    .collect(),
            };
            s.files = files;
        }
        m.check()?;
        Ok(m)
    }
}

impl Campaign {
    /// The campaign of positions `keep` alone ([`Manifest::restrict`]), at the same path.
    pub fn restrict(&self, keep: &[usize]) -> Result<Campaign> {
        Ok(Campaign {
            manifest: (self.manifest.restrict(keep))
                .map_err(|e| Error::input(&self.path, e.to_string()))?,
            path: self.path.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Five poses, three directions, two pulses; position 1 lacks direction 2, position 3
    /// direction 0.
    fn manifest(sweeps: &str) -> Manifest {
        let mut text = String::from(
            "schema_version = 1\nname = \"t\"\nlayout = \"l.geojson\"\nseed = 3\npulses = 2\n\
             [band]\nstart_hz = 57.5e9\nstop_hz = 63.5e9\npoints = 801\n\
             [array]\nelements = 16\n\
             [directions]\nstart_deg = -10.0\nstop_deg = 10.0\nstep_deg = 10.0\n\
             [noise]\nfloor_dbm = -100.0\n",
        );
        for i in 0..5 {
            text += &format!(
                "[[poses]]\nx_m = {i}.5\ny_m = 0.25\nheading_deg = {}\n",
                10 * i
            );
        }
        text += sweeps;
        text += "\n[[sweeps.missing]]\nposition = 1\ndirection = 2\n\
                 [[sweeps.missing]]\nposition = 3\ndirection = 0\n";
        let m: Manifest = toml::from_str(&text).unwrap();
        m.check().unwrap();
        m
    }

    /// Positions kept in order with their labels (the original indices when the manifest
    /// has none), poses equal to the original's, `missing` remapped, the pattern expanded
    /// into the kept positions' files under their original names.
    #[test]
    fn restrict_remaps_positions() {
        let m = manifest(
            "[sweeps]\nformat = \"touchstone\"\npattern = \"p{position:02}_d{direction}_k{pulse}.s2p\"\n\
             dropped_positions = [\"X\"]",
        );
        let r = m.restrict(&[1, 3, 4]).unwrap();
        assert_eq!(r.poses, vec![m.poses[1], m.poses[3], m.poses[4]]);
        assert_eq!(r.labels, ["1", "3", "4"]);
        assert_eq!(r.label(2), "4");
        assert_eq!(r.missing(), vec![(0, 2), (1, 0)]);
        let s = r.sweeps.as_ref().unwrap();
        assert!(s.pattern.is_none());
        assert_eq!(s.dropped_positions, ["X"]);
        // 3 positions × 3 directions × 2 pulses, less two missing directions' 2 pulses each
        assert_eq!(s.files.len(), 18 - 4);
        let f = s
            .files
            .iter()
            .find(|f| (f.position, f.direction, f.pulse) == (1, 1, 1))
            .unwrap();
        assert_eq!(f.path.to_str(), Some("p03_d1_k1.s2p"));
        assert!(!s.files.iter().any(|f| (f.position, f.direction) == (0, 2)));
        // unchanged: what is not indexed by position
        assert_eq!(
            (r.band, r.directions, r.seed, r.pulses),
            (m.band, m.directions, m.seed, m.pulses)
        );
        // one position: the missing pairs of others gone
        let one = m.restrict(&[2]).unwrap();
        assert!(one.missing().is_empty());
        assert_eq!(one.labels, ["2"]);
    }

    /// Listed files and lab labels are remapped with their positions; a bad list is one
    /// line naming the entry.
    #[test]
    fn restrict_files_labels_and_refusals() {
        let mut files = String::from("[sweeps]\nformat = \"parquet\"\npath = \"s.parquet\"\n");
        for (p, d, k) in [(0, 0, 0), (3, 1, 1), (4, 2, 0)] {
            files += &format!(
                "[[sweeps.files]]\nposition = {p}\ndirection = {d}\npulse = {k}\npath = \"f{p}{d}{k}.s2p\"\n"
            );
        }
        let mut m = manifest(&files);
        m.labels = ["P1", "P2", "P3", "P4", "P5"].map(String::from).to_vec();
        let r = m.restrict(&[3, 4]).unwrap();
        assert_eq!(r.labels, ["P4", "P5"]);
        let s = r.sweeps.as_ref().unwrap();
        assert_eq!(s.path.as_deref(), Some(std::path::Path::new("s.parquet")));
        let got: Vec<(usize, usize, usize, &str)> = (s.files.iter())
            .map(|f| (f.position, f.direction, f.pulse, f.path.to_str().unwrap()))
            .collect();
        assert_eq!(got, [(0, 1, 1, "f311.s2p"), (1, 2, 0, "f420.s2p")]);
        assert_eq!(r.missing(), vec![(0, 0)]);
        for (keep, says) in [
            (vec![], "no position"),
            (vec![1, 5], "keep[1] = 5 outside the campaign's 5 positions"),
            (vec![2, 2], "keep[1] = 2 after 2"),
            (vec![3, 1], "keep[1] = 1 after 3"),
        ] {
            let e = m.restrict(&keep).unwrap_err().to_string();
            assert!(e.contains(says) && !e.contains('\n'), "{e}");
        }
    }
}
