//! A step's identity: the SHA-256 of the tool version, its argument list (its
//! settings), the bytes of every file it reads (by their SHA-256) and the
//! identities of the steps whose outputs it reads. A step runs when its identity
//! differs from the one it last ran with; the identity of a step it reads is known
//! before that step runs, so a whole plan is known before anything runs.
//!
//! Hashing is the cost of an up-to-date project: a file is hashed only when its
//! size or modification time differs from the stat cache's ([`Hashes`]).

use crate::project::file::Step;
use crate::project::state::{Stamp, Stat};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::Path;

/// The value of an input that is not there.
pub const MISSING: &str = "missing";

/// File hashes through the stat cache of the state file.
pub struct Hashes<'a> {
    dir: &'a Path,
    cache: &'a mut BTreeMap<String, Stamp>,
    /// Whether the cache changed (and is worth saving).
    pub changed: bool,
}

impl<'a> Hashes<'a> {
    /// Hashes of files under `dir` through `cache`.
    pub fn new(dir: &'a Path, cache: &'a mut BTreeMap<String, Stamp>) -> Self {
        Hashes {
            dir,
            cache,
            changed: false,
        }
    }

    /// The hex SHA-256 of a project-relative file, [`MISSING`] when it cannot be
    /// read; hashed only when its stat is not the cached one.
    pub fn of(&mut self, rel: &str) -> String {
        let p = self.dir.join(rel);
        let Some(stat) = Stat::of(&p) else {
            return MISSING.into();
        };
        if let Some(s) = self.cache.get(rel) {
            if s.stat == stat {
                return s.sha256.clone();
            }
        }
        let Ok(bytes) = std::fs::read(&p) else {
            return MISSING.into();
        };
        let sha256 = crate::io::sha256_hex(&bytes);
        self.cache.insert(
            rel.to_string(),
            Stamp {
                stat,
                sha256: sha256.clone(),
            },
        );
        self.changed = true;
        sha256
    }
}

/// The identity of `step` with these input hashes and upstream identities.
pub fn identity(
    step: &Step,
    inputs: &BTreeMap<String, String>,
    upstream: &BTreeMap<String, String>,
) -> String {
    let mut h = Sha256::new();
    let mut field = |tag: &str, s: &str| {
        h.update(tag.as_bytes());
        h.update((s.len() as u64).to_le_bytes());
        h.update(s.as_bytes());
    };
    field("tool", env!("CARGO_PKG_VERSION"));
    for a in &step.args {
        field("arg", a);
    }
    for (p, x) in inputs {
        field("input", p);
        field("sha256", x);
    }
    for (t, x) in upstream {
        field("upstream", t);
        field("identity", x);
    }
    crate::io::hex(&h.finalize())
}
