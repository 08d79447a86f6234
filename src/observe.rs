//! Observers of a least-squares search (argmin's `Observe` on
//! [`LmState`](crate::fit::lm::LmState)), for the CLI: a progress bar and a
//! JSON-lines iteration trace (`--trace FILE`). Give them to a search through
//! [`Control::observers`](crate::fit::lm::Control), one per start.

use crate::error::{Error, Result};
use crate::fit::lm::LmState;
use argmin::core::observers::Observe;
use argmin::core::{State, KV};
use indicatif::{ProgressBar, ProgressStyle};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The LM's count `key` (`iteration`, `evaluations`).
fn count(kv: &KV, key: &str) -> Option<u64> {
    kv.get(key)?.get_uint()
}

/// A bar of starts done, its message the current start's iteration and cost. One
/// bar may serve every start of a multi-start (each start's observer holds a clone).
pub struct Progress {
    bar: ProgressBar,
    start: usize,
}

impl Progress {
    /// A bar for `starts` searches on stderr (hidden when stderr is not a terminal).
    pub fn bar(starts: usize) -> ProgressBar {
        let bar = ProgressBar::new(starts as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} starts {msg}") {
            bar.set_style(style);
        }
        bar
    }

    /// The observer of start `start` on `bar`.
    pub fn new(bar: &ProgressBar, start: usize) -> Progress {
        Progress {
            bar: bar.clone(),
            start,
        }
    }
}

impl Observe<LmState> for Progress {
    fn observe_iter(
        &mut self,
        state: &LmState,
        kv: &KV,
    ) -> std::result::Result<(), argmin::core::Error> {
        let it = count(kv, "iteration").unwrap_or(0);
        self.bar.set_message(format!(
            "start {}: iteration {it}, cost {:.4e}",
            self.start,
            state.get_cost()
        ));
        Ok(())
    }

    fn observe_final(&mut self, _state: &LmState) -> std::result::Result<(), argmin::core::Error> {
        self.bar.inc(1);
        Ok(())
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
