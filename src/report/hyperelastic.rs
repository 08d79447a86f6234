//! Report of a hyperelastic fit: data vs model for every mode on one figure
//! (modes without data drawn dashed as extrapolation), residuals, and a Markdown page.

use super::format::{parameter_cells, si, PARAMETER_HEADER};
use super::page::{code, text, Page};
use super::plot::{Chart, Series, Style};
use super::runs::Run;
use crate::data::Dataset;
use crate::error::Result;
use crate::fit::hyperelastic::HyperelasticFit;
use crate::material::hyperelastic::Mode;
use std::path::{Path, PathBuf};

fn mode_color(m: Mode) -> usize {
    match m {
        Mode::Uniaxial => 0,
        Mode::Equibiaxial => 1,
        Mode::Planar => 2,
    }
}

/// Write `fit.svg`, `residuals.svg` and the page (`index.md`, `index.html`, `run.json`)
/// into `dir`; returns the HTML page.
pub fn write(fit: &HyperelasticFit, data: &Dataset, dir: &Path) -> Result<PathBuf> {
    let model = fit.evaluator()?;
    let p = fit.values();
    let mut series = Vec::new();
    let mut resid = Vec::new();
    let lam_max = data.samples.iter().map(|s| s.stretch).fold(1.0, f64::max);
    for m in Mode::ALL {
        let pts: Vec<(f64, f64)> = data
            .samples
            .iter()
            .filter(|s| s.mode == m)
            .map(|s| (s.stretch, s.stress / 1e6))
            .collect();
        let (lo, hi, style, label) = match data.stretch_range(m) {
            Some((lo, hi)) => (lo.min(1.0), hi, Style::Line, format!("{} {m}", fit.model)),
            None => (
                1.0,
                if m == Mode::Equibiaxial {
                    lam_max.min(4.0)
                } else {
                    lam_max
                },
                Style::Dashed,
                format!("{} {m} (extrapolated, no data)", fit.model),
            ),
        };
        if !pts.is_empty() {
            series.push(Series {
                label: format!("data {m}"),
                points: pts,
                color: mode_color(m),
                style: Style::Points,
            });
            resid.push(Series {
                label: format!("{m}"),
                points: data
                    .samples
                    .iter()
                    .filter(|s| s.mode == m)
                    .map(|s| {
                        (
                            s.stretch,
                            (model.nominal_stress(&p, m, s.stretch) - s.stress) / 1e3,
                        )
                    })
                    .collect(),
                color: mode_color(m),
                style: Style::Points,
            });
        }
        let curve = (0..=200)
            .map(|i| {
                let l = lo + (hi - lo) * i as f64 / 200.0;
                (l, model.nominal_stress(&p, m, l) / 1e6)
            })
            .collect();
        series.push(Series {
            label,
            points: curve,
            color: mode_color(m),
            style,
        });
    }
    let fit_chart = Chart {
        title: format!("{}: data and model", fit.model),
        x_label: "stretch λ".into(),
        y_label: "nominal stress [MPa]".into(),
        series,
        log_x: false,
    };
    let resid_chart = Chart {
        title: format!("{}: residuals (model − data)", fit.model),
        x_label: "stretch λ".into(),
        y_label: "residual [kPa]".into(),
        series: resid,
        log_x: false,
    };
    let mut page = Page::new(format!("Hyperelastic fit: {}", fit.model));
    let files: Vec<String> = fit
        .provenance
        .files
        .iter()
        .map(|f| f.path.clone())
        .collect();
    let mut data_line = vec![text("Data: ")];
    for (i, f) in fit.provenance.files.iter().enumerate() {
        if i > 0 {
            data_line.push(text(", "));
        }
        data_line.push(code(&f.path));
        data_line.push(text(format!(
            " ({} points, sha256 {}…)",
            f.points,
            f.sha256.get(..12).unwrap_or(&f.sha256)
        )));
    }
    page.para(data_line);
    page.status_line(fit.status, fit.status);
    page.chart(dir, "fit.svg", "data and model", &fit_chart)?;
    page.chart(dir, "residuals.svg", "residuals", &resid_chart)?;
    let rows: Vec<Vec<String>> = fit
        .parameters
        .iter()
        .map(|p| {
            let [v, ci] = parameter_cells(p);
            vec![p.name.clone(), v, ci]
        })
        .collect();
    let [hv, hci] = PARAMETER_HEADER;
    page.table(&["parameter", hv, hci], rows);
    let r2 = fit.r2.map(|v| format!("{v:.5}")).unwrap_or("n/a".into());
    page.text(format!(
        "μ0 = {}, RMSE = {}, R² = {r2}, %RMSE (seed Eq. 3.28) = {}, AICc = {}, BIC = {:.2}",
        si(fit.initial_shear_modulus_pa, "Pa"),
        si(fit.rmse_pa, "Pa"),
        fit.rmse_pct
            .map(|v| format!("{v:.3} %"))
            .unwrap_or("n/a".into()),
        fit.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
        fit.bic
    ));
    page.heading("Drucker stability (stretch 0.1–10)");
    page.bullets(fit.drucker.iter().map(|d| {
        format!(
            "{}: {} (stable {:.3}–{:.3})",
            d.mode,
            if d.stable { "stable" } else { "UNSTABLE" },
            d.stretch_min,
            d.stretch_max
        )
    }));
    if let Some(sel) = &fit.selection {
        page.heading("Model selection");
        page.text(format!("Rule: {}.", sel.rule));
        page.text(format!("Chosen: {}.", sel.reason));
        let rows: Vec<Vec<String>> = sel
            .candidates
            .iter()
            .map(|c| {
                vec![
                    c.model.clone(),
                    c.k.to_string(),
                    si(c.rmse_pa, "Pa"),
                    c.r2.map(|v| format!("{v:.5}")).unwrap_or("n/a".into()),
                    c.delta_aicc
                        .map(|v| format!("{v:.2}"))
                        .unwrap_or("n/a".into()),
                    c.status.to_string(),
                    if c.eligible { "yes" } else { "no" }.to_string(),
                ]
            })
            .collect();
        page.table(
            &["model", "k", "RMSE", "R²", "ΔAICc", "status", "eligible"],
            rows,
        );
    }
    super::warnings_and_solver(&mut page, &fit.warnings, &fit.solver);
    let run = Run::new("hyperelastic", files.join(", "), fit.model.clone()).headline(vec![
        format!("μ0 {}", si(fit.initial_shear_modulus_pa, "Pa")),
        format!("RMSE {}", si(fit.rmse_pa, "Pa")),
        format!("R² {r2}"),
    ]);
    page.write(dir, "index", run)
}
