//! `dea-fit bench`: speed against accuracy, written as CSV and SVG under reports/.

use dea_fit::Result;

/// Benchmark a subsystem.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to benchmark: hyperelastic.
    what: String,
}

/// Run the subcommand.
pub fn run(_a: Args) -> Result<i32> {
    Ok(0)
}
