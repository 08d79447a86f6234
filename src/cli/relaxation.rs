//! `dea-fit relaxation`: Prony / Kelvin-Maxwell constants from a stress-relaxation curve.

use super::Output;
use clap::ValueEnum;
use dea_fit::fit::problem::Residual;
use dea_fit::fit::relaxation::{
    self, Criterion, FileRef, Loading, Method, QlvInput, RelaxationFit, Settings,
};
use dea_fit::io::relaxation::{self as reader, RelaxationOptions};
use dea_fit::io::table::ColumnMap;
use dea_fit::material::viscoelastic::{preset, Preset};
use dea_fit::report::format::{si, table};
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

/// Fit a Prony series (and the Kelvin-Maxwell arms of El Atrache Ceballos (2021)) to a relaxation curve:
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
    /// Name the columns of a testing machine's export: ROLE=COLUMN[:UNIT],… (roles
    /// time, stress, force, strain, stretch), e.g. time=Time:s,force=Load:N; or a
    /// file of ROLE = COLUMN[:UNIT] lines.
    #[arg(long, value_name = "MAP")]
    columns: Option<String>,
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
    /// (elatrache2021-table-3.3, elatrache2021-table-4.2).
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
        return Err(Error::settings("no data file given").with_hint(
            "dea-fit relaxation test.csv --strain 0.5   (or --preset elatrache2021-table-3.3)",
        ));
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
    let map = a
        .columns
        .as_deref()
        .map(|m| ColumnMap::parse(m, reader::ROLES))
        .transpose()?
        .unwrap_or_default();
    let data = reader::read_with(&file, &RelaxationOptions { area }, &map)?;
    let qlv = a.hyperelastic.as_deref().map(load_qlv).transpose()?;
    let loading = Loading { strain, ramp_time };
    let fit = relaxation::fit(&data, &loading, qlv.as_ref(), &settings)?;
    let stem = super::data_name(&file, "relaxation");
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
        || dea_fit::report::relaxation::summary(&fit),
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
