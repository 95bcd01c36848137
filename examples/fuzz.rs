//! The fuzz driver (`scripts/fuzz`): `cargo run --release --features fuzz --example fuzz --
//! [--iterations N] [--seed S] [TARGET…]` runs every parser's harness ([`pradar::fuzz`]) for N mutated
//! inputs (default 100 000) from its committed seeds and prints one line per target:
//! executions, accepted, refused, panics, aborts. Each target runs in a child process
//! (this program with `--child`); when the child dies (an allocation failure aborts it),
//! the input it was running is saved, counted as an abort, and a new child resumes the
//! same stream after it. Failing inputs go to `fuzz/crashes/<target>/`; copy them to
//! `fuzz/regressions/<target>/` to replay them in every test run. Exit status 1 when any
//! target panicked or aborted.

use pradar::fuzz::{
    load_seeds, parquet_input, run, save_crash, silence_panics, Drive, Scratch, Target,
};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

struct Args {
    iterations: u64,
    seed: u64,
    targets: Vec<Target>,
    child: Option<(u64, PathBuf)>,
}

fn args() -> Args {
    let mut a = Args {
        iterations: 100_000,
        seed: 1,
        targets: Vec::new(),
        child: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(x) = it.next() {
        let mut num = |what: &str| -> u64 {
            it.next()
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("{what} needs a number"))
        };
        match x.as_str() {
            "--iterations" => a.iterations = num("--iterations"),
            "--seed" => a.seed = num("--seed"),
            "--child" => {
                let skip = num("--child");
                let dir = PathBuf::from(it.next().expect("--child SKIP DIR"));
                a.child = Some((skip, dir));
            }
            name => a.targets.push(Target::parse(name).unwrap_or_else(|| {
                eprintln!(
                    "unknown target {name} (one of {:?})",
                    Target::ALL.map(|t| t.name())
                );
                std::process::exit(2)
            })),
        }
    }
    if a.targets.is_empty() {
        a.targets = Target::ALL.to_vec();
    }
    a
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The child: run one target from execution `skip`, writing the index of each execution to
/// `dir/index` before it runs and `COUNTS exec ok err panics` lines to stdout.
fn child(a: &Args, skip: u64, dir: &Path) {
    let t = a.targets[0];
    let scratch = Scratch::new(dir).expect("scratch folder");
    silence_panics();
    let seeds: Vec<Vec<u8>> = load_seeds(&root(), t).into_iter().map(|(_, b)| b).collect();
    let crashes = root().join("fuzz/crashes").join(t.name());
    let index = std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .truncate(true)
        .open(dir.join("index"))
        .expect("index file");
    let mark = |i: u64| {
        use std::os::unix::fs::FileExt;
        let _ = index.write_at(&i.to_le_bytes(), 0);
    };
    let out = std::sync::Mutex::new(std::io::stdout());
    let say = |s: &pradar::fuzz::Stats| {
        let mut o = out.lock().unwrap();
        let _ = writeln!(
            o,
            "COUNTS {} {} {} {}",
            s.executions, s.ok, s.errors, s.panics
        );
        let _ = o.flush();
    };
    let drive = Drive {
        skip,
        mark: &mark,
        progress: &say,
    };
    let s = run(
        t,
        &seeds,
        a.iterations,
        a.seed,
        &scratch,
        Some(&crashes),
        &drive,
    );
    say(&s);
    for m in &s.panic_messages {
        let _ = writeln!(out.lock().unwrap(), "PANIC {}", m.replace('\n', " "));
    }
    let _ = writeln!(out.lock().unwrap(), "DONE");
}

fn main() {
    let a = args();
    if let Some((skip, dir)) = &a.child {
        child(&a, *skip, dir);
        return;
    }
    let exe = std::env::current_exe().expect("own path");
    let mut failed = false;
    for t in &a.targets {
        let dir =
            std::env::temp_dir().join(format!("pradar-fuzz-{}-{}", std::process::id(), t.name()));
        let start = std::time::Instant::now();
        let (mut exec, mut ok, mut err, mut panics, mut aborts) = (0u64, 0u64, 0u64, 0u64, 0u64);
        let mut messages = Vec::new();
        let mut skip = 0u64;
        loop {
            let mut c = std::process::Command::new(&exe)
                .args([
                    "--iterations",
                    &a.iterations.to_string(),
                    "--seed",
                    &a.seed.to_string(),
                ])
                .args([
                    "--child",
                    &skip.to_string(),
                    dir.to_str().unwrap(),
                    t.name(),
                ])
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::null())
                .spawn()
                .expect("child");
            let mut last = (0u64, 0u64, 0u64, 0u64);
            let mut done = false;
            for line in std::io::BufReader::new(c.stdout.take().unwrap()).lines() {
                let line = line.unwrap_or_default();
                if let Some(rest) = line.strip_prefix("COUNTS ") {
                    let v: Vec<u64> = rest.split(' ').filter_map(|x| x.parse().ok()).collect();
                    last = (v[0], v[1], v[2], v[3]);
                    if (exec + last.0).is_multiple_of(100_000) {
                        eprintln!("  {} {} executions", t.name(), exec + last.0);
                    }
                } else if let Some(m) = line.strip_prefix("PANIC ") {
                    messages.push(m.to_string());
                } else if line == "DONE" {
                    done = true;
                }
            }
            let _ = c.wait();
            exec += last.0;
            ok += last.1;
            err += last.2;
            panics += last.3;
            if done {
                break;
            }
            // the child died: the execution it was running is `index`
            let b = std::fs::read(dir.join("index")).unwrap_or_default();
            let i =
                u64::from_le_bytes(b.get(..8).and_then(|x| x.try_into().ok()).unwrap_or([0; 8]));
            let executed_since = i + 1 - skip;
            // executions after the last COUNTS line up to the abort: refused or accepted,
            // unknown; counted as executions, the abort itself once
            exec += executed_since - last.0;
            aborts += 1;
            if matches!(t, Target::Energy | Target::Mpc | Target::Cluster) {
                if let Ok(input) = std::fs::read(parquet_input(&dir, *t)) {
                    let p = save_crash(&root().join("fuzz/crashes").join(t.name()), &input);
                    messages.push(format!("abort at execution {i}: {}", p.display()));
                }
            } else {
                messages.push(format!("abort at execution {i}"));
            }
            skip = i + 1;
        }
        let _ = std::fs::remove_dir_all(&dir);
        println!(
            "{:<11} {} executions ({} accepted, {} refused, rest unknown), {} panics, {} aborts, {:.0} s",
            t.name(),
            exec,
            ok,
            err,
            panics,
            aborts,
            start.elapsed().as_secs_f64()
        );
        for m in messages.iter().take(8) {
            println!("  {m}");
        }
        failed |= panics + aborts > 0;
    }
    std::process::exit(i32::from(failed));
}
