//! `dea-fit completions <SHELL>`: a shell completion script generated from the clap
//! definitions (clap_complete), on stdout.

use clap::CommandFactory;
use dea_fit::Result;

/// Print a shell completion script for dea-fit.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Shell to complete for.
    shell: clap_complete::Shell,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let mut cmd = super::Cli::command();
    clap_complete::generate(a.shell, &mut cmd, "dea-fit", &mut std::io::stdout());
    Ok(0)
}
