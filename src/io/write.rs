//! Atomic output: write to a temporary file beside the target, then rename, so a
//! reader never sees half a file and a crash never leaves one.

use crate::error::{Error, Result};
use std::io::{BufRead, Write};
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
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes).map_err(|e| Error::io(path, e))?;
    f.commit()
}

/// A file written as a stream and put in place only when complete: the bytes go
/// to a temporary file beside the target, renamed onto it by [`AtomicFile::commit`];
/// dropped without a commit (an error, a panic), the temporary file is removed and
/// the target never appears half-written. A device or a pipe is written into
/// directly.
pub struct AtomicFile {
    path: PathBuf,
    /// The temporary file, `None` for a device or a pipe.
    tmp: Option<PathBuf>,
    out: std::io::BufWriter<std::fs::File>,
}

impl AtomicFile {
    /// Start writing `path`, creating parent directories.
    pub fn create(path: &Path) -> Result<AtomicFile> {
        if is_stream(path) {
            let f = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(|e| Error::io(path, e))?;
            return Ok(AtomicFile {
                path: path.to_path_buf(),
                tmp: None,
                out: std::io::BufWriter::new(f),
            });
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
        let f = std::fs::File::create(&tmp).map_err(|e| Error::io(path, e))?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp: Some(tmp),
            out: std::io::BufWriter::with_capacity(1 << 16, f),
        })
    }

    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flush and sync the temporary file (its path, `None` for a stream).
    fn finish(&mut self) -> Result<Option<PathBuf>> {
        self.out.flush().map_err(|e| Error::io(&self.path, e))?;
        if let Some(tmp) = &self.tmp {
            self.out
                .get_ref()
                .sync_all()
                .map_err(|e| Error::io(&self.path, e))?;
            return Ok(Some(tmp.clone()));
        }
        Ok(None)
    }

    /// Put the complete file in place (replacing what was there).
    pub fn commit(mut self) -> Result<()> {
        if let Some(tmp) = self.finish()? {
            std::fs::rename(&tmp, &self.path).map_err(|e| Error::io(&self.path, e))?;
            self.tmp = None;
        }
        Ok(())
    }

    /// Put the complete file in place without losing what was there, as
    /// [`write_keeping`] does: an existing file with other bytes is first kept
    /// as `<stem>.previous-<n>.<ext>`. The files are compared in chunks (neither is
    /// read whole).
    pub fn commit_keeping(mut self) -> Result<Replaced> {
        let Some(tmp) = self.finish()? else {
            return Ok(Replaced::Stream);
        };
        let same = |old: &Path| -> std::io::Result<bool> { same_bytes(old, &tmp) };
        let replaced = keep_aside(&self.path, same)?;
        std::fs::rename(&tmp, &self.path).map_err(|e| Error::io(&self.path, e))?;
        self.tmp = None;
        Ok(replaced)
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.out.write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.out.write_all(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(tmp) = &self.tmp {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Whether two files hold the same bytes, read in chunks.
fn same_bytes(a: &Path, b: &Path) -> std::io::Result<bool> {
    let (fa, fb) = (std::fs::File::open(a)?, std::fs::File::open(b)?);
    if fa.metadata()?.len() != fb.metadata()?.len() {
        return Ok(false);
    }
    let (mut ra, mut rb) = (
        std::io::BufReader::with_capacity(1 << 16, fa),
        std::io::BufReader::with_capacity(1 << 16, fb),
    );
    loop {
        let (ba, bb) = (ra.fill_buf()?, rb.fill_buf()?);
        let n = ba.len().min(bb.len());
        if n == 0 {
            return Ok(ba.len() == bb.len());
        }
        if ba[..n] != bb[..n] {
            return Ok(false);
        }
        ra.consume(n);
        rb.consume(n);
    }
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
    let replaced = keep_aside(path, |p| std::fs::read(p).map(|old| same(&old)))?;
    atomic_write(path, bytes)?;
    Ok(replaced)
}

/// Before `path` is replaced: nothing there ([`Replaced::New`]), the same result
/// (`same(path)` true), or another file, renamed to `<stem>.previous-<n>.<ext>`. An
/// existing path that cannot be read is an error, never taken for "no file".
fn keep_aside(path: &Path, same: impl FnOnce(&Path) -> std::io::Result<bool>) -> Result<Replaced> {
    match same(path) {
        Ok(true) => Ok(Replaced::Same),
        Ok(false) => {
            let keep = previous_name(path);
            std::fs::rename(path, &keep).map_err(|e| Error::io(path, e))?;
            Ok(Replaced::KeptAs(keep))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Replaced::New),
        Err(e) => Err(Error::io(path, e)),
    }
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
