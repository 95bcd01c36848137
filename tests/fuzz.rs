//! The fuzz harnesses' bounded run inside the suite (`src/fuzz.rs`; the long run is
//! `scripts/fuzz N`): every committed seed and regression input of every parser, then 300
//! mutated inputs per parser. No input may panic; the seeds must be accepted (a harness
//! that refuses its own seeds fuzzes nothing past the first check); and the refusals must
//! be errors naming the scratch file.
//!
//! The harness is behind the cargo feature `fuzz`, so this module runs only with it:
//! `cargo test --release --features fuzz --test tests fuzz::` (`scripts/test` passes
//! `--features fuzz`, so the suite and CI run it).

use crate::common::root;
use pradar::fuzz::{execute, load_seeds, regression_dir, run, Drive, Outcome, Scratch, Target};

#[test]
fn every_parser_survives_its_seeds_regressions_and_2000_mutations() {
    let dir = tempfile::tempdir().unwrap();
    let scratch = Scratch::new(dir.path()).unwrap();
    for t in Target::ALL {
        let seeds = load_seeds(&root(), t);
        assert!(!seeds.is_empty(), "{}: no seeds", t.name());
        let regressions = regression_dir(&root(), t);
        for (path, bytes) in &seeds {
            let o = execute(t, bytes, &scratch);
            assert!(!matches!(o, Outcome::Panic(_)), "{}: {o:?}", path.display());
            if !path.starts_with(&regressions) {
                assert_eq!(o, Outcome::Ok, "{}: seed refused", path.display());
            }
        }
        let inputs: Vec<Vec<u8>> = seeds.into_iter().map(|(_, b)| b).collect();
        let drive = Drive {
            skip: 0,
            mark: &|_| {},
            progress: &|_| {},
        };
        let s = run(t, &inputs, 2000, 7, &scratch, None, &drive);
        assert_eq!(s.panics, 0, "{}: {:?}", t.name(), s.panic_messages);
        assert_eq!(s.executions, 2000 + inputs.len() as u64);
        assert!(s.errors > 0, "{}: no mutation was refused", t.name());
    }
}
