//! The integration tests, gathered into one test binary (as BurntSushi/ripgrep's
//! `tests/tests.rs`): one link instead of one per file. Each file in `tests/` is a module
//! here, so a test is named `<file>::<test>` (`cargo test --release --test tests cli::`
//! runs the CLI tests); `tests/common/` holds the helpers they share. `Cargo.toml` sets
//! `autotests = false`, so a new `tests/*.rs` file must be declared below:
//! `every_test_file_is_a_module` fails until it is.

mod common;

mod bad_inputs;
mod calibrate;
mod calibration;
mod check;
mod cli;
mod closed_loop;
mod cluster;
mod diffuse;
mod ekf;
mod experiment;
mod explore;
mod fit_cli;
mod fit_coverage;
mod fit_estimators;
mod fold;
#[cfg(feature = "fuzz")]
mod fuzz;
mod import;
mod kill;
mod lab;
mod mapping;
mod mpc;
mod occlusion;
mod physics;
mod report;
mod responsiveness;
mod slam;
mod smm;
mod streaming;
mod synth;
mod touchstone;

/// With `autotests = false` cargo builds only this file: a `tests/*.rs` left out of the
/// `mod` list above would never run, so it is an error.
#[test]
fn every_test_file_is_a_module() {
    let dir = common::root().join("tests");
    let this = std::fs::read_to_string(dir.join("tests.rs")).unwrap();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if path.extension().is_some_and(|e| e == "rs")
            && stem != "tests"
            && !this.contains(&format!("\nmod {stem};\n"))
        {
            missing.push(stem.to_string());
        }
    }
    assert!(
        missing.is_empty(),
        "tests/{{{}}}.rs not declared in tests/tests.rs: add `mod <name>;`",
        missing.join(",")
    );
}
