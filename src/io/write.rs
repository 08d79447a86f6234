//! The write policy: every file dea-fit writes goes through this module.
//!
//! - **Complete first.** A file is written whole to a temporary file beside its
//!   target, `.<name>.tmp-<pid>-<n>-<host>` (created exclusively, so no two writers,
//!   threads or processes, ever share one), flushed and synced; only then is anything
//!   that exists touched. A write that fails (a full disk, a file-size limit, an
//!   error, a panic) removes the temporary file and leaves the target as it was.
//! - **Nothing lost.** A single output file (fit, trajectory, CSV, export, shard) is
//!   put in place by [`AtomicFile::commit_keeping`] / [`write_keeping`] under an
//!   advisory lock (`flock`) on `.<name>.dea-fit-lock` beside it, held across the
//!   three steps that must not interleave with another run's: compare the old file
//!   with the new one, keep a different old file as `<stem>.previous-<n>.<ext>` (the
//!   name claimed by a hard link, which fails when the name is taken, so a kept file
//!   is never replaced), and rename the new file in. The target never disappears: a
//!   reader sees the old file or the new one. Two runs writing one output both keep
//!   their results, one under the name and one kept aside, and each says which.
//! - **No litter.** Temporary files, lock files and the folders a run created are
//!   registered while they live; [`remove_litter`] removes them (and a folder this
//!   run created and left empty) when a run is interrupted (SIGINT, SIGTERM, SIGHUP:
//!   `src/main.rs`) or refused. A run also removes the temporary files it finds
//!   beside its target that a dead process of this host left (the PID is in the
//!   name; `kill(pid, 0)` tells whether it lives).

use crate::error::{Error, Result};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// What a run has made that must not outlive it unfinished: its live temporary
/// and lock files, and the folders it created (in the order created).
struct Litter {
    files: Vec<PathBuf>,
    dirs: Vec<PathBuf>,
}

impl Litter {
    /// No longer litter: `path` was renamed into place or removed.
    fn forget(&mut self, path: &Path) {
        if let Some(i) = self.files.iter().position(|p| p == path) {
            self.files.swap_remove(i);
        }
    }
}

static LITTER: Mutex<Litter> = Mutex::new(Litter {
    files: Vec::new(),
    dirs: Vec::new(),
});

/// The registry, held while a registered file is created, renamed or removed, so
/// that [`remove_litter`] sees each file either live or gone.
fn litter() -> MutexGuard<'static, Litter> {
    LITTER.lock().unwrap_or_else(|e| e.into_inner())
}

/// Remove this run's litter: its live temporary and lock files, then each folder
/// it created that holds nothing (or only the [`MARKER`] of a report folder nothing
/// was written into), deepest first. `then` runs with the registry still held, so
/// no thread of this run can create or rename a registered file after the removal:
/// the signal handler ends the process in `then`.
pub fn remove_litter<T>(then: impl FnOnce() -> T) -> T {
    let mut l = litter();
    for f in l.files.drain(..) {
        let _ = std::fs::remove_file(f);
    }
    for d in l.dirs.drain(..).rev() {
        remove_if_empty(&d);
    }
    then()
}

/// Remove the folder `dir` if it holds nothing but, at most, the report marker.
fn remove_if_empty(dir: &Path) {
    let Ok(names) = std::fs::read_dir(dir).map(|r| {
        r.flatten()
            .map(|e| e.file_name())
            .take(2)
            .collect::<Vec<_>>()
    }) else {
        return;
    };
    let marked = match names.as_slice() {
        [] => false,
        [n] if n == MARKER => true,
        _ => return,
    };
    let marker = dir.join(MARKER);
    if marked && std::fs::remove_file(&marker).is_err() {
        return;
    }
    if std::fs::remove_dir(dir).is_err() && marked {
        // Another run wrote into the folder meanwhile: it stays, marked.
        let _ = std::fs::write(&marker, MARKER_TEXT);
    }
}

/// Create `dir` and its missing parents, registering each folder made here.
fn create_dirs(dir: &Path) -> Result<()> {
    let mut missing = Vec::new();
    let mut d = dir;
    while !d.as_os_str().is_empty() && std::fs::symlink_metadata(d).is_err() {
        missing.push(d);
        d = d.parent().unwrap_or(Path::new(""));
    }
    let mut l = litter();
    for m in missing.into_iter().rev() {
        match std::fs::create_dir(m) {
            Ok(()) => l.dirs.push(m.to_path_buf()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && m.is_dir() => {}
            Err(e) => return Err(Error::io(m, e)),
        }
    }
    Ok(())
}

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

/// The folder of `path` (`.` for a bare file name) and its file name.
fn split(path: &Path) -> (&Path, String) {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    (dir, name)
}

/// This host's name as it appears in temporary file names (letters, digits, `.`,
/// `_`, `-`; at most 64 bytes), so that a run cleaning stale temporary files never
/// takes one of another host's live process on a shared folder for its own.
fn host() -> &'static str {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    HOST.get_or_init(|| {
        let name: String = hostname()
            .chars()
            .map(|c| match c {
                'a'..='z' | 'A'..='Z' | '0'..='9' | '.' | '_' | '-' => c,
                _ => '_',
            })
            .take(64)
            .collect();
        if name.is_empty() {
            "host".into()
        } else {
            name
        }
    })
}

#[cfg(unix)]
fn hostname() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: the buffer is valid for its length; gethostname writes at most that.
    let r = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    match r {
        0 => String::from_utf8_lossy(&buf[..end]).into_owned(),
        _ => String::new(),
    }
}

#[cfg(not(unix))]
fn hostname() -> String {
    std::env::var("COMPUTERNAME").unwrap_or_default()
}

/// Whether the process `pid` of this host is known to be gone (`kill(pid, 0)`
/// fails with ESRCH). A process of another user, or any doubt, counts as alive.
#[cfg(unix)]
fn is_dead(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    // SAFETY: signal 0 sends nothing; it only checks that `pid` exists.
    pid > 0
        && unsafe { libc::kill(pid, 0) } == -1
        && std::io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH)
}

#[cfg(not(unix))]
fn is_dead(_pid: u32) -> bool {
    false
}

/// The process that made the temporary file whose name ends in `rest` (after
/// `.<name>.tmp-`), when that process ran on this host: `<pid>-<n>-<host>`, or the
/// `<pid>` alone of files from dea-fit before the host was in the name.
fn temp_owner(rest: &str) -> Option<u32> {
    let mut parts = rest.splitn(3, '-');
    let pid = parts.next()?;
    if !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let pid = pid.parse().ok()?;
    match (parts.next(), parts.next()) {
        (None, _) => Some(pid),
        (Some(n), Some(h)) if n.bytes().all(|b| b.is_ascii_digit()) && h == host() => Some(pid),
        _ => None,
    }
}

/// Remove the temporary files of `name` in `dir` that dead processes of this host
/// left (an interrupted or killed run): they are never completed.
fn remove_stale_temps(dir: &Path, name: &str) {
    let prefix = format!(".{name}.tmp-");
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let file = e.file_name();
        let Some(rest) = file.to_str().and_then(|f| f.strip_prefix(&prefix)) else {
            continue;
        };
        if temp_owner(rest).is_some_and(is_dead) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Create a new temporary file for `name` in `dir`, exclusively, registered as
/// litter.
fn new_temp(dir: &Path, name: &str) -> Result<(PathBuf, std::fs::File)> {
    static SEQ: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    loop {
        let n = SEQ.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.tmp-{}-{n}-{}", std::process::id(), host()));
        let mut l = litter();
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => {
                l.files.push(tmp.clone());
                return Ok((tmp, f));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(Error::io(&tmp, e)),
        }
    }
}

/// An advisory lock on a single output file: `flock` on `.<name>.dea-fit-lock`
/// beside it, removed by its holder when released. A waiter that finds the lock
/// file it locked removed (or replaced) by the previous holder tries again, so at
/// most one run holds the lock of a target at a time. On a filesystem without
/// locks there is none (`None`), and only the hard-link claims below protect.
pub(crate) struct TargetLock {
    path: PathBuf,
    _file: std::fs::File,
}

/// Take the lock of `target`, waiting for another run that holds it.
#[cfg(unix)]
pub(crate) fn lock_target(target: &Path) -> Result<Option<TargetLock>> {
    use std::os::unix::fs::MetadataExt;
    use std::os::unix::io::AsRawFd;
    let (dir, name) = split(target);
    let path = dir.join(format!(".{name}.dea-fit-lock"));
    loop {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        // SAFETY: flock on a file descriptor this function owns.
        while unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } != 0 {
            let e = std::io::Error::last_os_error();
            match e.raw_os_error() {
                Some(libc::EINTR) => continue,
                Some(libc::ENOLCK | libc::EOPNOTSUPP | libc::ENOSYS) => {
                    let _ = std::fs::remove_file(&path);
                    return Ok(None);
                }
                _ => return Err(Error::io(&path, e)),
            }
        }
        let held = match (file.metadata(), std::fs::metadata(&path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        };
        if held {
            litter().files.push(path.clone());
            return Ok(Some(TargetLock { path, _file: file }));
        }
    }
}

#[cfg(not(unix))]
pub(crate) fn lock_target(_target: &Path) -> Result<Option<TargetLock>> {
    Ok(None)
}

impl Drop for TargetLock {
    fn drop(&mut self) {
        // Removed while still locked; the file closes (and unlocks) after this.
        let mut l = litter();
        let _ = std::fs::remove_file(&self.path);
        l.forget(&self.path);
    }
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
    /// Start writing `path`, creating parent directories, and remove the temporary
    /// files of `path` that dead processes left beside it.
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
        let (dir, name) = split(path);
        create_dirs(dir)?;
        remove_stale_temps(dir, &name);
        let (tmp, f) = new_temp(dir, &name)?;
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

    /// A failed write into the temporary file, saying that nothing was replaced.
    fn unwritten(&self, e: std::io::Error) -> std::io::Error {
        match &self.tmp {
            Some(_) => std::io::Error::new(
                e.kind(),
                format!("{e}; the new file could not be written whole, so nothing was replaced or kept aside"),
            ),
            None => e,
        }
    }

    /// Flush and sync the temporary file (its path, `None` for a stream).
    fn finish(&mut self) -> Result<Option<PathBuf>> {
        let done = self.out.flush().and_then(|()| match &self.tmp {
            Some(_) => self.out.get_ref().sync_all(),
            None => Ok(()),
        });
        done.map_err(|e| Error::io(&self.path, self.unwritten(e)))?;
        Ok(self.tmp.clone())
    }

    /// Rename the complete temporary file onto the target.
    fn put_in_place(&mut self, tmp: &Path) -> Result<()> {
        let mut l = litter();
        std::fs::rename(tmp, &self.path).map_err(|e| Error::io(&self.path, e))?;
        l.forget(tmp);
        self.tmp = None;
        Ok(())
    }

    /// Put the complete file in place (replacing what was there).
    pub fn commit(mut self) -> Result<()> {
        if let Some(tmp) = self.finish()? {
            self.put_in_place(&tmp)?;
        }
        Ok(())
    }

    /// Put the complete file in place without losing what was there, as
    /// [`write_keeping`] does: an existing file with other bytes is first kept
    /// as `<stem>.previous-<n>.<ext>`. The files are compared in chunks (neither is
    /// read whole).
    pub fn commit_keeping(self) -> Result<Replaced> {
        let tmp = self.tmp.clone();
        self.commit_compared(|old| match &tmp {
            Some(t) => same_bytes(old, t),
            None => Ok(false),
        })
    }

    /// Put the complete file in place under the target's lock: nothing there
    /// ([`Replaced::New`]), the same result (`same(target)` true, refreshed), or
    /// another file, kept aside ([`keep_aside`]) before the rename. An existing
    /// target that cannot be read is an error, never taken for "no file"; a rename
    /// that fails takes the kept name back, so the old file stays under its name.
    fn commit_compared(
        mut self,
        same: impl FnOnce(&Path) -> std::io::Result<bool>,
    ) -> Result<Replaced> {
        let Some(tmp) = self.finish()? else {
            return Ok(Replaced::Stream);
        };
        let _lock = lock_target(&self.path)?;
        let (replaced, kept) = match same(&self.path) {
            Ok(true) => (Replaced::Same, None),
            Ok(false) => {
                let k = keep_aside(&self.path)?;
                (Replaced::KeptAs(k.path.clone()), Some(k))
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => (Replaced::New, None),
            Err(e) => return Err(Error::io(&self.path, e)),
        };
        if let Err(e) = self.put_in_place(&tmp) {
            if let Some(k) = kept {
                k.undo(&self.path);
            }
            return Err(e);
        }
        Ok(replaced)
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.out.write(buf).map_err(|e| self.unwritten(e))
    }
    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.out.write_all(buf).map_err(|e| self.unwritten(e))
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush().map_err(|e| self.unwritten(e))
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(tmp) = &self.tmp {
            let mut l = litter();
            let _ = std::fs::remove_file(tmp);
            l.forget(tmp);
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
/// export, shard) without ever losing what was there: the new file is written whole
/// first, then, under the target's lock, if `path` exists and `same(old_bytes)` is
/// false (including an old file that is not UTF-8 text, or not ours at all), the
/// old file is kept as `<stem>.previous-<n>.<ext>` (first free n) and the new one
/// renamed in (see the module's policy). An existing path that cannot be read is an
/// error, never taken for "no file".
pub fn write_keeping(path: &Path, bytes: &[u8], same: impl Fn(&[u8]) -> bool) -> Result<Replaced> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes).map_err(|e| Error::io(path, e))?;
    f.commit_compared(|old| std::fs::read(old).map(|b| same(&b)))
}

/// An old file kept aside, and how (to take it back if the new file cannot be
/// renamed in).
struct Kept {
    path: PathBuf,
    /// A hard link (the old file is still under its name too), else a rename.
    linked: bool,
}

impl Kept {
    /// Put things back as they were before [`keep_aside`].
    fn undo(self, target: &Path) {
        let _ = match self.linked {
            true => std::fs::remove_file(&self.path),
            false => std::fs::rename(&self.path, target),
        };
    }
}

/// Keep the file at `path` under the first free `<stem>.previous-<n>.<ext>`,
/// claimed by a hard link: creating a link fails when the name is taken, so a name
/// another run (or a file of the user's) holds is never replaced, and `path` keeps
/// its file until the new one is renamed over it. Where links are not supported,
/// the file is renamed to a name found free (under the target's lock).
fn keep_aside(path: &Path) -> Result<Kept> {
    for n in 1u64.. {
        let keep = previous_name(path, n);
        match std::fs::hard_link(path, &keep) {
            Ok(()) => {
                return Ok(Kept {
                    path: keep,
                    linked: true,
                })
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(Error::io(path, e)),
            Err(_) if std::fs::symlink_metadata(&keep).is_ok() => continue,
            Err(_) => {
                std::fs::rename(path, &keep).map_err(|e| Error::io(path, e))?;
                return Ok(Kept {
                    path: keep,
                    linked: false,
                });
            }
        }
    }
    unreachable!("a free previous-<n> name exists below 2⁶⁴")
}

/// A fit file: as [`write_keeping`], `same` comparing the old text with the new fit
/// (an old file that is not UTF-8 is not the same fit).
pub fn write_fit(path: &Path, bytes: &[u8], same: impl Fn(&str) -> bool) -> Result<Replaced> {
    write_keeping(path, bytes, |old| std::str::from_utf8(old).is_ok_and(&same))
}

/// `<stem>.previous-<n>.<ext>` beside `path`.
fn previous_name(path: &Path, n: u64) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    path.with_file_name(format!("{stem}.previous-{n}{ext}"))
}

/// The file that marks a directory as dea-fit's own output.
pub const MARKER: &str = ".dea-fit-output";

/// What the [`MARKER`] file says.
const MARKER_TEXT: &[u8] =
    b"dea-fit writes into this directory and replaces its own files here on the next run.\n";

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
    atomic_write(&marker, MARKER_TEXT)
}
