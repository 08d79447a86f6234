//! `dea-fit status`: where each step of a project stands, without running anything.

use dea_fit::Result;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    dir: super::make::ProjectDir,
    /// Print every step as JSON (target, kind, state, reason, outputs, command)
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args) -> Result<i32> {
    let p = super::make::read_project(&a.dir.dir, false)?;
    let (steps, _) = dea_fit::project::run::status(&p)?;
    super::make::print(&a.dir.dir, "status", &steps, a.json, false);
    Ok(0)
}
