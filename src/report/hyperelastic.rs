//! Report of a hyperelastic fit: data vs model for every mode on one figure
//! (modes without data drawn dashed as extrapolation), residuals, and a Markdown page.

use super::format::{parameter_cells, si, PARAMETER_HEADER};
use super::page::{code, text, Page};
use super::plot::{band, Chart, Series, Style, BAND_LABEL};
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
    let mut bands = 0;
    let lam_max = data.samples.iter().map(|s| s.stretch).fold(1.0, f64::max);
    for m in Mode::ALL {
        let pts: Vec<(f64, f64)> = data
            .samples
            .iter()
            .filter(|s| s.mode == m)
            .map(|s| (s.stretch, s.stress))
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
                    .map(|s| (s.stretch, model.nominal_stress(&p, m, s.stretch) - s.stress))
                    .collect(),
                color: mode_color(m),
                style: Style::Points,
            });
        }
        let stretches: Vec<f64> = (0..=200)
            .map(|i| lo + (hi - lo) * i as f64 / 200.0)
            .collect();
        let stress: Vec<f64> = stretches
            .iter()
            .map(|&l| model.nominal_stress(&p, m, l))
            .collect();
        if let Some(std) = fit.stress_std(m, &stretches) {
            let (down, up): (Vec<f64>, Vec<f64>) =
                stress.iter().zip(&std).map(|(s, d)| (s - d, s + d)).unzip();
            series.push(Series {
                // one legend entry for the bands of every mode
                label: match bands {
                    0 => BAND_LABEL.into(),
                    _ => String::new(),
                },
                points: band(&stretches, &down, &up),
                color: mode_color(m),
                style: Style::Band,
            });
            bands += 1;
        }
        let curve = stretches.iter().copied().zip(stress).collect();
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
        y_label: "nominal stress".into(),
        series,
        log_x: false,
        x_unit: None,
        y_unit: Some("Pa".into()),
    };
    let resid_chart = Chart {
        title: format!("{}: residuals (model − data)", fit.model),
        x_label: "stretch λ".into(),
        y_label: "residual".into(),
        series: resid,
        log_x: false,
        x_unit: None,
        y_unit: Some("Pa".into()),
    };
    let page = page(fit, |page| {
        page.chart(dir, "fit.svg", "data and model", &fit_chart)?;
        if bands == 0 {
            page.text("No confidence band: a parameter has no standard error (see the warnings).");
        }
        page.chart(dir, "residuals.svg", "residuals", &resid_chart)
    })?;
    let files: Vec<&str> = fit
        .provenance
        .files
        .iter()
        .map(|f| f.path.as_str())
        .collect();
    let run = Run::new("hyperelastic", files.join(", "), fit.model.clone()).headline(vec![
        format!("μ0 {}", si(fit.initial_shear_modulus_pa, "Pa")),
        format!("RMSE {}", si(fit.rmse_pa, "Pa")),
        format!("R² {}", r2(fit)),
    ]);
    page.write(dir, "index", run)
}

/// The summary `dea-fit hyperelastic` prints: the report's page without its charts.
pub fn summary(fit: &HyperelasticFit) -> Result<String> {
    Ok(page(fit, |_| Ok(()))?.terminal())
}

fn r2(fit: &HyperelasticFit) -> String {
    fit.r2.map(|v| format!("{v:.5}")).unwrap_or("n/a".into())
}

/// The one rendering of a hyperelastic fit (the terminal, Markdown and HTML all
/// show this page): data, status, `charts` (added by the report), model selection,
/// parameters, statistics, Drucker stability, warnings and solver.
fn page(fit: &HyperelasticFit, charts: impl FnOnce(&mut Page) -> Result<()>) -> Result<Page> {
    let mut page = Page::new(format!(
        "Hyperelastic fit: {}{}",
        fit.model,
        fit.form.map(|f| format!(" ({f} form)")).unwrap_or_default()
    ));
    for f in &fit.provenance.files {
        let modes: Vec<String> = f.modes.iter().map(|m| m.to_string()).collect();
        page.para(vec![
            text("Data: "),
            code(&f.path),
            text(format!(
                " ({}, {} points, λ {:.3}–{:.3}, sha256 {}…)",
                modes.join("+"),
                f.points,
                f.stretch_min,
                f.stretch_max,
                f.sha256.get(..12).unwrap_or(&f.sha256)
            )),
        ]);
    }
    page.status_line(fit.status, fit.status);
    charts(&mut page)?;
    if let Some(sel) = &fit.selection {
        page.heading("Model selection");
        page.text(format!("Rule: {}.", sel.rule));
        let rows: Vec<Vec<String>> = sel
            .candidates
            .iter()
            .map(|c| {
                vec![
                    c.model.clone(),
                    c.k.to_string(),
                    si(c.rmse_pa, "Pa"),
                    c.r2.map(|v| format!("{v:.5}")).unwrap_or("n/a".into()),
                    c.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
                    c.delta_aicc
                        .map(|v| format!("{v:.2}"))
                        .unwrap_or("n/a".into()),
                    format!("{:.2}", c.bic),
                    c.status.to_string(),
                    if c.eligible { "yes" } else { "no" }.to_string(),
                ]
            })
            .collect();
        page.table(
            &[
                "model", "k", "RMSE", "R²", "AICc", "ΔAICc", "BIC", "status", "eligible",
            ],
            rows,
        );
        page.text("ΔAICc: AICc minus the smallest AICc of the models compared.");
        page.text(format!("Chosen: {}.", sel.reason));
    }
    page.heading("Parameters");
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
    page.text(format!(
        "μ0 {}  RMSE {}",
        si(fit.initial_shear_modulus_pa, "Pa"),
        si(fit.rmse_pa, "Pa"),
    ));
    page.text(format!(
        "R² {}  %RMSE (El Atrache Ceballos (2021) Eq. 3.28) {}  AICc {}  BIC {:.2}",
        r2(fit),
        fit.rmse_pct
            .map(|v| format!("{v:.3} %"))
            .unwrap_or("n/a".into()),
        fit.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
        fit.bic
    ));
    page.heading("Drucker stability (λ 0.1–10)");
    page.bullets(fit.drucker.iter().map(|d| match d.stable {
        true => format!("{}: stable", d.mode),
        false => format!(
            "{}: stable only for λ {:.3}–{:.3}",
            d.mode, d.stretch_min, d.stretch_max
        ),
    }));
    let tested: Vec<String> = fit
        .per_mode
        .iter()
        .filter_map(|s| {
            let l = s.lack_of_fit?;
            Some(format!(
                "{}: {} runs where {:.1} are expected of noise (z = {:.2}, p = {:.1e}){}{}",
                s.mode,
                l.runs.runs,
                l.runs.expected_runs,
                l.runs.z,
                l.runs.p,
                l.noise_pa
                    .filter(|n| *n > 0.0)
                    .map(|n| format!(", RMSE {:.1} × the noise σ", s.rmse_pa / n))
                    .unwrap_or_default(),
                if l.lacks_fit { ": lack of fit" } else { "" }
            ))
        })
        .collect();
    if !tested.is_empty() {
        page.heading("Lack of fit (runs test of the residual signs)");
        page.bullets(tested);
    }
    super::warnings_and_solver(&mut page, &fit.warnings, &fit.solver);
    Ok(page)
}
