//! `dea-fit bench scale`: how each reader and estimator's time grows with the size of
//! its input. Times the tensile reader, reading + a Yeoh fit, `hyperelastic --model
//! auto` and `relaxation --terms auto` at growing row counts (half-decade steps), fits
//! the log-log slope of time against rows for each (1 = linear), and writes
//! `scale.{csv,json,svg,md}` under the output directory.
//!
//! Data: tensile rows generated from the Ogden-3 fit of Treloar's three modes (over
//! each mode's measured stretch range, 1 % relative noise, a third of the rows per
//! mode); relaxation curves from the seed's Table 3.3 series (log-spaced over
//! 0.01–1000 s, step to strain 0.5, 1 % noise), as `bench relaxation` uses.

use super::bench::{progress_bar, Verdict};
use dea_fit::bench::{measure, shipped_datasets, Budget, TRELOAR_ALL};
use dea_fit::data::Dataset;
use dea_fit::fit::hyperelastic::{self, Settings};
use dea_fit::fit::relaxation::{self, Loading};
use dea_fit::io::relaxation::{log_times, RelaxationData, RelaxationOptions, Synthetic};
use dea_fit::io::table::Table;
use dea_fit::io::tensile::{self, TensileOptions};
use dea_fit::io::write::atomic_write;
use dea_fit::material::hyperelastic::{Mode, ModelSpec, StrainEnergy};
use dea_fit::material::viscoelastic::preset;
use dea_fit::report::format::{si, table};
use dea_fit::units::CountRange;
use dea_fit::{Error, Result};
use rand::SeedableRng;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Rows of one timed size: a 10⁷-row table is some 400 MB in memory, the most a
/// 2-core bench machine should be asked to read.
const ROWS: CountRange = CountRange::new(10, 10_000_000, "rows of one timed size");

/// What `bench scale` measures.
#[derive(Debug, clap::Args)]
pub struct ScaleArgs {
    /// Fewest rows: the first size of every series.
    #[arg(long, default_value_t = 1000, value_parser = |s: &str| ROWS.parse(s))]
    min_rows: usize,
    /// Most rows read (the reader and reading + Yeoh fit).
    #[arg(long, default_value_t = 1_000_000, value_parser = |s: &str| ROWS.parse(s))]
    max_rows: usize,
    /// Most rows fitted by the automatic choices (`hyperelastic --model auto`,
    /// `relaxation --terms auto`).
    #[arg(long, default_value_t = 100_000, value_parser = |s: &str| ROWS.parse(s))]
    max_fit_rows: usize,
    /// Most rows fitted by `relaxation --terms auto` (its scaling to 10⁶ points is
    /// the point: issue 36, "Speed").
    #[arg(long, default_value_t = 1_000_000, value_parser = |s: &str| ROWS.parse(s))]
    max_relaxation_rows: usize,
    /// Seconds spent repeating each size (at least --min-repeats runs).
    #[arg(long, default_value_t = 0.5)]
    budget: f64,
    /// Fewest timed runs per size.
    #[arg(long, default_value_t = 3)]
    min_repeats: usize,
    /// Directory of the report.
    #[arg(long, default_value = "reports/bench")]
    out_dir: PathBuf,
    /// Directory holding treloar/ (the truth of the generated tensile data).
    #[arg(long, default_value = "datasets")]
    data_dir: PathBuf,
}

/// One timed size.
#[derive(Debug, Clone, Serialize)]
struct Row {
    estimator: &'static str,
    rows: usize,
    median_s: f64,
    min_s: f64,
    repeats: usize,
    /// Median seconds per row.
    per_row_s: f64,
    /// Peak resident memory of the process over this size's runs (MB), where the
    /// system tells ([`peak_memory`]).
    peak_rss_mb: Option<f64>,
}

/// Reset the process's peak resident memory to what it holds now (Linux: "5" into
/// `/proc/self/clear_refs`), so that [`peak_memory`] then reads the peak of what
/// runs after; false where that cannot be done.
fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The process's peak resident memory (MB) since [`reset_peak_memory`]: VmHWM of
/// `/proc/self/status`; None where the system does not tell.
fn peak_memory() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0 / 1e6)
}

/// The log-log slope of one estimator's times.
#[derive(Debug, Clone, Serialize)]
struct Slope {
    estimator: &'static str,
    /// d ln t / d ln n, least squares over the sizes (1: linear).
    slope: f64,
    sizes: usize,
}

#[derive(Serialize)]
struct Report<'a> {
    tool_version: &'static str,
    budget_s: f64,
    min_repeats: usize,
    slopes: &'a [Slope],
    rows: &'a [Row],
}

/// Row counts from `lo` to `hi` in half-decade steps (`hi` itself last).
fn sizes(lo: usize, hi: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut k = 0;
    loop {
        let n = (lo as f64 * 10f64.powf(k as f64 / 2.0)).round() as usize;
        if n >= hi {
            break;
        }
        out.push(n);
        k += 1;
    }
    out.push(hi);
    out
}

/// Least-squares slope of ln t against ln n (NaN with fewer than two sizes).
fn log_log_slope(pts: &[(usize, f64)]) -> f64 {
    let xy: Vec<(f64, f64)> = pts
        .iter()
        .map(|&(n, t)| ((n as f64).ln(), t.ln()))
        .collect();
    let m = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / m,
        xy.iter().map(|p| p.1).sum::<f64>() / m,
    );
    let sxy: f64 = xy.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xy.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// The generated tensile test: one CSV text per mode, `rows` in all.
struct Tensile {
    files: Vec<(Mode, String)>,
}

impl Tensile {
    fn new(
        model: &dyn StrainEnergy,
        p: &[f64],
        ranges: &[(Mode, f64, f64)],
        rows: usize,
    ) -> Result<Tensile> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1944);
        let mut files = Vec::new();
        for (i, &(mode, l0, l1)) in ranges.iter().enumerate() {
            // A share of the rows per mode; the first modes take the remainder.
            let count = (rows / ranges.len() + usize::from(i < rows % ranges.len())).max(2);
            let mut s = format!("# mode: {mode}\nstretch,nominal_stress_kPa\n");
            tensile::synthetic_rows(
                model,
                p,
                mode,
                (0..count).map(|j| l0 + (l1 - l0) * j as f64 / (count - 1) as f64),
                (0.01, 0.0),
                &mut rng,
                &mut s,
            )?;
            files.push((mode, s));
        }
        Ok(Tensile { files })
    }

    /// Read every file as `dea-fit hyperelastic` does.
    fn read(&self) -> Result<Dataset> {
        let mut data = Dataset::default();
        for (mode, text) in &self.files {
            let path = PathBuf::from(format!("scale-{mode}.csv"));
            let opts = TensileOptions {
                mode: Some(*mode),
                ..TensileOptions::default()
            };
            data.extend(tensile::from_table(
                &Table::parse(&path, text.as_bytes())?,
                &opts,
            )?);
        }
        Ok(data)
    }
}

fn relaxation_data(rows: usize) -> Result<RelaxationData> {
    let syn = Synthetic {
        prony: preset("elatrache2021-table-3.3")?.prony,
        strain: 0.5,
        ramp_time: None,
        times: log_times(0.01, 1000.0, rows, false),
        noise: 0.01,
        seed: 4910,
        record_strain: false,
    };
    let csv = syn.csv(&["dea-fit bench scale"])?;
    dea_fit::io::relaxation::from_table(
        &Table::parse(Path::new("scale-relaxation.csv"), csv.as_bytes())?,
        &RelaxationOptions::default(),
    )
}

/// Run the benchmark.
pub fn run(a: &ScaleArgs) -> Result<Verdict> {
    if a.min_rows < 10
        || a.max_rows <= a.min_rows
        || a.max_fit_rows <= a.min_rows
        || a.max_relaxation_rows <= a.min_rows
    {
        return Err(Error::settings(format!(
            "rows: expected 10 ≤ --min-rows ({}) < --max-rows ({}), --max-fit-rows ({}) and --max-relaxation-rows ({})",
            a.min_rows, a.max_rows, a.max_fit_rows, a.max_relaxation_rows
        ))
        .with_hint("e.g. --min-rows 1000 --max-rows 1000000 --max-fit-rows 100000 --max-relaxation-rows 1000000"));
    }
    let budget = Budget {
        min_repeats: a.min_repeats,
        seconds: a.budget,
        ..Budget::default()
    };
    budget.check()?;
    // The truth: Ogden-3 fitted to Treloar's three modes, over their stretch ranges.
    let sets = shipped_datasets(&a.data_dir)
        .map_err(|e| e.with_hint("run from the repository root or pass --data-dir"))?;
    let treloar = &sets
        .iter()
        .find(|d| d.name == TRELOAR_ALL)
        .ok_or_else(|| Error::settings("the shipped datasets hold no Treloar set"))?
        .data;
    let spec = ModelSpec::new("ogden3", Default::default());
    let truth = hyperelastic::fit(treloar, &spec, &Settings::default())?;
    let p: Vec<f64> = truth.parameters.iter().map(|q| q.value).collect();
    let model = spec.build()?;
    let ranges: Vec<(Mode, f64, f64)> = treloar
        .modes()
        .into_iter()
        .filter_map(|m| treloar.stretch_range(m).map(|(lo, hi)| (m, lo, hi)))
        .collect();

    let read_sizes = sizes(a.min_rows, a.max_rows);
    let fit_sizes = sizes(a.min_rows, a.max_fit_rows);
    let relaxation_sizes = sizes(a.min_rows, a.max_relaxation_rows);
    let bar = progress_bar(
        "scale",
        2 * read_sizes.len() + fit_sizes.len() + 2 * relaxation_sizes.len(),
    );
    let settings = Settings::default();
    let yeoh = ModelSpec::new("yeoh", Default::default());
    let mut verdict = Verdict::default();
    let mut rows: Vec<Row> = Vec::new();
    let mut push = |estimator: &'static str, n: usize, t: dea_fit::bench::Timing, peak| {
        bar.set_message(format!("{estimator} {n}: {}", si(t.median_s, "s")));
        bar.inc(1);
        rows.push(Row {
            estimator,
            rows: n,
            median_s: t.median_s,
            min_s: t.min_s,
            repeats: t.repeats,
            per_row_s: t.median_s / n as f64,
            peak_rss_mb: peak,
        });
    };
    // The peak memory of each size's runs: reset once its input is made, read
    // (and reset for the next runs) after them.
    let peak = || peak_memory().filter(|_| reset_peak_memory());
    for &n in &read_sizes {
        let data = Tensile::new(model.as_ref(), &p, &ranges, n)?;
        reset_peak_memory();
        let (t, _) = measure(&budget, || data.read())?;
        push("read", n, t, peak());
        let (t, fit) = measure(&budget, || {
            hyperelastic::fit(&data.read()?, &yeoh, &settings)
        })?;
        verdict.add(format!("read+yeoh {n} rows"), fit.status);
        push("read+yeoh", n, t, peak());
    }
    for &n in &fit_sizes {
        let data = Tensile::new(model.as_ref(), &p, &ranges, n)?.read()?;
        reset_peak_memory();
        let (t, (fit, _)) = measure(&budget, || hyperelastic::fit_auto(&data, &settings))?;
        verdict.add(format!("hyperelastic auto {n} rows"), fit.status);
        push("hyperelastic-auto", n, t, peak());
    }
    for &n in &relaxation_sizes {
        let data = relaxation_data(n)?;
        let loading = Loading {
            strain: Some(0.5),
            ramp_time: None,
        };
        let rs = relaxation::Settings::default();
        reset_peak_memory();
        let (t, fit) = measure(&budget, || relaxation::fit(&data, &loading, None, &rs))?;
        verdict.add(format!("relaxation auto {n} rows"), fit.status);
        push("relaxation-auto", n, t, peak());
        // what `relaxation` writes after the fit: the charts of every point, the page
        // (into a scratch folder, removed after: a report also lists itself in the
        // folder above it)
        let scratch =
            std::env::temp_dir().join(format!("dea-fit-bench-scale-{}", std::process::id()));
        let dir = scratch.join("relaxation-report");
        reset_peak_memory();
        let (t, _) = measure(&budget, || {
            dea_fit::report::relaxation::write(&fit, &data, None, &dir)
        })?;
        push("relaxation-report", n, t, peak());
        std::fs::remove_dir_all(&scratch).map_err(|e| Error::io(&scratch, e))?;
    }
    bar.finish();

    let names = [
        "read",
        "read+yeoh",
        "hyperelastic-auto",
        "relaxation-auto",
        "relaxation-report",
    ];
    let slopes: Vec<Slope> = names
        .iter()
        .map(|&e| {
            let pts: Vec<(usize, f64)> = rows
                .iter()
                .filter(|r| r.estimator == e)
                .map(|r| (r.rows, r.median_s))
                .collect();
            Slope {
                estimator: e,
                slope: log_log_slope(&pts),
                sizes: pts.len(),
            }
        })
        .collect();
    write(a, &rows, &slopes)?;
    for s in &slopes {
        println!(
            "{:<18} slope {:.2} over {} sizes",
            s.estimator, s.slope, s.sizes
        );
    }
    println!("report: {}", a.out_dir.join("scale.md").display());
    Ok(verdict)
}

fn write(a: &ScaleArgs, rows: &[Row], slopes: &[Slope]) -> Result<()> {
    let dir = &a.out_dir;
    super::claim_dir(dir)?;
    let io = |e: String| Error::settings(format!("could not write the bench report: {e}"));
    super::bench::write_csv(&dir.join("scale.csv"), rows)?;
    let report = Report {
        tool_version: env!("CARGO_PKG_VERSION"),
        budget_s: a.budget,
        min_repeats: a.min_repeats,
        slopes,
        rows,
    };
    let json = serde_json::to_string_pretty(&report).map_err(|e| io(e.to_string()))?;
    atomic_write(&dir.join("scale.json"), json.as_bytes())?;
    let groups = slopes
        .iter()
        .map(|s| {
            let points = rows.iter().filter(|r| r.estimator == s.estimator);
            let points = points.map(|r| (r.rows as f64, r.median_s)).collect();
            (format!("{} (slope {:.2})", s.estimator, s.slope), points)
        })
        .collect();
    super::bench::loglog_times(
        "time against input size (log-log; slope 1 = linear)",
        "log₁₀ rows",
        groups,
    )
    .write_svg(&dir.join("scale.svg"))?;
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let head = [r.estimator.to_string(), r.rows.to_string()];
            let times = super::bench::time_cells(r.median_s, r.min_s, r.repeats, r.per_row_s);
            let peak = r.peak_rss_mb.map_or("–".into(), |mb| format!("{mb:.0} MB"));
            head.into_iter().chain(times).chain([peak]).collect()
        })
        .collect();
    let tab = table(
        &[
            "estimator",
            "rows",
            "median",
            "fastest",
            "runs",
            "per row",
            "peak memory",
        ],
        &body,
    );
    let slope_tab = table(
        &["estimator", "log-log slope", "sizes"],
        &slopes
            .iter()
            .map(|s| {
                vec![
                    s.estimator.to_string(),
                    format!("{:.2}", s.slope),
                    s.sizes.to_string(),
                ]
            })
            .collect::<Vec<_>>(),
    );
    let md = format!(
        "# Time against input size\n\ndea-fit {}; budget {} s and at least {} runs per size. Rerun: `dea-fit bench scale`.\n\n\
         Each estimator is timed at growing row counts (half-decade steps); the slope of ln t against ln n, fitted by least squares, is 1 when the cost grows linearly. \
         *read*: the tensile reader (CSV text in memory → samples); *read+yeoh*: reading and the whole Yeoh fit call; *hyperelastic-auto*: `hyperelastic --model auto` on the samples; \
         *relaxation-auto*: `relaxation --terms auto`; *relaxation-report*: the report it writes after (charts of every point, the page). Peak memory: the process's resident high-water mark over each size's runs, its input included (Linux only). Tensile data: the Ogden-3 fit of Treloar's three modes, 1 % noise; relaxation: the Table 3.3 series of El Atrache Ceballos (2021), 1 % noise.\n\n\
         ![scale](scale.svg)\n\n```\n{slope_tab}```\n\nAll rows: [scale.csv](scale.csv), [scale.json](scale.json).\n\n```\n{tab}```\n",
        env!("CARGO_PKG_VERSION"),
        a.budget,
        a.min_repeats
    );
    atomic_write(&dir.join("scale.md"), md.as_bytes())
}
