//! The multi-start search: the scene's own values plus starts spread over each free
//! constant's start box by a Latin hypercube (fixed seed), every start a bounded
//! Levenberg–Marquardt search ([`crate::fit::lm`]) on its own copy of the problem,
//! run in parallel with rayon.

use super::problem::{Counts, Problem};
use crate::fit::lm::{self, LmSettings, Termination};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// A start whose final cost is within this much of the best (in ½χ², i.e. a
/// hundredth of the 0.5 that moving one constant by one σ costs) or within 10⁻⁶ of it
/// relative, reached the best.
pub const AT_BEST_ABS: f64 = 0.01;

/// One start's outcome.
#[derive(Debug, Clone)]
pub struct StartResult {
    /// The start (search coordinates).
    pub x0: Vec<f64>,
    /// Where it ended.
    pub x: Vec<f64>,
    /// ½χ² there (∞ when the start could not be simulated).
    pub cost: f64,
    /// Iterations.
    pub iterations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// Simulator runs it took.
    pub counts: Counts,
    /// Why its last evaluation failed, if it did.
    pub failure: Option<String>,
}

impl StartResult {
    /// Whether this start reached `best`.
    pub fn at_best(&self, best: f64) -> bool {
        self.cost.is_finite() && self.cost - best <= AT_BEST_ABS.max(1e-6 * best)
    }
}

/// The starts: `first` (the scene's values), then `n − 1` Latin-hypercube points
/// over the start boxes (in search coordinates), seeded.
pub fn starts(problem: &Problem, first: Vec<f64>, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let k = problem.free.len();
    let m = n.saturating_sub(1);
    let mut out = vec![first];
    if m == 0 {
        return out;
    }
    let boxes: Vec<(f64, f64)> = problem
        .free
        .iter()
        .map(|c| {
            let (a, b) = (c.space.x(c.start_box.0), c.space.x(c.start_box.1));
            (a.min(b), a.max(b))
        })
        .collect();
    let strata: Vec<Vec<usize>> = (0..k)
        .map(|_| {
            let mut s: Vec<usize> = (0..m).collect();
            s.shuffle(&mut rng);
            s
        })
        .collect();
    for i in 0..m {
        let x = (0..k)
            .map(|j| {
                let u = (strata[j][i] as f64 + rng.gen::<f64>()) / m as f64;
                boxes[j].0 + u * (boxes[j].1 - boxes[j].0)
            })
            .collect();
        out.push(x);
    }
    out
}

/// Run one search from `x0` on a copy of `problem`.
pub fn run_one(problem: &Problem, x0: &[f64], settings: &LmSettings) -> StartResult {
    let mut p = problem.clone();
    p.counts = Counts::default();
    let bounds = p.x_bounds();
    let res = lm::minimize(&mut p, x0, &bounds, settings);
    StartResult {
        x0: x0.to_vec(),
        x: res.x,
        cost: if res.cost.is_finite() {
            res.cost
        } else {
            f64::INFINITY
        },
        iterations: res.iterations,
        termination: res.termination,
        counts: p.counts,
        failure: p.last_failure,
    }
}

/// Run every start in parallel; the results sorted by final cost.
pub fn run_all(problem: &Problem, starts: &[Vec<f64>], settings: &LmSettings) -> Vec<StartResult> {
    let mut r: Vec<StartResult> = starts
        .par_iter()
        .map(|x0| run_one(problem, x0, settings))
        .collect();
    r.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    r
}
