//! The `flags` surface: the real binary run with numeric flag values replaced —
//! counts, lengths, times, frequencies, voltages, fractions, with and without units:
//! 0, −1, huge, 2⁶⁴ − 1, 1e308, inf, nan, 1e-300, garbage, a wrong unit. Each case
//! is one run of `dea-fit` in a fresh directory, killed after [`RUN_LIMIT`]: no
//! panic, no abort, no hang; a refusal is exit 2 with an `error:` line; an accepted
//! run (exit 0 or 1) writes CSV files with at least one row and finite numbers only.

use super::mutate::Mutated;
use super::readers::Verdict;
use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A run longer than this is a hang (below the harness's default wall bound of 10 s,
/// so that the run is killed here and the case reported as such).
const RUN_LIMIT: Duration = Duration::from_secs(8);

/// What a flag's value is.
#[derive(Clone, Copy)]
enum Kind {
    Count,
    Number,
    Length,
    Area,
    Time,
    Voltage,
    Capacitance,
    Stress,
    /// START:STOP:COUNT of plain numbers.
    Range,
    /// FMIN:FMAX:COUNT with frequency units.
    Sweep,
}

impl Kind {
    fn units(self) -> &'static [&'static str] {
        match self {
            Kind::Length => &["mm", "um", "m", "cm"],
            Kind::Area => &["mm2", "cm2", "m2"],
            Kind::Time => &["s", "ms", "us", "min"],
            Kind::Sweep => &["Hz", "kHz", "MHz"],
            Kind::Voltage => &["V", "kV"],
            Kind::Capacitance => &["pF", "nF", "F"],
            Kind::Stress => &["Pa", "kPa", "MPa"],
            _ => &[],
        }
    }
}

/// Numbers a value is replaced by.
const EXTREMES: [&str; 16] = [
    "0",
    "-1",
    "-0",
    "1e308",
    "-1e308",
    "1e-300",
    "inf",
    "nan",
    "18446744073709551615",
    "9223372036854775807",
    "4294967296",
    "1000000000",
    "1e8",
    "2.5",
    "1e-17",
    "garbage",
];

/// `old` (a number with an optional unit) with its number scaled by 10^±1 at
/// random: a plausible value, as often as not one the command accepts.
fn plausible(old: &str, rng: &mut ChaCha8Rng) -> String {
    let end = old
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .unwrap_or(old.len());
    let (num, unit) = old.split_at(end);
    let v: f64 = num.parse().unwrap_or(1.0);
    let scaled = v * 10f64.powf(rng.gen_range(-1.0..1.0));
    match num.contains('.') || num.contains('e') {
        true => format!("{scaled}{unit}"),
        false => format!("{}{unit}", scaled.round().max(1.0)),
    }
}

/// A replacement value of `kind` for the default `old`: 30 % of the time a plausible
/// one, else an extreme with a unit of its kind, none or a wrong one.
fn value(kind: Kind, old: &str, rng: &mut ChaCha8Rng) -> String {
    if rng.gen_bool(0.3) {
        return match kind {
            Kind::Range | Kind::Sweep => {
                let mut parts: Vec<String> = old.split(':').map(str::to_string).collect();
                let i = rng.gen_range(0..parts.len());
                parts[i] = plausible(&parts[i], rng);
                parts.join(":")
            }
            _ => plausible(old, rng),
        };
    }
    let x = *EXTREMES.choose(rng).unwrap();
    let unit = |rng: &mut ChaCha8Rng| match rng.gen_range(0..6) {
        0 => String::new(),
        1 => "furlong".into(),
        _ => kind
            .units()
            .choose(rng)
            .map_or(String::new(), |u| u.to_string()),
    };
    match kind {
        Kind::Range | Kind::Sweep => {
            let mut parts: Vec<String> = old.split(':').map(str::to_string).collect();
            let i = rng.gen_range(0..parts.len());
            parts[i] = match (i, kind) {
                (2, _) => x.to_string(),
                (_, Kind::Sweep) => format!("{x}{}", unit(rng)),
                _ => x.to_string(),
            };
            parts.join(":")
        }
        Kind::Count | Kind::Number => x.to_string(),
        _ => format!("{x}{}", unit(rng)),
    }
}

/// A command: its fixed arguments (`%path` a repository file) and its numeric flags
/// with their defaults (the values of a run that works).
struct Cmd {
    args: &'static [&'static str],
    flags: &'static [(&'static str, Kind, &'static str)],
}

const COMMANDS: [Cmd; 8] = [
    Cmd {
        args: &["synth", "lcr", "--out", "out.csv"],
        flags: &[
            ("--eps-r", Kind::Number, "4.7"),
            ("--tan-delta", Kind::Number, "0.005"),
            ("--diameter", Kind::Length, "30mm"),
            ("--thickness", Kind::Length, "1mm"),
            ("--sweep", Kind::Sweep, "100Hz:1MHz:17"),
            ("--stray", Kind::Capacitance, "0.3pF"),
            ("--noise", Kind::Number, "0.001"),
        ],
    },
    Cmd {
        args: &["synth", "lcr", "--pair", "cs-rs", "--out", "out.csv"],
        flags: &[
            ("--eps-r", Kind::Number, "3"),
            ("--tan-delta", Kind::Number, "0.01"),
            ("--area", Kind::Area, "14.39cm2"),
            ("--thickness", Kind::Length, "2.2mm"),
            ("--sweep", Kind::Sweep, "20Hz:2MHz:51"),
        ],
    },
    Cmd {
        args: &[
            "synth",
            "relaxation",
            "--preset",
            "elatrache2021-table-3.3",
            "--out",
            "out.csv",
        ],
        flags: &[
            ("--strain", Kind::Number, "0.5"),
            ("--ramp-time", Kind::Time, "0.8s"),
            ("--time", Kind::Range, "0.01:1000:200"),
            ("--noise", Kind::Number, "0.01"),
        ],
    },
    Cmd {
        args: &[
            "synth",
            "hyperelastic",
            "--model",
            "yeoh",
            "--param",
            "C10=69.3kPa",
            "--param",
            "C20=-0.5kPa",
            "--param",
            "C30=0.01kPa",
            "--out",
            "out.csv",
        ],
        flags: &[
            ("--stretch", Kind::Range, "1.0:3.0:25"),
            ("--noise", Kind::Number, "0.01"),
            ("--noise-abs", Kind::Stress, "100Pa"),
        ],
    },
    Cmd {
        args: &[
            "static",
            "%datasets/scenes/stack_step_5kV.toml",
            "--no-report",
            "--out",
            "out.csv",
        ],
        flags: &[
            ("--points", Kind::Count, "200"),
            ("--stretch-min", Kind::Number, "0.3"),
        ],
    },
    Cmd {
        args: &[
            "synth",
            "trace",
            "%datasets/scenes/stack_step_5kV_damped.toml",
            "--out",
            "out.csv",
        ],
        flags: &[
            ("--noise", Kind::Voltage, "voltage=5V"),
            ("--seed", Kind::Count, "1"),
        ],
    },
    Cmd {
        args: &[
            "permittivity",
            "%datasets/composites/sylgard_batio3/s00_cpd.csv",
            "--out",
            "out.json",
        ],
        flags: &[
            ("--diameter", Kind::Length, "42.8mm"),
            ("--thickness", Kind::Length, "2.2mm"),
            ("--stray", Kind::Capacitance, "0.3pF"),
        ],
    },
    Cmd {
        args: &[
            "relaxation",
            "%datasets/vhb4910/relaxation.csv",
            "--no-report",
            "--max-terms",
            "2",
            "--out",
            "out.json",
        ],
        flags: &[
            ("--strain", Kind::Number, "0.5"),
            ("--ramp-time", Kind::Time, "0.8s"),
            ("--grid-per-decade", Kind::Count, "6"),
        ],
    },
];

fn repo(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(p)
        .display()
        .to_string()
}

/// A case: one command with one or two of its flags' values replaced, the others
/// at their defaults; its arguments one a line (`%path` for a repository file).
pub fn case(rng: &mut ChaCha8Rng) -> Mutated {
    let cmd = COMMANDS.choose(rng).unwrap();
    let n = rng.gen_range(1..=2).min(cmd.flags.len());
    let changed: Vec<usize> = rand::seq::index::sample(rng, cmd.flags.len(), n).into_vec();
    let mut args: Vec<String> = cmd.args.iter().map(|a| a.to_string()).collect();
    let (mut what, mut kind) = (Vec::new(), Vec::new());
    for (i, &(flag, k, default)) in cmd.flags.iter().enumerate() {
        let v = match changed.contains(&i) {
            true => {
                let (prefix, old) = default
                    .split_once('=')
                    .map_or(("", default), |(p, o)| (p, o));
                let new = value(k, old, rng);
                let new = match prefix {
                    "" => new,
                    p => format!("{p}={new}"),
                };
                what.push(format!("{flag} {default} → {new}"));
                kind.push(flag.to_string());
                new
            }
            false => default.to_string(),
        };
        args.push(format!("{flag}={v}"));
    }
    Mutated {
        bytes: args.join("\n").into_bytes(),
        what: format!("{} {}", cmd.args[..2].join(" "), what.join("; ")),
        kind: kind.join(" + "),
    }
}

/// The arguments of a case's file, `%path` made a repository path.
pub fn args(bytes: &[u8]) -> Vec<String> {
    String::from_utf8_lossy(bytes)
        .lines()
        .map(|a| match a.strip_prefix('%') {
            Some(p) => repo(p),
            None => a.to_string(),
        })
        .collect()
}

/// The command line that replays a case in `dir`.
pub fn replay(bytes: &[u8], dir: &Path) -> String {
    let quoted: Vec<String> = args(bytes).iter().map(|a| format!("'{a}'")).collect();
    format!("cd {} && dea-fit {}", dir.display(), quoted.join(" "))
}

/// A header and at least one row (a count that wrapped to 0 once wrote an empty
/// sweep under `ok`), and every field of every CSV line that is a number finite.
fn finite_csv(path: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    if text.lines().filter(|l| !l.starts_with('#')).count() < 2 {
        return Err(format!("{}: no data row", path.display()));
    }
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#'))
    {
        for f in line.split(',') {
            if f.trim().parse::<f64>().is_ok_and(|v| !v.is_finite()) {
                return Err(format!("{}:{}: {f}", path.display(), i + 1));
            }
        }
    }
    Ok(())
}

/// Run the case's command in a fresh directory inside `dir`.
pub fn run(bytes: &[u8], dir: &Path) -> Verdict {
    let work = tempfile::tempdir_in(dir).unwrap();
    let (status, stderr) = match child(&args(bytes), work.path(), "flags") {
        Ok(x) => x,
        Err(v) => return v,
    };
    match status.code() {
        Some(2) if stderr.contains("error") => Verdict::Refused,
        Some(0 | 1) => {
            let csvs = std::fs::read_dir(work.path())
                .unwrap()
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "csv"));
            for p in csvs {
                if let Err(detail) = finite_csv(&p) {
                    return Verdict::Failed {
                        class: "flags: a non-finite value or no row written".into(),
                        detail,
                    };
                }
            }
            Verdict::Accepted
        }
        code => Verdict::Failed {
            class: format!("flags: exit {code:?} (an abort, or a refusal without an error)"),
            detail: first_error(&stderr),
        },
    }
}

/// The first line of stderr that says a panic or an error, at most 200 characters.
pub fn first_error(s: &str) -> String {
    s.lines()
        .find(|l| l.contains("panicked") || l.starts_with("error"))
        .unwrap_or("")
        .chars()
        .take(200)
        .collect()
}

/// Run `dea-fit args…` in `cwd`, killed after [`RUN_LIMIT`]: its exit status and
/// stderr, or the failure (a hang, a panic) of a case of the surface `what`.
pub fn child(
    args: &[String],
    cwd: &Path,
    what: &str,
) -> Result<(std::process::ExitStatus, String), Verdict> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_dea-fit"))
        .args(args)
        .current_dir(cwd)
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the dea-fit binary runs");
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut err, &mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if start.elapsed() > RUN_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr = reader.join().unwrap();
    let Some(status) = status else {
        return Err(Verdict::Failed {
            class: format!("{what}: hang (over {RUN_LIMIT:?})"),
            detail: "killed".into(),
        });
    };
    if stderr.contains("panicked") {
        let at = stderr
            .lines()
            .find(|l| l.contains("panicked at"))
            .and_then(|l| l.split("panicked at ").nth(1))
            .unwrap_or("?");
        return Err(Verdict::Failed {
            class: format!("{what}: panic at {at}"),
            detail: first_error(&stderr),
        });
    }
    Ok((status, stderr))
}
