//! `dea-fit relaxation`: Prony / Kelvin-Maxwell constants from a stress-relaxation curve.

use super::Output;
use clap::ValueEnum;
use dea_fit::fit::problem::Residual;
use dea_fit::fit::relaxation::{
    self, Criterion, FileRef, Loading, Method, QlvInput, RelaxationFit, Settings,
};
use dea_fit::io::relaxation::{self as reader, RelaxationOptions};
use dea_fit::material::viscoelastic::{preset, Preset};
use dea_fit::report::format::{si, si_pm, table};
use dea_fit::units::{parse_quantity, Dimension};
use dea_fit::{Error, Result};
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ResidualArg {
    Auto,
    Rel,
    Abs,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum CriterionArg {
    Aicc,
    Bic,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum MethodArg {
    Refined,
    Grid,
}

/// Fit a Prony series (and the seed's Kelvin-Maxwell arms) to a relaxation curve:
/// stress or force against time at a held strain.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Relaxation test file (CSV: time_s|ms|min, stress_Pa|kPa|MPa or force_N,
    /// optionally strain|strain_pct|stretch recording the loading).
    file: Option<PathBuf>,
    /// Held engineering strain ε0 (modulus = stress/ε0 after a step).
    #[arg(long, conflicts_with = "stretch")]
    strain: Option<f64>,
    /// Held stretch λ0 = 1 + ε0.
    #[arg(long)]
    stretch: Option<f64>,
    /// Duration of the linear loading ramp from t = 0, e.g. 0.8s or 800ms (bare: s).
    #[arg(long, value_name = "TIME")]
    ramp_time: Option<String>,
    /// Reference cross-section for force columns, e.g. 22mm2 (bare number: m²).
    #[arg(long)]
    area: Option<String>,
    /// Hyperelastic fit file: fit the QLV relaxation function whose instantaneous
    /// response is this fit's uniaxial stress.
    #[arg(long, value_name = "FIT")]
    hyperelastic: Option<PathBuf>,
    /// Number of Prony terms, or auto (the fewest the data support).
    #[arg(long, default_value = "auto")]
    terms: String,
    /// Largest term count auto tries.
    #[arg(long, default_value_t = 6)]
    max_terms: usize,
    /// Score of the automatic choice.
    #[arg(long, value_enum, default_value = "aicc")]
    criterion: CriterionArg,
    /// Auto: the fewest terms whose relative RMSE is at most this (e.g. 0.01 or 1%).
    #[arg(long)]
    tolerance: Option<String>,
    /// Residuals: auto (default: rel for a held strain, so the long-time tail counts;
    /// abs for a recorded history that unloads, e.g. a load-unload cycle), rel or abs.
    #[arg(long, value_enum, default_value = "auto")]
    residual: ResidualArg,
    /// Method: refined (grid NNLS + LM) or grid (grid NNLS only).
    #[arg(long, value_enum, default_value = "refined")]
    method: MethodArg,
    /// τ grid points per decade of the NNLS stage.
    #[arg(long, default_value_t = 6)]
    grid_per_decade: usize,
    /// Print a preset's constants and predictions instead of fitting
    /// (seed-table-3.3, seed-table-4.2).
    #[arg(long, value_name = "NAME")]
    preset: Option<String>,
    #[command(flatten)]
    output: Output,
}

fn settings(a: &Args) -> Result<Settings> {
    let terms = match a.terms.trim() {
        "auto" => None,
        t => Some(t.parse::<usize>().map_err(|_| {
            Error::settings(format!("--terms: expected a number or auto, found '{t}'"))
        })?),
    };
    let tolerance = a
        .tolerance
        .as_deref()
        .map(|t| {
            let t = t.trim();
            let (v, f) = match t.strip_suffix('%') {
                Some(p) => (p.trim(), 0.01),
                None => (t, 1.0),
            };
            v.parse::<f64>().map(|v| v * f).map_err(|_| {
                Error::settings(format!(
                    "--tolerance: expected e.g. 0.01 or 1%, found '{t}'"
                ))
            })
        })
        .transpose()?;
    Ok(Settings {
        terms,
        max_terms: a.max_terms,
        criterion: match a.criterion {
            CriterionArg::Aicc => Criterion::Aicc,
            CriterionArg::Bic => Criterion::Bic,
        },
        tolerance,
        residual: match a.residual {
            ResidualArg::Auto => None,
            ResidualArg::Rel => Some(Residual::Rel),
            ResidualArg::Abs => Some(Residual::Abs),
        },
        method: match a.method {
            MethodArg::Refined => Method::Refined,
            MethodArg::Grid => Method::Grid,
        },
        grid_per_decade: a.grid_per_decade,
        ..Settings::default()
    })
}

fn quantity(flag: &str, text: Option<&str>, dim: Dimension) -> Result<Option<f64>> {
    let v = text
        .map(|s| parse_quantity(s, dim))
        .transpose()
        .map_err(|e| Error::settings(format!("{flag}: {e}")))?;
    if let Some(v) = v.filter(|v| v.is_nan() || *v <= 0.0) {
        return Err(Error::settings(format!("{flag} must be > 0, found {v}")));
    }
    Ok(v)
}

/// The hyperelastic material of a QLV run (a hyperelastic fit or an identified
/// material), read by parameter name and checked against its model
/// (`material::file`), with its checksum for the provenance.
fn load_qlv(path: &Path) -> Result<QlvInput> {
    let fit = dea_fit::material::file::read_hyperelastic(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(QlvInput {
        fit,
        file: FileRef {
            path: path.display().to_string(),
            sha256: dea_fit::io::sha256_hex(&bytes),
        },
    })
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    if let Some(name) = &a.preset {
        let p = preset(name)?;
        if a.output.json {
            println!(
                "{}",
                serde_json::to_string_pretty(&p).expect("a preset serialises")
            );
        } else {
            print!("{}", preset_summary(&p));
        }
        return Ok(0);
    }
    let Some(file) = a.file.clone() else {
        return Err(Error::settings("no data file given")
            .with_hint("dea-fit relaxation test.csv --strain 0.5   (or --preset seed-table-3.3)"));
    };
    let settings = settings(&a)?;
    let area = quantity("--area", a.area.as_deref(), Dimension::Area)?;
    let ramp_time = quantity("--ramp-time", a.ramp_time.as_deref(), Dimension::Time)?;
    let strain = match (a.strain, a.stretch) {
        (Some(e), _) => Some(e),
        (None, Some(l)) if l > 0.0 => Some(l - 1.0),
        (None, Some(l)) => {
            return Err(Error::settings(format!("--stretch must be > 0, found {l}")))
        }
        (None, None) => None,
    };
    let data = reader::read(&file, &RelaxationOptions { area })?;
    let qlv = a.hyperelastic.as_deref().map(load_qlv).transpose()?;
    let loading = Loading { strain, ramp_time };
    let fit = relaxation::fit(&data, &loading, qlv.as_ref(), &settings)?;
    let stem = {
        let s = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "relaxation".into());
        match file.parent().and_then(|p| p.file_name()) {
            Some(d) => format!("{}-{s}", d.to_string_lossy()),
            None => s,
        }
    };
    let name = format!(
        "{stem}-{}{}",
        if qlv.is_some() { "qlv" } else { "prony" },
        fit.prony.len()
    );
    a.output.deliver(
        &name,
        &fit,
        fit.status,
        |old| same_fit(old, &fit),
        || summary(&fit),
        |dir| dea_fit::report::relaxation::write(&fit, &data, qlv.as_ref(), dir),
    )
}

/// Same formulation, inputs and constants: the file holds this very fit.
fn same_fit(old: &str, new: &RelaxationFit) -> bool {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    serde_json::from_str::<RelaxationFit>(old).is_ok_and(|o| {
        o.formulation == new.formulation
            && o.provenance.files == new.provenance.files
            && o.provenance.hyperelastic_fit == new.provenance.hyperelastic_fit
            && o.prony.len() == new.prony.len()
            && close(o.long_term_modulus_pa, new.long_term_modulus_pa)
            && o.prony
                .iter()
                .zip(&new.prony)
                .all(|(a, b)| close(a.tau_s, b.tau_s) && close(a.modulus_pa, b.modulus_pa))
    })
}

/// The human-readable summary printed by `dea-fit relaxation`.
pub fn summary(fit: &RelaxationFit) -> String {
    let mut s = String::new();
    for f in &fit.provenance.files {
        s.push_str(&format!(
            "data: {} ({} points, t {}–{})\n",
            f.path,
            f.points,
            si(f.time_min_s, "s"),
            si(f.time_max_s, "s")
        ));
    }
    s.push_str(&format!(
        "loading: {}; formulation: {}; residuals: {}\n",
        fit.loading,
        fit.formulation,
        match fit.residual {
            Residual::Rel => "relative",
            Residual::Abs => "absolute",
        }
    ));
    if let Some(sel) = &fit.selection {
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
                    if c.eligible {
                        "yes".into()
                    } else {
                        format!("no: {}", c.note.clone().unwrap_or_default())
                    },
                ]
            })
            .collect();
        s.push_str("\nterm-count comparison\n");
        s.push_str(&table(
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
            &rows,
        ));
        s.push_str(&format!("chosen: {}\n", sel.reason));
    }
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
    s.push_str(&format!("\nProny series ({} terms)\n", fit.prony.len()));
    s.push_str(&table(
        &["τ ± std. error", "E ± std. error", "g", "arm n = E·τ"],
        &rows,
    ));
    s.push_str(&format!(
        "E∞ {}  E0 {}  g∞ {:.4}  RMSE {}  rel. RMSE {:.3} %  R² {:.5}  AICc {}  BIC {:.2}\n",
        si(fit.long_term_modulus_pa, "Pa"),
        si(fit.instantaneous_modulus_pa, "Pa"),
        fit.g_inf,
        si(fit.rmse_pa, "Pa"),
        100.0 * fit.rel_rmse,
        fit.r2,
        fit.aicc.map(|v| format!("{v:.2}")).unwrap_or("n/a".into()),
        fit.bic
    ));
    if let Some(q) = &fit.qlv {
        s.push_str(&format!(
            "QLV: instantaneous response = {:.4} × {} (3μ0 = {}); moduli are g × E0\n",
            q.instantaneous_scale,
            q.hyperelastic_model,
            si(q.reference_modulus_pa, "Pa")
        ));
    }
    s.push_str(&super::solver_and_status(
        &fit.solver,
        fit.status,
        &fit.warnings,
        true,
    ));
    s
}

/// A preset's constants and a few predictions.
fn preset_summary(p: &Preset) -> String {
    let mut s = format!(
        "preset {} ({} formulation)\nsource: {}\nreference modulus {}\n",
        p.name,
        p.formulation,
        p.source,
        si(p.reference_modulus, "Pa")
    );
    let (_, g) = p.prony.normalized();
    let rows: Vec<Vec<String>> = p
        .prony
        .terms
        .iter()
        .zip(&g)
        .zip(&p.kelvin_maxwell.arms)
        .map(|((t, g), arm)| {
            vec![
                si(t.tau, "s"),
                si(t.modulus, "Pa"),
                format!("{g:.4}"),
                si(arm.k, "Pa"),
                si(arm.n, "Pa·s"),
            ]
        })
        .collect();
    s.push_str(&table(&["τ", "E", "g", "k", "n"], &rows));
    s.push_str(&format!(
        "E∞ {}  E0 {}  Nv {}\n",
        si(p.prony.e_inf, "Pa"),
        si(p.prony.instantaneous(), "Pa"),
        si(p.kelvin_maxwell.n_v, "Pa·s")
    ));
    let creep = p.kelvin_maxwell.creep().ok();
    let rows: Vec<Vec<String>> = [0.01, 0.1, 1.0, 10.0, 100.0, 1000.0]
        .iter()
        .map(|&t: &f64| {
            let (e1, e2) = p
                .kelvin_maxwell
                .storage_loss(1.0 / t)
                .unwrap_or((f64::NAN, f64::NAN));
            vec![
                si(t, "s"),
                si(p.prony.relaxation_modulus(t), "Pa"),
                creep
                    .as_ref()
                    .map(|c| format!("{:.4e}", c.compliance(t)))
                    .unwrap_or("n/a".into()),
                si(1.0 / t, "rad/s"),
                si(e1, "Pa"),
                si(e2, "Pa"),
            ]
        })
        .collect();
    s.push_str(&table(
        &["t", "E(t)", "J(t) [1/Pa]", "ω = 1/t", "E'", "E''"],
        &rows,
    ));
    s
}
