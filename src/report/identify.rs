//! Report of an identification: every trace against the model per channel, the
//! residuals over their noise, the scaled sensitivities of each channel to the free
//! constants, the correlation matrix as a picture, the multi-start waterfall, and a
//! Markdown page linking them.

use super::format::{constant, constant_pm, si};
use super::page::{code, text, Page};
use super::plot::{band, Chart, Series, Style, AXIS_FONT, BAND_LABEL, SVG_FONT};
use super::runs::Run;
use crate::error::{Error, Result};
use crate::identify::failure::Failure;
use crate::identify::geometry::Geometry;
use crate::identify::material::Validation;
use crate::identify::noise::SigmaSource;
use crate::identify::params;
use crate::identify::problem::{sensitivity, simulated, Channel, ChannelKind, Experiment};
use crate::identify::selection::{flags, Comparison};
use crate::identify::Identification;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The SI unit of a channel's values.
fn si_unit(kind: ChannelKind) -> &'static str {
    match kind {
        ChannelKind::Contraction | ChannelKind::Length => "m",
        ChannelKind::Capacitance => "F",
        ChannelKind::Current => "A",
        ChannelKind::Force => "N",
        ChannelKind::Stretch => "1",
    }
}

/// Write the report into `dir` (claimed by the caller); returns the page. `selection`:
/// the comparison of `--arms auto` / `--hyperelastic auto`, when one chose the model.
pub fn write(
    id: &Identification,
    experiments: &[Experiment],
    validation: &[Validation],
    selection: Option<&Comparison>,
    dir: &Path,
) -> Result<PathBuf> {
    let page = page(id, experiments, validation, selection, |page| {
        charts(id, experiments, page, dir)
    })?;
    let files: Vec<&str> = experiments.iter().map(|e| e.name.as_str()).collect();
    let scene = experiments
        .first()
        .map_or(String::new(), |e| e.scene.name.clone());
    let run = Run::new("identify", files.join(", "), scene).headline(
        id.parameters
            .iter()
            .take(4)
            .map(|p| format!("{} {}", p.name, constant(&p.name, p.value, &p.unit)))
            .chain(std::iter::once(format!("χ²/dof {:.3}", id.chi2_per_dof)))
            .collect(),
    );
    page.write(dir, "index", run)
}

/// The summary `dea-fit identify` prints: the report's page without its charts.
pub fn summary(
    id: &Identification,
    experiments: &[Experiment],
    validation: &[Validation],
    selection: Option<&Comparison>,
) -> Result<String> {
    Ok(page(id, experiments, validation, selection, |_| Ok(()))?.terminal())
}

/// The title of every identification page.
const TITLE: &str = "Identification from actuator traces";

/// The one rendering of an identification (the terminal, Markdown and HTML all show
/// this page): traces, status, the model selection if one was made, the constants,
/// the channels (held-out traces too), the fit's quality and profiles, `charts`
/// (added by the report), warnings and solver.
fn page(
    id: &Identification,
    experiments: &[Experiment],
    validation: &[Validation],
    selection: Option<&Comparison>,
    charts: impl FnOnce(&mut Page) -> Result<()>,
) -> Result<Page> {
    let mut page = Page::new(TITLE);
    let mut traces = vec![text("Traces: ")];
    for (i, e) in experiments.iter().enumerate() {
        if i > 0 {
            traces.push(text(", "));
        }
        traces.push(code(&e.name));
    }
    page.para(traces);
    page.status_line(id.status, id.status);
    if let Some(c) = selection {
        selection_section(c, &mut page);
    }
    page.heading("Constants");
    let derived = id.derived.iter().map(|p| (p, " (derived)"));
    let rows: Vec<Vec<String>> = id
        .parameters
        .iter()
        .map(|p| (p, ""))
        .chain(derived)
        .map(|(p, note)| {
            let [v, ci] = constant_pm(&p.name, p.value, p.std_error, p.ci95, &p.unit);
            vec![
                format!("{}{note}", p.name),
                v,
                ci,
                interval_kind(p),
                if p.identifiable {
                    "yes".into()
                } else {
                    format!("no: {}", p.reason.as_deref().unwrap_or(""))
                },
            ]
        })
        .collect();
    page.table(
        &[
            "parameter",
            "value ± σ",
            "95 % interval",
            "kind",
            "identifiable",
        ],
        rows,
    );
    held_section(id, &mut page);
    reduction_section(id, &mut page);
    geometry_section(&id.geometry, &mut page);
    page.heading("Channels");
    page.table(
        &["trace", "channel", "points", "σ", "σ from", "RMSE", "%RMSE"],
        channel_rows(id, validation),
    );
    page.text(format!(
        "χ²/dof {:.4}, condition {:.3e} (of the column-normalised Jacobian).",
        id.chi2_per_dof, id.assessment.condition
    ));
    page.bullets(id.profiles.iter().map(|p| {
        let side = |v: Option<f64>| {
            v.map(|v| si(v, &p.unit))
                .unwrap_or_else(|| "beyond the grid".into())
        };
        format!(
            "profile {}: Δχ² ≤ {:.2} from {} to {}",
            p.name,
            p.threshold,
            side(p.interval[0]),
            side(p.interval[1])
        )
    }));
    charts(&mut page)?;
    page.warnings(&id.warnings);
    let v = &id.solver;
    page.heading("Solver");
    page.text(format!("{}; {}.", v.method, v.termination));
    page.text(format!(
        "{} start(s), {} at the best objective, {} abandoned; {} iterations, {} simulator runs ({} with sensitivities), {:.3} s.",
        v.starts, v.starts_at_best, v.starts_abandoned, v.iterations, v.simulator_runs, v.sensitivity_runs, v.seconds
    ));
    page.text(format!(
        "Intervals (covariance, profile checks and intervals): {:.3} s of these.",
        v.interval_seconds
    ));
    if let Some(z) = v.integration_shift {
        page.text(format!(
            "Integration check: at 1/100 of the simulator's tolerance the optimum moves by {z:.2e} standard errors at most."
        ));
    }
    Ok(page)
}

/// The kind of an estimate's interval for the constants table: Wald or profile,
/// its open side, what it is conditional on; "held by the bound" for a constant at a
/// bound of its search (no interval).
fn interval_kind(p: &crate::identify::assessment::Estimate) -> String {
    let mut s = match (p.interval, p.at_bound) {
        (Some(k), _) => k.to_string(),
        (None, true) => "held by the bound".into(),
        (None, false) => "—".into(),
    };
    if let Some(o) = p.open {
        s.push_str(&format!(", open {o}"));
    }
    if !p.conditional_on.is_empty() {
        s.push_str(&format!(
            ", given {} at a bound",
            p.conditional_on.join(", ")
        ));
    }
    s
}

/// The constants not fitted, under the constants: each one's value and how it got
/// it (`fixed`: typed in; `scene`: the scene's value; `dropped`: by the model
/// reduction, with its reason), and what the intervals above are conditional on.
fn held_section(id: &Identification, page: &mut Page) {
    use crate::identify::reduce::How;
    if id.held.is_empty() {
        return;
    }
    page.text("Held (not fitted):".to_string());
    let rows = id
        .held
        .iter()
        .map(|h| {
            vec![
                h.name.clone(),
                constant(&h.name, h.value, &h.unit),
                match h.how {
                    How::Fixed => "fixed (stated)",
                    How::Scene => "scene's value",
                    How::Dropped => "dropped",
                }
                .to_string(),
                h.reason.clone().unwrap_or_default(),
            ]
        })
        .collect();
    page.table(&["held", "value", "how", "why"], rows);
    if !id.conditional_on.is_empty() {
        let on: Vec<String> = id
            .held
            .iter()
            .filter(|h| id.conditional_on.contains(&h.name))
            .map(|h| format!("{} = {}", h.name, constant(&h.name, h.value, &h.unit)))
            .collect();
        page.text(format!(
            "Every interval above is conditional on the held {}: it assumes {} exact, and does not include their uncertainty.",
            on.join(", "),
            match on.len() {
                1 => "this value",
                _ => "these values",
            }
        ));
    }
}

/// The default model reduction, when it reduced the scene's model: the full
/// model's fit, each round (what it dropped and why), ΔAICc and the flags that
/// give the reduced model directly.
fn reduction_section(id: &Identification, page: &mut Page) {
    use crate::identify::reduce::MAX_DELTA_AICC;
    let Some(r) = &id.reduction else { return };
    page.heading("Model reduced");
    let aicc = |a: Option<f64>| a.map_or("—".into(), |a| format!("{a:.1}"));
    page.text(format!(
        "The scene's full model ({} free constants) left {} not identifiable (status {}, χ²/dof {:.4}, AICc {}); the constants above are those of the smallest model whose constants the traces pin down, reached by dropping one constant per round (the same σ throughout).",
        r.full.free,
        r.full.not_identifiable.join(", "),
        r.full.status,
        r.full.chi2_per_dof,
        aicc(r.full.aicc),
    ));
    let rows = r
        .rounds
        .iter()
        .enumerate()
        .map(|(i, d)| {
            vec![
                (i + 1).to_string(),
                d.action.clone(),
                format!("{:.4}", d.chi2_per_dof),
                aicc(d.aicc),
                d.reason.clone(),
            ]
        })
        .collect();
    page.table(&["round", "dropped", "χ²/dof", "AICc", "why"], rows);
    let delta = r
        .delta_aicc
        .map_or("undefined".into(), |d| format!("{d:.1}"));
    page.text(format!(
        "ΔAICc (reduced − full) = {delta}{}{}",
        match r.delta_aicc.is_some_and(|d| d > MAX_DELTA_AICC) {
            true => format!(": above {MAX_DELTA_AICC}, the full model fits much better and the dropped terms together matter."),
            false => format!(" (at most {MAX_DELTA_AICC}: the dropped terms do not matter to the fit)."),
        },
        r.flags
            .as_ref()
            .map_or(String::new(), |f| format!(" The same model directly: {f}.")),
    ));
}

/// What the scene's geometry adds to the intervals ([`crate::identify::geometry`]):
/// whether they include its tolerances, and per constant the σ from the trace, the
/// σ from the geometry and the move per 1 % of each length.
fn geometry_section(g: &Geometry, page: &mut Page) {
    page.heading("Geometry");
    page.text(format!("{}.", g.statement()));
    let Some(first) = g.constants.first() else {
        if let Some(why) = &g.failed {
            page.text(format!("Not computed: {why}."));
        }
        return;
    };
    let mut header = vec![
        "parameter".to_string(),
        "σ from the trace".into(),
        "σ from the geometry".into(),
    ];
    header.extend(
        first
            .per_percent
            .iter()
            .map(|m| format!("per +1 % {}", m.length)),
    );
    let rows = g
        .constants
        .iter()
        .map(|t| {
            let sd = |s: Option<f64>| s.map_or("—".into(), |s| constant(&t.name, s, &t.unit));
            let mut row = vec![t.name.clone(), sd(t.sigma_trace)];
            row.push(match g.included {
                true => sd(t.sigma_geometry),
                false => "excluded".into(),
            });
            row.extend(t.per_percent.iter().map(|m| m.words(&t.unit)));
            row
        })
        .collect();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    page.table(&header, rows);
}

/// The channels table: each identified channel (points, σ and where it came from,
/// RMSE), then each held-out trace's (RMSE of the prediction, or why there is none).
fn channel_rows(id: &Identification, validation: &[Validation]) -> Vec<Vec<String>> {
    let pct = |p: Option<f64>| p.map(|p| format!("{p:.3}")).unwrap_or_else(|| "—".into());
    let mut ch = Vec::new();
    for e in &id.experiments {
        for c in &e.channels {
            ch.push(vec![
                e.file.clone(),
                c.channel.to_string(),
                c.points.to_string(),
                si(c.sigma, c.unit),
                match c.sigma_source {
                    SigmaSource::Given => "given",
                    SigmaSource::Residuals => "residuals",
                }
                .into(),
                si(c.rmse, c.unit),
                pct(c.rmse_pct),
            ]);
        }
    }
    for v in validation {
        let held = format!("{} (held out)", v.file);
        let blank = || String::new();
        if let Some(why) = &v.failed {
            ch.push(vec![
                held.clone(),
                "—".into(),
                blank(),
                blank(),
                blank(),
                format!("not predicted: {why}"),
                "—".into(),
            ]);
        }
        for c in &v.channels {
            ch.push(vec![
                held.clone(),
                c.channel.to_string(),
                blank(),
                si(c.sigma, c.unit),
                "held-out data".into(),
                si(c.rmse, c.unit),
                pct(c.rmse_pct),
            ]);
        }
    }
    ch
}

/// The comparison of `--arms auto` / `--hyperelastic auto`, with the chosen row
/// marked (the model column when the model was chosen, the arms column when the
/// arms were), the candidates that failed, and why the chosen one.
fn selection_section(c: &Comparison, page: &mut Page) {
    let opt = |v: Option<f64>| v.map(|a| format!("{a:.2}")).unwrap_or_else(|| "—".into());
    let rows: Vec<Vec<String>> = c
        .candidates
        .iter()
        .enumerate()
        .map(|(i, k)| {
            let mark = if i == c.chosen { " ←" } else { "" };
            let mut row = Vec::new();
            if c.choose.hyperelastic {
                row.push(k.model.clone());
            }
            if c.choose.arms {
                row.push(k.arms.to_string());
            }
            row.last_mut().expect("a chosen column").push_str(mark);
            row.extend([
                k.free.to_string(),
                k.chi2_per_dof
                    .map(|c| format!("{c:.4}"))
                    .unwrap_or_else(|| "—".into()),
                opt(k.aicc),
                opt(k.delta_aicc),
                opt(k.bic),
                k.status.to_string(),
                if k.eligible { "yes" } else { "no" }.into(),
            ]);
            row
        })
        .collect();
    let mut header = Vec::new();
    if c.choose.hyperelastic {
        header.push("model");
    }
    if c.choose.arms {
        header.push("arms");
    }
    header.extend([
        "free", "χ²/dof", "AICc", "ΔAICc", "BIC", "status", "eligible",
    ]);
    page.heading("Model selection");
    page.table(&header, rows);
    page.bullets(
        c.candidates
            .iter()
            .filter(|k| k.failure.is_some())
            .map(|k| {
                format!(
                    "{} with {} arm(s) failed: {}",
                    k.model,
                    k.arms,
                    k.failure.as_deref().unwrap_or("")
                )
            }),
    );
    let (k, from) = (&c.candidates[c.chosen], &c.candidates[c.sigma_from]);
    page.text(format!(
        "{}: {} with {} arm(s), the fewest free constants within ΔAICc ≤ 2 of the best eligible candidate (a common σ from the {} fit with {} arm(s)). ΔAICc: AICc minus the smallest AICc of the eligible candidates.",
        flags(c.choose),
        k.model,
        k.arms,
        from.model,
        from.arms
    ));
}

/// The summary `dea-fit identify` prints for a failed run (no fit file, no report):
/// what failed, each failed start with its constants and reason, the search, and
/// what to do.
pub fn failure_summary(f: &Failure) -> String {
    let mut page = Page::new(TITLE);
    page.status_line(f.status, f.status);
    page.text(f.reason.clone());
    page.bullets(f.starts.iter().map(|st| {
        let at: Vec<String> = st
            .constants
            .iter()
            .map(|c| format!("{} = {}", c.name, si(c.value, &c.unit)))
            .collect();
        format!("start {} ({}): {}", st.start, at.join(", "), st.reason)
    }));
    let v = &f.solver;
    page.text(format!(
        "Solver: {} start(s), {} simulator runs, {:.3} s.",
        v.starts, v.simulator_runs, v.seconds
    ));
    page.text(format!("Hint: {}", f.hint));
    page.text("Nothing written (no fit file, no report).");
    page.terminal()
}

/// The charts of every trace and channel (measured against the model with its ±1σ
/// band, residuals, sensitivities), the multi-start waterfall, the profiles and the
/// correlation matrix, drawn into `dir` and shown on `page`.
fn charts(
    id: &Identification,
    experiments: &[Experiment],
    page: &mut Page,
    dir: &Path,
) -> Result<()> {
    for (ei, (e, o)) in experiments.iter().zip(&id.runs).enumerate() {
        let s0 = o.samples[0];
        for (ci, c) in e.channels.iter().enumerate() {
            let unit = si_unit(c.kind);
            let data: Vec<(f64, f64)> = o
                .samples
                .iter()
                .zip(&c.values)
                .filter(|(_, y)| y.is_finite())
                .map(|(s, y)| (s.time_s, *y))
                .collect();
            let times: Vec<f64> = o.samples.iter().map(|s| s.time_s).collect();
            let model: Vec<f64> = o
                .samples
                .iter()
                .map(|s| simulated(c.kind, &s0, s))
                .collect();
            let mut series = vec![Series {
                label: "measured".into(),
                points: data,
                color: 0,
                style: Style::Points,
            }];
            let std = id.model_std(e, ei, c.kind);
            if let Some(std) = &std {
                let (down, up): (Vec<f64>, Vec<f64>) =
                    model.iter().zip(std).map(|(m, d)| (m - d, m + d)).unzip();
                series.push(Series {
                    label: BAND_LABEL.into(),
                    points: band(&times, &down, &up),
                    color: 1,
                    style: Style::Band,
                });
            }
            series.push(Series {
                label: "identified model".into(),
                points: times.iter().copied().zip(model).collect(),
                color: 1,
                style: Style::Line,
            });
            let name = format!("trace{}-{}.svg", ei + 1, c.kind);
            page.chart(
                dir,
                &name,
                &format!("{}: {}, measured and identified model", e.name, c.kind),
                &Chart {
                    title: format!("{}: {}", e.name, c.kind),
                    x_label: "time".into(),
                    y_label: c.kind.to_string(),
                    series,
                    log_x: false,
                    x_unit: Some("s".into()),
                    y_unit: Some(unit.into()),
                },
            )?;
            if std.is_none() {
                page.text("No confidence band: a free constant has no standard error (see the parameters).");
            }
            let sigma = id.experiments[ei].channels[ci].sigma;
            let res: Vec<(f64, f64)> = o
                .samples
                .iter()
                .zip(&c.values)
                .filter(|(_, y)| y.is_finite())
                .map(|(s, y)| (s.time_s, (simulated(c.kind, &s0, s) - y) / sigma))
                .collect();
            let rname = format!("trace{}-{}-residuals.svg", ei + 1, c.kind);
            page.chart(
                dir,
                &rname,
                &format!("{}: {} residual / σ", e.name, c.kind),
                &Chart {
                    title: format!("{}: {} residual / σ", e.name, c.kind),
                    x_label: "time (s)".into(),
                    y_label: "(model − measured) / σ".into(),
                    series: vec![Series {
                        label: "residual".into(),
                        points: res,
                        color: 2,
                        style: Style::Points,
                    }],
                    log_x: false,
                    x_unit: None,
                    y_unit: None,
                },
            )?;
            if let Some((sname, chart)) = sensitivity_chart(id, e, ei, c, sigma) {
                let noise = si(sigma, unit);
                page.text(format!(
                    "Scaled sensitivities of the {kind}: θ·∂y/∂θ / σ for each free constant θ, the first-order change of the simulated {kind} y, in units of its noise σ = {noise}, for a 100 % change of θ, at the identified constants. A constant whose curve is small everywhere is weakly pinned down by this channel; two constants with proportional curves cannot be told apart by it.",
                    kind = c.kind,
                ));
                let alt = format!("{}: {} sensitivities", e.name, c.kind);
                page.chart(dir, &sname, &alt, &chart)?;
            }
        }
    }
    let costs: Vec<(f64, f64)> = id
        .solver
        .final_costs
        .iter()
        .enumerate()
        .filter(|(_, c)| c.is_finite())
        .map(|(i, c)| {
            (
                (i + 1) as f64,
                (c - id.solver.final_costs[0] + 1e-3).log10(),
            )
        })
        .collect();
    page.chart(
        dir,
        "waterfall.svg",
        "waterfall",
        &Chart {
            title: format!(
                "multi-start: {} of {} starts at the best cost, {} abandoned (cost where given up)",
                id.solver.starts_at_best, id.solver.starts, id.solver.starts_abandoned
            ),
            x_label: "start (sorted by final cost)".into(),
            y_label: "log10(cost − best + 0.001)".into(),
            series: vec![Series {
                label: "final ½χ²".into(),
                points: costs,
                color: 3,
                style: Style::Points,
            }],
            log_x: false,
            x_unit: None,
            y_unit: None,
        },
    )?;
    for p in &id.profiles {
        let pts: Vec<(f64, f64)> = p
            .values
            .iter()
            .zip(&p.delta_chi2)
            .filter(|(_, d)| d.is_finite())
            .map(|(v, d)| (*v, *d))
            .collect();
        let (lo, hi) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            });
        let name = format!("profile-{}.svg", p.name);
        page.chart(
            dir,
            &name,
            &name,
            &Chart {
                title: format!("profile likelihood of {}", p.name),
                x_label: p.name.clone(),
                y_label: "Δχ² (others re-fitted)".into(),
                series: vec![
                    Series {
                        label: "profile".into(),
                        points: pts,
                        color: 0,
                        style: Style::Line,
                    },
                    Series {
                        label: format!("95 % (t²s² = {:.2})", p.threshold),
                        points: vec![(lo, p.threshold), (hi, p.threshold)],
                        color: 1,
                        style: Style::Dashed,
                    },
                ],
                log_x: false,
                x_unit: Some(p.unit.clone()),
                y_unit: None,
            },
        )?;
    }
    let corr = correlation(id, &dir.join("correlation.svg"))?;
    page.svg(
        dir,
        "correlation.svg",
        "correlation of the free constants",
        corr,
    )?;
    Ok(())
}

/// The chart of θk·∂y/∂θk / σ against time for channel `c` of experiment `ei` (`e`)
/// and every free constant θk, at the identified constants, with its file name; None
/// when the run has no sensitivities.
fn sensitivity_chart(
    id: &Identification,
    e: &Experiment,
    ei: usize,
    c: &Channel,
    sigma: f64,
) -> Option<(String, Chart)> {
    let o = &id.runs[ei];
    let se = o.sensitivities.as_ref()?;
    let constants = params::constants(&e.scene);
    let series = id
        .parameters
        .iter()
        .filter_map(|p| constants.iter().find(|k| k.name == p.name))
        .filter_map(|k| se.column(k.index).map(|col| (k, col)))
        .enumerate()
        .map(|(j, (k, col))| Series {
            label: k.name.clone(),
            points: o
                .samples
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    let d = id.theta[k.index] * sensitivity(c.kind, se, i, col) / sigma;
                    (s.time_s, d)
                })
                .filter(|(_, d)| d.is_finite())
                .collect(),
            color: j,
            style: Style::Line,
        })
        .collect();
    let name = format!("sensitivities{}-{}.svg", ei + 1, c.kind);
    let chart = Chart {
        title: format!("{}: {} sensitivities θ·∂y/∂θ / σ", e.name, c.kind),
        x_label: "time (s)".into(),
        y_label: format!("θ·∂({})/∂θ / σ  (noise units)", c.kind),
        series,
        log_x: false,
        x_unit: None,
        y_unit: None,
    };
    Some((name, chart))
}

/// The correlation matrix of the free constants as coloured cells (blue −1 … white
/// 0 … red +1; grey where undefined), with the names on both axes, as SVG text;
/// `path` (where it goes) names it in an error.
fn correlation(id: &Identification, path: &Path) -> Result<String> {
    let names: Vec<&str> = id.parameters.iter().map(|p| p.name.as_str()).collect();
    let k = names.len();
    // text at the charts' tick size as drawn (plotters-svg divides by SVG_FONT);
    // a cell holds "-0.99" and a column's name ("arm1.tau") at that size
    let font = ("sans-serif", AXIS_FONT * SVG_FONT);
    let cell = 62i32;
    let margin = 90i32;
    let size = (margin + cell * k as i32 + 20) as u32;
    let fail = |e: String| Error::settings(format!("{}: {e}", path.display()));
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (size, size)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
    for (a, row) in id.assessment.correlation.iter().enumerate() {
        for (b, rho) in row.iter().enumerate() {
            let (x, y) = (margin + cell * b as i32, margin + cell * a as i32);
            let fill = match rho {
                Some(r) if r.is_finite() => {
                    let t = r.clamp(-1.0, 1.0);
                    let w = |c: f64| (255.0 * (1.0 - t.abs()) + c * t.abs()) as u8;
                    if t >= 0.0 {
                        RGBColor(w(214.0), w(39.0), w(40.0))
                    } else {
                        RGBColor(w(31.0), w(119.0), w(180.0))
                    }
                }
                _ => RGBColor(200, 200, 200),
            };
            root.draw(&Rectangle::new(
                [(x, y), (x + cell, y + cell)],
                fill.filled(),
            ))
            .map_err(|e| fail(e.to_string()))?;
            let label = rho.map(|r| format!("{r:.2}")).unwrap_or_else(|| "—".into());
            root.draw(&Text::new(label, (x + 8, y + cell / 2 - 7), font))
                .map_err(|e| fail(e.to_string()))?;
        }
        root.draw(&Text::new(
            names[a].to_string(),
            (4, margin + cell * a as i32 + cell / 2 - 7),
            font,
        ))
        .map_err(|e| fail(e.to_string()))?;
        root.draw(&Text::new(
            names[a].to_string(),
            (margin + cell * a as i32 + 2, margin - 22),
            font,
        ))
        .map_err(|e| fail(e.to_string()))?;
    }
    root.present().map_err(|e| fail(e.to_string()))?;
    drop(root);
    Ok(svg)
}
