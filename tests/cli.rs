//! The `dea-fit` binary as a user meets it: the bad-input corpus
//! (`tests/data/bad/`), accepted input variants (`tests/data/ok/`), golden outputs
//! (`tests/golden/`), fit-file and report behaviour, and the README's first command.
//!
//! Every run of the binary happens in a fresh temporary directory with `--out` and
//! `--report` pointing into it, so the tests never write into the worktree (except
//! when regenerating goldens, see [`golden`]).

use crate::support::{copy_dir, names_in, repo, run};
use dea_fit::data::Dataset;
use dea_fit::io::tensile::{self, TensileOptions};
use dea_fit::material::hyperelastic::Mode;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

fn data(dir: &str, file: &str) -> PathBuf {
    repo().join("tests/data").join(dir).join(file)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Run `dea-fit hyperelastic ARGS --out DIR/fit.json --report DIR/report` in `dir`.
fn hyperelastic(dir: &Path, args: &[&str]) -> Output {
    hyperelastic_in(dir, dir, args)
}

/// Run `dea-fit hyperelastic ARGS --out OUT/fit.json --report OUT/report` in `cwd`.
fn hyperelastic_in(cwd: &Path, out: &Path, args: &[&str]) -> Output {
    let report = out.join("report");
    let out = out.join("fit.json");
    let mut all = vec!["hyperelastic"];
    all.extend_from_slice(args);
    all.extend_from_slice(&[
        "--out",
        out.to_str().expect("utf-8 temp path"),
        "--report",
        report.to_str().expect("utf-8 temp path"),
    ]);
    run(cwd, &all)
}

/// Assert a successful run and return its stdout.
fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}\nstderr:\n{}",
        o.status.code(),
        stderr(o)
    );
    stdout(o)
}

fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary directory")
}

fn read_json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

// ---------------------------------------------------------------------------------
// Bad input: tests/data/bad/expected.tsv
// ---------------------------------------------------------------------------------

/// One line of `tests/data/bad/expected.tsv` (format documented in that file).
struct BadCase {
    file: String,
    args: Vec<String>,
    location: String,
    expected: Vec<String>,
}

fn bad_cases() -> Vec<BadCase> {
    let table = std::fs::read_to_string(data("bad", "expected.tsv")).expect("expected.tsv");
    table
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let cols: Vec<&str> = l.split('\t').collect();
            assert!(cols.len() >= 4, "expected.tsv: too few columns in {l:?}");
            let path = data("bad", cols[0]);
            let args = if cols[1] == "-" { "FILE" } else { cols[1] };
            BadCase {
                file: cols[0].to_string(),
                args: args
                    .split_whitespace()
                    .map(|a| {
                        if a == "FILE" {
                            path.display().to_string()
                        } else {
                            a.to_string()
                        }
                    })
                    .collect(),
                location: cols[2].to_string(),
                expected: cols[3..].iter().map(|s| s.to_string()).collect(),
            }
        })
        .collect()
}

/// Every malformed file gets exit status 2, its own message at its own location,
/// no panic, and leaves no fit file or report behind.
#[test]
fn bad_input_corpus() {
    let cases = bad_cases();
    assert!(cases.len() >= 24, "the corpus shrank to {}", cases.len());
    // The table and the directory list the same files.
    let mut listed: Vec<&str> = cases.iter().map(|c| c.file.as_str()).collect();
    listed.sort();
    let on_disk: Vec<String> = names_in(&data("bad", ""))
        .into_iter()
        .filter(|n| n != "expected.tsv")
        .collect();
    assert_eq!(listed, on_disk, "expected.tsv and tests/data/bad/ disagree");

    let mut failures = Vec::new();
    for case in &cases {
        let dir = tempdir();
        let args: Vec<&str> = case.args.iter().map(String::as_str).collect();
        let o = hyperelastic(dir.path(), &args);
        let err = stderr(&o);
        let mut problems = Vec::new();
        if o.status.code() != Some(2) {
            problems.push(format!("exit status {:?}, expected 2", o.status.code()));
        }
        if err.contains("panicked") {
            problems.push("panicked".into());
        }
        let path = data("bad", &case.file).display().to_string();
        let prefix = match case.location.as_str() {
            "-" => "error: ".to_string(),
            "file" => format!("error: {path}: "),
            loc => format!("error: {path}:{loc}: "),
        };
        if !err.starts_with(&prefix) {
            problems.push(format!("message does not start with {prefix:?}"));
        }
        if case.location == "-" && err.contains(&path) {
            problems.push("a non-file error names the file as its location".into());
        }
        for want in &case.expected {
            if !err.contains(want.as_str()) {
                problems.push(format!("missing {want:?}"));
            }
        }
        let left = names_in(dir.path());
        if !left.is_empty() {
            problems.push(format!("wrote {left:?}"));
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{}: {}\n  stderr: {err}",
                case.file,
                problems.join("; ")
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

// ---------------------------------------------------------------------------------
// Accepted variants: tests/data/ok/
// ---------------------------------------------------------------------------------

/// A file large enough to be read in parallel (≥ PARALLEL_ROWS rows) gives the samples
/// of reading its rows one by one, and of two bad rows reports the first in file order
/// (the later one falls in an earlier-finishing block as often as not).
#[test]
fn big_files_read_in_parallel_as_in_order() {
    use dea_fit::fit::problem::PARALLEL_ROWS;
    use dea_fit::io::table::Table;
    let n = 3 * PARALLEL_ROWS + 7;
    let mut text = String::from("stretch,nominal_stress_kPa\n");
    for i in 0..n {
        text.push_str(&format!("{},{}\n", 1.0 + i as f64 * 1e-5, 0.5 * i as f64));
    }
    let opts = TensileOptions::default();
    let path = Path::new("big.csv");
    let d = tensile::from_table(&Table::parse(path, text.as_bytes()).unwrap(), &opts).unwrap();
    assert_eq!(d.samples.len(), n);
    for (i, s) in d.samples.iter().enumerate() {
        assert_eq!((s.line, s.mode), (i + 2, Mode::Uniaxial));
        assert_eq!(
            s.stretch,
            format!("{}", 1.0 + i as f64 * 1e-5).parse::<f64>().unwrap()
        );
        assert_eq!(
            s.stress,
            1e3 * format!("{}", 0.5 * i as f64).parse::<f64>().unwrap()
        );
    }
    // Bad rows in the second block and the last: the error names the earlier line.
    let mut lines: Vec<&str> = text.lines().collect();
    let (early, late) = (PARALLEL_ROWS + 11, n - 1);
    lines[early] = "1.1,x";
    lines[late] = "-1,0";
    let bad = lines.join("\n");
    let e = tensile::from_table(&Table::parse(path, bad.as_bytes()).unwrap(), &opts)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with(&format!("big.csv:{}:2", early + 1)), "{e}");
}

fn read_ok(file: &str, opts: &TensileOptions) -> Dataset {
    tensile::read(&data("ok", file), opts).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// (mode, stretch, stress, weight) of every sample, sorted by mode then stretch.
fn samples(d: &Dataset) -> Vec<(Mode, f64, f64, f64)> {
    let mut v: Vec<_> = d
        .samples
        .iter()
        .map(|s| (s.mode, s.stretch, s.stress, s.weight))
        .collect();
    v.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    v
}

/// Relative closeness; both zero counts as equal.
fn close(a: f64, b: f64, rel: f64) -> bool {
    a == b || (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// Same samples in SI to 1e-12 relative (the variants write the same decimal values
/// in other units, so only the floating-point unit conversion may differ: ~1e-16).
fn assert_same_samples(name: &str, got: &Dataset, want: &Dataset) {
    let (g, w) = (samples(got), samples(want));
    assert_eq!(g.len(), w.len(), "{name}: number of samples");
    for (a, b) in g.iter().zip(&w) {
        assert!(
            a.0 == b.0 && close(a.1, b.1, 1e-12) && close(a.2, b.2, 1e-12) && a.3 == b.3,
            "{name}: {a:?} differs from {b:?}"
        );
    }
}

/// Each variant file holds the samples of `plain.csv`, read by the library and by the
/// binary (which must accept it and fit the same Neo-Hookean μ).
#[test]
fn accepted_variants_match_the_plain_file() {
    let none = TensileOptions::default();
    let plain = read_ok("plain.csv", &none);
    assert_eq!(plain.samples.len(), 7);
    let variants: &[(&str, &[&str])] = &[
        ("semicolon_decimal_comma.csv", &[]),
        ("tab.tsv", &[]),
        ("bom.csv", &[]),
        ("crlf.csv", &[]),
        ("cr_only.csv", &[]),
        ("comments_blank_lines.csv", &[]),
        ("quoted.csv", &[]),
        ("strain.csv", &[]),
        ("strain_pct.csv", &[]),
        ("true_stress_MPa.csv", &[]),
        ("force_N.csv", &["--area", "22mm2"]),
        ("displacement_mm.csv", &["--gauge-length", "80mm"]),
        ("bracket_header.csv", &[]),
        ("n_per_mm2.csv", &[]),
    ];
    let dir = tempdir();
    let mu = |file: &Path, extra: &[&str]| -> f64 {
        let mut args = vec![file.to_str().expect("utf-8 path"), "--model", "neo-hookean"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--json", "--no-report"]);
        let o = hyperelastic(dir.path(), &args);
        let fit: Value = serde_json::from_str(&ok(&o)).expect("--json prints JSON");
        fit["parameters"][0]["value"].as_f64().expect("mu")
    };
    let mu_plain = mu(&data("ok", "plain.csv"), &[]);
    for (file, extra) in variants {
        let opts = TensileOptions {
            area: extra.contains(&"--area").then_some(22e-6),
            gauge_length: extra.contains(&"--gauge-length").then_some(80e-3),
            mode: None,
        };
        let got = read_ok(file, &opts);
        assert_same_samples(file, &got, &plain);
        if *file == "true_stress_MPa.csv" {
            assert!(got.sources[0].conversions[0].contains("true stress / stretch"));
        }
        let m = mu(&data("ok", file), extra);
        // The same samples to 1e-12 give the same exact linear solve to ~1e-12.
        assert!(close(m, mu_plain, 1e-9), "{file}: μ {m} vs {mu_plain}");
    }
}

/// A `mode` column mixing modes holds the same samples as the plain uniaxial file plus
/// the plain equibiaxial file passed with `--equibiaxial`.
#[test]
fn mode_column_mixes_modes() {
    let mixed = read_ok("mode_column.csv", &TensileOptions::default());
    let mut separate = read_ok("plain.csv", &TensileOptions::default());
    separate.extend(read_ok(
        "plain_equibiaxial.csv",
        &TensileOptions {
            mode: Some(Mode::Equibiaxial),
            ..TensileOptions::default()
        },
    ));
    assert_eq!(
        mixed.sources[0].modes,
        vec![Mode::Uniaxial, Mode::Equibiaxial]
    );
    assert_same_samples("mode_column.csv", &mixed, &separate);
}

/// The `weight` column is read as written; everything else as in the plain file.
#[test]
fn weight_column_is_read() {
    let got = read_ok("weight.csv", &TensileOptions::default());
    let plain = read_ok("plain.csv", &TensileOptions::default());
    let weights: Vec<f64> = got.samples.iter().map(|s| s.weight).collect();
    assert_eq!(weights, [1.0, 2.0, 0.5, 1.0, 3.0, 1.0, 0.25]);
    for (a, b) in got.samples.iter().zip(&plain.samples) {
        assert!(close(a.stretch, b.stretch, 1e-12) && close(a.stress, b.stress, 1e-12));
        assert_eq!(b.weight, 1.0);
    }
}

/// End to end, weight w on a point is the same objective as the point written w
/// times (the residual is scaled by √w), so both files give the same Yeoh fit.
#[test]
fn integer_weights_equal_repeated_points() {
    let dir = tempdir();
    let rows = [
        ("1.0", "0", 1),
        ("1.3", "40", 2),
        ("1.7", "71", 1),
        ("2.2", "93", 3),
        ("3.0", "121", 1),
        ("4.0", "170", 2),
    ];
    let mut weighted = String::from("stretch,nominal_stress_kPa,weight\n");
    let mut repeated = String::from("stretch,nominal_stress_kPa\n");
    for (l, p, w) in rows {
        weighted.push_str(&format!("{l},{p},{w}\n"));
        repeated.push_str(&format!("{l},{p}\n").repeat(w));
    }
    let fit = |name: &str, text: &str| -> Vec<f64> {
        let f = dir.path().join(name);
        std::fs::write(&f, text).expect("write");
        let o = hyperelastic(
            dir.path(),
            &[
                f.to_str().expect("utf-8"),
                "--model",
                "yeoh",
                "--json",
                "--no-report",
            ],
        );
        let v: Value = serde_json::from_str(&ok(&o)).expect("json");
        v["parameters"]
            .as_array()
            .expect("parameters")
            .iter()
            .map(|p| p["value"].as_f64().expect("value"))
            .collect()
    };
    let a = fit("weighted.csv", &weighted);
    let b = fit("repeated.csv", &repeated);
    for (x, y) in a.iter().zip(&b) {
        // Same normal equations up to summation order: exact linear solve, 1e-9.
        assert!(close(*x, *y, 1e-9), "{a:?} vs {b:?}");
    }
}

// ---------------------------------------------------------------------------------
// Golden outputs: tests/golden/
// ---------------------------------------------------------------------------------

/// Relative tolerance for numbers in golden files: the linear models are solved
/// exactly (SVD), so only floating-point rounding differs across platforms and
/// compilers (~1e-15 relative, amplified by the condition number, here < 1e3).
const GOLDEN_RTOL: f64 = 1e-9;

/// Replace what changes from run to run or machine to machine: the wall-clock time,
/// the tool version, and absolute paths (made relative to the repository).
fn redact_json(v: &mut Value) {
    v["tool_version"] = Value::from("<tool_version>");
    v["solver"]["seconds"] = Value::from(0.0);
    let root = format!("{}/", repo().display());
    if let Some(files) = v["provenance"]["files"].as_array_mut() {
        for f in files {
            if let Some(p) = f["path"].as_str() {
                f["path"] = Value::from(p.strip_prefix(&root).unwrap_or(p));
            }
        }
    }
}

/// The same as [`redact_json`] for the human-readable summary.
fn redact_text(s: &str) -> String {
    s.lines()
        .map(|l| {
            if l.starts_with("fit: ") {
                "fit: <out>".to_string()
            } else if l.starts_with("report: ") {
                "report: <report>".to_string()
            } else {
                // "..., 0.036 ms." → "..., <time> ms."
                let words: Vec<&str> = l.split(' ').collect();
                let timed = |i: usize| {
                    words
                        .get(i + 1)
                        .is_some_and(|n| n.trim_end_matches(['.', ',', ';']) == "ms")
                        && words[i].parse::<f64>().is_ok()
                };
                (0..words.len())
                    .map(|i| if timed(i) { "<time>" } else { words[i] })
                    .collect::<Vec<_>>()
                    .join(" ")
                    .replace(&format!("{}/", repo().display()), "")
            }
        })
        .map(|l| l + "\n")
        .collect()
}

/// Structural equality, numbers to `rtol`; the path of the first difference.
fn json_diff(got: &Value, want: &Value, path: &str, rtol: f64) -> Option<String> {
    match (got, want) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64()?, b.as_f64()?);
            (!close(a, b, rtol)).then(|| format!("{path}: {a} vs golden {b}"))
        }
        (Value::Array(a), Value::Array(b)) => {
            if a.len() != b.len() {
                return Some(format!("{path}: length {} vs golden {}", a.len(), b.len()));
            }
            a.iter()
                .zip(b)
                .enumerate()
                .find_map(|(i, (x, y))| json_diff(x, y, &format!("{path}[{i}]"), rtol))
        }
        (Value::Object(a), Value::Object(b)) => {
            let (ka, kb): (Vec<_>, Vec<_>) = (a.keys().collect(), b.keys().collect());
            if ka != kb {
                return Some(format!("{path}: keys {ka:?} vs golden {kb:?}"));
            }
            a.iter()
                .find_map(|(k, x)| json_diff(x, &b[k], &format!("{path}.{k}"), rtol))
        }
        _ => (got != want).then(|| format!("{path}: {got} vs golden {want}")),
    }
}

/// Compare `got` with `tests/golden/<name>`, or (re)write the golden file when the
/// environment variable `UPDATE_GOLDEN=1` is set:
///
/// ```text
/// UPDATE_GOLDEN=1 cargo test --release golden   # then review `git diff tests/golden`
/// ```
///
/// Regenerate only after a deliberate change of the output (a new field, a changed
/// dataset, a better estimator), and say why in the commit.
pub fn golden(name: &str, got: &str, same: impl Fn(&str) -> Option<String>) {
    let path = repo().join("tests/golden").join(name);
    if std::env::var("UPDATE_GOLDEN").is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(path.parent().expect("parent")).expect("mkdir");
        std::fs::write(&path, got).expect("write golden");
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; create it with UPDATE_GOLDEN=1 cargo test --release golden",
            path.display()
        )
    });
    if let Some(diff) = same(&want) {
        panic!(
            "output differs from {}: {diff}\nif the change is intended: UPDATE_GOLDEN=1 cargo test --release golden\n--- got ---\n{got}",
            path.display()
        );
    }
}

fn golden_json(name: &str, args: &[&str]) {
    // Run in the repository so that the data paths are relative, as a user types them.
    let dir = tempdir();
    let o = hyperelastic_in(
        &repo(),
        dir.path(),
        &[args, &["--json", "--no-report"]].concat(),
    );
    let mut v: Value = serde_json::from_str(&ok(&o)).expect("--json prints JSON");
    redact_json(&mut v);
    let text = serde_json::to_string_pretty(&v).expect("serialise") + "\n";
    golden(name, &text, |want| {
        let want: Value = serde_json::from_str(want).expect("golden is JSON");
        json_diff(&v, &want, "$", GOLDEN_RTOL)
    });
}

/// `dea-fit hyperelastic datasets/vhb4910/uniaxial.csv --model yeoh --json`.
#[test]
fn golden_vhb4910_yeoh_json() {
    golden_json(
        "vhb4910-uniaxial-yeoh.json",
        &["datasets/vhb4910/uniaxial.csv", "--model", "yeoh"],
    );
}

/// Treloar's three modes, `--model mooney-rivlin --json`.
#[test]
fn golden_treloar_mooney_rivlin_json() {
    golden_json(
        "treloar-3modes-mooney-rivlin.json",
        &[
            "datasets/treloar/uniaxial.csv",
            "--equibiaxial",
            "datasets/treloar/equibiaxial.csv",
            "--planar",
            "datasets/treloar/planar.csv",
            "--model",
            "mooney-rivlin",
        ],
    );
}

/// The human-readable table for the VHB 4910 Yeoh fit (time redacted; the printed
/// numbers are rounded to 5 digits, so they are compared as text).
#[test]
fn golden_vhb4910_yeoh_table() {
    let dir = tempdir();
    let o = hyperelastic_in(
        &repo(),
        dir.path(),
        &[
            "datasets/vhb4910/uniaxial.csv",
            "--model",
            "yeoh",
            "--no-report",
        ],
    );
    let text = redact_text(&ok(&o));
    golden("vhb4910-uniaxial-yeoh.txt", &text, |want| {
        (want != text).then(|| "the text differs".to_string())
    });
}

/// `dea-fit static` on the seed's stack: the pull-in line, the curve's shape table
/// (printed numbers are rounded, so compared as text) and the status.
#[test]
fn golden_static_stack_table() {
    let o = run(
        &repo(),
        &[
            "static",
            "datasets/scenes/stack_step_5kV.toml",
            "--no-report",
        ],
    );
    let text = ok(&o);
    golden("static-stack_step_5kV.txt", &text, |want| {
        (want != text).then(|| "the text differs".to_string())
    });
}

/// `static --out`: the whole curve as CSV, units in the headers, equal to the
/// `--json` curve; the capacitance is the stack's closed form
/// C(λ) = N·εr·ε0·πR²/(H·λ²) (incompressible layers: area ∝ 1/λ, gap ∝ λ), to 1e-12
/// relative (rounding only); the shape table spans the curve with the pull-in at the
/// voltage maximum; a different old CSV is kept aside, never overwritten silently.
#[test]
fn static_out_writes_the_curve_as_csv() {
    let dir = tempdir();
    let scene = repo_file("datasets/scenes/stack_step_5kV.toml");
    let json: Value = serde_json::from_str(&ok(&run(
        dir.path(),
        &[
            "static",
            &scene,
            "--json",
            "--out",
            "curve.csv",
            "--no-report",
        ],
    )))
    .expect("JSON");
    assert_eq!(json["curve_file"], "curve.csv");
    let csv = std::fs::read_to_string(dir.path().join("curve.csv")).expect("curve.csv");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("voltage_V,stretch,capacitance_F"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    let curve = json["curve"].as_array().expect("curve");
    assert_eq!(rows.len(), curve.len());
    assert!(
        rows.len() > 190,
        "the whole curve (200 points from the rest state at 0 V)"
    );
    let c_ref =
        10.0 * 4.7 * 8.854_187_812_8e-12 * std::f64::consts::PI * 2.25e-3f64.powi(2) / 500e-6;
    for (r, p) in rows.iter().zip(curve) {
        assert_eq!(r[0], p["voltage_V"].as_f64().unwrap());
        assert_eq!(r[1], p["stretch"].as_f64().unwrap());
        assert_eq!(r[2], p["capacitance_F"].as_f64().unwrap());
        assert!(
            close(r[2] * r[1] * r[1], c_ref, 1e-12),
            "C·λ² = {}",
            r[2] * r[1] * r[1]
        );
    }
    let v_pull_in = json["pull_in"]["voltage_V"].as_f64().expect("pull-in");
    assert!(rows.iter().all(|r| r[0] <= v_pull_in));

    // The text: the pull-in row between the rows around it, at the largest voltage.
    let text = ok(&run(
        dir.path(),
        &["static", &scene, "--out", "curve.csv", "--no-report"],
    ));
    assert_eq!(
        names_in(dir.path()),
        ["curve.csv"],
        "the same curve: refreshed"
    );
    let table: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("voltage (kV)"))
        .skip(2)
        .take_while(|l| !l.starts_with("curve:"))
        .collect();
    assert_eq!(
        table.len(),
        12,
        "ten rows, the breakdown and the pull-in:\n{text}"
    );
    let volts: Vec<f64> = table
        .iter()
        .map(|l| l.split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    let peak = table
        .iter()
        .position(|l| l.ends_with("pull-in"))
        .expect("pull-in row");
    assert!(volts.iter().all(|&v| v <= volts[peak]), "{volts:?}");
    assert!(text.contains("curve: curve.csv\nstatus: ok\n"), "{text}");

    // A different curve: the old file is kept aside, and stderr says so.
    let o = run(
        dir.path(),
        &[
            "static",
            &scene,
            "--out",
            "curve.csv",
            "--points",
            "20",
            "--no-report",
        ],
    );
    ok(&o);
    assert_eq!(names_in(dir.path()), ["curve.csv", "curve.previous-1.csv"]);
    assert!(stderr(&o).contains("kept as"), "{}", stderr(&o));
}

/// The README's scene with `breakdown = "25 V/um"` and the 5 kV step replaced,
/// written to `dir/name`.
fn breakdown_scene(dir: &Path, name: &str, breakdown: Option<&str>, amplitude: &str) -> String {
    let text = std::fs::read_to_string(repo().join("datasets/scenes/stack_step_5kV.toml"))
        .expect("the README's scene");
    let line = match breakdown {
        Some(b) => format!("breakdown = {b}\n"),
        None => String::new(),
    };
    let text = text
        .replace("breakdown = \"25 V/um\"\n", &line)
        .replace(
            "amplitude = \"5 kV\"",
            &format!("amplitude = \"{amplitude}\""),
        )
        .replace("span = \"10 s\"", "span = \"50 ms\"")
        .replace("samples = 2000", "samples = 10");
    std::fs::write(dir.join(name), text).expect("written");
    name.to_string()
}

/// `static` says which of breakdown and pull-in comes first, a case each way: on
/// the README's scene (25 V/µm, stated) the field reaches Eb at V_b = Eb·zd0·λ on
/// the stable branch, 11.8 kV, long before the pull-in at 20.75 kV (where the true
/// field is 65 V/µm); at 100 V/µm the pull-in comes first. Without a breakdown the
/// output (table and JSON) says none was checked.
#[test]
fn static_says_whether_breakdown_or_pull_in_comes_first() {
    let dir = tempdir();
    let json = |scene: &str| -> Value {
        serde_json::from_str(&ok(&run(
            dir.path(),
            &["static", scene, "--json", "--no-report"],
        )))
        .expect("JSON")
    };
    let readme = repo_file("datasets/scenes/stack_step_5kV.toml");
    let v = json(&readme);
    let b = &v["breakdown"];
    assert_eq!(b["first"], "breakdown", "{b}");
    assert_eq!(b["checked"], true);
    assert_eq!(v["status"], "ok", "5 kV stays below breakdown");
    let (vb, lam) = (
        b["point"]["voltage_V"].as_f64().unwrap(),
        b["point"]["stretch"].as_f64().unwrap(),
    );
    // On the curve the field meets Eb: V = Eb·zd0·λ, to 1e-9 relative (λ bisected to
    // 1e-12, the curve's slope a few kV per unit λ).
    assert!(
        (vb / (25e6 * 500e-6 * lam) - 1.0).abs() < 1e-9,
        "{vb} at {lam}"
    );
    let v_pi = v["pull_in"]["voltage_V"].as_f64().unwrap();
    assert!(
        vb < v_pi && (11_000.0..12_500.0).contains(&vb),
        "{vb} {v_pi}"
    );
    // The field under the 5 kV input: E = V/(zd0·λ), margin 1 − E/Eb (1e-12: rounding).
    let e = b["peak"]["field_V_per_m"].as_f64().unwrap();
    let l_in = b["peak"]["stretch"].as_f64().unwrap();
    assert!((e / (5e3 / (500e-6 * l_in)) - 1.0).abs() < 1e-12);
    assert!((b["margin"].as_f64().unwrap() - (1.0 - e / 25e6)).abs() < 1e-12);
    let text = ok(&run(dir.path(), &["static", &readme, "--no-report"]));
    assert!(text.contains("breakdown comes first"), "{text}");
    assert!(
        text.contains("64.96 V/µm"),
        "the true field at pull-in:\n{text}"
    );
    assert!(
        text.lines().any(|l| l.trim_end().ends_with("breakdown")),
        "{text}"
    );

    let strong = breakdown_scene(dir.path(), "strong.toml", Some("\"100 V/um\""), "5 kV");
    let v = json(&strong);
    assert_eq!(v["breakdown"]["first"], "pull_in", "{}", v["breakdown"]);
    assert!(v["breakdown"]["point"].is_null());
    let text = ok(&run(dir.path(), &["static", &strong, "--no-report"]));
    assert!(text.contains("pull-in comes first"), "{text}");

    let none = breakdown_scene(dir.path(), "none.toml", None, "5 kV");
    let v = json(&none);
    assert_eq!(v["breakdown"]["checked"], false);
    assert!(v["breakdown"]["message"]
        .as_str()
        .unwrap()
        .starts_with("breakdown not checked: the scene states none"));
    let text = ok(&run(dir.path(), &["static", &none, "--no-report"]));
    assert!(
        text.contains("breakdown not checked: the scene states none"),
        "{text}"
    );
    assert!(!text.contains("breakdown V_b"), "{text}");
}

/// A drive beyond breakdown (15 kV: past V_b = 11.8 kV, below the pull-in at
/// 20.75 kV) is the status `breakdown` of `static` and of `simulate`, in the summary
/// and the JSON: exit 0, and exit 1 under `--strict`; 10 kV (static field 20.5 V/µm,
/// the step's overshoot included below 25) is not.
#[test]
fn a_drive_beyond_breakdown_blocks_under_strict() {
    let dir = tempdir();
    let over = breakdown_scene(dir.path(), "over.toml", Some("\"25 V/um\""), "15 kV");
    for cmd in ["static", "simulate"] {
        let o = run(dir.path(), &[cmd, &over, "--no-report"]);
        assert_eq!(o.status.code(), Some(0), "{cmd}: {}", stderr(&o));
        let t = stdout(&o);
        assert!(
            t.contains("status: breakdown") && t.contains("beyond breakdown"),
            "{cmd}: {t}"
        );
        let o = run(dir.path(), &[cmd, &over, "--no-report", "--strict"]);
        assert_eq!(o.status.code(), Some(1), "{cmd} --strict: {}", stdout(&o));
        assert!(stdout(&o).contains("status: breakdown"));
        let v: Value = serde_json::from_str(&stdout(&run(
            dir.path(),
            &[cmd, &over, "--no-report", "--json"],
        )))
        .expect("JSON");
        assert_eq!(v["status"], "breakdown", "{cmd}");
        assert_eq!(v["breakdown"]["exceeded"], true, "{cmd}");
        assert!(v["breakdown"]["margin"].as_f64().unwrap() < 0.0, "{cmd}");
    }
    let below = breakdown_scene(dir.path(), "below.toml", Some("\"25 V/um\""), "10 kV");
    for (cmd, status) in [("static", "ok"), ("simulate", "completed")] {
        let o = run(dir.path(), &[cmd, &below, "--no-report", "--strict"]);
        assert_eq!(o.status.code(), Some(0), "{cmd}: {}", stdout(&o));
        assert!(
            stdout(&o).contains(&format!("status: {status}")),
            "{}",
            stdout(&o)
        );
    }
    let v: Value = serde_json::from_str(&ok(&run(
        dir.path(),
        &["simulate", &below, "--no-report", "--json"],
    )))
    .expect("JSON");
    let b = &v["breakdown"];
    assert_eq!(b["checked"], true);
    assert!(
        b["field_max_V_per_m"].as_f64().unwrap()
            >= b["field_max_at_samples_V_per_m"].as_f64().unwrap()
    );
    assert_eq!(v["integrator"]["status"], "completed");
}

// ---------------------------------------------------------------------------------
// Fit files, --json, --strict, reports
// ---------------------------------------------------------------------------------

const VHB: &str = "datasets/vhb4910/uniaxial.csv";

fn repo_file(rel: &str) -> String {
    repo().join(rel).display().to_string()
}

/// The fit file is written (atomically: no temporary file is left beside it), and
/// `--json` prints exactly the object it holds.
#[test]
fn json_is_the_fit_file() {
    let dir = tempdir();
    let o = hyperelastic(dir.path(), &[&repo_file(VHB), "--model", "yeoh", "--json"]);
    let printed = ok(&o);
    let file = std::fs::read_to_string(dir.path().join("fit.json")).expect("fit file");
    assert_eq!(
        printed.trim_end(),
        file.trim_end(),
        "--json and the fit file differ"
    );
    let v: Value = serde_json::from_str(&printed).expect("one JSON object on stdout");
    assert_eq!(v["model"], "yeoh");
    assert_eq!(v["schema"], "dea-fit/hyperelastic-fit/1");
    // Nothing but the fit, the report and the run list of the folder holding the
    // report (docs/reports.md): no leftover temporary file.
    assert_eq!(names_in(dir.path()), ["fit.json", "index.html", "report"]);
}

/// The report directory holds the figure of data vs model, the residuals and a page
/// linking them.
#[test]
fn report_has_figures_and_index() {
    let dir = tempdir();
    let o = hyperelastic(dir.path(), &[&repo_file(VHB), "--model", "yeoh"]);
    let text = ok(&o);
    let report = dir.path().join("report");
    assert_eq!(
        names_in(&report),
        [
            ".dea-fit-output",
            "fit.svg",
            "index.html",
            "index.md",
            "residuals.svg",
            "run.json"
        ]
    );
    for svg in ["fit.svg", "residuals.svg"] {
        let s = std::fs::read_to_string(report.join(svg)).expect("svg");
        assert!(s.trim_start().starts_with("<svg"), "{svg} is not SVG");
    }
    let index = std::fs::read_to_string(report.join("index.md")).expect("index.md");
    assert!(index.contains("fit.svg") && index.contains("residuals.svg"));
    assert!(text.contains(&format!("report: {}", report.join("index.html").display())));
    // --no-report writes none.
    let dir2 = tempdir();
    ok(&hyperelastic(
        dir2.path(),
        &[&repo_file(VHB), "--model", "yeoh", "--no-report"],
    ));
    assert_eq!(names_in(dir2.path()), ["fit.json"]);
}

/// The same fit twice keeps one file and says nothing; a different fit on the same
/// `--out` keeps the old one as `fit.previous-N.json` and says so on stderr.
#[test]
fn fits_are_never_silently_overwritten() {
    let dir = tempdir();
    let args = [
        repo_file(VHB),
        "--model".into(),
        "yeoh".into(),
        "--no-report".into(),
    ];
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let first = hyperelastic(dir.path(), &args);
    ok(&first);
    let again = hyperelastic(dir.path(), &args);
    ok(&again);
    // The same fit is refreshed in place (only its solver time differs).
    let original = std::fs::read_to_string(dir.path().join("fit.json")).expect("fit");
    assert_eq!(names_in(dir.path()), ["fit.json"]);
    assert!(!stderr(&again).contains("note:"), "{}", stderr(&again));

    let other = repo_file("datasets/vhb4910/planar.csv");
    let second = hyperelastic(dir.path(), &[&other, "--model", "yeoh", "--no-report"]);
    ok(&second);
    assert_eq!(names_in(dir.path()), ["fit.json", "fit.previous-1.json"]);
    let kept = std::fs::read_to_string(dir.path().join("fit.previous-1.json")).expect("kept");
    assert!(kept == original, "the earlier fit was not kept as it was");
    let note = stderr(&second);
    assert!(
        note.contains("held a different fit; it was kept as")
            && note.contains("fit.previous-1.json"),
        "{note}"
    );
    let now = read_json(&dir.path().join("fit.json"));
    assert!(now["provenance"]["files"][0]["path"]
        .as_str()
        .is_some_and(|p| p.ends_with("planar.csv")));

    // A third, different fit takes the next free name.
    let third = hyperelastic(
        dir.path(),
        &[&other, "--model", "neo-hookean", "--no-report"],
    );
    ok(&third);
    assert_eq!(
        names_in(dir.path()),
        ["fit.json", "fit.previous-1.json", "fit.previous-2.json"]
    );
}

/// `--strict` exits 1 on a blocking status (here ill-posed: 3 points for Yeoh's 3
/// constants leave no degree of freedom) and still writes the fit; without it, 0.
#[test]
fn strict_exits_1_on_an_ill_posed_fit() {
    let three = data("ok", "three_points.csv").display().to_string();
    let dir = tempdir();
    let o = hyperelastic(
        dir.path(),
        &[&three, "--model", "yeoh", "--strict", "--no-report"],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"));
    let fit = read_json(&dir.path().join("fit.json"));
    assert_eq!(fit["status"], "ill_posed");
    assert!(fit["warnings"]
        .as_array()
        .expect("warnings")
        .iter()
        .any(|w| w
            .as_str()
            .is_some_and(|w| w.contains("3 points for 3 parameters"))));
    let dir = tempdir();
    ok(&hyperelastic(
        dir.path(),
        &[&three, "--model", "yeoh", "--no-report"],
    ));
    // A fit that is fine passes --strict.
    let dir = tempdir();
    ok(&hyperelastic(
        dir.path(),
        &[
            &repo_file(VHB),
            "--model",
            "yeoh",
            "--strict",
            "--no-report",
        ],
    ));
}

/// Ogden-3 on Treloar's uniaxial data alone is the issue's nearly ill-posed case.
/// Whatever status the estimator reports, `--strict` must agree with it: exit 1
/// exactly when the status is blocking (ill_posed, unstable, not_converged).
#[test]
fn strict_agrees_with_the_reported_status() {
    let dir = tempdir();
    let o = hyperelastic(
        dir.path(),
        &[
            &repo_file("datasets/treloar/uniaxial.csv"),
            "--model",
            "ogden3",
            "--strict",
            "--json",
            "--no-report",
        ],
    );
    let fit: Value = serde_json::from_str(&stdout(&o)).expect("json");
    let status = fit["status"].as_str().expect("status");
    let blocking = matches!(status, "ill_posed" | "unstable" | "not_converged");
    assert_eq!(
        o.status.code(),
        Some(if blocking { 1 } else { 0 }),
        "status {status}"
    );
    // The fit must not pass silently: at least a warning, with the reason said.
    assert_ne!(status, "ok");
    let warnings: Vec<&str> = fit["warnings"]
        .as_array()
        .expect("warnings")
        .iter()
        .filter_map(Value::as_str)
        .collect();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("correlated") || w.contains("bound") || w.contains("negligible")),
        "{warnings:?}"
    );
}

// ---------------------------------------------------------------------------------
// The README
// ---------------------------------------------------------------------------------

/// The lines of the README's first fenced code block, comments stripped.
fn readme_first_block() -> Vec<String> {
    command_blocks("README.md")
        .into_iter()
        .next()
        .unwrap_or_default()
}

/// The fenced code blocks without a language tag whose first line is a command
/// (`dea-fit …` or `cargo …`) in the Markdown file `doc` (relative to the
/// repository), as commands: comments (` #` to the end of a line) stripped, lines
/// continued with `\` joined, blank lines dropped. Other blocks (printed output,
/// TOML) are skipped.
fn command_blocks(doc: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(repo().join(doc)).expect(doc);
    let mut blocks = Vec::new();
    let mut lines = text.lines();
    while let Some(fence) = lines.by_ref().find(|l| l.starts_with("```")) {
        let tagged = fence.trim() != "```";
        let mut block = Vec::new();
        let mut pending = String::new();
        for l in lines.by_ref().take_while(|l| !l.starts_with("```")) {
            let l = l.split(" #").next().unwrap_or("").trim();
            match l.strip_suffix('\\') {
                Some(head) => {
                    pending.push_str(head.trim());
                    pending.push(' ');
                }
                None => {
                    pending.push_str(l);
                    if !pending.trim().is_empty() {
                        block.push(pending.trim().to_string());
                    }
                    pending.clear();
                }
            }
        }
        assert!(
            pending.is_empty(),
            "{doc}: a block ends in a continued line"
        );
        let commands = block
            .first()
            .is_some_and(|l| l.starts_with("dea-fit ") || l.starts_with("cargo "));
        if !tagged && commands {
            blocks.push(block);
        }
    }
    blocks
}

/// Commands of the README that are not run here, and why.
const README_NOT_RUN: &[(&str, &str)] = &[
    (
        "cargo test --release",
        "the suite itself; readme_test_command_is_what_ci_runs checks CI runs it",
    ),
    (
        "cargo install --path .",
        "a second release build (minutes); the binary it installs is the one run here",
    ),
];

/// Run every command of `doc`'s command blocks as written (a POSIX shell in `dir`, the
/// built `dea-fit` first on the PATH; `cargo run --release --` read as `dea-fit`), in
/// order (later examples read the fits earlier ones write); each must exit 0, and a
/// `--json` example must print JSON. Returns how many ran.
fn run_doc_examples(doc: &str, dir: &Path) -> usize {
    let bin = Path::new(env!("CARGO_BIN_EXE_dea-fit"));
    let path = std::env::join_paths(
        std::iter::once(bin.parent().expect("bin dir").to_path_buf()).chain(std::env::split_paths(
            &std::env::var_os("PATH").unwrap_or_default(),
        )),
    )
    .expect("PATH");
    let mut ran = 0;
    for command in command_blocks(doc).into_iter().flatten() {
        if README_NOT_RUN.iter().any(|(c, _)| *c == command) {
            continue;
        }
        let line = match command.strip_prefix("cargo run --release -- ") {
            Some(args) => format!("dea-fit {args}"),
            None => command.clone(),
        };
        assert!(
            line.starts_with("dea-fit "),
            "a README command this test cannot run: '{command}' \
             (run it here or list it in README_NOT_RUN with the reason)"
        );
        let o = std::process::Command::new("sh")
            .args(["-c", &line])
            .env("PATH", &path)
            .current_dir(dir)
            .output()
            .expect("sh runs");
        assert_eq!(
            o.status.code(),
            Some(0),
            "{doc}: example '{command}' failed:\n{}",
            stderr(&o)
        );
        if line.contains("--json") && !line.contains('>') {
            serde_json::from_slice::<Value>(&o.stdout)
                .unwrap_or_else(|e| panic!("{doc}: example '{command}': not JSON on stdout: {e}"));
        } else if let Some(l) = stdout(&o).lines().find(|l| l.chars().count() > 100) {
            // Text for people fits a 100-column terminal (tables wrap their cells).
            panic!(
                "{doc}: example '{command}' prints a line of {} characters:\n{l}",
                l.chars().count()
            );
        }
        ran += 1;
    }
    ran
}

/// Every example command of the README runs as written on a copy of the shipped
/// datasets (see [`run_doc_examples`]). So the README cannot name a file that does
/// not ship or a flag that does not exist.
#[test]
fn readme_examples_run() {
    let dir = tempdir();
    copy_dir(&repo().join("datasets"), &dir.path().join("datasets"));
    let ran = run_doc_examples("README.md", dir.path());
    // Nothing was left out but the commands listed (with the reason) as not run, and
    // each of those is still in the README.
    let all: Vec<String> = command_blocks("README.md").into_iter().flatten().collect();
    for (c, _) in README_NOT_RUN {
        assert!(
            all.iter().any(|a| a == c),
            "README_NOT_RUN names '{c}', no longer in the README"
        );
    }
    assert_eq!(ran + README_NOT_RUN.len(), all.len());
    assert!(
        ran >= 25,
        "{ran} README examples ran: were the code blocks found?"
    );
    // What the examples say they write.
    for f in [
        "fits/vhb4910-uniaxial-yeoh.json",
        "fits/vhb4910-relaxation-qlv4.json",
        "exports/vhb4910-uniaxial-yeoh-abaqus.inp",
        "reports/index.html",
        "sweep.sh",
    ] {
        assert!(dir.path().join(f).exists(), "{f} not written");
    }
}

/// docs/worked-example.md: every command runs as written, in order, on a copy of the
/// shipped datasets, and the numbers the page quotes are what they print.
#[test]
fn worked_example_runs() {
    let dir = tempdir();
    copy_dir(&repo().join("datasets"), &dir.path().join("datasets"));
    let ran = run_doc_examples("docs/worked-example.md", dir.path());
    assert_eq!(ran, 5, "the page's five steps");
    let page = std::fs::read_to_string(repo().join("docs/worked-example.md")).expect("page");
    let run = |args: &[&str]| stdout(&crate::support::run_ok(dir.path(), args));
    // Each quoted line of output must be printed as quoted (the runs are deterministic).
    let outputs = [
        run(&[
            "hyperelastic",
            "datasets/vhb4910/uniaxial.csv",
            "--equibiaxial",
            "datasets/vhb4910/equibiaxial.csv",
            "--planar",
            "datasets/vhb4910/planar.csv",
            "--model",
            "yeoh",
            "--no-report",
        ]),
        run(&[
            "relaxation",
            "datasets/vhb4910/relaxation.csv",
            "--strain",
            "0.5",
            "--no-report",
        ]),
        run(&[
            "permittivity",
            "datasets/vhb4910/lcr_cpd.csv",
            "--diameter",
            "30.00mm±0.05mm",
            "--thickness",
            "1.000mm±0.010mm",
        ]),
        run(&["static", "datasets/vhb4910/stack_fitted.toml"]),
    ]
    .concat();
    for quoted in [
        "C10        69.14 ± 0.22 kPa    [68.70, 69.57] kPa",
        "μ0 138.27 kPa  RMSE 3.1121 kPa",
        "157.9 ± 6.0 ms  114.4 ± 5.1 kPa",
        "A = (7.069 ± 0.024)e-4 m², d = 1.000 ± 0.010 mm",
        "E∞ 43.204 kPa  E0 222.19 kPa",
        "1000.00  4.6875  0.0494",
        "pull-in at stretch 0.650071, 20997.4 V (rest stretch 1.015455)",
    ] {
        assert!(
            page.contains(quoted),
            "the page no longer quotes '{quoted}'"
        );
        assert!(
            outputs.contains(quoted),
            "the page quotes '{quoted}' but the commands print:\n{outputs}"
        );
    }
}

/// The README's second command is the test command, and CI runs exactly it.
#[test]
fn readme_test_command_is_what_ci_runs() {
    let block = readme_first_block();
    let test = block.get(1).expect("a second command: the tests");
    let ci = std::fs::read_to_string(repo().join(".ci/run")).expect(".ci/run");
    assert!(
        ci.lines().any(|l| l.trim() == test),
        ".ci/run does not run the README's test command '{test}'"
    );
}

// ---------------------------------------------------------------------------------
// No panic on any input
// ---------------------------------------------------------------------------------

/// Pieces a tensile file is made of, plus the usual ways it goes wrong.
const PIECES: &[&[u8]] = &[
    b"stretch",
    b"strain_pct",
    b"nominal_stress_kPa",
    b"true_stress_MPa",
    b"force_N",
    b"displacement_mm",
    b"weight",
    b"mode",
    b"time_s",
    b"nominal_stress [kPa]",
    b"uniaxial",
    b"planar",
    b"# mode: equibiaxial",
    b"# mode: bulge",
    b"#",
    b",",
    b";",
    b"\t",
    b"\n",
    b"\r\n",
    b"\r",
    b" ",
    b"\"",
    b"0",
    b"1",
    b"1.5",
    b"-2",
    b"1,5",
    b"1e400",
    b"NaN",
    b"-inf",
    b"\xef\xbb\xbf",
    b"\xff",
    b"\xc3",
    b"\xc2\xb2",
    b",,\n",
    b" ; \n",
];

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]
    /// Whatever the bytes, the reader returns data or an error naming the file, and
    /// what it returns is physical: stretch > 0, finite stress, weight > 0.
    #[test]
    fn reader_never_panics(
        header in proptest::bool::ANY,
        picks in proptest::collection::vec(0..PIECES.len(), 0..30),
    ) {
        // Half the cases start with a good header, so that the rows get read too.
        let mut bytes = if header { b"stretch,nominal_stress_kPa\n".to_vec() } else { Vec::new() };
        bytes.extend(picks.iter().flat_map(|&i| PIECES[i].iter().copied()));
        let path = Path::new("fuzz.csv");
        let opts = TensileOptions { area: Some(22e-6), gauge_length: Some(0.08), mode: None };
        let result = dea_fit::io::table::Table::parse(path, &bytes)
            .and_then(|t| tensile::from_table(&t, &opts));
        match result {
            Ok(d) => {
                proptest::prop_assert!(!d.samples.is_empty());
                for s in &d.samples {
                    proptest::prop_assert!(s.stretch > 0.0 && s.stretch.is_finite());
                    proptest::prop_assert!(s.stress.is_finite() && s.weight > 0.0);
                }
            }
            Err(e) => proptest::prop_assert!(e.to_string().starts_with("fuzz.csv"), "{e}"),
        }
    }
}
