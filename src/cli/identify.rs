//! `dea-fit identify`: material constants from measured actuator traces, with the
//! simulator in the loop (`dea_fit::identify`).

use dea_fit::fit::lm::{Checkpoint, Control};
use dea_fit::fit::Status;
use dea_fit::identify::failure::Failure;
use dea_fit::identify::material::{material_file, validate, Validation};
use dea_fit::identify::noise::Sigma;
use dea_fit::identify::problem::{ChannelKind, Experiment};
use dea_fit::identify::selection::{select, Candidate, Choose, HYPERELASTIC_MODELS, MAX_ARMS};
use dea_fit::identify::{identify_with, Identification, Run, Settings};
use dea_fit::io::trace;
use dea_fit::io::write::AtomicFile;
use dea_fit::observe::{Meter, Searches, Trace as TraceFile};
use dea_fit::sim::scene::Scene;
use dea_fit::units::{parse_quantity, CountRange};
use dea_fit::{Error, Result};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// `--starts`: each start is a whole simulator-in-the-loop search (seconds to
/// minutes), and one checkpoint file is kept per start.
const STARTS: CountRange = CountRange::new(1, 1000, "searches from different starting constants");

/// `--max-iterations`: an LM search converges in tens of iterations; more than
/// 10⁵ is a slip, not a budget (`--max-time` bounds the wall time).
const ITERATIONS: CountRange = CountRange::new(1, 100_000, "iterations of one start's search");

/// Identify material constants from actuator traces (one experiment per file,
/// fitted jointly).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Trace CSV files (time, voltage and measured channels; docs/traces.md).
    #[arg(required = true)]
    traces: Vec<PathBuf>,
    /// Scene of the actuator: geometry, load, source and the starting material; the
    /// traces replace its input and time.
    #[arg(long)]
    scene: PathBuf,
    /// Constants to fit, comma-separated (default: every material constant).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    free: Option<Vec<String>>,
    /// Constants held, comma-separated, each NAME or NAME=VALUE.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    fix: Vec<String>,
    /// Noise of a channel: NAME=VALUE with a unit (contraction=0.5um) or a percentage
    /// of the channel's RMS (capacitance=0.2%); channels not given are estimated from
    /// their residuals.
    #[arg(long, value_name = "NAME=VALUE")]
    sigma: Vec<String>,
    /// Number of starts (the scene's values are the first).
    #[arg(long, default_value_t = 8, value_parser = |s: &str| STARTS.parse(s))]
    starts: usize,
    /// Seed of the start design.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Iteration limit per start.
    #[arg(long, default_value_t = 100, value_parser = |s: &str| ITERATIONS.parse(s))]
    max_iterations: usize,
    /// Relative tolerance of the simulator (default: the scene's).
    #[arg(long)]
    rtol: Option<f64>,
    /// `auto`: fit 0 to 4 Maxwell arms (in place of the scene's) and keep the fewest
    /// within ΔAICc ≤ 2 of the best identifiable candidate; the comparison is printed.
    #[arg(long, value_name = "auto")]
    arms: Option<String>,
    /// `auto`: fit the invariant models (neo-hookean, mooney-rivlin, gent, yeoh) in
    /// place of the scene's and keep the fewest constants within ΔAICc ≤ 2 of the best
    /// identifiable candidate; with --arms auto every model with every number of arms.
    #[arg(long, value_name = "auto")]
    hyperelastic: Option<String>,
    /// Profile likelihoods of these free constants, comma-separated (plotted in the
    /// report, the profile 95 % interval printed).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    profiles: Vec<String>,
    /// Held-out traces to predict with the identified constants.
    #[arg(long, value_name = "FILE")]
    validate: Vec<PathBuf>,
    /// JSON-lines iteration trace of every start.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Checkpoint file of the search (one per start: FILE.0, FILE.1, …; each names
    /// its problem, and is resumed on that problem only). Files already there are
    /// refused without --resume.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// Resume the search from --checkpoint.
    #[arg(long, requires = "checkpoint")]
    resume: bool,
    /// Wall-time limit in seconds (above 0, at most 1e9): of each start (a start
    /// stopped by it is not converged; with --checkpoint it can be resumed), and of
    /// the traces' preparation (an error past it).
    #[arg(long, value_name = "SECONDS")]
    max_time: Option<f64>,
    #[command(flatten)]
    output: super::Output,
}

/// What `--json` prints: the identification, the held-out predictions and the fit
/// file written.
#[derive(Serialize)]
struct Printed<'a> {
    #[serde(flatten)]
    id: &'a Identification,
    #[serde(skip_serializing_if = "Option::is_none")]
    arms_selection: Option<&'a [Candidate]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hyperelastic_selection: Option<&'a [Candidate]>,
    validation: &'a [Validation],
    fit_file: String,
}

/// What `--json` prints for a failed run: the failure and no fit file (`null`).
#[derive(Serialize)]
struct PrintedFailure<'a> {
    #[serde(flatten)]
    failure: &'a Failure,
    fit_file: Option<String>,
}

/// A `--sigma NAME=VALUE`.
fn parse_sigma(text: &str) -> Result<(ChannelKind, Sigma)> {
    let bad = |msg: String| {
        Error::settings(format!("--sigma {text}: {msg}"))
            .with_hint("e.g. --sigma contraction=0.5um or --sigma capacitance=0.2%")
    };
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| bad("expected NAME=VALUE".into()))?;
    let kind = ChannelKind::parse(name.trim()).ok_or_else(|| {
        let names: Vec<&str> = ChannelKind::ALL.iter().map(|k| k.name()).collect();
        bad(format!(
            "no channel '{name}' (channels: {})",
            names.join(", ")
        ))
    })?;
    let value = value.trim();
    if let Some(p) = value.strip_suffix('%') {
        let f: f64 = p
            .trim()
            .parse()
            .map_err(|_| bad(format!("'{value}' is not a percentage")))?;
        return Ok((kind, Sigma::Relative(f / 100.0)));
    }
    let v = match kind.dimension() {
        Some(d) => parse_quantity(value, d).map_err(bad)?,
        None => value
            .parse()
            .map_err(|_| bad(format!("'{value}' is not a number")))?,
    };
    Ok((kind, Sigma::Absolute(v)))
}

/// `--NAME auto`, or an error for anything else.
fn auto(flag: &str, value: Option<&str>, hint: &str) -> Result<bool> {
    match value {
        None => Ok(false),
        Some("auto") => Ok(true),
        Some(other) => Err(
            Error::settings(format!("--{flag} {other}: only auto is understood"))
                .with_hint(hint.to_string()),
        ),
    }
}

/// The experiments of trace files on `base`, each file read once, with their
/// provenance entries (file and sha256).
fn experiments(
    files: &[PathBuf],
    base: &Scene,
    deadline: Option<Instant>,
) -> Result<(Vec<Experiment>, Vec<serde_json::Value>)> {
    let mut exps = Vec::with_capacity(files.len());
    let mut prov = Vec::with_capacity(files.len());
    for f in files {
        let t = trace::read(f)?;
        prov.push(
            serde_json::json!({"file": f.display().to_string(), "sha256": t.provenance.sha256}),
        );
        exps.push(Experiment::from_trace_within(&t, base, deadline)?);
    }
    Ok((exps, prov))
}

/// The largest `--max-time`: 10⁹ s (about 32 years), beyond any run, and well
/// inside what a `Duration` holds (1.8·10¹⁹ s).
pub const MAX_TIME_S: f64 = 1e9;

/// The wall-time limit of `--max-time SECONDS`: finite, above 0 and at most
/// [`MAX_TIME_S`], else refused (never a panic of `Duration`).
fn wall_limit(seconds: Option<f64>) -> Result<Option<Duration>> {
    let Some(t) = seconds else { return Ok(None) };
    if !(t.is_finite() && t > 0.0 && t <= MAX_TIME_S) {
        return Err(Error::settings(format!(
            "--max-time {t}: give a number of seconds above 0 and at most {MAX_TIME_S:e}"
        ))
        .with_hint("leave --max-time out for no time limit"));
    }
    Ok(Some(Duration::from_secs_f64(t)))
}

/// Refuse to start afresh over checkpoint files already there (`FILE.0` …
/// `FILE.starts`, the last the polish's): without `--resume` they would be
/// replaced, and they may be a search to resume or not checkpoints at all.
fn refuse_existing_checkpoints(file: &Path, starts: usize) -> Result<()> {
    let named = Checkpoint {
        file: file.to_path_buf(),
        every: 1,
        problem: Vec::new(),
    };
    let found: Vec<String> = (0..=starts)
        .map(|i| named.for_start(i).file)
        .filter(|f| std::fs::symlink_metadata(f).is_ok())
        .map(|f| f.display().to_string())
        .collect();
    if found.is_empty() {
        return Ok(());
    }
    Err(Error::settings(format!(
        "--checkpoint {}: {} already there; a fresh search would replace {}",
        file.display(),
        found.join(", "),
        if found.len() == 1 { "it" } else { "them" }
    ))
    .with_hint("add --resume to continue that search, or give another --checkpoint name"))
}

/// The `--trace` file as the write policy has it: lines go to a temporary file
/// beside the target ([`AtomicFile`]), put in place by [`TraceOut::commit`] when
/// the run has ended (a different file already there kept aside); a run refused
/// before that leaves the target as it was.
struct TraceOut {
    file: Arc<Mutex<Option<AtomicFile>>>,
    path: PathBuf,
}

/// The writer the [`TraceFile`] writes into: the shared temporary file.
struct Shared(Arc<Mutex<Option<AtomicFile>>>);

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut f = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        f.as_mut().map_or(Ok(buf.len()), |f| f.write(buf))
    }
    fn flush(&mut self) -> std::io::Result<()> {
        let mut f = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        f.as_mut().map_or(Ok(()), |f| f.flush())
    }
}

impl TraceOut {
    fn create(path: &Path) -> Result<TraceOut> {
        Ok(TraceOut {
            file: Arc::new(Mutex::new(Some(AtomicFile::create(path)?))),
            path: path.to_path_buf(),
        })
    }

    /// The trace the observers write.
    fn trace(&self) -> TraceFile {
        TraceFile::to_writer(Box::new(Shared(self.file.clone())), &self.path)
    }

    /// Put the trace in place (after every [`TraceOut::trace`] is dropped, which
    /// flushes its lines).
    fn commit(self) -> Result<()> {
        let file = self
            .file
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take();
        file.map_or(Ok(()), super::commit_noted)
    }
}

/// The stem of the first trace (for the default names).
fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "trace".into())
}

/// The searches an identification plans: `starts` per candidate, every model tried
/// by `--hyperelastic auto` ([`HYPERELASTIC_MODELS`]) with every number of arms
/// tried by `--arms auto` (0 to [`MAX_ARMS`]), one candidate without either. The
/// polish of a start's optimum, the rounds of the model reduction and a re-fit for
/// profiles come on top, as they begin ([`Searches`]).
fn planned_searches(starts: usize, choose: Choose) -> u64 {
    let models = match choose.hyperelastic {
        true => HYPERELASTIC_MODELS.len(),
        false => 1,
    };
    let arms = match choose.arms {
        true => MAX_ARMS + 1,
        false => 1,
    };
    (models * arms * starts) as u64
}

/// How to resume a search checkpointed in `file` (`FILE.0` … `FILE.starts`): this
/// command line with `--resume`.
fn resume_hint(file: &Path, starts: usize) -> String {
    let mut words: Vec<String> = std::env::args().collect();
    if !words.iter().any(|w| w == "--resume") {
        words.push("--resume".into());
    }
    let line: Vec<String> = words.iter().map(|w| shell_word(w)).collect();
    format!(
        "the search is checkpointed in {0}.0 … {0}.{starts}; to go on from there, run\n  {1}",
        file.display(),
        line.join(" ")
    )
}

/// `w` as a POSIX shell reads it back: as it is when made of plain characters,
/// else in single quotes.
fn shell_word(w: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./:=,@%+".contains(c);
    match !w.is_empty() && w.chars().all(plain) {
        true => w.to_string(),
        false => format!("'{}'", w.replace('\'', r"'\''")),
    }
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let choose = Choose {
        arms: auto(
            "arms",
            a.arms.as_deref(),
            "give the arms in the scene, or --arms auto to choose 0 to 4",
        )?,
        hyperelastic: auto(
            "hyperelastic",
            a.hyperelastic.as_deref(),
            "give the model in the scene, or --hyperelastic auto to choose an invariant model",
        )?,
    };
    let max_wall = wall_limit(a.max_time)?;
    // the traces' preparation (fitting each measured drive) is under the time
    // budget too: it ends by the command's start plus --max-time
    let deadline = max_wall.map(|d| std::time::Instant::now() + d);
    if a.checkpoint.is_some() && (choose.arms || choose.hyperelastic) {
        return Err(Error::settings(
            "--checkpoint with --arms auto or --hyperelastic auto: a checkpoint holds the \
             search of one problem, and a selection fits one per candidate",
        )
        .with_hint("give the model and arms in the scene to checkpoint the search"));
    }
    let base = Scene::read(&a.scene)?;
    let (exps, traces) = experiments(&a.traces, &base, deadline)?;
    let (mut held, _) = experiments(&a.validate, &base, deadline)?;
    // a held-out trace the scene cannot start on is refused before the search
    for e in &held {
        e.check_start(&dea_fit::identify::params::theta(&e.scene))?;
    }
    let settings = Settings {
        free: a.free.clone(),
        fix: a.fix.clone(),
        sigma: a
            .sigma
            .iter()
            .map(|s| parse_sigma(s))
            .collect::<Result<_>>()?,
        starts: a.starts,
        seed: a.seed,
        lm: dea_fit::fit::lm::LmSettings {
            max_iterations: a.max_iterations,
            ..Settings::default().lm
        },
        rtol: a.rtol,
        profiles: a.profiles.clone(),
        ..Settings::default()
    };
    settings.check()?;
    // every file this run writes, known before anything runs: none inside the
    // report folder
    let name = format!("{}-identified", stem(&a.traces[0]));
    let (out, dir) = a.output.paths(&name);
    super::refuse_in_report(
        dir.as_deref(),
        &[
            ("--out", Some(&out)),
            ("--trace", a.trace.as_deref()),
            ("--checkpoint", a.checkpoint.as_deref()),
        ],
    )?;
    if let (Some(f), false) = (&a.checkpoint, a.resume) {
        refuse_existing_checkpoints(f, a.starts)?;
    }
    // settings checked: the trace goes to a temporary file, put in place when the
    // run ends (a run refused later leaves the file there as it was)
    let trace_out = a.trace.as_deref().map(TraceOut::create).transpose()?;
    let trace_file = trace_out.as_ref().map(TraceOut::trace);
    let searches = Searches::new(Meter::new(
        "identify",
        "searches",
        Some(planned_searches(a.starts, choose)),
    ));
    let resume = a.checkpoint.as_ref().map(|f| resume_hint(f, a.starts));
    dea_fit::observe::on_interrupt(resume.clone());
    let control = |i: usize| {
        let mut c = Control::default();
        c.observers.push(Box::new(searches.observer(i)));
        if let Some(t) = &trace_file {
            c.observers.push(Box::new(t.observer(i)));
        }
        c.checkpoint = a.checkpoint.as_ref().map(|f| {
            Checkpoint {
                file: f.clone(),
                every: 1,
                // stamped with the problem's parts by identify_with
                problem: Vec::new(),
            }
            .for_start(i)
        });
        c.resume = a.resume;
        c.max_wall = max_wall;
        c
    };
    // The experiments as identified (with the chosen model and arms, when a
    // selection chose them), for the material file and the report.
    let (run, kept, selection) = match choose {
        Choose {
            arms: false,
            hyperelastic: false,
        } if a.free.is_none() && a.fix.is_empty() => {
            // the default: the smallest identifiable model
            let run = dea_fit::identify::reduce::identify(&exps, &settings, &control)?;
            (run, exps, None)
        }
        Choose {
            arms: false,
            hyperelastic: false,
        } => {
            let kept = exps.clone();
            (identify_with(exps, &settings, &control)?, kept, None)
        }
        _ => {
            let (id, kept, comparison) = select(exps, &settings, choose, &control)?;
            (Run::Identified(Box::new(id)), kept, Some(comparison))
        }
    };
    searches.meter().finish();
    dea_fit::observe::on_interrupt(None);
    if let (Some(hint), true) = (&resume, searches.timed_out()) {
        eprintln!("note: a search stopped at its --max-time limit; {hint}");
    }
    drop(trace_file);
    if let Some(t) = trace_out {
        t.commit()?;
    }
    let mut id = match run {
        Run::Identified(id) => *id,
        Run::Failed(f) => return Ok(failed(&f, a.output.json)),
    };
    // The held-out traces on the material as identified (a selection may have
    // changed its model and arms).
    for e in &mut held {
        e.scene.material = kept[0].scene.material.clone();
    }
    let validation: Vec<Validation> = held
        .iter()
        .map(|e| validate(&id, e))
        .collect::<Result<_>>()?;
    // a held-out trace the identified constants cannot run, or miss, is a finding,
    // not an error: status `not_validated` (blocking under --strict) unless the
    // identification already blocks for its own reason
    for w in validation.iter().filter_map(Validation::warning) {
        id.warnings.push(w);
        if !id.status.is_blocking() {
            id.status = Status::NotValidated;
        }
    }
    let provenance = serde_json::json!({
        "tool": format!("dea-fit {}", env!("CARGO_PKG_VERSION")),
        "traces": traces,
        "scene": {
            "file": a.scene.display().to_string(),
            "sha256": dea_fit::io::sha256_hex(&std::fs::read(&a.scene).map_err(|e| Error::io(&a.scene, e))?),
        },
        "settings": {
            "free": id.parameters.iter().map(|p| p.name.clone()).collect::<Vec<_>>(),
            "held": &id.held,
            "starts": a.starts, "seed": a.seed, "rtol": a.rtol, "sigma": a.sigma,
            "arms": a.arms, "hyperelastic": a.hyperelastic,
        },
    });
    let file = material_file(&id, &kept[0].scene, provenance)?;
    let json = file.to_json()?;
    if let Some(d) = &dir {
        super::claim_dir(d)?;
    }
    super::write_fit_noted(&out, json.as_bytes(), |old| old == json)?;
    let page = dir
        .map(|d| dea_fit::report::identify::write(&id, &kept, &validation, selection.as_ref(), &d))
        .transpose()?;
    if a.output.json {
        let p = Printed {
            id: &id,
            arms_selection: selection
                .as_ref()
                .filter(|c| c.choose.arms)
                .map(|c| c.candidates.as_slice()),
            hyperelastic_selection: selection
                .as_ref()
                .filter(|c| c.choose.hyperelastic)
                .map(|c| c.candidates.as_slice()),
            validation: &validation,
            fit_file: out.display().to_string(),
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&p).expect("an identification serialises")
        );
    } else {
        print!(
            "{}",
            dea_fit::report::identify::summary(&id, &kept, &validation, selection.as_ref())?
        );
        println!("fit: {}", out.display());
        if let Some(r) = &page {
            println!("report: {}", r.display());
        }
    }
    Ok(id.status.exit_code(a.output.strict))
}

/// Print a failed run (JSON or text) and give its exit status, 1: no fit file or
/// report is written. (A failed `--arms auto` is the failure of its largest
/// candidate, before there is a comparison to print.)
fn failed(f: &Failure, json: bool) -> i32 {
    if json {
        let p = PrintedFailure {
            failure: f,
            fit_file: None,
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&p).expect("a failure serialises")
        );
    } else {
        print!("{}", dea_fit::report::identify::failure_summary(f));
    }
    1
}

#[cfg(test)]
mod tests {
    use super::*;
    use dea_fit::observe::Show;
    use std::time::Duration;

    /// The count of `--arms auto --hyperelastic auto` (issue 35: the bar read "36/9
    /// starts"): the total plans every candidate's starts, and the searches past it
    /// (each candidate's polish) raise it as they begin, so the count never passes
    /// its total and ends at the number that ran.
    #[test]
    fn the_search_count_never_passes_its_total() {
        let both = Choose {
            arms: true,
            hyperelastic: true,
        };
        let starts = 2;
        let planned = planned_searches(starts, both);
        assert_eq!(planned, 4 * 5 * 2);
        assert_eq!(
            planned_searches(
                8,
                Choose {
                    arms: false,
                    hyperelastic: true
                }
            ),
            32
        );
        assert_eq!(
            planned_searches(
                8,
                Choose {
                    arms: false,
                    hyperelastic: false
                }
            ),
            8
        );
        let meter = Meter::shown(
            Show::Off,
            Duration::from_secs(5),
            "identify",
            "searches",
            Some(planned),
        );
        let s = Searches::new(meter);
        // every candidate: its starts, then a polish
        let ran = 20 * (starts as u64 + 1);
        for _ in 0..ran {
            s.begin();
            let (pos, len) = s.meter().position();
            assert!(pos < len.unwrap(), "{pos}/{len:?}");
            s.end(false);
            let (pos, len) = s.meter().position();
            assert!(pos <= len.unwrap(), "{pos}/{len:?}");
        }
        assert_eq!(s.meter().position(), (ran, Some(ran)));
        assert!(!s.timed_out());
        s.begin();
        s.end(true);
        assert!(s.timed_out());
    }

    #[test]
    fn resume_words_read_back() {
        assert_eq!(shell_word("--resume"), "--resume");
        assert_eq!(shell_word("a b"), "'a b'");
        assert_eq!(shell_word("it's"), r"'it'\''s'");
        assert_eq!(shell_word(""), "''");
    }
}
