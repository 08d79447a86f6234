//! `dea-fit`: the command-line shell. Flags → checked settings → library calls.
//! Exit status: 0 done, 2 error (bad input or settings), 1 a blocking fit status
//! under `--strict`.

mod cli;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
