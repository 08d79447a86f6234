//! The project file `dea-fit.toml` (docs/project.md) → the steps of a project.
//!
//! ```toml
//! strict = true                        # every step with --strict (optional)
//!
//! [materials.vhb4910.tensile]          # target vhb4910/tensile: dea-fit hyperelastic
//! files = "raw/vhb4910/tensile_*.csv"  # the command's files, patterns sorted
//! equibiaxial = "raw/vhb4910/equibiaxial.csv"
//! model = "yeoh"                       # any flag of the command: model → --model=yeoh
//!
//! [materials.vhb4910.relaxation]       # target vhb4910/relaxation
//! file = "raw/vhb4910/relaxation.csv"
//! strain = 0.5
//! hyperelastic = { target = "vhb4910/tensile" }   # that step's fit file; runs after it
//!
//! [actuators.stack.identify]           # target stack/identify
//! scene = "stack.toml"
//! traces = "raw/stack/step.csv"
//! reads = [{ target = "vhb4910/tensile" }]         # what the scene reads
//! ```
//!
//! A step is `[<group>.<name>.<step>]` with group `materials`, `actuators` or
//! `designs`; its target is `<name>/<step>`; its command is `kind`, by default the
//! one its step name says (tensile → hyperelastic; relaxation, permittivity,
//! breakdown, dma, composite, identify and rank are their own). Every other key is
//! the command's flag of that name, checked against the command's own flags (an
//! unknown one is refused, located, with the near miss). A step writes
//! `fits/<name>-<step>.json` and `reports/<name>-<step>/` unless its `out`,
//! `report` or `no-report` say otherwise.

use crate::error::{Error, Location, Result};
use crate::material::check::did_you_mean;
use crate::project::glob;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// A long flag of a command, as its command line defines it.
#[derive(Debug, Clone)]
pub struct Flag {
    /// Its name without the dashes (`gauge-length`).
    pub long: String,
    /// Whether it takes a value (`--model yeoh`) or is a switch (`--stable`).
    pub takes_value: bool,
}

/// Step names with the command each runs by default, the key of the command's
/// positional file argument(s), and whether it writes a fit file (`--out`; rank's
/// `--out` is a shard's file, its result is the report).
pub const KINDS: [(&str, &str, &str, bool); 8] = [
    ("tensile", "hyperelastic", "files", true),
    ("relaxation", "relaxation", "file", true),
    ("permittivity", "permittivity", "files", true),
    ("breakdown", "breakdown", "files", true),
    ("dma", "dma", "files", true),
    ("composite", "composite", "manifest", true),
    ("identify", "identify", "traces", true),
    ("rank", "rank", "design", false),
];

/// The top-level tables that hold steps.
const GROUPS: [&str; 3] = ["materials", "actuators", "designs"];

/// One step: a command line of dea-fit, run in the project folder.
#[derive(Debug, Clone)]
pub struct Step {
    /// `<name>/<step>`.
    pub target: String,
    /// The command (`hyperelastic`).
    pub kind: String,
    /// The arguments after `dea-fit`, the command first.
    pub args: Vec<String>,
    /// The files it reads that no step writes (project-relative, `/`-separated),
    /// sorted.
    pub inputs: Vec<String>,
    /// The steps whose outputs it reads (indices into [`Project::steps`]), sorted.
    pub needs: Vec<usize>,
    /// Its fit or result file, if it writes one.
    pub fit: Option<String>,
    /// Everything it writes that must exist after it ran: the fit file, the report
    /// folder.
    pub outputs: Vec<String>,
    /// Where the project file declares it.
    pub at: Location,
}

/// A parsed project.
#[derive(Debug, Clone)]
pub struct Project {
    /// The project folder (the steps' working directory).
    pub dir: PathBuf,
    /// Whether every step runs with `--strict`.
    pub strict: bool,
    /// The steps, in the project file's (sorted) order.
    pub steps: Vec<Step>,
}

impl Project {
    /// Read `<dir>/dea-fit.toml`; `flags` gives the long flags of a command (None
    /// for a command that does not exist); `strict` forces `--strict` on every step.
    pub fn read(
        dir: &Path,
        flags: &dyn Fn(&str) -> Option<Vec<Flag>>,
        strict: bool,
    ) -> Result<Project> {
        let (file, text) = read_text(dir)?;
        Project::parse(&text, dir, &file, flags, strict)
    }

    /// Parse project text; `file` names it in errors, `dir` is the project folder.
    pub fn parse(
        text: &str,
        dir: &Path,
        file: &Path,
        flags: &dyn Fn(&str) -> Option<Vec<Flag>>,
        strict: bool,
    ) -> Result<Project> {
        let cx = Cx::new(file, text, dir);
        let root = cx.root()?;
        let mut strict = strict;
        let decl = cx.declare(&root, &mut strict)?;
        let fits = cx.fits(&decl)?;
        let targets: Vec<&str> = decl.iter().map(|d| d.target.as_str()).collect();
        let mut steps = Vec::with_capacity(decl.len());
        let written: std::collections::HashSet<&str> =
            fits.iter().flatten().map(|f| f.as_str()).collect();
        for (me, d) in decl.iter().enumerate() {
            steps.push(cx.step(d, me, &targets, &fits, &written, flags, strict)?);
        }
        // a file another step writes is that step's output: read after it, by its identity
        let mut writers: BTreeMap<&str, usize> = BTreeMap::new();
        for (i, s) in steps.iter().enumerate() {
            for o in &s.outputs {
                if let Some(j) = writers.insert(o, i) {
                    return Err(Error::input(
                        s.at.clone(),
                        format!(
                            "{} writes {o}, which {} writes too",
                            s.target, steps[j].target
                        ),
                    )
                    .with_hint("give one of them another out (or report)"));
                }
            }
        }
        let writers: BTreeMap<String, usize> = writers
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        for (i, s) in steps.iter_mut().enumerate() {
            // (its own output, named by a file it reads, is not read)
            s.inputs.retain(|p| match writers.get(p) {
                Some(&j) if j != i => {
                    s.needs.push(j);
                    false
                }
                Some(_) => false,
                None => true,
            });
            s.needs.sort_unstable();
            s.needs.dedup();
        }
        Ok(Project {
            dir: dir.to_path_buf(),
            strict,
            steps,
        })
    }
}

/// `<dir>/dea-fit.toml`: its path and text, or the error that says how to make one.
fn read_text(dir: &Path) -> Result<(PathBuf, String)> {
    let file = dir.join(super::FILE);
    let text = std::fs::read_to_string(&file).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            Error::input(Location::file(&file), "no project file here").with_hint(format!(
                "run `dea-fit init{}` to write one from the files in the folder, or give the project folder with -C DIR (docs/project.md)",
                if dir == Path::new(".") { String::new() } else { format!(" -C {}", dir.display()) }
            ))
        } else {
            Error::io(&file, e)
        }
    })?;
    Ok((file, text))
}

/// Every target of the project in `dir` with its fit file (project-relative; None
/// for a step that writes none), in the project file's order: what a `{ target =
/// "…" }` in a scene or manifest stands for ([`super::refs`]). Only the steps'
/// names, kinds and `out` are read: their settings are checked by [`Project::read`].
pub fn fit_files(dir: &Path) -> Result<Vec<(String, Option<String>)>> {
    let (file, text) = read_text(dir)?;
    let cx = Cx::new(&file, &text, dir);
    let root = cx.root()?;
    let decl = cx.declare(&root, &mut false)?;
    let fits = cx.fits(&decl)?;
    Ok(decl.into_iter().map(|d| d.target).zip(fits).collect())
}

/// `base/rel` (both `/`-separated, project-relative) with `.` and `..` folded;
/// None for an absolute path or one that leaves the project folder.
fn joined(base: &str, rel: &str) -> Option<String> {
    if rel.starts_with('/') || rel.contains('\\') {
        return None;
    }
    let mut parts: Vec<&str> = Vec::new();
    for c in base.split('/').chain(rel.split('/')) {
        match c {
            "" | "." => {}
            ".." => {
                parts.pop()?;
            }
            c => parts.push(c),
        }
    }
    Some(parts.join("/"))
}

/// A step as declared.
struct Decl<'t, 'i> {
    target: String,
    file_stem: String,
    kind: String,
    path: String,
    body: &'t DeTable<'i>,
    at: Location,
}

/// `did you mean 'x'? ` for the nearest of `known`, or nothing.
pub fn near(found: &str, known: &[&str]) -> String {
    did_you_mean(found, known)
        .map(|m| format!("did you mean '{m}'? "))
        .unwrap_or_default()
}

/// The error of a reference to a target the project does not have.
fn no_target(at: Location, key: &str, name: &str, targets: &[&str]) -> Error {
    Error::input(at, format!("{key}: no target '{name}' in the project")).with_hint(format!(
        "{}targets: {}",
        near(name, targets),
        targets.join(", ")
    ))
}

/// `p` without a leading `./` (the one spelling of a project-relative path).
fn clean(s: &str) -> String {
    let mut s = s;
    while let Some(r) = s.strip_prefix("./") {
        s = r;
    }
    s.trim_end_matches('/').to_string()
}

/// Whether a flag's value may name a file: it has a `/`, or ends in an extension
/// that starts with a letter (`design.toml`, not `1.000mm` or `0.5`); a value that
/// does is read (and hashed) when the file exists.
fn looks_like_a_path(s: &str) -> bool {
    s.contains('/')
        || s.rsplit_once('.').is_some_and(|(stem, ext)| {
            !stem.is_empty()
                && ext.starts_with(|c: char| c.is_ascii_alphabetic())
                && ext.chars().all(|c| c.is_ascii_alphanumeric())
        })
}

struct Cx<'a> {
    file: &'a Path,
    text: &'a str,
    dir: &'a Path,
    /// The byte offset where each line starts (a location is found by bisection:
    /// a project of thousands of steps is read in linear time).
    lines: Vec<usize>,
}

type Val<'i> = Spanned<DeValue<'i>>;

impl<'a> Cx<'a> {
    fn new(file: &'a Path, text: &'a str, dir: &'a Path) -> Cx<'a> {
        Cx {
            file,
            text,
            dir,
            lines: std::iter::once(0)
                .chain(text.match_indices('\n').map(|(i, _)| i + 1))
                .collect(),
        }
    }

    /// The project file's TOML.
    fn root(&self) -> Result<DeTable<'a>> {
        DeTable::parse(self.text)
            .map(|t| t.into_inner())
            .map_err(|e| {
                Error::input(
                    self.loc(e.span().map_or(0, |s| s.start)),
                    e.message().trim().to_string(),
                )
                .with_hint("the project file must be valid TOML; see docs/project.md")
            })
    }

    /// The steps the project file declares (`strict` set by its `strict = true`),
    /// before their references are resolved.
    fn declare<'t, 'i>(
        &self,
        root: &'t DeTable<'i>,
        strict: &mut bool,
    ) -> Result<Vec<Decl<'t, 'i>>> {
        let cx = self;
        // the declared steps, before their references are resolved
        let mut decl: Vec<Decl<'t, 'i>> = Vec::new();
        for (k, v) in root.iter() {
            let key = k.get_ref().as_ref();
            if key == "strict" {
                *strict |= cx.bool(v, "strict")?;
                continue;
            }
            if !GROUPS.contains(&key) {
                let mut known = GROUPS.to_vec();
                known.push("strict");
                return Err(cx.unknown(k.span().start, "top-level key", key, &known));
            }
            for (name, steps) in cx.table(v, key)? {
                let name_s = name.get_ref().as_ref();
                cx.name(name.span().start, name_s)?;
                for (step, body) in cx.table(steps, &format!("{key}.{name_s}"))? {
                    let step_s = step.get_ref().as_ref();
                    cx.name(step.span().start, step_s)?;
                    let path = format!("{key}.{name_s}.{step_s}");
                    let body = cx.table(body, &path)?;
                    let kind = match body.get("kind") {
                        Some(kv) => {
                            let s = cx.str(kv, &format!("{path}.kind"))?;
                            if !KINDS.iter().any(|k| k.1 == s) {
                                let known: Vec<&str> = KINDS.iter().map(|k| k.1).collect();
                                return Err(cx.unknown(
                                    kv.span().start,
                                    &format!("{path}.kind: command"),
                                    s,
                                    &known,
                                ));
                            }
                            s.to_string()
                        }
                        None => match KINDS.iter().find(|k| k.0 == step_s) {
                            Some(k) => k.1.to_string(),
                            None => {
                                let known: Vec<&str> = KINDS.iter().map(|k| k.0).collect();
                                return Err(cx
                                    .unknown(step.span().start, "step name", step_s, &known)
                                    .with_hint(format!(
                                        "a step is named by what it runs ({}), or says its command with kind = \"…\" (docs/project.md); {}",
                                        known.join(", "),
                                        match did_you_mean(step_s, &known) {
                                            Some(m) => format!("did you mean '{m}'?"),
                                            None => "add kind = \"<command>\"".into(),
                                        }
                                    )));
                            }
                        },
                    };
                    decl.push(Decl {
                        target: format!("{name_s}/{step_s}"),
                        file_stem: format!("{name_s}-{step_s}"),
                        kind,
                        path,
                        body,
                        at: cx.loc(step.span().start),
                    });
                }
            }
        }
        Ok(decl)
    }

    /// Each declared step's fit file, known before any reference is resolved.
    fn fits(&self, decl: &[Decl<'_, '_>]) -> Result<Vec<Option<String>>> {
        let cx = self;
        decl.iter()
            .map(|d| {
                if !KINDS.iter().any(|k| k.1 == d.kind && k.3) {
                    return Ok(None);
                }
                Ok(Some(match d.body.get("out") {
                    Some(v) => clean(cx.str(v, &format!("{}.out", d.path))?),
                    None => format!("fits/{}.json", d.file_stem),
                }))
            })
            .collect::<Result<_>>()
    }
}

impl<'a> Cx<'a> {
    /// 1-based line and column (in characters) of a byte offset.
    fn loc(&self, offset: usize) -> Location {
        let offset = offset.min(self.text.len());
        let line = self.lines.partition_point(|&s| s <= offset);
        let start = self.lines[line - 1];
        let col = self.text[start..offset].chars().count() + 1;
        Location::at(self.file, line, col)
    }

    fn err(&self, offset: usize, msg: impl Into<String>) -> Error {
        Error::input(self.loc(offset), msg).with_hint("see docs/project.md")
    }

    fn unknown(&self, offset: usize, what: &str, found: &str, known: &[&str]) -> Error {
        Error::input(self.loc(offset), format!("unknown {what} '{found}'")).with_hint(format!(
            "{}known: {} (docs/project.md)",
            near(found, known),
            known.join(", ")
        ))
    }

    /// A target or step name: letters, digits, `-`, `_` and `.` (it names files).
    fn name(&self, offset: usize, s: &str) -> Result<()> {
        if s.is_empty()
            || s.starts_with('.')
            || !s
                .chars()
                .all(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | '.'))
        {
            return Err(self
                .err(offset, format!("'{s}' cannot name a target"))
                .with_hint("use letters, digits, '-', '_' and '.' (not first): it names the step's fit file and report folder"));
        }
        Ok(())
    }

    fn table<'t, 'i>(&self, v: &'t Val<'i>, key: &str) -> Result<&'t DeTable<'i>> {
        v.get_ref().as_table().ok_or_else(|| {
            self.err(
                v.span().start,
                format!("{key} must be a table, found a {}", v.get_ref().type_str()),
            )
        })
    }

    fn str<'t>(&self, v: &'t Val<'_>, key: &str) -> Result<&'t str> {
        v.get_ref().as_str().ok_or_else(|| {
            self.err(
                v.span().start,
                format!("{key} must be a string, found a {}", v.get_ref().type_str()),
            )
        })
    }

    fn bool(&self, v: &Val<'_>, key: &str) -> Result<bool> {
        v.get_ref().as_bool().ok_or_else(|| {
            self.err(
                v.span().start,
                format!(
                    "{key} must be true or false, found a {}",
                    v.get_ref().type_str()
                ),
            )
        })
    }

    /// `{ target = "x/y" }`: the index of the target.
    fn target_ref(&self, v: &Val<'_>, key: &str, targets: &[&str]) -> Result<Option<usize>> {
        let Some(t) = v.get_ref().as_table() else {
            return Ok(None);
        };
        let mut out = None;
        for (k, x) in t.iter() {
            if k.get_ref() != "target" {
                return Err(self.unknown(
                    k.span().start,
                    &format!("key of {key}"),
                    k.get_ref(),
                    &["target"],
                ));
            }
            let name = self.str(x, &format!("{key}.target"))?;
            let i = targets
                .iter()
                .position(|t| *t == name)
                .ok_or_else(|| no_target(self.loc(x.span().start), key, name, targets))?;
            out = Some(i);
        }
        out.map(Some).ok_or_else(|| {
            self.err(
                v.span().start,
                format!("{key}: a table here names a target: {{ target = \"<name>/<step>\" }}"),
            )
        })
    }

    /// The files a path or pattern names: a pattern expanded (at least one match),
    /// a path as written (it need not exist yet: a step may write it).
    fn files(&self, v: &Val<'_>, key: &str) -> Result<Vec<String>> {
        let s = clean(self.str(v, key)?);
        if glob::is_pattern(&s) {
            let found = glob::expand(self.dir, &s);
            if found.is_empty() {
                return Err(Error::input(
                    self.loc(v.span().start),
                    format!("{key}: no file matches '{s}' in {}", self.dir.display()),
                )
                .with_hint("patterns are relative to the project folder (the one holding dea-fit.toml); * and ? match within one folder name"));
            }
            return Ok(found);
        }
        Ok(vec![s])
    }

    /// A value or an array of values.
    fn each<'t, 'i>(&self, v: &'t Val<'i>) -> Vec<&'t Val<'i>> {
        match v.get_ref().as_array() {
            Some(a) => a.iter().collect(),
            None => vec![v],
        }
    }

    /// What the scenes and manifests a step reads name, followed into the TOML
    /// files they name in turn: their `{ target = "…" }` references (the step runs
    /// after those steps, [`super::refs`]) and the files they name by path (read,
    /// so hashed; a path another step writes makes the step run after it).
    fn named(
        &self,
        d: &Decl<'_, '_>,
        inputs: &mut Vec<String>,
        needs: &mut Vec<usize>,
        targets: &[&str],
        fits: &[Option<String>],
        written: &std::collections::HashSet<&str>,
    ) -> Result<()> {
        let mut k = 0;
        while k < inputs.len() {
            let f = inputs[k].clone();
            k += 1;
            if !f.ends_with(".toml") {
                continue;
            }
            let path = self.dir.join(&f);
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            let base = f.rsplit_once('/').map_or("", |(b, _)| b);
            let scan = super::refs::scan(&text);
            for r in &scan.refs {
                let at = || {
                    let (l, c) = super::refs::line_col(&text, r.at);
                    Location::at(&path, l, c)
                };
                let i = targets
                    .iter()
                    .position(|t| *t == r.target)
                    .ok_or_else(|| no_target(at(), "target", &r.target, targets))?;
                if fits[i].is_none() {
                    return Err(Error::input(
                        at(),
                        format!("target '{}' writes no fit file to read", r.target),
                    )
                    .with_hint(format!("{} reads it (docs/project.md)", d.target)));
                }
                needs.push(i);
            }
            for (v, _) in &scan.strings {
                let Some(p) = joined(base, v) else { continue };
                if !inputs.contains(&p)
                    && (written.contains(p.as_str())
                        || (looks_like_a_path(&p) && self.dir.join(&p).is_file()))
                {
                    inputs.push(p);
                }
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn step(
        &self,
        d: &Decl<'_, '_>,
        me: usize,
        targets: &[&str],
        fits: &[Option<String>],
        written: &std::collections::HashSet<&str>,
        flags: &dyn Fn(&str) -> Option<Vec<Flag>>,
        strict: bool,
    ) -> Result<Step> {
        let known = flags(&d.kind).unwrap_or_default();
        let has = |f: &str| known.iter().any(|k| k.long == f);
        let positional = KINDS
            .iter()
            .find(|k| k.1 == d.kind)
            .map_or("files", |k| k.2);
        let mut args = vec![d.kind.clone()];
        let mut inputs: Vec<String> = Vec::new();
        let mut needs: Vec<usize> = Vec::new();
        let mut flags_out: Vec<String> = Vec::new();
        let mut positionals: Vec<String> = Vec::new();
        let fit_of = |i: usize, key: &str, at: usize| -> Result<String> {
            fits[i].clone().ok_or_else(|| {
                self.err(
                    at,
                    format!("{key}: {} writes no fit file to read", targets[i]),
                )
            })
        };
        for (k, v) in d.body.iter() {
            let key = k.get_ref().as_ref();
            let path = format!("{}.{key}", d.path);
            match key {
                "kind" => continue,
                "reads" => {
                    for x in self.each(v) {
                        match self.target_ref(x, &path, targets)? {
                            Some(i) => needs.push(i),
                            None => inputs.extend(self.files(x, &path)?),
                        }
                    }
                    continue;
                }
                _ if key == positional => {
                    for x in self.each(v) {
                        match self.target_ref(x, &path, targets)? {
                            Some(i) => {
                                needs.push(i);
                                positionals.push(fit_of(i, &path, x.span().start)?);
                            }
                            None => {
                                for f in self.files(x, &path)? {
                                    inputs.push(f.clone());
                                    positionals.push(f);
                                }
                            }
                        }
                    }
                    continue;
                }
                _ => {}
            }
            let flag = key.replace('_', "-");
            let Some(f) = known.iter().find(|f| f.long == flag) else {
                let mut names: Vec<&str> = known
                    .iter()
                    .map(|f| f.long.as_str())
                    .filter(|n| !matches!(*n, "help" | "json" | "strict"))
                    .collect();
                names.extend(["kind", "reads", positional]);
                return Err(self.unknown(
                    k.span().start,
                    &format!("setting of a {} step", d.kind),
                    key,
                    &names,
                ));
            };
            match f.long.as_str() {
                "strict" => {
                    return Err(self
                        .err(k.span().start, format!("{path}: make sets --strict"))
                        .with_hint("write strict = true at the top of dea-fit.toml (every step), or run dea-fit make --strict"))
                }
                "json" | "help" => {
                    return Err(self.err(
                        k.span().start,
                        format!("{path}: make runs the step with its own output (its log is .dea-fit/logs/)"),
                    ))
                }
                _ => {}
            }
            for x in self.each(v) {
                match x.get_ref() {
                    DeValue::Boolean(b) if !f.takes_value => {
                        if *b {
                            flags_out.push(format!("--{flag}"));
                        }
                    }
                    _ if !f.takes_value => {
                        return Err(
                            self.err(x.span().start, format!("{path} is a switch: true or false"))
                        )
                    }
                    DeValue::String(s) => {
                        let s = s.as_ref();
                        if glob::is_pattern(s) {
                            for p in self.files(x, &path)? {
                                flags_out.push(format!("--{flag}={p}"));
                                inputs.push(p);
                            }
                        } else {
                            let c = clean(s);
                            // a value naming a file (or a step's fit) is read; the
                            // step's own out and report are what it writes
                            let own = matches!(flag.as_str(), "out" | "report");
                            if !own
                                && (written.contains(c.as_str())
                                    || (looks_like_a_path(&c) && self.dir.join(&c).is_file()))
                            {
                                inputs.push(c);
                            }
                            flags_out.push(format!("--{flag}={s}"));
                        }
                    }
                    DeValue::Integer(n) => flags_out.push(format!("--{flag}={n}")),
                    DeValue::Float(n) => flags_out.push(format!("--{flag}={n}")),
                    DeValue::Table(_) => {
                        let i = self
                            .target_ref(x, &path, targets)?
                            .expect("a table value is a target reference");
                        needs.push(i);
                        flags_out.push(format!("--{flag}={}", fit_of(i, &path, x.span().start)?));
                    }
                    other => {
                        return Err(self.err(
                            x.span().start,
                            format!("{path}: a {} cannot be a flag's value", other.type_str()),
                        ))
                    }
                }
            }
        }
        args.extend(positionals);
        args.extend(flags_out);
        let mut outputs = Vec::new();
        let fit = fits[me].clone();
        if let Some(f) = &fit {
            if !d.body.contains_key("out") {
                args.push(format!("--out={f}"));
            }
            outputs.push(f.clone());
        }
        let no_report = d
            .body
            .get("no-report")
            .or_else(|| d.body.get("no_report"))
            .and_then(|v| v.get_ref().as_bool())
            == Some(true);
        if has("report") && !no_report {
            match d.body.get("report") {
                Some(v) => outputs.push(clean(self.str(v, &format!("{}.report", d.path))?)),
                None => {
                    let r = format!("reports/{}", d.file_stem);
                    args.push(format!("--report={r}"));
                    outputs.push(r);
                }
            }
        }
        if strict && has("strict") {
            args.push("--strict".into());
        }
        self.named(d, &mut inputs, &mut needs, targets, fits, written)?;
        inputs.sort();
        inputs.dedup();
        needs.sort_unstable();
        needs.dedup();
        Ok(Step {
            target: d.target.clone(),
            kind: d.kind.clone(),
            args,
            inputs,
            needs,
            fit,
            outputs,
            at: d.at.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(kind: &str) -> Option<Vec<Flag>> {
        let f = |long: &str, takes_value: bool| Flag {
            long: long.into(),
            takes_value,
        };
        (kind == "breakdown").then(|| {
            vec![
                f("out", true),
                f("report", true),
                f("no-report", false),
                f("strict", false),
            ]
        })
    }

    /// A step's own `out` is what it writes, never what it reads, also when the
    /// file is there from its last run (read, it would change the step's identity
    /// with every run).
    #[test]
    fn own_out_is_not_an_input() {
        let d = tempfile::tempdir().unwrap();
        for f in ["raw/a.csv", "fits/mine.json"] {
            std::fs::create_dir_all(d.path().join(f).parent().unwrap()).unwrap();
            std::fs::write(d.path().join(f), "x").unwrap();
        }
        let text = "[materials.a.breakdown]\nfiles = \"raw/a.csv\"\nout = \"fits/mine.json\"\n";
        let p = Project::parse(text, d.path(), Path::new("dea-fit.toml"), &flags, false).unwrap();
        let s = &p.steps[0];
        assert_eq!(s.inputs, ["raw/a.csv"]);
        assert_eq!(s.fit.as_deref(), Some("fits/mine.json"));
        assert!(s.args.contains(&"--out=fits/mine.json".to_string()));
    }
}
