//! Profile likelihoods: for a free constant held at a value, the others re-fitted
//! with the search's bounded Levenberg–Marquardt, the rise Δχ² of χ² above its
//! minimum (Venzon & Moolgavkar 1988; Bates & Watts, *Nonlinear Regression
//! Analysis*, 1988, §6.1). Unlike the linearised (Wald) interval it follows a
//! curved or one-sided valley. One machinery ([`Profiler`]) serves three uses:
//!
//! - **The check of every Wald interval** ([`assess`], by default): in a linear
//!   model the profile of constant j at x̂ⱼ + δ rises by exactly Δχ² = (δ/σⱼ)²·s²
//!   (σⱼ from the covariance with every constant free, s² = χ²/(N − p)), so at
//!   δ = ±2σⱼ by 4·s². Where the measured rise on either side differs from that by
//!   more than [`WALD_TOLERANCE`], the linearisation does not hold over the interval
//!   and the Wald interval is not trusted.
//! - **The profile interval** there: on each side the value where Δχ² = t²·s² (t
//!   the Student quantile of the Wald interval, so that for a linear model both
//!   intervals coincide), by a secant on √Δχ² (linear in δ for a quadratic
//!   profile) kept inside its bracket. A side on which Δχ² stays below t²·s² up
//!   to the search's bound is open: the interval ends at that bound and says so.
//! - **The grid** of `--profiles NAME` ([`POINTS`] values over ±3σ) that reports
//!   plot.
//!
//! The re-fits start at the nearest profiled point moved along the linear
//! prediction x_o + Σ_oj/Σ_jj·δ. A constant that ended at a bound of its search is
//! free in them to cross that bound by up to the search box's width (search
//! coordinates; the simulator's domain refuses what is not physical), so a profile
//! is not conditional on a bound the search happened to stop at; a re-fitted
//! constant that ends at a bound at an interval's end makes that interval
//! conditional on it (`conditional_on`). A re-fit that finds a χ² below the
//! optimum's means the search missed the optimum: a warning.

use super::assessment::{self, Assessment, Context, Open};
use super::problem::Problem;
use crate::fit::lm::{self, LmSettings};
use crate::report::format::si;
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::Serialize;

/// Grid points per `--profiles` profile.
pub const POINTS: usize = 11;

/// Where the Wald interval is checked: x̂ ± this many σ (a little beyond the 95 %
/// interval's t ≈ 1.96, so the check covers the whole interval).
pub const CHECK_SIGMAS: f64 = 2.0;

/// Largest relative disagreement of the profile's rise at ±2σ with the quadratic
/// model's, |Δχ²/(4·s²) − 1|, for which the Wald interval is kept: 20 %, about 10 %
/// in the distance at which the profile reaches a level (√Δχ² is linear in δ for a
/// quadratic profile), while the rise's own error (the re-fits stop within
/// [`super::MIN_DECREASE`] of ½χ², ≤ 0.002 in Δχ² against 4) is far below it.
pub const WALD_TOLERANCE: f64 = 0.2;

/// A profile end is found when √Δχ² is within this fraction of t·s: the end is then
/// within about 1 % of its distance from the estimate.
pub const ROOT_TOLERANCE: f64 = 0.01;

/// Re-fits per side of a profile interval at most (beyond the check's); the last
/// one goes to the search's bound when no crossing was bracketed before.
pub const MAX_ROOT_STEPS: usize = 8;

/// A profile point whose χ² is below the optimum's by more than this is a better
/// point than the search's optimum: the search stops when a step promises less
/// than [`super::MIN_DECREASE`] = 10⁻³ of ½χ² (2·10⁻³ of χ²), so 0.01 is five times
/// what a converged search can leave.
pub const LOWER: f64 = 0.01;

/// The smallest decrease of ½χ² a re-fit's step must promise (the search's
/// [`super::MIN_DECREASE`] = 10⁻³ where that is larger): 0.01, so a re-fitted Δχ²
/// is within 0.02 of its minimum: 0.5 % of the 95 % level t²·s² ≈ 3.84 (0.25 % in
/// the distance of an interval's end, against [`ROOT_TOLERANCE`] = 1 %) and 2.5 %
/// of the [`WALD_TOLERANCE`] band (0.8 at ±2σ). The search's own rule chases the
/// integration noise of the cost there for nothing: a re-fit from the linear
/// prediction then ends after its first Jacobian more often (rig trace: 58
/// sensitivity runs for the checks and intervals of 7 constants before).
pub const REFIT_DECREASE: f64 = 0.01;

/// A profile point whose re-fit rose above this multiple of the 95 % level (or
/// failed) is re-fitted again from the nearest profiled point's values unmoved,
/// and the lower of the two is the profile's: a rise that steep next to a point
/// below the level is more often a re-fit that lost the valley (a weak constant
/// carried far by the linear prediction) than the trace. Points just above the
/// level, the ordinary ends of a bracket, keep one start.
pub const SECOND_START: f64 = 2.0;

/// A re-fitted constant within this fraction of its bounds' width (search
/// coordinates) of a bound is held by it (the assessment's test, [`assessment`]).
const AT_EDGE: f64 = 1e-6;

/// One constant's profile on the `--profiles` grid.
#[derive(Debug, Clone, Serialize)]
pub struct Profile {
    /// Constant.
    pub name: String,
    /// SI unit.
    pub unit: String,
    /// Held values (SI).
    pub values: Vec<f64>,
    /// χ²(value) − χ²min (∞ where the others could not be re-fitted; 0 where the
    /// re-fit went below the optimum, which a warning reports).
    pub delta_chi2: Vec<f64>,
    /// The 95 % level of Δχ²: t²·s² (3.84 for many points and s² = 1).
    pub threshold: f64,
    /// Where Δχ² crosses the threshold on each side (None: not within the grid).
    pub interval: [Option<f64>; 2],
}

/// The assessment of the optimum `x` (search coordinates) of `problem` with the
/// Jacobian `jac` of its scaled residuals and χ² = `rss`: the linearised one
/// ([`assessment::assess`]), each Wald interval checked against the profile at
/// ±2σ and replaced by the profile interval where they disagree
/// ([`WALD_TOLERANCE`]), in parallel; and the grid profiles of the free constants
/// `profiled`. The warnings of the profiles are in [`Assessment::warnings`].
/// `unchecked` says, from the linear estimates, when the checks are not wanted (a
/// model the default reduction shrinks further: [`super::reduce`]); the
/// assessment is then the linear one.
#[allow(clippy::too_many_arguments)]
pub fn assess(
    problem: &Problem,
    x: &[f64],
    jac: &DMatrix<f64>,
    rss: f64,
    ctx: &Context,
    profiled: &[usize],
    settings: &LmSettings,
    unchecked: &dyn Fn(&[assessment::Estimate]) -> bool,
) -> (Assessment, Vec<Profile>) {
    let mut lin = assessment::linear(&problem.free, x, jac, rss, ctx);
    let check = !unchecked(&lin.assessment.estimates);
    let (n, k) = (jac.nrows(), jac.ncols());
    let s2 = rss / n.saturating_sub(k).max(1) as f64;
    let box_bounds = problem.x_bounds();
    let at_bound: Vec<bool> = lin
        .assessment
        .estimates
        .iter()
        .map(|e| e.at_bound)
        .collect();
    let base = Base {
        problem,
        x,
        cost: 0.5 * rss,
        refit_bounds: released(&box_bounds, x, &at_bound),
        box_bounds,
        covariance: lin.covariance.clone(),
        s2,
        target: lin.t * lin.t * s2,
        settings: LmSettings {
            min_decrease: settings.min_decrease.max(REFIT_DECREASE),
            ..*settings
        },
    };
    // the check of every Wald interval, both sides of every constant in parallel
    let sides: Vec<(usize, f64)> = (0..k)
        .filter(|&j| check && lin.sigma_x[j].is_some())
        .flat_map(|j| [(j, -1.0), (j, 1.0)])
        .collect();
    // every side a task of its own (`with_max_len(1)`): a side's re-fits cost
    // from one run to dozens, and sides grouped into one task leave a thread idle
    let checks: Vec<(Point, bool, Option<Point>)> = sides
        .par_iter()
        .with_max_len(1)
        .map(|&(j, sign)| {
            let mut p = Profiler::new(&base, j);
            let sx = lin.sigma_x[j].expect("checked");
            let (point, agrees) = p.check(sx, sign);
            (point, agrees, p.lowest())
        })
        .collect();
    let mut lowest: Vec<(usize, Point)> = sides
        .iter()
        .zip(&checks)
        .filter_map(|(&(j, _), c)| c.2.clone().map(|p| (j, p)))
        .collect();
    // the profile interval of every constant whose check failed on either side
    let failed = |j: usize| sides.iter().zip(&checks).any(|(&(i, _), c)| i == j && !c.1);
    let ends: Vec<((usize, f64), End, Option<Point>)> = sides
        .iter()
        .zip(&checks)
        .filter(|(&(j, _), _)| failed(j))
        .collect::<Vec<_>>()
        .into_par_iter()
        .with_max_len(1)
        .map(|(&(j, sign), c)| {
            let mut p = Profiler::new(&base, j);
            p.points.push(c.0.clone());
            let end = p.end(sign);
            ((j, sign), end, p.lowest())
        })
        .collect();
    lowest.extend(
        ends.iter()
            .filter_map(|((j, _), _, l)| l.clone().map(|p| (*j, p))),
    );
    let profiled_intervals: Vec<usize> = (0..k)
        .filter(|&j| lin.sigma_x[j].is_some() && failed(j))
        .collect();
    for j in profiled_intervals {
        let side = |s: f64| {
            ends.iter()
                .find(|((i, sign), _, _)| *i == j && *sign == s)
                .map(|e| &e.1)
                .expect("both sides of a failed check")
        };
        let (below, above) = (side(-1.0), side(1.0));
        let c = &problem.free[j];
        let (a, b) = (c.space.theta(below.at), c.space.theta(above.at));
        let open = match (below.open, above.open) {
            (true, true) => Some(Open::Both),
            (true, false) => Some(Open::Below),
            (false, true) => Some(Open::Above),
            (false, false) => None,
        };
        let mut given: Vec<usize> = below.held.iter().chain(&above.held).copied().collect();
        given.sort_unstable();
        given.dedup();
        let given = given
            .iter()
            .map(|&i| problem.free[i].name.clone())
            .collect();
        lin.with_profile(&problem.free, j, [a.min(b), a.max(b)], open, given, ctx);
    }
    // the grids asked for
    let grids: Vec<(Profile, Option<Point>)> = profiled
        .par_iter()
        .with_max_len(1)
        .map(|&j| {
            let mut p = Profiler::new(&base, j);
            (p.grid(lin.sigma_x[j]), p.lowest())
        })
        .collect();
    lowest.extend(
        profiled
            .iter()
            .zip(&grids)
            .filter_map(|(&j, g)| g.1.clone().map(|p| (j, p))),
    );
    let mut a = lin.assessment;
    a.warnings.extend(missed_optimum(problem, &lowest));
    (a, grids.into_iter().map(|g| g.0).collect())
}

/// The warning of profile points below the optimum (`lowest`: constant, its
/// lowest point), naming the lowest.
fn missed_optimum(problem: &Problem, lowest: &[(usize, Point)]) -> Option<String> {
    let below: Vec<&(usize, Point)> = lowest.iter().filter(|(_, p)| p.delta < -LOWER).collect();
    let (j, p) = below
        .iter()
        .min_by(|a, b| a.1.delta.total_cmp(&b.1.delta))?;
    let c = &problem.free[*j];
    Some(format!(
        "the search missed the optimum: the profile of {} re-fitted the others to a χ² {:.3} below the reported optimum's at {} = {} ({} profile point(s) below it); the estimates and intervals are about the wrong point: rerun with more starts (--starts) or a scene nearer that point",
        c.name,
        -p.delta,
        c.name,
        si(c.space.theta(p.at), c.unit),
        below.len()
    ))
}

/// The bounds of the re-fits: the search box, a constant that ended at a bound
/// (`at_bound`) free to cross it by the box's width.
fn released(bounds: &[(f64, f64)], x: &[f64], at_bound: &[bool]) -> Vec<(f64, f64)> {
    bounds
        .iter()
        .zip(x)
        .zip(at_bound)
        .map(|((&(lo, hi), &xj), &held)| {
            let w = hi - lo;
            match (held, (xj - lo).abs() <= (hi - xj).abs()) {
                (false, _) => (lo, hi),
                (true, true) => (lo - w, hi),
                (true, false) => (lo, hi + w),
            }
        })
        .collect()
}

/// Whether `v` is held by a bound of `(lo, hi)` ([`AT_EDGE`]).
fn at_edge(v: f64, (lo, hi): (f64, f64)) -> bool {
    let tol = AT_EDGE * (hi - lo).abs().max(f64::MIN_POSITIVE);
    (v - lo).abs() <= tol || (hi - v).abs() <= tol
}

/// What every profile of one optimum shares.
struct Base<'a> {
    /// The problem, every free constant free.
    problem: &'a Problem,
    /// The optimum (search coordinates).
    x: &'a [f64],
    /// ½χ² at the optimum.
    cost: f64,
    /// The search box (search coordinates).
    box_bounds: Vec<(f64, f64)>,
    /// The re-fits' bounds ([`released`]).
    refit_bounds: Vec<(f64, f64)>,
    /// Covariance with every constant free (search coordinates; NaN if singular).
    covariance: DMatrix<f64>,
    /// s² = χ²/(N − p).
    s2: f64,
    /// The 95 % level of Δχ²: t²·s².
    target: f64,
    /// The re-fits' stopping rules (the search's, [`REFIT_DECREASE`]).
    settings: LmSettings,
}

/// One profiled point.
#[derive(Debug, Clone)]
struct Point {
    /// The held constant's value (search coordinates).
    at: f64,
    /// Δχ² (∞ where the others could not be re-fitted: the model cannot run there
    /// near the trace, so the value is excluded).
    delta: f64,
    /// The re-fitted others (search coordinates).
    others: Vec<f64>,
    /// The free constants (indices) a bound held in the re-fit.
    held: Vec<usize>,
}

/// One end of a profile interval.
#[derive(Debug, Clone)]
struct End {
    /// Where (search coordinates): the crossing, or the bound of an open side.
    at: f64,
    /// No crossing before the bound.
    open: bool,
    /// The free constants a bound held in the re-fit nearest the end.
    held: Vec<usize>,
}

/// The bracket of a profile end on one side: the farthest point (distance from
/// the estimate, √Δχ²) below the level and the nearest at or above it.
struct Bracket {
    level: f64,
    below: (f64, f64),
    above: Option<(f64, f64)>,
}

impl Bracket {
    fn add(&mut self, d: f64, u: f64) {
        if u < self.level {
            if d > self.below.0 {
                self.below = (d, u);
            }
        } else if self.above.is_none_or(|(a, _)| d < a) {
            self.above = Some((d, u));
        }
    }

    /// The crossing interpolated linearly in √Δχ² between the bracket's ends (its
    /// middle when the upper end could not be re-fitted); the upper end without one.
    fn crossing(&self) -> f64 {
        let (da, ua) = self.below;
        match self.above {
            Some((db, ub)) if ub.is_finite() => da + (self.level - ua) * (db - da) / (ub - ua),
            Some((db, _)) => 0.5 * (da + db),
            None => da,
        }
    }
}

/// The profile of free constant j: a copy of the problem with j held, re-fitted
/// at each value asked for.
struct Profiler<'a> {
    base: &'a Base<'a>,
    /// The held constant.
    j: usize,
    /// The problem of the others (j held through θ).
    problem: Problem,
    /// The others' re-fit bounds.
    bounds: Vec<(f64, f64)>,
    /// Σ_oj/Σ_jj of each other (0 where the covariance is singular).
    slope: Vec<f64>,
    /// Profiled so far; the optimum first.
    points: Vec<Point>,
}

impl<'a> Profiler<'a> {
    fn new(base: &'a Base<'a>, j: usize) -> Profiler<'a> {
        let mut problem = base.problem.clone();
        problem.free.remove(j);
        let skip = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .enumerate()
                .filter(|&(o, _)| o != j)
                .map(|(_, &x)| x)
                .collect()
        };
        let mut bounds = base.refit_bounds.clone();
        bounds.remove(j);
        let column: Vec<f64> = base.covariance.column(j).iter().copied().collect();
        let cjj = base.covariance[(j, j)];
        let slope = skip(&column)
            .into_iter()
            .map(|c| Some(c / cjj).filter(|s| s.is_finite()).unwrap_or(0.0))
            .collect();
        let optimum = Point {
            at: base.x[j],
            delta: 0.0,
            others: skip(base.x),
            held: Vec::new(),
        };
        Profiler {
            base,
            j,
            problem,
            bounds,
            slope,
            points: vec![optimum],
        }
    }

    /// The profile at x_j = `v`: the others re-fitted from the nearest point
    /// profiled so far, moved along the linear prediction (projected on the
    /// re-fit bounds; if the model cannot start there, on the search box).
    fn at(&mut self, v: f64) -> &Point {
        let near = self
            .points
            .iter()
            .min_by(|a, b| (a.at - v).abs().total_cmp(&(b.at - v).abs()))
            .expect("the optimum is a point");
        let from = near.others.clone();
        let predicted: Vec<f64> = near
            .others
            .iter()
            .zip(&self.slope)
            .map(|(&o, &s)| o + s * (v - near.at))
            .collect();
        let c = &self.base.problem.free[self.j];
        self.problem.theta[c.index] = c.space.theta(v);
        let project = |bounds: &[(f64, f64)]| -> Vec<f64> {
            predicted
                .iter()
                .zip(bounds)
                .map(|(&p, &b)| lm::project(p, b))
                .collect()
        };
        let mut r = lm::minimize(
            &mut self.problem,
            &project(&self.bounds),
            &self.bounds,
            &self.base.settings,
        );
        if r.evaluations <= 1 && !r.cost.is_finite() {
            let mut inside = self.base.box_bounds.clone();
            inside.remove(self.j);
            r = lm::minimize(
                &mut self.problem,
                &project(&inside),
                &self.bounds,
                &self.base.settings,
            );
        }
        let rise = 2.0 * (r.cost - self.base.cost);
        if rise.is_nan() || rise >= SECOND_START * self.base.target {
            // the linear prediction can carry a weak constant (an arm as slow as
            // the trace: its σ is huge) to where the model does not run, or into
            // another valley; the nearest profiled point's others, unmoved, are a
            // second start, and the lower re-fit is the profile's (slow-arm
            // study: three arm1.τ intervals 0.3–4 % wide, whose one-start
            // re-fits rose far above the level or failed, missed the truth)
            let unmoved: Vec<f64> = from
                .iter()
                .zip(&self.bounds)
                .map(|(&o, &b)| lm::project(o, b))
                .collect();
            let again = lm::minimize(
                &mut self.problem,
                &unmoved,
                &self.bounds,
                &self.base.settings,
            );
            if again.cost < r.cost || !r.cost.is_finite() {
                r = again;
            }
        }
        let delta = match r.cost.is_finite() {
            true => 2.0 * (r.cost - self.base.cost),
            false => f64::INFINITY,
        };
        let held = (0..r.x.len())
            .filter(|&o| at_edge(r.x[o], self.bounds[o]))
            .map(|o| if o < self.j { o } else { o + 1 })
            .collect();
        self.points.push(Point {
            at: v,
            delta,
            others: r.x,
            held,
        });
        self.points.last().expect("pushed")
    }

    /// The held constant's search-box bound on side `sign` (search coordinates).
    fn edge(&self, sign: f64) -> f64 {
        let (lo, hi) = self.base.box_bounds[self.j];
        if sign < 0.0 {
            lo
        } else {
            hi
        }
    }

    /// The check of the Wald interval on side `sign`: the profile at x̂ ± 2σ_x
    /// (within the box), and whether its rise agrees with the quadratic model's
    /// (δ/σ_x)²·s² to [`WALD_TOLERANCE`].
    fn check(&mut self, sx: f64, sign: f64) -> (Point, bool) {
        let xj = self.base.x[self.j];
        let (lo, hi) = self.base.box_bounds[self.j];
        let v = lm::project(xj + sign * CHECK_SIGMAS * sx, (lo, hi));
        let expected = ((v - xj) / sx).powi(2) * self.base.s2;
        let p = self.at(v).clone();
        let agrees = expected <= 0.0 || (p.delta / expected - 1.0).abs() <= WALD_TOLERANCE;
        (p, agrees)
    }

    /// The end of the profile interval on side `sign`, from the points profiled
    /// so far: where Δχ² = t²·s² ([`ROOT_TOLERANCE`]), by a secant on √Δχ² from
    /// the estimate outwards until it is bracketed, then inside the bracket (never
    /// within 5 % of its ends, so it shrinks); open when Δχ² at the search's bound
    /// is still below the level.
    fn end(&mut self, sign: f64) -> End {
        let xj = self.base.x[self.j];
        let edge = self.edge(sign);
        let dmax = (edge - xj).abs();
        let level = self.base.target.sqrt();
        let u = |p: &Point| p.delta.max(0.0).sqrt();
        let dist = |p: &Point| (p.at - xj) * sign;
        let mut br = Bracket {
            level,
            below: (0.0, 0.0),
            above: None,
        };
        for p in self.points.iter().filter(|p| dist(p) > 0.0) {
            br.add(dist(p), u(p));
        }
        let mut last = self.points.last().expect("the optimum").clone();
        for step in 0..MAX_ROOT_STEPS {
            if dist(&last) > 0.0 && (u(&last) - level).abs() <= ROOT_TOLERANCE * level {
                return End {
                    at: last.at,
                    open: false,
                    held: last.held,
                };
            }
            let d = match br.above {
                Some((db, _)) => {
                    let da = br.below.0;
                    let w = db - da;
                    br.crossing().clamp(da + 0.05 * w, db - 0.05 * w)
                }
                None if br.below.0 >= dmax => {
                    return End {
                        at: edge,
                        open: true,
                        held: last.held,
                    }
                }
                None => {
                    let (da, ua) = br.below;
                    let grow = if ua > 0.0 { level / ua } else { 4.0 };
                    match da > 0.0 && step + 1 < MAX_ROOT_STEPS {
                        true => (da * grow.clamp(1.1, 4.0)).min(dmax),
                        false => dmax,
                    }
                }
            };
            last = self.at(xj + sign * d).clone();
            br.add(d, u(&last));
        }
        match br.above {
            // the last bracket's interpolated crossing
            Some(_) => End {
                at: xj + sign * br.crossing(),
                open: false,
                held: last.held,
            },
            None => End {
                at: edge,
                open: true,
                held: last.held,
            },
        }
    }

    /// The `--profiles` grid: [`POINTS`] values over ±3σ_x (±2.3 in x, a factor 10
    /// for a log constant, without σ), within the box, profiled from the estimate
    /// outwards; the crossings of the 95 % level interpolated between grid points.
    fn grid(&mut self, sigma_x: Option<f64>) -> Profile {
        let c = self.base.problem.free[self.j].clone();
        let xj = self.base.x[self.j];
        let half = sigma_x
            .map(|s| 3.0 * s)
            .filter(|h| h.is_finite() && *h > 0.0)
            .unwrap_or(2.3);
        let bounds = self.base.box_bounds[self.j];
        let grid: Vec<f64> = (0..POINTS)
            .map(|i| xj - half + 2.0 * half * i as f64 / (POINTS - 1) as f64)
            .map(|v| lm::project(v, bounds))
            .collect();
        let mid = POINTS / 2;
        let mut delta = vec![0.0; POINTS];
        for i in (mid..POINTS).chain((0..mid).rev()) {
            delta[i] = self.at(grid[i]).delta.max(0.0);
        }
        let values: Vec<f64> = grid.iter().map(|&v| c.space.theta(v)).collect();
        let level = self.base.target;
        let cross = |range: Vec<usize>| {
            range.windows(2).find_map(|w| {
                let (a, b) = (w[0], w[1]);
                (delta[a] < level && delta[b] >= level && delta[b].is_finite()).then(|| {
                    let f = (level - delta[a]) / (delta[b] - delta[a]);
                    values[a] + f * (values[b] - values[a])
                })
            })
        };
        Profile {
            name: c.name.clone(),
            unit: c.unit.to_string(),
            interval: [
                cross((0..=mid).rev().collect()),
                cross((mid..POINTS).collect()),
            ],
            values,
            delta_chi2: delta,
            threshold: level,
        }
    }

    /// The profiled point of lowest Δχ² (the optimum excluded).
    fn lowest(&self) -> Option<Point> {
        self.points
            .iter()
            .skip(1)
            .min_by(|a, b| a.delta.total_cmp(&b.delta))
            .cloned()
    }
}
