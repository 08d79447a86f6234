//! What a project's runs left: `<project>/.dea-fit/state.json`, written atomically
//! ([`crate::io::write::atomic_write`]), and its journal
//! `<project>/.dea-fit/journal.jsonl`. It holds each step's record (the identity it
//! ran with, its exit status, the parts of the identity, so that a later run can say
//! what changed, and the stamps of what it wrote) and the stat cache of the input
//! files ([`crate::project::identity`]).
//!
//! A step that ends is recorded by appending one line to the journal (under the
//! state file's lock), so that a killed `make` leaves every finished step recorded
//! and no other, at a cost that does not grow with the project (rewriting the whole
//! state after each of n steps would be O(n²)). Reading the state replays the
//! journal over `state.json`, later lines winning; a line cut short by a kill does
//! not parse and is skipped (its step runs again). [`State::update`] folds the
//! journal into `state.json` (`make` does at its end).

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

/// `<dir>/.dea-fit/journal.jsonl`: the records since `state.json` was written.
fn journal(dir: &Path) -> PathBuf {
    dir.join(super::STATE_DIR).join("journal.jsonl")
}

/// One line of the journal.
#[derive(Serialize, Deserialize)]
struct Entry {
    target: String,
    record: Record,
}

impl State {
    /// The project's state; empty when there is none yet, and (with a note on
    /// stderr) when the file is unreadable or of another format: every step then
    /// counts as never run.
    pub fn load(dir: &Path) -> State {
        let p = path(dir);
        let mut s = match std::fs::read(&p) {
            Err(_) => State::default(),
            Ok(bytes) => match serde_json::from_slice::<State>(&bytes) {
                Ok(s) if s.format == FORMAT => s,
                _ => {
                    eprintln!(
                        "note: {} is not a state file of this version; every step counts as never run",
                        p.display()
                    );
                    State::default()
                }
            },
        };
        if let Ok(text) = std::fs::read_to_string(journal(dir)) {
            for e in text
                .lines()
                .filter_map(|l| serde_json::from_str::<Entry>(l).ok())
            {
                s.steps.insert(e.target, e.record);
            }
        }
        s
    }

    /// Record `rec` as the last run of `target`: one line appended to the journal
    /// under the lock of `state.json` ([`crate::io::write`]), so that the records
    /// of other `make` processes finishing at once (one job a step under Slurm)
    /// are kept; `self` gets it too.
    pub fn record(&mut self, dir: &Path, target: &str, rec: Record) -> Result<()> {
        use std::io::{Read, Seek, SeekFrom, Write};
        let entry = Entry {
            target: target.to_string(),
            record: rec,
        };
        let mut line = serde_json::to_vec(&entry).map_err(|e| Error::settings(e.to_string()))?;
        line.push(b'\n');
        let j = journal(dir);
        let sd = dir.join(super::STATE_DIR);
        std::fs::create_dir_all(&sd).map_err(|e| Error::io(&sd, e))?;
        let _lock = crate::io::write::lock_target(&path(dir))?;
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .read(true)
            .append(true)
            .open(&j)
            .map_err(|e| Error::io(&j, e))?;
        // a line cut short by a kill is ended first, so that this one parses
        let len = f.metadata().map_err(|e| Error::io(&j, e))?.len();
        if len > 0 {
            let mut last = [0u8];
            f.seek(SeekFrom::Start(len - 1))
                .and_then(|_| f.read_exact(&mut last))
                .map_err(|e| Error::io(&j, e))?;
            if last[0] != b'\n' {
                line.insert(0, b'\n');
            }
        }
        f.write_all(&line).map_err(|e| Error::io(&j, e))?;
        self.steps.insert(entry.target, entry.record);
        Ok(())
    }

    /// Change the state as `f` says and write it, journal folded in, as one
    /// locked read-modify-write: the state is read again under the lock (records
    /// other processes appended are kept), `f` applied, `state.json` written
    /// atomically, then the journal removed (a kill in between replays records
    /// `state.json` already holds). Returns the state written.
    pub fn update(dir: &Path, f: impl FnOnce(&mut State)) -> Result<State> {
        let sd = dir.join(super::STATE_DIR);
        std::fs::create_dir_all(&sd).map_err(|e| Error::io(&sd, e))?;
        let _lock = crate::io::write::lock_target(&path(dir))?;
        let mut s = State::load(dir);
        f(&mut s);
        s.format = FORMAT;
        let json = serde_json::to_vec(&s).map_err(|e| Error::settings(e.to_string()))?;
        crate::io::write::atomic_write(&path(dir), &json)?;
        let j = journal(dir);
        match std::fs::remove_file(&j) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::io(&j, e)),
            _ => Ok(s),
        }
    }

    /// Fold the journal into `state.json`, if there is one ([`State::update`]).
    pub fn compact(dir: &Path) -> Result<()> {
        if journal(dir).exists() {
            State::update(dir, |_| {})?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(identity: &str) -> Record {
        Record {
            identity: identity.into(),
            exit: 0,
            error: String::new(),
            tool: "t".into(),
            args: vec![],
            inputs: BTreeMap::new(),
            upstream: BTreeMap::new(),
            outputs: BTreeMap::new(),
        }
    }

    /// Records go to the journal and are read back over state.json, the later one
    /// winning; a line cut short by a kill is skipped and does not spoil the next
    /// record; folding the journal in keeps every record and removes it.
    #[test]
    fn journal_replays_and_folds() {
        let d = tempfile::tempdir().unwrap();
        let dir = d.path();
        let mut s = State::load(dir);
        s.record(dir, "a/x", rec("1")).unwrap();
        s.record(dir, "b/y", rec("2")).unwrap();
        s.record(dir, "a/x", rec("3")).unwrap();
        // a kill in the middle of an append
        let j = journal(dir);
        let mut text = std::fs::read(&j).unwrap();
        text.extend_from_slice(b"{\"target\":\"c/z\",\"rec");
        std::fs::write(&j, text).unwrap();
        s.record(dir, "d/w", rec("4")).unwrap();
        let l = State::load(dir);
        let ids: Vec<(&str, &str)> = l
            .steps
            .iter()
            .map(|(t, r)| (t.as_str(), r.identity.as_str()))
            .collect();
        assert_eq!(ids, [("a/x", "3"), ("b/y", "2"), ("d/w", "4")]);
        let u = State::update(dir, |s| {
            s.steps.remove("b/y");
        })
        .unwrap();
        assert!(!j.exists());
        assert_eq!(u.steps.len(), 2);
        assert_eq!(State::load(dir).steps, u.steps);
    }
}
