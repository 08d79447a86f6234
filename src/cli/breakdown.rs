//! `dea-fit breakdown`: the Weibull α and β of a breakdown series (docs/breakdown.md),
//! with bounds and percentiles, at the specimens' and at the actuator's electrode area.

use super::Output;
use clap::ValueEnum;
use dea_fit::error::Location;
use dea_fit::fit::weibull::{self, Covariate, Method, Positions, Settings, Specimen};
use dea_fit::io::breakdown::{
    self as reader, BreakdownOptions, BreakdownSeries, BreakdownSpecimen,
};
use dea_fit::report::breakdown::{result, summary, write, BreakdownResult};
use dea_fit::units::{parse_quantity, Dimension};
use dea_fit::{Error, Result};
use serde::Serialize;
use std::path::PathBuf;

/// Estimator.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum MethodArg {
    /// Maximum likelihood with right censoring (default).
    Mle,
    /// Rank regression of y = ln(−ln(1 − F)) on ln E.
    Rry,
    /// Rank regression of ln E on y.
    Rrx,
}

/// Plotting position.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum PositionsArg {
    /// (i − 0.3)/(n + 0.4), Bernard's median-rank approximation (default).
    Bernard,
    /// The exact median rank (inverse incomplete beta).
    Exact,
    /// (i − 0.44)/(n + 0.25), IEEE Std 930.
    Ieee930,
}

/// Covariate of α.
#[derive(Debug, Clone, Copy, PartialEq, ValueEnum)]
enum CovariateArg {
    /// Film thickness h: α ∝ h^a.
    Thickness,
    /// Prestretch λ: α ∝ λ^b.
    Prestretch,
}

/// Weibull analysis of a breakdown series: α, β, percentiles and bounds, a fit
/// file for scenes and the ranking, a report with the probability plot.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Breakdown series (CSV, one specimen a row: field_V_per_um or voltage_kV with
    /// thickness_um; optional survived, area_mm2, prestretch, specimen). Several
    /// files are one series.
    files: Vec<PathBuf>,
    /// Estimator.
    #[arg(long, value_enum, default_value = "mle")]
    method: MethodArg,
    /// Plotting position of a rank regression and of the probability plot.
    #[arg(long, value_enum, default_value = "bernard")]
    positions: PositionsArg,
    /// Fit a threshold field γ too (three-parameter Weibull; unstable, said in the output).
    #[arg(long)]
    threshold: bool,
    /// Covariates of α, comma-separated (thickness, prestretch): α = C·h^a·λ^b, common β.
    #[arg(long, value_enum, value_delimiter = ',')]
    covariates: Vec<CovariateArg>,
    /// Film thickness of every specimen, e.g. 300um (for a voltage column).
    #[arg(long)]
    thickness: Option<String>,
    /// Electrode area of every specimen, e.g. 1cm2 (else an area_mm2 column).
    #[arg(long)]
    specimen_area: Option<String>,
    /// The actuator's electrode area, e.g. 40cm2: α and percentiles there (weakest link).
    #[arg(long)]
    area: Option<String>,
    #[command(flatten)]
    output: Output,
}

/// What `--json` prints: the fit file's object and where it went.
#[derive(Serialize)]
struct Printed<'a> {
    #[serde(flatten)]
    result: &'a BreakdownResult,
    fit_file: String,
}

/// A positive quantity of a flag, SI.
fn positive(flag: &str, text: Option<&str>, dim: Dimension) -> Result<Option<f64>> {
    text.map(|t| match parse_quantity(t, dim) {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(v) => Err(Error::settings(format!("{flag} must be > 0, found {v}"))),
        Err(e) => Err(Error::settings(format!("{flag}: {e}"))),
    })
    .transpose()
}

/// The estimator's settings of the flags.
fn settings(a: &Args) -> Settings {
    Settings {
        method: match a.method {
            MethodArg::Mle => Method::Mle,
            MethodArg::Rry => Method::Rry,
            MethodArg::Rrx => Method::Rrx,
        },
        positions: match a.positions {
            PositionsArg::Bernard => Positions::Bernard,
            PositionsArg::Exact => Positions::Exact,
            PositionsArg::Ieee930 => Positions::Ieee930,
        },
        threshold: a.threshold,
        covariates: a
            .covariates
            .iter()
            .map(|c| match c {
                CovariateArg::Thickness => Covariate::Thickness,
                CovariateArg::Prestretch => Covariate::Prestretch,
            })
            .collect(),
        ..Settings::default()
    }
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    if a.files.is_empty() {
        return Err(Error::settings("no breakdown series given")
            .with_hint("dea-fit breakdown series.csv   (make one with dea-fit synth breakdown)"));
    }
    let opts = BreakdownOptions {
        thickness: positive("--thickness", a.thickness.as_deref(), Dimension::Length)?,
        area: positive(
            "--specimen-area",
            a.specimen_area.as_deref(),
            Dimension::Area,
        )?,
    };
    let area = positive("--area", a.area.as_deref(), Dimension::Area)?;
    let settings = settings(&a);
    let o = &a.output;
    let name = format!("{}-breakdown", super::data_name(&a.files[0], "series"));
    let (out, dir) = o.paths(&name);
    super::refuse_in_report(dir.as_deref(), &[("--out", Some(&out))])?;
    let series = a
        .files
        .iter()
        .map(|f| reader::read(f, &opts))
        .collect::<Result<Vec<BreakdownSeries>>>()?;
    let specimens: Vec<Specimen> = series
        .iter()
        .flat_map(|s| &s.specimens)
        .map(BreakdownSpecimen::weibull)
        .collect();
    let fit = weibull::fit(&specimens, &settings).map_err(|e| located(e, &series))?;
    if area.is_some() && fit.reference_area.is_none() {
        return Err(
            Error::settings("--area needs the specimens' electrode area to scale from")
                .with_hint("give it with --specimen-area (e.g. 1cm2) or an area_mm2 column"),
        );
    }
    let provenance = serde_json::json!({
        "files": series.iter().map(|s| serde_json::json!({
            "path": s.path.display().to_string(),
            "sha256": s.sha256,
            "specimens": s.specimens.len(),
        })).collect::<Vec<_>>(),
        "settings": {
            "method": settings.method.name(),
            "positions": settings.positions.name(),
            "threshold": settings.threshold,
            "covariates": settings.covariates.iter().map(|c| c.name()).collect::<Vec<_>>(),
            "thickness_m": opts.thickness,
            "specimen_area_m2": opts.area,
            "actuator_area_m2": area,
        },
    });
    let r = result(&fit, &series, area, provenance)?;
    let json = serde_json::to_string_pretty(&r).expect("a breakdown fit serialises");
    if let Some(d) = &dir {
        super::claim_dir(d)?;
    }
    super::write_fit_noted(&out, json.as_bytes(), |old| same(old, &r))?;
    let page = dir.map(|d| write(&r, &fit, &series, &d)).transpose()?;
    if o.json {
        let p = Printed {
            result: &r,
            fit_file: out.display().to_string(),
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&p).expect("a breakdown fit serialises")
        );
    } else {
        print!("{}", summary(&r, &series)?);
        println!("fit: {}", out.display());
        if let Some(p) = &page {
            println!("report: {}", p.display());
        }
    }
    Ok(fit.status.exit_code(o.strict))
}

/// The estimator's refusal, at the file and line of the specimen it names.
fn located(e: weibull::WeibullError, series: &[BreakdownSeries]) -> Error {
    let hint = e.hint();
    let at = e.specimen().and_then(|i| {
        series
            .iter()
            .flat_map(|s| s.specimens.iter().map(move |x| (&s.path, x.line)))
            .nth(i)
    });
    match at {
        Some((path, line)) => Error::input(Location::line(path, line), e.to_string()),
        None => Error::settings(e.to_string()),
    }
    .with_hint(hint)
}

/// The file holds this very fit: same inputs, settings and estimates.
fn same(old: &str, new: &BreakdownResult) -> bool {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    serde_json::from_str::<BreakdownResult>(old).is_ok_and(|o| {
        o.fit.provenance == new.fit.provenance
            && o.fit.parameters.len() == new.fit.parameters.len()
            && o.fit
                .parameters
                .iter()
                .zip(&new.fit.parameters)
                .all(|(a, b)| a.name == b.name && close(a.value, b.value))
    })
}
