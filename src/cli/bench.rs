//! `dea-fit bench <what>`: speed against accuracy, written as CSV, SVG and Markdown
//! under `reports/bench/`. One subcommand per estimator.

use dea_fit::bench::{self, Budget, HyperPlan};
use dea_fit::report;
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// Measure speed against accuracy.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
    /// Exit with status 1 when a measured case ended in a blocking status (a fit
    /// `ill_posed`, `unstable` or `not_converged`, a run at `pull_in`); a run that
    /// failed exits 1 with or without it.
    #[arg(long, global = true)]
    strict: bool,
}

#[derive(Debug, clap::Subcommand)]
enum What {
    /// The hyperelastic estimator: every model on the shipped data; for Ogden-3 on
    /// Treloar's three modes, multi-start points and LM tolerance against objective
    /// and time, and variable projection against full LM.
    Hyperelastic(HyperArgs),
    /// The relaxation estimator: term count and method (grid NNLS only vs refined)
    /// against error and time.
    Relaxation,
    /// The simulator: error against run time over tolerances, integrators and
    /// fidelity levels for the scenes of El Atrache Ceballos (2021).
    Simulate(SimArgs),
    /// Every integrator and `auto` on every shipped scene and over damping ratios
    /// 10⁻⁴…10: auto's time as a ratio to the best method's.
    Integrators(SimArgs),
    /// Identification from a rig-log-sized trace: parameter error against time over
    /// simulator tolerances and start counts.
    Identify(IdentifyArgs),
    /// Ranking: candidate evaluations per second against sweep size and threads.
    Rank(super::bench_rank::RankArgs),
    /// Growth with input size: each reader and estimator timed at growing row counts,
    /// with the log-log slope of time against rows (1 = linear).
    Scale(super::bench_scale::ScaleArgs),
    /// `dea-fit make`: a generated project of 1 000 steps and the lab project, from
    /// scratch and up to date (wall time of the whole process).
    Make(super::bench_make::MakeArgs),
}

#[derive(Debug, clap::Args)]
struct IdentifyArgs {
    /// The scene whose simulated trace is identified.
    #[arg(long, default_value = "datasets/scenes/stack_rig_7s.toml")]
    scene: PathBuf,
}

#[derive(Debug, clap::Args)]
struct SimArgs {
    /// Directory of the scenes to run.
    #[arg(long, default_value = "datasets/scenes")]
    scenes: PathBuf,
}

/// Options every bench takes.
#[derive(Debug, clap::Args)]
struct Common {
    /// Directory of the report.
    #[arg(long, default_value = "reports/bench")]
    out_dir: PathBuf,
    /// Seconds spent repeating each case (at least --min-repeats runs).
    #[arg(long, default_value_t = 0.2)]
    budget: f64,
    /// Fewest timed runs per case.
    #[arg(long, default_value_t = 5)]
    min_repeats: usize,
}

impl Common {
    fn budget(&self) -> Result<Budget> {
        let b = Budget {
            min_repeats: self.min_repeats,
            seconds: self.budget,
            ..Budget::default()
        };
        b.check()?;
        Ok(b)
    }
}

#[derive(Debug, clap::Args)]
struct HyperArgs {
    #[command(flatten)]
    common: Common,
    /// Directory holding vhb4910/ and treloar/ (the shipped datasets).
    #[arg(long, default_value = "datasets")]
    data_dir: PathBuf,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let verdict = match a.what {
        What::Hyperelastic(h) => hyperelastic(h)?,
        What::Relaxation => super::bench_relaxation::run()?,
        What::Simulate(s) => super::bench_simulate::run(&s.scenes)?,
        What::Integrators(s) => super::bench_integrators::run(&s.scenes)?,
        What::Identify(i) => super::bench_identify::run(&i.scene)?,
        What::Rank(r) => super::bench_rank::run(&r)?,
        What::Scale(s) => super::bench_scale::run(&s)?,
        What::Make(m) => super::bench_make::run(&m)?,
    };
    Ok(verdict.report(a.strict))
}

/// What a bench found besides its measurements: the cases that ended in a blocking
/// status and those that failed (no result), each described for the summary.
#[derive(Debug, Default)]
pub struct Verdict {
    /// Cases with a blocking status (`case: status`).
    pub blocking: Vec<String>,
    /// Cases that failed.
    pub failed: Vec<String>,
}

impl Verdict {
    /// Count a case by its status.
    pub fn add(&mut self, case: String, status: dea_fit::fit::Status) {
        match status {
            dea_fit::fit::Status::Failed => self.failed.push(format!("{case}: {status}")),
            s if s.is_blocking() => self.blocking.push(format!("{case}: {s}")),
            _ => {}
        }
    }

    /// Print the `status:` line (and each blocking or failed case) and return the exit
    /// status: 1 when a case failed, or under `--strict` when one is blocking.
    fn report(&self, strict: bool) -> i32 {
        let (status, code) = match (self.failed.is_empty(), self.blocking.is_empty()) {
            (false, _) => ("failed", 1),
            (true, false) => ("blocking", i32::from(strict)),
            (true, true) => ("ok", 0),
        };
        let cases = self.failed.len() + self.blocking.len();
        match cases {
            0 => println!("status: {status}"),
            n => println!("status: {status} ({n} case(s) without a usable result; the measurements are written)"),
        }
        for c in self.failed.iter().chain(&self.blocking) {
            println!("  {c}");
        }
        code
    }
}

/// A chart of median wall time against size, both log₁₀ (slope 1: linear): one
/// line per group, each (label, [(size, median seconds)]), as `bench scale` and
/// `bench make` draw them.
pub fn loglog_times(
    title: &str,
    x_label: &str,
    groups: Vec<(String, Vec<(f64, f64)>)>,
) -> dea_fit::report::plot::Chart {
    use dea_fit::report::plot::{Chart, Series, Style};
    Chart {
        title: title.into(),
        x_label: x_label.into(),
        y_label: "log₁₀ median time [s]".into(),
        series: groups
            .into_iter()
            .enumerate()
            .map(|(i, (label, points))| Series {
                label,
                points: points
                    .into_iter()
                    .map(|(size, s)| (size.log10(), s.log10()))
                    .collect(),
                color: i,
                style: Style::Line,
            })
            .collect(),
        log_x: false,
        x_unit: None,
        y_unit: None,
    }
}

/// Write `rows` as CSV to `path` (atomically), one line per row with a header.
pub fn write_csv<T: serde::Serialize>(path: &std::path::Path, rows: &[T]) -> Result<()> {
    let io = |e: String| Error::settings(format!("could not write the bench report: {e}"));
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|e| io(e.to_string()))?;
    }
    let csv = w.into_inner().map_err(|e| io(e.to_string()))?;
    dea_fit::io::write::atomic_write(path, &csv)
}

/// The timing cells of a `bench scale` or `bench make` table row: median,
/// fastest, runs, and the median per unit of size (a row, a step).
pub fn time_cells(median_s: f64, min_s: f64, repeats: usize, per_unit_s: f64) -> [String; 4] {
    use dea_fit::report::format::si;
    [
        si(median_s, "s"),
        si(min_s, "s"),
        repeats.to_string(),
        si(per_unit_s, "s"),
    ]
}

/// The progress of `bench <what>` over `len` cases ([`dea_fit::observe::Meter`]).
pub fn progress_bar(what: &str, len: usize) -> dea_fit::observe::Meter {
    dea_fit::observe::Meter::new(&format!("bench {what}"), "cases", Some(len as u64))
}

fn hyperelastic(a: HyperArgs) -> Result<Verdict> {
    let budget = a.common.budget()?;
    if !a.data_dir.join("vhb4910").is_dir() || !a.data_dir.join("treloar").is_dir() {
        return Err(Error::settings(format!(
            "{} does not hold the shipped datasets vhb4910/ and treloar/",
            a.data_dir.display()
        ))
        .with_hint("run from the repository root or pass --data-dir path/to/datasets"));
    }
    let data = bench::shipped_datasets(&a.data_dir)?;
    let plan = HyperPlan::standard(data, budget)?;
    let bar = progress_bar("hyperelastic", plan.cases.len());
    let rows = plan.run(&mut |r| {
        bar.set_message(format!(
            "{} {} {} {}",
            r.dataset, r.model, r.setting, r.value
        ));
        bar.inc(1);
    });
    bar.finish();
    let rows = rows?;
    let note = format!(
        "dea-fit {}; budget {} s and at least {} runs per case; {} cases. Rerun: dea-fit bench hyperelastic.",
        env!("CARGO_PKG_VERSION"),
        budget.seconds,
        budget.min_repeats,
        rows.len()
    );
    super::claim_dir(&a.common.out_dir)?;
    let page = report::bench::write_hyperelastic(&rows, &note, &a.common.out_dir)
        .map_err(|e: Error| e.with_hint("check that --out-dir is writable"))?;
    for h in report::bench::headline(&rows) {
        println!("{h}");
    }
    println!("report: {}", page.display());
    let mut verdict = Verdict::default();
    for r in &rows {
        verdict.add(
            format!("{} {} {}={}", r.dataset, r.model, r.setting, r.value),
            r.status,
        );
    }
    Ok(verdict)
}

#[cfg(test)]
mod tests {
    use super::Verdict;
    use dea_fit::fit::Status;

    /// The exit status follows the README: a failed case exits 1 always, a blocking
    /// one only under --strict, `warning` never.
    #[test]
    fn verdict_exit_codes() {
        let mut v = Verdict::default();
        v.add("a".into(), Status::Ok);
        v.add("b".into(), Status::Warning);
        assert_eq!((v.report(false), v.report(true)), (0, 0));
        v.add("c".into(), Status::IllPosed);
        assert_eq!((v.report(false), v.report(true)), (0, 1));
        v.add("d".into(), Status::Failed);
        assert_eq!((v.report(false), v.report(true)), (1, 1));
        assert_eq!(v.blocking, ["c: ill_posed"]);
        assert_eq!(v.failed, ["d: failed"]);
    }
}
