//! The run list of a reports folder. Every report page leaves its run's metadata
//! beside it (`run.json` beside `index.html`; `<stem>.run.json` beside a named page
//! such as `bench/hyperelastic.html`), and the folder holding the run folders gets an
//! `index.html` listing every run it holds, newest first, rebuilt from that metadata
//! whenever a command writes a report there: a deleted run folder drops out of the
//! list at the next run, and any number of runs is listed.
//!
//! The list is only ever written over an `index.html` that is itself a run list (it
//! carries [`LIST_MARKER`]); a folder whose `index.html` is anything else (a page of
//! your own, a run's page when reports are nested) keeps it, and gets no list.
//!
//! Runs finishing at once in one folder never drop each other from the list: the
//! list is rebuilt under a lock ([`refresh_index`]).

use super::page::{code, text, Cell, Page, Tone};
use crate::error::{Error, Result};
use crate::io::write::{atomic_write, lock_target};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The schema tag of a run's metadata.
pub const SCHEMA: &str = "dea-fit/run/1";

/// The `<meta>` element that marks an `index.html` as a run list dea-fit may rebuild.
pub const LIST_MARKER: &str = "<meta name=\"dea-fit-page\" content=\"run-list\">";

/// What a report says about its run for the folder's list: what kind of run, on what
/// input, with what model, and its headline numbers.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Run {
    /// The command (`hyperelastic`, `relaxation`, `simulate`, `bench hyperelastic` …).
    pub kind: String,
    /// The input file(s) or manifest.
    pub input: String,
    /// The model, rule, scene or design the run used.
    pub model: String,
    /// A few headline figures, each with its name and unit ("RMSE 1.2 kPa").
    pub headline: Vec<String>,
}

impl Run {
    /// A run of `kind` on `input` with `model`.
    pub fn new(kind: impl Into<String>, input: impl Into<String>, model: impl Into<String>) -> Run {
        Run {
            kind: kind.into(),
            input: input.into(),
            model: model.into(),
            headline: Vec::new(),
        }
    }

    /// With these headline figures.
    pub fn headline(mut self, h: Vec<String>) -> Run {
        self.headline = h;
        self
    }
}

/// A run's metadata as written beside its page (`run.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunMeta {
    /// [`SCHEMA`].
    pub schema: String,
    /// dea-fit version that wrote the report.
    pub tool_version: String,
    /// [`Run::kind`].
    pub kind: String,
    /// The page's title.
    pub title: String,
    /// [`Run::input`].
    pub input: String,
    /// [`Run::model`].
    pub model: String,
    /// The run's status as the page states it ("" when the page has none).
    pub status: String,
    /// [`Run::headline`].
    pub headline: Vec<String>,
    /// The HTML page, relative to the run's folder.
    pub page: String,
    /// When the report was written (RFC 3339, UTC, to the second).
    pub written: String,
    /// The same instant in seconds since 1970 (orders runs written within a second).
    pub written_unix_s: f64,
}

/// The metadata file of the page `<stem>.html`: `run.json` for `index`, else
/// `<stem>.run.json`.
pub fn meta_name(stem: &str) -> String {
    match stem {
        "index" => "run.json".into(),
        s => format!("{s}.run.json"),
    }
}

/// Write the metadata of the page `dir/<stem>.html` and rebuild the run list of the
/// folder holding `dir` ([`refresh_index`]).
pub fn record(dir: &Path, stem: &str, page: &Page, run: Run) -> Result<()> {
    let now = std::time::SystemTime::now();
    let meta = RunMeta {
        schema: SCHEMA.into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        kind: run.kind,
        title: page.title().into(),
        input: run.input,
        model: run.model,
        status: page.status().unwrap_or_default().into(),
        headline: run.headline,
        page: format!("{stem}.html"),
        written: humantime::format_rfc3339_seconds(now).to_string(),
        written_unix_s: now
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64()),
    };
    let json = serde_json::to_string_pretty(&meta).expect("run metadata serialises");
    atomic_write(&dir.join(meta_name(stem)), json.as_bytes())?;
    refresh_index(&parent(dir))?;
    Ok(())
}

/// The folder holding the run folder `dir` (`.` for a relative `dir` of one part).
fn parent(dir: &Path) -> PathBuf {
    match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// One entry of the list: the run folder's name and its metadata, or why the
/// metadata file could not be read.
struct Entry {
    folder: String,
    file: String,
    meta: std::result::Result<RunMeta, String>,
}

/// Every run's metadata in the folders of `root` (one level down), newest first;
/// unreadable metadata last, by folder name.
fn entries(root: &Path) -> Result<Vec<Entry>> {
    let mut out = Vec::new();
    let rd = std::fs::read_dir(root).map_err(|e| Error::io(root, e))?;
    for d in rd.flatten() {
        let folder = d.path();
        if !folder.is_dir() {
            continue;
        }
        let Ok(files) = std::fs::read_dir(&folder) else {
            continue;
        };
        for f in files.flatten() {
            let file = f.file_name().to_string_lossy().into_owned();
            if file != "run.json" && !file.ends_with(".run.json") {
                continue;
            }
            let meta = std::fs::read(f.path())
                .map_err(|e| e.to_string())
                .and_then(|b| serde_json::from_slice::<RunMeta>(&b).map_err(|e| e.to_string()));
            out.push(Entry {
                folder: d.file_name().to_string_lossy().into_owned(),
                file,
                meta,
            });
        }
    }
    out.sort_by(|a, b| match (&a.meta, &b.meta) {
        (Ok(x), Ok(y)) => y
            .written_unix_s
            .total_cmp(&x.written_unix_s)
            .then_with(|| (&a.folder, &a.file).cmp(&(&b.folder, &b.file))),
        (Ok(_), Err(_)) => std::cmp::Ordering::Less,
        (Err(_), Ok(_)) => std::cmp::Ordering::Greater,
        (Err(_), Err(_)) => (&a.folder, &a.file).cmp(&(&b.folder, &b.file)),
    });
    Ok(out)
}

/// The run list of `root` as a page.
fn list_page(root: &Path, entries: &[Entry]) -> Page {
    let mut page = Page::new("Reports").run_list();
    let ok = entries.iter().filter(|e| e.meta.is_ok()).count();
    page.para(vec![text(format!(
        "{ok} run(s) in {}, newest first. dea-fit rebuilds this list from each run's metadata whenever a command writes a report here; each run's page is self-contained (charts inline) and can be mailed on its own.",
        root.display()
    ))]);
    list_table(&mut page, entries);
    page
}

/// The runs of `root`'s folders as a table on `page` (newest first; links relative
/// to `root`), for a page in `root` that is not the run list (a project page).
pub fn list_into(page: &mut Page, root: &Path) -> Result<()> {
    list_table(page, &entries(root)?);
    Ok(())
}

/// The table of `entries`, then those whose metadata could not be read.
fn list_table(page: &mut Page, entries: &[Entry]) {
    let rows: Vec<Vec<Cell>> = entries
        .iter()
        .filter_map(|e| e.meta.as_ref().ok().map(|m| (e, m)))
        .map(|(e, m)| {
            vec![
                Cell::text(m.written.replace('T', " ").replace('Z', " UTC")),
                Cell {
                    text: m.title.clone(),
                    href: Some(format!("{}/{}", e.folder, m.page)),
                    tone: None,
                },
                Cell::text(m.kind.clone()),
                Cell::text(m.input.clone()),
                Cell::text(m.model.clone()),
                Cell {
                    text: m.status.clone(),
                    href: None,
                    tone: (!m.status.is_empty()).then(|| Tone::of(&m.status)),
                },
                Cell::text(m.headline.join("; ")),
            ]
        })
        .collect();
    page.linked_table(
        &[
            "written", "report", "kind", "input", "model", "status", "headline",
        ],
        rows,
    );
    let bad: Vec<_> = entries
        .iter()
        .filter_map(|e| e.meta.as_ref().err().map(|why| (e, why)))
        .map(|(e, why)| {
            vec![
                code(format!("{}/{}", e.folder, e.file)),
                text(format!(": unreadable ({why})")),
            ]
        })
        .collect();
    if !bad.is_empty() {
        page.heading("Runs whose metadata could not be read");
        page.list(bad);
    }
}

/// Set (by `dea-fit make`, for the steps it runs) to leave the run list alone:
/// make rebuilds each list its steps wrote into once at its end, so that n steps
/// cost n reports, not n² list entries.
pub const DEFER_ENV: &str = "DEA_FIT_DEFER_RUN_LIST";

/// Rebuild `root/index.html`, the list of the runs in `root`'s folders, unless
/// `root/index.html` exists and is not a run list (it is then left alone). Written
/// atomically, as a locked read-modify-write (the lock of `index.html`,
/// [`crate::io::write`]): every run writes its metadata before it takes the lock,
/// so the last of several runs finishing at once lists them all, and no run's
/// rebuild from an older listing can replace a newer one.
pub fn refresh_index(root: &Path) -> Result<()> {
    if std::env::var_os(DEFER_ENV).is_some() {
        return Ok(());
    }
    let path = root.join("index.html");
    let _lock = lock_target(&path)?;
    match std::fs::read(&path) {
        Ok(old) if !String::from_utf8_lossy(&old).contains(LIST_MARKER) => return Ok(()),
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(Error::io(&path, e)),
    }
    let entries = entries(root)?;
    atomic_write(&path, list_page(root, &entries).html(None).as_bytes())
}
