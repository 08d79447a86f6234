//! `dea-fit make`, `status` and `init` on the shipped lab project (datasets/lab),
//! copied to a temporary folder first (its outputs never land in the repository).

use crate::support::{copy_dir, repo, run};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A fresh copy of datasets/lab without any outputs a developer's run left there.
fn lab() -> tempfile::TempDir {
    let d = tempfile::tempdir().expect("tempdir");
    copy_dir(&repo().join("datasets/lab"), d.path());
    for o in ["fits", "reports", ".dea-fit"] {
        let _ = std::fs::remove_dir_all(d.path().join(o));
    }
    d
}

/// `dea-fit <args> --json` in `dir`: the exit status and the steps' (target → state).
fn steps(dir: &Path, args: &[&str]) -> (i32, BTreeMap<String, String>, Value) {
    let mut a = args.to_vec();
    a.push("--json");
    let o = run(dir, &a);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "{args:?}: {e}\n{}\n{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    });
    let m = v["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .map(|s| {
            (
                s["target"].as_str().unwrap().to_string(),
                s["state"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    (o.status.code().expect("an exit status"), m, v)
}

/// The targets in a given state.
fn with(m: &BTreeMap<String, String>, state: &str) -> Vec<String> {
    m.iter()
        .filter(|(_, s)| *s == state)
        .map(|(t, _)| t.clone())
        .collect()
}

const ALL: usize = 12;

/// From scratch every step runs; again, none does; one changed raw file re-runs
/// exactly its fit and what reads it (the relaxation's QLV reads the tensile fit,
/// the identification's scene reads it too); one changed setting re-runs exactly
/// that step; `status` and `--dry-run` say why without running anything.
#[test]
fn make_reruns_exactly_what_changed() {
    let d = lab();
    let p = d.path();
    let (code, m, _) = steps(p, &["make", "--jobs", "2"]);
    assert_eq!(code, 0, "{m:?}");
    assert_eq!(with(&m, "ran").len(), ALL, "{m:?}");

    let (code, m, _) = steps(p, &["make"]);
    assert_eq!(code, 0);
    assert_eq!(
        with(&m, "up_to_date").len(),
        ALL,
        "an unchanged project runs nothing: {m:?}"
    );
    // a target named by its output file brings what it needs along
    let (_, m, _) = steps(p, &["make", "--dry-run", "fits/vhb4910-rel*"]);
    assert_eq!(
        m.keys().collect::<Vec<_>>(),
        ["vhb4910/relaxation", "vhb4910/tensile"]
    );

    // one raw file: its fit and the two steps that read that fit
    let f = p.join("raw/vhb4910/uniaxial.csv");
    let mut text = std::fs::read_to_string(&f).unwrap();
    text.push_str("# one more comment line\n");
    std::fs::write(&f, text).unwrap();
    let (_, m, v) = steps(p, &["status"]);
    assert_eq!(
        with(&m, "stale"),
        ["stack/identify", "vhb4910/relaxation", "vhb4910/tensile"]
    );
    let reason = |v: &Value, t: &str| {
        v["steps"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["target"] == t)
            .map(|s| s["reason"].as_str().unwrap().to_string())
            .unwrap()
    };
    assert_eq!(
        reason(&v, "vhb4910/tensile"),
        "input raw/vhb4910/uniaxial.csv changed"
    );
    assert_eq!(
        reason(&v, "vhb4910/relaxation"),
        "upstream vhb4910/tensile changed"
    );
    let (_, m, _) = steps(p, &["make", "--dry-run"]);
    assert_eq!(with(&m, "stale").len(), 3, "dry run: {m:?}");
    let (code, m, _) = steps(p, &["make"]);
    assert_eq!(code, 0);
    assert_eq!(
        with(&m, "ran"),
        ["stack/identify", "vhb4910/relaxation", "vhb4910/tensile"]
    );

    // one setting
    let proj = p.join("dea-fit.toml");
    let t = std::fs::read_to_string(&proj).unwrap();
    std::fs::write(&proj, t.replace("strain = 0.5", "strain = 0.50001")).unwrap();
    let (_, m, v) = steps(p, &["make"]);
    assert_eq!(with(&m, "ran"), ["vhb4910/relaxation"]);
    assert_eq!(
        reason(&v, "vhb4910/relaxation"),
        "settings changed: --strain=0.50001 (was --strain=0.5)"
    );

    // a new coupon matching a pattern is picked up
    std::fs::copy(
        p.join("raw/sylgard184/tensile_2.csv"),
        p.join("raw/sylgard184/tensile_3.csv"),
    )
    .unwrap();
    let (_, m, v) = steps(p, &["make", "sylgard184/*"]);
    assert_eq!(with(&m, "ran"), ["sylgard184/tensile"]);
    assert_eq!(m.len(), 2, "only the selected targets: {m:?}");
    assert!(reason(&v, "sylgard184/tensile").contains("new input raw/sylgard184/tensile_3.csv"));
}

/// A failing step blocks only what depends on it; the rest runs; the exit status
/// and the summary say so; the next `status` names the failure and the blocks.
#[test]
fn a_failing_step_blocks_only_its_dependents() {
    let d = lab();
    let p = d.path();
    std::fs::write(
        p.join("raw/vhb4910/uniaxial.csv"),
        "stretch,stress_kPa\n1,x\n",
    )
    .unwrap();
    let (code, m, _) = steps(p, &["make"]);
    assert_eq!(code, 1);
    assert_eq!(with(&m, "failed"), ["vhb4910/tensile"]);
    assert_eq!(
        with(&m, "blocked"),
        ["stack/identify", "vhb4910/relaxation"]
    );
    assert_eq!(with(&m, "ran").len(), ALL - 3);
    let o = run(p, &["make"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("keep-going"), "{out}");
    assert!(out.contains("1 failed, 2 blocked"), "{out}");
    let (code, m, _) = steps(p, &["status"]);
    assert_eq!(code, 0);
    assert_eq!(with(&m, "failed"), ["vhb4910/tensile"]);
    assert_eq!(
        with(&m, "blocked"),
        ["stack/identify", "vhb4910/relaxation"]
    );
    assert_eq!(with(&m, "up_to_date").len(), ALL - 3);
}

/// The fit files of a folder with every `seconds` (solver wall time) and
/// `sha256` field removed: the hyperelastic and relaxation fits record their
/// solver's seconds, and a fit records the SHA-256 of a fit file it read, which
/// differs with that file's seconds. Reports are not compared: their run.json and
/// reports/index.html hold when they were written.
fn fits(dir: &Path) -> BTreeMap<String, Value> {
    fn strip(v: &mut Value) {
        match v {
            Value::Object(m) => {
                m.remove("seconds");
                m.remove("sha256");
                m.values_mut().for_each(strip);
            }
            Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut out = BTreeMap::new();
    for e in std::fs::read_dir(dir.join("fits")).expect("fits/") {
        let e = e.unwrap();
        let mut v: Value = serde_json::from_slice(&std::fs::read(e.path()).unwrap()).unwrap();
        strip(&mut v);
        out.insert(e.file_name().to_string_lossy().into_owned(), v);
    }
    out
}

/// The names of every file under a folder (sorted, relative), but the copies the
/// one write policy keeps aside (`<stem>.previous-<n>.<ext>`: a step the killed run
/// had finished but not recorded runs again, and its fit differs in its seconds).
fn tree(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if !p.to_string_lossy().contains(".previous-") {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// Serial and parallel runs write the same fits (timings aside, see [`fits`]) and
/// the same report files.
#[test]
fn parallel_and_serial_runs_agree() {
    let (a, b) = (lab(), lab());
    assert_eq!(steps(a.path(), &["make", "--jobs", "1"]).0, 0);
    assert_eq!(steps(b.path(), &["make", "--jobs", "2"]).0, 0);
    assert_eq!(
        fits(a.path()).len(),
        ALL - 1,
        "every step but the ranking writes a fit"
    );
    assert_eq!(fits(a.path()), fits(b.path()));
    assert_eq!(
        tree(&a.path().join("reports")),
        tree(&b.path().join("reports"))
    );
}

/// A `make` killed (SIGKILL) in the middle, then `make` again, leaves the same
/// files as an uninterrupted run: no step is recorded done that did not end, the
/// steps it had started die with it, and the second run finishes the rest.
#[test]
fn a_killed_make_then_make_gives_the_same_files() {
    let (a, b) = (lab(), lab());
    assert_eq!(steps(a.path(), &["make", "--jobs", "1"]).0, 0);
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_dea-fit"))
        .args(["make", "--jobs", "1"])
        .current_dir(b.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // kill it once the third step has started (each step's log is made as it starts)
    let logs = b.path().join(".dea-fit/logs");
    let t0 = std::time::Instant::now();
    while std::fs::read_dir(&logs).map_or(0, |r| r.count()) < 3 {
        assert!(
            t0.elapsed().as_secs() < 60,
            "make never got to its third step"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let (code, m, _) = steps(b.path(), &["make", "--jobs", "1"]);
    assert_eq!(code, 0, "{m:?}");
    assert!(
        with(&m, "ran").len() < ALL,
        "the killed run did some steps: {m:?}"
    );
    assert_eq!(fits(a.path()), fits(b.path()));
    assert_eq!(tree(&a.path().join("fits")), tree(&b.path().join("fits")));
    assert_eq!(
        tree(&a.path().join("reports")),
        tree(&b.path().join("reports"))
    );
    let (_, m, _) = steps(b.path(), &["status"]);
    assert_eq!(with(&m, "up_to_date").len(), ALL);
}

/// `make` in a folder holding `project` as dea-fit.toml (and the files named): the
/// exit status and stderr.
fn bad(project: &str, files: &[&str]) -> (i32, String) {
    let d = tempfile::tempdir().unwrap();
    for f in files {
        let p = d.path().join(f);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, "stretch,stress_Pa\n1,0\n").unwrap();
    }
    std::fs::write(d.path().join("dea-fit.toml"), project).unwrap();
    let o = run(d.path(), &["make", "--dry-run"]);
    (
        o.status.code().unwrap(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Bad project files are refused with exit 2 and the place: a misspelt flag with
/// the near miss, a reference to no target, a pattern matching nothing, a TOML
/// error, a cycle named with its members.
#[test]
fn bad_project_files_get_located_errors() {
    let (c, e) = bad(
        "[materials.a.tensile]\nfiles = \"t.csv\"\nmodle = \"yeoh\"\n",
        &["t.csv"],
    );
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("dea-fit.toml:3:1: unknown setting of a hyperelastic step 'modle'"),
        "{e}"
    );
    assert!(e.contains("did you mean 'model'?"), "{e}");

    let (c, e) = bad(
        "[materials.a.relaxation]\nfile = \"t.csv\"\nhyperelastic = { target = \"a/tensil\" }\n[materials.a.tensile]\nfiles = \"t.csv\"\n",
        &["t.csv"],
    );
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("dea-fit.toml:3:27: materials.a.relaxation.hyperelastic: no target 'a/tensil'"),
        "{e}"
    );
    assert!(e.contains("did you mean 'a/tensile'?"), "{e}");

    let (c, e) = bad("[materials.a.tensile]\nfiles = \"raw/t_*.csv\"\n", &[]);
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("dea-fit.toml:2:9: materials.a.tensile.files: no file matches 'raw/t_*.csv'"),
        "{e}"
    );

    let (c, e) = bad("[materials.a.tensile]\nfiles = [\"t.csv\"\n", &["t.csv"]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("dea-fit.toml:2:"), "{e}");

    let (c, e) = bad("[materials.a.tensil]\nfiles = \"t.csv\"\n", &["t.csv"]);
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("dea-fit.toml:1:14: unknown step name 'tensil'"),
        "{e}"
    );
    assert!(e.contains("did you mean 'tensile'?"), "{e}");

    let cycle = "[materials.a.relaxation]\nfile = \"t.csv\"\nhyperelastic = { target = \"b/identify\" }\n\
                 [materials.b.identify]\ntraces = \"t.csv\"\nscene = \"s.toml\"\nreads = [{ target = \"c/tensile\" }]\n\
                 [materials.c.tensile]\nfiles = \"t.csv\"\nreads = [{ target = \"a/relaxation\" }]\n";
    let (c, e) = bad(cycle, &["t.csv"]);
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("the steps form a cycle: a/relaxation → b/identify → c/tensile → a/relaxation"),
        "{e}"
    );
    assert!(e.contains("dea-fit.toml:1:"), "{e}");

    let (c, e) = bad("", &[]);
    assert_eq!(c, 0, "an empty project is nothing to do: {e}");
    let d = tempfile::tempdir().unwrap();
    let o = run(d.path(), &["make"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("dea-fit init"));
}

/// `init` classifies the lab's raw files by the readers' own column detection into
/// one step per kind and folder, and never overwrites a project file.
#[test]
fn init_writes_a_project_from_the_files_and_never_overwrites() {
    let d = tempfile::tempdir().unwrap();
    copy_dir(&repo().join("datasets/lab/raw"), &d.path().join("raw"));
    // a file name with a quote and a backslash is written as a TOML string
    std::fs::copy(
        d.path().join("raw/sylgard184/tensile_1.csv"),
        d.path().join("raw/sylgard184/tensile \"3\\.csv"),
    )
    .unwrap();
    let o = run(d.path(), &["init"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let t = std::fs::read_to_string(d.path().join("dea-fit.toml")).unwrap();
    for s in [
        "[materials.raw-vhb4910.tensile]",
        "[materials.raw-vhb4910.relaxation]",
        "[materials.raw-vhb4910.permittivity]",
        "[materials.raw-vhb4910.breakdown]",
        "[materials.raw-vhb4910.dma]",
        "[materials.raw-sylgard184.tensile]",
        "# [actuators.raw-stack.identify]",
    ] {
        assert!(t.contains(s), "{s} missing:\n{t}");
    }
    // the project it wrote parses: what it can run without a geometry runs
    let (_, m, v) = steps(d.path(), &["make", "--dry-run"]);
    assert!(m.contains_key("raw-vhb4910/tensile"), "{m:?}");
    assert!(
        v.to_string().contains(r#"tensile \"3\\.csv"#),
        "the odd name is read: {v}"
    );
    let o = run(d.path(), &["init"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("never overwrites"));
    assert_eq!(
        std::fs::read_to_string(d.path().join("dea-fit.toml")).unwrap(),
        t
    );
}

/// `make` writes the project page, reports/index.html and index.md: every target
/// with its state (a target left out of a partial make shows as stale, with the
/// reason), the provenance of the ranking and the identification down to the raw
/// files with their SHA-256 (computed here from the files' bytes), and the run
/// list of the reports folder; `--no-report` leaves the page as it was.
#[test]
fn make_writes_the_project_page() {
    use sha2::Digest;
    let d = lab();
    let p = d.path();
    assert_eq!(steps(p, &["make", "--no-report"]).0, 0);
    assert!(
        !p.join("reports/index.html").exists() || {
            // the run list the steps' own reports keep there, not a project page
            let h = std::fs::read_to_string(p.join("reports/index.html")).unwrap();
            !h.contains("content=\"project\"")
        }
    );
    // one changed coupon, and a make of another target only: that fit is stale
    let f = p.join("raw/sylgard184/tensile_2.csv");
    let mut b = std::fs::read(&f).unwrap();
    b.extend_from_slice(b"\n");
    std::fs::write(&f, b).unwrap();
    assert_eq!(steps(p, &["make", "vhb4910/*"]).0, 0);
    let html = std::fs::read_to_string(p.join("reports/index.html")).unwrap();
    let md = std::fs::read_to_string(p.join("reports/index.md")).unwrap();
    assert!(html.contains("content=\"project\""), "a project page");
    let (_, m, v) = steps(p, &["status"]);
    assert_eq!(with(&m, "stale"), ["sylgard184/tensile"]);
    for s in v["steps"].as_array().unwrap() {
        let target = s["target"].as_str().unwrap();
        let state = match s["state"].as_str().unwrap() {
            "up_to_date" => "up to date",
            x => x,
        };
        // the target's row (the HTML lets a path break after its slashes)
        let name = format!(">{}</a></td>", target.replace('/', "/<wbr>"));
        let at = html.find(&name).unwrap_or_else(|| panic!("{name}"));
        let row = &html[at..];
        let row = &row[..row.find("</tr>").unwrap()];
        assert!(
            row.contains(&format!(">{state}</strong>")),
            "{target} is {state}: {row}"
        );
    }
    assert!(
        html.contains(&"input raw/sylgard184/tensile_2.csv changed".replace('/', "/<wbr>")),
        "the reason"
    );
    // provenance: every raw file the ranking and the identification rest on
    for raw in [
        "raw/vhb4910/breakdown.csv",
        "raw/sylgard_batio3_20wt/equibiaxial.csv",
        "design.toml",
        "raw/stack/step.csv",
        "raw/vhb4910/uniaxial.csv",
    ] {
        let sha = format!(
            "{:x}",
            sha2::Sha256::digest(std::fs::read(p.join(raw)).unwrap())
        );
        assert!(html.contains(&sha), "{raw} {sha}");
        assert!(md.contains(&sha[..20]), "{raw} in index.md");
    }
    // the run list of the folder, embedded: every step's report
    assert!(html.contains("fillers-rank/index.html"));
    // --no-report leaves the page alone
    let before = std::fs::read(p.join("reports/index.html")).unwrap();
    assert_eq!(steps(p, &["make", "--no-report"]).0, 0);
    assert_eq!(std::fs::read(p.join("reports/index.html")).unwrap(), before);
}

/// One job of `submit.sh`: its variable, script, targets and the variables of the
/// jobs it waits for.
struct Job {
    var: String,
    script: String,
    targets: Vec<String>,
    after: Vec<String>,
}

/// The jobs of `.dea-fit/slurm/submit.sh`, in submission order.
fn jobs(submit: &str) -> Vec<Job> {
    submit
        .lines()
        .filter(|l| l.contains("sbatch --parsable"))
        .map(|l| {
            let words: Vec<&str> = l.split_whitespace().collect();
            let script = words
                .iter()
                .find(|w| w.ends_with(".sbatch);"))
                .unwrap()
                .trim_end_matches(");")
                .to_string();
            let after = words
                .iter()
                .find_map(|w| w.strip_prefix("--dependency=afterany:"))
                .map_or(Vec::new(), |d| {
                    d.split(':')
                        .map(|x| x.trim_start_matches('$').to_string())
                        .collect()
                });
            // echo "<targets…> $jK"
            let echo = &l[l.find("echo \"").unwrap() + 6..l.rfind(" $").unwrap()];
            Job {
                var: l[..l.find('=').unwrap()].to_string(),
                script,
                targets: echo.split(' ').map(str::to_string).collect(),
                after,
            }
        })
        .collect()
}

/// `make --slurm` writes the steps that would run as batch jobs, each running
/// `dea-fit make --only --jobs 1 --no-report <targets…>` in the project folder:
/// the quick steps (fits of coupon files) up to `--batch` (8) to a job, identify
/// and rank a job each, a page job after all of them, and submit.sh with each
/// job's `afterany` dependencies on the jobs of the steps it reads (no job waits
/// for itself, none for a later one). `--batch 1` is one job a step. The scripts
/// run here as a Slurm node would (the jobs that wait for nothing all at once, so
/// their records race for the state file) leave the same fits as a local make, a
/// project page, and `status` saying everything is up to date.
#[test]
fn make_slurm_writes_jobs_with_dependencies() {
    let (d, local) = (lab(), lab());
    let p = d.path();
    assert_eq!(steps(local.path(), &["make", "--jobs", "2"]).0, 0);
    let s = p.join(".dea-fit/slurm");
    // one job a step
    let (code, m, _) = steps(p, &["make", "--slurm", "--batch", "1"]);
    assert_eq!(code, 0);
    assert_eq!(with(&m, "stale").len(), ALL, "every step would run");
    let one = jobs(&std::fs::read_to_string(s.join("submit.sh")).unwrap());
    assert_eq!(one.len(), ALL + 1);
    assert!(one[..ALL].iter().all(|j| j.targets.len() == 1));
    // batched (the default)
    let (code, _, _) = steps(p, &["make", "--slurm"]);
    assert_eq!(code, 0);
    let submit = std::fs::read_to_string(s.join("submit.sh")).unwrap();
    let all = jobs(&submit);
    let (page, steps_jobs) = all.split_last().unwrap();
    let job_of = |t: &str| {
        steps_jobs
            .iter()
            .position(|j| j.targets.iter().any(|x| x == t))
            .unwrap_or_else(|| panic!("{t} has no job: {submit}"))
    };
    let n: usize = steps_jobs.iter().map(|j| j.targets.len()).sum();
    assert_eq!(n, ALL, "every step in one job: {submit}");
    // 10 quick steps in two batches of at most 8, identify and rank alone
    assert_eq!(steps_jobs.len(), 4, "{submit}");
    assert!(steps_jobs.iter().all(|j| j.targets.len() <= 8));
    for t in ["stack/identify", "fillers/rank"] {
        let j = &steps_jobs[job_of(t)];
        assert_eq!(j.targets, [t]);
        assert_eq!(j.script, format!("{}.sbatch", t.replace('/', "-")));
    }
    assert!(steps_jobs
        .iter()
        .filter(|j| j.targets.len() > 1)
        .all(|j| j.script.starts_with("batch-")));
    // each step after what it reads: in its own job before it, or in a job waited for
    for (user, need) in [
        ("stack/identify", "vhb4910/tensile"),
        ("vhb4910/relaxation", "vhb4910/tensile"),
        ("fillers/rank", "vhb4910/breakdown"),
        ("fillers/rank", "sylgard_batio3/composite"),
        ("fillers/rank", "sylgard_batio3_20wt/tensile"),
        ("fillers/rank", "sylgard_batio3_40wt/tensile"),
    ] {
        let (u, n) = (job_of(user), job_of(need));
        if u == n {
            let t = &steps_jobs[u].targets;
            let at = |x: &str| t.iter().position(|y| y == x).unwrap();
            assert!(at(need) < at(user), "{user} after {need} in {t:?}");
        } else {
            assert!(n < u, "{need}'s job is submitted first");
            assert!(
                steps_jobs[u].after.contains(&steps_jobs[n].var),
                "{user} waits for {need}: {submit}"
            );
        }
    }
    for (k, j) in steps_jobs.iter().enumerate() {
        for a in &j.after {
            let w = steps_jobs.iter().position(|x| &x.var == a).unwrap();
            assert!(w < k, "{} waits for a later job", j.script);
        }
    }
    assert_eq!(
        page.after.len(),
        steps_jobs.len(),
        "the page waits for every job"
    );
    let job = std::fs::read_to_string(s.join("stack-identify.sbatch")).unwrap();
    assert!(
        job.contains("'make' '--only' '--jobs' '1' '--no-report' 'stack/identify'"),
        "{job}"
    );
    assert!(job.contains("#SBATCH --chdir="), "{job}");

    // run them as the node would: every job whose jobs have ended, at once
    let mut done: Vec<String> = Vec::new();
    while done.len() < all.len() {
        let ready: Vec<&Job> = all
            .iter()
            .filter(|j| !done.contains(&j.var) && j.after.iter().all(|x| done.contains(x)))
            .collect();
        assert!(!ready.is_empty(), "a job can start");
        let kids: Vec<_> = ready
            .iter()
            .map(|j| {
                std::process::Command::new("sh")
                    .arg(s.join(&j.script))
                    .current_dir(p)
                    .stdout(std::process::Stdio::null())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for (j, mut k) in ready.iter().zip(kids) {
            assert!(k.wait().unwrap().success(), "{}", j.script);
            done.push(j.var.clone());
        }
    }
    assert_eq!(fits(p), fits(local.path()), "the same fits as a local make");
    let (code, m, _) = steps(p, &["status"]);
    assert_eq!(code, 0);
    assert_eq!(with(&m, "up_to_date").len(), ALL, "{m:?}");
    let html = std::fs::read_to_string(p.join("reports/index.html")).unwrap();
    assert!(
        html.contains("content=\"project\""),
        "the page job wrote it"
    );
    // an up-to-date project has no step job, only the page
    let (code, _, _) = steps(p, &["make", "--slurm"]);
    assert_eq!(code, 0);
    let submit = std::fs::read_to_string(s.join("submit.sh")).unwrap();
    assert_eq!(submit.matches("sbatch --parsable").count(), 1, "{submit}");
}

/// An up-to-date `make` writes nothing: the page of the same identity is left as
/// it is (and says so), the state is not rewritten; a deleted page or a report a
/// single command wrote into reports/ brings the page back up to date. With
/// `--no-report`, the steps' run list is rebuilt once, at the end, listing every
/// step's report (the steps themselves leave it to make).
#[test]
fn an_up_to_date_make_writes_nothing() {
    let d = lab();
    let p = d.path();
    assert_eq!(steps(p, &["make", "--no-report"]).0, 0);
    let list = std::fs::read_to_string(p.join("reports/index.html")).unwrap();
    assert!(list.contains("content=\"run-list\""), "a run list");
    let (_, _, v) = steps(p, &["status"]);
    for s in v["steps"].as_array().unwrap() {
        let t = s["target"].as_str().unwrap().replace('/', "-");
        assert!(list.contains(&format!("{t}/index.html")), "{t} listed");
    }
    assert!(!p.join(".dea-fit/journal.jsonl").exists(), "folded in");
    let o = run(p, &["make"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("project page: "));
    let stamp = |f: &str| std::fs::metadata(p.join(f)).unwrap().modified().unwrap();
    let files = [
        "reports/index.html",
        "reports/index.md",
        ".dea-fit/state.json",
    ];
    let before: Vec<_> = files.iter().map(|f| stamp(f)).collect();
    let o = run(p, &["make"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("index.html (unchanged)"), "{out}");
    assert_eq!(files.iter().map(|f| stamp(f)).collect::<Vec<_>>(), before);
    // a page removed comes back
    std::fs::remove_file(p.join("reports/index.html")).unwrap();
    let o = run(p, &["make"]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("(unchanged)"));
    assert!(p.join("reports/index.html").exists());
    // a single command's report in reports/ joins the page's run list
    let o = run(
        p,
        &[
            "breakdown",
            "raw/vhb4910/breakdown.csv",
            "--report",
            "reports/by-hand",
        ],
    );
    assert!(o.status.success());
    let o = run(p, &["make"]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("(unchanged)"));
    let html = std::fs::read_to_string(p.join("reports/index.html")).unwrap();
    assert!(html.contains("by-hand/index.html"), "listed");
}

/// `{ target = "…" }` inside the lab's scene and design manifest (no `reads` in
/// the project file): each step is ordered after the steps it names, a changed
/// fit re-runs exactly the steps whose files name it, the scene runs standalone
/// (`dea-fit simulate`, from another folder too), and a misspelt target is a
/// located error with the near miss (exit 2), in `make` and standalone alike.
#[test]
fn targets_inside_scenes_and_manifests() {
    let d = lab();
    let p = d.path();
    assert!(!std::fs::read_to_string(p.join("dea-fit.toml"))
        .unwrap()
        .contains("reads"));
    let (_, _, v) = steps(p, &["make", "--dry-run"]);
    let order: Vec<&str> = v["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["target"].as_str().unwrap())
        .collect();
    let at = |t: &str| order.iter().position(|x| *x == t).unwrap();
    assert!(at("stack/identify") > at("vhb4910/tensile"), "{order:?}");
    for t in [
        "vhb4910/breakdown",
        "sylgard_batio3/composite",
        "sylgard_batio3_20wt/tensile",
        "sylgard_batio3_40wt/tensile",
    ] {
        assert!(at("fillers/rank") > at(t), "{t}: {order:?}");
    }
    assert_eq!(steps(p, &["make"]).0, 0);
    // a changed coupon of the 20 wt% series: its fit, then the ranking that names it
    let f = p.join("raw/sylgard_batio3_20wt/equibiaxial.csv");
    let mut b = std::fs::read(&f).unwrap();
    b.extend_from_slice(b"\n");
    std::fs::write(&f, b).unwrap();
    let (_, m, _) = steps(p, &["make"]);
    assert_eq!(
        with(&m, "ran"),
        ["fillers/rank", "sylgard_batio3_20wt/tensile"]
    );
    // standalone, from the project folder and from its parent
    let traj = p.join("t.csv");
    let traj = traj.to_str().unwrap();
    for (cwd, scene) in [
        (p.to_path_buf(), "scenes/stack.toml".to_string()),
        (
            p.parent().unwrap().to_path_buf(),
            format!(
                "{}/scenes/stack.toml",
                p.file_name().unwrap().to_str().unwrap()
            ),
        ),
    ] {
        let o = run(&cwd, &["simulate", &scene, "--no-report", "--out", traj]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    // a misspelt target
    let s = p.join("scenes/stack.toml");
    let text = std::fs::read_to_string(&s).unwrap();
    let line = text
        .lines()
        .position(|l| l.contains("vhb4910/tensile\" }"))
        .unwrap()
        + 1;
    std::fs::write(
        &s,
        text.replace("vhb4910/tensile\" }", "vhb4910/tensil\" }"),
    )
    .unwrap();
    for args in [
        vec!["make", "--dry-run"],
        vec![
            "simulate",
            "scenes/stack.toml",
            "--no-report",
            "--out",
            traj,
        ],
    ] {
        let o = run(p, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(&format!("stack.toml:{line}:")), "{err}");
        assert!(err.contains("did you mean 'vhb4910/tensile'"), "{err}");
    }
    // outside any project
    let out = tempfile::tempdir().unwrap();
    std::fs::write(out.path().join("stack.toml"), &text).unwrap();
    let o = run(
        out.path(),
        &["simulate", "stack.toml", "--no-report", "--out", traj],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no project file"));
}

/// `make`, `make --dry-run` and `status` with `--json` list every step (of the
/// selection) with exactly its target, kind (the command), state (`up_to_date`,
/// `stale`, `ran`, `failed`, `blocked`), reason (empty only when up to date),
/// outputs and command line, and counts of every state; across the runs below
/// every state occurs.
#[test]
fn json_lists_every_step_with_its_fields() {
    let d = lab();
    let p = d.path();
    let mut seen = std::collections::BTreeSet::new();
    let mut check = |args: &[&str], want: usize| {
        let (_, m, v) = steps(p, args);
        assert_eq!(m.len(), want, "{args:?}: {m:?}");
        let list = v["steps"].as_array().unwrap();
        for s in list {
            let o = s.as_object().unwrap();
            let keys: Vec<&str> = o.keys().map(|k| k.as_str()).collect();
            assert_eq!(
                keys,
                ["command", "kind", "outputs", "reason", "state", "target"],
                "{args:?}"
            );
            let state = s["state"].as_str().unwrap();
            assert!(
                ["up_to_date", "stale", "ran", "failed", "blocked"].contains(&state),
                "{state}"
            );
            seen.insert(state.to_string());
            assert_eq!(
                s["reason"].as_str().unwrap().is_empty(),
                state == "up_to_date",
                "{args:?}: {s}"
            );
            let kind = s["kind"].as_str().unwrap();
            assert!(
                s["command"]
                    .as_str()
                    .unwrap()
                    .starts_with(&format!("dea-fit {kind} ")),
                "{s}"
            );
            assert!(!s["outputs"].as_array().unwrap().is_empty(), "{s}");
        }
        let counts = v["counts"].as_object().unwrap();
        assert_eq!(counts.len(), 5);
        let total: u64 = counts.values().map(|c| c.as_u64().unwrap()).sum();
        assert_eq!(total as usize, list.len());
    };
    check(&["make", "--dry-run"], ALL);
    check(&["status"], ALL);
    check(&["make"], ALL);
    check(&["make", "--dry-run", "vhb4910/relaxation"], 2);
    std::fs::write(
        p.join("raw/vhb4910/uniaxial.csv"),
        "stretch,stress_kPa\n1,x\n",
    )
    .unwrap();
    check(&["make"], ALL);
    check(&["status"], ALL);
    assert_eq!(
        seen.into_iter().collect::<Vec<_>>(),
        ["blocked", "failed", "ran", "stale", "up_to_date"]
    );
}

/// `dea-fit bench make`, short (a 5-step generated project, one timed run each):
/// both projects from scratch and up to date, as CSV, JSON, chart and page.
#[test]
fn bench_make_times_both_projects() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("bench");
    let lab = repo().join("datasets/lab");
    let o = run(
        d.path(),
        &[
            "bench",
            "make",
            "--steps",
            "5",
            "--budget",
            "0",
            "--min-repeats",
            "1",
            "--lab",
            lab.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("make.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    for (row, want) in rows.iter().zip([
        "generated,5,from_scratch",
        "generated,5,up_to_date",
        "lab,12,from_scratch",
        "lab,12,up_to_date",
    ]) {
        assert!(row.starts_with(want), "{row}");
        let t: f64 = row.split(',').nth(3).unwrap().parse().unwrap();
        assert!(t > 0.0 && t.is_finite(), "{row}");
    }
    for f in ["make.json", "make.svg", "make.md"] {
        assert!(out.join(f).is_file(), "{f}");
    }
}
