//! What a checkpoint of an identification belongs to: the parts that define its
//! problem, each as a sha256 digest (or a short value), saved in every checkpoint
//! file ([`crate::fit::lm::Checkpoint::problem`]) and compared when a search
//! resumes, so that a checkpoint written for one trace, scene, free set or setting
//! is refused on another (naming the parts that differ) instead of returning the
//! first problem's constants.
//!
//! The parts: `tool` (the dea-fit version: another version may pose the problem
//! otherwise), `trace N` (each trace's sample times, measured drive as the
//! simulator sees it, channels' values), `sigma` (every channel's noise σ, which
//! weighs its residuals: given, or from the data, and for the polish from the
//! best search's residuals), `scene` (actuator, load, source,
//! control, tolerances and integrator, the material's model and structure),
//! `free` (the free constants, their search coordinates and bounds), `constants`
//! (every constant's value: the fixed ones and the free ones' start), `settings`
//! (the start design's seed and count, the simulator's run options) and `start`
//! (the index of the search: start i, or the polish).
//!
//! Values are hashed by their `Debug` text, which for an f64 is the shortest
//! decimal that reads back to the same bits: equal digests mean equal bits.

use super::problem::Problem;
use super::Settings;
use crate::fit::lm::{Control, LeastSquares};
use sha2::{Digest, Sha256};
use std::fmt::Write;

/// A sha256 fed through `fmt::Write` (a `Debug` text is streamed, never built).
struct Hasher(Sha256);

impl Write for Hasher {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.update(s.as_bytes());
        Ok(())
    }
}

impl Hasher {
    fn new() -> Hasher {
        Hasher(Sha256::new())
    }

    /// Feed `v`'s `Debug` text and a separator.
    fn feed(&mut self, v: &dyn std::fmt::Debug) {
        // writing into a hasher cannot fail
        let _ = write!(self, "{v:?};");
    }

    fn hex(self) -> String {
        crate::io::hex(&self.0.finalize())
    }
}

/// The parts of `problem` under `settings` (module documentation), without the
/// start.
pub fn parts(problem: &Problem, settings: &Settings) -> Vec<(String, String)> {
    let mut out = vec![(
        "tool".to_string(),
        format!("dea-fit {}", env!("CARGO_PKG_VERSION")),
    )];
    let mut scene = Hasher::new();
    for (j, e) in problem.experiments.iter().enumerate() {
        let mut h = Hasher::new();
        h.feed(&e.scene.time);
        h.feed(&e.scene.input);
        for c in &e.channels {
            h.feed(&(c.kind.name(), &c.values));
        }
        out.push((format!("trace {}", j + 1), h.hex()));
        let s = &e.scene;
        let m = &s.material;
        scene.feed(&(s.actuator, s.load, s.source, &s.control));
        scene.feed(&(s.time.rtol, s.time.atol, s.time.method, s.time.fidelity));
        scene.feed(&(&m.spec, &m.viscous, m.composite, m.density, m.resistivity));
    }
    out.push(("scene".into(), scene.hex()));
    out.push(sigma(problem));
    let mut free = Hasher::new();
    for c in &problem.free {
        free.feed(&(&c.name, c.index, c.space, c.bounds, c.start_box, &c.mixture));
    }
    out.push(("free".into(), free.hex()));
    let mut constants = Hasher::new();
    constants.feed(&problem.theta);
    out.push(("constants".into(), constants.hex()));
    let mut s = Hasher::new();
    s.feed(&(settings.seed, settings.starts, problem.run));
    out.push(("settings".into(), s.hex()));
    out
}

/// The `sigma` part: every channel's σ, in the order of the traces.
fn sigma(problem: &Problem) -> (String, String) {
    let mut h = Hasher::new();
    for e in &problem.experiments {
        for c in &e.channels {
            h.feed(&(c.kind.name(), c.sigma));
        }
    }
    ("sigma".into(), h.hex())
}

/// The polish's `control` after its σ were estimated from the best search's
/// residuals: its `sigma` part is the polish problem's. A checkpoint it cannot
/// resume from (a polish of another best search, whose σ differ, or a file that
/// is not one of this problem's) is not read: the polish starts afresh from this
/// run's best, its first save keeping that file aside.
pub fn for_polish(c: &mut Control, problem: &Problem) {
    let Some(cp) = &mut c.checkpoint else { return };
    let (name, digest) = sigma(problem);
    for part in cp.problem.iter_mut().filter(|p| p.0 == name) {
        part.1 = digest.clone();
    }
    if c.resume && cp.file.exists() && cp.check(problem.dims(), &problem.x_bounds()).is_err() {
        c.resume = false;
    }
}

/// `control` with each checkpoint stamped with `parts` and the search's index
/// (`start`: i for start i, the number of starts for the polish).
pub fn stamped<'a>(
    control: &'a (dyn Fn(usize) -> Control + Sync),
    parts: &'a [(String, String)],
) -> impl Fn(usize) -> Control + Sync + 'a {
    move |i| {
        let mut c = control(i);
        if let Some(cp) = &mut c.checkpoint {
            cp.problem = parts.to_vec();
            cp.problem.push(("start".into(), i.to_string()));
        }
        c
    }
}
