//! Progress of long runs (issue 35, part 4): a heartbeat line on a stderr that is
//! not a terminal, none with `DEA_FIT_PROGRESS=off`, and an interrupted
//! `identify --checkpoint` says how to resume.

use std::path::Path;
use std::process::{Command, Output, Stdio};

fn dea_fit(cwd: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dea-fit"));
    c.args(args).current_dir(cwd);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("the dea-fit binary runs")
}

/// A simulation longer than the heartbeat period (5 ms here, set by
/// `DEA_FIT_PROGRESS_PERIOD`; the run takes ≈ 0.1 s in release at rtol 1e-9) writes
/// heartbeat lines on its piped stderr, what runs and how far; stdout stays the
/// JSON. With `DEA_FIT_PROGRESS=off` it writes none.
#[test]
fn a_heartbeat_shows_on_a_stderr_that_is_not_a_terminal() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let scene = super::support::repo().join("datasets/scenes/stack_step_5kV.toml");
    let scene = scene.display().to_string();
    let args = [
        "simulate",
        &scene,
        "--no-report",
        "--json",
        "--rtol",
        "1e-9",
    ];
    let o = dea_fit(
        dir.path(),
        &args,
        &[
            ("DEA_FIT_PROGRESS_PERIOD", "0.005"),
            ("DEA_FIT_PROGRESS", ""),
        ],
    );
    assert_eq!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    let beats: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("progress: simulate stack_step_5kV, "))
        .collect();
    assert!(!beats.is_empty(), "no heartbeat in:\n{err}");
    assert!(beats.iter().all(|l| l.ends_with("/2001 samples")), "{err}");
    serde_json::from_slice::<serde_json::Value>(&o.stdout).expect("stdout is the JSON");
    let off = dea_fit(
        dir.path(),
        &args,
        &[
            ("DEA_FIT_PROGRESS_PERIOD", "0.005"),
            ("DEA_FIT_PROGRESS", "off"),
        ],
    );
    assert_eq!(off.status.code(), Some(0));
    let err = String::from_utf8_lossy(&off.stderr);
    assert!(!err.contains("progress:"), "{err}");
}

/// `identify --checkpoint` on the worked example's step from a scene far from its
/// constants (C10 ×5.8, the arm's k ÷10.6: 60 iterations, ≈ 0.3 s in release on an
/// idle machine; the traces' preparation ≈ 0.04 s),
/// its search stopped by `--max-time` (0.15 s; ×20 in a debug build): stderr gives
/// the command line to go on with, `--resume` added; that line resumes.
#[test]
fn an_identification_stopped_by_max_time_says_how_to_resume() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let d = super::support::repo().join("datasets/identify");
    let scene = std::fs::read_to_string(d.join("stack.toml"))
        .expect("shipped scene")
        .replace("C10 = \"69.3 kPa\"", "C10 = \"400 kPa\"")
        .replace("k = \"106 kPa\"", "k = \"10 kPa\"");
    std::fs::write(dir.path().join("far.toml"), scene).expect("written");
    let trace = d.join("step.csv").display().to_string();
    let limit = match cfg!(debug_assertions) {
        true => "3",
        false => "0.15",
    };
    let args = [
        "identify",
        &trace,
        "--scene",
        "far.toml",
        "--starts",
        "1",
        "--free",
        "eps_r,C10,arm1.k,arm1.tau",
        "--no-report",
        "--checkpoint",
        "ck",
        "--max-time",
        limit,
    ];
    let o = dea_fit(dir.path(), &args, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("stopped at its --max-time limit"), "{err}");
    let line = err
        .lines()
        .skip_while(|l| !l.contains("to go on from there, run"))
        .nth(1)
        .expect("the command line")
        .trim();
    assert!(line.ends_with("--resume"), "{line}");
    assert!(
        line.contains("--checkpoint ck") && line.contains(&trace),
        "{line}"
    );
    // the line, as a shell reads it (plain words here), resumes the search
    let words: Vec<&str> = line.split(' ').skip(1).collect();
    assert_eq!(&words[..args.len()], &args[..]);
    let again = dea_fit(dir.path(), &words, &[]);
    assert_eq!(
        again.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
}

/// Ctrl-C (SIGINT) during a checkpointed identification: the run ends by the
/// signal and says how to resume, with the same command line. A run that finished
/// before the signal reached it (a loaded machine can starve this test's polling
/// thread past the whole search) tested nothing: it is repeated with four times
/// the starts.
#[cfg(unix)]
#[test]
fn an_interrupted_identification_says_how_to_resume() {
    use std::os::unix::process::ExitStatusExt;
    let d = super::support::repo().join("datasets/identify");
    let trace = d.join("step.csv").display().to_string();
    let scene = d.join("stack.toml").display().to_string();
    for starts in ["2", "8"] {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let child = super::support::interruptible()
            .args([
                "identify",
                &trace,
                "--scene",
                &scene,
                "--starts",
                starts,
                "--no-report",
                "--checkpoint",
                "ck",
            ])
            .current_dir(dir.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("dea-fit runs");
        // the search has begun once a checkpoint is written
        let t0 = std::time::Instant::now();
        while !dir.path().join("ck.0").exists() && !dir.path().join("ck.1").exists() {
            assert!(
                t0.elapsed().as_secs() < 120,
                "no checkpoint after 2 minutes"
            );
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let killed = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .expect("kill runs");
        assert!(killed.success());
        let o = child.wait_with_output().expect("dea-fit ends");
        let err = String::from_utf8_lossy(&o.stderr);
        if o.status.success() && starts == "2" {
            continue;
        }
        assert_eq!(o.status.signal(), Some(2), "{:?}: {err}", o.status);
        assert!(err.contains("the search is checkpointed in ck.0"), "{err}");
        assert!(err.contains("--checkpoint ck --resume"), "{err}");
        return;
    }
}
