//! `dea-fit permittivity`: εr, ε″, tan δ and conductivity per frequency from LCR
//! exports, one file or a parallel batch with a progress bar.

use clap::ValueEnum;
use dea_fit::fit::permittivity::{self, EdgeCorrection, Geometry, Input, Settings};
use dea_fit::io::lcr::LcrOptions;
use dea_fit::io::manifest::sidecar;
use dea_fit::material::dielectric::Pair;
use dea_fit::report::permittivity::{summary, write_samples};
use dea_fit::units::{parse_quantity, parse_uncertain, Dimension, Quantity};
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// Edge (fringe-field) correction.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Edge {
    /// No correction (default).
    None,
    /// Kirchhoff edge term in air, subtracted (coupon flush with the plates).
    Air,
    /// Kirchhoff edge term in the coupon (coupon larger than the plates).
    Filled,
}

/// Permittivity from LCR-meter exports.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Export files (E4990A, E4980A data lines, Hioki or plain CSV).
    files: Vec<PathBuf>,
    /// Plate area, e.g. 1.439e-3 (m²) or 14.39cm2, optionally ±tolerance.
    #[arg(long)]
    area: Option<String>,
    /// Plate diameter, e.g. 42.8mm±0.1mm (instead of --area).
    #[arg(long)]
    diameter: Option<String>,
    /// Coupon thickness, e.g. 2.2mm±0.05mm.
    #[arg(long)]
    thickness: Option<String>,
    /// Open-fixture (stray) capacitance to subtract, e.g. 0.3pF±0.05pF.
    #[arg(long)]
    stray: Option<String>,
    /// Edge correction for unguarded plates (Kirchhoff; ASTM D150).
    #[arg(long, value_enum, default_value = "none")]
    edge: Edge,
    /// Measured pair of headerless data or to pick from several (cp-d, cs-rs, z-theta, ZTD, ...).
    #[arg(long)]
    pair: Option<String>,
    /// Frequency list of headerless E4980A data, e.g. 100Hz,1kHz,10kHz.
    #[arg(long)]
    frequencies: Option<String>,
    /// Write the result (JSON) to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write a report (SVG + index.md) into this directory.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
    /// Exit 1 when a sample's status is blocking (e.g. εr below 1).
    #[arg(long)]
    strict: bool,
}

fn quantity(flag: &str, v: &Option<String>, dim: Dimension) -> Result<Option<Quantity>> {
    v.as_deref()
        .map(|s| parse_uncertain(s, dim))
        .transpose()
        .map_err(|e| Error::settings(format!("{flag}: {e}")))
}

/// Flags → LCR options and permittivity settings.
pub fn lcr_settings(
    pair: &Option<String>,
    frequencies: &Option<String>,
    stray: &Option<String>,
    edge: Edge,
) -> Result<(LcrOptions, Settings)> {
    let pair = pair
        .as_deref()
        .map(|p| {
            Pair::parse(p).ok_or_else(|| {
                Error::settings(format!("--pair: unknown pair '{p}'")).with_hint(
                    "use cp-d, cp-q, cp-g, cp-rp, cs-d, cs-q, cs-rs, ls-rs, lp-rp, r-x, z-theta, g-b, y-theta",
                )
            })
        })
        .transpose()?;
    let frequencies = frequencies
        .as_deref()
        .map(|s| {
            s.split(',')
                .map(|f| parse_quantity(f, Dimension::Frequency))
                .collect::<std::result::Result<Vec<f64>, String>>()
        })
        .transpose()
        .map_err(|e| Error::settings(format!("--frequencies: {e}")))?;
    let stray = quantity("--stray", stray, Dimension::Capacitance)?;
    let settings = Settings {
        stray: stray.map(|q| q.value),
        stray_std: stray.and_then(|q| q.tolerance),
        edge: match edge {
            Edge::None => EdgeCorrection::None,
            Edge::Air => EdgeCorrection::Air,
            Edge::Filled => EdgeCorrection::Filled,
        },
    };
    settings.check()?;
    Ok((LcrOptions { pair, frequencies }, settings))
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    if a.files.is_empty() {
        return Err(Error::settings("no export files given")
            .with_hint("dea-fit permittivity sweep.csv --area 1.439e-3 --thickness 2.2mm±0.05mm"));
    }
    super::refuse_in_report(a.report.as_deref(), &[("--out", a.out.as_deref())])?;
    let (opts, settings) = lcr_settings(&a.pair, &a.frequencies, &a.stray, a.edge)?;
    let flags = [
        quantity("--area", &a.area, Dimension::Area)?,
        quantity("--diameter", &a.diameter, Dimension::Length)?,
        quantity("--thickness", &a.thickness, Dimension::Length)?,
    ];
    let mut inputs = Vec::with_capacity(a.files.len());
    for f in &a.files {
        let (q, from) = match sidecar(f)? {
            Some((p, [ar, di, th])) => {
                let area_given = ar.is_some() || di.is_some();
                (
                    [
                        if area_given { ar } else { flags[0] },
                        if area_given { di } else { flags[1] },
                        th.or(flags[2]),
                    ],
                    format!("sidecar {}", p.display()),
                )
            }
            None => (flags, "flags".to_string()),
        };
        inputs.push(Input {
            path: f.clone(),
            name: permittivity::default_name(f),
            geometry: Geometry::new(q[0], q[1], q[2]).map_err(|e| e.to_string()),
            geometry_from: from,
        });
    }
    if let Some(Err(e)) = inputs.first().map(|i| &i.geometry) {
        if inputs.iter().all(|i| i.geometry.is_err()) {
            return Err(Error::settings(e.clone()));
        }
    }
    let bar = dea_fit::observe::Meter::new("permittivity", "files", Some(inputs.len() as u64));
    let run = permittivity::analyse_batch(&inputs, &opts, &settings, &|| bar.inc(1))?;
    bar.finish();
    let json = serde_json::to_string_pretty(&run).expect("a result serialises");
    // A file that could not be used is a refused input: exit 2, and (like every
    // refusal) nothing is written; the other files' results are still printed.
    let refused = !run.failed.is_empty();
    let page = match (&a.report, refused) {
        (Some(dir), false) => {
            super::claim_dir(dir)?;
            Some(dir)
        }
        _ => None,
    };
    if let (Some(out), false) = (&a.out, refused) {
        super::write_fit_noted(out, json.as_bytes(), |old| old == json)?;
    }
    let page = page.map(|dir| write_samples(&run, dir)).transpose()?;
    if a.json {
        println!("{json}");
    } else {
        print!("{}", summary(&run)?);
        if let Some(p) = page {
            println!("report: {}", p.display());
        }
        if let (Some(o), false) = (&a.out, refused) {
            println!("result: {}", o.display());
        }
    }
    for f in &run.failed {
        eprintln!("error: {}", f.error);
    }
    if refused && (a.out.is_some() || a.report.is_some()) {
        eprintln!("note: nothing was written; fix or leave out the file(s) that failed");
    }
    Ok(if refused {
        2
    } else {
        run.status.exit_code(a.strict)
    })
}
