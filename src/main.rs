//! `dea-fit`: the command-line shell. Flags → checked settings → library calls.
//! Exit status (README, "Exit status and statuses"): 0 done, 2 an input or setting
//! refused, 1 a run without a result (`failed`) or a blocking status under
//! `--strict`; a closed pipe ends the process quietly, as it does any Unix filter.

mod cli;

use clap::Parser;

fn main() {
    quiet_on_closed_pipe();
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}

/// Rust starts with SIGPIPE ignored, so every `println!` to a reader that went away
/// (`dea-fit static … | head`) would panic on EPIPE. The default action ends the
/// process at the first such write without a message, like `cat` or `grep`.
#[cfg(unix)]
fn quiet_on_closed_pipe() {
    // SAFETY: called first in `main`, before any other thread exists; SIG_DFL is a
    // valid disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn quiet_on_closed_pipe() {}
