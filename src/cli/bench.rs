//! `dea-fit bench`: speed against accuracy, written as CSV and SVG under reports/.

use dea_fit::Result;

/// Benchmark a subsystem.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to benchmark: hyperelastic or simulate.
    what: String,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    if a.what == "simulate" {
        return super::bench_simulate::run(std::path::Path::new("datasets/scenes"));
    }
    Ok(0)
}
