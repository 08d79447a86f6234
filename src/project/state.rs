//! What a project's runs left: `<project>/.dea-fit/state.json`, one file written
//! atomically ([`crate::io::write::atomic_write`]) after every step that ends, so
//! that a killed `make` leaves every finished step recorded and no other. It holds
//! each step's record (the identity it ran with, its exit status, the parts of the
//! identity, so that a later run can say what changed, and the stamps of what it
//! wrote) and the stat cache of the input files ([`crate::project::identity`]).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The format of the state file; another one is read as empty (every step runs).
const FORMAT: u32 = 1;

/// Size and modification time of a file (nanoseconds since the Unix epoch).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stat {
    /// Bytes.
    pub size: u64,
    /// Modification time, ns since 1970.
    pub mtime_ns: u64,
}

impl Stat {
    /// The stat of a file; None for anything else or nothing.
    pub fn of(path: &Path) -> Option<Stat> {
        let m = std::fs::metadata(path).ok()?;
        if !m.is_file() {
            return None;
        }
        let t = m
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos() as u64);
        Some(Stat {
            size: m.len(),
            mtime_ns: t,
        })
    }
}

/// An input file's stat and the SHA-256 of its bytes when it had that stat.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stamp {
    /// Size and time when hashed.
    #[serde(flatten)]
    pub stat: Stat,
    /// Hex SHA-256 of the bytes.
    pub sha256: String,
}

/// The last run of a step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// The identity it ran with ([`crate::project::identity::identity`]).
    pub identity: String,
    /// Its exit status (0 done; anything else failed; -1 ended by a signal or not
    /// started).
    pub exit: i32,
    /// The last line of its log when it failed.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub error: String,
    /// The tool version.
    pub tool: String,
    /// Its arguments.
    pub args: Vec<String>,
    /// Its input files and their SHA-256 ("missing" for one that was not there).
    pub inputs: BTreeMap<String, String>,
    /// The identities of the steps it read, by target.
    pub upstream: BTreeMap<String, String>,
    /// What it wrote: a file's stat, None for a folder.
    pub outputs: BTreeMap<String, Option<Stat>>,
}

/// The state file's content.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct State {
    /// [`FORMAT`].
    pub format: u32,
    /// The stat cache: input file → stat and hash.
    pub files: BTreeMap<String, Stamp>,
    /// The last run of each step, by target.
    pub steps: BTreeMap<String, Record>,
}

/// `<dir>/.dea-fit/state.json`.
pub fn path(dir: &Path) -> PathBuf {
    dir.join(super::STATE_DIR).join("state.json")
}

impl State {
    /// The project's state; empty when there is none yet, and (with a note on
    /// stderr) when the file is unreadable or of another format: every step then
    /// counts as never run.
    pub fn load(dir: &Path) -> State {
        let p = path(dir);
        let Ok(bytes) = std::fs::read(&p) else {
            return State::default();
        };
        match serde_json::from_slice::<State>(&bytes) {
            Ok(s) if s.format == FORMAT => s,
            _ => {
                eprintln!(
                    "note: {} is not a state file of this version; every step counts as never run",
                    p.display()
                );
                State::default()
            }
        }
    }

    /// Record `rec` as the last run of `target` in the state file, as a locked
    /// read-modify-write (the lock of `state.json`, [`crate::io::write`]): the
    /// file is read again under the lock, so that the records of other `make`
    /// processes finishing at once (one job a step under Slurm) are kept. `self`
    /// becomes the merged state; its stat cache entries win (they are newer).
    pub fn record(&mut self, dir: &Path, target: &str, rec: Record) -> Result<()> {
        let _lock = crate::io::write::lock_target(&path(dir))?;
        let mut now = State::load(dir);
        now.files.extend(std::mem::take(&mut self.files));
        now.steps.insert(target.to_string(), rec);
        now.save(dir)?;
        *self = now;
        Ok(())
    }

    /// Write the state atomically.
    pub fn save(&self, dir: &Path) -> Result<()> {
        let mut s = self.clone();
        s.format = FORMAT;
        let json = serde_json::to_vec(&s).map_err(|e| Error::settings(e.to_string()))?;
        crate::io::write::atomic_write(&path(dir), &json)
    }
}
