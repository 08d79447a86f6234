//! `dea-fit bench integrators`: every integrator timed on every shipped scene and on
//! the 5 kV stack over damping ratios 10⁻⁴…10 (its dashpot set for each ζ, 1 s
//! span), with the method `auto` chose and its time as a ratio to the best method's
//! in the same run (the goal of issue 12: within 1.5×). Writes
//! reports/bench-integrators/{results.csv, index.md}.

use dea_fit::io::write::atomic_write;
use dea_fit::sim::integrate::Method;
use dea_fit::sim::scene::Scene;
use dea_fit::sim::{fidelity, trajectory, RunOptions, RunStatus, Trajectory};
use dea_fit::Result;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Damping ratios of the sweep.
const ZETAS: [f64; 11] = [1e-4, 1e-3, 1e-2, 0.03, 0.05, 0.1, 0.2, 0.3, 1.0, 3.0, 10.0];
/// Seconds spent repeating each case (at least one run), and the seconds within
/// which a case is run at least three times (the machine is shared: one run of a
/// long case can be 2× off).
const CASE_SECONDS: f64 = 0.3;
const THREE_RUNS_WITHIN: f64 = 3.0;
/// auto's time may be this many times the best method's.
const GOAL: f64 = 1.5;

/// Best time of repeated runs of `s` with `method` (None: auto), and the last run.
fn timed(s: &Scene, method: Option<Method>) -> Result<(Trajectory, f64)> {
    let o = RunOptions {
        method,
        ..Default::default()
    };
    let (mut best, mut spent) = (f64::INFINITY, 0.0);
    let (mut last, mut runs) = (None, 0);
    while last.is_none() || spent < CASE_SECONDS || (runs < 3 && spent < THREE_RUNS_WITHIN) {
        runs += 1;
        let t = Instant::now();
        let r = trajectory(s, &o)?;
        let dt = t.elapsed().as_secs_f64();
        best = best.min(dt);
        spent += dt;
        last = Some(r);
    }
    Ok((last.expect("ran"), best))
}

/// The 5 kV stack with its dashpot set for damping ratio `zeta` over 1 s.
fn damped(base: &Scene, zeta: f64) -> Result<Scene> {
    let mut s = base.clone();
    s.name = format!("stack_step_5kV zeta={zeta:e}");
    s.time.span = 1.0;
    s.time.samples = (1..=200).map(|i| i as f64 / 200.0).collect();
    let at = |nv: f64| -> Result<f64> {
        let mut t = s.clone();
        t.material.viscous.nv_pa_s = nv;
        Ok(fidelity::axial_mode(&dea_fit::sim::full_plant(&t)?).damping_ratio)
    };
    // ζ is linear in the dashpot: ζ(Nv) = ζ(0) + Nv·(ζ(1) − ζ(0))
    let (z0, z1) = (at(0.0)?, at(1.0)?);
    s.material.viscous.nv_pa_s = ((zeta - z0) / (z1 - z0)).max(0.0);
    Ok(s)
}

/// Run the benchmark.
pub fn run(dir: &Path) -> Result<super::bench::Verdict> {
    let out_dir = PathBuf::from("reports/bench-integrators");
    let mut scenes = Vec::new();
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| dea_fit::Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    names.sort();
    for p in &names {
        scenes.push(Scene::read(p)?);
    }
    let base = Scene::read(&dir.join("stack_step_5kV.toml"))?;
    for z in ZETAS {
        scenes.push(damped(&base, z)?);
    }
    super::claim_dir(&out_dir)?;
    let mut csv = String::from("scene,damping_ratio,method,run_time_s,steps,rejected,status\n");
    let mut md = String::from(
        "# Integrators per scene\n\nBest time of repeated runs (`sim::trajectory`), every method and `auto`, in one run of `dea-fit bench integrators`; the ratio is auto's time over the best method's (goal ≤ 1.5).\n\n| scene | ζ | ",
    );
    for m in Method::ALL {
        let _ = write!(md, "{m} | ");
    }
    md.push_str("auto | auto / best |\n|---|---|");
    md.push_str(&"---|".repeat(Method::ALL.len() + 2));
    md.push('\n');
    let mut verdict = super::bench::Verdict::default();
    let bar = super::bench::progress_bar("integrators", scenes.len());
    for s in &scenes {
        bar.set_message(s.name.clone());
        let zeta = fidelity::axial_mode(&dea_fit::sim::full_plant(s)?).damping_ratio;
        let mut s = s.clone();
        s.time.method = None;
        let why = dea_fit::sim::budget::estimate(&s)?
            .auto
            .map(|a| a.1)
            .unwrap_or_default();
        let _ = write!(md, "| {} | {zeta:.1e} | ", s.name);
        let mut best = f64::INFINITY;
        for m in Method::ALL {
            let (r, t) = timed(&s, Some(m))?;
            let _ = writeln!(
                csv,
                "{},{zeta:e},{m},{t:e},{},{},{}",
                s.name, r.stats.steps, r.stats.rejected, r.status
            );
            match r.status {
                RunStatus::Completed => {
                    best = best.min(t);
                    let _ = write!(md, "{:.3} ms | ", t * 1e3);
                }
                st => {
                    let _ = write!(md, "{st} | ");
                }
            }
        }
        let (r, t) = timed(&s, None)?;
        let _ = writeln!(
            csv,
            "{},{zeta:e},auto:{},{t:e},{},{},{}",
            s.name, r.method, r.stats.steps, r.stats.rejected, r.status
        );
        let ratio = t / best;
        let _ = writeln!(
            md,
            "{} {:.3} ms | {ratio:.2}{} |",
            r.method,
            t * 1e3,
            if ratio > GOAL { " ✗" } else { "" }
        );
        let case = format!("{} auto ({})", s.name, r.method);
        match r.status {
            RunStatus::Completed => {}
            RunStatus::PullIn => verdict.blocking.push(format!("{case}: pull_in")),
            RunStatus::Failed => verdict.failed.push(format!("{case}: {}", r.message)),
        }
        println!(
            "{:<36} ζ {zeta:8.1e}  auto {:<8} {:9.3} ms  best {:9.3} ms  ratio {ratio:.2}",
            s.name,
            r.method.to_string(),
            t * 1e3,
            best * 1e3
        );
        println!("    {why}");
        bar.inc(1);
    }
    bar.finish();
    atomic_write(&out_dir.join("results.csv"), csv.as_bytes())?;
    let page = out_dir.join("index.md");
    atomic_write(&page, md.as_bytes())?;
    println!("report: {}", page.display());
    Ok(verdict)
}
