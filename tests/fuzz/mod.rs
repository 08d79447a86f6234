//! Fuzzing every reader with mutated shipped files (docs/fuzzing.md).
//!
//! Each reader's cases run in a child process (this test binary again, with
//! `DEA_FIT_FUZZ_CHILD` set), one after the other; the child reports each case on a
//! line of its stdout. The parent is the watchdog: a case that takes longer than the
//! wall bound is a hang (the child is killed, since a stuck thread cannot be), a
//! child that dies is an abort (a failed allocation, a stack overflow); either way a
//! new child goes on with the next case. Cases are made from a seeded ChaCha8 stream
//! per (reader, case), so the parent remakes any case to write its reproducer.

mod checkpoint;
mod flags;
mod generate;
mod merge;
mod mutate;
mod readers;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use readers::{Case, Reader, Verdict};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{mpsc, Mutex};
use std::time::Duration;

/// Cases per reader when `DEA_FIT_FUZZ_CASES` is not set (CI: a few seconds).
const CI_CASES: u64 = 40;
/// Reproducers written per failure class.
const REPRODUCERS_PER_CLASS: usize = 5;
/// Address space of a child (KiB), so that an absurd allocation fails (and aborts
/// the child) instead of taking the machine's memory.
const CHILD_MEMORY_KIB: u64 = 4 << 20;

struct Config {
    cases: u64,
    seed: u64,
    wall: Duration,
    readers: Vec<Reader>,
}

fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name).map_or(default, |v| {
        v.trim()
            .parse()
            .unwrap_or_else(|_| panic!("{name}: expected a whole number, found '{v}'"))
    })
}

impl Config {
    fn from_env() -> Config {
        let readers = match std::env::var("DEA_FIT_FUZZ_READERS") {
            Ok(list) => list
                .split(',')
                .map(|r| {
                    Reader::parse(r).unwrap_or_else(|| {
                        let all: Vec<&str> = Reader::ALL.iter().map(|r| r.name()).collect();
                        panic!(
                            "DEA_FIT_FUZZ_READERS: unknown reader '{r}' ({})",
                            all.join(", ")
                        )
                    })
                })
                .collect(),
            Err(_) => Reader::ALL.to_vec(),
        };
        Config {
            cases: env_number("DEA_FIT_FUZZ_CASES", CI_CASES),
            seed: env_number("DEA_FIT_FUZZ_SEED", 9),
            wall: Duration::from_secs(env_number("DEA_FIT_FUZZ_WALL_S", 10)),
            readers,
        }
    }
}

/// The generator of case `i` of reader `r`: one ChaCha8 stream per (reader, case).
fn case(r: Reader, seeds: &[Vec<(String, Vec<u8>)>], seed: u64, i: u64) -> Case {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(((r as u64) << 48) | i);
    readers::generate(r, seeds, &mut rng)
}

/// `s` on one line of the child's report (no line breaks, no tabs).
fn one_line(s: &str) -> String {
    s.replace(['\n', '\t'], " ")
}

/// A message as a class: its part before the first `:` or `=` (what comes after is
/// mostly values), on one line, each run of digits masked as `#`, so that messages
/// differing only in their numbers group together.
fn masked(s: &str) -> String {
    let mut out = String::new();
    for c in one_line(s.split([':', '=']).next().unwrap_or("")).chars() {
        if !c.is_ascii_digit() {
            out.push(c);
        } else if !out.ends_with('#') {
            out.push('#');
        }
    }
    out.chars().take(90).collect()
}

/// A source path without the registry's or the toolchain's prefix
/// (`nalgebra-0.35.0/src/...`, `core/src/...`).
fn crate_path(file: &str) -> &str {
    if let Some((_, rest)) = file.split_once("registry/src/") {
        return rest.split_once('/').map_or(rest, |(_, p)| p);
    }
    match file.split_once("/library/") {
        Some((_, rest)) if file.starts_with("/rustc/") => rest,
        _ => file,
    }
}

/// For a panic outside the crate (`f64::clamp` in core, an SVD in nalgebra), the
/// innermost frame of dea-fit's own `src/` that led to it.
fn caller_in_crate(at: &str) -> Option<String> {
    if at.starts_with("src/") {
        return None;
    }
    let bt = std::backtrace::Backtrace::force_capture().to_string();
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/src/");
    bt.lines().find_map(|l| {
        let p = l.trim().strip_prefix("at ")?;
        let p = p.strip_prefix(src).or_else(|| p.strip_prefix("./src/"))?;
        // `file:line:column` → `src/file:line`
        Some(format!("src/{}", p.rsplit_once(':').map_or(p, |(f, _)| f)))
    })
}

/// The last panic of the child: location and message.
static PANIC: Mutex<Option<String>> = Mutex::new(None);

/// The child: run cases `first..cases` of one reader, one report line per case.
fn child(cfg: &Config, spec: &str) {
    let (name, first) = spec.split_once(':').expect("reader:first");
    let r = Reader::parse(name).expect("a reader");
    let first: u64 = first.parse().expect("a case number");
    panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        let at = info
            .location()
            .map(|l| format!("{}:{}", crate_path(l.file()), l.line()))
            .unwrap_or_default();
        let at = match caller_in_crate(&at) {
            Some(c) => format!("{c} (in {at})"),
            None => at,
        };
        *PANIC.lock().unwrap() = Some(format!("{at}\t{msg}"));
    }));
    let seeds = readers::seeds(r);
    let dir = tempfile::tempdir().unwrap();
    println!("@fuzz ready");
    for i in first..cfg.cases {
        let c = case(r, &seeds, cfg.seed, i);
        *PANIC.lock().unwrap() = None;
        let line = match panic::catch_unwind(AssertUnwindSafe(|| readers::run(r, &c, dir.path()))) {
            Ok(Verdict::Refused) => "refused".to_string(),
            Ok(Verdict::Accepted) => "accepted".to_string(),
            Ok(Verdict::Failed { class, detail }) => {
                format!("lie\t{}\t{}", one_line(&class), one_line(&detail))
            }
            Err(_) => {
                let p = PANIC.lock().unwrap().take().unwrap_or_default();
                let (at, msg) = p.split_once('\t').unwrap_or(("?", ""));
                format!("panic\tpanic at {at}: {}\t{}", masked(msg), one_line(msg))
            }
        };
        println!("@fuzz {i} {line}");
    }
}

/// Counts of one reader.
#[derive(Default)]
struct Tally {
    cases: u64,
    accepted: u64,
    refused: u64,
    panics: u64,
    hangs: u64,
    aborts: u64,
    lies: u64,
    seconds: f64,
}

/// Failures of one class.
struct Group {
    count: u64,
    reproducers: Vec<PathBuf>,
    example: String,
}

/// Failures of one reader, by class.
type Groups = BTreeMap<String, Group>;

fn failures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-failures")
}

/// Record a failure of case `i`; the first few of each class get a reproducer.
fn record(
    r: Reader,
    cfg: &Config,
    seeds: &[Vec<(String, Vec<u8>)>],
    groups: &mut Groups,
    i: u64,
    class: String,
    detail: &str,
) {
    let c = case(r, seeds, cfg.seed, i);
    let g = groups.entry(class.clone()).or_insert(Group {
        count: 0,
        reproducers: Vec::new(),
        example: format!("{}: {detail}", c.what).chars().take(300).collect(),
    });
    g.count += 1;
    if g.reproducers.len() < REPRODUCERS_PER_CLASS {
        let dir = failures_dir().join(r.name()).join(i.to_string());
        for (name, bytes) in &c.files {
            let p = dir.join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, bytes).unwrap();
        }
        let note = format!(
            "reader: {}\nseed: {}\ncase: {i}\nclass: {class}\ndetail: {detail}\nmutation: {} [{}]\nreplay: {}\n",
            r.name(),
            cfg.seed,
            c.what,
            c.kind,
            readers::replay(r, &c, &dir)
        );
        std::fs::write(dir.join("case.txt"), note).unwrap();
        g.reproducers.push(dir);
    }
}

/// Run one reader's cases in child processes, watching each case's wall time.
fn supervise(r: Reader, cfg: &Config) -> (Tally, Groups) {
    let _ = std::fs::remove_dir_all(failures_dir().join(r.name()));
    let seeds = readers::seeds(r);
    let start = std::time::Instant::now();
    let (mut tally, mut groups) = (Tally::default(), Groups::new());
    let mut next = 0;
    while next < cfg.cases {
        let exe = std::env::current_exe().unwrap();
        let mut proc = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v {CHILD_MEMORY_KIB} 2>/dev/null; exec \"$0\" \"$@\""
            ))
            .arg(exe)
            .args([
                "fuzz::readers",
                "--exact",
                "--nocapture",
                "--test-threads=1",
            ])
            .env("DEA_FIT_FUZZ_CHILD", format!("{}:{next}", r.name()))
            // The last line of stderr is then the reason of an abort.
            .env("RUST_BACKTRACE", "0")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the test binary runs again");
        let (tx, rx) = mpsc::channel();
        let out = proc.stdout.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                // libtest may print "test fuzz::readers ... " before the first line.
                if let Some((_, l)) = line.split_once("@fuzz ") {
                    let _ = tx.send(l.to_string());
                }
            }
        });
        let mut err = proc.stderr.take().unwrap();
        let stderr = std::thread::spawn(move || {
            let mut s = String::new();
            let _ = err.read_to_string(&mut s);
            s
        });
        let mut ready = false;
        let stuck = loop {
            match rx.recv_timeout(cfg.wall) {
                Ok(l) if l == "ready" => ready = true,
                Ok(l) => {
                    let (i, rest) = l.split_once(' ').unwrap();
                    let i: u64 = i.parse().unwrap();
                    let mut f = rest.splitn(3, '\t');
                    let (what, class, detail) = (f.next().unwrap(), f.next(), f.next());
                    tally.cases += 1;
                    match what {
                        "refused" => tally.refused += 1,
                        "accepted" => tally.accepted += 1,
                        kind => {
                            if kind == "panic" {
                                tally.panics += 1;
                            } else {
                                tally.accepted += 1;
                                tally.lies += 1;
                            }
                            let class = format!("{}: {}", r.name(), class.unwrap());
                            record(r, cfg, &seeds, &mut groups, i, class, detail.unwrap());
                        }
                    }
                    next = i + 1;
                }
                Err(mpsc::RecvTimeoutError::Timeout) => break true,
                Err(mpsc::RecvTimeoutError::Disconnected) => break false,
            }
        };
        if stuck {
            let _ = proc.kill();
        }
        let status = proc.wait().unwrap();
        let stderr = stderr.join().unwrap();
        if !ready {
            panic!(
                "the fuzz child of {} did not start ({status}):\n{stderr}",
                r.name()
            );
        }
        if next < cfg.cases {
            tally.cases += 1;
            let (class, detail) = if stuck {
                tally.hangs += 1;
                (
                    format!("{}: hang (over {:?})", r.name(), cfg.wall),
                    "no answer within the wall bound".to_string(),
                )
            } else {
                tally.aborts += 1;
                let last = stderr
                    .lines()
                    .rev()
                    .find(|l| !l.trim().is_empty() && !l.starts_with("note:"))
                    .unwrap_or("");
                (
                    format!("{}: abort: {}", r.name(), masked(last)),
                    format!("{status}: {last}"),
                )
            };
            record(r, cfg, &seeds, &mut groups, next, class, &detail);
            next += 1;
        }
    }
    tally.seconds = start.elapsed().as_secs_f64();
    (tally, groups)
}

/// The report: counts per reader, then the failure classes, most frequent first,
/// each with its first reproducers.
fn report(cfg: &Config, results: &[(Reader, Tally, Groups)]) -> String {
    let mut s = format!(
        "fuzz: seed {}, {} case(s) per reader, wall bound {:?} per case\n\n",
        cfg.seed, cfg.cases, cfg.wall
    );
    s.push_str("| reader | cases | accepted | refused | panics | hangs | aborts | non-finite or wrong but usable | seconds |\n|---|---|---|---|---|---|---|---|---|\n");
    for (r, t, _) in results {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.1} |\n",
            r.name(),
            t.cases,
            t.accepted,
            t.refused,
            t.panics,
            t.hangs,
            t.aborts,
            t.lies,
            t.seconds
        ));
    }
    let mut all: Vec<(&String, &Group)> = results.iter().flat_map(|(_, _, g)| g).collect();
    all.sort_by(|a, b| b.1.count.cmp(&a.1.count).then(a.0.cmp(b.0)));
    if !all.is_empty() {
        s.push_str(&format!("\n{} failure class(es):\n", all.len()));
    }
    for (class, g) in all {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let repro: Vec<String> = g
            .reproducers
            .iter()
            .map(|p| p.strip_prefix(root).unwrap_or(p).display().to_string())
            .collect();
        s.push_str(&format!(
            "\n- {} × {class}\n  e.g. {}\n  reproducers: {}\n",
            g.count,
            g.example,
            repro.join(", ")
        ));
    }
    s
}

#[test]
fn readers() {
    let cfg = Config::from_env();
    if let Ok(spec) = std::env::var("DEA_FIT_FUZZ_CHILD") {
        return child(&cfg, &spec);
    }
    let cfg = &cfg;
    let results: Vec<(Reader, Tally, Groups)> = std::thread::scope(|s| {
        let runs: Vec<_> = cfg
            .readers
            .iter()
            .map(|&r| (r, s.spawn(move || supervise(r, cfg))))
            .collect();
        runs.into_iter()
            .map(|(r, h)| {
                let (t, g) = h.join().unwrap();
                (r, t, g)
            })
            .collect()
    });
    let text = report(cfg, &results);
    std::fs::create_dir_all(failures_dir()).unwrap();
    std::fs::write(failures_dir().join("summary.md"), &text).unwrap();
    println!("{text}");
    let failed = results.iter().any(|(_, _, g)| !g.is_empty());
    assert!(!failed, "the fuzz harness found failures:\n{text}");
}
