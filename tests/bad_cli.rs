//! The cross-command bad-input corpus: `tests/data/bad_cli/*.tsv`, one table per area
//! (scene, fit file, statuses, ...). Each line is one run of the real binary on an
//! input that once panicked, hung or lied, with the exit status it must give and what
//! its output must say. The format is documented in `tests/data/bad_cli/README.md`.

use crate::support::{names_in, repo};
use std::path::PathBuf;
use std::process::Command;

/// One corpus line.
struct Case {
    table: String,
    line: usize,
    args: Vec<String>,
    exit: i32,
    expected: Vec<String>,
}

/// Expand one argument: `@name` is a corpus file, `%path` a repository file.
fn expand(arg: &str) -> String {
    if let Some(f) = arg.strip_prefix('@') {
        repo()
            .join("tests/data/bad_cli/files")
            .join(f)
            .display()
            .to_string()
    } else if let Some(f) = arg.strip_prefix('%') {
        repo().join(f).display().to_string()
    } else {
        arg.to_string()
    }
}

fn cases() -> Vec<Case> {
    let dir = repo().join("tests/data/bad_cli");
    let mut tables: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/data/bad_cli")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "tsv"))
        .collect();
    tables.sort();
    let mut out = Vec::new();
    for t in tables {
        let text = std::fs::read_to_string(&t).expect("a corpus table");
        let table = t.file_name().unwrap().to_string_lossy().into_owned();
        for (i, l) in text.lines().enumerate() {
            if l.starts_with('#') || l.trim().is_empty() {
                continue;
            }
            let cols: Vec<&str> = l.split('\t').collect();
            assert!(cols.len() >= 2, "{table}:{}: needs args and exit", i + 1);
            out.push(Case {
                table: table.clone(),
                line: i + 1,
                args: cols[0].split_whitespace().map(expand).collect(),
                exit: cols[1]
                    .trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("{table}:{}: exit status", i + 1)),
                expected: cols[2..].iter().map(|s| s.to_string()).collect(),
            });
        }
    }
    out
}

/// Every corpus run gives its exit status, says what it must, never panics, and when
/// it refuses the input (exit 2) leaves nothing behind in its working directory.
#[test]
fn bad_cli_corpus() {
    let cases = cases();
    assert!(!cases.is_empty(), "the corpus is empty");
    let mut failures = Vec::new();
    for c in &cases {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let o = Command::new(env!("CARGO_BIN_EXE_dea-fit"))
            .args(&c.args)
            .current_dir(dir.path())
            .output()
            .expect("the dea-fit binary runs");
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        let mut problems = Vec::new();
        if o.status.code() != Some(c.exit) {
            problems.push(format!("exit {:?}, expected {}", o.status.code(), c.exit));
        }
        if text.contains("panicked") {
            problems.push("panicked".into());
        }
        // Text for people wraps at 100 columns: compare words, not line breaks.
        let words = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
        let flowed = words(&text);
        for w in &c.expected {
            if !flowed.contains(&words(w)) {
                problems.push(format!("missing {w:?}"));
            }
        }
        if c.exit == 2 {
            let left = names_in(dir.path());
            if !left.is_empty() {
                problems.push(format!("refused, yet wrote {left:?}"));
            }
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{}:{}: dea-fit {}: {}\n  output: {}",
                c.table,
                c.line,
                c.args.join(" "),
                problems.join("; "),
                text.trim_end()
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
