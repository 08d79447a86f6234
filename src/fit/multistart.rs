//! Multi-start: many LM searches of one problem from starts spread over the bounds,
//! run in parallel, and how many of them reach the best cost.
//!
//! The spread is a Latin hypercube (McKay, Beckman & Conover 1979): for n starts
//! each coordinate's range is cut into n equal strata and every stratum holds
//! exactly one start, at a uniform position inside it, the strata paired across
//! coordinates by independent random permutations (ChaCha8, fixed seed, so the
//! design is reproducible). A coordinate with a positive lower bound is spread in
//! log space (its strata equal ratios), as positive material constants span
//! decades.

use super::lm::{self, Control, LeastSquares, LmResult, LmSettings};
use crate::error::{Error, Result};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Relative tolerance of "at the best cost": a start reached the best if its cost is
/// at most `best · (1 + AT_BEST_REL) + AT_BEST_ABS`. 1e-6 is far above the LM's
/// cost tolerance (ftol 1e-12: converged starts of one minimum agree to ≈ 1e-10) and
/// far below the gap between distinct minima worth reporting.
pub const AT_BEST_REL: f64 = 1e-6;

/// Absolute floor of "at the best cost" (see [`AT_BEST_REL`]), for a best cost at
/// or near zero (an exact fit, where the relative rule alone counts only the start
/// whose rounding happened to be smallest). Costs are those of scaled residuals, as
/// every problem of the house has (stress over its scale, residuals over their
/// noise σ): rounding leaves an exact fit at ≈ m·1e-30, while measured data cannot
/// go below ≈ m·2e-15 (a 24-bit reading resolves 6e-8 of full scale); 1e-18 lies
/// orders from both.
pub const AT_BEST_ABS: f64 = 1e-18;

/// `n` starts of a Latin hypercube over `bounds` from `seed` (see the module doc).
/// Every bound must be finite with lo < hi, or lo = hi (the coordinate is then that
/// value in every start): a range without ends cannot be spread over.
pub fn latin_hypercube(bounds: &[(f64, f64)], n: usize, seed: u64) -> Result<Vec<Vec<f64>>> {
    if let Some((j, &(lo, hi))) = bounds
        .iter()
        .enumerate()
        .find(|(_, &(lo, hi))| !(lo.is_finite() && hi.is_finite() && lo <= hi))
    {
        return Err(Error::settings(format!(
            "parameter {j} has bounds [{lo}, {hi}]: starts can only be spread over a finite range"
        ))
        .with_hint("give the parameter finite search bounds (lo ≤ hi) or fix it"));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut starts = vec![vec![0.0; bounds.len()]; n];
    let mut strata: Vec<usize> = (0..n).collect();
    for (j, &(lo, hi)) in bounds.iter().enumerate() {
        strata.shuffle(&mut rng);
        let log = lo > 0.0;
        let (a, b) = if log { (lo.ln(), hi.ln()) } else { (lo, hi) };
        for (start, &k) in starts.iter_mut().zip(&strata) {
            let u = (k as f64 + rng.gen::<f64>()) / n as f64;
            let v = a + u * (b - a);
            // exp/ln may step a rounding outside [lo, hi]: project back.
            start[j] = lm::project(if log { v.exp() } else { v }, (lo, hi));
        }
    }
    Ok(starts)
}

/// How many of `costs` are at the best (finite) one, by [`AT_BEST_REL`] and
/// [`AT_BEST_ABS`], widened by twice the searches' noise floor
/// ([`LmSettings::min_decrease`]: a search stopped there is within about that of
/// its minimum, so two stops in one minimum differ by up to twice it); 0 when
/// none is finite.
pub fn starts_at_best(costs: &[f64], min_decrease: f64) -> usize {
    let best = costs.iter().copied().fold(f64::INFINITY, f64::min);
    if !best.is_finite() {
        return 0;
    }
    costs
        .iter()
        .filter(|&&c| c <= best * (1.0 + AT_BEST_REL) + AT_BEST_ABS + 2.0 * min_decrease)
        .count()
}

/// The searches of a multi-start.
#[derive(Debug, Clone)]
pub struct MultiStart {
    /// Each start and its search's result (final cost, x, iterations, evaluations,
    /// termination), in the order of the starts given.
    pub runs: Vec<(Vec<f64>, LmResult)>,
    /// Index into `runs` of the lowest finite cost (the first of equals); None if
    /// no search ended finite.
    pub best: Option<usize>,
    /// How many searches reached the best cost ([`starts_at_best`]).
    pub at_best: usize,
    /// How many were given up as out of reach of the first start's cost
    /// ([`lm::Termination::Abandoned`]; their final cost is where they stopped).
    pub abandoned: usize,
}

impl MultiStart {
    /// The best search, if any ended finite.
    pub fn best(&self) -> Option<&LmResult> {
        self.best.map(|i| &self.runs[i].1)
    }

    /// Final costs sorted ascending (non-finite last): the waterfall of a
    /// multi-start, flat at the bottom for the starts that found the best minimum.
    pub fn waterfall(&self) -> Vec<f64> {
        let mut costs: Vec<f64> = self.runs.iter().map(|(_, r)| r.cost).collect();
        costs.sort_by(|a, b| match (a.is_finite(), b.is_finite()) {
            (true, true) => a.total_cmp(b),
            (x, y) => y.cmp(&x),
        });
        costs
    }
}

/// Search `problem` from every start in `starts`: the first alone, then the
/// others in parallel (rayon; each gets its own clone of the problem and the
/// [`Control`] that `control` makes for its index: observers, checkpoint, wall
/// time), each given up once it cannot come within `margin` of the first's cost
/// ([`lm::out_of_reach`]). The first is the caller's best guess (for
/// identification the scene's own constants); racing the others against it, not
/// against each other, keeps the result independent of the thread count.
pub fn run<P, C>(
    problem: &P,
    starts: &[Vec<f64>],
    bounds: &[(f64, f64)],
    settings: &LmSettings,
    margin: f64,
    control: C,
) -> MultiStart
where
    P: LeastSquares + Clone + Send + Sync,
    C: Fn(usize) -> Control + Sync,
{
    let search = |i: usize, x0: &Vec<f64>, reach: Option<lm::Reach>| {
        let mut p = problem.clone();
        let mut c = control(i);
        c.reach = reach;
        (x0.clone(), lm::search(&mut p, x0, bounds, settings, &mut c))
    };
    let mut runs: Vec<(Vec<f64>, LmResult)> = Vec::with_capacity(starts.len());
    if let Some(x0) = starts.first() {
        runs.push(search(0, x0, None));
    }
    let reach = runs
        .first()
        .map(|r| r.1.cost)
        .filter(|c| c.is_finite())
        .map(|cost| lm::Reach { cost, margin });
    runs.par_extend(
        starts
            .par_iter()
            .enumerate()
            .skip(1)
            // every start a task of its own: their costs differ by 10× and more, so
            // starts grouped into one task leave a thread idle at the end
            .with_max_len(1)
            .map(|(i, x0)| search(i, x0, reach)),
    );
    let costs: Vec<f64> = runs.iter().map(|(_, r)| r.cost).collect();
    let best = (0..costs.len())
        .filter(|&i| costs[i].is_finite())
        .min_by(|&a, &b| costs[a].total_cmp(&costs[b]));
    MultiStart {
        at_best: starts_at_best(&costs, settings.min_decrease),
        abandoned: runs
            .iter()
            .filter(|r| matches!(r.1.termination, lm::Termination::Abandoned(_)))
            .count(),
        best,
        runs,
    }
}
