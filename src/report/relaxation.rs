//! Report of a relaxation fit: data and model on log time (linear time for a history
//! that unloads), the residuals the fit minimised, the
//! relaxation spectrum (grid NNLS and the fitted terms), storage and loss moduli
//! against frequency, and a Markdown page.

use super::format::{si, table};
use super::plot::{Chart, Series, Style};
use crate::error::Result;
use crate::fit::problem::{Residual, REL_FLOOR};
use crate::fit::relaxation::{predict, unloads, QlvInput, RelaxationFit};
use crate::io::relaxation::RelaxationData;
use crate::io::write::atomic_write;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Write `fit.svg`, `residuals.svg`, `spectrum.svg`, `dynamic.svg` and `index.md` into
/// `dir`; returns the page.
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
    Chart {
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
    }
    .write_svg(&dir.join("fit.svg"))?;
    let ymax = data.stress.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let scale = |y: f64| match fit.residual {
        Residual::Rel => y.abs().max(REL_FLOOR * ymax),
        Residual::Abs => ymax,
    };
    Chart {
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
    }
    .write_svg(&dir.join("residuals.svg"))?;
    Chart {
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
    }
    .write_svg(&dir.join("spectrum.svg"))?;
    let prony = fit.prony_series()?;
    let (lo, hi) = (
        1.0 / fit.time_window_s[1] / 10.0,
        10.0 / fit.time_window_s[0],
    );
    let omegas: Vec<f64> = (0..=120)
        .map(|i| lo * (hi / lo).powf(i as f64 / 120.0))
        .collect();
    let sl: Vec<(f64, f64)> = omegas.iter().map(|&w| prony.storage_loss(w)).collect();
    Chart {
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
    }
    .write_svg(&dir.join("dynamic.svg"))?;
    let page = dir.join("index.md");
    atomic_write(&page, markdown(fit).as_bytes())?;
    Ok(page)
}

/// The Markdown summary of a relaxation fit.
pub fn markdown(fit: &RelaxationFit) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Relaxation fit: {} Prony terms ({} formulation)\n",
        fit.prony.len(),
        fit.formulation
    );
    for f in &fit.provenance.files {
        let _ = writeln!(
            s,
            "Data: `{}` ({} points, sha256 {}…); loading: {}.\n",
            f.path,
            f.points,
            &f.sha256[..12.min(f.sha256.len())],
            fit.loading
        );
    }
    let _ = writeln!(s, "Status: **{}**\n", fit.status);
    let _ = writeln!(
        s,
        "![data and fit](fit.svg)\n\n![residuals](residuals.svg)\n\n![spectrum](spectrum.svg)\n\n![storage and loss](dynamic.svg)\n"
    );
    let rows: Vec<Vec<String>> = fit
        .prony
        .iter()
        .map(|p| {
            vec![
                si(p.tau_s, "s"),
                p.tau_std_s.map(|e| si(e, "s")).unwrap_or("n/a".into()),
                si(p.modulus_pa, "Pa"),
                p.modulus_std_pa
                    .map(|e| si(e, "Pa"))
                    .unwrap_or("n/a".into()),
                format!("{:.4}", p.g),
                si(p.modulus_pa * p.tau_s, "Pa·s"),
            ]
        })
        .collect();
    let _ = writeln!(
        s,
        "```\n{}```\n",
        table(&["τ", "σ(τ)", "E = k", "σ(E)", "g", "n = k·τ"], &rows)
    );
    let _ = writeln!(
        s,
        "E∞ = {}, E0 = {}, g∞ = {:.4}; RMSE = {}, relative RMSE = {:.3} %, R² = {:.5}, AICc = {}, BIC = {:.2}\n",
        si(fit.long_term_modulus_pa, "Pa"),
        si(fit.instantaneous_modulus_pa, "Pa"),
        fit.g_inf,
        si(fit.rmse_pa, "Pa"),
        100.0 * fit.rel_rmse,
        fit.r2,
        fit.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
        fit.bic
    );
    if let Some(sel) = &fit.selection {
        let _ = writeln!(
            s,
            "## Term count\n\nRule: {}.\n\nChosen: {}.\n",
            sel.rule, sel.reason
        );
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
        let _ = writeln!(
            s,
            "```\n{}```",
            table(&["N", "rel. RMSE", "Δ", "eligible"], &rows)
        );
    }
    s.push_str(&super::warnings_and_solver(&fit.warnings, &fit.solver));
    s
}
