//! Shard files: one slice of a sweep (`rank --shard K/N --out F`), and their merge
//! (`rank merge`) into the evaluations a single run gives.
//!
//! A shard file holds the run's identity ([`RunInfo`]: the design's SHA-256 over
//! the manifest and every file it reads, the drive, the sweep, the number of points,
//! the tool version), the `--sweep` flags, the shard (K, N), its evaluations, and
//! the SHA-256 of all of these ([`ShardFile::digest`]). It is written atomically (a
//! temporary file, then a rename), so a killed task leaves no half file and running
//! the task again repairs the sweep.
//!
//! The merge trusts nothing a file says ([`merge`]): every key must be one the
//! schema knows; the digest must match the content (an edited or damaged file is
//! refused); the design is read again and must give the same identity (a shard of
//! another manifest, scene, fit file, drive, sweep or tool version is refused, with
//! what differs); the shards must be exactly the N of that run (none missing,
//! repeated or foreign; N at most the number of points); every evaluation must be
//! at a point of its shard, name the candidate the design gives there with the
//! design's catalogue figures, and hold figures in their domains
//! ([`check_evaluation`]).

use super::candidate;
use super::figures::{catalogue, CurvePoint, Evaluated, State, KEPT_POINTS};
use super::manifest::{self, Design, Level};
use super::sweep::{Point, Points, Shard, Sweep, MAX_SHARDS, SHARD_COUNT};
use super::Figure;
use crate::error::{Error, Location, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Schema tag of shard files (2: with the digest and the sweep flags; 3: the
/// provenance `stated`, the margins to breakdown and pull-in, σ by central
/// differences).
pub const SCHEMA: &str = "dea-fit/rank-shard/3";

/// The prefix of every shard schema, of any version: a file with it is a shard
/// file that a re-run of its task may replace.
const SCHEMA_FAMILY: &str = "dea-fit/rank-shard/";

/// What to do with a shard file that is refused.
const RERUN: &str = "the file was edited or damaged: run its task again (dea-fit rank DESIGN --sweep ... --shard K/N --out FILE)";

/// What makes two runs the same: everything the evaluations depend on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunInfo {
    /// Design name.
    pub design: String,
    /// Manifest path as given.
    pub manifest: String,
    /// SHA-256 over the manifest and every file it reads.
    pub sha256: String,
    /// The actuator scene.
    pub scene: String,
    /// The drive of the manifest in words.
    pub drive: String,
    /// The sweep in words.
    pub sweep: String,
    /// Number of points of the whole run.
    pub points: usize,
    /// dea-fit version.
    pub tool_version: String,
}

impl RunInfo {
    /// The identity of a run of `d` under `sweep` with `points` points.
    pub fn new(d: &Design, sweep: &Sweep, points: usize) -> RunInfo {
        let dr = &d.drive;
        let level = match dr.level {
            Level::Voltage(v) => format!("{v} V"),
            Level::BreakdownFraction(f) => format!("{f} of the breakdown voltage"),
        };
        RunInfo {
            design: d.name.clone(),
            manifest: d.path.display().to_string(),
            sha256: d.sha256.clone(),
            scene: d.scene_path.display().to_string(),
            drive: format!(
                "{level} at {} Hz; step window {} s in {} samples",
                dr.frequency_hz, dr.step_span_s, dr.step_samples
            ),
            sweep: sweep.describe(),
            points,
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
        }
    }

    /// The first field in which `self` differs from `other`, in words (`self`'s
    /// value first), or none.
    pub fn differs(&self, other: &RunInfo) -> Option<String> {
        let short = |h: &str| h.chars().take(12).collect::<String>();
        let fields = [
            ("design hash", short(&self.sha256), short(&other.sha256)),
            ("sweep", self.sweep.clone(), other.sweep.clone()),
            ("points", self.points.to_string(), other.points.to_string()),
            ("drive", self.drive.clone(), other.drive.clone()),
            ("scene", self.scene.clone(), other.scene.clone()),
            ("design name", self.design.clone(), other.design.clone()),
            ("manifest", self.manifest.clone(), other.manifest.clone()),
            (
                "tool version",
                self.tool_version.clone(),
                other.tool_version.clone(),
            ),
        ];
        if let Some((what, a, b)) = fields.iter().find(|(_, a, b)| a != b) {
            return Some(format!("{what} '{a}' vs '{b}'"));
        }
        (self != other).then(|| "design hash".to_string())
    }
}

/// A shard file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardFile {
    /// [`SCHEMA`].
    pub schema: String,
    /// The run.
    pub run: RunInfo,
    /// The `--sweep` flags of the run (canonical order), from which the merge
    /// makes the points again.
    pub sweep: Vec<String>,
    /// Which slice.
    pub shard: Shard,
    /// Its evaluations, by index.
    pub evaluations: Vec<Evaluated>,
    /// [`ShardFile::digest`] of the above, in hex.
    pub sha256: String,
}

impl ShardFile {
    /// A shard file of `evaluations`, with its digest.
    pub fn new(run: RunInfo, sweep: &Sweep, shard: Shard, evaluations: Vec<Evaluated>) -> Self {
        let mut f = ShardFile {
            schema: SCHEMA.into(),
            run,
            sweep: sweep.text.clone(),
            shard,
            evaluations,
            sha256: String::new(),
        };
        f.sha256 = f.digest();
        f
    }

    /// SHA-256 (hex) of the schema, run, sweep, shard and evaluations as compact
    /// JSON. The JSON of what was read equals the JSON that was written (floats
    /// round-trip exactly: serde_json's `float_roundtrip`, which the lock file
    /// enables), so an untouched file verifies and any change of a value does not.
    pub fn digest(&self) -> String {
        let content = (
            &self.schema,
            &self.run,
            &self.sweep,
            &self.shard,
            &self.evaluations,
        );
        let json = serde_json::to_vec(&content).expect("a shard serialises");
        crate::io::sha256_hex(&json)
    }
}

/// The schema of a file, read without the rest (any other keys allowed).
#[derive(Deserialize)]
struct Head {
    schema: Option<String>,
}

/// Write a shard by the write policy ([`crate::io::write::write_keeping`]): an
/// existing file is replaced only when it is a shard file of any schema version,
/// even a damaged one (a re-run of the task repairs it), anything else is refused;
/// an older, different shard is kept aside (what happened to it is returned), and
/// two tasks writing one file both keep theirs.
pub fn write(path: &Path, s: &ShardFile) -> Result<crate::io::write::Replaced> {
    let is_shard = |p: &Path| {
        std::fs::read(p).is_ok_and(|b| {
            serde_json::from_slice::<Head>(&b)
                .ok()
                .and_then(|h| h.schema)
                .is_some_and(|s| s.starts_with(SCHEMA_FAMILY))
        })
    };
    if path.is_file() && !is_shard(path) {
        return Err(Error::settings(format!(
            "{} exists and is not a rank shard file: it is not replaced",
            path.display()
        ))
        .with_hint("choose another --out"));
    }
    let json = serde_json::to_string(s).expect("a shard serialises");
    crate::io::write::write_keeping(path, json.as_bytes(), |old| old == json.as_bytes())
}

/// Read a shard file: its schema, every key known (no other), and its digest.
pub fn read(path: &Path) -> Result<ShardFile> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let hint = "shard files are written by dea-fit rank --shard K/N --out FILE";
    let head: Head = serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a rank shard file: {e}"),
        )
        .with_hint(hint)
    })?;
    match head.schema.as_deref() {
        Some(SCHEMA) => {}
        other => {
            let older = other.is_some_and(|s| s.starts_with(SCHEMA_FAMILY));
            return Err(Error::input(
                Location::file(path),
                format!(
                    "schema: expected \"{SCHEMA}\", found {}",
                    other.map_or("none".into(), |s| format!("\"{s}\""))
                ),
            )
            .with_hint(match older {
                true => {
                    "a shard of another dea-fit version: run the sweep's tasks again with this one"
                }
                false => hint,
            }));
        }
    }
    let s: ShardFile = serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a rank shard file of its schema: {e}"),
        )
        .with_hint(RERUN)
    })?;
    let digest = s.digest();
    if digest != s.sha256 {
        return Err(Error::input(
            Location::file(path),
            format!(
                "the content does not match its digest (sha256 {} in the file, {} of its content)",
                short_hash(&s.sha256),
                short_hash(&digest)
            ),
        )
        .with_hint(RERUN));
    }
    Ok(s)
}

/// The first 12 characters of a hash.
fn short_hash(h: &str) -> String {
    h.chars().take(12).collect()
}

/// Merge shard files into the run's identity and its evaluations in run order,
/// refusing anything but exactly the N shards of one run of the design, with
/// figures the design can give. The design is read again from `design`, or else
/// from the manifest path the shards name.
pub fn merge(paths: &[PathBuf], design: Option<&Path>) -> Result<(RunInfo, Vec<Evaluated>)> {
    let Some(first) = paths.first() else {
        return Err(
            Error::settings("no shard files given").with_hint("dea-fit rank merge shard-*.json")
        );
    };
    if paths.len() > MAX_SHARDS {
        return Err(Error::settings(format!(
            "{} shard files: a sweep has at most {MAX_SHARDS} shards",
            paths.len()
        )));
    }
    let shards: Vec<ShardFile> = paths.iter().map(|p| read(p)).collect::<Result<_>>()?;
    let s0 = &shards[0];
    let (run, n) = (s0.run.clone(), s0.shard.n);
    for (p, s) in paths.iter().zip(&shards) {
        let what = match run.differs(&s.run) {
            Some(w) => Some(w),
            None if s.sweep != s0.sweep => Some(format!("--sweep {:?} vs {:?}", s.sweep, s0.sweep)),
            None if s.shard.n != n => Some(format!("{} shards vs {n}", s.shard.n)),
            None => None,
        };
        if let Some(what) = what {
            return Err(Error::input(
                Location::file(p),
                format!("belongs to another run than {} ({what})", first.display()),
            )
            .with_hint(
                "merge the shards of one sweep: the same manifest and files, sweep and shard count",
            ));
        }
    }
    // N bounded before anything is sized by it: by the stated maximum, then by the
    // number of points the design itself gives.
    if let Err(why) = SHARD_COUNT.check(n as u64) {
        return Err(
            Error::input(Location::file(first), format!("shard count {why}")).with_hint(RERUN),
        );
    }

    // The design, read again: the same identity as the shards', or refused.
    let dpath = design.map_or_else(|| PathBuf::from(&run.manifest), Path::to_path_buf);
    let d = manifest::read(&dpath).map_err(|e| match e {
        Error::Io { path, source } => Error::settings(format!(
            "{}: the design the shards were computed from cannot be read: {source}",
            path.display()
        ))
        .with_hint(
            "rank merge reads the design again to check the shards: run it where the manifest path in the shards is valid, or give it with --design FILE",
        ),
        other => other,
    })?;
    let sweep = Sweep::parse(&s0.sweep).map_err(|e| {
        Error::input(Location::file(first), format!("its sweep is not one: {e}")).with_hint(RERUN)
    })?;
    let pts = Points::new(&d, &sweep)?;
    let mut now = RunInfo::new(&d, &sweep, pts.len());
    now.manifest.clone_from(&run.manifest);
    if let Some(what) = now.differs(&run) {
        return Err(Error::input(
            Location::file(first),
            format!(
                "the shards were computed from another design than {} is now: {what} (now vs in the shards)",
                dpath.display()
            ),
        )
        .with_hint("merge with the manifest and files the shards were computed from, or run the sweep's tasks again"));
    }
    Shard { k: 0, n }
        .check(pts.len())
        .map_err(|e| Error::input(Location::file(first), e.to_string()).with_hint(RERUN))?;

    let mut seen: BTreeMap<usize, &Path> = BTreeMap::new();
    for (p, s) in paths.iter().zip(&shards) {
        let k = s.shard.k;
        if k >= n {
            return Err(Error::input(
                Location::file(p),
                format!("shard {k} of {n} does not exist"),
            )
            .with_hint(RERUN));
        }
        if let Some(other) = seen.insert(k, p) {
            return Err(Error::input(
                Location::file(p),
                format!("shard {k}/{n} is given twice (also {})", other.display()),
            )
            .with_hint("give each shard once"));
        }
    }
    let missing: Vec<String> = (0..n)
        .filter(|k| !seen.contains_key(k))
        .map(|k| k.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(Error::settings(format!(
            "{} of {n} shards missing: {} (of the run of {})",
            missing.len(),
            missing.join(", "),
            run.manifest
        ))
        .with_hint(format!(
            "run the missing tasks again, e.g. dea-fit rank {} --shard {}/{n} --out ...",
            run.manifest, missing[0]
        )));
    }
    let mut slots: Vec<Option<Evaluated>> = vec![None; pts.len()];
    for (p, s) in paths.iter().zip(shards) {
        let k = s.shard.k;
        let bad = |msg: String| Error::input(Location::file(p), msg).with_hint(RERUN);
        for e in s.evaluations {
            let i = e.evaluation.index;
            let Some(pt) = pts.get(i).filter(|_| i % n == k) else {
                return Err(bad(format!(
                    "evaluation {i} does not belong to shard {k}/{n} of a {}-point run",
                    pts.len()
                )));
            };
            if slots[i].is_some() {
                return Err(bad(format!("evaluation {i} is repeated")));
            }
            check_evaluation(&d, &pt, &e)
                .map_err(|why| bad(format!("evaluation {i} ({}): {why}", e.evaluation.name)))?;
            slots[i] = Some(e);
        }
    }
    let evals: Vec<Evaluated> = slots
        .into_iter()
        .enumerate()
        .map(|(i, e)| {
            e.ok_or_else(|| {
                Error::input(
                    Location::file(seen[&(i % n)]),
                    format!("point {i} is missing from shard {}/{n}", i % n),
                )
                .with_hint(RERUN)
            })
        })
        .collect::<Result<_>>()?;
    Ok((run, evals))
}

/// Largest contraction a stroke may be below zero (1 − λ/λ0 at the rest state is 0
/// up to rounding; the equilibrium solvers work to 1e-10 in λ or better).
const STROKE_SLACK: f64 = 1e-9;

/// The unit of every figure of an evaluation, by field name (SI; `1`: none).
const UNITS: [(&str, &str); 15] = [
    ("voltage", "V"),
    ("eps_r", "1"),
    ("youngs_modulus", "Pa"),
    ("beta", "1/Pa"),
    ("fm", "1"),
    ("tan_delta", "1"),
    ("breakdown_field", "V/m"),
    ("static_stroke", "1"),
    ("max_stroke", "1"),
    ("blocked_force", "N"),
    ("response_time", "s"),
    ("energy_in", "J"),
    ("loss_per_cycle", "J"),
    ("breakdown_margin", "1"),
    ("pull_in_margin", "1"),
];

/// The domain of a figure's value: the name of the rule and whether it holds.
fn domain(field: &str, v: f64) -> std::result::Result<(), &'static str> {
    let ok = match field {
        "voltage" => (0.0..=crate::sim::budget::VOLTAGE.max).contains(&v),
        "static_stroke" | "max_stroke" => (-STROKE_SLACK..1.0).contains(&v),
        "eps_r" | "youngs_modulus" | "beta" | "fm" | "breakdown_field" | "response_time" => v > 0.0,
        "tan_delta" | "blocked_force" | "loss_per_cycle" => v >= 0.0,
        "breakdown_margin" | "pull_in_margin" => v <= 1.0,
        _ => true,
    };
    match (v.is_finite(), ok, field) {
        (false, _, _) => Err("not finite"),
        (true, true, _) => Ok(()),
        (true, false, "voltage") => Err("not a drive voltage (0 … the simulator's budget)"),
        (true, false, "static_stroke" | "max_stroke") => Err("not a stroke (0 ≤ s < 1)"),
        (true, false, "tan_delta" | "blocked_force" | "loss_per_cycle") => Err("negative"),
        (true, false, "breakdown_margin" | "pull_in_margin") => Err("not a margin (≤ 1)"),
        (true, false, _) => Err("not positive"),
    }
}

/// A point of a curve: a finite voltage ≥ 0 and a stroke in [0, 1).
fn curve_point(what: &str, q: &CurvePoint) -> std::result::Result<(), String> {
    match q.voltage_v.is_finite() && q.voltage_v >= 0.0 && (-STROKE_SLACK..1.0).contains(&q.stroke)
    {
        true => Ok(()),
        false => Err(format!(
            "{what} ({} V, stroke {}) is not a point of a static curve",
            q.voltage_v, q.stroke
        )),
    }
}

/// A figure equal to `want` but for its standard error (which the merge cannot
/// compute without evaluating again).
fn same_figure(what: &str, got: &Figure, want: &Figure) -> std::result::Result<(), String> {
    let strip = |f: &Figure| f.clone().with_std_error(None);
    match strip(got) == strip(want) {
        true => Ok(()),
        false => Err(format!(
            "{what} is not the design's ({} {} from {}; the design gives {} {} from {})",
            got.value.map_or("none".into(), |v| v.to_string()),
            got.unit,
            got.source,
            want.value.map_or("none".into(), |v| v.to_string()),
            want.unit,
            want.source
        )),
    }
}

/// Whether `e` can be the evaluation of point `p` of design `d`: the candidate the
/// design gives there (names, loading, volume fraction, rules, εr, Y, tan δ, Eb, β,
/// Fm and their sources, warnings), the drive voltage of the point, every figure's
/// unit, every value finite and in its domain (strokes in [0, 1), voltages, fields,
/// moduli and times positive, losses and forces not negative), every standard error
/// finite and not negative, the state consistent with the static stroke, and the
/// curves' points in range. The simulated values themselves are covered by the
/// file's digest, not recomputed.
pub fn check_evaluation(d: &Design, p: &Point, e: &Evaluated) -> std::result::Result<(), String> {
    let c = candidate::build(d, p.series, p.loading)
        .map_err(|err| format!("the design gives no candidate at this point ({err})"))?;
    let mut ev = e.evaluation.clone();
    let names = [
        ("name", &ev.name, &c.name),
        ("series", &ev.series, &c.series),
        ("matrix", &ev.matrix, &c.matrix),
        ("rules", &ev.rules, &c.rules),
    ];
    for (what, got, want) in names {
        if got != want {
            return Err(format!("{what} '{got}' is not the design's '{want}'"));
        }
    }
    if ev.filler != c.filler || ev.basis != c.basis {
        return Err(format!(
            "filler {:?} on a {:?} basis is not the design's {:?} on a {:?} basis",
            ev.filler, ev.basis, c.filler, c.basis
        ));
    }
    if ev.loading.to_bits() != c.loading.to_bits()
        || ev.volume_fraction.to_bits() != c.volume_fraction.to_bits()
    {
        return Err(format!(
            "loading {} (volume fraction {}) is not the point's {} ({})",
            ev.loading, ev.volume_fraction, c.loading, c.volume_fraction
        ));
    }
    let (beta, fm) = catalogue(&c);
    same_figure("eps_r", &ev.eps_r, &c.eps_r)?;
    same_figure("youngs_modulus", &ev.youngs_modulus, &c.youngs_modulus)?;
    same_figure("tan_delta", &ev.tan_delta, &c.tan_delta)?;
    same_figure("breakdown_field", &ev.breakdown_field, &c.breakdown)?;
    same_figure("beta", &ev.beta, &beta)?;
    same_figure("fm", &ev.fm, &fm)?;
    // The candidate's warnings, then at most the one of the standard errors
    // (`Evaluation::spread`: "<name>: with <property> 1σ higher|lower …").
    let spread = format!("{}: with ", c.name);
    let own = ev.warnings.starts_with(&c.warnings);
    let rest = ev.warnings.get(c.warnings.len()..).unwrap_or_default();
    if !own
        || rest.len() > 1
        || rest
            .iter()
            .any(|w| !(w.starts_with(&spread) && w.contains(" 1σ ")))
    {
        return Err("its warnings are not the candidate's".into());
    }
    let state = ev.state;
    match (p.level, ev.voltage.value) {
        (Level::Voltage(x), Some(v)) if v.to_bits() != x.to_bits() => {
            return Err(format!("drive voltage {v} V is not the point's {x} V"))
        }
        (_, None) if state != State::Failed => {
            return Err(format!("state {state} without a drive voltage"))
        }
        _ => {}
    }
    match (state, ev.static_stroke.value) {
        (State::Ok, None) => return Err("state ok without a static stroke".into()),
        (State::PullIn | State::Breakdown, Some(_)) => {
            return Err(format!("state {state} with a static stroke"))
        }
        _ => {}
    }
    for ((field, f), (name, unit)) in ev.figures_mut().into_iter().zip(UNITS) {
        debug_assert_eq!(field, name);
        if f.unit != unit {
            return Err(format!("{field}: unit '{}', expected '{unit}'", f.unit));
        }
        if let Some(v) = f.value {
            domain(field, v).map_err(|why| format!("{field} {v} {unit}: {why}"))?;
        }
        if let Some(s) = f.std_error {
            if f.value.is_none() {
                return Err(format!("{field}: a standard error without a value"));
            }
            if !(s.is_finite() && s >= 0.0) {
                return Err(format!("{field}: standard error {s} is not finite and ≥ 0"));
            }
        }
    }
    if e.curve.len() > KEPT_POINTS {
        return Err(format!(
            "a curve of {} points (at most {KEPT_POINTS})",
            e.curve.len()
        ));
    }
    for q in &e.curve {
        curve_point("a point of its curve", q)?;
    }
    if let Some(q) = &ev.pull_in {
        curve_point("its pull-in", q)?;
    }
    if let Some(q) = &ev.breakdown {
        curve_point("its breakdown point", q)?;
    }
    Ok(())
}

/// Largest array a generated Slurm script asks for (Slurm's default
/// `MaxArraySize` is 1001: indices 0 … 1000).
pub const MAX_SLURM_TASKS: usize = 1000;

/// A shell word in single quotes.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// What a generated Slurm job runs.
#[derive(Debug, Clone)]
pub struct SlurmJob {
    /// Number of shards (array tasks).
    pub tasks: usize,
    /// The dea-fit executable (absolute).
    pub exe: PathBuf,
    /// The directory the jobs run in (absolute).
    pub cwd: PathBuf,
    /// The design manifest, as given (relative to `cwd`).
    pub design: PathBuf,
    /// The `--sweep` values.
    pub sweep: Vec<String>,
    /// Flags of the merge (ranking and output), as words.
    pub merge_flags: Vec<String>,
    /// Directory of the shard files, job scripts and logs (relative to `cwd`).
    pub dir: String,
    /// Whether the merge prints JSON (`--json`): its output is then
    /// `<dir>/ranking.json`, else the table in `<dir>/ranking.txt`.
    pub json: bool,
}

/// A POSIX shell script that writes a Slurm array job (one task per shard, each
/// `rank --shard $SLURM_ARRAY_TASK_ID/N`) and a merge job, and submits both, the
/// merge with `--dependency=afterok` on the whole array. The merge's table goes to
/// `<dir>/ranking.txt` (its JSON to `<dir>/ranking.json` with `--json`), its errors
/// to `<dir>/merge.log`.
pub fn slurm_script(j: &SlurmJob) -> String {
    let n = j.tasks;
    let dir = &j.dir;
    let exe = quote(&j.exe.display().to_string());
    let sweep: String = j
        .sweep
        .iter()
        .map(|s| format!(" --sweep {}", quote(s)))
        .collect();
    let merge: String = j
        .merge_flags
        .iter()
        .map(|f| format!(" {}", quote(f)))
        .collect();
    format!(
        r#"#!/bin/sh
# A {n}-shard dea-fit rank sweep on Slurm, written by
#   dea-fit rank {design} ... --slurm {n}
# Run it where sbatch works: sh THIS_FILE. It writes {dir}/shard.sbatch (a job array,
# one task per shard) and {dir}/merge.sbatch, submits the array and then the merge
# with --dependency=afterok on the whole array: the merge starts only when every
# task succeeded. Shard files are written atomically (a killed task leaves none);
# to repair a sweep, run the failed task again and then the merge:
#   sbatch --array=K {dir}/shard.sbatch && sbatch {dir}/merge.sbatch
# The merged {what} is {dir}/{out}; rank merge refuses missing, repeated, foreign
# (another manifest, sweep or shard count) or altered shards, see {dir}/merge.log.
set -eu
cd {cwd}
mkdir -p {qdir}
cat > {qdir}/shard.sbatch <<'DEA_FIT_SHARD'
#!/bin/sh
#SBATCH --job-name=dea-fit-rank
#SBATCH --array=0-{last}
#SBATCH --ntasks=1
#SBATCH --output={dir}/shard-%a.log
set -eu
exec {exe} rank {qdesign}{sweep} --shard "$SLURM_ARRAY_TASK_ID/{n}" --out "{dir}/shard-$SLURM_ARRAY_TASK_ID.json"
DEA_FIT_SHARD
cat > {qdir}/merge.sbatch <<'DEA_FIT_MERGE'
#!/bin/sh
#SBATCH --job-name=dea-fit-rank-merge
#SBATCH --ntasks=1
#SBATCH --output={dir}/{out}
#SBATCH --error={dir}/merge.log
set -eu
exec {exe} rank merge {dir}/shard-*.json{merge}
DEA_FIT_MERGE
array=$(sbatch --parsable {qdir}/shard.sbatch)
array=${{array%%;*}}
merge=$(sbatch --parsable --dependency=afterok:$array --kill-on-invalid-dep=yes {qdir}/merge.sbatch)
echo "submitted array job $array ({n} shards) and merge job ${{merge%%;*}}; the {what} will be in {dir}/{out}"
"#,
        design = j.design.display(),
        qdesign = quote(&j.design.display().to_string()),
        cwd = quote(&j.cwd.display().to_string()),
        qdir = quote(dir),
        last = n - 1,
        out = match j.json {
            true => "ranking.json",
            false => "ranking.txt",
        },
        what = match j.json {
            true => "ranking (JSON)",
            false => "table",
        },
    )
}
