//! README "Your own campaign" as a user runs it (issue 32 item 5): `scripts/lab-campaign`
//! simulates the corridor, rewrites its sweeps as two labs would have left them with
//! scikit-rf (`scripts/lab_folders.py`: dB and MA Touchstone files in GHz with Keysight and
//! R&S headers, named `P03_az-45.s2p`, a `Pos,X [m],Y [m],Heading [deg]` poses CSV, a
//! `base.toml`), runs the section's `pradar import` → `pradar report` on each, and checks
//! that each lab's energy equals the simulated one within 1e-9 relative, that its Table 1
//! equals the simulated campaign's in every column (without a truth column) and that its
//! page carries the campaign's name and the labels P01..P12. About 65 s on 2 idle cores.

use crate::common::{python, root, skip_python};

/// The figure after `key` on `line` (e.g. `max|a-b|/max|b| = 1.99e-16;`).
fn figure(line: &str, key: &str) -> Option<f64> {
    let rest = &line[line.find(key)? + key.len()..];
    rest.split([';', ' ', ','])
        .find(|t| !t.is_empty())?
        .parse()
        .ok()
}

#[test]
fn lab_campaign_script_passes() {
    let has = python()
        .args(["-c", "import numpy, pandas, pyarrow, skrf"])
        .output();
    match has {
        Ok(o) if o.status.success() => {}
        _ if skip_python() => {
            eprintln!("skipped (PRADAR_SKIP_PYTHON=1): no Python with numpy, pandas, pyarrow, scikit-rf");
            return;
        }
        _ => panic!(
            "scripts/lab-campaign needs a Python with numpy, pandas, pyarrow and scikit-rf (run scripts/test, which makes that venv; or set PRADAR_PYTHON, or PRADAR_SKIP_PYTHON=1)"
        ),
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("lab");
    let exe = std::env::var_os("PRADAR_PYTHON").unwrap_or_else(|| "python3".into());
    let o = std::process::Command::new("bash")
        .arg(root().join("scripts/lab-campaign"))
        .arg(&out)
        .env("PRADAR", env!("CARGO_BIN_EXE_pradar"))
        .env("PYTHON", exe)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    eprintln!("{text}\n{err}");
    assert!(
        o.status.success(),
        "scripts/lab-campaign failed ({:?}): see its output above",
        o.status.code()
    );
    for (lab, name) in [
        ("lab-keysight", "lab-corridor-keysight"),
        ("lab-rs", "lab-corridor-rs"),
    ] {
        // the block of lines of this folder's checks
        let head = format!("{lab} ({name}):");
        let block: Vec<&str> = text
            .lines()
            .skip_while(|l| *l != head)
            .skip(1)
            .take_while(|l| l.starts_with("    "))
            .collect();
        assert!(!block.is_empty(), "no checks printed for {lab}");
        let energy = block.iter().find(|l| l.contains("energy:")).unwrap();
        let global = figure(energy, "max|a-b|/max|b| =").unwrap();
        let per_row = figure(energy, "max relative").unwrap();
        assert!(global <= 1e-9 && per_row <= 1e-9, "{lab}: {energy}");
        let table = block.iter().find(|l| l.contains("Table 1:")).unwrap();
        assert!(table.contains("15 rows"), "{lab}: {table}");
        assert!(
            figure(table, "worst relative").unwrap() <= 1e-9,
            "{lab}: {table}"
        );
        let page = block.iter().find(|l| l.contains("page:")).unwrap();
        let title = page
            .split("title `")
            .nth(1)
            .and_then(|t| t.split('`').next());
        assert!(title.is_some_and(|t| t.contains(name)), "{lab}: {page}");
        assert!(
            page.contains("labels on the page: 12 of 12"),
            "{lab}: {page}"
        );
        assert_eq!(block.last().map(|l| l.trim()), Some("ok"), "{lab}");
    }
    assert!(text.contains("lab-campaign: ok"), "{text}");
}
