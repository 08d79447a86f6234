//! Report of a relaxation fit: data and model on log time (linear time for a history
//! that unloads), the residuals the fit minimised, the
//! relaxation spectrum (grid NNLS and the fitted terms), storage and loss moduli
//! against frequency, and a Markdown page.

use super::format::{si, si_pm};
use super::page::{code, text, Page};
use super::plot::{band, error_bars, line, Chart, Series, Style, BAND_LABEL};
use super::runs::Run;
use crate::error::Result;
use crate::fit::problem::{Residual, REL_FLOOR};
use crate::fit::relaxation::{predict, unloads, Prediction, QlvInput, RelaxationFit};
use crate::io::relaxation::RelaxationData;
use std::path::{Path, PathBuf};

/// What the "Δ" column of a term-count comparison holds, said under the table.
pub const DELTA_LEGEND: &str =
    "Δ: the rule's score (AICc, BIC where AICc is undefined; BIC with --criterion bic) minus the smallest score of the counts tried";

/// Write `fit.svg`, `residuals.svg`, `spectrum.svg`, `dynamic.svg` and the page
/// (`index.md`, `index.html`, `run.json`) into `dir`; returns the HTML page.
pub fn write(
    fit: &RelaxationFit,
    data: &RelaxationData,
    qlv: Option<&QlvInput>,
    dir: &Path,
) -> Result<PathBuf> {
    let Prediction { stress: pred, std } = predict(fit, data, qlv)?;
    // A relaxation spans decades of time; a load-unload cycle is read on linear time.
    let log_x = !data.strain.as_deref().is_some_and(unloads);
    let idx: Vec<usize> = (0..data.time.len())
        .filter(|&i| !log_x || data.time[i] > 0.0)
        .collect();
    let n = fit.prony.len();
    // Each chart is made where it is drawn and dropped after: a chart of 10⁶ points
    // holds 64 MB until it is thinned for drawing.
    let band_series = || {
        std.as_ref().map(|std| {
            let t: Vec<f64> = idx.iter().map(|&i| data.time[i]).collect();
            let (down, up): (Vec<f64>, Vec<f64>) = idx
                .iter()
                .map(|&i| (pred[i] - std[i], pred[i] + std[i]))
                .unzip();
            Series {
                label: BAND_LABEL.into(),
                points: band(&t, &down, &up),
                color: 1,
                style: Style::Band,
            }
        })
    };
    let fit_chart = || Chart {
        title: format!("relaxation: data and {n}-term Prony fit"),
        x_label: "time (s)".into(),
        y_label: "nominal stress".into(),
        series: band_series()
            .into_iter()
            .chain([
                Series {
                    label: "data".into(),
                    points: idx
                        .iter()
                        .map(|&i| (data.time[i], data.stress[i]))
                        .collect(),
                    color: 0,
                    style: Style::Points,
                },
                Series {
                    label: format!("Prony fit ({n} terms, {})", fit.formulation),
                    points: line(idx.iter().map(|&i| (data.time[i], pred[i]))),
                    color: 1,
                    style: Style::Line,
                },
            ])
            .collect(),
        log_x,
        x_unit: None,
        y_unit: Some("Pa".into()),
    };
    let ymax = data.stress.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let scale = |y: f64| match fit.residual {
        Residual::Rel => y.abs().max(REL_FLOOR * ymax),
        Residual::Abs => ymax,
    };
    let residuals_chart = || Chart {
        title: match fit.residual {
            Residual::Rel => "relative residuals (model − data) / |data|".into(),
            Residual::Abs => "residuals (model − data) / peak |data|".into(),
        },
        x_label: "time (s)".into(),
        y_label: "residual (%)".into(),
        series: vec![Series {
            label: "residual".into(),
            points: idx
                .iter()
                .map(|&i| {
                    let y = data.stress[i];
                    (data.time[i], 100.0 * (pred[i] - y) / scale(y))
                })
                .collect(),
            color: 0,
            style: Style::Points,
        }],
        log_x,
        x_unit: None,
        y_unit: None,
    };
    // A discrete spectrum: the fitted terms as stems with their ±σ, the grid
    // stage's nonzero moduli as points (a line between grid points would draw a
    // continuous spectrum the NNLS never found).
    let spectrum_chart = Chart {
        title: "relaxation spectrum".into(),
        x_label: "relaxation time τ (s)".into(),
        y_label: "modulus".into(),
        series: vec![
            Series {
                label: "grid NNLS spectrum (stage 1, nonzero moduli)".into(),
                points: fit
                    .spectrum
                    .iter()
                    .filter(|p| p.modulus_pa > 0.0)
                    .map(|p| (p.tau_s, p.modulus_pa))
                    .collect(),
                color: 2,
                style: Style::Points,
            },
            Series {
                label: "fitted Prony terms".into(),
                points: fit.prony.iter().map(|p| (p.tau_s, p.modulus_pa)).collect(),
                color: 1,
                style: Style::Stems,
            },
            Series {
                label: "± σ of the terms' moduli".into(),
                points: error_bars(
                    fit.prony
                        .iter()
                        .map(|p| (p.tau_s, p.modulus_pa, p.modulus_std_pa.unwrap_or(f64::NAN))),
                ),
                color: 1,
                style: Style::ErrorBars,
            },
        ],
        log_x: true,
        x_unit: None,
        y_unit: Some("Pa".into()),
    };
    let prony = fit.prony_series()?;
    let (lo, hi) = (
        1.0 / fit.time_window_s[1] / 10.0,
        10.0 / fit.time_window_s[0],
    );
    let omegas: Vec<f64> = (0..=120)
        .map(|i| lo * (hi / lo).powf(i as f64 / 120.0))
        .collect();
    let sl: Vec<(f64, f64)> = omegas.iter().map(|&w| prony.storage_loss(w)).collect();
    // The data's time window [t1, tn] probes ω from 1/tn to 1/t1; the curves run a
    // decade beyond on each side: shade what the data support.
    let dynamic_chart = Chart {
        title: "storage and loss moduli (from the fit)".into(),
        x_label: "angular frequency ω (rad/s)".into(),
        y_label: "modulus".into(),
        series: vec![
            Series {
                label: "ω the data's times support, 1/t_max – 1/t_min (beyond: extrapolated)"
                    .into(),
                points: vec![
                    (1.0 / fit.time_window_s[1], 0.0),
                    (1.0 / fit.time_window_s[0], 0.0),
                ],
                color: 8,
                style: Style::Span,
            },
            Series {
                label: "storage E'".into(),
                points: omegas.iter().zip(&sl).map(|(w, s)| (*w, s.0)).collect(),
                color: 0,
                style: Style::Line,
            },
            Series {
                label: "loss E''".into(),
                points: omegas.iter().zip(&sl).map(|(w, s)| (*w, s.1)).collect(),
                color: 1,
                style: Style::Line,
            },
        ],
        log_x: true,
        x_unit: None,
        y_unit: Some("Pa".into()),
    };
    let page = page(fit, |page| {
        page.chart(dir, "fit.svg", "data and fit", &fit_chart())?;
        if std.is_none() {
            page.text("No confidence band: a parameter has no standard error (see the warnings).");
        }
        page.chart(dir, "residuals.svg", "residuals", &residuals_chart())?;
        page.chart(dir, "spectrum.svg", "spectrum", &spectrum_chart)?;
        page.chart(dir, "dynamic.svg", "storage and loss", &dynamic_chart)
    })?;
    let files: Vec<&str> = fit
        .provenance
        .files
        .iter()
        .map(|f| f.path.as_str())
        .collect();
    let run = Run::new(
        "relaxation",
        files.join(", "),
        format!("Prony, {} terms ({})", fit.prony.len(), fit.formulation),
    )
    .headline(vec![
        format!("E0 {}", si(fit.instantaneous_modulus_pa, "Pa")),
        format!("E∞ {}", si(fit.long_term_modulus_pa, "Pa")),
        format!("relative RMSE {:.3} %", 100.0 * fit.rel_rmse),
    ]);
    page.write(dir, "index", run)
}

/// The summary `dea-fit relaxation` prints: the report's page without its charts.
pub fn summary(fit: &RelaxationFit) -> Result<String> {
    Ok(page(fit, |_| Ok(()))?.terminal())
}

/// The one rendering of a relaxation fit (the terminal, Markdown and HTML all show
/// this page): data and loading, status, `charts` (added by the report), the term
/// count's choice, the Prony series, statistics, QLV, warnings and solver.
fn page(fit: &RelaxationFit, charts: impl FnOnce(&mut Page) -> Result<()>) -> Result<Page> {
    let mut page = Page::new(format!(
        "Relaxation fit: {} Prony terms ({} formulation)",
        fit.prony.len(),
        fit.formulation
    ));
    for f in &fit.provenance.files {
        page.para(vec![
            text("Data: "),
            code(&f.path),
            text(format!(
                " ({} points, t {}–{}, sha256 {}…).",
                f.points,
                si(f.time_min_s, "s"),
                si(f.time_max_s, "s"),
                f.sha256.get(..12).unwrap_or(&f.sha256)
            )),
        ]);
    }
    page.text(format!(
        "Loading: {}; residuals: {}.",
        fit.loading,
        match fit.residual {
            Residual::Rel => "relative",
            Residual::Abs => "absolute",
        }
    ));
    page.status_line(fit.status, fit.status);
    charts(&mut page)?;
    if let Some(sel) = &fit.selection {
        page.heading("Term count");
        page.text(format!("Rule: {}.", sel.rule));
        let rows: Vec<Vec<String>> = sel
            .candidates
            .iter()
            .map(|c| {
                vec![
                    c.terms.to_string(),
                    c.k.to_string(),
                    si(c.rmse_pa, "Pa"),
                    format!("{:.3} %", 100.0 * c.rel_rmse),
                    c.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
                    format!("{:.2}", c.bic),
                    format!("{:.2}", c.delta),
                    c.tau_s
                        .iter()
                        .map(|t| si(*t, "s"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    match c.eligible {
                        true => "yes".into(),
                        false => format!("no: {}", c.note.clone().unwrap_or_default()),
                    },
                ]
            })
            .collect();
        page.table(
            &[
                "N",
                "k",
                "RMSE",
                "rel. RMSE",
                "AICc",
                "BIC",
                "Δ",
                "τ",
                "eligible",
            ],
            rows,
        );
        page.text(DELTA_LEGEND);
        page.text(format!("Chosen: {}.", sel.reason));
    }
    page.heading(format!("Prony series ({} terms)", fit.prony.len()));
    let rows: Vec<Vec<String>> = fit
        .prony
        .iter()
        .map(|p| {
            vec![
                si_pm(p.tau_s, p.tau_std_s, "s"),
                si_pm(p.modulus_pa, p.modulus_std_pa, "Pa"),
                format!("{:.4}", p.g),
                si(p.modulus_pa * p.tau_s, "Pa·s"),
            ]
        })
        .collect();
    page.table(&["τ ± σ", "E = k ± σ", "g", "n = k·τ"], rows);
    page.text("σ: standard error; k, n: the Maxwell arm of El Atrache Ceballos (2021) (spring k = E, dashpot n = E·τ).");
    page.text(format!(
        "E∞ {}  E0 {}  g∞ {:.4}",
        si(fit.long_term_modulus_pa, "Pa"),
        si(fit.instantaneous_modulus_pa, "Pa"),
        fit.g_inf,
    ));
    page.text(format!(
        "RMSE {}  rel. RMSE {:.3} %  R² {:.5}  AICc {}  BIC {:.2}",
        si(fit.rmse_pa, "Pa"),
        100.0 * fit.rel_rmse,
        fit.r2,
        fit.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
        fit.bic
    ));
    if let Some(q) = &fit.qlv {
        page.text(format!(
            "QLV: instantaneous response = {:.4} × {} (3μ0 = {}); moduli are g × E0.",
            q.instantaneous_scale,
            q.hyperelastic_model,
            si(q.reference_modulus_pa, "Pa")
        ));
    }
    super::warnings_and_solver(&mut page, &fit.warnings, &fit.solver);
    Ok(page)
}
