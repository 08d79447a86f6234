//! `dea-fit simulate`: run a scene; trajectory CSV, charts and summary.
//!
//! Status: `completed` (the whole span, every state and output finite), `pull_in`
//! (stopped at pull-in: a result; exit 1 under `--strict`), `failed` (integrator
//! failure, step budget, non-finite state or output, with the time: no result past
//! it, exit 1 whatever `--strict` says; the partial trajectory is still written for
//! diagnosis).

use dea_fit::report::simulation;
use dea_fit::sim::{self, integrate::Method, scene::Scene, RunOptions, RunStatus};
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// Simulate an actuator scene (TOML, see docs/scenes.md).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Trajectory CSV to write (default reports/sim-<scene>/trajectory.csv).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print the JSON summary on stdout.
    #[arg(long)]
    json: bool,
    /// Override the scene's relative tolerance.
    #[arg(long)]
    rtol: Option<f64>,
    /// Override the scene's integrator: bdf, esdirk34, tr-bdf2, tsit45 or dp54.
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
    /// Do not write the report (charts, index.md).
    #[arg(long)]
    no_report: bool,
    /// Exit with status 1 at pull-in too (a failed run always exits 1).
    #[arg(long)]
    strict: bool,
}

fn parse_method(s: &str) -> std::result::Result<Method, String> {
    Method::parse(s).ok_or_else(|| {
        format!("unknown integrator '{s}': use bdf, esdirk34, tr-bdf2, tsit45 or dp54")
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
    let t = std::time::Instant::now();
    let o = sim::simulate(
        &scene,
        &RunOptions {
            rtol: a.rtol,
            method: a.method,
            sensitivities: a.sensitivities,
            ..Default::default()
        },
    )?;
    let run_time = t.elapsed().as_secs_f64();
    let dir = a
        .report
        .unwrap_or_else(|| PathBuf::from(format!("reports/sim-{}", scene.name)));
    // Claim the report directory before writing anything, so that a refusal
    // writes nothing.
    if !a.no_report || a.out.is_none() {
        super::claim_dir(&dir)?;
    }
    let trajectory = simulation::trajectory_csv(&o);
    let csv = match a.out {
        Some(out) => {
            super::write_noted(&out, trajectory.as_bytes())?;
            out
        }
        None => {
            let csv = dir.join("trajectory.csv");
            dea_fit::io::write::atomic_write(&csv, trajectory.as_bytes())?;
            csv
        }
    };
    let page = (!a.no_report)
        .then(|| simulation::write(&o, &a.scene.display().to_string(), &dir))
        .transpose()?;
    let last = o.samples.last().copied();
    let summary = serde_json::json!({
        "scene": o.scene,
        "status": o.integrator.status,
        "events": o.events,
        "fidelity": o.fidelity,
        "axial_mode": o.mode,
        "integrator": o.integrator,
        "final": last.map(|s| serde_json::json!({
            "time_s": s.time_s, "voltage_V": s.voltage_v, "stretch": s.stretch,
            "length_m": s.length_m, "stroke_m": o.rest_length_m - s.length_m,
            "capacitance_F": s.capacitance_f, "current_A": s.current_a, "power_W": s.power_w,
        })),
        "extremes": o.extremes(),
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
        let x = o.extremes();
        println!(
            "{}: {} ({}), {} steps, stretch {:.5}…{:.5}, {} event(s); {:.3} ms; trajectory {}",
            o.scene,
            o.fidelity.model,
            o.integrator.message,
            o.integrator.stats.steps,
            x.stretch_min,
            x.stretch_max,
            o.events.len(),
            run_time * 1e3,
            csv.display()
        );
        println!("status: {}", o.integrator.status);
        for w in &o.warnings {
            println!("warning: {w}");
        }
        if let Some(p) = &page {
            println!("report: {}", p.display());
        }
    }
    Ok(match o.integrator.status {
        RunStatus::Completed => 0,
        RunStatus::PullIn => i32::from(a.strict),
        RunStatus::Failed => 1,
    })
}
