//! Atomic output: every file is written to a temporary sibling and renamed into place, so a
//! failed run never leaves a half-written output behind; and the guards around it.
//!
//! * [`destination`]: what an output path is before anything is written. A missing path or
//!   a regular file is replaced (temp sibling, then rename); a character device or a FIFO
//!   (`--out /dev/null`) is written straight into and never renamed over, removed or
//!   truncated to a regular file; a directory, socket or block device is refused in one
//!   line naming the path.
//! * [`OutputFile`]: the one way an output is written: [`OutputFile::create`] opens the temp
//!   sibling (or the device), [`OutputFile::commit`] flushes, syncs and renames it into
//!   place. Every write, the flush and the fsync are checked, so a full disk or device
//!   (`/dev/full`) is an error; on any error (or a drop before the commit) the temp file is
//!   removed. [`write_atomic`], [`write_bytes`], the Parquet streams
//!   ([`crate::table::ParquetStream`]) and the PNG writers ([`write_rendered`], for
//!   backends that write a path themselves) all go through it.
//! * [`temp_path`]: `.<name>.tmp<PID>` beside the output. A run killed while writing leaves
//!   it behind; the next write of the same output removes every such sibling whose process
//!   is gone ([`clean_stale_temps`], called by [`OutputFile::create`]).
//!   A sibling of a live process (another run writing the same output) is left alone.
//! * [`refuse_overwrite`]: no output of a run may be one of its inputs, or another of its
//!   outputs. Paths are compared canonically (symlinks, `..`, relative and absolute
//!   spellings of one file are one file) and by file identity (device and inode: hard
//!   links, bind mounts); an output that does not exist yet is compared by its canonical
//!   parent folder and its name. The refusal is one line naming the output, the input and
//!   the flags that gave them. A character-device output (`/dev/null`) is never refused:
//!   writing into it destroys no file.
//! * [`regular_input`]: an input file named by another input (a sweep file, an index row)
//!   must be a regular file: a device, FIFO, directory, dangling link or symlink loop is
//!   refused, naming the path, before it is opened.

use crate::error::{Error, Result};
use std::fs;
use std::io::{BufWriter, Write};
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Path, PathBuf};

/// The temporary sibling used while `path` is being written.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.tmp{}", std::process::id()))
}

/// Whether `name` is a temp sibling of the output called `output_name`, and the PID in it
/// (a rendered image's temp carries the image extension after the PID: `.tmp123.png`).
fn temp_pid(name: &str, output_name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?.strip_prefix(output_name)?;
    let pid = rest.strip_prefix(".tmp")?;
    let pid = pid.split_once('.').map_or(pid, |(p, _)| p);
    pid.parse::<u32>().ok()
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

/// How an output path is written ([`destination`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dest {
    /// Missing, or a regular file (or a link to one): written to a temp sibling, renamed
    /// over.
    Replace,
    /// A character device or a FIFO (or a link to one): written straight into.
    Stream,
}

/// What the output `path` is: [`Dest::Replace`] for a missing path or a regular file,
/// [`Dest::Stream`] for a character device or FIFO; a directory, socket or block device
/// (anything else) is refused in one line naming the path.
pub fn destination(path: &Path) -> Result<Dest> {
    let meta = match fs::metadata(path) {
        Ok(m) => m,
        // missing, or a dangling link: a new file (the rename replaces the link)
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Dest::Replace),
        Err(e) => return Err(Error::io(path, e)),
    };
    let t = meta.file_type();
    if t.is_file() {
        return Ok(Dest::Replace);
    }
    if t.is_char_device() || t.is_fifo() {
        return Ok(Dest::Stream);
    }
    let what = if t.is_dir() {
        "a directory"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_block_device() {
        "a block device"
    } else {
        "not a regular file"
    };
    Err(Error::input(
        path,
        format!("the output is {what}; refusing to write over it (name a file, or a character device or FIFO to write into)"),
    ))
}

/// An output being written ([`OutputFile::create`], then [`OutputFile::commit`]); dropped
/// before the commit, its temp file is removed and the output left as it was.
#[derive(Debug)]
pub struct OutputFile {
    path: PathBuf,
    /// The temp sibling ([`Dest::Replace`]); None when written straight into a device.
    tmp: Option<PathBuf>,
}

impl OutputFile {
    /// Start writing `path` ([`destination`] decides how): the file to fill, buffered.
    pub fn create(path: &Path) -> Result<(OutputFile, BufWriter<fs::File>)> {
        let (out, file) = match destination(path)? {
            Dest::Replace => {
                ensure_parent(path)?;
                clean_stale_temps(path);
                let tmp = temp_path(path);
                let file = fs::File::create(&tmp).map_err(|e| Error::io(path, e))?;
                let out = OutputFile {
                    path: path.to_path_buf(),
                    tmp: Some(tmp),
                };
                (out, file)
            }
            Dest::Stream => {
                let file = fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(|e| Error::io(path, e))?;
                let out = OutputFile {
                    path: path.to_path_buf(),
                    tmp: None,
                };
                (out, file)
            }
        };
        Ok((out, BufWriter::with_capacity(1 << 16, file)))
    }

    /// The output's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flush and sync what `w` holds (every error checked: a full disk or device fails
    /// here) and rename the temp file into place.
    pub fn commit(mut self, mut w: BufWriter<fs::File>) -> Result<()> {
        let path = self.path.clone();
        w.flush().map_err(|e| Error::io(&path, e))?;
        let file = w
            .into_inner()
            .map_err(|e| Error::io(&path, e.into_error()))?;
        match self.tmp.take() {
            Some(tmp) => {
                let r = sync(&file, &path, false).and_then(|_| {
                    drop(file);
                    fs::rename(&tmp, &path).map_err(|e| Error::io(&path, e))
                });
                if r.is_err() {
                    let _ = fs::remove_file(&tmp);
                }
                r
            }
            None => sync(&file, &path, true),
        }
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if let Some(tmp) = self.tmp.take() {
            let _ = fs::remove_file(tmp);
        }
    }
}

/// fsync `file`, checked; a device or FIFO that cannot be synced (EINVAL) is not an error
/// when `stream` (every write to it was already checked).
fn sync(file: &fs::File, path: &Path, stream: bool) -> Result<()> {
    match file.sync_all() {
        Err(e) if stream && e.kind() == std::io::ErrorKind::InvalidInput => Ok(()),
        r => r.map_err(|e| Error::io(path, e)),
    }
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

/// The (device, inode) of an existing path (links followed).
fn inode(path: &Path) -> Option<(u64, u64)> {
    fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// Refuse a run whose output is one of its inputs, or two of whose outputs are one file.
/// `outputs` and `inputs` are (path, what gave it, e.g. `--out`) pairs; inputs that do not
/// exist are skipped. One file is one canonical path or one (device, inode). The error
/// names the output file and the input's path:
/// `OUT: is also IN, the input --campaign of this run; refusing to overwrite it (choose another --out)`.
/// A character-device output (`/dev/null`) is skipped: writing into it destroys nothing.
pub fn refuse_overwrite(outputs: &[(&Path, &str)], inputs: &[(&Path, &str)]) -> Result<()> {
    type Id = (PathBuf, Option<(u64, u64)>);
    let same = |a: &Id, b: &Id| a.0 == b.0 || (a.1.is_some() && a.1 == b.1);
    let ins: Vec<(Id, &Path, &str)> = inputs
        .iter()
        .filter_map(|(p, what)| fs::canonicalize(p).ok().map(|c| ((c, inode(p)), *p, *what)))
        .collect();
    let mut seen: Vec<(Id, &str)> = Vec::new();
    for (out, out_what) in outputs {
        if fs::metadata(out).is_ok_and(|m| m.file_type().is_char_device()) {
            continue;
        }
        let Some(id) = identity(out) else { continue };
        let id = (id, inode(out));
        if let Some((_, in_path, in_what)) = ins.iter().find(|(c, _, _)| same(c, &id)) {
            return Err(Error::input(
                out,
                format!(
                    "is also {}, the input {in_what} of this run; refusing to overwrite it (choose another {out_what})",
                    in_path.display()
                ),
            ));
        }
        if let Some((_, other)) = seen.iter().find(|(c, _)| same(c, &id)) {
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

/// Check that `path`, a file an input names (`what`: e.g. "sweep file listed in X"), is a
/// regular file before it is opened: a missing file, a dangling link, a symlink loop, a
/// directory, a device or a FIFO (which would block, or never end) is refused in one line
/// naming the path.
pub fn regular_input(path: &Path, what: &str) -> Result<()> {
    let why = match fs::metadata(path) {
        Ok(m) if m.is_file() => return Ok(()),
        Ok(m) => {
            let t = m.file_type();
            if t.is_dir() {
                "is a directory"
            } else if t.is_fifo() {
                "is a FIFO"
            } else if t.is_char_device() || t.is_block_device() {
                "is a device"
            } else if t.is_socket() {
                "is a socket"
            } else {
                "is not a regular file"
            }
            .to_string()
        }
        Err(e) => match fs::symlink_metadata(path) {
            Ok(l) if l.file_type().is_symlink() => {
                // ELOOP (40 on Linux): the link resolves to itself
                if e.raw_os_error() == Some(40) {
                    "is a symlink loop".to_string()
                } else {
                    "is a dangling symbolic link".to_string()
                }
            }
            _ if e.kind() == std::io::ErrorKind::NotFound => "not found".to_string(),
            _ => e.to_string(),
        },
    };
    Err(Error::input(
        path,
        format!("{what} {why} (a regular file is needed)"),
    ))
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

/// Write a file atomically ([`OutputFile`]): `fill` writes into a buffered temp file, which
/// is flushed, synced and renamed to `path` (or, for a device or FIFO, written straight
/// into it). On any error the temp file is removed.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<fs::File>) -> Result<()>,
{
    let (out, mut w) = OutputFile::create(path)?;
    fill(&mut w)?;
    out.commit(w)
}

/// Write bytes atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

/// Write an output that a backend renders to a path itself (plotters' bitmap backend
/// picks the image format from the path's extension, `ext`): `draw` renders into a temp
/// file ending in `.ext`, which then goes through [`OutputFile`] like every output (renamed
/// over a regular file; for a device or FIFO, the temp sits in the system's temp folder
/// and its bytes are written into the device). The temp is removed on any error.
pub fn write_rendered(
    path: &Path,
    ext: &str,
    draw: impl FnOnce(&Path) -> Result<()>,
) -> Result<()> {
    let dest = destination(path)?;
    let tmp = match dest {
        Dest::Replace => {
            ensure_parent(path)?;
            clean_stale_temps(path);
            PathBuf::from(format!("{}.{ext}", temp_path(path).display()))
        }
        Dest::Stream => {
            let name = temp_path(path);
            let name = name.file_name().unwrap_or_default().to_string_lossy();
            std::env::temp_dir().join(format!("pradar{name}.{ext}"))
        }
    };
    // the rendered temp is the output's temp (synced and renamed by the commit), or, for
    // a device, copied into it
    let out = OutputFile {
        path: path.to_path_buf(),
        tmp: Some(tmp.clone()),
    };
    draw(&tmp)?;
    let rendered = fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&tmp)
        .map_err(|e| Error::io(path, e))?;
    match dest {
        Dest::Replace => out.commit(BufWriter::new(rendered)),
        Dest::Stream => {
            let (device, mut w) = OutputFile::create(path)?;
            std::io::copy(&mut &rendered, &mut w).map_err(|e| Error::io(path, e))?;
            device.commit(w)
            // `out` drops here and removes the temp
        }
    }
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
            e.contains("the input --campaign") && e.contains("--out"),
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
    fn hard_links_are_one_file_and_char_devices_never_refused() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("poses.csv");
        fs::write(&input, "x").unwrap();
        let link = dir.path().join("link.csv");
        fs::hard_link(&input, &link).unwrap();
        let e = refuse_overwrite(&[(&link, "--out")], &[(&input, "--poses")])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("input --poses") && e.contains("poses.csv"),
            "{e}"
        );
        let null = Path::new("/dev/null");
        refuse_overwrite(&[(null, "--out"), (null, "--table")], &[(null, "--in")]).unwrap();
    }

    #[test]
    fn outputs_that_are_not_regular_files() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(destination(&dir.path().join("new")).unwrap(), Dest::Replace);
        assert_eq!(destination(Path::new("/dev/null")).unwrap(), Dest::Stream);
        let e = write_bytes(dir.path(), b"x").unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        // written into, not replaced; a full device is an error
        write_bytes(Path::new("/dev/null"), b"discarded").unwrap();
        assert!(fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device());
        let e = write_bytes(Path::new("/dev/full"), b"x")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("/dev/full") && e.contains("No space left"),
            "{e}"
        );
        // a rendered output into a device leaves no temp behind
        let out = dir.path().join("p.png");
        write_rendered(&out, "png", |t| {
            fs::write(t, b"png").map_err(|e| Error::io(t, e))
        })
        .unwrap();
        assert_eq!(fs::read(&out).unwrap(), b"png");
        assert_eq!(
            fs::read_dir(dir.path()).unwrap().count(),
            1,
            "a temp was left"
        );
    }

    #[test]
    fn inputs_must_be_regular_files() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let f = d.join("ok.s2p");
        fs::write(&f, "x").unwrap();
        regular_input(&f, "sweep file").unwrap();
        std::os::unix::fs::symlink("gone", d.join("dangling")).unwrap();
        std::os::unix::fs::symlink("loop", d.join("loop")).unwrap();
        for (p, want) in [
            (d.to_path_buf(), "is a directory"),
            (PathBuf::from("/dev/zero"), "is a device"),
            (d.join("dangling"), "dangling"),
            (d.join("loop"), "symlink loop"),
            (d.join("missing"), "not found"),
        ] {
            let e = regular_input(&p, "sweep file").unwrap_err().to_string();
            assert!(e.contains(want) && e.contains("sweep file"), "{e}");
        }
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
