//! `dea-fit simulate`: run a scene; trajectory CSV, charts and summary.
//!
//! Status: `completed` (the whole span, every state and output finite), `breakdown`
//! (the largest true field in a layer over the run reaches the scene's breakdown
//! field: a result; exit 1 under `--strict`), `pull_in` (stopped at pull-in below
//! breakdown: a result; exit 1 under `--strict`), `failed` (integrator failure, step
//! budget, non-finite state or output, with the time: no result past it, exit 1
//! whatever `--strict` says; the partial trajectory is still written for
//! diagnosis). The run's own status stays in `integrator.status`.
//!
//! The trajectory is streamed to its CSV as the run reaches each sample (memory
//! does not grow with the sample count); the file appears when complete. The
//! charts are drawn from at most [`CHARTED`] of the samples, each with the min/max of
//! those it stands for. `--no-report` writes nothing but the `--out` file, if given.

use dea_fit::io::write::AtomicFile;
use dea_fit::report::simulation::{self, TrajectoryCsv};
use dea_fit::sim::{self, breakdown, integrate::Method, scene::Scene, RunOptions, RunStatus};
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// Simulate an actuator scene (TOML, see docs/scenes.md).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Trajectory CSV to write (default reports/sim-<scene>/trajectory.csv with the
    /// report; none with --no-report).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print the JSON summary on stdout.
    #[arg(long)]
    json: bool,
    /// Override the scene's relative tolerance.
    #[arg(long)]
    rtol: Option<f64>,
    /// Override the scene's integrator: bdf, esdirk34, tr-bdf2, tsit45, dp54 or dop853.
    #[arg(long, value_parser = parse_method)]
    method: Option<Method>,
    /// Also integrate the forward sensitivities to the material parameters: adds
    /// the derivatives of stretch, length, capacitance and current to every
    /// parameter as trajectory columns (dlength_d_C10_m_per_Pa, …), a chart, and the
    /// scaled sensitivities to the summary.
    #[arg(long)]
    sensitivities: bool,
    /// Report directory (default reports/sim-<scene>).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Do not write the report (charts, index.md) nor, without --out, the trajectory.
    #[arg(long)]
    no_report: bool,
    /// Exit with status 1 at pull-in or beyond breakdown too (a failed run always
    /// exits 1).
    #[arg(long)]
    strict: bool,
}

/// What the summary's `extremes` are taken over (`extremes_at_output_samples`:
/// the same at the output samples only, what the trajectory shows).
const EXTREMES_OVER: &str = "every accepted step of the integration and every output sample";

/// Most samples the charts draw (the report's memory and SVG size stay bounded).
const CHARTED: usize = 4000;

fn parse_method(s: &str) -> std::result::Result<Method, String> {
    Method::parse(s).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.map(Method::name).to_vec();
        format!("unknown integrator '{s}': use {}", names.join(", "))
    })
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let scene = Scene::read(&a.scene)?;
    if let Some(r) = a.rtol {
        if !(r > 0.0 && r < 0.1) {
            return Err(Error::settings(format!(
                "--rtol must be in (0, 0.1), found {r}"
            )));
        }
    }
    let dir = a
        .report
        .unwrap_or_else(|| PathBuf::from(format!("reports/sim-{}", scene.name)));
    super::refuse_in_report(
        (!a.no_report).then_some(&dir),
        &[("--out", a.out.as_deref())],
    )?;
    let csv = match (&a.out, a.no_report) {
        (Some(out), _) => Some(out.clone()),
        (None, false) => Some(dir.join("trajectory.csv")),
        (None, true) => None,
    };
    // Opened at the first sample, after the scene passed the guard: a refusal (of the
    // scene, or of the report directory) writes nothing.
    let mut writer: Option<TrajectoryCsv<AtomicFile>> = None;
    let meter = dea_fit::observe::Meter::new(
        &format!("simulate {}", scene.name),
        "samples",
        Some(scene.time.samples.len() as u64 + 1),
    );
    let mut sink = |row: &sim::Row| -> Result<()> {
        meter.inc(1);
        let Some(path) = &csv else { return Ok(()) };
        if writer.is_none() {
            if !a.no_report {
                super::claim_dir(&dir)?;
            }
            writer = Some(TrajectoryCsv::new(AtomicFile::create(path)?));
        }
        let w = writer.as_mut().expect("opened");
        w.row(row).map_err(|e| Error::io(path, e))
    };
    let t = std::time::Instant::now();
    let o = sim::simulate_streaming(
        &scene,
        &RunOptions {
            rtol: a.rtol,
            method: a.method,
            sensitivities: a.sensitivities,
            ..Default::default()
        },
        CHARTED,
        Some(&mut sink),
    )?;
    let run_time = t.elapsed().as_secs_f64();
    meter.finish();
    if let Some(w) = writer {
        let file = w.into_inner();
        match a.out {
            Some(_) => super::commit_noted(file)?,
            None => file.commit()?,
        }
    }
    let x = o.extremes();
    let check = breakdown::check(
        scene.breakdown.as_ref(),
        x.field,
        "the largest true field E = V/h(λ) over the run (every accepted step)",
    );
    // A film that breaks down ends the run whatever came after (a pull-in too).
    let status = match (o.integrator.status, check.exceeded) {
        (RunStatus::Failed, _) => "failed".to_string(),
        (_, true) => "breakdown".to_string(),
        (s, false) => s.to_string(),
    };
    let page = (!a.no_report)
        .then(|| simulation::write(&o, &a.scene.display().to_string(), &dir, &status, &check))
        .transpose()?;
    let last = o.samples.last().copied();
    let summary = serde_json::json!({
        "scene": o.scene,
        "status": status,
        "breakdown": serde_json::json!({
            "checked": check.checked,
            "field_max_V_per_m": check.peak.field,
            "at": check.peak,
            "taken_over": EXTREMES_OVER,
            "field_max_at_samples_V_per_m": o.extremes_at_samples().field.field,
            "breakdown_V_per_m": check.breakdown,
            "breakdown_std_error_V_per_m": check.std_error,
            "origin": check.origin,
            "source": check.source,
            "notes": check.notes,
            "margin": check.margin,
            "probability": check.probability,
            "exceeded": check.exceeded,
            "message": check.message,
        }),
        "events": o.events,
        "fidelity": o.fidelity,
        "axial_mode": o.mode,
        "integrator": o.integrator,
        "final": last.map(|s| serde_json::json!({
            "time_s": s.time_s, "voltage_V": s.voltage_v, "stretch": s.stretch,
            "length_m": s.length_m, "stroke_m": o.rest_length_m - s.length_m,
            "capacitance_F": s.capacitance_f, "current_A": s.current_a, "power_W": s.power_w,
        })),
        "extremes": x,
        "extremes_taken_over": EXTREMES_OVER,
        "extremes_at_output_samples": o.extremes_at_samples(),
        "rest": { "stretch": o.rest_stretch, "length_m": o.rest_length_m },
        "energy": o.energy,
        "tracking_rmse_pct": o.tracking_rmse_pct,
        "warnings": o.warnings,
        "sensitivities": o.sensitivities.as_ref().map(simulation::scaled_sensitivities),
        "run_time_s": run_time,
        "trajectory": csv,
    });
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).expect("serialisable")
        );
    } else {
        let head = format!(
            "{}: {} ({}), {} steps, stretch {:.5}…{:.5}, max power {}, max current {}, {} event(s) (extremes over every accepted step); {:.3} ms; trajectory {}\n",
            o.scene,
            o.fidelity.model,
            o.integrator.message,
            o.integrator.stats.steps,
            x.stretch_min,
            x.stretch_max,
            dea_fit::report::format::si(x.power_max_w, "W"),
            dea_fit::report::format::si(x.current_max_a, "A"),
            o.events.len(),
            run_time * 1e3,
            csv.as_ref()
                .map_or("not written (--no-report)".into(), |c| c
                    .display()
                    .to_string())
        );
        print!("{}", dea_fit::report::format::fit_width(&head));
        let mut said = format!("{}\n", check.message);
        for n in &check.notes {
            said.push_str(&format!("note: {n}\n"));
        }
        print!("{}", dea_fit::report::format::fit_width(&said));
        println!("status: {status}");
        for w in &o.warnings {
            print!(
                "{}",
                dea_fit::report::format::fit_width(&format!("warning: {w}\n"))
            );
        }
        if let Some(p) = &page {
            println!("report: {}", p.display());
        }
    }
    Ok(match status.as_str() {
        "completed" => 0,
        "failed" => 1,
        _ => i32::from(a.strict),
    })
}
