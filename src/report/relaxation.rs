//! Report of a relaxation fit: data and model on log time (linear time for a history
//! that unloads), the residuals the fit minimised, the
//! relaxation spectrum (grid NNLS and the fitted terms), storage and loss moduli
//! against frequency, and a Markdown page.

use super::format::{si, si_pm};
use super::page::{code, text, Page};
use super::plot::{Chart, Series, Style};
use super::runs::Run;
use crate::error::Result;
use crate::fit::problem::{Residual, REL_FLOOR};
use crate::fit::relaxation::{predict, unloads, QlvInput, RelaxationFit};
use crate::io::relaxation::RelaxationData;
use std::path::{Path, PathBuf};

/// Write `fit.svg`, `residuals.svg`, `spectrum.svg`, `dynamic.svg` and the page
/// (`index.md`, `index.html`, `run.json`) into `dir`; returns the HTML page.
pub fn write(
    fit: &RelaxationFit,
    data: &RelaxationData,
    qlv: Option<&QlvInput>,
    dir: &Path,
) -> Result<PathBuf> {
    let pred = predict(fit, data, qlv)?;
    // A relaxation spans decades of time; a load-unload cycle is read on linear time.
    let log_x = !data.strain.as_deref().is_some_and(unloads);
    let idx: Vec<usize> = (0..data.time.len())
        .filter(|&i| !log_x || data.time[i] > 0.0)
        .collect();
    let n = fit.prony.len();
    let fit_chart = Chart {
        title: format!("relaxation: data and {n}-term Prony fit"),
        x_label: "time [s]".into(),
        y_label: "nominal stress [kPa]".into(),
        series: vec![
            Series {
                label: "data".into(),
                points: idx
                    .iter()
                    .map(|&i| (data.time[i], data.stress[i] / 1e3))
                    .collect(),
                color: 0,
                style: Style::Points,
            },
            Series {
                label: format!("Prony fit ({n} terms, {})", fit.formulation),
                points: idx.iter().map(|&i| (data.time[i], pred[i] / 1e3)).collect(),
                color: 1,
                style: Style::Line,
            },
        ],
        log_x,
    };
    let ymax = data.stress.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let scale = |y: f64| match fit.residual {
        Residual::Rel => y.abs().max(REL_FLOOR * ymax),
        Residual::Abs => ymax,
    };
    let residuals_chart = Chart {
        title: match fit.residual {
            Residual::Rel => "relative residuals (model − data) / |data|".into(),
            Residual::Abs => "residuals (model − data) / peak |data|".into(),
        },
        x_label: "time [s]".into(),
        y_label: "residual [%]".into(),
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
    };
    let spectrum_chart = Chart {
        title: "relaxation spectrum".into(),
        x_label: "relaxation time τ [s]".into(),
        y_label: "modulus [kPa]".into(),
        series: vec![
            Series {
                label: "grid NNLS spectrum (stage 1)".into(),
                points: fit
                    .spectrum
                    .iter()
                    .map(|p| (p.tau_s, p.modulus_pa / 1e3))
                    .collect(),
                color: 2,
                style: Style::Line,
            },
            Series {
                label: "fitted Prony terms".into(),
                points: fit
                    .prony
                    .iter()
                    .map(|p| (p.tau_s, p.modulus_pa / 1e3))
                    .collect(),
                color: 1,
                style: Style::Points,
            },
        ],
        log_x: true,
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
    let dynamic_chart = Chart {
        title: "storage and loss moduli (from the fit)".into(),
        x_label: "angular frequency ω [rad/s]".into(),
        y_label: "modulus [kPa]".into(),
        series: vec![
            Series {
                label: "storage E'".into(),
                points: omegas
                    .iter()
                    .zip(&sl)
                    .map(|(w, s)| (*w, s.0 / 1e3))
                    .collect(),
                color: 0,
                style: Style::Line,
            },
            Series {
                label: "loss E''".into(),
                points: omegas
                    .iter()
                    .zip(&sl)
                    .map(|(w, s)| (*w, s.1 / 1e3))
                    .collect(),
                color: 1,
                style: Style::Line,
            },
        ],
        log_x: true,
    };
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
                " ({} points, sha256 {}…); loading: {}.",
                f.points,
                &f.sha256[..12.min(f.sha256.len())],
                fit.loading
            )),
        ]);
    }
    page.status_line(fit.status, fit.status);
    page.chart(dir, "fit.svg", "data and fit", &fit_chart)?;
    page.chart(dir, "residuals.svg", "residuals", &residuals_chart)?;
    page.chart(dir, "spectrum.svg", "spectrum", &spectrum_chart)?;
    page.chart(dir, "dynamic.svg", "storage and loss", &dynamic_chart)?;
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
    page.text(format!(
        "E∞ = {}, E0 = {}, g∞ = {:.4}; RMSE = {}, relative RMSE = {:.3} %, R² = {:.5}, AICc = {}, BIC = {:.2}",
        si(fit.long_term_modulus_pa, "Pa"),
        si(fit.instantaneous_modulus_pa, "Pa"),
        fit.g_inf,
        si(fit.rmse_pa, "Pa"),
        100.0 * fit.rel_rmse,
        fit.r2,
        fit.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
        fit.bic
    ));
    if let Some(sel) = &fit.selection {
        page.heading("Term count");
        page.text(format!("Rule: {}.", sel.rule));
        page.text(format!("Chosen: {}.", sel.reason));
        let rows: Vec<Vec<String>> = sel
            .candidates
            .iter()
            .map(|c| {
                vec![
                    c.terms.to_string(),
                    format!("{:.3} %", 100.0 * c.rel_rmse),
                    format!("{:.2}", c.delta),
                    if c.eligible {
                        "yes".into()
                    } else {
                        c.note.clone().unwrap_or_default()
                    },
                ]
            })
            .collect();
        page.table(&["N", "rel. RMSE", "Δ", "eligible"], rows);
    }
    super::warnings_and_solver(&mut page, &fit.warnings, &fit.solver);
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
