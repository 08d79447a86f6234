//! `dea-fit static`: static voltage–stretch curve of a scene's actuator and its peak.
//!
//! Status: `ok` (the curve and its peak, or no peak down to `--stretch-min`, and the
//! scene's input stays below any pull-in), `pull_in` (the scene's largest input
//! voltage reaches the pull-in voltage: exit 1 under `--strict`), `failed` (the
//! search could not look: exit 1). Text output: that line, the curve's shape as a
//! table, the status; `--out` writes the whole curve as CSV; the report (unless
//! `--no-report`) holds the voltage–stretch chart with the pull-in and the table.

use dea_fit::report::static_curve as static_report;
use dea_fit::sim::static_curve::{self, Search};
use dea_fit::sim::{full_plant, scene::Scene};
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// Static (fully relaxed) voltage–stretch curve and pull-in of a scene's actuator.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Print JSON (`status`, `message`, `search`, `curve`, `pull_in`, `curve_file`).
    #[arg(long)]
    json: bool,
    /// Write the whole curve as CSV (`voltage_V,stretch,capacitance_F`); a different
    /// old file is kept aside.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Number of curve points (10 to 100000).
    #[arg(long, default_value_t = 200, value_parser = |s: &str| static_curve::POINTS.parse(s))]
    points: usize,
    /// Smallest stretch examined.
    #[arg(long, default_value_t = 0.3)]
    stretch_min: f64,
    /// Report directory (default reports/static-<scene>).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Do not write the report (chart, shape table, index.md, index.html).
    #[arg(long)]
    no_report: bool,
    /// Exit with status 1 when the scene's input reaches the pull-in voltage.
    #[arg(long)]
    strict: bool,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let scene = Scene::read(&a.scene)?;
    if !(a.stretch_min > 0.0 && a.stretch_min < 1.0) {
        return Err(Error::settings("--stretch-min must be in (0, 1)"));
    }
    let p = full_plant(&scene)?;
    let c = static_curve::static_curve(&p, a.points, a.stretch_min);
    dea_fit::io::finite_output(
        "the static curve",
        c.curve.iter().chain(&c.pull_in).flat_map(|p| {
            [
                ("voltage_V", p.voltage_v),
                ("stretch", p.stretch),
                ("capacitance_F", p.capacitance_f),
            ]
        }),
    )?;
    let v_in = dea_fit::sim::drive_max(&scene);
    let (status, line) = match (c.search, c.pull_in) {
        (Search::PullIn, Some(pi)) if v_in >= pi.voltage_v => (
            "pull_in",
            format!(
                "pull-in at stretch {:.6}, {:.1} V (rest stretch {:.6}); the scene's input reaches {v_in:.1} V, at or above it",
                pi.stretch, pi.voltage_v, p.lam0
            ),
        ),
        (Search::PullIn, Some(pi)) => (
            "ok",
            format!(
                "pull-in at stretch {:.6}, {:.1} V (rest stretch {:.6}); the scene's input peaks at {v_in:.1} V",
                pi.stretch, pi.voltage_v, p.lam0
            ),
        ),
        (Search::Rising, _) => (
            "ok",
            format!(
                "no pull-in down to stretch {} (V still rises there)",
                a.stretch_min
            ),
        ),
        _ => (
            "failed",
            format!(
                "pull-in not determined: {} of {} curve points have a real voltage and the largest is not inside the range",
                c.curve.len(),
                a.points
            ),
        ),
    };
    let dir = (!a.no_report).then(|| {
        a.report
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("reports/static-{}", scene.name)))
    });
    super::refuse_in_report(dir.as_deref(), &[("--out", a.out.as_deref())])?;
    if let Some(out) = &a.out {
        super::write_noted(out, static_report::curve_csv(&c).as_bytes())?;
    }
    let page = match dir {
        None => None,
        Some(dir) => {
            super::claim_dir(&dir)?;
            let outcome = static_report::Outcome {
                scene: &scene.name,
                input: &a.scene.display().to_string(),
                curve: &c,
                status,
                message: &line,
                input_peak_v: v_in,
            };
            Some(static_report::write(&outcome, &dir)?)
        }
    };
    if a.json {
        let mut v = serde_json::to_value(&c).expect("serialisable");
        v["status"] = status.into();
        v["message"] = line.clone().into();
        v["curve_file"] = a.out.as_ref().map(|o| o.display().to_string()).into();
        v["report"] = page.as_ref().map(|p| p.display().to_string()).into();
        println!(
            "{}",
            serde_json::to_string_pretty(&v).expect("serialisable")
        );
    } else {
        print!(
            "{}",
            dea_fit::report::format::fit_width(&format!("{}: {line}\n", scene.name))
        );
        print!("{}", static_report::shape_table(&c));
        if let Some(out) = &a.out {
            println!("curve: {}", out.display());
        }
        println!("status: {status}");
        if let Some(p) = &page {
            println!("report: {}", p.display());
        }
    }
    Ok(match status {
        "failed" => 1,
        "pull_in" => i32::from(a.strict),
        _ => 0,
    })
}
