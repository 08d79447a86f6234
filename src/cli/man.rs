//! `dea-fit man [--out DIR]`: roff man pages generated from the clap definitions
//! (clap_mangen): the top page on stdout, or with `--out` one page per command
//! (`dea-fit.1`, `dea-fit-hyperelastic.1`, …) written by the one file policy.

use clap::CommandFactory;
use dea_fit::Result;
use std::path::PathBuf;

/// Write the man pages of dea-fit and its subcommands.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Directory to write one page per command into (default: the top page on stdout).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let mut cmd = super::Cli::command().disable_help_subcommand(true);
    cmd.build();
    let pages = pages(&cmd);
    match a.out {
        None => print!("{}", String::from_utf8_lossy(&pages[0].1)),
        Some(dir) => {
            for (name, page) in &pages {
                let path = dir.join(name);
                super::write_noted(&path, page)?;
                println!("{}", path.display());
            }
        }
    }
    Ok(0)
}

/// The page of `cmd` (first) and of every visible subcommand below it, as roff with
/// its file name (`dea-fit-hyperelastic.1`).
fn pages(cmd: &clap::Command) -> Vec<(String, Vec<u8>)> {
    let man =
        clap_mangen::Man::new(cmd.clone()).source(concat!("dea-fit ", env!("CARGO_PKG_VERSION")));
    let mut page = Vec::new();
    man.render(&mut page).expect("roff renders into memory");
    let mut out = vec![(man.get_filename(), page)];
    for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
        out.extend(pages(sub));
    }
    out
}
