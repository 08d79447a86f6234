//! `dea-fit composite`: a composite series from a TOML manifest — εr of every
//! sample, mixing rules fitted per frequency and ranked by AICc, claims checked;
//! `--generate` writes the synthetic exports a manifest's `[synthetic]` table
//! describes.

use dea_fit::fit::composite::{self, check_claim, Basis};
use dea_fit::io::manifest;
use dea_fit::report::permittivity::{composite_summary, write_composite};
use dea_fit::{Error, Result};
use std::path::PathBuf;

/// Fit mixing rules to a composite series.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The series manifest (TOML).
    manifest: PathBuf,
    /// Also check a claimed increase, e.g. 400%@37.5% (basis unknown: both are
    /// read), 400%@37.5wt% or 400%@37.5vol%. Repeatable.
    #[arg(long, value_name = "CLAIM")]
    claim: Vec<String>,
    /// Write the synthetic exports of the manifest's [synthetic] table and exit.
    #[arg(long)]
    generate: bool,
    /// The fit file (default fits/<folder>-<manifest>-composite.json, as every
    /// estimator writes one), the report (default reports/<same name>/), --json,
    /// --strict (exit 1 when the series' status is blocking).
    #[command(flatten)]
    output: super::Output,
}

/// Parse `400%@37.5%`, `400%@37.5wt%`, `400%@0.375vol`.
pub fn parse_claim(s: &str) -> Result<(f64, f64, Option<Basis>)> {
    let bad = || {
        Error::settings(format!("--claim: cannot read '{s}'"))
            .with_hint("write the increase and the fraction, e.g. 400%@37.5% or 200%@10wt%")
    };
    let (inc, frac) = s.split_once('@').ok_or_else(bad)?;
    let inc: f64 = inc
        .trim()
        .trim_end_matches('%')
        .trim()
        .parse()
        .map_err(|_| bad())?;
    let f = frac.trim();
    let (f, basis) = if let Some(x) = f.strip_suffix("wt%").or_else(|| f.strip_suffix("wt")) {
        (x, Some(Basis::Weight))
    } else if let Some(x) = f.strip_suffix("vol%").or_else(|| f.strip_suffix("vol")) {
        (x, Some(Basis::Volume))
    } else {
        (f, None)
    };
    let pct = f.ends_with('%') || frac.contains('%');
    let v: f64 = f
        .trim()
        .trim_end_matches('%')
        .trim()
        .parse()
        .map_err(|_| bad())?;
    Ok((inc, if pct { v / 100.0 } else { v }, basis))
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let m = manifest::read(&a.manifest)?;
    if a.generate {
        for (path, text) in composite::synthesize(&m)? {
            super::write_noted(&path, text.as_bytes())?;
            println!("wrote {}", path.display());
        }
        return Ok(0);
    }
    let bar = dea_fit::observe::Meter::new("composite", "samples", Some(m.samples.len() as u64));
    let mut fit = composite::fit_series(&m, &|| bar.inc(1))?;
    bar.finish();
    for c in &a.claim {
        let (inc, frac, basis) = parse_claim(c)?;
        fit.claims
            .push(check_claim(frac, inc, basis, &fit.matrix, &fit.filler)?);
    }
    let json = serde_json::to_string_pretty(&fit).expect("a fit serialises");
    let name = format!("{}-composite", super::data_name(&a.manifest, "composite"));
    a.output.deliver(
        &name,
        &fit,
        fit.status,
        |old| old == json,
        || composite_summary(&fit),
        |dir| write_composite(&fit, dir),
    )
}
