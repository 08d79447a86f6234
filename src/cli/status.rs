//! `dea-fit status`: where each step of a project stands, without running anything.

use dea_fit::Result;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The project folder (the one holding dea-fit.toml)
    #[arg(
        short = 'C',
        long = "directory",
        value_name = "DIR",
        default_value = "."
    )]
    dir: PathBuf,
    /// Print every step as JSON (target, kind, state, reason, outputs, command)
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args) -> Result<i32> {
    let p = super::make::read_project(&a.dir, false)?;
    let steps = dea_fit::project::run::status(&p)?;
    super::make::print(&a.dir, "status", &steps, a.json, false);
    Ok(0)
}
