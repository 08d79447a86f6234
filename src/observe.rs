//! Progress of long commands on stderr ([`Meter`], the one way every command shows
//! it), observers of a least-squares search (argmin's `Observe` on
//! [`LmState`](crate::fit::lm::LmState)) for the CLI: progress ([`Searches`]) and a
//! JSON-lines iteration trace (`--trace FILE`). Give the observers to a search
//! through [`Control::observers`](crate::fit::lm::Control), one per start.
//!
//! The rule (README, "Progress"): `DEA_FIT_PROGRESS` = `auto` (the default) draws a
//! bar when stderr is a terminal and otherwise writes a heartbeat line every
//! `DEA_FIT_PROGRESS_PERIOD` seconds (default [`PERIOD_S`], the first after one
//! period, so a short run writes none): what runs, how far, the time elapsed;
//! `bar` and `lines` force either, `off` shows nothing. Progress goes to stderr
//! only, so it is there under `--json` too (stdout stays the JSON).

use crate::error::{Error, Result};
use crate::fit::lm::LmState;
use argmin::core::observers::Observe;
use argmin::core::{State, TerminationReason, KV};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressFinish, ProgressStyle};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

/// The LM's count `key` (`iteration`, `evaluations`).
fn count(kv: &KV, key: &str) -> Option<u64> {
    kv.get(key)?.get_uint()
}

/// Seconds between heartbeat lines unless `DEA_FIT_PROGRESS_PERIOD` says otherwise.
pub const PERIOD_S: f64 = 5.0;

/// How progress shows ([`Show::choose`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Show {
    /// A bar redrawn in place (a terminal).
    Bar,
    /// A heartbeat line every period (a file, a pipe, a notebook cell).
    Lines,
    /// Nothing.
    Off,
}

impl Show {
    /// What `setting` (the value of `DEA_FIT_PROGRESS`: `auto`, `bar`, `lines`,
    /// `off`; unset or empty is `auto`) asks for when stderr is a `terminal` or
    /// not; `Err` names a value not understood.
    pub fn choose(setting: Option<&str>, terminal: bool) -> std::result::Result<Show, String> {
        match setting.map(str::trim).unwrap_or("") {
            "" | "auto" if terminal => Ok(Show::Bar),
            "" | "auto" => Ok(Show::Lines),
            "bar" => Ok(Show::Bar),
            "lines" => Ok(Show::Lines),
            "off" => Ok(Show::Off),
            other => Err(format!(
                "DEA_FIT_PROGRESS={other} is not understood (auto, bar, lines or off): auto"
            )),
        }
    }

    /// From the environment, for this process's stderr (a value not understood is
    /// `auto`, with a warning).
    fn from_env() -> Show {
        use std::io::IsTerminal;
        let terminal = std::io::stderr().is_terminal();
        let setting = std::env::var("DEA_FIT_PROGRESS").ok();
        Show::choose(setting.as_deref(), terminal).unwrap_or_else(|why| {
            eprintln!("warning: {why}");
            Show::choose(None, terminal).unwrap_or(Show::Off)
        })
    }
}

/// The heartbeat period: `DEA_FIT_PROGRESS_PERIOD` seconds when it is a number
/// above 0 (at most a day), else [`PERIOD_S`].
fn period() -> Duration {
    std::env::var("DEA_FIT_PROGRESS_PERIOD")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|&s| s > 0.0 && s <= 86_400.0)
        .map_or(Duration::from_secs_f64(PERIOD_S), Duration::from_secs_f64)
}

/// The heartbeat thread of a [`Meter`]: stopped (and joined) by [`Beat::stop`] or
/// when the last clone of the meter goes.
struct Beat(Mutex<Option<(Sender<()>, JoinHandle<()>)>>);

impl Beat {
    fn stop(&self) {
        let taken = self.0.lock().unwrap_or_else(PoisonError::into_inner).take();
        if let Some((tx, thread)) = taken {
            drop(tx);
            let _ = thread.join();
        }
    }
}

impl Drop for Beat {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The progress of one long command on stderr, shown as the rule of the module
/// says: a count of `unit` done (of a total when known) with a message. Clones
/// share it (each observer of a multi-start holds one).
#[derive(Clone)]
pub struct Meter {
    bar: ProgressBar,
    beat: Arc<Beat>,
}

impl Meter {
    /// A meter of the command `what` (`identify`, `rank`), counting `unit`
    /// (`searches`, `candidates`) of `total` (None: no count, the meter says how
    /// long it has been running), shown as the environment asks.
    pub fn new(what: &str, unit: &str, total: Option<u64>) -> Meter {
        Meter::shown(Show::from_env(), period(), what, unit, total)
    }

    /// [`Meter::new`] shown as `show`, heartbeat lines every `period`.
    pub fn shown(
        show: Show,
        period: Duration,
        what: &str,
        unit: &str,
        total: Option<u64>,
    ) -> Meter {
        let target = match show {
            Show::Bar => ProgressDrawTarget::stderr(),
            Show::Lines | Show::Off => ProgressDrawTarget::hidden(),
        };
        // a meter dropped unfinished (an error) clears its bar too
        let bar =
            ProgressBar::with_draw_target(total, target).with_finish(ProgressFinish::AndClear);
        let template = match total {
            Some(_) => format!("{{bar:30}} {{pos}}/{{len}} {unit} {{elapsed}} {{msg}}"),
            None => format!("{{spinner}} {what} {{elapsed}} {{msg}}"),
        };
        if let Ok(style) = ProgressStyle::with_template(&template) {
            bar.set_style(style);
        }
        if show == Show::Bar && total.is_none() {
            bar.enable_steady_tick(Duration::from_millis(200));
        }
        let beat = Beat(Mutex::new(None));
        if show == Show::Lines {
            let (tx, rx) = channel::<()>();
            let (b, what, unit) = (bar.clone(), what.to_string(), unit.to_string());
            let thread = std::thread::spawn(move || {
                while let Err(RecvTimeoutError::Timeout) = rx.recv_timeout(period) {
                    eprintln!("{}", heartbeat(&b, &what, &unit));
                }
            });
            *beat.0.lock().unwrap_or_else(PoisonError::into_inner) = Some((tx, thread));
        }
        Meter {
            bar,
            beat: Arc::new(beat),
        }
    }

    /// `n` more done.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
    }

    /// What is running now (shown after the count).
    pub fn set_message(&self, msg: impl Into<String>) {
        self.bar.set_message(msg.into());
    }

    /// What is running now ([`Meter::set_message`]).
    pub fn message(&self) -> String {
        self.bar.message()
    }

    /// Count done and the total (None: not known).
    pub fn position(&self) -> (u64, Option<u64>) {
        (self.bar.position(), self.bar.length())
    }

    /// Raise the total to at least `n`.
    fn at_least(&self, n: u64) {
        if self.bar.length().is_some_and(|l| l < n) {
            self.bar.set_length(n);
        }
    }

    /// The command is done: the bar goes, the heartbeat stops.
    pub fn finish(&self) {
        self.beat.stop();
        self.bar.finish_and_clear();
    }
}

/// One heartbeat line: `progress: identify, 25.0 s: 3/20 searches; start 2 of a
/// search of 7 constants: iteration 7, cost 1.2340e-3`.
fn heartbeat(bar: &ProgressBar, what: &str, unit: &str) -> String {
    let count = match bar.length() {
        Some(n) => format!("{}/{n} {unit}", bar.position()),
        None => "running".to_string(),
    };
    let msg = bar.message();
    format!(
        "progress: {what}, {:.1} s: {count}{}",
        bar.elapsed().as_secs_f64(),
        match msg.is_empty() {
            true => String::new(),
            false => format!("; {msg}"),
        }
    )
}

/// The searches of a command on a [`Meter`] counting them: each search's observer
/// ([`Searches::observer`]) counts it begun and ended and shows its iteration and
/// cost. The total is the searches planned; each search begun past it (a polish, a
/// refit round, a re-fit with profiles) raises it by one, so the count never passes
/// its total, and at the end the total is the number that ran.
#[derive(Clone)]
pub struct Searches {
    meter: Meter,
    begun: Arc<Mutex<u64>>,
    timed_out: Arc<AtomicBool>,
}

impl Searches {
    /// Searches counted on `meter` (its total: the searches planned).
    pub fn new(meter: Meter) -> Searches {
        Searches {
            meter,
            begun: Arc::new(Mutex::new(0)),
            timed_out: Arc::new(AtomicBool::new(false)),
        }
    }

    /// The observer of the search of start `start`.
    pub fn observer(&self, start: usize) -> Progress {
        Progress {
            searches: self.clone(),
            start,
            label: String::new(),
        }
    }

    /// A search begins.
    pub fn begin(&self) {
        let mut n = self.begun.lock().unwrap_or_else(PoisonError::into_inner);
        *n += 1;
        self.meter.at_least(*n);
    }

    /// A search ended; `timed_out`: stopped at its wall-time limit.
    pub fn end(&self, timed_out: bool) {
        if timed_out {
            self.timed_out.store(true, Ordering::Relaxed);
        }
        self.meter.inc(1);
    }

    /// Whether a search stopped at its wall-time limit (`--max-time`).
    pub fn timed_out(&self) -> bool {
        self.timed_out.load(Ordering::Relaxed)
    }

    /// The meter.
    pub fn meter(&self) -> &Meter {
        &self.meter
    }
}

/// The observer of one search on [`Searches`].
pub struct Progress {
    searches: Searches,
    start: usize,
    /// The search's label ([`crate::fit::lm::Control::label`]) and ": ", or empty.
    label: String,
}

/// The label of a search from its key-value pairs, followed by ": " (empty
/// without one).
fn label(kv: &KV) -> String {
    kv.get("label")
        .and_then(|v| v.get_string())
        .map_or_else(String::new, |l| format!("{l}: "))
}

impl Observe<LmState> for Progress {
    fn observe_init(
        &mut self,
        _name: &str,
        state: &LmState,
        kv: &KV,
    ) -> std::result::Result<(), argmin::core::Error> {
        self.searches.begin();
        self.label = label(kv);
        self.searches.meter.set_message(format!(
            "{}start {} of a search of {} constants",
            self.label,
            self.start,
            state.get_param().map_or(0, |x| x.len())
        ));
        Ok(())
    }

    fn observe_iter(
        &mut self,
        state: &LmState,
        kv: &KV,
    ) -> std::result::Result<(), argmin::core::Error> {
        let it = count(kv, "iteration").unwrap_or(0);
        self.searches.meter.set_message(format!(
            "{}start {} of a search of {} constants: iteration {it}, cost {:.4e}",
            self.label,
            self.start,
            state.get_param().map_or(0, |x| x.len()),
            state.get_cost()
        ));
        Ok(())
    }

    fn observe_final(&mut self, state: &LmState) -> std::result::Result<(), argmin::core::Error> {
        self.searches
            .end(state.get_termination_reason() == Some(&TerminationReason::Timeout));
        Ok(())
    }
}

/// What an interrupted run says before it ends ([`on_interrupt`]).
static ON_INTERRUPT: Mutex<Option<String>> = Mutex::new(None);

/// Set (or, with `None`, clear) what an interrupted run (SIGINT, SIGTERM, SIGHUP)
/// writes on stderr before it ends: how to resume it, for a checkpointed search.
pub fn on_interrupt(text: Option<String>) {
    *ON_INTERRUPT.lock().unwrap_or_else(PoisonError::into_inner) = text;
}

/// Write what [`on_interrupt`] set, if anything: called by the binary's signal
/// thread (as ordinary code, not in a signal handler) before the process ends.
pub fn interrupted() {
    if let Some(t) = ON_INTERRUPT
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .as_deref()
    {
        eprintln!("\n{t}");
    }
}

/// Where a [`Trace`] writes, shared by the observers of all starts.
type Sink = BufWriter<Box<dyn Write + Send>>;

/// A JSON-lines trace: one object per line, at the start of each search and after
/// each of its iterations,
/// `{"start":0,"iteration":3,"cost":1.2e-4,"damping":1e-5,"evaluations":7,"x":[...]}`
/// (`cost` = ½‖r‖² in the problem's units, `damping` = the LM's μ relative to
/// diag(JᵀJ), `x` the parameters as the search sees them). Lines of parallel starts
/// interleave, each whole.
#[derive(Clone)]
pub struct Trace {
    out: Arc<Mutex<Sink>>,
    path: PathBuf,
}

impl Trace {
    /// A trace written to a new (or truncated) `path`.
    pub fn create(path: &Path) -> Result<Trace> {
        let file = File::create(path).map_err(|e| Error::io(path, e))?;
        Ok(Trace::to_writer(Box::new(file), path))
    }

    /// A trace written to `out`, named `path` in error messages.
    pub fn to_writer(out: Box<dyn Write + Send>, path: &Path) -> Trace {
        Trace {
            out: Arc::new(Mutex::new(BufWriter::new(out))),
            path: path.to_path_buf(),
        }
    }

    /// The observer of start `start`.
    pub fn observer(&self, start: usize) -> TraceObserver {
        TraceObserver {
            trace: self.clone(),
            start,
            last: None,
        }
    }

    fn write(
        &self,
        f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> std::result::Result<(), argmin::core::Error> {
        let mut out = self
            .out
            .lock()
            .map_err(|_| argmin::core::Error::msg("the trace writer was poisoned"))?;
        f(&mut *out).map_err(|e| {
            argmin::core::Error::msg(format!(
                "cannot write the trace {}: {e}",
                self.path.display()
            ))
        })
    }
}

/// Writes one start's lines to a [`Trace`].
pub struct TraceObserver {
    trace: Trace,
    start: usize,
    /// The iteration of the last line: the call that stops a search without a step
    /// repeats it and writes nothing.
    last: Option<u64>,
}

impl TraceObserver {
    fn line(&mut self, state: &LmState, kv: &KV) -> std::result::Result<(), argmin::core::Error> {
        let it = count(kv, "iteration");
        if it.is_some() && it == self.last {
            return Ok(());
        }
        self.last = it;
        let line = serde_json::json!({
            "start": self.start,
            "iteration": count(kv, "iteration"),
            "cost": state.get_cost(),
            "damping": kv.get("damping").and_then(|v| v.get_float()),
            "evaluations": count(kv, "evaluations"),
            "x": state.get_param(),
        });
        self.trace.write(|w| writeln!(w, "{line}"))
    }
}

impl Observe<LmState> for TraceObserver {
    fn observe_init(
        &mut self,
        _name: &str,
        state: &LmState,
        kv: &KV,
    ) -> std::result::Result<(), argmin::core::Error> {
        self.line(state, kv)
    }

    fn observe_iter(
        &mut self,
        state: &LmState,
        kv: &KV,
    ) -> std::result::Result<(), argmin::core::Error> {
        self.line(state, kv)
    }

    fn observe_final(&mut self, _state: &LmState) -> std::result::Result<(), argmin::core::Error> {
        self.trace.write(|w| w.flush())
    }
}
