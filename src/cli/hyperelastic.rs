//! `dea-fit hyperelastic`: fit strain-energy coefficients to tensile-test files.

use super::Output;
use clap::ValueEnum;
use dea_fit::data::Dataset;
use dea_fit::fit::hyperelastic::{self, Branch, HyperelasticFit, Sanity, Settings};
use dea_fit::fit::problem::Residual;
use dea_fit::io::table::ColumnMap;
use dea_fit::io::tensile::{self, TensileOptions};
use dea_fit::material::hyperelastic::{Mode, ModelSpec, OgdenForm};
use dea_fit::units::{parse_quantity, CountRange, Dimension};
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// `--max-starts`: a model has at most a few hundred multi-start points.
const STARTS: CountRange = CountRange::new(1, 100_000, "multi-start points to use");

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Form {
    /// 2μ/α², the form of Abaqus and CalculiX.
    Abaqus,
    Original,
    /// `abaqus` by its former name: hidden, still accepted, with a note.
    #[value(hide = true)]
    Seed,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum BranchArg {
    Loading,
    Unloading,
    All,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ResidualArg {
    Abs,
    Rel,
}

/// Fit hyperelastic coefficients. Positional files are uniaxial unless the file says
/// otherwise (a `mode` column or a `# mode: …` comment).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Test files (CSV; uniaxial unless they say otherwise).
    files: Vec<PathBuf>,
    /// Equibiaxial test file(s).
    #[arg(long, value_name = "FILE")]
    equibiaxial: Vec<PathBuf>,
    /// Planar (pure shear) test file(s).
    #[arg(long, value_name = "FILE")]
    planar: Vec<PathBuf>,
    /// Model: neo-hookean, mooney-rivlin, yeoh, gent, ogden1..ogden4, or auto.
    #[arg(long, default_value = "auto")]
    model: String,
    /// Ogden coefficient form: abaqus (El Atrache Ceballos (2021) Eq. 2.9, 2μ/α², the
    /// form of Abaqus and CalculiX) or original (Ogden 1972, μ/α).
    #[arg(long, value_enum, default_value = "abaqus")]
    ogden_form: Form,
    /// Residuals: abs (Pa; default, load-cell noise is absolute) or rel.
    #[arg(long, value_enum, default_value = "abs")]
    residual: ResidualArg,
    /// Keep the fit Drucker-stable over stretch 0.1–10 in every mode.
    #[arg(long)]
    stable: bool,
    /// Reference cross-section for force columns, e.g. 22mm2 (bare number: m²).
    #[arg(long)]
    area: Option<String>,
    /// Gauge length for displacement columns, e.g. 80mm (bare number: m).
    #[arg(long)]
    gauge_length: Option<String>,
    /// Name the columns of a testing machine's export: ROLE=COLUMN[:UNIT],… (roles
    /// stretch, strain, displacement, force, stress, true_stress, weight, mode,
    /// time), e.g. stretch=Extension:mm,force=Load:N; or a file of ROLE = COLUMN[:UNIT]
    /// lines.
    #[arg(long, value_name = "MAP")]
    columns: Option<String>,
    /// Of a record whose stretch reverses (a load–unload cycle), fit this branch
    /// (default loading, with a warning that says so).
    #[arg(long, value_enum)]
    branch: Option<BranchArg>,
    /// Cut a curve that ends in a break (a final stress drop) after its peak.
    #[arg(long)]
    until_break: bool,
    /// Remove the stress at λ = 1 (a preload offset) from each curve.
    #[arg(long)]
    zero_offset: bool,
    /// Fit only the points with a stretch in MIN:MAX, e.g. 1:3.
    #[arg(long, value_name = "MIN:MAX")]
    stretch_range: Option<String>,
    #[command(flatten)]
    output: Output,
    /// Use at most N multi-start points (default: all).
    #[arg(long, value_name = "N", value_parser = |s: &str| STARTS.parse(s))]
    max_starts: Option<usize>,
}

fn load(a: &Args) -> Result<Dataset> {
    let area = a
        .area
        .as_deref()
        .map(|s| parse_quantity(s, Dimension::Area))
        .transpose()
        .map_err(|e| Error::settings(format!("--area: {e}")))?;
    let gauge_length = a
        .gauge_length
        .as_deref()
        .map(|s| parse_quantity(s, Dimension::Length))
        .transpose()
        .map_err(|e| Error::settings(format!("--gauge-length: {e}")))?;
    for (name, v) in [("--area", area), ("--gauge-length", gauge_length)] {
        if let Some(v) = v.filter(|v| *v <= 0.0) {
            return Err(Error::settings(format!("{name} must be > 0, found {v}")));
        }
    }
    if a.files.is_empty() && a.equibiaxial.is_empty() && a.planar.is_empty() {
        return Err(Error::settings("no data files given").with_hint(
            "dea-fit hyperelastic tension.csv [--equibiaxial bulge.csv] [--planar shear.csv]",
        ));
    }
    let map = a
        .columns
        .as_deref()
        .map(|m| ColumnMap::parse(m, tensile::ROLES))
        .transpose()?
        .unwrap_or_default();
    let mut data = Dataset::default();
    let groups = [
        (&a.files, None),
        (&a.equibiaxial, Some(Mode::Equibiaxial)),
        (&a.planar, Some(Mode::Planar)),
    ];
    for (files, mode) in groups {
        for f in files {
            let opts = TensileOptions {
                area,
                gauge_length,
                mode,
            };
            data.extend(tensile::read_with(f, &opts, &map)?);
        }
    }
    hyperelastic::prepare(&data, &sanity(a)?)
}

/// The sanity options of the data (`--branch`, `--until-break`, `--zero-offset`,
/// `--stretch-range`).
fn sanity(a: &Args) -> Result<Sanity> {
    let stretch_range = a
        .stretch_range
        .as_deref()
        .map(|r| {
            let bad = || {
                Error::settings(format!(
                    "--stretch-range: expected MIN:MAX (two stretches, MIN < MAX), found '{r}'"
                ))
                .with_hint("e.g. --stretch-range 1:3")
            };
            let (lo, hi) = r.split_once(':').ok_or_else(bad)?;
            let lo: f64 = lo.trim().parse().map_err(|_| bad())?;
            let hi: f64 = hi.trim().parse().map_err(|_| bad())?;
            if lo.is_finite() && hi.is_finite() && lo < hi {
                Ok((lo, hi))
            } else {
                Err(bad())
            }
        })
        .transpose()?;
    Ok(Sanity {
        branch: a.branch.map(|b| match b {
            BranchArg::Loading => Branch::Loading,
            BranchArg::Unloading => Branch::Unloading,
            BranchArg::All => Branch::All,
        }),
        until_break: a.until_break,
        zero_offset: a.zero_offset,
        stretch_range,
    })
}

fn run_name(a: &Args, model: &str) -> String {
    let first = a.files.iter().chain(&a.equibiaxial).chain(&a.planar).next();
    let stem = first.map_or_else(|| "fit".into(), |f| super::data_name(f, ""));
    format!("{stem}-{model}")
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let data = load(&a)?;
    let settings = Settings {
        residual: match a.residual {
            ResidualArg::Abs => Residual::Abs,
            ResidualArg::Rel => Residual::Rel,
        },
        stable: a.stable,
        ogden_form: match a.ogden_form {
            Form::Abaqus => OgdenForm::Abaqus,
            Form::Original => OgdenForm::Original,
            Form::Seed => {
                eprintln!("{}", OgdenForm::FORMER_NAME_NOTE);
                OgdenForm::Abaqus
            }
        },
        max_starts: a.max_starts,
        ..Settings::default()
    };
    let meter = dea_fit::observe::Meter::new("hyperelastic", "", None);
    meter.set_message(match a.model.as_str() {
        "auto" => "fitting every model (auto)".to_string(),
        m => format!("fitting {m}"),
    });
    let fit = if a.model == "auto" {
        hyperelastic::fit_auto(&data, &settings)?.0
    } else {
        hyperelastic::fit(
            &data,
            &ModelSpec::new(&a.model, settings.ogden_form),
            &settings,
        )?
    };
    meter.finish();
    let name = run_name(&a, &fit.model);
    a.output.deliver(
        &name,
        &fit,
        fit.status,
        |old| same_fit(old, &fit),
        || dea_fit::report::hyperelastic::summary(&fit),
        |dir| dea_fit::report::hyperelastic::write(&fit, &data, dir),
    )
}

/// Same model, parameters and inputs: the file holds this very fit.
fn same_fit(old: &str, new: &HyperelasticFit) -> bool {
    serde_json::from_str::<HyperelasticFit>(old).is_ok_and(|o| {
        o.model == new.model
            && o.form == new.form
            && o.provenance.files == new.provenance.files
            && o.parameters.len() == new.parameters.len()
            && o.parameters
                .iter()
                .zip(&new.parameters)
                .all(|(a, b)| (a.value - b.value).abs() <= 1e-9 * a.value.abs().max(b.value.abs()))
    })
}
