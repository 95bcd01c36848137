//! Atomic output: every file is written to a temporary sibling and renamed into place, so a
//! failed run never leaves a half-written output behind; and the guards around it.
//!
//! * [`temp_path`]: `.<name>.tmp<PID>` beside the output. A run killed while writing leaves
//!   it behind; the next write of the same output removes every such sibling whose process
//!   is gone ([`clean_stale_temps`], called by [`write_atomic`] and the Parquet streams).
//!   A sibling of a live process (another run writing the same output) is left alone.
//! * [`refuse_overwrite`]: no output of a run may be one of its inputs, or another of its
//!   outputs. Paths are compared canonically (symlinks, `..`, relative and absolute
//!   spellings of one file are one file); an output that does not exist yet is compared by
//!   its canonical parent folder and its name. The refusal is one line naming the output,
//!   the input and the flags that gave them.

use crate::error::{Error, Result};
use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The temporary sibling used while `path` is being written.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.tmp{}", std::process::id()))
}

/// Whether `name` is a temp sibling of the output called `output_name`, and the PID in it.
fn temp_pid(name: &str, output_name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?.strip_prefix(output_name)?;
    rest.strip_prefix(".tmp")?.parse::<u32>().ok()
}

/// Whether process `pid` is alive (Linux: `/proc/PID` exists; elsewhere assumed gone).
fn process_alive(pid: u32) -> bool {
    pid == std::process::id() || Path::new("/proc").join(pid.to_string()).exists()
}

/// Remove the temp siblings of `path` ([`temp_path`]) left by killed runs: those whose
/// process is no longer alive. Returns how many were removed; errors are ignored (a
/// sibling that cannot be removed is left, and the write goes on).
pub fn clean_stale_temps(path: &Path) -> usize {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return 0;
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let Ok(entries) = fs::read_dir(&dir) else {
        return 0;
    };
    let mut removed = 0;
    for e in entries.flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        if let Some(pid) = temp_pid(&n, &name) {
            if !process_alive(pid) && fs::remove_file(e.path()).is_ok() {
                removed += 1;
            }
        }
    }
    removed
}

/// The identity of a path for [`refuse_overwrite`]: the canonical path when it exists,
/// else the canonical parent joined with the name (None when the parent does not exist
/// either: such a path cannot be an existing input).
fn identity(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = fs::canonicalize(path) {
        return Some(p);
    }
    let name = path.file_name()?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    fs::canonicalize(parent).ok().map(|p| p.join(name))
}

/// Refuse a run whose output is one of its inputs, or two of whose outputs are one file.
/// `outputs` and `inputs` are (path, what gave it, e.g. `--out`) pairs; inputs that do not
/// exist are skipped. The error names the output file once:
/// `OUT: is also the input --campaign of this run; refusing to overwrite it (choose another --out)`.
pub fn refuse_overwrite(outputs: &[(&Path, &str)], inputs: &[(&Path, &str)]) -> Result<()> {
    let ins: Vec<(PathBuf, &str)> = inputs
        .iter()
        .filter_map(|(p, what)| fs::canonicalize(p).ok().map(|c| (c, *what)))
        .collect();
    let mut seen: Vec<(PathBuf, &str)> = Vec::new();
    for (out, out_what) in outputs {
        let Some(id) = identity(out) else { continue };
        if let Some((_, in_what)) = ins.iter().find(|(c, _)| *c == id) {
            return Err(Error::input(
                out,
                format!(
                    "is also the input {in_what} of this run; refusing to overwrite it (choose another {out_what})"
                ),
            ));
        }
        if let Some((_, other)) = seen.iter().find(|(c, _)| *c == id) {
            return Err(Error::input(
                out,
                format!(
                    "given both as {other} and as {out_what}; the outputs must be different files"
                ),
            ));
        }
        seen.push((id, out_what));
    }
    Ok(())
}

/// Create the parent folder of `path` if needed.
pub fn ensure_parent(path: &Path) -> Result<()> {
    if let Some(parent) = path.parent() {
        if !parent.as_os_str().is_empty() {
            fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
        }
    }
    Ok(())
}

/// Write a file atomically: `fill` writes into a buffered temp file, which is flushed,
/// synced and renamed to `path`. On any error the temp file is removed.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<fs::File>) -> Result<()>,
{
    ensure_parent(path)?;
    clean_stale_temps(path);
    let tmp = temp_path(path);
    let result = (|| {
        let file = fs::File::create(&tmp).map_err(|e| Error::io(path, e))?;
        let mut w = BufWriter::with_capacity(1 << 16, file);
        fill(&mut w)?;
        w.flush().map_err(|e| Error::io(path, e))?;
        let file = w
            .into_inner()
            .map_err(|e| Error::io(path, e.into_error()))?;
        file.sync_all().map_err(|e| Error::io(path, e))?;
        fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Write bytes atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

/// Read a whole text file, naming it on error (a file that is not UTF-8 text is one line
/// too).
pub fn read_text(path: &Path) -> Result<String> {
    fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overwrite_of_an_input_is_refused_in_any_spelling() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("campaign.toml");
        fs::write(&input, "x").unwrap();
        let sub = dir.path().join("sub");
        fs::create_dir(&sub).unwrap();
        let dotted = sub.join("..").join("campaign.toml");
        let e = refuse_overwrite(&[(&dotted, "--out")], &[(&input, "--campaign")])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("is also the input --campaign") && e.contains("--out"),
            "{e}"
        );
        // a new file beside it is fine, and so is a missing input
        let other = dir.path().join("energy.parquet");
        refuse_overwrite(&[(&other, "--out")], &[(&input, "--campaign")]).unwrap();
        refuse_overwrite(&[(&input, "--out")], &[(&other, "--energy")]).unwrap();
        // two outputs that are one file (not existing yet)
        let e = refuse_overwrite(
            &[
                (&other, "--out"),
                (&sub.join("../energy.parquet"), "--table"),
            ],
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("given both as --out and as --table"), "{e}");
        assert_eq!(fs::read_to_string(&input).unwrap(), "x");
    }

    #[test]
    fn stale_temps_of_dead_processes_are_removed_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("e.parquet");
        // PID 4194304 + 1 is above Linux's pid_max: never alive
        let dead = dir.path().join(".e.parquet.tmp4194305");
        let live = temp_path(&out);
        let unrelated = dir.path().join(".f.parquet.tmp4194305");
        for p in [&dead, &live, &unrelated] {
            fs::write(p, "partial").unwrap();
        }
        assert_eq!(clean_stale_temps(&out), 1);
        assert!(!dead.exists());
        assert!(live.exists() && unrelated.exists());
        write_bytes(&out, b"done").unwrap();
        assert!(!live.exists(), "the run's own temp was renamed into place");
        assert_eq!(fs::read(&out).unwrap(), b"done");
    }
}
