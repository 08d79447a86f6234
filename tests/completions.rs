//! `dea-fit completions` and `dea-fit man` (issue 13): generated from the clap
//! definitions, so they name what `--help` names.

use crate::support::{names_in, run, run_ok};
use std::path::Path;

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("UTF-8 on stdout")
}

/// The subcommands `dea-fit --help` lists (without clap's `help`).
fn subcommands() -> Vec<String> {
    let help = stdout(&run_ok(Path::new("."), &["--help"]));
    let names: Vec<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|n| n != "help")
        .collect();
    assert!(names.len() >= 12, "subcommands from --help: {names:?}");
    names
}

/// The long options `dea-fit <args…> --help` lists.
fn long_options(args: &[&str]) -> Vec<String> {
    let help = stdout(&run_ok(Path::new("."), &[args, &["--help"]].concat()));
    let opts: Vec<String> = help
        .lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with('-'))
        .filter_map(|l| l.split_whitespace().find_map(|w| w.strip_prefix("--")))
        .map(|o| o.split(['=', '[', '<']).next().unwrap_or("").to_string())
        .collect();
    assert!(
        opts.contains(&"help".to_string()),
        "{args:?} options: {opts:?}"
    );
    opts
}

/// Every shell is generated; the bash script completes every subcommand.
#[test]
fn completion_scripts_name_every_subcommand() {
    let bash = stdout(&run_ok(Path::new("."), &["completions", "bash"]));
    for s in subcommands() {
        assert!(
            bash.contains(&format!("dea__fit,{s})")),
            "the bash script does not complete '{s}'"
        );
    }
    assert!(bash.contains("complete -F"), "not a bash completion script");
    for shell in ["zsh", "fish", "elvish", "powershell"] {
        let s = stdout(&run_ok(Path::new("."), &["completions", shell]));
        assert!(
            s.contains("hyperelastic") && s.contains("stretch-min"),
            "{shell} script"
        );
    }
    let o = run(Path::new("."), &["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2), "an unknown shell is refused");
}

/// Roff-ish: a `.TH` title with the page's name and section 1, a NAME section, every
/// line a request (`.XX`), a comment or text; and every option `--help` names.
fn check_page(page: &str, name: &str, options: &[String]) {
    let th = page
        .lines()
        .find(|l| l.starts_with(".TH "))
        .unwrap_or_else(|| panic!("{name}: no .TH"));
    assert!(th.starts_with(&format!(".TH {name} 1 ")), "{name}: {th}");
    assert!(page.contains(".SH NAME\n"), "{name}: no NAME section");
    assert!(
        page.contains(".SH SYNOPSIS\n"),
        "{name}: no SYNOPSIS section"
    );
    let text = page.replace("\\-", "-");
    for o in options {
        assert!(
            text.contains(&format!("\\fB--{o}\\fR")),
            "{name}: option --{o} missing"
        );
    }
}

/// The top page on stdout, with every subcommand; `--out` writes one page per command
/// (into a fresh directory) and they carry their options.
#[test]
fn man_pages_carry_commands_and_options() {
    let top = stdout(&run_ok(Path::new("."), &["man"]));
    check_page(
        &top,
        "dea-fit",
        &long_options(&[])
            .into_iter()
            .filter(|o| o != "help")
            .collect::<Vec<_>>(),
    );
    for s in subcommands() {
        assert!(
            top.replace("\\-", "-").contains(&format!("dea-fit-{s}(1)")),
            "top page: {s}"
        );
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("man1");
    run_ok(dir.path(), &["man", "--out", "man1"]);
    let names = names_in(&out);
    for s in subcommands() {
        assert!(
            names.contains(&format!("dea-fit-{s}.1")),
            "{s} page: {names:?}"
        );
    }
    let read = |n: &str| std::fs::read_to_string(out.join(n)).expect("page");
    assert_eq!(
        read("dea-fit.1"),
        top,
        "the written top page is the printed one"
    );
    let page = read("dea-fit-hyperelastic.1");
    let options = long_options(&["hyperelastic"]);
    assert!(options.len() > 5 && options.contains(&"model".to_string()));
    check_page(
        &page,
        "dea-fit-hyperelastic",
        &long_options(&["hyperelastic"]),
    );
    assert!(page.contains(".SH OPTIONS"), "hyperelastic: no OPTIONS");
    // A second run writes the same pages: no file kept aside.
    run_ok(dir.path(), &["man", "--out", "man1"]);
    assert_eq!(names_in(&out), names);
}
