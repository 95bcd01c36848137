//! The fuzz driver (`scripts/fuzz`): `cargo run --release --example fuzz -- [--iterations N]
//! [--seed S] [TARGET…]` runs every parser's harness ([`pradar::fuzz`]) for N mutated
//! inputs (default 100 000) from its committed seeds and prints one line per target:
//! executions, accepted, refused, panics. Panicking inputs go to `fuzz/crashes/<target>/`;
//! copy them to `fuzz/regressions/<target>/` to replay them in every test run. Exit status
//! 1 when any target panicked.

use pradar::fuzz::{load_seeds, run, silence_panics, Scratch, Target};
use std::path::PathBuf;

fn main() {
    let mut iterations: u64 = 100_000;
    let mut seed: u64 = 1;
    let mut targets = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--iterations" => {
                iterations = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--iterations N")
            }
            "--seed" => seed = args.next().and_then(|v| v.parse().ok()).expect("--seed S"),
            name => targets.push(Target::parse(name).unwrap_or_else(|| {
                eprintln!(
                    "unknown target {name} (one of {:?})",
                    Target::ALL.map(|t| t.name())
                );
                std::process::exit(2)
            })),
        }
    }
    if targets.is_empty() {
        targets = Target::ALL.to_vec();
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let scratch_dir = std::env::temp_dir().join(format!("pradar-fuzz-{}", std::process::id()));
    let scratch = Scratch::new(&scratch_dir).expect("scratch folder");
    silence_panics();
    let mut failed = false;
    for t in targets {
        let seeds: Vec<Vec<u8>> = load_seeds(&root, t).into_iter().map(|(_, b)| b).collect();
        let crashes = root.join("fuzz/crashes").join(t.name());
        let start = std::time::Instant::now();
        let s = run(
            t,
            &seeds,
            iterations,
            seed,
            &scratch,
            Some(&crashes),
            &|s| {
                if s.executions.is_multiple_of(100_000) {
                    eprintln!(
                        "  {} {} executions, {} panics",
                        t.name(),
                        s.executions,
                        s.panics
                    );
                }
            },
        );
        println!(
            "{:<11} {} seeds, {} executions ({} accepted, {} refused), {} panics, {:.0} s",
            t.name(),
            seeds.len(),
            s.executions,
            s.ok,
            s.errors,
            s.panics,
            start.elapsed().as_secs_f64()
        );
        for m in &s.panic_messages {
            println!("  panic: {m}");
        }
        failed |= s.panics > 0;
    }
    let _ = std::fs::remove_dir_all(&scratch_dir);
    std::process::exit(i32::from(failed));
}
