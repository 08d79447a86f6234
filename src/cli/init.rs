//! `dea-fit init`: write a first `dea-fit.toml` from the data files in a folder.
//!
//! Each CSV file is classified by the first of the tool's own readers that takes
//! it with default settings (the column detection of the commands themselves): an
//! actuator trace, a DMA sweep, a breakdown series, an LCR export, a relaxation
//! curve, a tensile test. Files of one kind in one folder make one step of the
//! material named by the folder; what a step cannot run without (an LCR coupon's
//! geometry, a trace's scene) is written as a commented line to fill in.

use dea_fit::io;
use dea_fit::project::{glob, FILE, STATE_DIR};
use dea_fit::{Error, Result};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    dir: super::make::ProjectDir,
}

/// Whether a reader takes a file.
type Reader = fn(&Path) -> bool;

/// What a data file is, by the reader that takes it (tried in this order: a
/// trace's time and voltage would read as neither of the others).
const READERS: [(&str, Reader); 6] = [
    ("trace", |p| io::trace::read(p).is_ok()),
    ("dma", |p| {
        dea_fit::dma::read::read_with(p, &io::table::ColumnMap::default()).is_ok()
    }),
    ("breakdown", |p| {
        io::breakdown::read(p, &Default::default()).is_ok()
    }),
    ("permittivity", |p| {
        io::lcr::read(p, &Default::default()).is_ok()
    }),
    ("relaxation", |p| {
        io::relaxation::read(p, &Default::default()).is_ok()
    }),
    ("tensile", |p| {
        io::tensile::read(p, &Default::default()).is_ok()
    }),
];

pub fn run(a: Args) -> Result<i32> {
    let file = a.dir.dir.join(FILE);
    if file.exists() {
        return Err(Error::settings(format!("{} exists already", file.display()))
            .with_hint("init never overwrites a project file: edit it (docs/project.md), or move it away and run init again"));
    }
    let mut csv = Vec::new();
    collect(&a.dir.dir, "", &mut csv);
    csv.sort();
    // folder → kind → files
    let mut found: BTreeMap<String, BTreeMap<&str, Vec<String>>> = BTreeMap::new();
    let mut unknown = Vec::new();
    for f in &csv {
        let p = a.dir.dir.join(f);
        match READERS.iter().find(|(_, ok)| ok(&p)) {
            Some((kind, _)) => {
                let folder = f.rsplit_once('/').map_or("", |(d, _)| d).to_string();
                found
                    .entry(folder)
                    .or_default()
                    .entry(kind)
                    .or_default()
                    .push(f.clone());
            }
            None => unknown.push(f.clone()),
        }
    }
    let text = project_text(&a.dir.dir, &found, &unknown);
    dea_fit::io::write::atomic_write(&file, text.as_bytes())?;
    let steps = text.lines().filter(|l| l.starts_with('[')).count();
    println!(
        "init: wrote {}: {steps} step(s) from {} data file(s){}",
        file.display(),
        csv.len() - unknown.len(),
        if unknown.is_empty() {
            String::new()
        } else {
            format!(" ({} not recognised, listed at its end)", unknown.len())
        },
    );
    println!(
        "edit it (docs/project.md), then run dea-fit make{}",
        if a.dir.dir == Path::new(".") {
            String::new()
        } else {
            format!(" -C {}", a.dir.dir.display())
        }
    );
    Ok(0)
}

/// The CSV files under `dir` (project-relative), outside the outputs and hidden folders.
fn collect(dir: &Path, rel: &str, out: &mut Vec<String>) {
    let Ok(rd) = std::fs::read_dir(dir.join(rel)) else {
        return;
    };
    for e in rd.filter_map(|e| e.ok()) {
        let name = e.file_name().to_string_lossy().into_owned();
        let r = if rel.is_empty() {
            name.clone()
        } else {
            format!("{rel}/{name}")
        };
        let skip = name.starts_with('.')
            || (rel.is_empty()
                && ["fits", "reports", "exports", "target", STATE_DIR].contains(&name.as_str()));
        if skip {
            continue;
        }
        let path = e.path();
        if path.is_dir() {
            collect(dir, &r, out);
        } else if glob::matches("*.csv", &name.to_lowercase()) {
            out.push(r);
        }
    }
}

/// The project file: one step per kind and folder.
fn project_text(
    dir: &Path,
    found: &BTreeMap<String, BTreeMap<&str, Vec<String>>>,
    unknown: &[String],
) -> String {
    let root = std::fs::canonicalize(dir)
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "lab".into());
    let mut t = String::from(
        "# dea-fit project (docs/project.md), written by dea-fit init: check every step,\n\
         # fill in what is commented, then run dea-fit make.\n",
    );
    // a path as a TOML string (a name may hold a quote or a backslash)
    let quoted = |f: &str| toml::Value::String(f.to_string()).to_string();
    let list = |files: &[String]| match files {
        [one] => quoted(one),
        many => format!(
            "[\n{}]",
            many.iter()
                .map(|f| format!("  {},\n", quoted(f)))
                .collect::<String>()
        ),
    };
    for (folder, kinds) in found {
        let name: String = match folder.as_str() {
            "" => root.clone(),
            f => f.replace('/', "-"),
        }
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
        for (kind, files) in kinds {
            let _ = writeln!(t);
            match *kind {
                "trace" => {
                    // no scene to run it with: commented out until the user gives one
                    let _ = writeln!(
                        t,
                        "# traces: give the actuator's scene (docs/scenes.md), then uncomment"
                    );
                    let _ = writeln!(t, "# [actuators.{name}.identify]");
                    let _ = writeln!(t, "# scene = \"…\"");
                    for l in format!("traces = {}", list(files)).lines() {
                        let _ = writeln!(t, "# {l}");
                    }
                }
                "relaxation" => {
                    for (k, f) in files.iter().enumerate() {
                        if k == 0 {
                            let _ = writeln!(t, "[materials.{name}.relaxation]");
                        } else {
                            let _ = writeln!(t, "[materials.{name}.relaxation-{}]", k + 1);
                            let _ = writeln!(t, "kind = \"relaxation\"");
                        }
                        let _ = writeln!(t, "file = {}", quoted(f));
                    }
                }
                "permittivity" => {
                    let _ = writeln!(t, "[materials.{name}.permittivity]");
                    let _ = writeln!(t, "files = {}", list(files));
                    let _ = writeln!(t, "# diameter = \"…\"   # or area: the plates (fill in)");
                    let _ = writeln!(t, "# thickness = \"…\"  # the coupon (fill in)");
                }
                k => {
                    let _ = writeln!(t, "[materials.{name}.{k}]");
                    let _ = writeln!(t, "files = {}", list(files));
                }
            }
        }
    }
    if !unknown.is_empty() {
        let _ = writeln!(
            t,
            "\n# CSV files no reader took with default settings (a column map or"
        );
        let _ = writeln!(t, "# an area may be needed; see docs/input-files.md):");
        for f in unknown {
            let _ = writeln!(t, "#   {f}");
        }
    }
    t
}
