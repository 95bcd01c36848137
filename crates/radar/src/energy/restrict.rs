//! An energy matrix restricted to some of its positions ([`EnergyMatrix::restrict`]): the
//! table of a held-out check's half, beside the campaign restricted alike
//! ([`Manifest::restrict`](crate::campaign::manifest::Manifest::restrict)).
//!
//! Takes a whole matrix (every position held) and the positions to keep, by index,
//! strictly increasing; gives the matrix of those positions alone, position i of the result
//! being position `keep[i]` of the original: its profiles (`data` is position-major, so
//! each kept position's directions × bins block is copied whole, bit for bit), its
//! heading, and the metadata's position-indexed entries remapped — `missing` (the field
//! and the `missing` key of `all`, dropped when no kept position lacks a sweep, as the
//! writer leaves it out of a complete table). Every other metadata entry (N0, TW, the
//! band, the campaign's name, …) describes the whole table's processing and is kept as it
//! is: a half's draws carry the whole table's recorded N0.

use super::EnergyMatrix;
use crate::campaign::manifest::check_keep;
use crate::error::{Error, Result};

impl EnergyMatrix {
    /// The matrix of positions `keep` alone (module docs); refused when the matrix is not
    /// whole or `keep` is empty, out of range or not strictly increasing.
    pub fn restrict(&self, keep: &[usize]) -> Result<EnergyMatrix> {
        if self.held() != (0..self.positions) {
            return Err(Error::param(
                "energy",
                format!(
                    "a matrix of positions {:?} of {} cannot be restricted (read the whole table)",
                    self.held(),
                    self.positions
                ),
            ));
        }
        check_keep(keep, self.positions)?;
        let per = self.directions() * self.bins;
        let mut data = Vec::with_capacity(keep.len() * per);
        for &p in keep {
            data.extend_from_slice(&self.data[p * per..(p + 1) * per]);
        }
        let mut meta = self.meta.clone();
        meta.missing = (self.meta.missing.iter())
            .filter_map(|&(p, d)| keep.binary_search(&p).ok().map(|i| (i, d)))
            .collect();
        let pairs: Vec<String> = (meta.missing.iter())
            .map(|(p, d)| format!("{p}:{d}"))
            .collect();
        meta.all.retain(|(k, _)| k != "missing");
        if !pairs.is_empty() {
            meta.all.push(("missing".into(), pairs.join(" ")));
        }
        Ok(EnergyMatrix {
            meta,
            positions: keep.len(),
            angles_rel_deg: self.angles_rel_deg.clone(),
            headings_deg: keep.iter().map(|&p| self.headings_deg[p]).collect(),
            bins: self.bins,
            first: 0,
            data,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::EnergyMeta;

    /// Four positions, two directions, three bins; every energy distinct
    /// (100·p + 10·d + b); position 1 lacks direction 0, position 2 direction 1.
    fn matrix() -> EnergyMatrix {
        let (np, nd, nb) = (4, 2, 3);
        let missing = vec![(1, 0), (2, 1)];
        let mut data: Vec<f64> = (0..np * nd * nb)
            .map(|i| (100 * (i / (nd * nb)) + 10 * ((i / nb) % nd) + i % nb) as f64)
            .collect();
        let meta = EnergyMeta {
            schema_version: 1,
            bin_width_ns: 1.0 / 6.0,
            pulses: 1,
            n0: 1e-13,
            enbw: 1.5,
            tw: 1.6,
            array: "4x4".into(),
            coupling: "gate".into(),
            all: vec![
                ("n0".into(), "1e-13".into()),
                ("missing".into(), "1:0 2:1".into()),
                ("campaign".into(), "t".into()),
            ],
            missing,
        };
        meta.mask_missing(nd, nb, &mut data);
        EnergyMatrix {
            meta,
            positions: np,
            angles_rel_deg: vec![-5.0, 5.0],
            headings_deg: vec![0.0, 10.0, 20.0, 30.0],
            bins: nb,
            first: 0,
            data,
        }
    }

    /// The kept positions' profiles equal the original's, bit for bit (NaN where missing);
    /// headings follow; `missing` is remapped in the field and in the metadata's pairs.
    #[test]
    fn restrict_keeps_rows_and_remaps_missing() {
        let em = matrix();
        let r = em.restrict(&[1, 3]).unwrap();
        assert_eq!((r.positions, r.directions(), r.bins), (2, 2, 3));
        assert_eq!(r.headings_deg, [10.0, 30.0]);
        assert_eq!(r.held(), 0..2);
        for (i, &p) in [1usize, 3].iter().enumerate() {
            for d in 0..2 {
                let (a, b) = (r.profile(i, d), em.profile(p, d));
                assert_eq!(
                    a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    b.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                );
                assert_eq!(r.has(i, d), em.has(p, d));
            }
        }
        assert_eq!(r.profile(1, 1), [310.0, 311.0, 312.0]);
        assert_eq!(r.meta.missing, [(0, 0)]);
        let get = |m: &EnergyMatrix, k: &str| {
            (m.meta.all.iter())
                .find(|(key, _)| key == k)
                .map(|(_, v)| v.clone())
        };
        assert_eq!(get(&r, "missing").as_deref(), Some("0:0"));
        assert_eq!(get(&r, "n0"), get(&em, "n0"));
        assert_eq!((r.meta.n0, r.meta.tw), (em.meta.n0, em.meta.tw));
        // no kept position lacks a sweep: no `missing` entry, as a complete table has
        let full = em.restrict(&[0, 3]).unwrap();
        assert!(full.meta.missing.is_empty() && get(&full, "missing").is_none());
        assert!(full.data.iter().all(|v| v.is_finite()));
        assert_eq!(full.data[..6], em.data[..6]);
        assert_eq!(full.data[6..], em.data[18..]);
    }

    /// A partial matrix or a bad list is refused with one line.
    #[test]
    fn restrict_refuses() {
        let em = matrix();
        for (keep, says) in [
            (vec![], "no position"),
            (vec![0, 4], "outside the campaign's 4 positions"),
            (vec![2, 1], "after 2"),
        ] {
            let e = em.restrict(&keep).unwrap_err().to_string();
            assert!(e.contains(says) && !e.contains('\n'), "{e}");
        }
        let mut part = em.clone();
        part.first = 2;
        part.data = part.data[12..].to_vec();
        let e = part.restrict(&[2]).unwrap_err().to_string();
        assert!(e.contains("cannot be restricted"), "{e}");
    }
}
