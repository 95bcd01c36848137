//! Energy tables read a few positions at a time (issue 20, item 6): the streaming reader
//! serves the same energies as the whole-table reader, `extract` finds the same MPCs from
//! either, the writer groups whole positions per row group, and a table whose rows are in
//! another order is still read (whole).

use crate::common;

use common::*;
use pradar::campaign::manifest::SweepFormat;
use pradar::energy::{EnergyMatrix, EnergySource, EnergyTable};
use pradar::mpc::{extract, extract_labelled, ExtractParams};
use pradar::params::ParamGuard;

/// The corridor with 16 elements and its first `n` poses, simulated, with its energy table.
fn corridor_chain(dir: &std::path::Path, n: usize) -> (pradar::campaign::Campaign, EnergyMatrix) {
    let mut t = corridor();
    set(&mut t, "array.elements", 16i64);
    let poses = t["poses"].as_array().unwrap()[..n].to_vec();
    t.insert("poses".into(), poses.into());
    chain(dir, &t, SweepFormat::Parquet)
}

#[test]
fn streamed_positions_and_mpcs_equal_the_whole_table() {
    let dir = tempfile::tempdir().unwrap();
    let (c, em) = corridor_chain(dir.path(), 7);
    let e = dir.path().join("energy.parquet");
    let t = EnergyTable::open(&e).unwrap();
    assert!(t.streams());
    let h = t.header();
    assert_eq!(
        (h.positions, h.directions(), h.bins),
        (em.positions, em.directions(), em.bins)
    );
    assert_eq!(h.angles_rel_deg, em.angles_rel_deg);
    assert_eq!(h.headings_deg, em.headings_deg);
    assert_eq!(h.meta, em.meta);
    // whole positions per row group: 37 x 481 bins = 17,797 rows, 3 positions per group
    let md = pradar::table::parquet_file_metadata(&e).unwrap();
    let rows: Vec<usize> = md.row_groups.iter().map(|g| g.num_rows()).collect();
    let per = em.directions() * em.bins;
    assert_eq!(per, 17_797);
    assert_eq!(rows, vec![3 * per, 3 * per, per]);
    for (p0, p1) in [(0, 1), (2, 5), (3, 6), (6, 7), (0, 7)] {
        let part = t.load(p0, p1).unwrap();
        assert_eq!(part.held(), p0..p1);
        for p in p0..p1 {
            for d in 0..em.directions() {
                assert_eq!(
                    part.profile(p, d),
                    em.profile(p, d),
                    "position {p} direction {d}"
                );
            }
        }
    }
    assert!(t.load(5, 8).is_err());
    let params = ExtractParams::default().check().unwrap();
    let whole = extract(&em, &c, &params).unwrap();
    let (streamed, _) = extract_labelled(&t, &c, &params).unwrap();
    assert!(whole.len() > 100, "{} MPCs", whole.len());
    assert_eq!(whole, streamed);
}

#[test]
fn a_table_in_another_row_order_is_read_whole() {
    let dir = tempfile::tempdir().unwrap();
    let (_, em) = corridor_chain(dir.path(), 2);
    let e = dir.path().join("energy.parquet");
    let df = pradar::table::read_parquet(&e, None).unwrap();
    // rows reversed, as another tool might write them
    let n = df.height() as u32;
    let idx = polars::prelude::IdxCa::from_vec("i".into(), (0..n).rev().collect());
    let rev = df.take(&idx).unwrap();
    let kv: Vec<(String, String)> = pradar::table::parquet_metadata(&e)
        .unwrap()
        .into_iter()
        .filter(|(k, _)| k != "ARROW:schema")
        .collect();
    let r = dir.path().join("reversed.parquet");
    pradar::table::write_parquet(&r, &rev, kv).unwrap();
    let t = EnergyTable::open(&r).unwrap();
    assert!(!t.streams());
    let part = t.load(0, 2).unwrap();
    assert_eq!(part.data, em.data);
    assert_eq!(t.header().headings_deg, em.headings_deg);
}
