//! `dea-fit bench make`: the wall time of `dea-fit make` (issue 37, "Speed") on two
//! projects, each in a temporary folder:
//!
//! - a generated project of `--steps` steps (default 1 000), each a `dea-fit
//!   breakdown` of its own 20-coupon series (a copy of the lab project's), run
//!   from scratch once, then timed up to date (make with its project page: nothing
//!   runs, nothing is written);
//! - the shipped lab project (`--lab`, datasets/lab) copied without its outputs,
//!   from scratch once, then up to date.
//!
//! Times are wall clock of the whole `dea-fit make` process (this program), the
//! up-to-date ones repeated within the budget and summarised by the median
//! ([`dea_fit::bench::measure`]). Writes `make.{csv,json,svg,md}` under the output
//! directory. `--steps 100 --budget 0 --min-repeats 1` is the short run for CI.

use dea_fit::bench::{copy_project, make_project, measure, Budget, Scratch, Timing};
use dea_fit::io::write::atomic_write;
use dea_fit::report::format::{si, table};
use dea_fit::units::CountRange;
use dea_fit::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Steps of the generated project: each is a process and a report, so 10⁵ is
/// minutes of a 2-core machine and some 10⁵ files.
const STEPS: CountRange = CountRange::new(1, 100_000, "steps of the generated project");

/// What `bench make` measures.
#[derive(Debug, clap::Args)]
pub struct MakeArgs {
    /// Steps of the generated project.
    #[arg(long, default_value_t = 1000, value_parser = |s: &str| STEPS.parse(s))]
    steps: usize,
    /// The lab project to copy and run from scratch.
    #[arg(long, default_value = "datasets/lab")]
    lab: PathBuf,
    /// Steps run at once (default: the number of CPUs), as make's --jobs.
    #[arg(long, short = 'j', value_parser = clap::value_parser!(u16).range(1..))]
    jobs: Option<u16>,
    /// Seconds spent repeating each up-to-date make (at least --min-repeats runs).
    #[arg(long, default_value_t = 1.0)]
    budget: f64,
    /// Fewest timed runs of each up-to-date make.
    #[arg(long, default_value_t = 5)]
    min_repeats: usize,
    /// Directory of the report.
    #[arg(long, default_value = "reports/bench")]
    out_dir: PathBuf,
}

/// One timed case.
#[derive(Debug, Clone, Serialize)]
struct Row {
    /// `generated` or `lab`.
    project: &'static str,
    steps: usize,
    /// `from_scratch` or `up_to_date`.
    case: &'static str,
    median_s: f64,
    min_s: f64,
    repeats: usize,
    /// Median seconds per step.
    per_step_s: f64,
}

#[derive(Serialize)]
struct Report<'a> {
    tool_version: &'static str,
    jobs: usize,
    budget_s: f64,
    min_repeats: usize,
    rows: &'a [Row],
}

/// `dea-fit make -C dir --jobs jobs` (this program): its wall time, or the error
/// with the end of what it printed.
fn make(dir: &Path, jobs: usize) -> Result<f64> {
    let exe = std::env::current_exe().map_err(|e| Error::io("dea-fit", e))?;
    let t = Instant::now();
    let o = std::process::Command::new(&exe)
        .arg("make")
        .arg("-C")
        .arg(dir)
        .args(["--jobs", &jobs.to_string()])
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| Error::io(&exe, e))?;
    let s = t.elapsed().as_secs_f64();
    if !o.status.success() {
        let out = String::from_utf8_lossy(&o.stdout);
        let tail: Vec<&str> = out.lines().rev().take(5).collect();
        return Err(Error::settings(format!(
            "dea-fit make -C {} ended with {}: {}{}",
            dir.display(),
            o.status,
            tail.into_iter().rev().collect::<Vec<_>>().join(" | "),
            String::from_utf8_lossy(&o.stderr).trim()
        )));
    }
    Ok(s)
}

/// The two cases of one project: from scratch (once), then up to date.
fn cases(
    project: &'static str,
    dir: &Path,
    steps: usize,
    jobs: usize,
    budget: &Budget,
) -> Result<Vec<Row>> {
    let scratch = make(dir, jobs)?;
    let (up, _) = measure(budget, || make(dir, jobs))?;
    let row = |case, t: Timing| Row {
        project,
        steps,
        case,
        median_s: t.median_s,
        min_s: t.min_s,
        repeats: t.repeats,
        per_step_s: t.median_s / steps as f64,
    };
    let once = Timing {
        median_s: scratch,
        min_s: scratch,
        repeats: 1,
    };
    Ok(vec![row("from_scratch", once), row("up_to_date", up)])
}

/// Run the benchmark.
pub fn run(a: &MakeArgs) -> Result<super::bench::Verdict> {
    let budget = Budget {
        min_repeats: a.min_repeats,
        seconds: a.budget,
        ..Budget::default()
    };
    budget.check()?;
    let coupon = a.lab.join("raw/vhb4910/breakdown.csv");
    let series = std::fs::read(&coupon).map_err(|e| {
        Error::io(&coupon, e)
            .with_hint("run from the repository root or pass --lab path/to/datasets/lab")
    })?;
    let jobs = a.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        usize::from,
    );
    let tmp = Scratch::new("bench-make")?;
    let generated = tmp.path().join("generated");
    make_project(&generated, a.steps, &series)?;
    let lab = tmp.path().join("lab");
    copy_project(&a.lab, &lab)?;
    let lab_steps = std::fs::read_to_string(lab.join(dea_fit::project::FILE))
        .map_err(|e| Error::io(&lab, e))?
        .lines()
        .filter(|l| {
            l.starts_with("[materials.")
                || l.starts_with("[actuators.")
                || l.starts_with("[designs.")
        })
        .count();
    println!("dea-fit bench make: {} generated steps and the lab project ({lab_steps} steps), --jobs {jobs}", a.steps);
    let mut rows = cases("generated", &generated, a.steps, jobs, &budget)?;
    rows.extend(cases("lab", &lab, lab_steps, jobs, &budget)?);
    for r in &rows {
        println!(
            "{:<10} {:>6} steps  {:<13} {:>10} (median of {})",
            r.project,
            r.steps,
            r.case.replace('_', " "),
            si(r.median_s, "s"),
            r.repeats
        );
    }
    write(a, jobs, &rows)?;
    println!("report: {}", a.out_dir.join("make.md").display());
    Ok(super::bench::Verdict::default())
}

fn write(a: &MakeArgs, jobs: usize, rows: &[Row]) -> Result<()> {
    let dir = &a.out_dir;
    super::claim_dir(dir)?;
    let io = |e: String| Error::settings(format!("could not write the bench report: {e}"));
    super::bench::write_csv(&dir.join("make.csv"), rows)?;
    let report = Report {
        tool_version: env!("CARGO_PKG_VERSION"),
        jobs,
        budget_s: a.budget,
        min_repeats: a.min_repeats,
        rows,
    };
    let json = serde_json::to_string_pretty(&report).map_err(|e| io(e.to_string()))?;
    atomic_write(&dir.join("make.json"), json.as_bytes())?;
    let groups = ["from_scratch", "up_to_date"]
        .iter()
        .map(|case| {
            let points = rows.iter().filter(|r| r.case == *case);
            let points = points.map(|r| (r.steps as f64, r.median_s)).collect();
            (case.replace('_', " "), points)
        })
        .collect();
    super::bench::loglog_times(
        "dea-fit make: wall time against the project's steps",
        "log₁₀ steps",
        groups,
    )
    .write_svg(&dir.join("make.svg"))?;
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let head = [
                r.project.to_string(),
                r.steps.to_string(),
                r.case.replace('_', " "),
            ];
            let times = super::bench::time_cells(r.median_s, r.min_s, r.repeats, r.per_step_s);
            head.into_iter().chain(times).collect()
        })
        .collect();
    let tab = table(
        &[
            "project", "steps", "case", "median", "fastest", "runs", "per step",
        ],
        &body,
    );
    let md = format!(
        "# dea-fit make: wall time\n\ndea-fit {}; --jobs {jobs}; budget {} s and at least {} runs per up-to-date case. Rerun: `dea-fit bench make`.\n\n\
         *generated*: a project of {} steps, each `dea-fit breakdown` of its own 20-coupon series with its report; *lab*: the shipped lab project ({}), copied without its outputs. \
         *from scratch*: the first make (every step runs; one run); *up to date*: make again, with its project page (nothing runs, nothing is written; the goal of issue 37 is ≤ 50 ms for 1 000 steps). \
         Each time is the wall clock of the whole `dea-fit make` process.\n\n\
         ![make](make.svg)\n\nAll rows: [make.csv](make.csv), [make.json](make.json).\n\n```\n{tab}```\n",
        env!("CARGO_PKG_VERSION"),
        a.budget,
        a.min_repeats,
        a.steps,
        a.lab.display()
    );
    atomic_write(&dir.join("make.md"), md.as_bytes())
}
