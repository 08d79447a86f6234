//! `dea-fit bench simulate`: error against run time over tolerances, integrators and
//! fidelity levels for seed scenes, against a tight-tolerance Dormand–Prince
//! reference (rtol 1e-11). Writes reports/bench-simulate/{results.csv, <scene>.svg}.

use dea_fit::io::write::atomic_write;
use dea_fit::report::plot::{Chart, Series, Style};
use dea_fit::sim::integrate::Method;
use dea_fit::sim::scene::{FidelityChoice, Scene};
use dea_fit::sim::{simulate, Outcome, RunOptions, RunStatus};
use dea_fit::Result;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

const SCENES: [&str; 3] = [
    "stack_step_5kV_damped",
    "stack_triangle_100Hz",
    "hdea_step_10N",
];

fn timed(s: &Scene, o: &RunOptions) -> Result<(Outcome, f64)> {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..3 {
        let t = Instant::now();
        let r = simulate(s, o)?;
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    Ok((out.expect("ran"), best))
}

/// Run the benchmark.
pub fn run(dir: &Path) -> Result<super::bench::Verdict> {
    let out_dir: PathBuf = PathBuf::from("reports/bench-simulate");
    super::claim_dir(&out_dir)?;
    let mut csv =
        String::from("scene,method,fidelity,rtol,run_time_s,steps,status,max_error_rel_stroke\n");
    // A failed run has no trajectory to compare: it is counted, and the bench exits 1.
    let mut verdict = super::bench::Verdict::default();
    let bar = super::bench::progress_bar("simulate", SCENES.len() * 6 * 6);
    for name in SCENES {
        let mut scene = Scene::read(&dir.join(format!("{name}.toml")))?;
        scene.time.samples = (1..=200)
            .map(|i| scene.time.span * i as f64 / 200.0)
            .collect();
        let mut reference_scene = scene.clone();
        reference_scene.time.fidelity = FidelityChoice::Dynamic;
        let reference = simulate(
            &reference_scene,
            &RunOptions {
                method: Some(Method::Dp54),
                rtol: Some(1e-11),
                ..Default::default()
            },
        )?;
        let stroke = reference
            .samples
            .iter()
            .map(|s| (s.stretch - reference.rest_stretch).abs())
            .fold(1e-300, f64::max);
        let mut series = Vec::new();
        for (ci, (method, fid)) in [
            (Method::Bdf, FidelityChoice::Dynamic),
            (Method::Esdirk34, FidelityChoice::Dynamic),
            (Method::TrBdf2, FidelityChoice::Dynamic),
            (Method::Tsit45, FidelityChoice::Dynamic),
            (Method::Dp54, FidelityChoice::Dynamic),
            (Method::Bdf, FidelityChoice::Auto),
        ]
        .into_iter()
        .enumerate()
        {
            let mut s = scene.clone();
            s.time.fidelity = fid;
            let mut pts = Vec::new();
            for rtol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
                bar.set_message(format!("{name} {method} rtol {rtol:e}"));
                let (o, t) = timed(
                    &s,
                    &RunOptions {
                        method: Some(method),
                        rtol: Some(rtol),
                        ..Default::default()
                    },
                )?;
                let err = o
                    .samples
                    .iter()
                    .zip(&reference.samples)
                    .map(|(a, b)| (a.stretch - b.stretch).abs())
                    .fold(0.0, f64::max)
                    / stroke;
                let _ = writeln!(
                    csv,
                    "{name},{method},{},{rtol:e},{t:e},{},{},{err:e}",
                    o.fidelity.model, o.integrator.stats.steps, o.integrator.status
                );
                bar.inc(1);
                let case = format!("{name} {method} rtol {rtol:e}");
                match o.integrator.status {
                    RunStatus::Failed => {
                        verdict
                            .failed
                            .push(format!("{case}: {}", o.integrator.message));
                        continue;
                    }
                    RunStatus::PullIn => verdict.blocking.push(format!("{case}: pull_in")),
                    RunStatus::Completed => {}
                }
                pts.push((t, err.max(1e-16).log10()));
            }
            series.push(Series {
                label: match fid {
                    FidelityChoice::Auto => format!("{method} auto fidelity"),
                    _ => format!("{method} dynamic"),
                },
                points: pts,
                color: ci,
                style: Style::Line,
            });
        }
        Chart {
            title: format!("{name}: error vs run time (rtol 1e-3 … 1e-8)"),
            x_label: "run time".into(),
            y_label: "log10 max |Δλ| / stroke".into(),
            series,
            log_x: true,
            x_unit: Some("s".into()),
            y_unit: None,
        }
        .write_svg(&out_dir.join(format!("{name}.svg")))?;
    }
    bar.finish();
    let path = out_dir.join("results.csv");
    atomic_write(&path, csv.as_bytes())?;
    print!("{csv}");
    println!("wrote {}", path.display());
    Ok(verdict)
}
