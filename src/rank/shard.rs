//! Shard files: one slice of a sweep (`rank --shard K/N --out F`), and their merge
//! (`rank merge`) into the evaluations a single run gives.
//!
//! A shard file holds the run's identity ([`RunInfo`]: the design's SHA-256 over
//! the manifest and every file it reads, the sweep, the number of points, the tool
//! version), the shard (K, N) and its evaluations. It is written atomically (a
//! temporary file, then a rename), so a killed task leaves no half file and running
//! the task again repairs the sweep. The merge refuses, naming the files: a file
//! that is not a shard, shards of different runs, a shard given twice, a missing
//! shard, and evaluations that do not cover the run's points exactly once.

use super::figures::Evaluated;
use super::manifest::{Design, Level};
use super::sweep::{Shard, Sweep};
use crate::error::{Error, Location, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Schema tag of shard files.
pub const SCHEMA: &str = "dea-fit/rank-shard/1";

/// What makes two runs the same: everything the evaluations depend on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
}

/// A shard file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShardFile {
    /// [`SCHEMA`].
    pub schema: String,
    /// The run.
    pub run: RunInfo,
    /// Which slice.
    pub shard: Shard,
    /// Its evaluations, by index.
    pub evaluations: Vec<Evaluated>,
}

/// Write a shard by the write policy ([`crate::io::write::write_keeping`]): an
/// existing file is replaced only when it is a shard file (a re-run of the task),
/// anything else is refused; an older, different shard is kept aside (what
/// happened to it is returned), and two tasks writing one file both keep theirs.
pub fn write(path: &Path, s: &ShardFile) -> Result<crate::io::write::Replaced> {
    if path.is_file() && read(path).is_err() {
        return Err(Error::settings(format!(
            "{} exists and is not a rank shard file: it is not replaced",
            path.display()
        ))
        .with_hint("choose another --out"));
    }
    let json = serde_json::to_string(s).expect("a shard serialises");
    crate::io::write::write_keeping(path, json.as_bytes(), |old| old == json.as_bytes())
}

/// Read a shard file.
pub fn read(path: &Path) -> Result<ShardFile> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a rank shard file: {e}"),
        )
        .with_hint("shard files are written by dea-fit rank --shard K/N --out FILE")
    })?;
    match v.get("schema").and_then(|s| s.as_str()) {
        Some(SCHEMA) => {}
        other => {
            return Err(Error::input(
                Location::file(path),
                format!(
                    "schema: expected \"{SCHEMA}\", found {}",
                    other.map_or("none".into(), |s| format!("\"{s}\""))
                ),
            )
            .with_hint("shard files are written by dea-fit rank --shard K/N --out FILE"))
        }
    }
    serde_json::from_value(v).map_err(|e| {
        Error::input(
            Location::file(path),
            format!("not a rank shard file of its schema: {e}"),
        )
    })
}

/// Merge shard files into the run's identity and its evaluations in run order,
/// refusing anything but exactly the N shards of one run.
pub fn merge(paths: &[PathBuf]) -> Result<(RunInfo, Vec<Evaluated>)> {
    let Some(first) = paths.first() else {
        return Err(
            Error::settings("no shard files given").with_hint("dea-fit rank merge shard-*.json")
        );
    };
    let shards: Vec<ShardFile> = paths.iter().map(|p| read(p)).collect::<Result<_>>()?;
    let (run, n) = (shards[0].run.clone(), shards[0].shard.n);
    let mut seen: Vec<Option<&Path>> = vec![None; n];
    for (p, s) in paths.iter().zip(&shards) {
        if s.run != run || s.shard.n != n {
            let what = if s.run.sha256 != run.sha256 {
                format!(
                    "design hash {} vs {}",
                    &s.run.sha256[..12.min(s.run.sha256.len())],
                    &run.sha256[..12.min(run.sha256.len())]
                )
            } else if s.run.sweep != run.sweep {
                format!("sweep '{}' vs '{}'", s.run.sweep, run.sweep)
            } else if s.shard.n != n {
                format!("{} shards vs {n}", s.shard.n)
            } else {
                "run settings".into()
            };
            return Err(Error::input(
                Location::file(p),
                format!("belongs to another run than {} ({what})", first.display()),
            )
            .with_hint(
                "merge the shards of one sweep: the same manifest and files, sweep and shard count",
            ));
        }
        let k = s.shard.k;
        if k >= n {
            return Err(Error::input(
                Location::file(p),
                format!("shard {k} of {n} does not exist"),
            ));
        }
        if let Some(other) = seen[k] {
            return Err(Error::input(
                Location::file(p),
                format!("shard {k}/{n} is given twice (also {})", other.display()),
            )
            .with_hint("give each shard once"));
        }
        seen[k] = Some(p);
    }
    let missing: Vec<String> = (0..n)
        .filter(|&k| seen[k].is_none())
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
    let mut slots: Vec<Option<Evaluated>> = vec![None; run.points];
    for (p, s) in paths.iter().zip(shards) {
        for e in s.evaluations {
            let i = e.evaluation.index;
            let ok = i < run.points && s.shard.k == i % n && slots[i].is_none();
            if !ok {
                return Err(Error::input(
                    Location::file(p),
                    format!("evaluation {i} does not belong to shard {}/{n} of a {}-point run, or is repeated", s.shard.k, run.points),
                )
                .with_hint("the file was edited or damaged: run its task again"));
            }
            slots[i] = Some(e);
        }
    }
    let evals: Vec<Evaluated> = slots
        .into_iter()
        .enumerate()
        .map(|(i, e)| {
            e.ok_or_else(|| {
                Error::input(
                    Location::file(seen[i % n].expect("every shard is present")),
                    format!("point {i} is missing from shard {}/{n}", i % n),
                )
                .with_hint("the file was edited or damaged: run its task again")
            })
        })
        .collect::<Result<_>>()?;
    Ok((run, evals))
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
}

/// A POSIX shell script that writes a Slurm array job (one task per shard, each
/// `rank --shard $SLURM_ARRAY_TASK_ID/N`) and a merge job, and submits both, the
/// merge with `--dependency=afterok` on the whole array. The merge's table goes to
/// `<dir>/ranking.txt`, its errors to `<dir>/merge.log`.
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
# The merged table is {dir}/ranking.txt; rank merge refuses missing, repeated or
# foreign shards (another manifest, sweep or shard count), see {dir}/merge.log.
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
#SBATCH --output={dir}/ranking.txt
#SBATCH --error={dir}/merge.log
set -eu
exec {exe} rank merge {dir}/shard-*.json{merge}
DEA_FIT_MERGE
array=$(sbatch --parsable {qdir}/shard.sbatch)
array=${{array%%;*}}
merge=$(sbatch --parsable --dependency=afterok:$array --kill-on-invalid-dep=yes {qdir}/merge.sbatch)
echo "submitted array job $array ({n} shards) and merge job ${{merge%%;*}}; the table will be in {dir}/ranking.txt"
"#,
        design = j.design.display(),
        qdesign = quote(&j.design.display().to_string()),
        cwd = quote(&j.cwd.display().to_string()),
        qdir = quote(dir),
        last = n - 1,
    )
}
