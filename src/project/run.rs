//! What is stale and why ([`plan`]), and the job queue that runs the stale steps
//! ([`make`]): each step is the command a user would type, run as a child process
//! of this very program in the project folder, its output captured into
//! `.dea-fit/logs/<target>.log`. A step starts when every step it needs has ended
//! well; a failed step blocks what depends on it and the rest goes on (keep-going).
//! A step is recorded done only after its process ended with status 0 and its
//! outputs exist; its record is appended to the state's journal as it ends
//! ([`State::record`]), so a killed run leaves no step recorded that did not end.

use crate::error::{Error, Result};
use crate::project::file::{Project, Step};
use crate::project::graph;
use crate::project::identity::{identity, Hashes, MISSING};
use crate::project::state::{Record, Stat, State};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where a step stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Standing {
    /// Its identity and outputs are those of its last, successful run.
    UpToDate,
    /// It would run (the reason says why).
    Stale,
    /// It ran and ended well (this run).
    Ran,
    /// It ran and failed (this run, or its last run with the same identity).
    Failed,
    /// A step it needs failed or is blocked.
    Blocked,
}

impl Standing {
    /// The word of the text summary.
    pub fn word(self) -> &'static str {
        match self {
            Standing::UpToDate => "up to date",
            Standing::Stale => "stale",
            Standing::Ran => "ran",
            Standing::Failed => "failed",
            Standing::Blocked => "blocked",
        }
    }
}

/// One step of a report (`make`, `make --dry-run`, `status`).
#[derive(Debug, Clone, Serialize)]
pub struct StepReport {
    /// `<name>/<step>`.
    pub target: String,
    /// The command it runs.
    pub kind: String,
    /// Where it stands.
    pub state: Standing,
    /// Why (empty when up to date).
    pub reason: String,
    /// What it writes.
    pub outputs: Vec<String>,
    /// The command line, as a user would type it in the project folder.
    pub command: String,
}

/// A step's plan: its identity with the parts that made it, and why it would run
/// (None: up to date).
struct Planned {
    identity: String,
    inputs: BTreeMap<String, String>,
    upstream: BTreeMap<String, String>,
    why: Option<String>,
    /// Its last run with this same identity failed.
    failed: bool,
}

/// The log file of a target.
pub fn log_path(target: &str) -> String {
    format!("{}/logs/{}.log", super::STATE_DIR, target.replace('/', "-"))
}

/// The plan of every step (in `order`): identities through the stat cache, and
/// what changed since each step's last run.
fn plan(p: &Project, state: &mut State, order: &[usize]) -> Vec<Planned> {
    let State { files, steps, .. } = state;
    let mut h = Hashes::new(&p.dir, files);
    let mut out: Vec<Option<Planned>> = (0..p.steps.len()).map(|_| None).collect();
    for &i in order {
        let s = &p.steps[i];
        let inputs: BTreeMap<String, String> =
            s.inputs.iter().map(|f| (f.clone(), h.of(f))).collect();
        let upstream: BTreeMap<String, String> = s
            .needs
            .iter()
            .map(|&j| {
                let id = &out[j].as_ref().expect("needs planned first").identity;
                (p.steps[j].target.clone(), id.clone())
            })
            .collect();
        let id = identity(s, &inputs, &upstream);
        let rec = steps.get(&s.target);
        let (why, failed) = match rec {
            None => (Some("never ran".to_string()), false),
            Some(r) if r.identity != id => (Some(changes(s, r, &inputs, &upstream)), false),
            Some(r) if r.exit != 0 => (
                Some(format!(
                    "failed last time (exit {}{}; log {})",
                    r.exit,
                    if r.error.is_empty() {
                        String::new()
                    } else {
                        format!(": {}", r.error)
                    },
                    log_path(&s.target)
                )),
                true,
            ),
            Some(r) => (outputs_changed(&p.dir, r), false),
        };
        out[i] = Some(Planned {
            identity: id,
            inputs,
            upstream,
            why,
            failed,
        });
    }
    out.into_iter()
        .map(|x| x.expect("every step planned"))
        .collect()
}

/// What differs between a step's last run and now, most telling first.
fn changes(
    s: &Step,
    r: &Record,
    inputs: &BTreeMap<String, String>,
    upstream: &BTreeMap<String, String>,
) -> String {
    let mut why = Vec::new();
    for (f, x) in inputs {
        match r.inputs.get(f) {
            None => why.push(format!("new input {f}")),
            Some(y) if y != x && x == MISSING => why.push(format!("input {f} is missing")),
            Some(y) if y != x => why.push(format!("input {f} changed")),
            _ => {}
        }
    }
    for f in r.inputs.keys().filter(|f| !inputs.contains_key(*f)) {
        why.push(format!("input {f} no longer read"));
    }
    for (t, x) in upstream {
        if r.upstream.get(t) != Some(x) {
            why.push(format!("upstream {t} changed"));
        }
    }
    if r.args != s.args {
        // the settings that differ (inputs are named above)
        let now: Vec<&String> = s.args.iter().filter(|a| !r.args.contains(a)).collect();
        let was: Vec<&String> = r.args.iter().filter(|a| !s.args.contains(a)).collect();
        let flag = |v: &[&String]| {
            v.iter()
                .filter(|a| a.starts_with("--"))
                .map(|a| a.as_str())
                .collect::<Vec<_>>()
                .join(" ")
        };
        let (n, w) = (flag(&now), flag(&was));
        if !n.is_empty() || !w.is_empty() {
            why.push(match (n.is_empty(), w.is_empty()) {
                (false, false) => format!("settings changed: {n} (was {w})"),
                (false, true) => format!("settings changed: {n} added"),
                _ => format!("settings changed: {w} removed"),
            });
        } else if why.is_empty() {
            why.push("its files changed".into());
        }
    }
    if r.tool != env!("CARGO_PKG_VERSION") {
        why.push(format!(
            "dea-fit version changed ({} → {})",
            r.tool,
            env!("CARGO_PKG_VERSION")
        ));
    }
    if why.is_empty() {
        why.push("its identity changed".into());
    }
    why.join("; ")
}

/// Why a step whose identity is unchanged must run again: an output missing, or
/// changed since it was written.
fn outputs_changed(dir: &Path, r: &Record) -> Option<String> {
    for (o, st) in &r.outputs {
        let p = dir.join(o);
        match st {
            None if !p.is_dir() => return Some(format!("output {o} is missing")),
            Some(_) if !p.is_file() => return Some(format!("output {o} is missing")),
            Some(s) if Stat::of(&p) != Some(*s) => {
                return Some(format!("output {o} changed since it was written"))
            }
            _ => {}
        }
    }
    None
}

/// The command line a user would type for a step.
fn command(s: &Step) -> String {
    let quote = |a: &String| {
        if a.chars()
            .any(|c| c.is_whitespace() || "'\"$`\\*?;&|<>()".contains(c))
        {
            format!("'{}'", a.replace('\'', r"'\''"))
        } else {
            a.clone()
        }
    };
    let mut c = String::from("dea-fit");
    for a in &s.args {
        c.push(' ');
        c.push_str(&quote(a));
    }
    c
}

fn report(s: &Step, state: Standing, reason: String) -> StepReport {
    StepReport {
        target: s.target.clone(),
        kind: s.kind.clone(),
        state,
        reason,
        outputs: s.outputs.clone(),
        command: command(s),
    }
}

/// Why a step is blocked: the need that failed or is blocked (or, under
/// `--only`, is not up to date), as it stands.
fn blocked(need: &Step, as_: Standing) -> String {
    format!("upstream {} {}", need.target, as_.word())
}

/// Where every step stands, without running anything: up to date, stale (with
/// what changed), failed (its last run with the same identity), or blocked (a
/// step it needs failed or is blocked). In dependency order, with the state it
/// was read from.
pub fn status(p: &Project) -> Result<(Vec<StepReport>, State)> {
    let order = graph::order(p)?;
    let mut state = State::load(&p.dir);
    let plans = plan(p, &mut state, &order);
    let mut st: Vec<Option<Standing>> = vec![None; p.steps.len()];
    let mut out = Vec::new();
    for &i in &order {
        let s = &p.steps[i];
        let pl = &plans[i];
        let bad = s
            .needs
            .iter()
            .find(|&&j| matches!(st[j], Some(Standing::Failed | Standing::Blocked)));
        let (x, why) = if let Some(&j) = bad {
            (Standing::Blocked, blocked(&p.steps[j], st[j].expect("set")))
        } else if pl.failed {
            (Standing::Failed, pl.why.clone().unwrap_or_default())
        } else {
            match &pl.why {
                Some(w) => (Standing::Stale, w.clone()),
                None => (Standing::UpToDate, String::new()),
            }
        };
        st[i] = Some(x);
        out.push(report(s, x, why));
    }
    Ok((out, state))
}

/// How `make` runs.
#[derive(Debug, Clone)]
pub struct Options {
    /// Steps at once (at least 1).
    pub jobs: usize,
    /// List what would run and why, run nothing.
    pub dry_run: bool,
    /// Target patterns ([`graph::select`]); none: every step.
    pub targets: Vec<String>,
    /// Run the selected steps only, not the steps they need: a need that is not
    /// up to date blocks them (one Slurm job a step, [`super::slurm`]).
    pub only: bool,
}

/// The end of a step's process.
struct Ended {
    step: usize,
    /// Exit status; None: it could not start or was ended by a signal (the text).
    exit: std::result::Result<i32, String>,
}

/// Bring the selected steps up to date: run every stale (or last failed) step
/// whose needs ended well, in dependency order, `jobs` at once; a step whose
/// need failed is blocked, and the rest goes on. Returns the selected steps in
/// dependency order, with the state they stand on (for the project page). `exe`
/// is the program each step runs (this one).
///
/// The queue is linear in steps and dependencies: each step waits on a count of
/// its needs still to end, and each end settles the steps that read it (the
/// ready ones start in the project file's order, so the start order does not
/// depend on timing).
pub fn make(p: &Project, opts: &Options, exe: &Path) -> Result<(Vec<StepReport>, State)> {
    let n = p.steps.len();
    let order = graph::order(p)?;
    let chosen = if opts.only {
        graph::matched(p, &opts.targets)?
    } else {
        graph::select(p, &opts.targets)?
    };
    let mut state = State::load(&p.dir);
    let cached = state.files.clone();
    let plans = plan(p, &mut state, &order);
    let order: Vec<usize> = order.into_iter().filter(|&i| chosen[i]).collect();
    let mut out: Vec<Option<StepReport>> = vec![None; n];
    // None: to run; Some(true): ended well or up to date; Some(false): failed or blocked
    let mut ok: Vec<Option<bool>> = vec![None; n];
    for &i in &order {
        if plans[i].why.is_none() {
            ok[i] = Some(true);
            out[i] = Some(report(&p.steps[i], Standing::UpToDate, String::new()));
        } else if opts.dry_run {
            out[i] = Some(report(
                &p.steps[i],
                Standing::Stale,
                plans[i].why.clone().expect("stale"),
            ));
        }
    }
    if opts.dry_run {
        return Ok((order.iter().filter_map(|&i| out[i].take()).collect(), state));
    }
    // with --only, the needs left out count as they stand
    let mut word: Vec<Standing> = vec![Standing::Stale; n];
    for j in (0..n).filter(|&j| !chosen[j]) {
        ok[j] = Some(plans[j].why.is_none());
    }
    // forget files and steps the project no longer has; keep the stat cache
    let read: std::collections::HashSet<&str> = p
        .steps
        .iter()
        .flat_map(|s| s.inputs.iter().map(|f| f.as_str()))
        .collect();
    state.files.retain(|f, _| read.contains(f.as_str()));
    let targets: std::collections::HashSet<&str> =
        p.steps.iter().map(|s| s.target.as_str()).collect();
    let gone = state.steps.keys().any(|t| !targets.contains(t.as_str()));
    if !opts.only && (state.files != cached || gone) {
        let files = state.files.clone();
        state = State::update(&p.dir, |s| {
            s.files = files;
            s.steps.retain(|t, _| targets.contains(t.as_str()));
        })?;
    }
    // the steps to run: each waits for its needs still to end
    let mut waiting = vec![0usize; n];
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut bad: Vec<Option<usize>> = vec![None; n];
    let mut rank = vec![0usize; n];
    for (k, &i) in order.iter().enumerate() {
        rank[i] = k;
    }
    let mut ready = std::collections::BTreeSet::new();
    let mut settled: Vec<usize> = Vec::new();
    for &i in order.iter().filter(|&&i| ok[i].is_none()) {
        for &j in &p.steps[i].needs {
            match ok[j] {
                None => {
                    waiting[i] += 1;
                    users[j].push(i);
                }
                Some(false) => bad[i] = Some(bad[i].map_or(j, |b: usize| b.min(j))),
                Some(true) => {}
            }
        }
        if waiting[i] == 0 {
            if bad[i].is_some() {
                settled.push(i);
            } else {
                ready.insert(rank[i]);
            }
        }
    }
    let logs = p.dir.join(super::STATE_DIR).join("logs");
    if !ready.is_empty() {
        std::fs::create_dir_all(&logs).map_err(|e| Error::io(&logs, e))?;
    }
    let (tx, rx) = std::sync::mpsc::channel::<Ended>();
    let mut running = 0usize;
    loop {
        // block what cannot run (and what reads it), then start what can
        while let Some(i) = settled.pop() {
            if ok[i].is_none() {
                let j = bad[i].expect("a settled step to block has a bad need");
                ok[i] = Some(false);
                word[i] = Standing::Blocked;
                out[i] = Some(report(
                    &p.steps[i],
                    Standing::Blocked,
                    blocked(&p.steps[j], word[j]),
                ));
            }
            let good = ok[i] == Some(true);
            for &u in &users[i] {
                if !good {
                    bad[u] = Some(bad[u].map_or(i, |b| b.min(i)));
                }
                waiting[u] -= 1;
                if waiting[u] == 0 {
                    if bad[u].is_some() {
                        settled.push(u);
                    } else {
                        ready.insert(rank[u]);
                    }
                }
            }
        }
        while running < opts.jobs.max(1) {
            let Some(k) = ready.pop_first() else { break };
            let i = order[k];
            running += 1;
            spawn(&p.dir, exe, i, &p.steps[i], tx.clone());
        }
        if running == 0 {
            break;
        }
        let e = rx.recv().expect("a running step reports its end");
        running -= 1;
        let step = e.step;
        let (x, why) = finish(p, &mut state, &plans[step], e)?;
        ok[step] = Some(x == Standing::Ran);
        word[step] = x;
        out[step] = Some(report(&p.steps[step], x, why));
        settled.push(step);
    }
    State::compact(&p.dir)?;
    // the run lists the steps left to make (DEFER_ENV): each folder's once
    let lists: std::collections::BTreeSet<PathBuf> = order
        .iter()
        .filter(|&&i| matches!(word[i], Standing::Ran | Standing::Failed))
        .flat_map(|&i| &p.steps[i].outputs)
        .map(|o| p.dir.join(o))
        .filter(|o| o.is_dir())
        .filter_map(|o| o.parent().map(Path::to_path_buf))
        .collect();
    for l in lists {
        crate::report::runs::refresh_index(&l)?;
    }
    Ok((order.iter().filter_map(|&i| out[i].take()).collect(), state))
}

/// Record a step's end in the state file (done only with status 0 and its
/// outputs there); returns its standing with the reason.
fn finish(p: &Project, state: &mut State, pl: &Planned, e: Ended) -> Result<(Standing, String)> {
    let s = &p.steps[e.step];
    let log = log_path(&s.target);
    let mut outputs = BTreeMap::new();
    let mut missing = None;
    for o in &s.outputs {
        let path = p.dir.join(o);
        if let Some(st) = Stat::of(&path) {
            outputs.insert(o.clone(), Some(st));
        } else if path.is_dir() {
            outputs.insert(o.clone(), None);
        } else if missing.is_none() {
            missing = Some(o.clone());
        }
    }
    let (exit, error) = match (&e.exit, &missing) {
        (Ok(0), None) => (0, String::new()),
        (Ok(0), Some(o)) => (-1, format!("it ended with status 0 but did not write {o}")),
        (Ok(c), _) => (*c, last_line(&p.dir.join(&log))),
        (Err(m), _) => (-1, m.clone()),
    };
    state.record(
        &p.dir,
        &s.target,
        Record {
            identity: pl.identity.clone(),
            exit,
            error: error.clone(),
            tool: env!("CARGO_PKG_VERSION").into(),
            args: s.args.clone(),
            inputs: pl.inputs.clone(),
            upstream: pl.upstream.clone(),
            outputs,
        },
    )?;
    let why = pl.why.clone().unwrap_or_default();
    if exit == 0 {
        return Ok((Standing::Ran, why));
    }
    let code = if exit >= 0 {
        format!("exit {exit}")
    } else {
        "no result".into()
    };
    let error = if error.is_empty() {
        error
    } else {
        format!(": {error}")
    };
    Ok((Standing::Failed, format!("{code}{error}; log {log}")))
}

/// The error a failed command printed: the last line of its log starting with
/// `error:`, else its last non-empty line; at most 200 characters.
fn last_line(log: &Path) -> String {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    let l = text
        .lines()
        .rev()
        .find(|l| l.starts_with("error:"))
        .or_else(|| text.lines().rev().find(|l| !l.trim().is_empty()))
        .unwrap_or("");
    l.chars().take(200).collect()
}

/// Run a step's command in a thread: the child's stdout and stderr go to its log;
/// its end goes to `tx`.
fn spawn(dir: &Path, exe: &Path, i: usize, s: &Step, tx: std::sync::mpsc::Sender<Ended>) {
    let dir: PathBuf = dir.to_path_buf();
    let exe = exe.to_path_buf();
    let args = s.args.clone();
    let log = dir.join(log_path(&s.target));
    let line = command(s);
    std::thread::spawn(move || {
        let exit = run_child(&dir, &exe, &args, &log, &line);
        // the receiver lives until every started step has reported
        let _ = tx.send(Ended { step: i, exit });
    });
}

fn run_child(
    dir: &Path,
    exe: &Path,
    args: &[String],
    log: &Path,
    line: &str,
) -> std::result::Result<i32, String> {
    use std::io::Write;
    let mut f = std::fs::File::create(log).map_err(|e| format!("{}: {e}", log.display()))?;
    let _ = writeln!(f, "$ {line}");
    let err = f.try_clone().map_err(|e| e.to_string())?;
    let mut cmd = std::process::Command::new(exe);
    cmd.args(args)
        .env(crate::report::runs::DEFER_ENV, "1")
        .current_dir(dir)
        .stdin(std::process::Stdio::null())
        .stdout(f)
        .stderr(err);
    die_with_parent(&mut cmd);
    let status = cmd
        .status()
        .map_err(|e| format!("{} could not start: {e}", exe.display()))?;
    match status.code() {
        Some(c) => Ok(c),
        None => Err(signal_text(&status)),
    }
}

#[cfg(unix)]
fn signal_text(s: &std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    format!("ended by signal {}", s.signal().unwrap_or(0))
}

#[cfg(not(unix))]
fn signal_text(_: &std::process::ExitStatus) -> String {
    "ended without a status".into()
}

/// A step's process ends (by SIGTERM, which removes its temporary files) when
/// the `make` that started it dies, killed or not: no orphan goes on writing
/// outputs that no state records (Linux `PR_SET_PDEATHSIG`; the thread that
/// started it waits for it, so the signal comes only with the process's end).
#[cfg(target_os = "linux")]
fn die_with_parent(cmd: &mut std::process::Command) {
    use std::os::unix::process::CommandExt;
    let parent = std::process::id() as libc::pid_t;
    // SAFETY: prctl and getppid are async-signal-safe; nothing is allocated.
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            // the parent died before the request: end now
            if libc::getppid() != parent {
                libc::_exit(143);
            }
            Ok(())
        });
    }
}

#[cfg(not(target_os = "linux"))]
fn die_with_parent(_: &mut std::process::Command) {}
