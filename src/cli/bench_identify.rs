//! `dea-fit bench identify`: time against parameter error of the identification of
//! a rig-log-sized trace (datasets/scenes/stack_rig_7s.toml: 7 s, 3500 samples of
//! contraction and capacitance, 9 free constants), over the drive (in closed form,
//! or measured as a rig logs it), simulator tolerances and start counts. Writes
//! `reports/bench/identify.{csv,svg,md}`.

use dea_fit::bench::{identify_rows, Drive};
use dea_fit::fit::{permittivity::worst, Status};
use dea_fit::io::write::atomic_write;
use dea_fit::report::format::table;
use dea_fit::report::page::{code, link, text, Page};
use dea_fit::report::plot::{Chart, Series, Style};
use dea_fit::report::runs::Run;
use dea_fit::sim::scene::Scene;
use dea_fit::Result;
use std::fmt::Write as _;
use std::path::Path;

/// Run the benchmark.
pub fn run(scene: &Path) -> Result<super::bench::Verdict> {
    let s = Scene::read(scene)?;
    let rtols = [1e-4, 1e-6];
    let starts = [1, 8];
    let drives = [Drive::ClosedForm, Drive::Measured];
    let bar = super::bench::progress_bar("identify", drives.len() * rtols.len() * starts.len());
    let rows = identify_rows(&s, &drives, &rtols, &starts, 1, &mut |r| {
        bar.set_message(format!(
            "{} drive, rtol {:e}, {} starts: {:.3} s",
            r.drive, r.rtol, r.starts, r.seconds
        ));
        bar.inc(1);
    })?;
    bar.finish();
    let mut csv = String::from("drive,rtol,starts,seconds,per_start_s,interval_s,max_rel_error,max_z,identified,free,starts_at_best,iterations,simulator_runs,status\n");
    let mut verdict = super::bench::Verdict::default();
    let mut table_rows = Vec::new();
    let mut series: Vec<Series> = Vec::new();
    for (i, (&d, &n)) in drives
        .iter()
        .flat_map(|d| starts.iter().map(move |n| (d, n)))
        .enumerate()
    {
        series.push(Series {
            label: format!("{d} drive, {n} start(s), rtol 1e-4 and 1e-6"),
            points: rows
                .iter()
                .filter(|r| r.starts == n && r.drive == d)
                .map(|r| (r.seconds, r.max_rel_error.max(1e-16).log10()))
                .collect(),
            color: i,
            style: Style::Line,
        });
    }
    for r in &rows {
        let _ = writeln!(
            csv,
            "{},{:e},{},{:e},{:e},{:e},{:e},{:e},{},{},{},{},{},{}",
            r.drive,
            r.rtol,
            r.starts,
            r.seconds,
            r.per_start_s,
            r.interval_s,
            r.max_rel_error,
            r.max_z,
            r.identified,
            r.free,
            r.starts_at_best,
            r.iterations,
            r.simulator_runs,
            r.status
        );
        verdict.add(
            format!("{} drive, rtol {:e}, {} starts", r.drive, r.rtol, r.starts),
            r.status,
        );
        table_rows.push(vec![
            r.drive.to_string(),
            format!("{:e}", r.rtol),
            r.starts.to_string(),
            format!("{:.3}", r.seconds),
            format!("{:.3}", r.per_start_s),
            format!("{:.3}", r.interval_s),
            format!("{:.2e}", r.max_rel_error),
            format!("{:.2}", r.max_z),
            format!("{}/{}", r.identified, r.free),
            r.starts_at_best.to_string(),
            r.simulator_runs.to_string(),
            r.status.to_string(),
        ]);
    }
    let dir = Path::new("reports").join("bench");
    super::claim_dir(&dir)?;
    atomic_write(&dir.join("identify.csv"), csv.as_bytes())?;
    let chart = Chart {
        title: "identification of a 7 s, 3500-sample trace, 9 constants: error vs time".into(),
        x_label: "wall time".into(),
        y_label: "log10 max |Δθ/θ| (identifiable constants)".into(),
        series,
        log_x: true,
        x_unit: Some("s".into()),
        y_unit: None,
    };
    let header = [
        "drive",
        "rtol",
        "starts",
        "time [s]",
        "per start [s]",
        "intervals [s]",
        "max |Δθ/θ|",
        "max |Δθ|/σ",
        "identified",
        "at best",
        "sim runs",
        "status",
    ];
    let tab = table(&header, &table_rows);
    let status = rows.iter().fold(Status::Ok, |s, r| worst(s, r.status));
    let mut page = Page::new("Identification: time against parameter error");
    page.para(vec![
        text("Scene "),
        code(scene.display().to_string()),
        text(" simulated at its constants, 1 % contraction and 0.1 % capacitance noise (seed 10); the search starts 20 % above every constant. The drive is the scene's input in closed form, or the actuator voltage as a rig logs it (0.1 % noise, seed 11) fitted as a measured input, as `identify` does with a trace file. Time: one whole identification (multi-start, σ re-estimation, polish, assessment) on this machine; of it, the interval stage (covariance, profile checks and profile intervals) in its own column. Rerun: "),
        code("dea-fit bench identify"),
        text(". All rows: "),
        link("identify.csv", "identify.csv"),
        text("."),
    ]);
    page.status_line(status, status);
    page.chart(&dir, "identify.svg", "error vs time", &chart)?;
    page.table(&header, table_rows);
    let fastest = rows
        .iter()
        .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
        .map(|r| {
            format!(
                "fastest {:.3} s ({} drive, rtol {:e}, {} start(s)), max |Δθ/θ| {:.2e}",
                r.seconds, r.drive, r.rtol, r.starts, r.max_rel_error
            )
        });
    let run = Run::new(
        "bench identify",
        scene.display().to_string(),
        s.name.clone(),
    )
    .headline(fastest.into_iter().collect());
    let html = page.write(&dir, "identify", run)?;
    print!("{tab}");
    println!("report: {}", html.display());
    Ok(verdict)
}
