//! Atomic output: write to a temporary file beside the target, then rename, so a
//! reader never sees half a file and a crash never leaves one.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Whether `path` exists and is not a regular file or a directory: a device or a
/// pipe (`/dev/null`, `/dev/stdout`, a FIFO). Such a target is written into, never
/// renamed over (renaming onto `/dev/null` would replace the device with a file)
/// and never kept aside.
fn is_stream(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Write `bytes` to `path` atomically, creating parent directories. A device or a
/// pipe is written into directly (it has no content to protect).
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<()> {
    if is_stream(path) {
        return std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .and_then(|mut f| f.write_all(bytes))
            .map_err(|e| Error::io(path, e));
    }
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// What happened to an existing file when a result was written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Replaced {
    /// There was no file.
    New,
    /// The file held the same result and was refreshed.
    Same,
    /// The file held something else; it was kept under this name.
    KeptAs(PathBuf),
    /// The path is a device or a pipe (`/dev/null`); it was written into.
    Stream,
}

/// Write a single output file (fit, result, trajectory, synthetic data, generated
/// export) without ever losing what was there: if `path` exists and `same(old_bytes)`
/// is false (including an old file that is not UTF-8 text, or not ours at all), the
/// old file is first renamed to `<stem>.previous-<n>.<ext>` (first free n). An
/// existing path that cannot be read is an error, never taken for "no file".
pub fn write_keeping(path: &Path, bytes: &[u8], same: impl Fn(&[u8]) -> bool) -> Result<Replaced> {
    if is_stream(path) {
        atomic_write(path, bytes)?;
        return Ok(Replaced::Stream);
    }
    let replaced = match std::fs::read(path) {
        Ok(old) if same(&old) => Replaced::Same,
        Ok(_) => {
            let keep = previous_name(path);
            std::fs::rename(path, &keep).map_err(|e| Error::io(path, e))?;
            Replaced::KeptAs(keep)
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Replaced::New,
        Err(e) => return Err(Error::io(path, e)),
    };
    atomic_write(path, bytes)?;
    Ok(replaced)
}

/// A fit file: as [`write_keeping`], `same` comparing the old text with the new fit
/// (an old file that is not UTF-8 is not the same fit).
pub fn write_fit(path: &Path, bytes: &[u8], same: impl Fn(&str) -> bool) -> Result<Replaced> {
    write_keeping(path, bytes, |old| std::str::from_utf8(old).is_ok_and(&same))
}

/// The first free `<stem>.previous-<n>.<ext>` beside `path`.
fn previous_name(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    (1u64..)
        .map(|n| path.with_file_name(format!("{stem}.previous-{n}{ext}")))
        .find(|p| !p.exists())
        .unwrap_or_else(|| path.with_extension("previous"))
}

/// The file that marks a directory as dea-fit's own output.
pub const MARKER: &str = ".dea-fit-output";

/// Take `dir` as an output directory (report, bench tables): a directory that does
/// not exist or is empty is created and marked with [`MARKER`]; one that holds the
/// marker is dea-fit's own, and its files are replaced; any other directory is
/// refused, since writing `index.md` and charts into it could replace files dea-fit
/// did not write.
pub fn claim_dir(dir: &Path) -> Result<()> {
    let marker = dir.join(MARKER);
    if marker.is_file() {
        return Ok(());
    }
    if dir.exists() {
        if !dir.is_dir() {
            return Err(
                Error::settings(format!("output directory {} is a file", dir.display()))
                    .with_hint("choose another directory"),
            );
        }
        let mut entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
        if entries.next().is_some() {
            return Err(Error::settings(format!(
                "output directory {} holds files dea-fit did not write (it has no {MARKER} file); writing there could replace them",
                dir.display()
            ))
            .with_hint("choose another directory, or move those files away"));
        }
    }
    atomic_write(
        &marker,
        b"dea-fit writes into this directory and replaces its own files here on the next run.\n",
    )
}
