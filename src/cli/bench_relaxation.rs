//! `dea-fit bench relaxation`: term count and method (grid NNLS only vs refined)
//! against error and time, on a synthetic curve made from the seed's Table 3.3 preset
//! (200 log-spaced points over 0.01–1000 s, step to strain 0.5, 1 % relative noise,
//! seed 4910). Writes `reports/bench/relaxation.{csv,svg,md}` and
//! `reports/bench/relaxation-time.svg`.

use dea_fit::fit::relaxation::{self, Loading, Method, Settings};
use dea_fit::fit::{permittivity::worst, Status};
use dea_fit::io::relaxation::{from_table, log_times, RelaxationOptions, Synthetic};
use dea_fit::io::table::Table;
use dea_fit::io::write::atomic_write;
use dea_fit::material::viscoelastic::preset;
use dea_fit::report::format::table;
use dea_fit::report::page::{code, link, text, Page};
use dea_fit::report::plot::{Chart, Series, Style};
use dea_fit::report::runs::Run;
use dea_fit::Result;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Repetitions per configuration; the fastest is reported (least disturbed by other
/// processes on a shared machine).
const REPS: usize = 15;

/// Run the benchmark.
pub fn run() -> Result<super::bench::Verdict> {
    let mut verdict = super::bench::Verdict::default();
    let mut status = Status::Ok;
    let truth = preset("elatrache2021-table-3.3")?.prony;
    let syn = Synthetic {
        prony: truth.clone(),
        strain: 0.5,
        ramp_time: None,
        times: log_times(0.01, 1000.0, 200, false),
        noise: 0.01,
        seed: 4910,
        record_strain: false,
    };
    let csv = syn.csv(&["dea-fit bench relaxation"])?;
    let data = from_table(
        &Table::parse(Path::new("bench-relaxation.csv"), csv.as_bytes())?,
        &RelaxationOptions::default(),
    )?;
    let loading = Loading {
        strain: Some(0.5),
        ramp_time: None,
    };
    // Error of the relaxation modulus against the truth over the sampled window.
    let check: Vec<f64> = log_times(0.01, 1000.0, 101, false);
    let mut rows = Vec::new();
    let mut csv_out = String::from("method,terms,seconds,rel_rmse,max_modulus_error\n");
    let mut err_series = vec![Vec::new(), Vec::new()];
    let mut time_series = vec![Vec::new(), Vec::new()];
    for (mi, method) in [Method::Grid, Method::Refined].into_iter().enumerate() {
        for terms in 1..=6 {
            let settings = Settings {
                terms: Some(terms),
                method,
                ..Settings::default()
            };
            let mut best = f64::INFINITY;
            let mut fit = None;
            for _ in 0..REPS {
                let t0 = Instant::now();
                let f = relaxation::fit(&data, &loading, None, &settings)?;
                best = best.min(t0.elapsed().as_secs_f64());
                fit = Some(f);
            }
            let fit = fit.expect("REPS > 0");
            let p = fit.prony_series()?;
            let err = check
                .iter()
                .map(|&t| {
                    let e = truth.relaxation_modulus(t);
                    ((p.relaxation_modulus(t) - e) / e).abs()
                })
                .fold(0.0, f64::max);
            let name = ["grid", "refined"][mi].to_string();
            verdict.add(format!("{name} {terms} terms"), fit.status);
            status = worst(status, fit.status);
            let _ = writeln!(
                csv_out,
                "{name},{terms},{best:.6e},{:.6e},{err:.6e}",
                fit.rel_rmse
            );
            rows.push(vec![
                name,
                terms.to_string(),
                format!("{:.3}", best * 1e3),
                format!("{:.3}", 100.0 * fit.rel_rmse),
                format!("{:.3}", 100.0 * err),
                fit.status.to_string(),
            ]);
            err_series[mi].push((terms as f64, 100.0 * err));
            time_series[mi].push((terms as f64, best));
        }
    }
    let dir = Path::new("reports").join("bench");
    super::claim_dir(&dir)?;
    atomic_write(&dir.join("relaxation.csv"), csv_out.as_bytes())?;
    let labels = ["grid NNLS only", "grid NNLS + LM refinement"];
    let series = |data: &[Vec<(f64, f64)>]| -> Vec<Series> {
        data.iter()
            .enumerate()
            .map(|(i, pts)| Series {
                label: labels[i].into(),
                points: pts.clone(),
                color: i,
                style: Style::Line,
            })
            .collect()
    };
    let error_chart = Chart {
        title: "Table 3.3 curve: max |ΔE/E| over 0.01–1000 s vs terms".into(),
        x_label: "Prony terms".into(),
        y_label: "max relative modulus error [%]".into(),
        series: series(&err_series),
        log_x: false,
        x_unit: None,
        y_unit: None,
    };
    let time_chart = Chart {
        title: "fit time (200 points, fastest of 15) vs terms".into(),
        x_label: "Prony terms".into(),
        y_label: "time".into(),
        series: series(&time_series),
        log_x: false,
        x_unit: None,
        y_unit: Some("s".into()),
    };
    let header = [
        "method",
        "terms",
        "time [ms]",
        "rel. RMSE [%]",
        "max |ΔE/E| [%]",
        "status",
    ];
    let tab = table(&header, &rows);
    let mut page = Page::new("Relaxation estimator: terms and method against error and time");
    page.para(vec![
        text(format!("Data: El Atrache Ceballos (2021) Table 3.3 (E0 = 222 kPa) as a step to strain 0.5, 200 log-spaced points over 0.01–1000 s, 1 % relative noise (seed 4910). Time: fastest of {REPS} runs, single fit with the given term count. Rerun: ")),
        code("dea-fit bench relaxation"),
        text(". All rows: "),
        link("relaxation.csv", "relaxation.csv"),
        text("."),
    ]);
    page.status_line(status, status);
    page.chart(&dir, "relaxation.svg", "error", &error_chart)?;
    page.chart(&dir, "relaxation-time.svg", "time", &time_chart)?;
    page.table(&header, rows);
    let run = Run::new(
        "bench relaxation",
        "synthetic: El Atrache Ceballos (2021) Table 3.3",
        "Prony, 1–6 terms",
    );
    let html = page.write(&dir, "relaxation", run)?;
    print!("{tab}");
    println!("report: {}", html.display());
    Ok(verdict)
}
