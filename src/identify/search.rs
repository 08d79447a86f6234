//! The multi-start search: the scene's own values plus starts spread over each free
//! constant's start box by the house's Latin hypercube
//! ([`crate::fit::multistart`], fixed seed), every start a bounded
//! Levenberg–Marquardt search ([`crate::fit::lm`], through argmin's `Executor`) on
//! its own copy of the problem, in parallel.

use super::problem::Problem;
use crate::error::Result;
use crate::fit::lm::{Control, LmSettings};
use crate::fit::multistart::{self, MultiStart};

/// The starts: `first` (the scene's values), then `n − 1` Latin-hypercube points
/// over the start boxes in search coordinates (a unit-cube design mapped onto each
/// box, so log-searched constants are spread evenly in ln θ).
pub fn starts(problem: &Problem, first: Vec<f64>, n: usize, seed: u64) -> Result<Vec<Vec<f64>>> {
    let boxes: Vec<(f64, f64)> = problem
        .free
        .iter()
        .map(|c| {
            let (a, b) = (c.space.x(c.start_box.0), c.space.x(c.start_box.1));
            (a.min(b), a.max(b))
        })
        .collect();
    let unit = vec![(0.0, 1.0); boxes.len()];
    let mut out = vec![first];
    for u in multistart::latin_hypercube(&unit, n.saturating_sub(1), seed)? {
        out.push(
            u.iter()
                .zip(&boxes)
                .map(|(u, (a, b))| a + u * (b - a))
                .collect(),
        );
    }
    Ok(out)
}

/// Search from every start in parallel, each with the [`Control`] `control` makes
/// for its index (progress, trace, checkpoint, wall time).
pub fn run_all(
    problem: &Problem,
    starts: &[Vec<f64>],
    settings: &LmSettings,
    control: impl Fn(usize) -> Control + Sync,
) -> MultiStart {
    multistart::run(problem, starts, &problem.x_bounds(), settings, control)
}
