//! Subcommands, one file each.

mod bench;
mod bench_relaxation;
mod bench_simulate;
mod composite;
mod hyperelastic;
mod permittivity;
mod relaxation;
mod simulate;
mod static_curve;
mod synth;

use clap::{Parser, Subcommand};
use dea_fit::Result;

/// Material constants and forward simulation for dielectric elastomer actuators.
#[derive(Debug, Parser)]
#[command(name = "dea-fit", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Fit hyperelastic strain-energy coefficients to tensile-test data.
    Hyperelastic(hyperelastic::Args),
    /// Relative permittivity and loss per frequency from LCR-meter exports.
    Permittivity(permittivity::Args),
    /// Fit mixing rules to a composite series described by a TOML manifest.
    Composite(composite::Args),
    /// Fit Prony / Kelvin-Maxwell constants to a stress-relaxation curve.
    Relaxation(relaxation::Args),
    /// Generate synthetic test data from known constants (with noise and seed).
    Synth(synth::Args),
    /// Simulate an actuator scene: trajectory CSV, charts, summary.
    Simulate(simulate::Args),
    /// Static voltage–stretch curve and pull-in of a scene's actuator.
    Static(static_curve::Args),
    /// Measure speed against accuracy and write tables and charts under reports/.
    Bench(bench::Args),
}

/// Run a parsed command line; returns the exit status.
pub fn run(cli: Cli) -> Result<i32> {
    match cli.command {
        Command::Hyperelastic(a) => hyperelastic::run(a),
        Command::Relaxation(a) => relaxation::run(a),
        Command::Synth(a) => synth::run(a),
        Command::Permittivity(a) => permittivity::run(a),
        Command::Composite(a) => composite::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Static(a) => static_curve::run(a),
    }
}

/// What a fitting command has to tell at its end.
pub struct Finish<'a> {
    /// The fit as JSON (printed with `--json`).
    json: &'a str,
    /// The human summary (None with `--json`).
    summary: Option<String>,
    /// Where the fit file went.
    out: &'a std::path::Path,
    /// The report page, if one was written.
    report: Option<&'a std::path::Path>,
    /// What happened to an older fit file there.
    replaced: &'a dea_fit::io::write::Replaced,
    /// `--strict` and a blocking status.
    exit_1: bool,
}

/// The common end of every fitting command: the summary (with where the fit and the
/// report went) or the JSON on stdout, a note on stderr if an older, different fit
/// was kept aside, and the exit status.
fn finish(f: Finish) -> i32 {
    match f.summary {
        None => println!("{}", f.json),
        Some(s) => {
            print!("{s}");
            println!("fit: {}", f.out.display());
            if let Some(r) = f.report {
                println!("report: {}", r.display());
            }
        }
    }
    if let dea_fit::io::write::Replaced::KeptAs(p) = f.replaced {
        eprintln!(
            "note: {} held a different fit; it was kept as {}",
            f.out.display(),
            p.display()
        );
    }
    i32::from(f.exit_1)
}
