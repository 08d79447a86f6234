//! `dea-fit dma`: DMA isotherms → time–temperature shifts → master curve (→ Prony),
//! docs/dma.md.

use super::Output;
use clap::ValueEnum;
use dea_fit::dma::fit::{self, DmaFit, Settings, ShiftMode};
use dea_fit::dma::law::LawKind;
use dea_fit::dma::read;
use dea_fit::dma::shift::ShiftOn;
use dea_fit::dma::temperature;
use dea_fit::io::table::ColumnMap;
use dea_fit::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ShiftArg {
    /// The free shifts of adjacent isotherms (default).
    Free,
    /// WLF fitted to the free shifts: log10 aT = −C1 (T − Tr)/(C2 + T − Tr).
    Wlf,
    /// Arrhenius fitted to the free shifts: log10 aT = Ea/(R ln 10)·(1/T − 1/Tr).
    Arrhenius,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ShiftOnArg {
    /// log E′ (default).
    Storage,
    /// log E″.
    Loss,
    /// log tan δ.
    TanDelta,
    /// log E′ and log E″ together.
    Both,
}

/// Shift DMA isotherms (frequency sweeps at several temperatures) onto a master curve
/// at a reference temperature, each shift with its standard error, optionally with a
/// WLF or Arrhenius law fitted to them.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// DMA files (CSV: frequency_Hz or omega_rad_s, storage_modulus_MPa, loss_modulus_MPa
    /// or tan_delta, temperature_C column or a '# temperature: 25 C' line; one file
    /// per isotherm, one file with a temperature column, or a master curve without
    /// temperature).
    files: Vec<PathBuf>,
    /// Reference temperature of the master curve, e.g. 25C, -5C or 298.15K (need not be
    /// a measured isotherm).
    #[arg(long, allow_hyphen_values = true, value_name = "T")]
    reference_temperature: Option<String>,
    /// Shifts the master curve is built with.
    #[arg(long, value_enum, default_value = "free")]
    shift: ShiftArg,
    /// Quantity the free shifts are computed on.
    #[arg(long, value_enum, default_value = "storage")]
    shift_on: ShiftOnArg,
    /// Fit a vertical (modulus) shift bT of each isotherm too.
    #[arg(long)]
    vertical_shift: bool,
    /// Number of Prony terms of the master curve, or auto.
    #[arg(long, default_value = "auto")]
    terms: String,
    /// Name the columns of an instrument's export: ROLE=COLUMN[:UNIT],… (roles
    /// frequency, omega, storage, loss, tan_delta, temperature), or a file of them.
    #[arg(long, value_name = "MAP")]
    columns: Option<String>,
    #[command(flatten)]
    output: Output,
}

/// What `--json` prints: the fit file's object and where it went.
#[derive(Serialize)]
struct Printed<'a> {
    #[serde(flatten)]
    fit: &'a DmaFit,
    fit_file: String,
}

fn settings(a: &Args) -> Result<Settings> {
    let reference_k = a
        .reference_temperature
        .as_deref()
        .map(|t| {
            temperature::parse(t)
                .map_err(|e| Error::settings(format!("--reference-temperature: {e}")))
        })
        .transpose()?;
    let terms = match a.terms.trim() {
        "auto" => None,
        t => Some(t.parse::<usize>().ok().filter(|&n| n >= 1).ok_or_else(|| {
            Error::settings(format!(
                "--terms: expected a number ≥ 1 or auto, found '{t}'"
            ))
        })?),
    };
    Ok(Settings {
        on: match a.shift_on {
            ShiftOnArg::Storage => ShiftOn::Storage,
            ShiftOnArg::Loss => ShiftOn::Loss,
            ShiftOnArg::TanDelta => ShiftOn::TanDelta,
            ShiftOnArg::Both => ShiftOn::Both,
        },
        vertical: a.vertical_shift,
        mode: match a.shift {
            ShiftArg::Free => ShiftMode::Free,
            ShiftArg::Wlf => ShiftMode::Law(LawKind::Wlf),
            ShiftArg::Arrhenius => ShiftMode::Law(LawKind::Arrhenius),
        },
        reference_k,
        terms,
    })
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    if a.files.is_empty() {
        return Err(Error::settings("no DMA file given")
            .with_hint("dea-fit dma isotherms.csv --reference-temperature 25C   (make one with dea-fit synth dma)"));
    }
    let settings = settings(&a)?;
    let map = a
        .columns
        .as_deref()
        .map(|m| ColumnMap::parse(m, read::ROLES))
        .transpose()?
        .unwrap_or_default();
    let o = &a.output;
    let name = format!("{}-dma", super::data_name(&a.files[0], "dma"));
    let (out, dir) = o.paths(&name);
    super::refuse_in_report(dir.as_deref(), &[("--out", Some(&out))])?;
    let paths: Vec<&Path> = a.files.iter().map(PathBuf::as_path).collect();
    let data = read::read_all(&paths, &map)?;
    let f = fit::fit(&data, &settings)?;
    let json = serde_json::to_string_pretty(&f).expect("a DMA fit serialises");
    if let Some(d) = &dir {
        super::claim_dir(d)?;
    }
    super::write_fit_noted(&out, json.as_bytes(), |old| same(old, &f))?;
    let page = dir
        .map(|d| dea_fit::dma::report::write(&f, &data, &d))
        .transpose()?;
    if o.json {
        let p = Printed {
            fit: &f,
            fit_file: out.display().to_string(),
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&p).expect("a DMA fit serialises")
        );
    } else {
        print!("{}", dea_fit::dma::report::summary(&f));
        println!("fit: {}", out.display());
        if let Some(p) = &page {
            println!("report: {}", p.display());
        }
    }
    Ok(f.status.exit_code(o.strict))
}

/// The file holds this very fit: same files, settings, shifts and Prony series
/// (the solver's timing aside).
fn same(old: &str, new: &DmaFit) -> bool {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    serde_json::from_str::<DmaFit>(old).is_ok_and(|o| {
        o.files
            .iter()
            .map(|s| &s.sha256)
            .eq(new.files.iter().map(|s| &s.sha256))
            && o.shift == new.shift
            && o.shift_on == new.shift_on
            && o.vertical_shift == new.vertical_shift
            && o.reference_temperature_k == new.reference_temperature_k
            && o.shift_factors.len() == new.shift_factors.len()
            && o.shift_factors
                .iter()
                .zip(&new.shift_factors)
                .all(|(a, b)| close(a.log10_at, b.log10_at))
            && close(o.prony.e_inf, new.prony.e_inf)
            && o.prony.terms.len() == new.prony.terms.len()
            && o.prony
                .terms
                .iter()
                .zip(&new.prony.terms)
                .all(|(a, b)| close(a.e, b.e) && close(a.tau, b.tau))
    })
}
