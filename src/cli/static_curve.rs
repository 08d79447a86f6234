//! `dea-fit static`: static voltage–stretch curve of a scene's actuator and its peak.
//!
//! Status: `ok` (the curve and its peak, or no peak down to `--stretch-min`, and the
//! scene's input stays below any pull-in and below breakdown), `breakdown` (the
//! true field under the scene's largest input reaches the scene's breakdown field
//! on the stable branch: exit 1 under `--strict`), `pull_in` (the scene's largest
//! input voltage reaches the pull-in voltage first: exit 1 under `--strict`),
//! `failed` (the search could not look: exit 1). Text output: that line, which of
//! breakdown and pull-in comes first, the field against breakdown (or that none was
//! checked), the curve's shape as a table (with the breakdown voltage
//! V_b(λ) = Eb·h(λ)), the material's warnings (a stretch outside the range its
//! constants were fitted over, constants its file calls not identifiable: the same
//! as `simulate`'s, `Scene::material_warnings`), the status; `--out` writes the whole curve as CSV; the report
//! (unless `--no-report`) holds the voltage–stretch chart with the pull-in, the
//! breakdown curve and the table.

use dea_fit::report::static_curve::{self as static_report, BreakdownLine};
use dea_fit::sim::breakdown::{self, v_per_um, FieldPeak};
use dea_fit::sim::static_curve::{self, Point, Search};
use dea_fit::sim::{full_plant, scene::Scene};
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// Static (fully relaxed) voltage–stretch curve and pull-in of a scene's actuator.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Print JSON (`status`, `message`, `search`, `curve`, `pull_in`, `breakdown`,
    /// `warnings`, `curve_file`).
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
    /// Exit with status 1 when the scene's input reaches the pull-in voltage or
    /// drives the film beyond breakdown.
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
    let (status, order, check, bd) = against_breakdown(&scene, &p, &c, v_in, status);
    // The material's warnings for the stretches the scene's input reaches: from the
    // rest stretch to its static equilibrium under the largest input (or the end
    // of the stable branch), as `simulate` gives them for a run.
    let warnings = scene.material_warnings(
        p.mode,
        (
            check.peak.stretch.min(p.lam0),
            check.peak.stretch.max(p.lam0),
        ),
    );
    let bline = line_of(&scene, bd);
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
                breakdown: bline.as_ref(),
                check: &check,
                order: order.as_deref(),
            };
            Some(static_report::write(&outcome, &dir)?)
        }
    };
    if a.json {
        let mut v = serde_json::to_value(&c).expect("serialisable");
        v["status"] = status.into();
        v["message"] = line.clone().into();
        let mut b = serde_json::to_value(&check).expect("serialisable");
        b["first"] = match (&bd, c.pull_in, check.checked) {
            (Some(_), _, _) => "breakdown".into(),
            (None, Some(_), true) => "pull_in".into(),
            _ => serde_json::Value::Null,
        };
        b["point"] = serde_json::to_value(bd).expect("serialisable");
        b["order"] = order.clone().into();
        v["breakdown"] = b;
        v["warnings"] = warnings.clone().into();
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
        let mut said = String::new();
        if let Some(o) = &order {
            said.push_str(&format!("{o}\n"));
        }
        said.push_str(&format!("{}\n", check.message));
        for n in &check.notes {
            said.push_str(&format!("note: {n}\n"));
        }
        print!("{}", dea_fit::report::format::fit_width(&said));
        print!("{}", static_report::shape_table(&c, bline.as_ref()));
        let warned: String = warnings.iter().map(|w| format!("warning: {w}\n")).collect();
        print!("{}", dea_fit::report::format::fit_width(&warned));
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
        "pull_in" | "breakdown" => i32::from(a.strict),
        _ => 0,
    })
}

/// The breakdown line of the scene's actuator, where the scene states breakdown.
fn line_of(scene: &Scene, point: Option<Point>) -> Option<BreakdownLine<'_>> {
    scene.breakdown.as_ref().map(|s| BreakdownLine {
        actuator: &scene.actuator,
        field: s.field,
        point,
    })
}

/// The static curve against the scene's breakdown field: the status (`breakdown`
/// when the field under the scene's largest input `v_in` reaches Eb, else
/// `status`), which of breakdown and pull-in comes first on the way up (in words),
/// the check of the largest field under the input, and the point where the curve's
/// field reaches Eb on the stable branch.
fn against_breakdown(
    scene: &Scene,
    p: &dea_fit::sim::plant::Plant,
    c: &static_curve::StaticCurve,
    v_in: f64,
    status: &'static str,
) -> (
    &'static str,
    Option<String>,
    breakdown::Check,
    Option<Point>,
) {
    let a = &scene.actuator;
    let bottom = c.pull_in.map_or(c.stretch_min, |q| q.stretch);
    // The field under the input: at its static equilibrium on the stable branch,
    // or, past the pull-in (no equilibrium), at least the pull-in's.
    let below = c.pull_in.is_none_or(|q| v_in < q.voltage_v);
    let (peak, what) = match (below, p.static_stretch(v_in, p.lam0)) {
        (true, Ok(l)) if l >= bottom => (
            FieldPeak {
                field: a.field(v_in, l),
                voltage_v: v_in,
                stretch: l,
                time_s: None,
            },
            format!(
                "the true field E = V/h(λ) under the scene's largest input ({v_in:.1} V, stretch {l:.6})"
            ),
        ),
        _ => {
            let q = c.pull_in.unwrap_or(Point {
                stretch: bottom,
                voltage_v: static_curve::voltage_at(p, bottom).unwrap_or(0.0),
                capacitance_f: 0.0,
            });
            (
                FieldPeak {
                    field: a.field(q.voltage_v, q.stretch),
                    voltage_v: q.voltage_v,
                    stretch: q.stretch,
                    time_s: None,
                },
                format!(
                    "the scene's input ({v_in:.1} V) has no static equilibrium; the true field E = V/h(λ) at the end of the stable branch (stretch {:.6}, a lower bound)",
                    q.stretch
                ),
            )
        }
    };
    let check = breakdown::check(scene.breakdown.as_ref(), peak, &what);
    let Some(eb) = scene.breakdown.as_ref().map(|s| s.field) else {
        return (status, None, check, None);
    };
    let bd = static_curve::breakdown_point(p, c, eb);
    let order = match (bd, c.pull_in, c.search) {
        (_, _, Search::Undetermined) => None,
        (Some(b), Some(q), _) => Some(format!(
            "breakdown comes first: the field reaches Eb = {} at {:.1} V (stretch {:.6}), below the pull-in at {:.1} V, where it would be {}",
            v_per_um(eb),
            b.voltage_v,
            b.stretch,
            q.voltage_v,
            v_per_um(a.field(q.voltage_v, q.stretch))
        )),
        (Some(b), None, _) => Some(format!(
            "breakdown comes first: the field reaches Eb = {} at {:.1} V (stretch {:.6}); no pull-in down to stretch {}",
            v_per_um(eb),
            b.voltage_v,
            b.stretch,
            c.stretch_min
        )),
        (None, Some(q), _) => Some(format!(
            "pull-in comes first: at the pull-in ({:.1} V, stretch {:.6}) the field is {}, below Eb = {}",
            q.voltage_v,
            q.stretch,
            v_per_um(a.field(q.voltage_v, q.stretch)),
            v_per_um(eb)
        )),
        (None, None, _) => Some(format!(
            "neither breakdown nor pull-in down to stretch {}: the field there is {}, below Eb = {}",
            c.stretch_min,
            v_per_um(a.field(
                static_curve::voltage_at(p, c.stretch_min).unwrap_or(0.0),
                c.stretch_min
            )),
            v_per_um(eb)
        )),
    };
    let status = match (status, check.exceeded) {
        ("failed", _) => "failed",
        (_, true) => "breakdown",
        (s, false) => s,
    };
    (status, order, check, bd)
}
