//! `dea-fit bench rank`: candidate evaluations per second of `dea-fit rank` (static
//! curve, pull-in, breakdown and a damped step each) on the shipped design, against
//! the sweep's size and the number of threads. Writes
//! reports/bench-rank/{results.csv, throughput.svg}.

use dea_fit::io::write::atomic_write;
use dea_fit::rank::figures::State;
use dea_fit::rank::manifest;
use dea_fit::rank::sweep::{self, Sweep};
use dea_fit::report::plot::{Chart, Series, Style};
use dea_fit::{Error, Result};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// What `bench rank` measures.
#[derive(Debug, clap::Args)]
pub struct RankArgs {
    /// The design to sweep.
    #[arg(long, default_value = "datasets/design/silicone_fillers.toml")]
    design: PathBuf,
    /// Loadings per series of each sweep (×10 drive voltages, 600 V–1 kV).
    #[arg(long, value_delimiter = ',', default_value = "6,25,100,400")]
    loadings: Vec<usize>,
    /// Directory of the report.
    #[arg(long, default_value = "reports/bench-rank")]
    out_dir: PathBuf,
}

/// CPU time of the process so far (s): user + system, all threads.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes into the zeroed struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return f64::NAN;
    }
    let t = |v: libc::timeval| v.tv_sec as f64 + 1e-6 * v.tv_usec as f64;
    t(u.ru_utime) + t(u.ru_stime)
}

/// Run the benchmark.
pub fn run(a: &RankArgs) -> Result<super::bench::Verdict> {
    if a.loadings.is_empty() || a.loadings.contains(&0) {
        return Err(Error::settings(
            "--loadings: give counts of 1 or more, e.g. 6,25,100,400",
        ));
    }
    let d = manifest::read(&a.design)?;
    super::claim_dir(&a.out_dir)?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads: Vec<usize> = match cores {
        1 => vec![1],
        n => vec![1, n],
    };
    let mut verdict = super::bench::Verdict::default();
    let mut csv = String::from(
        "points,threads,wall_s,cpu_s,evaluations_per_s,evaluations_per_cpu_s,failed\n",
    );
    let mut series: Vec<Series> = Vec::new();
    println!(
        "dea-fit bench rank: {} on {cores} core(s)",
        a.design.display()
    );
    println!(
        "{:>8} {:>8} {:>10} {:>10} {:>12} {:>14}",
        "points", "threads", "wall (s)", "CPU (s)", "evals/s", "evals/CPU-s"
    );
    for (k, &t) in threads.iter().enumerate() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map_err(|e| Error::settings(format!("no thread pool of {t}: {e}")))?;
        let mut pts_line = Vec::new();
        for &l in &a.loadings {
            let sw = Sweep::parse(&[format!("loading=0:0.4:{l}"), "voltage=600V:1kV:10".into()])?;
            let points = sweep::Points::new(&d, &sw)?;
            let (c0, t0) = (cpu_seconds(), Instant::now());
            let ev = pool.install(|| sweep::run_all(&d, &points, None, &|| {}))?;
            let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
            let failed = ev
                .iter()
                .filter(|e| e.evaluation.state == State::Failed)
                .count();
            if failed > 0 {
                verdict.failed.push(format!(
                    "{} points on {t} thread(s): {failed} evaluation(s) failed",
                    points.len()
                ));
            }
            let n = points.len() as f64;
            let _ = writeln!(
                csv,
                "{},{t},{wall:e},{cpu:e},{:e},{:e},{failed}",
                points.len(),
                n / wall,
                n / cpu
            );
            println!(
                "{:>8} {t:>8} {wall:>10.3} {cpu:>10.3} {:>12.0} {:>14.0}",
                points.len(),
                n / wall,
                n / cpu
            );
            pts_line.push((n, n / wall));
        }
        series.push(Series {
            label: format!("{t} thread(s), wall clock"),
            points: pts_line,
            color: k,
            style: Style::Line,
        });
    }
    Chart {
        title: "rank: candidate evaluations per second against the sweep's size".into(),
        x_label: "points of the sweep".into(),
        y_label: "evaluations per second".into(),
        series,
        log_x: true,
        x_unit: None,
        y_unit: None,
    }
    .write_svg(&a.out_dir.join("throughput.svg"))?;
    let path = a.out_dir.join("results.csv");
    atomic_write(&path, csv.as_bytes())?;
    println!("wrote {} and throughput.svg", path.display());
    Ok(verdict)
}
