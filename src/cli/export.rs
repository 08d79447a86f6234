//! `dea-fit export`: a material card for an FE code from fit files.

use clap::ValueEnum;
use dea_fit::export::{self, Options, Target};
use dea_fit::report::format::table;
use dea_fit::units::{parse_quantity, Dimension};
use dea_fit::{Error, Result};
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, ValueEnum)]
enum To {
    Abaqus,
    Calculix,
    Ansys,
    Lsdyna,
    Febio,
    Comsol,
}

/// Write the material card of a hyperelastic fit, a relaxation fit or an identified
/// material for an FE code, converted to the code's convention (docs/export.md).
/// Two files: a hyperelastic and a relaxation fit, written as one material.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Fit files: one hyperelastic fit, relaxation fit or identified material, or a
    /// hyperelastic and a relaxation fit.
    #[arg(required = true, num_args = 1..=2)]
    files: Vec<PathBuf>,
    /// The FE code.
    #[arg(long, value_enum)]
    to: To,
    /// Card file to write (default exports/<first file>-<code>.<ext>); a different
    /// existing file is kept as <name>.previous-N.<ext>.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Mass density, e.g. 960kg/m3 (bare number: kg/m³); LS-DYNA's card needs it.
    #[arg(long)]
    density: Option<String>,
    /// Bulk-to-shear modulus ratio K/mu0 of the codes without a fully
    /// incompressible rubber (calculix, lsdyna, febio): the card's stress differs
    /// from the incompressible fit's by O(stress/K).
    #[arg(long, default_value_t = export::BULK_RATIO)]
    bulk_ratio: f64,
    /// Print the card and its constants as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Exit with status 1 unless the card is exact: approximate (a warning says
    /// where), or made from a fit whose status is ill_posed, unstable,
    /// not_converged or failed.
    #[arg(long)]
    strict: bool,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let target = match a.to {
        To::Abaqus => Target::Abaqus,
        To::Calculix => Target::Calculix,
        To::Ansys => Target::Ansys,
        To::Lsdyna => Target::Lsdyna,
        To::Febio => Target::Febio,
        To::Comsol => Target::Comsol,
    };
    let density = a
        .density
        .as_deref()
        .map(|s| parse_quantity(s, Dimension::Density))
        .transpose()
        .map_err(|e| Error::settings(format!("--density: {e}")))?;
    let material = export::read(&a.files)?;
    let card = export::card(
        &material,
        target,
        &Options {
            density,
            bulk_ratio: a.bulk_ratio,
        },
    )?;
    if target == Target::Calculix {
        eprintln!("note: CalculiX ignores *VISCOELASTIC: the card holds the hyperelastic (long-term) response only");
    }
    let out = a.out.clone().unwrap_or_else(|| {
        let stem = a.files[0]
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "material".into());
        Path::new("exports").join(format!("{stem}-{}.{}", target.name(), target.extension()))
    });
    super::write_noted(&out, card.text.as_bytes())?;
    if a.json {
        let mut v = serde_json::to_value(&card).expect("a card serialises");
        v["out"] = serde_json::Value::from(out.display().to_string());
        println!("{}", serde_json::to_string_pretty(&v).expect("JSON"));
    } else {
        print!("{}", dea_fit::report::format::fit_width(&summary(&card)));
        println!("card: {}", out.display());
    }
    Ok(card.exit_code(a.strict))
}

/// The terminal summary: the constants as the card holds them, the status, the
/// warnings.
fn summary(card: &export::Card) -> String {
    let mut s = format!("{} card for {}\n", card.target.name(), card.material);
    for f in &card.sources {
        s.push_str(&format!("source: {}\n", f.describe()));
    }
    let rows: Vec<Vec<String>> = card
        .constants
        .iter()
        .map(|c| vec![c.name.clone(), export::num(c.value), c.unit.to_string()])
        .collect();
    s.push_str(&table(&["constant", "value (SI)", "unit"], &rows));
    s.push_str(&format!("status: {}\n", card.status));
    for w in &card.warnings {
        s.push_str(&format!("warning: {w}\n"));
    }
    s
}
