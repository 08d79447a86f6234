//! What every command says and how it exits (README, "Exit status and statuses"):
//! each command on a good and a bad input, with the printed status checked against
//! the exit code; runs that go non-finite or run out of steps; the file policy
//! (nothing the tool did not write is ever replaced); a reader that goes away.

use crate::support::{names_in, repo, run};
use dea_fit::sim::integrate::{self, End, Extra, Method, Options, Stats, System};
use std::process::{Command, Output, Stdio};

fn file(name: &str) -> String {
    repo()
        .join("tests/data/bad_cli/files")
        .join(name)
        .display()
        .to_string()
}

fn shipped(rel: &str) -> String {
    repo().join(rel).display().to_string()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The status a run printed: the last `status: X` line, or the JSON `status`.
fn printed_status(o: &Output) -> Option<String> {
    let out = String::from_utf8_lossy(&o.stdout);
    if let Ok(v) = serde_json::from_str::<serde_json::Value>(&out) {
        return v["status"]
            .as_str()
            .or_else(|| v["integrator"]["status"].as_str())
            .map(str::to_string);
    }
    out.lines()
        .rev()
        .find_map(|l| l.rsplit_once("status: ").map(|(_, s)| s))
        .map(|s| s.split_whitespace().next().unwrap_or("").to_string())
}

/// Statuses that block (exit 1) under `--strict`.
const BLOCKING: [&str; 9] = [
    "approximate",
    "blocking",
    "breakdown",
    "ill_posed",
    "unstable",
    "not_converged",
    "not_validated",
    "pull_in",
    "failed",
];

/// The README's rule: 2 = refused (an `error:` line, status absent or `failed`);
/// 1 = `failed`, or a blocking status under `--strict`; 0 = anything else, never
/// `failed`, and never a blocking status under `--strict`.
fn check_agrees(args: &[&str], o: &Output) {
    let code = o.status.code().expect("an exit code, not a signal");
    let status = printed_status(o);
    let strict = args.contains(&"--strict");
    let t = text(o);
    assert!(!t.contains("panicked"), "{args:?} panicked:\n{t}");
    let s = status.as_deref();
    let ok = match code {
        2 => t.contains("error:") && matches!(s, None | Some("failed")),
        1 => s == Some("failed") || (strict && s.is_some_and(|s| BLOCKING.contains(&s))),
        0 => s.is_some_and(|s| s != "failed" && !(strict && BLOCKING.contains(&s))),
        _ => false,
    };
    assert!(ok, "{args:?}: exit {code} with status {s:?}:\n{t}");
}

/// Run every case in a fresh directory, check the exit code it must give and that
/// its printed status agrees with it.
fn cases(list: &[(&[&str], i32)]) {
    for (args, exit) in list {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let o = run(dir.path(), args);
        assert_eq!(
            o.status.code(),
            Some(*exit),
            "{args:?}: exit status\n{}",
            text(&o)
        );
        check_agrees(args, &o);
    }
}

#[test]
fn every_command_status_agrees_with_exit_code() {
    let uniaxial = shipped("datasets/vhb4910/uniaxial.csv");
    let relax = shipped("datasets/vhb4910/relaxation.csv");
    let composite = shipped("datasets/composites/sylgard_batio3.toml");
    let scene = shipped("datasets/scenes/stack_step_5kV_damped.toml");
    let good_lcr = file("status_lcr_good.csv");
    let neg_d = file("status_lcr_negative_d.csv");
    let one_fraction = file("status_composite_one_fraction.toml");
    let nan_scene = file("status_scene_nan.toml");
    let missing = file("status_does_not_exist.csv");
    let yeoh_fit = shipped("tests/data/export/vhb4910-yeoh.json");
    let h = &uniaxial[..];
    cases(&[
        // hyperelastic
        (
            &[
                "hyperelastic",
                h,
                "--model",
                "yeoh",
                "--no-report",
                "--strict",
            ],
            0,
        ),
        (&["hyperelastic", &missing, "--model", "yeoh"], 2),
        // relaxation
        (&["relaxation", &relax, "--strain", "0.5", "--no-report"], 0),
        // bench: its 6-term Prony cases on 200 points are ill-posed / not converged
        // (seeded data, so always): measured and listed, blocking under --strict.
        (&["bench", "relaxation"], 0),
        (&["bench", "relaxation", "--strict"], 1),
        (&["relaxation", &missing, "--strain", "0.5"], 2),
        // permittivity: a good file; a refused one beside it (status failed, exit 2)
        (
            &[
                "permittivity",
                &good_lcr,
                "--area",
                "1.439e-3",
                "--thickness",
                "2.2mm",
                "--strict",
            ],
            0,
        ),
        (
            &[
                "permittivity",
                &good_lcr,
                &neg_d,
                "--area",
                "1.439e-3",
                "--thickness",
                "2.2mm",
            ],
            2,
        ),
        // composite: the shipped series; one fraction (every rule ill-posed)
        (&["composite", &composite, "--strict"], 0),
        (&["composite", &one_fraction], 0),
        (&["composite", &one_fraction, "--strict"], 1),
        // simulate: a damped scene; one whose εr once made the state non-finite (refused now)
        (&["simulate", &scene, "--no-report", "--strict"], 0),
        (&["simulate", &nan_scene, "--no-report"], 2),
        // export: an exact card; an approximate one (blocking under --strict); a CSV
        (&["export", &yeoh_fit, "--to", "abaqus", "--strict"], 0),
        (&["export", &yeoh_fit, "--to", "febio"], 0),
        (&["export", &yeoh_fit, "--to", "febio", "--strict"], 1),
        (&["export", h, "--to", "abaqus"], 2),
        // static: the curve; too few points to look for a peak
        (&["static", &scene, "--strict"], 0),
        (&["static", &scene, "--points", "2"], 2),
        // synth
        (
            &[
                "synth",
                "hyperelastic",
                "--model",
                "neo-hookean",
                "--param",
                "mu=100kPa",
                "--mode",
                "uniaxial",
                "--stretch",
                "1:3:11",
                "--out",
                "s.csv",
            ],
            0,
        ),
        (
            &[
                "synth",
                "hyperelastic",
                "--model",
                "neo-hookean",
                "--param",
                "mu=oops",
                "--mode",
                "uniaxial",
                "--stretch",
                "1:3:11",
                "--out",
                "s.csv",
            ],
            2,
        ),
    ]);
}

/// `bench` refuses a data directory without the shipped datasets before it runs.
#[test]
fn bench_refuses_missing_datasets() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let args = ["bench", "hyperelastic", "--data-dir", "nowhere"];
    let o = run(dir.path(), &args);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    check_agrees(&args, &o);
}

/// y' = −y, with a right-hand side that turns NaN once y falls below ½ (at t = ln 2).
struct GoesNan;

impl System for GoesNan {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = if y[0] < 0.5 { f64::NAN } else { -y[0] };
    }
    fn jacobian_times(&self, _t: f64, _y: &[f64], v: &[f64], out: &mut [f64]) {
        out[0] = -v[0];
    }
    fn n_params(&self) -> usize {
        0
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut [f64]) {
        jac[0] = -1.0;
    }
    fn param_jacobian(&self, _t: f64, _y: &[f64], _dfdp: &mut [f64]) {}
    fn sensitivity_rate(&self, _t: f64, _y: &[f64], _s: &[f64], _k: usize, _out: &mut [f64]) {}
    fn initial_sensitivity(&self, _out: &mut [f64]) {}
}

fn options(max_steps: usize) -> Options {
    Options {
        rtol: 1e-6,
        atol: 1e-9,
        h_max: 0.1,
        h_init: 1e-3,
        max_steps,
        fixed_step: None,
    }
}

fn integrate(m: Method, o: &Options, y: &mut [f64]) -> End {
    let mut stats = Stats::default();
    integrate::run(
        &GoesNan,
        m,
        o,
        &[1.0],
        &[0.0, 2.0],
        y,
        &[0.5, 1.0, 1.5, 2.0],
        Extra::None,
        &mut |_, _, _| {},
        &mut |_, _| {},
        None,
        &mut |_, _| {},
        &mut stats,
    )
}

/// Every method (diffsol's and our DP54) stops where the state goes non-finite,
/// leaves a finite state, and never reports `Done`.
#[test]
fn every_integrator_stops_at_a_non_finite_state() {
    for m in Method::ALL {
        let mut y = [1.0];
        let end = integrate(m, &options(1_000_000), &mut y);
        let End::Failed(why) = &end else {
            panic!("{m}: {end:?} on a state that went NaN at t = ln 2");
        };
        assert!(why.contains("t = "), "{m}: {why}");
        assert!(y[0].is_finite(), "{m}: left a non-finite state {y:?}");
    }
}

/// A run that runs out of its step budget says so, with the time it had reached.
#[test]
fn step_budget_exhausted_is_a_failure_with_its_time() {
    for m in Method::ALL {
        let mut y = [1.0];
        let end = integrate(m, &options(3), &mut y);
        let End::Failed(why) = &end else {
            panic!("{m}: {end:?} with a budget of 3 steps");
        };
        assert!(why.contains("step budget exhausted at t = "), "{m}: {why}");
    }
}

/// `static --points 0|1|2` once claimed "no pull-in"; it is now refused, and with
/// enough points the shipped stack's pull-in is found.
#[test]
fn static_refuses_too_few_points() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let scene = shipped("datasets/scenes/stack_step_5kV.toml");
    for n in ["0", "1", "2", "9"] {
        let o = run(dir.path(), &["static", &scene, "--points", n]);
        assert_eq!(o.status.code(), Some(2), "--points {n}: {}", text(&o));
        assert!(!text(&o).contains("no pull-in"), "{}", text(&o));
    }
    let o = run(dir.path(), &["static", &scene, "--points", "10"]);
    assert!(text(&o).contains("pull-in at stretch"), "{}", text(&o));
}

/// `dea-fit static … | head` ends quietly: a reader that goes away is no error.
#[cfg(unix)]
#[test]
fn closed_pipe_ends_quietly() {
    let scene = shipped("datasets/scenes/stack_step_5kV.toml");
    let bin = env!("CARGO_BIN_EXE_dea-fit");
    for args in [
        vec!["static", &scene[..], "--json", "--points", "100000"],
        vec!["static", &scene[..], "--points", "100000"],
    ] {
        // `head -c 16` reads 16 bytes and exits; the JSON is megabytes long.
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "'{bin}' {} | head -c 16 >/dev/null",
                args.iter()
                    .map(|a| format!("'{a}'"))
                    .collect::<Vec<_>>()
                    .join(" ")
            ))
            .stderr(Stdio::piped())
            .output()
            .expect("sh runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.is_empty(),
            "{args:?}: stderr after the reader left:\n{err}"
        );
    }
    // The reader closes before the first write: killed by SIGPIPE, no message.
    let mut child = Command::new(bin)
        .args(["static", &scene, "--json", "--points", "100000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("dea-fit runs");
    drop(child.stdout.take());
    let o = child.wait_with_output().expect("dea-fit ends");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked") && err.is_empty(), "{err}");
}

/// `--out` onto a file that is not UTF-8 once replaced it; it is kept aside, byte for
/// byte, for fits, trajectories and synthetic data alike.
#[test]
fn out_never_replaces_a_foreign_file() {
    let foreign: &[u8] = b"\xff\xfe not a fit \x00\x01";
    let scene = shipped("datasets/scenes/stack_step_5kV_damped.toml");
    let uniaxial = shipped("datasets/vhb4910/uniaxial.csv");
    let runs: [(&str, Vec<&str>); 3] = [
        (
            "fit.json",
            vec![
                "hyperelastic",
                &uniaxial,
                "--model",
                "yeoh",
                "--no-report",
                "--out",
                "fit.json",
            ],
        ),
        (
            "run.csv",
            vec!["simulate", &scene, "--no-report", "--out", "run.csv"],
        ),
        (
            "data.csv",
            vec![
                "synth",
                "hyperelastic",
                "--model",
                "neo-hookean",
                "--param",
                "mu=100kPa",
                "--mode",
                "uniaxial",
                "--stretch",
                "1:3:11",
                "--out",
                "data.csv",
            ],
        ),
    ];
    for (name, args) in runs {
        let dir = tempfile::tempdir().expect("a temporary directory");
        std::fs::write(dir.path().join(name), foreign).expect("writes");
        let o = run(dir.path(), &args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", text(&o));
        let (stem, ext) = name.split_once('.').expect("a name with an extension");
        let kept = dir.path().join(format!("{stem}.previous-1.{ext}"));
        assert_eq!(
            std::fs::read(&kept).ok().as_deref(),
            Some(foreign),
            "{args:?}: the old file was not kept as {}; directory {:?}",
            kept.display(),
            names_in(dir.path())
        );
        assert!(text(&o).contains("kept as"), "{}", text(&o));
    }
}

/// `--out` onto a device or a pipe (`--out /dev/null` to discard) once renamed the
/// device aside and put a regular file in its place. A FIFO stands in for the device
/// here (a regression must not break the test machine's /dev/null): it stays a FIFO,
/// nothing is kept aside, and its reader receives the fit.
#[test]
fn out_onto_a_pipe_writes_into_it() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().expect("a temporary directory");
    let fifo = dir.path().join("fit.json");
    let made = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success(), "mkfifo failed");
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(&fifo).expect("reads the FIFO"))
    };
    let uniaxial = shipped("datasets/vhb4910/uniaxial.csv");
    let o = run(
        dir.path(),
        &[
            "hyperelastic",
            &uniaxial,
            "--model",
            "yeoh",
            "--no-report",
            "--out",
            "fit.json",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let got = reader.join().expect("the reader thread");
    assert!(
        String::from_utf8_lossy(&got).contains("\"model\": \"yeoh\""),
        "the FIFO's reader got {} bytes",
        got.len()
    );
    let kind = std::fs::symlink_metadata(&fifo)
        .expect("the FIFO is there")
        .file_type();
    assert!(kind.is_fifo(), "the FIFO was replaced: {kind:?}");
    assert_eq!(
        names_in(dir.path()),
        ["fit.json"],
        "something was kept aside"
    );
}

/// A report directory holding files dea-fit did not write is refused before anything
/// is written; one dea-fit wrote (it carries the marker) is refreshed.
#[test]
fn report_dir_of_someone_else_is_refused() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let theirs = dir.path().join("theirs");
    std::fs::create_dir(&theirs).expect("mkdir");
    std::fs::write(theirs.join("index.md"), "my notes").expect("writes");
    let uniaxial = shipped("datasets/vhb4910/uniaxial.csv");
    let scene = shipped("datasets/scenes/stack_step_5kV_damped.toml");
    let runs: [Vec<&str>; 2] = [
        vec![
            "hyperelastic",
            &uniaxial,
            "--model",
            "yeoh",
            "--report",
            "theirs",
            "--out",
            "f.json",
        ],
        vec!["simulate", &scene, "--report", "theirs", "--out", "t.csv"],
    ];
    for args in &runs {
        let o = run(dir.path(), args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
        assert!(text(&o).contains("did not write"), "{}", text(&o));
        assert_eq!(names_in(&theirs), ["index.md"]);
        assert_eq!(
            std::fs::read_to_string(theirs.join("index.md"))
                .ok()
                .as_deref(),
            Some("my notes")
        );
        assert_eq!(names_in(dir.path()), ["theirs"], "{args:?} wrote something");
    }
    // A directory dea-fit made is its own: a second run refreshes it.
    for _ in 0..2 {
        let o = run(
            dir.path(),
            &["simulate", &scene, "--report", "ours", "--out", "t.csv"],
        );
        assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    }
    assert!(names_in(&dir.path().join("ours")).contains(&".dea-fit-output".to_string()));
}

/// `composite --generate` keeps an export that differs from what it would write.
#[test]
fn generate_keeps_a_different_export() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let m = dir.path().join("series.toml");
    std::fs::copy(shipped("datasets/composites/sylgard_batio3.toml"), &m).expect("copies");
    let sub = dir.path().join("sylgard_batio3");
    std::fs::create_dir(&sub).expect("mkdir");
    std::fs::write(sub.join("s00_cpd.csv"), "measured, do not lose\n").expect("writes");
    let o = run(dir.path(), &["composite", "series.toml", "--generate"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(
        std::fs::read_to_string(sub.join("s00_cpd.previous-1.csv"))
            .ok()
            .as_deref(),
        Some("measured, do not lose\n")
    );
    // Generating again finds its own files: nothing more is kept aside.
    let o = run(dir.path(), &["composite", "series.toml", "--generate"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(!sub.join("s00_cpd.previous-2.csv").exists());
}

/// One spelling of every status, and no Rust Debug names, in every output.
#[test]
fn one_spelling_of_statuses_and_no_debug_names() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let one_fraction = file("status_composite_one_fraction.toml");
    let good_lcr = file("status_lcr_good.csv");
    let scene = shipped("datasets/scenes/stack_step_5kV_damped.toml");
    let outs = [
        run(dir.path(), &["composite", &one_fraction, "--report", "c"]),
        run(
            dir.path(),
            &[
                "permittivity",
                &good_lcr,
                "--area",
                "1.439e-3",
                "--thickness",
                "2.2mm",
                "--report",
                "p",
            ],
        ),
        run(dir.path(), &["simulate", &scene, "--report", "s"]),
    ];
    let mut all: String = outs.iter().map(text).collect();
    for d in ["c", "p", "s"] {
        all.push_str(
            &std::fs::read_to_string(dir.path().join(d).join("index.md")).unwrap_or_default(),
        );
    }
    assert!(all.contains("ill_posed"), "{all}");
    for bad in [
        "illposed",
        "IllPosed",
        "NotConverged",
        "E4990a",
        "E4980a",
        "Csv,",
        "Bdf",
        "Dynamic",
        "Weight",
        "Volume)",
    ] {
        assert!(!all.contains(bad), "{bad:?} in the output:\n{all}");
    }
    // No tolerance was given: the ± column says so instead of ± 0.0000.
    assert!(!all.contains("0.0000  "), "{all}");
    assert!(all.contains('—'), "{all}");
}

/// `stiff.toml` and `stiff.csv` in `dir`: the worked example's stack made stiffer
/// (C10 = 200 kPa, pull-in near 35 kV) and its trace of a 25 kV step (1 s, 200
/// samples, 0.5 µm contraction noise), which the worked example's constants (pull-in
/// at 20.8 kV) cannot run.
fn stiff_trace(dir: &std::path::Path) {
    let stack = repo().join("datasets/identify/stack.toml");
    let stiff = std::fs::read_to_string(&stack)
        .unwrap()
        .replace("C10 = \"69.3 kPa\"", "C10 = \"200 kPa\"")
        .replace("amplitude = \"5 kV\"", "amplitude = \"25 kV\"")
        .replace("span = \"3 s\"", "span = \"1 s\"")
        .replace("samples = 1500", "samples = 200");
    assert!(stiff.contains("200 kPa") && stiff.contains("25 kV") && stiff.contains("= 200"));
    std::fs::write(dir.join("stiff.toml"), stiff).unwrap();
    let synth = run(
        dir,
        &[
            "synth",
            "trace",
            "stiff.toml",
            "--noise",
            "contraction=0.5um",
            "--seed",
            "5",
            "--out",
            "stiff.csv",
        ],
    );
    assert_eq!(synth.status.code(), Some(0), "{}", text(&synth));
}

/// `identify` when no start can simulate the traces: a trace of a stiffer actuator
/// (C10 = 200 kPa, pull-in near 35 kV) driven by a 25 kV step, identified with only
/// the dashpot nv free on the worked example's stack (C10 = 69.3 kPa: pull-in at
/// 20.8 kV). Every start pulls in, whatever nv: the run is `failed` (exit 1), says
/// which starts failed and why, in text and in JSON (`fit_file` null), and writes no
/// fit file and no report. The same scene with a constant fixed where it has no rest
/// state cannot start at all: that input is refused (exit 2) before any search.
#[test]
fn identify_without_any_start_that_simulates_is_failed() {
    let stack = repo().join("datasets/identify/stack.toml");
    let dir = tempfile::tempdir().unwrap();
    stiff_trace(dir.path());
    let scene = stack.display().to_string();
    let args = |json: bool| {
        let mut a = vec![
            "identify",
            "stiff.csv",
            "--scene",
            &scene,
            "--free",
            "nv",
            "--starts",
            "3",
        ];
        if json {
            a.push("--json");
        }
        a
    };
    let o = run(dir.path(), &args(false));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    check_agrees(&args(false), &o);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("no start could simulate the traces"), "{out}");
    for i in 0..3 {
        assert!(
            out.lines()
                .any(|l| l.contains(&format!("start {i} (nv = ")) && l.contains("pull_in")),
            "start {i} and its pull-in are not named:\n{out}"
        );
    }
    let o = run(dir.path(), &args(true));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    check_agrees(&args(true), &o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["status"], "failed");
    assert!(v["fit_file"].is_null(), "{v}");
    let starts = v["starts"].as_array().unwrap();
    assert_eq!(starts.len(), 3);
    for s in starts {
        assert_eq!(s["constants"][0]["name"], "nv");
        assert!(
            s["reason"].as_str().unwrap().contains("pull-in at t ="),
            "{s}"
        );
    }
    assert_eq!(
        names_in(dir.path()),
        ["stiff.csv", "stiff.toml"],
        "a failed run writes nothing"
    );
    // a fixed constant without rest state: the input cannot start (exit 2)
    let helix = repo().join("datasets/identify");
    let o = run(
        dir.path(),
        &[
            "identify",
            &helix.join("helix_step.csv").display().to_string(),
            "--scene",
            &helix.join("helix.toml").display().to_string(),
            "--fix",
            "C10=1Pa",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("the scene at its starting constants cannot run this trace"),
        "{}",
        text(&o)
    );
}

/// A held-out trace the identified constants cannot run (the worked example's step
/// identified, the stiff 25 kV trace held out: the identified stack pulls in) is a
/// finding about the constants, not a refused input: status `not_validated` (exit 0
/// without `--strict`, 1 with it), the
/// warning names the trace and the pull-in, the JSON's validation says why, and the
/// fit file is written.
#[test]
fn identify_with_a_held_out_trace_it_cannot_predict_warns() {
    let d = repo().join("datasets/identify");
    let dir = tempfile::tempdir().unwrap();
    stiff_trace(dir.path());
    let p = |f: &str| d.join(f).display().to_string();
    let args = [
        "identify",
        &p("step.csv"),
        "--scene",
        &p("stack.toml"),
        "--free",
        "C10,eps_r",
        "--starts",
        "1",
        "--validate",
        "stiff.csv",
        "--no-report",
        "--out",
        "fit.json",
        "--json",
    ];
    let o = run(dir.path(), &args);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    check_agrees(&args, &o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["status"], "not_validated");
    let why = v["validation"][0]["failed"].as_str().unwrap_or("");
    assert!(why.starts_with("pull_in"), "{}", v["validation"]);
    assert!(
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap_or("").contains(
                "stiff.csv: the identified constants do not predict this held-out trace: pull_in"
            )),
        "{}",
        v["warnings"]
    );
    assert!(dir.path().join("fit.json").exists());
    // the same under --strict: the status blocks, and the exit status says so
    let strict: Vec<&str> = args.iter().copied().chain(["--strict"]).collect();
    let o = run(dir.path(), &strict);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    check_agrees(&strict, &o);
}
