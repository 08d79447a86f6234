//! The write policy under faults (issue 32, "Data lost"): writers racing on one
//! output, a write that fails after part of the new file, runs finishing at once
//! in one reports folder, an output inside the report folder, and interrupted
//! runs. Repetitions are modest here; `DEA_FIT_FAULT_REPS=N` multiplies them.

use crate::support::{names_in, repo, run};
use dea_fit::io::write::{write_keeping, Replaced};
use std::path::Path;
use std::process::{Command, Stdio};

/// The repetitions of a race: `base` times `DEA_FIT_FAULT_REPS` (default 1).
fn reps(base: usize) -> usize {
    base * std::env::var("DEA_FIT_FAULT_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1)
}

fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary directory")
}

/// What the write policy may leave beside `name` in `dir` after every writer ended:
/// nothing but the target and its kept files (no temporary or lock file).
fn litter(dir: &Path, name: &str) -> Vec<String> {
    names_in(dir)
        .into_iter()
        .filter(|n| n.starts_with(&format!(".{name}.")))
        .collect()
}

/// The contents of `out.csv` and its `out.previous-<n>.csv` in `dir`.
fn kept_contents(dir: &Path) -> Vec<Vec<u8>> {
    names_in(dir)
        .into_iter()
        .filter(|n| n == "out.csv" || (n.starts_with("out.previous-") && n.ends_with(".csv")))
        .map(|n| std::fs::read(dir.join(n)).expect("a kept file reads"))
        .collect()
}

/// Threads of one process racing on one target with different contents: every
/// content survives under the target or a `previous-<n>` name, exactly one writer
/// found no file, every other says truthfully where the file it replaced went, and
/// no temporary or lock file is left.
#[test]
fn racing_threads_keep_every_result() {
    const WRITERS: usize = 8;
    for _ in 0..reps(25) {
        let d = tempdir();
        let target = d.path().join("out.csv");
        let barrier = std::sync::Barrier::new(WRITERS);
        let replaced: Vec<Replaced> = std::thread::scope(|s| {
            let hs: Vec<_> = (0..WRITERS)
                .map(|w| {
                    let (target, barrier) = (&target, &barrier);
                    s.spawn(move || {
                        let bytes = format!("result of writer {w}\n").repeat(100 + w);
                        barrier.wait();
                        write_keeping(target, bytes.as_bytes(), |old| old == bytes.as_bytes())
                            .expect("every writer succeeds")
                    })
                })
                .collect();
            hs.into_iter()
                .map(|h| h.join().expect("no panic"))
                .collect()
        });
        let mut got = kept_contents(d.path());
        got.sort();
        let mut want: Vec<Vec<u8>> = (0..WRITERS)
            .map(|w| {
                format!("result of writer {w}\n")
                    .repeat(100 + w)
                    .into_bytes()
            })
            .collect();
        want.sort();
        assert_eq!(got, want, "every result is kept, once");
        assert_eq!(
            replaced.iter().filter(|r| **r == Replaced::New).count(),
            1,
            "{replaced:?}"
        );
        let mut kept: Vec<_> = replaced
            .iter()
            .filter_map(|r| match r {
                Replaced::KeptAs(p) => Some(p.clone()),
                _ => None,
            })
            .collect();
        kept.sort();
        kept.dedup();
        assert_eq!(kept.len(), WRITERS - 1, "each kept file named once");
        assert!(kept.iter().all(|p| p.is_file()));
        assert_eq!(litter(d.path(), "out.csv"), Vec::<String>::new());
    }
}

/// The arguments of a `synth hyperelastic` run writing `out.csv` whose content
/// depends on `w`.
fn synth_args(w: usize, out: &str) -> Vec<String> {
    [
        "synth",
        "hyperelastic",
        "--model",
        "neo-hookean",
        "--param",
        &format!("mu={}kPa", 100 + w),
        "--seed",
        &w.to_string(),
        "--out",
        out,
    ]
    .map(String::from)
    .to_vec()
}

/// Separate processes of the real binary racing on one `--out`: each exits 0,
/// every result survives (compared with the same run written alone), and the
/// notes name each kept file once.
#[test]
fn racing_processes_keep_every_result() {
    const WRITERS: usize = 4;
    let refs = tempdir();
    let want: Vec<Vec<u8>> = (0..WRITERS)
        .map(|w| {
            let name = format!("ref{w}.csv");
            crate::support::run_ok(
                refs.path(),
                &synth_args(w, &name)
                    .iter()
                    .map(String::as_str)
                    .collect::<Vec<_>>(),
            );
            std::fs::read(refs.path().join(name)).expect("the reference reads")
        })
        .collect();
    let mut want_sorted = want.clone();
    want_sorted.sort();
    for _ in 0..reps(10) {
        let d = tempdir();
        let children: Vec<_> = (0..WRITERS)
            .map(|w| {
                Command::new(env!("CARGO_BIN_EXE_dea-fit"))
                    .args(synth_args(w, "out.csv"))
                    .current_dir(d.path())
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .expect("the binary starts")
            })
            .collect();
        let mut notes = Vec::new();
        for c in children {
            let o = c.wait_with_output().expect("the run ends");
            let err = String::from_utf8_lossy(&o.stderr).into_owned();
            assert_eq!(o.status.code(), Some(0), "{err}");
            notes.extend(
                err.lines()
                    .filter_map(|l| l.split_once("it was kept as "))
                    .map(|(_, p)| p.to_string()),
            );
        }
        let mut got = kept_contents(d.path());
        got.sort();
        assert_eq!(got, want_sorted, "every run's result is kept");
        notes.sort();
        notes.dedup();
        assert_eq!(notes.len(), WRITERS - 1, "{notes:?}");
        assert!(notes.iter().all(|n| d.path().join(n).is_file()));
        assert_eq!(litter(d.path(), "out.csv"), Vec::<String>::new());
    }
}

/// A write that fails part-way (a file-size limit, as a full disk would): the old
/// file is still under its name, nothing is kept aside, no temporary file is left,
/// and the run exits 2 saying nothing was replaced. The limit is set in the child
/// (RLIMIT_FSIZE); SIGXFSZ is left at its default, which would kill the run: the
/// binary itself turns it into an error.
#[cfg(unix)]
#[test]
fn failed_write_leaves_the_old_file() {
    use std::os::unix::process::CommandExt;
    let d = tempdir();
    let old = b"the user's earlier result\n";
    std::fs::write(d.path().join("out.csv"), old).expect("setup");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_dea-fit"));
    cmd.args(synth_args(1, "out.csv"))
        .args(["--stretch", "1.0:3.0:5000"])
        .current_dir(d.path());
    // SAFETY: setrlimit is async-signal-safe; the limit is on the child alone.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: 4096,
                rlim_max: 4096,
            };
            match libc::setrlimit(libc::RLIMIT_FSIZE, &lim) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    let o = cmd.output().expect("the binary runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("nothing was replaced"), "{err}");
    assert_eq!(std::fs::read(d.path().join("out.csv")).unwrap(), old);
    assert_eq!(names_in(d.path()), vec!["out.csv".to_string()]);
}

/// Runs finishing at once, each with its own report folder in one reports folder:
/// the run list names every one of them.
#[test]
fn run_list_keeps_every_run() {
    const RUNS: usize = 3;
    let data = repo().join("datasets/treloar/uniaxial.csv");
    for _ in 0..reps(4) {
        let d = tempdir();
        let children: Vec<_> = (0..RUNS)
            .map(|r| {
                Command::new(env!("CARGO_BIN_EXE_dea-fit"))
                    .arg("hyperelastic")
                    .arg(&data)
                    .args(["--model", "neo-hookean", "--out"])
                    .arg(format!("f{r}.json"))
                    .arg("--report")
                    .arg(format!("reports/run{r}"))
                    .current_dir(d.path())
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .expect("the binary starts")
            })
            .collect();
        for c in children {
            let o = c.wait_with_output().expect("the run ends");
            assert_eq!(
                o.status.code(),
                Some(0),
                "{}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        let list = std::fs::read_to_string(d.path().join("reports/index.html")).unwrap();
        for r in 0..RUNS {
            assert!(
                list.contains(&format!("href=\"run{r}/index.html\"")),
                "run{r} missing from the run list"
            );
        }
        assert_eq!(
            litter(d.path().join("reports").as_path(), "index.html"),
            Vec::<String>::new()
        );
    }
}

/// An output file inside the command's own report folder (or the folder itself,
/// however spelled) is refused with exit 2 and a hint, before anything is written;
/// one beside the folder is not.
#[test]
fn output_inside_the_report_folder_is_refused() {
    let data = repo().join("datasets/treloar/uniaxial.csv");
    let data = data.to_str().unwrap();
    let relax = repo().join("datasets/vhb4910/relaxation.csv");
    let relax = relax.to_str().unwrap();
    let scene = repo().join("datasets/scenes/stack_step_3kV.toml");
    let scene = scene.to_str().unwrap();
    let lcr = repo().join("datasets/lcr_samples/E4990A-example1.csv");
    let lcr = lcr.to_str().unwrap();
    let manifest = repo().join("datasets/composites/sylgard_batio3.toml");
    let manifest = manifest.to_str().unwrap();
    let step = repo().join("datasets/identify/step.csv");
    let step = step.to_str().unwrap();
    let stack = repo().join("datasets/identify/stack.toml");
    let stack = stack.to_str().unwrap();
    // identify: each of its files (the fit, --trace, --checkpoint's FILE.k), refused
    // before the search runs
    let identify = |flag: &'static str, file: &'static str| {
        vec![
            "identify", step, "--scene", stack, "--free", "eps_r", flag, file, "--report", "rep",
        ]
    };
    let mut cases: Vec<Vec<&str>> = vec![
        identify("--out", "rep/fit.json"),
        identify("--trace", "rep/trace.jsonl"),
        identify("--checkpoint", "rep/ck"),
    ];
    cases.extend([
        vec![
            "hyperelastic",
            data,
            "--model",
            "neo-hookean",
            "--out",
            "rep/index.md",
            "--report",
            "rep",
        ],
        vec![
            "hyperelastic",
            data,
            "--model",
            "neo-hookean",
            "--out",
            "rep",
            "--report",
            "rep",
        ],
        vec![
            "hyperelastic",
            data,
            "--model",
            "neo-hookean",
            "--out",
            "./x/../rep/fit.json",
            "--report",
            "rep/",
        ],
        vec![
            "relaxation",
            relax,
            "--strain",
            "0.5",
            "--out",
            "rep/run.json",
            "--report",
            "rep",
        ],
        vec![
            "simulate",
            scene,
            "--out",
            "rep/trajectory.csv",
            "--report",
            "rep",
        ],
        vec![
            "static",
            scene,
            "--out",
            "reports/static-stack_step_3kV/curve.csv",
        ],
        vec![
            "permittivity",
            lcr,
            "--out",
            "rep/index.md",
            "--report",
            "rep",
        ],
        vec![
            "composite",
            manifest,
            "--out",
            "rep/index.md",
            "--report",
            "rep",
        ],
    ]);
    for args in cases {
        let d = tempdir();
        let o = run(d.path(), &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("overlaps the report folder") && err.contains("hint:"),
            "{args:?}: {err}"
        );
        assert_eq!(
            names_in(d.path()),
            Vec::<String>::new(),
            "{args:?}: nothing written"
        );
    }
    let d = tempdir();
    crate::support::run_ok(
        d.path(),
        &[
            "hyperelastic",
            data,
            "--model",
            "neo-hookean",
            "--out",
            "rep-fit.json",
            "--report",
            "rep",
        ],
    );
}

/// A scene whose streamed trajectory is large (`samples`; 10⁶ samples are ≈ 200 MB,
/// ≈ 2 s) so that a signal reaches the run mid-write.
fn long_scene(dir: &Path, samples: usize) -> std::path::PathBuf {
    let text = std::fs::read_to_string(repo().join("datasets/scenes/stack_step_3kV.toml"))
        .unwrap()
        .replace("samples = 2000", &format!("samples = {samples}"));
    let p = dir.join("long.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// SIGINT and SIGTERM in the middle of a streamed `simulate --out`: the run ends by
/// that signal (a shell reports 130, 143), its temporary file is gone, and neither
/// the output nor the folders it created (the output's, and the report folder,
/// empty but for its marker) are left. A run that finished before the signal
/// reached it, or before this test's polling thread saw it writing (a loaded
/// machine can starve that thread), tested nothing: it is repeated with a scene
/// four times as long.
#[cfg(unix)]
#[test]
fn interrupted_simulate_leaves_no_litter() {
    use std::os::unix::process::ExitStatusExt;
    for sig in [libc::SIGINT, libc::SIGTERM] {
        let mut samples = 1_000_000;
        loop {
            let d = tempdir();
            let scene = long_scene(d.path(), samples);
            let mut child = super::support::interruptible()
                .arg("simulate")
                .arg(&scene)
                .args(["--out", "new/out.csv", "--report", "rep"])
                .current_dir(d.path())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("the binary starts");
            let writing = || {
                let new = d.path().join("new");
                litter(&new, "out.csv")
                    .iter()
                    .any(|n| std::fs::metadata(new.join(n)).is_ok_and(|m| m.len() > 0))
            };
            let start = std::time::Instant::now();
            let mut ended = None;
            while !writing() {
                if let Some(status) = child.try_wait().unwrap() {
                    // it finished while this thread waited to look
                    ended = Some(status);
                    break;
                }
                assert!(start.elapsed().as_secs() < 60, "no temporary file appeared");
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
            let status = match ended {
                Some(status) => status,
                None => {
                    // SAFETY: a signal to the child this test started.
                    unsafe { libc::kill(child.id() as libc::pid_t, sig) };
                    child.wait().unwrap()
                }
            };
            if status.success() && samples < 16_000_000 {
                samples *= 4;
                continue;
            }
            assert_eq!(status.signal(), Some(sig), "{status:?}");
            assert_eq!(
                names_in(d.path()),
                vec!["long.toml".to_string()],
                "signal {sig}"
            );
            break;
        }
    }
}

/// A temporary file of a dead process of this host beside the target is removed by
/// the next run writing that target (both the current name and the one of earlier
/// versions, without the host); one of a live process, or of another host, is not.
#[cfg(unix)]
#[test]
fn stale_temporaries_of_dead_processes_are_removed() {
    let d = tempdir();
    let mut dead = Command::new(env!("CARGO_BIN_EXE_dea-fit"))
        .arg("--version")
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let dead_pid = dead.id();
    dead.wait().unwrap();
    let live_pid = std::process::id();
    let mut buf = [0u8; 256];
    // SAFETY: the buffer is valid for its length.
    unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
    let host: String = String::from_utf8_lossy(&buf[..buf.iter().position(|&b| b == 0).unwrap()])
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect();
    let stale = [
        format!(".out.csv.tmp-{dead_pid}-0-{host}"),
        format!(".out.csv.tmp-{dead_pid}"),
    ];
    let kept = [
        format!(".out.csv.tmp-{live_pid}-0-{host}"),
        format!(".out.csv.tmp-{live_pid}"),
        format!(".out.csv.tmp-{dead_pid}-0-another-host"),
    ];
    for n in stale.iter().chain(&kept) {
        std::fs::write(d.path().join(n), "partial").unwrap();
    }
    crate::support::run_ok(
        d.path(),
        &synth_args(1, "out.csv")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    let mut want: Vec<String> = kept.to_vec();
    want.sort();
    assert_eq!(litter(d.path(), "out.csv"), want);
    assert!(d.path().join("out.csv").is_file());
}
