//! `dea-fit rank`: rank fillers and composites by what they buy an actuator
//! (docs/rank.md); `rank merge` joins the shard files of a sweep.
//!
//! Status: `ok`, `warning` (properties held or extrapolated), `incomplete`
//! (candidates that could not be evaluated: exit 1 under `--strict`), `failed` (no
//! candidate could be ranked: exit 1).

use dea_fit::rank::figures::{Evaluated, State};
use dea_fit::rank::manifest;
use dea_fit::rank::ranking::{self, Objective};
use dea_fit::rank::report;
use dea_fit::rank::shard::{self, RunInfo, ShardFile, SlurmJob};
use dea_fit::rank::sweep::{self, Points, Shard, Sweep};
use dea_fit::{Error, Result};
use std::path::{Path, PathBuf};

/// Rank fillers and composites by what they buy an actuator.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    #[command(subcommand)]
    merge: Option<Sub>,
    /// The design manifest (TOML, docs/rank.md).
    #[arg(required = true)]
    design: Option<PathBuf>,
    /// Sweep KEY=START:STOP:COUNT replacing the manifest's: loading (fractions on
    /// each series' basis, e.g. loading=0:0.4:41) or voltage (e.g.
    /// voltage=1kV:8kV:15). Repeatable.
    #[arg(long, value_name = "KEY=RANGE")]
    sweep: Vec<String>,
    /// Evaluate only shard K of N (the points whose index is K modulo N, K from 0;
    /// N at most 10000 and at most the number of points) and write them to --out;
    /// `rank merge` joins and ranks the shards (the ranking and output flags are
    /// refused here: give them to the merge).
    #[arg(long, value_name = "K/N", requires = "out")]
    shard: Option<String>,
    /// The shard file to write (with --shard).
    #[arg(long, requires = "shard")]
    out: Option<PathBuf>,
    /// Print a Slurm script (an N-task job array and a merge job after it) instead
    /// of running.
    #[arg(long, value_name = "N", conflicts_with_all = ["shard", "out"])]
    slurm: Option<usize>,
    /// With --slurm: directory of the shard files, job scripts and logs.
    #[arg(long, default_value = "rank-shards", requires = "slurm")]
    shard_dir: String,
    #[command(flatten)]
    present: Present,
}

#[derive(Debug, clap::Subcommand)]
enum Sub {
    /// Join the shard files of one sweep into the ranking a single run gives.
    Merge(MergeArgs),
}

#[derive(Debug, clap::Args)]
struct MergeArgs {
    /// The shard files (all N of them).
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// The design manifest the shards were computed from (default: the manifest
    /// path the shards name). It is read again to check the shards.
    #[arg(long)]
    design: Option<PathBuf>,
    #[command(flatten)]
    present: Present,
}

/// Ranking and output flags, shared by a run and a merge.
#[derive(Debug, Clone, clap::Args)]
struct Present {
    /// Objective to rank by: stroke, max-stroke, force, speed, fm, beta, loss
    /// (default stroke).
    #[arg(long)]
    by: Option<String>,
    /// The two objectives of the Pareto front (default stroke,speed).
    #[arg(long, value_name = "A,B")]
    pareto: Option<String>,
    /// Relative tolerance within which two candidates without a standard error
    /// cannot be told apart (a tie), as a fraction or percentage (default 1%; 0:
    /// only equal values tie). With standard errors: 2σ of the difference.
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    tie_tolerance: Option<String>,
    /// Rows of the printed table and the report's table (0: all; default 20).
    #[arg(long)]
    top: Option<usize>,
    /// Print the ranking as JSON.
    #[arg(long)]
    json: bool,
    /// Write every evaluation as CSV to this file.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Report directory (default reports/rank-<design>).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Do not write the report.
    #[arg(long)]
    no_report: bool,
    /// Exit with status 1 when some candidates could not be evaluated.
    #[arg(long)]
    strict: bool,
}

/// Default of `--pareto`.
const PARETO: &str = "stroke,speed";
/// Default of `--top`.
const TOP: usize = 20;

impl Present {
    /// The objective, the Pareto pair and the tie tolerance, checked before any
    /// work.
    fn objectives(&self) -> Result<(Objective, [Objective; 2], f64)> {
        let by = Objective::parse(self.by.as_deref().unwrap_or("stroke"))?;
        let tie = self
            .tie_tolerance
            .as_deref()
            .map_or(Ok(ranking::TOLERANCE), ranking::parse_tie_tolerance)?;
        let pareto = self.pareto.as_deref().unwrap_or(PARETO);
        let pair: Vec<&str> = pareto.split(',').collect();
        let [a, b] = pair[..] else {
            return Err(
                Error::settings(format!("--pareto {pareto}: expected two objectives A,B"))
                    .with_hint("e.g. --pareto stroke,speed"),
            );
        };
        let (a, b) = (Objective::parse(a)?, Objective::parse(b)?);
        if a == b {
            return Err(Error::settings("--pareto: the two objectives must differ"));
        }
        Ok((by, [a, b], tie))
    }

    /// Rows of the tables.
    fn top(&self) -> usize {
        self.top.unwrap_or(TOP)
    }

    /// A shard is not ranked: the flags of the ranking and its outputs are refused
    /// with it (honoured by `rank merge`); `--strict` (the shard's exit status) and
    /// `--no-report` (no report is written) hold as they are.
    fn refuse_with_shard(&self) -> Result<()> {
        let given: Vec<&str> = [
            (self.by.is_some(), "--by"),
            (self.pareto.is_some(), "--pareto"),
            (self.tie_tolerance.is_some(), "--tie-tolerance"),
            (self.top.is_some(), "--top"),
            (self.json, "--json"),
            (self.csv.is_some(), "--csv"),
            (self.report.is_some(), "--report"),
        ]
        .into_iter()
        .filter_map(|(on, f)| on.then_some(f))
        .collect();
        match given.is_empty() {
            true => Ok(()),
            false => Err(Error::settings(format!(
                "--shard with {}: a shard writes only its shard file (--out); the ranking and its table, JSON, CSV and report are made by rank merge",
                given.join(", ")
            ))
            .with_hint(format!(
                "drop {} here and give {} to dea-fit rank merge SHARD-FILES...",
                given.join(", "),
                match given.len() {
                    1 => "it",
                    _ => "them",
                }
            ))),
        }
    }

    /// The flags as words, for the merge job of a Slurm script (paths as given: the
    /// jobs run in the directory the script was written in).
    fn words(&self) -> Vec<String> {
        let mut w = Vec::new();
        if let Some(by) = &self.by {
            w.extend(["--by".into(), by.clone()]);
        }
        if let Some(p) = &self.pareto {
            w.extend(["--pareto".into(), p.clone()]);
        }
        if let Some(t) = &self.tie_tolerance {
            w.extend(["--tie-tolerance".into(), t.clone()]);
        }
        if let Some(t) = self.top {
            w.extend(["--top".into(), t.to_string()]);
        }
        if self.json {
            w.push("--json".into());
        }
        if let Some(c) = &self.csv {
            w.extend(["--csv".into(), c.display().to_string()]);
        }
        match (&self.report, self.no_report) {
            (_, true) => w.push("--no-report".into()),
            (Some(r), false) => w.extend(["--report".into(), r.display().to_string()]),
            (None, false) => {}
        }
        if self.strict {
            w.push("--strict".into());
        }
        w
    }
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    if let Some(Sub::Merge(m)) = a.merge {
        m.present.objectives()?;
        let (info, evals) = shard::merge(&m.shards, m.design.as_deref())?;
        return present(&info, &evals, &m.present);
    }
    let design = a.design.expect("clap requires the design");
    a.present.objectives()?;
    let sweep = Sweep::parse(&a.sweep)?;
    let shard = a.shard.as_deref().map(Shard::parse).transpose()?;
    if shard.is_some() {
        a.present.refuse_with_shard()?;
    }
    let d = manifest::read(&design)?;
    let points = Points::new(&d, &sweep)?;
    let shard = shard.map(|s| s.check(points.len())).transpose()?;
    let info = RunInfo::new(&d, &sweep, points.len());
    if let Some(n) = a.slurm {
        if n == 0 || n > shard::MAX_SLURM_TASKS {
            return Err(Error::settings(format!(
                "--slurm {n}: expected 1 … {}",
                shard::MAX_SLURM_TASKS
            ))
            .with_hint("Slurm's default MaxArraySize is 1001; put more work into each shard"));
        }
        Shard { k: 0, n }
            .check(points.len())
            .map_err(|e| Error::settings(format!("--slurm {n}: {e}")))?;
        if a.shard_dir.is_empty()
            || !a
                .shard_dir
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "._/-".contains(c))
        {
            return Err(Error::settings(format!(
                "--shard-dir '{}': use letters, digits and . _ / -",
                a.shard_dir
            )));
        }
        let exe = std::env::current_exe().map_err(|e| Error::io("dea-fit", e))?;
        let cwd = std::env::current_dir().map_err(|e| Error::io(".", e))?;
        print!(
            "{}",
            shard::slurm_script(&SlurmJob {
                tasks: n,
                exe,
                design: design.clone(),
                cwd,
                sweep: a.sweep.clone(),
                merge_flags: a.present.words(),
                dir: a.shard_dir.clone(),
                json: a.present.json,
            })
        );
        return Ok(0);
    }
    let bar = dea_fit::observe::Meter::new("rank", "candidates", Some(points.count(shard) as u64));
    let evals = sweep::run_all(&d, &points, shard, &|| bar.inc(1))?;
    bar.finish();
    match (shard, &a.out) {
        (Some(s), Some(out)) => {
            let failed = evals
                .iter()
                .filter(|e| e.evaluation.state == State::Failed)
                .count();
            let file = ShardFile::new(info.clone(), &sweep, s, evals);
            super::note(out, "shard", &shard::write(out, &file)?);
            let status = match failed {
                0 => ranking::Status::Ok,
                _ => ranking::Status::Incomplete,
            };
            println!(
                "shard {}/{}: {} of {} points evaluated ({failed} could not be) → {}",
                s.k,
                s.n,
                file.evaluations.len(),
                info.points,
                out.display()
            );
            println!("status: {status}");
            Ok(status.exit_code(a.present.strict))
        }
        _ => present(&info, &evals, &a.present),
    }
}

/// Rank the evaluations of a run and write what was asked: the table or JSON on
/// stdout, the CSV, the report.
fn present(info: &RunInfo, evals: &[Evaluated], p: &Present) -> Result<i32> {
    let (by, pair, tie) = p.objectives()?;
    let list: Vec<_> = evals.iter().map(|e| e.evaluation.clone()).collect();
    let r = ranking::rank_with(&list, by, pair, tie);
    let dir = (!p.no_report).then(|| {
        p.report.clone().unwrap_or_else(|| {
            let slug: String = info
                .design
                .to_lowercase()
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
                .collect();
            Path::new("reports").join(format!("rank-{}", slug.trim_matches('-')))
        })
    });
    super::refuse_in_report(dir.as_deref(), &[("--csv", p.csv.as_deref())])?;
    if let Some(d) = &dir {
        super::claim_dir(d)?;
    }
    if let Some(c) = &p.csv {
        super::write_noted(c, report::csv(evals, &r).as_bytes())?;
    }
    let page = dir
        .map(|d| report::write(&d, info, evals, &r, p.top()))
        .transpose()?;
    if p.json {
        println!("{}", report::json(info, evals, &r));
    } else {
        print!("{}", report::summary(info, evals, &r, p.top())?);
        if let Some(pg) = page {
            eprintln!("report: {}", pg.display());
        }
    }
    Ok(r.status.exit_code(p.strict))
}
