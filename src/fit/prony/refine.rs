//! Stage 3: each term count's search from its starts, variable projection then a
//! joint polish.

use super::grid::{nnls_at, Grid};
use super::problem::Problem;
use super::projection::Projected;
use super::starts::starts;
use super::{Kernels, Method, Search, Setup};
use crate::error::Result;
use crate::fit::lm::{self, LmResult, LmSettings, Termination};
use rayon::prelude::*;

/// A fit at one term count.
#[derive(Debug, Clone)]
pub struct TermFit<K: Kernels> {
    /// Number of terms N.
    pub n_terms: usize,
    /// Scaled parameters, terms sorted by τ.
    pub p: Vec<f64>,
    /// ½‖r‖² at `p` as the fit found it (the polish's [`LmResult::cost`], the grid
    /// NNLS's residual), ∞ where not finite: what [`from_neighbours`] compares.
    pub cost: f64,
    /// LM iterations (summed over the searches).
    pub iterations: usize,
    /// Evaluations (summed over the searches).
    pub evaluations: usize,
    /// Why the last search stopped.
    pub termination: Termination,
    /// Starts searched.
    pub starts: usize,
    /// Starts whose search ended at the best cost.
    pub at_best: usize,
    /// The count's problem.
    pub problem: Problem<K>,
}

/// The subsamples the search of a longer curve runs on ([`Problem::subsample`]):
/// [`START_POINTS`] points, then ten times more a level while fewer than all of
/// them (none for a curve of at most [`START_POINTS`] points). Built once and
/// shared by every term count's searches: built by each, a 10⁶-point curve's
/// levels were 4·10⁵ + 4·10⁴ + 4·10³ rows (some 30 MB) again for every search,
/// two searches at a time.
#[derive(Debug, Clone)]
pub struct Levels<K: Kernels>(Vec<Problem<K>>);

impl<K: Kernels> Levels<K> {
    /// The levels of `prob`.
    pub fn new(prob: &Problem<K>) -> Levels<K> {
        let mut levels = Vec::new();
        let mut count = START_POINTS;
        while let Some(level) = prob.subsample(count) {
            levels.push(level);
            count *= 10;
        }
        Levels(levels)
    }
}

/// Stage 2 and 3 for every term count of `counts`, in parallel, then
/// [`from_neighbours`].
pub fn fit_counts<K: Kernels>(
    setup: &Setup<K>,
    grid: &Grid,
    counts: &[usize],
    settings: &Search,
) -> Result<Vec<TermFit<K>>> {
    let levels = Levels::new(&setup.prob);
    let fits = counts
        .par_iter()
        .map(|&nt| fit_terms(setup, &levels, grid, nt, settings))
        .collect::<Result<Vec<_>>>()?;
    Ok(match settings.method {
        Method::Grid => fits,
        _ => from_neighbours(setup, &levels, fits, settings),
    })
}

/// Stage 3b: each count searched again from its neighbours' optima (in parallel),
/// kept where it ends lower: the N + 1 terms' optimum without its term of least
/// reach ([`Problem::reach`]) where that count's χ² is lower by more than 10 of its
/// residual variances, and the N − 1 terms' optimum with a term put in the middle
/// of the widest gap of ln τ (the window's ends included) where N − 1 terms ended
/// lower than N. The grid's peaks can all
/// lead a count to a local minimum its neighbours are not in: on a 12-decade master
/// curve of ten terms a decade apart, 10 terms from the peaks ended with a term
/// beyond the data and the RMSE of 9 (1.76 %), where 11 terms without their least
/// reaching one reach 0.7 % (tests/dma.rs, the Prony recovery).
fn from_neighbours<K: Kernels>(
    setup: &Setup<K>,
    levels: &Levels<K>,
    fits: Vec<TermFit<K>>,
    settings: &Search,
) -> Vec<TermFit<K>> {
    let costs: Vec<f64> = fits.iter().map(|f| f.cost).collect();
    let m = setup.prob.len() as f64;
    let index = |n: usize| fits.iter().position(|g| g.n_terms == n);
    let starts: Vec<Vec<Vec<f64>>> = fits
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let n = f.n_terms;
            let mut s = Vec::new();
            if let Some(j) = index(n + 1) {
                // only where one more term lowers χ² by more than 10 (in units of
                // its residual variance): where it does not, there is nothing the
                // neighbour found that this count missed
                let s2 = 2.0 * costs[j] / (m - (2 * n + 3) as f64).max(1.0);
                if costs[i] - costs[j] > 5.0 * s2 {
                    s.push(without_least_reaching(setup, &fits[j]));
                }
            }
            match n.checked_sub(1).and_then(index) {
                Some(j) if costs[j] < costs[i] => s.push(with_widest_gap_filled(setup, &fits[j])),
                _ => {}
            }
            s
        })
        .collect();
    fits.into_par_iter()
        .zip(starts)
        .zip(costs)
        .map(|((f, s), fc)| {
            if s.is_empty() {
                return f;
            }
            let g = fit_from(setup, levels, f.n_terms, &s, settings);
            let (mut best, other) = match g.cost < fc {
                true => (g, f),
                false => (f, g),
            };
            best.iterations += other.iterations;
            best.evaluations += other.evaluations;
            best.starts += other.starts;
            best
        })
        .collect()
}

/// The ln τ of a fit of N + 1 terms without its term of least reach.
fn without_least_reaching<K: Kernels>(setup: &Setup<K>, f: &TermFit<K>) -> Vec<f64> {
    let n = f.n_terms;
    let mut prob = setup.prob.clone();
    prob.n_terms = n;
    let reach = prob.reach(&f.p);
    let weakest = (0..n)
        .min_by(|&a, &b| reach[a].total_cmp(&reach[b]))
        .expect("a term");
    (0..n)
        .filter(|&i| i != weakest)
        .map(|i| f.p[1 + n + i])
        .collect()
}

/// The ln τ of a fit of N − 1 terms with one more in the middle of the widest gap
/// between them and the window's ends.
fn with_widest_gap_filled<K: Kernels>(setup: &Setup<K>, f: &TermFit<K>) -> Vec<f64> {
    let n = f.n_terms;
    let mut knots = vec![setup.window.0.ln()];
    knots.extend(&f.p[1 + n..]);
    knots.push(setup.window.1.ln());
    let g = (0..knots.len() - 1)
        .max_by(|&a, &b| (knots[a + 1] - knots[a]).total_cmp(&(knots[b + 1] - knots[b])))
        .expect("two knots");
    let mut out = f.p[1 + n..].to_vec();
    out.insert(g, 0.5 * (knots[g] + knots[g + 1]));
    out
}

/// Stage 2 for one term count: the [`starts`], then either the moduli at the first
/// start's τ (the grid method) or [`refine`] (on `levels`, those of the setup's
/// problem).
pub fn fit_terms<K: Kernels>(
    setup: &Setup<K>,
    levels: &Levels<K>,
    grid: &Grid,
    n: usize,
    settings: &Search,
) -> Result<TermFit<K>> {
    let starts = starts(setup.window, grid, n, settings.max_starts);
    if settings.method == Method::Grid {
        let mut prob = count_problem(setup, n);
        let ts: Vec<f64> = starts[0].iter().map(|l| l.exp()).collect();
        let (e, it, cost) = nnls_at(&mut prob, &ts)?;
        let mut p = e;
        p.extend(ts.iter().map(|t| t.ln()));
        return Ok(TermFit {
            n_terms: n,
            p,
            cost,
            iterations: it,
            evaluations: prob.evaluations,
            termination: Termination::Converged("exact (NNLS at fixed τ)"),
            starts: 1,
            at_best: 1,
            problem: prob,
        });
    }
    Ok(fit_from(setup, levels, n, &starts, settings))
}

/// The problem of `setup` at `n` terms, its evaluations counted from 0.
fn count_problem<K: Kernels>(setup: &Setup<K>, n: usize) -> Problem<K> {
    at_count(&setup.prob, n)
}

/// `prob` (its rows shared) at `n` terms, its evaluations counted from 0.
fn at_count<K: Kernels>(prob: &Problem<K>, n: usize) -> Problem<K> {
    let mut prob = prob.clone();
    prob.n_terms = n;
    prob.evaluations = 0;
    prob
}

/// Stage 3 for `n` terms from the given starts (ln τ of each term): [`refine`] on
/// `levels` (those of the setup's problem).
pub fn fit_from<K: Kernels>(
    setup: &Setup<K>,
    levels: &Levels<K>,
    n: usize,
    starts: &[Vec<f64>],
    settings: &Search,
) -> TermFit<K> {
    refine(
        count_problem(setup, n),
        levels,
        starts,
        setup.bounds,
        settings,
    )
}

/// Sort the terms of a scaled parameter vector by τ.
fn sort_terms(p: &mut [f64], n: usize) {
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| p[1 + n + a].total_cmp(&p[1 + n + b]));
    let old = p.to_vec();
    for (new, &o) in idx.iter().enumerate() {
        p[1 + new] = old[1 + o];
        p[1 + n + new] = old[1 + n + o];
    }
}

/// Stage 3 for one term count: from each start, variable projection over ln τ
/// ([`Projected`]) on a subsample of at most [`START_POINTS`] points (all the data
/// when there are no more), stopping at the noise floor of its own cost
/// ([`NOISE_FLOOR`]); the best end carried through subsamples ten times larger
/// to all the data, each search starting next to its optimum and stopping at the
/// noise floor of the level before ([`NOISE_FLOOR`]); then one LM search over
/// all 2N + 1 parameters of [`Problem`] from the projection's optimum and its moduli,
/// a point of the joint problem's own valley floor: it takes an iteration or two and
/// makes the optimum the joint problem's to the solver's tolerances.
fn refine<K: Kernels>(
    mut prob: Problem<K>,
    levels: &Levels<K>,
    starts: &[Vec<f64>],
    ln_tau: (f64, f64),
    settings: &Search,
) -> TermFit<K> {
    let n = prob.n_terms;
    // The starts' searches stop at the noise floor of their own cost (as the polish
    // does): an accepted step that lowers ½‖r‖² by less than NOISE_FLOOR·s²,
    // s² = 2·cost/(m − 2N − 1) on the rows searched, ends them.
    let start_dof = prob
        .len()
        .min(START_POINTS)
        .saturating_sub(2 * n + 1)
        .max(1) as f64;
    let lms = LmSettings {
        max_iterations: settings.max_iterations,
        ftol: settings.ftol.max(2.0 * NOISE_FLOOR / start_dof),
        ..LmSettings::default()
    };
    let bounds = vec![ln_tau; n];
    let mut iterations = 0;
    let mut evaluations = 0;
    let mut tail = lms;
    let (r, joint, at_best) = match levels.0.split_first() {
        // Every point: the starts' projection is the last one; the moduli at the end
        // come from a cold start, as a fresh projection's would.
        None => {
            let mut vp = Projected::new(&mut prob);
            let (r, at_best) = best_start(&mut vp, starts, &bounds, &lms, &mut iterations);
            vp.positive.fill(false);
            vp.c.fill(0.0);
            vp.moduli_at(&r.x);
            let joint = vp.joint(&r.x);
            (r, joint, at_best)
        }
        Some((first, rest)) => {
            let mut sub = at_count(first, n);
            let (mut r, at_best) = {
                let mut vp = Projected::new(&mut sub);
                best_start(&mut vp, starts, &bounds, &lms, &mut iterations)
            };
            evaluations = sub.evaluations;
            // Past the starts, the searches stop at the noise floor of the level before.
            let floor = |cost: f64, m: usize| match cost.is_finite() {
                true => NOISE_FLOOR * 2.0 * cost / (m - (2 * n + 1)) as f64,
                false => 0.0,
            };
            tail.min_decrease = floor(r.cost, sub.len());
            for level in rest {
                let mut level = at_count(level, n);
                r = lm::minimize(&mut Projected::new(&mut level), &r.x, &bounds, &tail);
                iterations += r.iterations;
                evaluations += level.evaluations;
                tail.min_decrease = floor(r.cost, level.len());
            }
            let mut vp = Projected::new(&mut prob);
            r = lm::minimize(&mut vp, &r.x, &bounds, &tail);
            iterations += r.iterations;
            // The moduli at the end (the search's last evaluation may have been a
            // rejected trial).
            vp.moduli_at(&r.x);
            let joint = vp.joint(&r.x);
            (r, joint, at_best)
        }
    };
    let mut joint_bounds = vec![(0.0, f64::INFINITY); 1 + n];
    joint_bounds.extend(bounds);
    // The polish stops at the noise floor of the data too: where an accepted step
    // lowers ½χ² by less than NOISE_FLOOR (½‖r‖² by less than NOISE_FLOOR·s²,
    // s² = 2·cost/(m − 2N − 1), a relative decrease below 2·NOISE_FLOOR/(m − 2N − 1)).
    let dof = prob.len().saturating_sub(2 * n + 1).max(1) as f64;
    let polish_settings = LmSettings {
        ftol: tail.ftol.max(2.0 * NOISE_FLOOR / dof),
        ..tail
    };
    let polish = lm::minimize(&mut prob, &joint, &joint_bounds, &polish_settings);
    iterations += polish.iterations;
    let termination = match r.termination {
        Termination::Converged(_) => polish.termination,
        t => t,
    };
    let mut p = polish.x;
    sort_terms(&mut p, n);
    prob.release_kernels();
    TermFit {
        n_terms: n,
        p,
        cost: if polish.cost.is_finite() {
            polish.cost
        } else {
            f64::INFINITY
        },
        iterations,
        evaluations: prob.evaluations + evaluations,
        termination,
        starts: starts.len(),
        at_best,
        problem: prob,
    }
}

/// The projection's search from each start (their iterations added to
/// `iterations`): the end of lowest cost (the first of them; the first start's when
/// none is finite), and how many ends are within 10⁻⁶ of its cost.
fn best_start<K: Kernels>(
    vp: &mut Projected<K>,
    starts: &[Vec<f64>],
    bounds: &[(f64, f64)],
    lms: &LmSettings,
    iterations: &mut usize,
) -> (LmResult, usize) {
    let mut results: Vec<LmResult> = starts
        .iter()
        .map(|s| lm::minimize(vp, s, bounds, lms))
        .collect();
    *iterations += results.iter().map(|r| r.iterations).sum::<usize>();
    let best = results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.cost.is_finite())
        .min_by(|a, b| a.1.cost.total_cmp(&b.1.cost))
        .map(|(i, _)| i)
        .unwrap_or(0);
    let bc = results[best].cost;
    let at_best = results
        .iter()
        .filter(|r| (r.cost - bc).abs() <= 1e-6 * bc.max(f64::MIN_POSITIVE))
        .count();
    (results.swap_remove(best), at_best)
}

/// Points on which the multi-start search of a term count runs: a longer curve is
/// subsampled evenly ([`Problem::subsample`]) and only the best start is carried to all
/// the data. Every shipped curve has fewer points, so its fits search all of it.
pub const START_POINTS: usize = 400;

/// The noise floor of the searches that carry the best start of a longer curve to
/// all its points ([`LmSettings::min_decrease`]), as a fraction of the residual
/// variance s² = ‖r‖²/(m − 2N − 1) of the level before: they stop when even the
/// Gauss-Newton step would lower ½‖r‖²/s² (half the χ²) by less than 10⁻³, where no
/// estimate can move by more than about √(2·10⁻³) ≈ 0.045 standard errors, instead
/// of walking the flat valleys of a term count the data do not support. The starts'
/// searches and the polish, which have no level before, take s² from their own cost
/// (a relative decrease of ½‖r‖² below 2·10⁻³/(m − 2N − 1) ends them): on the
/// shipped DMA master curve at 30 terms the starts walked 35–90 iterations each
/// without it, 21–33 with it (E∞ 79 811 → 79 809 Pa, no σ at 30 terms; the chosen
/// `auto` fit's E∞ moved by 0.002 Pa of its σ 105 Pa).
const NOISE_FLOOR: f64 = 1e-3;
