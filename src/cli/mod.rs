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
