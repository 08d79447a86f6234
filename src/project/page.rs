//! The project page, `<project>/reports/index.html` (and `index.md`), written by
//! `dea-fit make`: every target with where it stands (up to date, stale, failed,
//! blocked, with the reason), grouped by material, actuator or design, with its
//! report's status, model and headline figures (the run metadata each command
//! leaves beside its page, [`crate::report::runs`]); then the provenance of every
//! ranking and identification: the chain of steps it read, back to the raw files
//! with the SHA-256 each step last ran with (the project state); then every run of
//! the reports folder (the run list a single command writes there).
//!
//! It replaces the run list as `reports/index.html` (which single commands then
//! leave alone, [`crate::report::runs::refresh_index`]), and is only ever written
//! over a missing page, a run list or an earlier project page ([`MARKER`]).
//!
//! The page has an identity too ([`identity`]): what the steps say, the records
//! they stand on and the stat of every run folder under `reports/`. When it is the
//! one the page was last written with (`.dea-fit/page.json`) and `index.html` is
//! as written, the page is left as it is: an up-to-date `make` reads no report.

use crate::error::{Error, Result};
use crate::io::write::{atomic_write, lock_target};
use crate::project::file::Project;
use crate::project::run::{Standing, StepReport};
use crate::project::state::{Stat, State};
use crate::report::page::{code, text, Cell, Page, Tone};
use crate::report::runs::{self, RunMeta, LIST_MARKER};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::PathBuf;

/// The `<meta>` element that marks an `index.html` as a project page.
pub const MARKER: &str = "<meta name=\"dea-fit-page\" content=\"project\">";

/// The folder of the project page, relative to the project.
pub const DIR: &str = "reports";

fn tone(s: Standing) -> Tone {
    match s {
        Standing::UpToDate | Standing::Ran => Tone::Good,
        Standing::Stale => Tone::Caution,
        Standing::Failed | Standing::Blocked => Tone::Bad,
    }
}

/// A step's report: its folder (project-relative) and the metadata its command
/// left there, if it ran.
fn report_of(p: &Project, outputs: &[String]) -> Option<(String, RunMeta)> {
    outputs.iter().find_map(|o| {
        let dir = p.dir.join(o);
        let bytes = std::fs::read(dir.join(runs::meta_name("index"))).ok()?;
        let m: RunMeta = serde_json::from_slice(&bytes).ok()?;
        Some((o.clone(), m))
    })
}

/// A link from the page in `reports/` to `file` (project-relative).
fn href(file: &str) -> String {
    match file.strip_prefix(&format!("{DIR}/")) {
        Some(r) => r.to_string(),
        None => format!("../{file}"),
    }
}

/// The page of a project whose steps stand as `steps` say, with `state` their
/// records ([`super::run::status`]).
pub fn page(p: &Project, steps: &[StepReport], state: &State) -> Result<Page> {
    let mut page = Page::new("Project").marked(MARKER);
    let count = |x: Standing| steps.iter().filter(|s| s.state == x).count();
    let parts: Vec<String> = [
        Standing::UpToDate,
        Standing::Stale,
        Standing::Failed,
        Standing::Blocked,
    ]
    .into_iter()
    .filter(|&x| count(x) > 0)
    .map(|x| format!("{} {}", count(x), x.word()))
    .collect();
    page.para(vec![
        text(format!(
            "{} step(s) of {}: {}. Rebuilt by ",
            steps.len(),
            super::FILE,
            parts.join(", ")
        )),
        code("dea-fit make"),
        text("; "),
        code("dea-fit status"),
        text(" says the same in a terminal, and "),
        code("dea-fit status --json"),
        text(" gives each step's command line."),
    ]);
    // targets, grouped by the name before the slash, in dependency order
    let mut names: Vec<&str> = Vec::new();
    for s in steps {
        let n = s.target.split('/').next().unwrap_or_default();
        if !names.contains(&n) {
            names.push(n);
        }
    }
    page.heading("Targets");
    for n in names {
        page.subheading(n);
        let rows = steps
            .iter()
            .filter(|s| s.target.split('/').next() == Some(n))
            .map(|s| {
                let rep = report_of(p, &s.outputs);
                let meta = rep.as_ref().map(|(_, m)| m);
                vec![
                    Cell {
                        text: s.target.clone(),
                        href: rep.as_ref().map(|(d, m)| href(&format!("{d}/{}", m.page))),
                        tone: None,
                    },
                    Cell::text(s.kind.clone()),
                    Cell {
                        text: s.state.word().into(),
                        href: None,
                        tone: Some(tone(s.state)),
                    },
                    Cell::text(s.reason.clone()),
                    Cell {
                        text: meta.map_or(String::new(), |m| m.status.clone()),
                        href: None,
                        tone: meta
                            .filter(|m| !m.status.is_empty())
                            .map(|m| Tone::of(&m.status)),
                    },
                    Cell::text(meta.map_or(String::new(), |m| m.model.clone())),
                    Cell::text(meta.map_or(String::new(), |m| m.headline.join("; "))),
                ]
            })
            .collect();
        page.linked_table(
            &[
                "target", "kind", "state", "reason", "status", "model", "headline",
            ],
            rows,
        );
    }
    provenance(&mut page, p, state);
    page.heading("Runs in reports/");
    page.text(
        "Every report in this folder, newest first (the run list single commands keep here when there is no project page).",
    );
    runs::list_into(&mut page, &p.dir.join(DIR))?;
    Ok(page)
}

/// For every ranking and identification: the steps it reads, transitively, and
/// each one's raw files with the SHA-256 it last ran with.
fn provenance(page: &mut Page, p: &Project, state: &State) {
    let finals: Vec<usize> = (0..p.steps.len())
        .filter(|&i| matches!(p.steps[i].kind.as_str(), "rank" | "identify"))
        .collect();
    if finals.is_empty() {
        return;
    }
    page.heading("Provenance");
    page.text(
        "Every ranked figure and identified constant back to the raw files: the steps each ranking or identification read, transitively, and the SHA-256 of every file each of them last ran with (.dea-fit/state.json).",
    );
    for f in finals {
        // the chain: this step, then every step it reads, depth first, each once
        let mut chain = vec![f];
        let mut k = 0;
        while k < chain.len() {
            for &j in &p.steps[chain[k]].needs {
                if !chain.contains(&j) {
                    chain.push(j);
                }
            }
            k += 1;
        }
        let s = &p.steps[f];
        page.subheading(&s.target);
        let reads: Vec<&str> = chain[1..]
            .iter()
            .map(|&j| p.steps[j].target.as_str())
            .collect();
        page.para(vec![
            code(&s.target),
            text(if reads.is_empty() {
                " reads no other step.".to_string()
            } else {
                format!(" ← {}", reads.join(", "))
            }),
        ]);
        let mut rows = Vec::new();
        for &j in &chain {
            let t = &p.steps[j];
            let rec = state.steps.get(&t.target);
            for file in &t.inputs {
                let sha = match rec.and_then(|r| r.inputs.get(file)) {
                    Some(h) => h.clone(),
                    None => "not run yet".into(),
                };
                rows.push(vec![t.target.clone(), file.clone(), sha]);
            }
        }
        page.table(&["step", "file", "SHA-256"], rows);
    }
}

/// What [`write`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum Wrote {
    /// The page was written, at this path.
    Written(PathBuf),
    /// The page at this path was already the page of this identity.
    Unchanged(PathBuf),
    /// `index.html` is a page of someone else's: nothing was written (why).
    Refused(String),
}

/// The page's identity: the SHA-256 of the tool version, every step's report
/// (target, kind, state, reason, outputs, command), the identity and exit status
/// of every record, and the name, size and modification time of every run folder
/// under `reports/` (a report written or removed in one changes its folder's
/// time: files are written by rename).
fn identity(p: &Project, steps: &[StepReport], state: &State) -> String {
    let mut h = Sha256::new();
    let mut field = |s: &[u8]| {
        h.update((s.len() as u64).to_le_bytes());
        h.update(s);
    };
    field(env!("CARGO_PKG_VERSION").as_bytes());
    field(&serde_json::to_vec(steps).expect("step reports serialise"));
    for (t, r) in &state.steps {
        field(t.as_bytes());
        field(r.identity.as_bytes());
        field(&r.exit.to_le_bytes());
    }
    let mut runs: Vec<(String, u64, u64)> = std::fs::read_dir(p.dir.join(DIR))
        .map(|rd| {
            rd.flatten()
                .filter_map(|e| {
                    let m = e.metadata().ok().filter(|m| m.is_dir())?;
                    let t = m
                        .modified()
                        .ok()
                        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                        .map_or(0, |d| d.as_nanos() as u64);
                    Some((e.file_name().to_string_lossy().into_owned(), m.len(), t))
                })
                .collect()
        })
        .unwrap_or_default();
    runs.sort();
    for (name, size, t) in runs {
        field(name.as_bytes());
        field(&size.to_le_bytes());
        field(&t.to_le_bytes());
    }
    crate::io::hex(&h.finalize())
}

/// The page's identity and the stat of the `index.html` written with it.
#[derive(Serialize, Deserialize, PartialEq)]
struct Written {
    identity: String,
    html: Stat,
}

/// `<project>/.dea-fit/page.json`.
fn written_path(p: &Project) -> PathBuf {
    p.dir.join(super::STATE_DIR).join("page.json")
}

/// Write the project page into `<project>/reports/` (`index.html` and
/// `index.md`, atomically, under the lock of `index.html` that the run list takes
/// too), unless it is the page of this very identity already, or `index.html`
/// there is a page of someone else's.
pub fn write(p: &Project, steps: &[StepReport], state: &State) -> Result<Wrote> {
    let dir = p.dir.join(DIR);
    let html = dir.join("index.html");
    let id = identity(p, steps, state);
    let was: Option<Written> = std::fs::read(written_path(p))
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok());
    if was.is_some_and(|w| w.identity == id && Stat::of(&html) == Some(w.html)) {
        return Ok(Wrote::Unchanged(html));
    }
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let _lock = lock_target(&html)?;
    match std::fs::read(&html) {
        Ok(old) => {
            let old = String::from_utf8_lossy(&old);
            if !old.contains(MARKER) && !old.contains(LIST_MARKER) {
                return Ok(Wrote::Refused(format!(
                    "{} is not a page dea-fit wrote; the project page was not written over it",
                    html.display()
                )));
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(Error::io(&html, e)),
    }
    let page = page(p, steps, state)?;
    atomic_write(&dir.join("index.md"), page.markdown().as_bytes())?;
    atomic_write(&html, page.html(Some("index.md")).as_bytes())?;
    if let Some(st) = Stat::of(&html) {
        let w = Written {
            identity: id,
            html: st,
        };
        let json = serde_json::to_vec(&w).expect("the page's identity serialises");
        atomic_write(&written_path(p), &json)?;
    }
    Ok(Wrote::Written(html))
}
