//! Atomic output: write to a temporary file beside the target, then rename, so a
//! reader never sees half a file and a crash never leaves one.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Write `bytes` to `path` atomically, creating parent directories.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<()> {
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

/// What happened to an existing file when a fit was written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Replaced {
    /// There was no file.
    New,
    /// The file held the same result and was refreshed.
    Same,
    /// The file held a different result; it was kept under this name.
    KeptAs(PathBuf),
}

/// Write a fit file without ever losing an earlier, different fit: if `path` exists
/// and `same(old_text)` is false, the old file is first renamed to
/// `<stem>.previous-<n>.json` (first free n).
pub fn write_fit(path: &Path, bytes: &[u8], same: impl Fn(&str) -> bool) -> Result<Replaced> {
    let replaced = match std::fs::read_to_string(path) {
        Ok(old) if same(&old) => Replaced::Same,
        Ok(_) => {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let keep = (1..)
                .map(|n| path.with_file_name(format!("{stem}.previous-{n}.json")))
                .find(|p| !p.exists())
                .expect("an unused name exists");
            std::fs::rename(path, &keep).map_err(|e| Error::io(path, e))?;
            Replaced::KeptAs(keep)
        }
        Err(_) => Replaced::New,
    };
    atomic_write(path, bytes)?;
    Ok(replaced)
}
