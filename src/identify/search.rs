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
/// for its index (progress, trace, checkpoint, wall time), raced against the
/// first start's cost with the margin [`reach_margin`].
pub fn run_all(
    problem: &Problem,
    starts: &[Vec<f64>],
    settings: &LmSettings,
    control: impl Fn(usize) -> Control + Sync,
) -> MultiStart {
    let margin = reach_margin(problem.free.len());
    multistart::run(
        problem,
        starts,
        &problem.x_bounds(),
        settings,
        margin,
        control,
    )
}

/// The margin in ½χ² above the first start's cost within which a start is never
/// given up ([`crate::fit::lm::out_of_reach`]): ½·χ²₀.₉₉₉(p), p the free
/// constants (13.9 for 9). A minimum that much worse is rejected against the
/// first start's by the likelihood-ratio test at the 0.1 % level, so a start that
/// settles there can never be the answer; the cost is χ² of residuals scaled by
/// their σ, so the margin does not grow with the number of samples (the 1 % of
/// the cost used before was 36 on the rig trace's 7000 residuals: there two starts
/// crept along a valley 23 above the best for 40 and 20 iterations, a quarter of
/// the search's CPU time, to reach the same optimum).
pub fn reach_margin(p: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(p.max(1) as f64).map_or(10.0, |c| 0.5 * c.inverse_cdf(0.999))
}
