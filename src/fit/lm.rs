//! Bounded Levenberg-Marquardt (Marquardt scaling, Nielsen's damping update,
//! active-set handling of box bounds), run by argmin's `Executor`.
//!
//! The algorithm is written here rather than taken from a crate because the
//! estimators need box bounds, analytic Jacobians supplied in place, variable
//! projection on top, and exact counts for the solver report; none of the Rust LM
//! crates offers all four. One iteration is [`Lm::step`]; argmin's `Executor` drives
//! it ([`search`]) and adds what a long search needs: observers (progress bar,
//! iteration trace: [`crate::observe`]), checkpoints to resume from, and a wall-time
//! limit. [`minimize`] is the same search without those (docs/architecture.md,
//! "argmin: what it bought, what it cost").

use crate::io::write::AtomicFile;
use argmin::core::checkpointing::{Checkpoint as Save, CheckpointingFrequency};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Executor, IterState, Problem, Solver, State, TerminationReason, KV};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// A nonlinear least-squares problem: minimise ½‖r(p)‖².
pub trait LeastSquares {
    /// (number of residuals, number of parameters).
    fn dims(&self) -> (usize, usize);
    /// Residuals into `r` and, if asked, the Jacobian ∂r/∂p into `jac`.
    /// Returns false when `p` is outside the model's domain or a value is not finite.
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool;
    /// Why the last [`LeastSquares::eval`] that returned false did, if the problem
    /// knows (a simulation that pulled in, a constant outside the model's domain);
    /// a search that cannot start reports it.
    fn failure(&self) -> Option<String> {
        None
    }
    /// Whether the first trial of each iteration should be evaluated with the
    /// Jacobian, which an accepted step then keeps instead of evaluating again at
    /// the same point: worth it when the Jacobian costs less than a second
    /// residual evaluation on top (a simulator with forward sensitivities: a trial
    /// and a re-run with them cost 1 + 3.5 runs, a trial with them 3.5, and most
    /// first trials are accepted). Later trials of an iteration, after a
    /// rejection, are evaluated without, and so is the first trial after an
    /// iteration whose step the linear model predicted poorly ([`TRUSTED_RHO`]).
    fn jacobian_with_trial(&self) -> bool {
        false
    }
    /// Told, before each iteration, the cost of the point the search stands on
    /// (its start, then every accepted step) and the cost another start of a
    /// multi-start reached ([`Control::reach`]), if any: a problem whose
    /// evaluations can be made cheaper for a search still far above that (a
    /// simulator run at a looser tolerance) chooses their accuracy from them. The
    /// trials of an iteration are evaluated alike.
    fn stands_at(&mut self, _cost: f64, _reference: Option<f64>) {}
    /// Whether, after an accepted step evaluated without the Jacobian, the search
    /// may take Broyden's secant update of its Jacobian
    /// J ← J + (Δr − J·Δx)·Δxᵀ / (Δxᵀ·Δx) (Madsen, Nielsen & Tingleff 2004, §3.4)
    /// instead of evaluating it: for a problem whose Jacobian is costly at points
    /// where its accuracy matters little (a far start of a multi-start, see
    /// [`LeastSquares::stands_at`]). The search evaluates the Jacobian before it
    /// relies on a secant one for more than the next step: before a stopping rule
    /// that reads the gradient or the step, and after a rejected trial (where the
    /// model may be what failed), the damping then unchanged.
    fn secant_jacobian(&self) -> bool {
        false
    }
    /// Whether the problem forms the Gauss-Newton normal equations JᵀJ and Jᵀr
    /// itself ([`LeastSquares::normal_equations`]) instead of the m × n Jacobian
    /// (whose products are all the search uses of it): from small Gram products of
    /// its own columns, without the passes over the data the tall Jacobian and
    /// its products take. The search then hands [`LeastSquares::eval`] an empty
    /// (0 × n) Jacobian as the request to form them, takes no secant updates, and
    /// returns an empty [`LmResult::jacobian`]; such a search cannot be
    /// checkpointed.
    fn forms_normal_equations(&self) -> bool {
        false
    }
    /// JᵀJ and Jᵀr of the last evaluation asked for a Jacobian, if it was at `p`
    /// (see [`LeastSquares::forms_normal_equations`]).
    fn normal_equations(&self, _p: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
        None
    }
}

/// Relative damping of the Gauss-Newton step of the noise-floor test
/// ([`LmSettings::min_decrease`]): enough to keep the normal equations of
/// constants the data do not pin down positive definite, far too little to shorten
/// the step along any direction the data see.
const GN_DAMPING: f64 = 1e-9;

/// Stopping rules.
#[derive(Debug, Clone, Copy)]
pub struct LmSettings {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Relative cost decrease below which the search stops.
    pub ftol: f64,
    /// Relative step below which the search stops.
    pub xtol: f64,
    /// Projected-gradient infinity norm (relative to the cost) below which it stops.
    pub gtol: f64,
    /// Absolute decrease of the cost below which a step is not worth taking: the
    /// search stops (converged, "noise floor") when the linear model predicts less
    /// for the Gauss-Newton step (damped by [`GN_DAMPING`] only), without
    /// evaluating it. 0 disables the test. For residuals
    /// scaled by their noise (cost = ½χ²) a value of 10⁻³ means no estimate can move
    /// by more than about √(2·10⁻³) ≈ 0.045 standard errors, while the trials below
    /// it only chase the simulator's integration noise in the cost.
    pub min_decrease: f64,
}

impl Default for LmSettings {
    fn default() -> Self {
        LmSettings {
            max_iterations: 200,
            ftol: 1e-12,
            xtol: 1e-10,
            gtol: 1e-12,
            min_decrease: 0.0,
        }
    }
}

/// Why a search stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum Termination {
    /// A convergence test passed (which one).
    Converged(&'static str),
    /// The iteration limit was reached.
    MaxIterations,
    /// The wall-time limit of [`Control::max_wall`] was reached; with a checkpoint
    /// the search can be resumed from where it stopped.
    WallTime,
    /// Given up: at its pace the search could not come within reach of the cost
    /// another start reached ([`Control::reach`]); why, in numbers.
    Abandoned(String),
    /// The start was outside the domain, the problem produced non-finite values, or
    /// the machinery around the search (trace, checkpoint) failed: why.
    Failed(String),
}

impl Termination {
    /// What a search that stopped this way falls short of, in words (None when it
    /// converged): the warning an estimator prints for it.
    pub fn shortfall(&self) -> Option<String> {
        match self {
            Termination::Converged(_) => None,
            Termination::MaxIterations => {
                Some("the search stopped at the iteration limit without converging".into())
            }
            Termination::WallTime => Some("the search stopped at its wall-time limit".into()),
            Termination::Abandoned(w) => Some(format!("the search was abandoned: {w}")),
            Termination::Failed(w) => Some(format!("the search failed: {w}")),
        }
    }
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Termination::Converged(w) => write!(f, "converged ({w})"),
            Termination::MaxIterations => f.write_str("iteration limit"),
            Termination::WallTime => f.write_str("wall-time limit"),
            Termination::Abandoned(w) => write!(f, "abandoned ({w})"),
            Termination::Failed(w) => write!(f, "failed: {w}"),
        }
    }
}

/// Result of one search.
#[derive(Debug, Clone)]
pub struct LmResult {
    /// Final parameters.
    pub x: Vec<f64>,
    /// ½‖r‖² at `x`.
    pub cost: f64,
    /// Iterations taken (accepted steps; across a resume, the total).
    pub iterations: usize,
    /// Residual evaluations (each with or without Jacobian; across a resume, the total).
    pub evaluations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// The residuals at `x` (empty when the search never evaluated there).
    pub residuals: DVector<f64>,
    /// The Jacobian at `x` (empty as the residuals are; after a failed
    /// evaluation not to be trusted, as `cost` is not). A search
    /// [`Termination::Abandoned`] or stopped by the wall time may leave a secant
    /// update here ([`LeastSquares::secant_jacobian`]); every other stop evaluates
    /// it. Empty (0 × n) for a problem that forms its normal equations itself
    /// ([`LeastSquares::forms_normal_equations`]).
    pub jacobian: DMatrix<f64>,
}

impl LmResult {
    /// The result of a search that could not start (why), at `x0`.
    fn unstarted(x0: &[f64], why: String) -> LmResult {
        LmResult {
            x: x0.to_vec(),
            cost: f64::INFINITY,
            iterations: 0,
            evaluations: 0,
            termination: Termination::Failed(why),
            residuals: DVector::zeros(0),
            jacobian: DMatrix::zeros(0, 0),
        }
    }
}

/// JᵀJ as `jac.tr_mul(&jac)` computes it (each entry nalgebra's dot of two
/// columns, which is symmetric in its operands bit for bit), each product below the
/// diagonal taken once and mirrored: half the passes over a tall Jacobian.
fn gram(jac: &DMatrix<f64>) -> DMatrix<f64> {
    let n = jac.ncols();
    let mut a = DMatrix::zeros(n, n);
    for j in 0..n {
        for i in j..n {
            let v = jac.column(i).dot(&jac.column(j));
            a[(i, j)] = v;
            a[(j, i)] = v;
        }
    }
    a
}

/// `v` moved into `[lo, hi]`. Unlike `f64::clamp` it never panics (NaN or inverted
/// bounds); [`minimize`] refuses such bounds before it projects anything.
pub fn project(v: f64, (lo, hi): (f64, f64)) -> f64 {
    v.max(lo).min(hi)
}

/// Why `x0` and `bounds` cannot start a search, if they cannot: one start value and
/// one (lo, hi) pair per parameter, a finite start, bounds not NaN with lo ≤ hi.
fn invalid_start(n: usize, x0: &[f64], bounds: &[(f64, f64)]) -> Option<String> {
    if x0.len() != n || bounds.len() != n {
        return Some(format!(
            "{} start values and {} bounds for {n} parameters",
            x0.len(),
            bounds.len()
        ));
    }
    if let Some(i) = (0..n).find(|&i| !x0[i].is_finite()) {
        return Some(format!("start value {i} is {}", x0[i]));
    }
    if let Some(&(lo, hi)) = bounds
        .iter()
        .find(|(lo, hi)| lo.is_nan() || hi.is_nan() || lo > hi)
    {
        return Some(format!("empty bounds [{lo}, {hi}]"));
    }
    None
}

/// The search between two iterations: everything a checkpoint holds. Settings are
/// not state: a resumed search takes the caller's (so it may be given more
/// iterations or time than the first run).
#[derive(Debug, Clone)]
pub struct Lm {
    settings: LmSettings,
    bounds: Vec<(f64, f64)>,
    x: Vec<f64>,
    r: DVector<f64>,
    jac: DMatrix<f64>,
    cost: f64,
    /// Damping relative to diag(JᵀJ) (Marquardt scaling), so dimensionless.
    mu: f64,
    /// Growth factor for `mu` while the damped system is singular.
    nu: f64,
    iterations: usize,
    evaluations: usize,
    /// The cost at the start and after each iteration (the pace of [`out_of_reach`]).
    costs: Vec<f64>,
    /// The Jacobian at the trial point, for [`LeastSquares::jacobian_with_trial`]
    /// (empty until first used; not part of a checkpoint).
    jac_trial: DMatrix<f64>,
    /// The residuals at the trial point (kept across iterations so that a step
    /// allocates nothing of the data's size; zeroed at each step as a fresh vector
    /// would be; not part of a checkpoint).
    r_trial: DVector<f64>,
    /// Whether the last iteration's first trial was accepted with ρ ≥
    /// [`TRUSTED_RHO`]: only then is the next first trial evaluated with the
    /// Jacobian ([`LeastSquares::jacobian_with_trial`]).
    trusted: bool,
    /// Whether `jac` is a secant update ([`LeastSquares::secant_jacobian`]), not
    /// an evaluation at `x`.
    secant: bool,
}

/// The agreement ρ of actual and predicted decrease above which a step's linear
/// model is trusted enough to evaluate the next trial with the Jacobian: where the
/// model is poor, trials land at far points, are rejected more often, and there
/// (a simulator at stiff corners of the constants) the Jacobian costs most.
pub const TRUSTED_RHO: f64 = 0.5;

/// Iterations over which [`out_of_reach`] measures a search's pace.
pub const PACE_WINDOW: usize = 5;
/// How much faster than its pace over the last [`PACE_WINDOW`] iterations a search
/// is allowed to close the gap before it is given up ([`out_of_reach`]).
pub const PACE_ALLOWANCE: f64 = 2.0;

/// The cost another start of a multi-start reached, and the margin above it
/// within which a search is never given up ([`out_of_reach`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// The reference cost.
    pub cost: f64,
    /// The margin (cost units), beyond the difference of two stops in one
    /// minimum.
    pub margin: f64,
}

/// Why a search whose costs so far are `costs` (the start's, then one per
/// iteration) cannot come within reach of `reach` in the `left` iterations it
/// has: its cost lies above the reference + its margin + 2·`floor` (the noise
/// floor, [`LmSettings::min_decrease`]) by a gap that even [`PACE_ALLOWANCE`]
/// times its mean decrease over the last [`PACE_WINDOW`] iterations, kept up for
/// all of them, would not close. None while it can.
pub fn out_of_reach(costs: &[f64], reach: Reach, floor: f64, left: usize) -> Option<String> {
    let k = costs.len().checked_sub(1)?;
    let reference = reach.cost;
    if k < PACE_WINDOW || !reference.is_finite() {
        return None;
    }
    let now = costs[k];
    let gap = now - (reference + reach.margin + 2.0 * floor);
    let pace = (costs[k - PACE_WINDOW] - now) / PACE_WINDOW as f64;
    (gap > PACE_ALLOWANCE * pace * left as f64).then(|| {
        format!(
            "after {k} iterations the cost {now:.6} is {:.4} above the best start's {reference:.6} and falls by {pace:.3e} per iteration, with {left} iterations left",
            now - reference
        )
    })
}

/// Smallest and largest factor by which a rejected trial's step is shrunk for the
/// next one (Moré 1978, §5: the trust radius falls to between 1/10 and 1/2 of the
/// rejected step).
const SHRINK_RANGE: (f64, f64) = (0.1, 0.5);

/// The factor by which to shrink a rejected step δ (Moré 1978, §5): the minimiser
/// t* = −d / (2(f₁ − f₀ − d)) of the parabola through the cost f₀ at t = 0 with
/// slope d = gᵀδ and the trial's cost f₁ at t = 1, within [`SHRINK_RANGE`]; the
/// smallest factor when the trial could not be evaluated (`ok` false or f₁ not
/// finite) or the parabola has no minimum inside.
fn rejected_shrink(ok: bool, f0: f64, f1: f64, d: f64) -> f64 {
    let (lo, hi) = SHRINK_RANGE;
    let curvature = f1 - f0 - d;
    if !(ok && f1.is_finite() && d < 0.0 && curvature > 0.0) {
        return lo;
    }
    let t = -d / (2.0 * curvature);
    if t.is_finite() {
        t.clamp(lo, hi)
    } else {
        lo
    }
}

/// ‖D·δ‖ with D² = diag(JᵀJ): the step length in the scale the damping μ·diag(JᵀJ)
/// works in (Marquardt 1963).
fn scaled_norm(a: &DMatrix<f64>, step: &DVector<f64>) -> f64 {
    step.iter()
        .enumerate()
        .map(|(i, s)| a[(i, i)] * s * s)
        .sum::<f64>()
        .sqrt()
}

/// Broyden's rank-one secant update J ← J + (Δr − J·Δx)·Δxᵀ / (Δxᵀ·Δx) (Broyden
/// 1965; in LM, Madsen, Nielsen & Tingleff 2004, §3.4): the least change to J that
/// maps the step `dx` onto the residuals' change `dr`. A zero step leaves J as is.
fn broyden(jac: &mut DMatrix<f64>, dx: &DVector<f64>, dr: &DVector<f64>) {
    let dd = dx.norm_squared();
    if dd <= 0.0 || !dd.is_finite() {
        return;
    }
    let u = (dr - &*jac * dx) / dd;
    jac.ger(1.0, &u, dx, 1.0);
}

/// The damping for the next trial after a rejection at `mu`: doubled (at least
/// once) until the damped step's scaled norm, given by `norm` (None where the
/// system is singular), is at most `target`. Solving the small normal equations
/// again costs microseconds; each trial the doubling saves is an evaluation of the
/// problem (for identification a simulator run). Beyond 10³⁰⁰ there is nothing
/// left to try: the caller stops.
fn damping_for(mu: f64, target: f64, norm: impl Fn(f64) -> Option<f64>) -> f64 {
    let mut mu = 2.0 * mu;
    while mu.is_finite() && mu <= 1e300 {
        match norm(mu) {
            Some(s) if s <= target => return mu,
            _ => mu *= 2.0,
        }
    }
    mu
}

impl Lm {
    /// Project `x0` into `bounds` and evaluate there (one evaluation, with Jacobian;
    /// none when `known` holds them for x0, see [`Control::known_start`]). A start or bounds that cannot be used (see [`invalid_start`]) or a start
    /// where the problem is not finite give the failed result instead.
    fn start<P: LeastSquares + ?Sized>(
        problem: &mut P,
        x0: &[f64],
        bounds: &[(f64, f64)],
        settings: &LmSettings,
        known: Option<(DVector<f64>, DMatrix<f64>)>,
    ) -> Result<Lm, Box<LmResult>> {
        let (m, n) = problem.dims();
        if let Some(why) = invalid_start(n, x0, bounds) {
            return Err(Box::new(LmResult::unstarted(x0, why)));
        }
        let mut lm = Lm {
            settings: *settings,
            bounds: bounds.to_vec(),
            x: x0
                .iter()
                .zip(bounds)
                .map(|(&v, &b)| project(v, b))
                .collect(),
            r: DVector::zeros(m),
            jac: DMatrix::zeros(
                if problem.forms_normal_equations() {
                    0
                } else {
                    m
                },
                n,
            ),
            cost: f64::INFINITY,
            mu: 1e-3,
            nu: 2.0,
            iterations: 0,
            evaluations: 1,
            costs: Vec::new(),
            jac_trial: DMatrix::zeros(0, 0),
            r_trial: DVector::zeros(0),
            trusted: true,
            secant: false,
        };
        // residuals and Jacobian the caller has at x0 (inside the bounds, finite)
        let known = known.filter(|(r, j)| {
            r.len() == m
                && j.shape() == (m, n)
                && lm.x.as_slice() == x0
                && r.iter().chain(j.iter()).all(|v| v.is_finite())
        });
        match known {
            Some((r, j)) => {
                (lm.r, lm.jac, lm.evaluations) = (r, j, 0);
            }
            None => {
                if !problem.eval(&lm.x, &mut lm.r, Some(&mut lm.jac)) {
                    let why = problem.failure().unwrap_or_else(|| "not finite".into());
                    return Err(Box::new(
                        lm.finish(Termination::Failed(format!("at the start: {why}"))),
                    ));
                }
            }
        }
        lm.cost = 0.5 * lm.r.norm_squared();
        lm.costs.push(lm.cost);
        Ok(lm)
    }

    /// One iteration: the damped Gauss-Newton step
    /// (JᵀJ + μ·diag(JᵀJ)) δ = −Jᵀr over the free variables (Marquardt 1963),
    /// projected onto the bounds, tried until the cost decreases (then μ shrinks by
    /// max(1/3, 1 − (2ρ − 1)³) with ρ the actual over the predicted decrease, Nielsen
    /// 1999; after a rejected trial μ grows until the step has shrunk as
    /// [`rejected_shrink`] says, see [`damping_for`]) or a stopping rule holds. Variables at a bound whose gradient pushes
    /// outward are held (active set). None while the search goes on.
    pub fn step<P: LeastSquares + ?Sized>(&mut self, problem: &mut P) -> Option<Termination> {
        if self.iterations >= self.settings.max_iterations {
            return self.exact(problem).or(Some(Termination::MaxIterations));
        }
        let n = self.x.len();
        let (a, g) = match self.normal_equations(&*problem) {
            Ok(ag) => ag,
            Err(stop) => return Some(stop),
        };
        let (x, bounds, settings) = (&mut self.x, &self.bounds, &self.settings);
        if !(a.iter().all(|v| v.is_finite()) && g.iter().all(|v| v.is_finite())) {
            return Some(Termination::Failed(
                "the normal equations overflowed".into(),
            ));
        }
        let mut free = vec![true; n];
        for i in 0..n {
            let (lo, hi) = bounds[i];
            if (x[i] <= lo && g[i] > 0.0) || (x[i] >= hi && g[i] < 0.0) {
                free[i] = false;
            }
        }
        let gnorm = (0..n)
            .filter(|&i| free[i])
            .map(|i| g[i].abs())
            .fold(0.0, f64::max);
        if gnorm <= settings.gtol * (1.0 + self.cost) {
            return self.stop_unless_secant(problem, Termination::Converged("gradient"));
        }
        // Damped normal equations over the free variables (held ones fixed at 0).
        let normal = |mu: f64| {
            let mut sys = a.clone();
            let mut rhs = -&g;
            for i in 0..n {
                if free[i] {
                    sys[(i, i)] += mu * a[(i, i)].max(1e-12 * (1.0 + a[(i, i)]));
                } else {
                    for j in 0..n {
                        sys[(i, j)] = 0.0;
                        sys[(j, i)] = 0.0;
                    }
                    sys[(i, i)] = 1.0;
                    rhs[i] = 0.0;
                }
            }
            sys.cholesky().map(|c| c.solve(&rhs))
        };
        // The noise floor: even the (barely damped) Gauss-Newton step predicts a
        // decrease ½·gᵀ·δ below `min_decrease`. The damped step's own prediction
        // would not do: in a long curved valley it is small at every iteration
        // while the full step still sees the valley's floor far below.
        if settings.min_decrease > 0.0 {
            if let Some(gn) = normal(GN_DAMPING) {
                if -0.5 * g.dot(&gn) < settings.min_decrease {
                    return self.stop_unless_secant(problem, Termination::Converged("noise floor"));
                }
            }
        }
        let mut x_new = vec![0.0; n];
        if self.r_trial.len() == self.r.len() {
            self.r_trial.fill(0.0);
        } else {
            self.r_trial = DVector::zeros(self.r.len());
        }
        let r_new = &mut self.r_trial;
        let mut trial_jac = self.trusted && problem.jacobian_with_trial();
        let mut first = true;
        if trial_jac && self.jac_trial.shape() != self.jac.shape() {
            self.jac_trial = DMatrix::zeros(self.jac.nrows(), n);
        }
        loop {
            let Some(step) = normal(self.mu) else {
                self.mu *= self.nu;
                self.nu *= 2.0;
                if !self.mu.is_finite() || self.mu > 1e300 {
                    return Some(Termination::Failed("singular system".into()));
                }
                continue;
            };
            for i in 0..n {
                x_new[i] = project(x[i] + step[i], bounds[i]);
            }
            let dx = DVector::from_fn(n, |i, _| x_new[i] - x[i]);
            let dx_norm = dx.iter().map(|d| d * d).sum::<f64>().sqrt();
            let x_norm = x.iter().map(|d| d * d).sum::<f64>().sqrt();
            if dx_norm <= settings.xtol * (x_norm + settings.xtol) {
                return self.stop_unless_secant(problem, Termination::Converged("step"));
            }
            // Predicted decrease of the linear model for the (projected) step.
            let pred = -(g.dot(&dx)) - 0.5 * (&a * &dx).dot(&dx);
            // A step the projection onto the bounds turned uphill even in the linear
            // model (pred ≤ 0) cannot be accepted (that needs ρ > 0): it is rejected
            // without evaluating the problem there.
            // How far the rejected step is shrunk for the next trial (½ when the
            // projection made it useless, see below).
            let mut shrink = 0.5;
            if pred > 0.0 {
                self.evaluations += 1;
                let ok = match trial_jac {
                    true => problem.eval(&x_new, r_new, Some(&mut self.jac_trial)),
                    false => problem.eval(&x_new, r_new, None),
                };
                let cost_new = 0.5 * r_new.norm_squared();
                if ok && cost_new < self.cost {
                    let rho = (self.cost - cost_new) / pred;
                    let rel = (self.cost - cost_new) / self.cost.max(f64::MIN_POSITIVE);
                    x.copy_from_slice(&x_new);
                    self.secant = !trial_jac
                        && problem.secant_jacobian()
                        && !problem.forms_normal_equations();
                    if trial_jac {
                        std::mem::swap(&mut self.r, r_new);
                        std::mem::swap(&mut self.jac, &mut self.jac_trial);
                    } else if self.secant {
                        broyden(&mut self.jac, &dx, &(&*r_new - &self.r));
                        std::mem::swap(&mut self.r, r_new);
                    } else {
                        self.evaluations += 1;
                        problem.eval(x, &mut self.r, Some(&mut self.jac));
                    }
                    self.cost = cost_new;
                    self.costs.push(cost_new);
                    self.trusted = first && rho >= TRUSTED_RHO;
                    self.mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                    self.nu = 2.0;
                    self.iterations += 1;
                    return (rel <= settings.ftol).then_some(Termination::Converged("cost"));
                }
                shrink = rejected_shrink(ok, self.cost, cost_new, g.dot(&dx));
            }
            if self.secant {
                // the model the step came from was a secant one: evaluate it and
                // try again at the same damping
                return self.exact(problem);
            }
            trial_jac = false;
            first = false;
            let target = shrink * scaled_norm(&a, &step);
            self.mu = damping_for(self.mu, target, |mu| {
                normal(mu).map(|s| scaled_norm(&a, &s))
            });
            if !self.mu.is_finite() || self.mu > 1e300 {
                return Some(Termination::Converged("no further decrease"));
            }
        }
    }

    /// JᵀJ and Jᵀr at `x`: from the Jacobian, or the problem's own
    /// ([`LeastSquares::forms_normal_equations`]: every point the search stands on
    /// was evaluated with them last). Err: the problem has none for `x`.
    fn normal_equations<P: LeastSquares + ?Sized>(
        &self,
        problem: &P,
    ) -> Result<(DMatrix<f64>, DVector<f64>), Termination> {
        if !problem.forms_normal_equations() {
            return Ok((gram(&self.jac), self.jac.tr_mul(&self.r)));
        }
        problem.normal_equations(&self.x).ok_or_else(|| {
            Termination::Failed(
                "the problem formed no normal equations at the current point".into(),
            )
        })
    }

    /// A stopping rule that read the Jacobian (gradient, noise floor, step) holds:
    /// stop with `rule`, unless the Jacobian is a secant update, which is then
    /// evaluated and the search goes on (the next iteration tests the rule again
    /// on the exact one).
    fn stop_unless_secant<P: LeastSquares + ?Sized>(
        &mut self,
        problem: &mut P,
        rule: Termination,
    ) -> Option<Termination> {
        match self.secant {
            true => self.exact(problem),
            false => Some(rule),
        }
    }

    /// Evaluate the Jacobian at `x` where it is a secant update (None: the search
    /// goes on; the failure where the evaluation fails).
    fn exact<P: LeastSquares + ?Sized>(&mut self, problem: &mut P) -> Option<Termination> {
        if !self.secant {
            return None;
        }
        self.secant = false;
        self.evaluations += 1;
        if problem.eval(&self.x, &mut self.r, Some(&mut self.jac)) {
            return None;
        }
        let why = problem.failure().unwrap_or_else(|| "not finite".into());
        Some(Termination::Failed(format!(
            "the Jacobian at an accepted point: {why}"
        )))
    }

    /// The result as it stands, stopped for `termination`.
    fn finish(self, termination: Termination) -> LmResult {
        LmResult {
            x: self.x,
            cost: self.cost,
            iterations: self.iterations,
            evaluations: self.evaluations,
            termination,
            residuals: self.r,
            jacobian: self.jac,
        }
    }

    /// What observers see after each iteration besides the parameters and the cost.
    fn kv(&self) -> KV {
        let mut kv = KV::new();
        kv.insert("iteration", (self.iterations as u64).into());
        kv.insert("evaluations", (self.evaluations as u64).into());
        kv.insert("damping", self.mu.into());
        kv
    }

    /// The argmin state matching this search: parameters, cost and the iteration
    /// count (which tells the `Executor` whether the search is starting or resuming).
    fn state(&self) -> LmState {
        let mut state = LmState::new().param(self.x.clone()).cost(self.cost);
        for _ in 0..self.iterations {
            state.increment_iter();
        }
        state
    }
}

/// The argmin state the LM reports to observers (`get_param`, `get_cost`,
/// `get_iter`); the key-value pairs beside it hold `iteration` (accepted steps so
/// far), `evaluations` and `damping` (μ).
pub type LmState = IterState<Vec<f64>, (), (), (), (), f64>;

/// The LM as an argmin [`Solver`]: each `next_iter` is one [`Lm::step`].
struct LmSolver<'s> {
    lm: &'s mut Lm,
    /// [`Control::reach`].
    reach: Option<Reach>,
    /// [`Control::label`].
    label: Option<String>,
    stopped: Option<Termination>,
    /// Whether anyone reads the key-value pairs (they cost a few allocations).
    observed: bool,
}

/// The problem as argmin holds it.
struct Held<'p, P: ?Sized>(&'p mut P);

impl LmSolver<'_> {
    /// What the observers are told: the search's pairs and its label.
    fn kv(&self) -> KV {
        let mut kv = self.lm.kv();
        if let Some(l) = &self.label {
            kv.insert("label", l.clone().into());
        }
        kv
    }
}

impl<P: LeastSquares + ?Sized> Solver<Held<'_, P>, LmState> for LmSolver<'_> {
    fn name(&self) -> &str {
        "bounded Levenberg-Marquardt"
    }

    fn init(
        &mut self,
        _problem: &mut Problem<Held<'_, P>>,
        state: LmState,
    ) -> Result<(LmState, Option<KV>), argmin::core::Error> {
        Ok((state, self.observed.then(|| self.kv())))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<Held<'_, P>>,
        state: LmState,
    ) -> Result<(LmState, Option<KV>), argmin::core::Error> {
        let Some(Held(p)) = problem.problem.as_mut() else {
            return Err(argmin::core::Error::msg("the executor lost the problem"));
        };
        let lm = &mut *self.lm;
        p.stands_at(lm.cost, self.reach.map(|r| r.cost));
        let stop = lm.step(*p).or_else(|| {
            let left = lm.settings.max_iterations.saturating_sub(lm.iterations);
            out_of_reach(&lm.costs, self.reach?, lm.settings.min_decrease, left)
                .map(Termination::Abandoned)
        });
        let state = state.param(self.lm.x.clone()).cost(self.lm.cost);
        let state = match &stop {
            None => state,
            Some(Termination::Converged(_)) => {
                state.terminate_with(TerminationReason::SolverConverged)
            }
            Some(t) => state.terminate_with(TerminationReason::SolverExit(t.to_string())),
        };
        self.stopped = stop;
        Ok((state, self.observed.then(|| self.kv())))
    }
}

/// Where and how often a search saves itself, and what problem it belongs to.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    /// The checkpoint file (JSON, written by the house's write policy
    /// ([`crate::io::write`]): a temporary file beside it renamed over it; the
    /// first save of a search that did not resume from it keeps a different file
    /// already there aside as `<stem>.previous-<n>.<ext>`).
    pub file: PathBuf,
    /// Save after every this many iterations (≥ 1); a search stopped by the wall
    /// time saves at once whatever the cadence.
    pub every: u64,
    /// What defines the problem the search belongs to, part by part: (name, value
    /// or digest), from the caller (identification: the tool version, each trace's
    /// data, the scene, the free set, the constants, the settings that move the
    /// optimum, the start; `crate::identify::checkpoint`). Saved in the file; a
    /// file whose parts differ is refused, naming them. Empty: only the sizes and
    /// bounds are checked.
    pub problem: Vec<(String, String)>,
}

impl Checkpoint {
    /// The checkpoint of start `i` of a multi-start: `FILE.i`.
    pub fn for_start(&self, i: usize) -> Checkpoint {
        let mut name = self.file.clone().into_os_string();
        name.push(format!(".{i}"));
        Checkpoint {
            file: name.into(),
            every: self.every,
            problem: self.problem.clone(),
        }
    }

    /// Whether a search of a problem with `dims` (residuals, parameters), `bounds`
    /// and this checkpoint's [`Checkpoint::problem`] could resume from the file:
    /// the reason when not (not a checkpoint, damaged or edited, of another
    /// format, or written for another problem).
    pub fn check(&self, dims: (usize, usize), bounds: &[(f64, f64)]) -> Result<(), String> {
        load(self, dims, bounds).map(|_| ())
    }
}

/// An argmin observer of the LM, boxed ([`crate::observe`] has the house's).
pub type Observer = Box<dyn Observe<LmState>>;

/// What runs around a [`search`]: observers, checkpointing, resume, wall time.
#[derive(Default)]
pub struct Control {
    /// Told of the start, every iteration and the end; a search takes them (argmin
    /// owns its observers), so a [`Control`] serves one search.
    pub observers: Vec<Observer>,
    /// Save the search to resume it later.
    pub checkpoint: Option<Checkpoint>,
    /// Continue from the checkpoint file if it exists (else start afresh). Without
    /// this an existing checkpoint file is never read: the search's first save
    /// keeps it aside ([`Checkpoint::file`]).
    pub resume: bool,
    /// Stop with [`Termination::WallTime`] once an iteration ends past this time.
    pub max_wall: Option<Duration>,
    /// The residuals and Jacobian at the start when the caller has them (a polish
    /// from another search's optimum after a change of weights): the search then
    /// does not evaluate there. Ignored when resuming from a checkpoint, and when
    /// their shapes are not the problem's.
    pub known_start: Option<(DVector<f64>, DMatrix<f64>)>,
    /// The cost another start of a multi-start reached: stop with
    /// [`Termination::Abandoned`] once this search cannot come within reach of it
    /// ([`out_of_reach`]).
    pub reach: Option<Reach>,
    /// What the search is of, for its observers (the key `label` of their
    /// key-value pairs): a candidate model, a reduction round.
    pub label: Option<String>,
}

/// Minimise ½‖r(p)‖² from `x0` within `bounds`: [`search`] without observers,
/// checkpoints or time limit.
pub fn minimize<P: LeastSquares + ?Sized>(
    problem: &mut P,
    x0: &[f64],
    bounds: &[(f64, f64)],
    settings: &LmSettings,
) -> LmResult {
    search(problem, x0, bounds, settings, &mut Control::default())
}

/// Minimise ½‖r(p)‖² from `x0` within `bounds` (or from the checkpoint when
/// `control.resume` and its file exists), through argmin's `Executor` with the
/// observers, checkpointing and wall-time limit of `control`. A resumed search gives
/// the same result, iterations and evaluations (totals) as one never interrupted.
/// A start or bounds that cannot be used end the search at once as
/// [`Termination::Failed`], and so does a checkpoint written for another problem.
pub fn search<P: LeastSquares + ?Sized>(
    problem: &mut P,
    x0: &[f64],
    bounds: &[(f64, f64)],
    settings: &LmSettings,
    control: &mut Control,
) -> LmResult {
    let resumed = match (&control.checkpoint, control.resume) {
        (Some(c), true) if c.file.exists() => Some(load(c, problem.dims(), bounds)),
        _ => None,
    };
    let fresh = resumed.is_none();
    let mut lm = match resumed {
        Some(Ok(mut lm)) => {
            lm.settings = *settings;
            lm
        }
        Some(Err(why)) => return LmResult::unstarted(x0, why),
        None => match Lm::start(problem, x0, bounds, settings, control.known_start.take()) {
            Ok(lm) => lm,
            Err(failed) => return *failed,
        },
    };
    // a search that did not resume from the file keeps what is there aside at its
    // first save; later saves (and a resumed search's) replace its own state
    let keep = Arc::new(AtomicBool::new(fresh));
    let state = lm.state();
    let mut executor = Executor::new(
        Held(problem),
        LmSolver {
            lm: &mut lm,
            reach: control.reach,
            label: control.label.clone(),
            stopped: None,
            observed: !control.observers.is_empty(),
        },
    )
    .configure(|_| state)
    .ctrlc(false);
    for observer in control.observers.drain(..) {
        executor = executor.add_observer(Forward(observer), ObserverMode::Always);
    }
    if let Some(c) = &control.checkpoint {
        executor = executor.checkpointing(FileCheckpoint(c.clone(), keep.clone()));
    }
    if let Some(limit) = control.max_wall {
        executor = executor.timeout(limit);
    }
    let run = executor.run();
    let termination = match run {
        Err(e) => Termination::Failed(format!("{e:#}")),
        Ok(done) => match done.solver.stopped {
            Some(t) => t,
            None if done.state.get_termination_reason() == Some(&TerminationReason::Timeout) => {
                Termination::WallTime
            }
            None => Termination::Failed(format!(
                "the executor stopped the search: {}",
                done.state.get_termination_status()
            )),
        },
    };
    if let (Termination::WallTime, Some(c)) = (&termination, &control.checkpoint) {
        if let Err(e) = save(c, &lm, &keep) {
            return lm.finish(Termination::Failed(e));
        }
    }
    lm.finish(termination)
}

/// Forwards argmin's calls to a boxed observer (argmin takes observers by value).
struct Forward(Observer);

impl Observe<LmState> for Forward {
    fn observe_init(
        &mut self,
        name: &str,
        state: &LmState,
        kv: &KV,
    ) -> Result<(), argmin::core::Error> {
        self.0.observe_init(name, state, kv)
    }
    fn observe_iter(&mut self, state: &LmState, kv: &KV) -> Result<(), argmin::core::Error> {
        self.0.observe_iter(state, kv)
    }
    fn observe_final(&mut self, state: &LmState) -> Result<(), argmin::core::Error> {
        self.0.observe_final(state)
    }
}

/// argmin's checkpointing hook for the LM: saves [`Lm`] as [`Saved`] (the flag:
/// whether the next save keeps a different file aside, see [`save`]). Loading is
/// done by [`search`] itself (it must give the caller's settings to the loaded
/// search and check the file belongs to the problem).
struct FileCheckpoint(Checkpoint, Arc<AtomicBool>);

impl<'s> Save<LmSolver<'s>, LmState> for FileCheckpoint {
    /// A search the solver has stopped is not saved: resuming repeats its last
    /// iteration, which stops it the same way.
    fn save(&self, solver: &LmSolver<'s>, _state: &LmState) -> Result<(), argmin::core::Error> {
        if solver.stopped.is_some() {
            return Ok(());
        }
        save(&self.0, solver.lm, &self.1).map_err(argmin::core::Error::msg)
    }
    fn load(&self) -> Result<Option<(LmSolver<'s>, LmState)>, argmin::core::Error> {
        Ok(None)
    }
    fn frequency(&self) -> CheckpointingFrequency {
        CheckpointingFrequency::Every(self.0.every.max(1))
    }
}

/// The checkpoint file's content. Every f64 is kept as its bit pattern: JSON has no
/// infinity (unbounded parameters) and a decimal round trip is not guaranteed exact,
/// while a resumed search must continue bit for bit.
#[derive(Serialize, Deserialize)]
struct Saved {
    format: String,
    /// [`Checkpoint::problem`] of the search that wrote it.
    problem: Vec<(String, String)>,
    residuals: usize,
    bounds: Vec<(u64, u64)>,
    x: Vec<u64>,
    r: Vec<u64>,
    jac: Vec<u64>,
    cost: u64,
    mu: u64,
    nu: u64,
    iterations: usize,
    evaluations: usize,
    /// The costs so far (the pace of [`out_of_reach`]).
    costs: Vec<u64>,
    /// [`Lm::trusted`].
    trusted: bool,
    /// [`Lm::secant`].
    secant: bool,
    /// sha256 of the file's JSON written with this field empty ([`Saved::digest`]):
    /// a damaged or edited file is refused, not resumed.
    digest: String,
}

impl Saved {
    /// The sha256 (hex) of `self` serialised with an empty `digest`.
    fn digest(&mut self) -> String {
        let kept = std::mem::take(&mut self.digest);
        let text = serde_json::to_string(self).expect("a checkpoint serialises");
        self.digest = kept;
        crate::io::sha256_hex(text.as_bytes())
    }
}

/// The first lines every version of the file has: its format.
#[derive(Deserialize)]
struct Head {
    format: String,
}

/// The `format` of a checkpoint file this version reads (2: the problem's parts
/// and the digest; a file of format 1 carries neither and is refused).
const FORMAT: &str = "dea-fit lm checkpoint 2";

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn unbits(v: &[u64]) -> Vec<f64> {
    v.iter().map(|&b| f64::from_bits(b)).collect()
}

/// Write `lm` to the checkpoint's file by the write policy: a temporary file
/// beside it renamed over it (a search killed while saving leaves the previous
/// checkpoint whole). While `keep` is set (a search's first save, unless it
/// resumed from the file), a different file already there is kept aside as
/// `<stem>.previous-<n>.<ext>` ([`AtomicFile::commit_keeping`]) instead of
/// replaced; later saves replace the search's own state.
fn save(c: &Checkpoint, lm: &Lm, keep: &AtomicBool) -> Result<(), String> {
    let mut saved = Saved {
        format: FORMAT.into(),
        problem: c.problem.clone(),
        residuals: lm.r.len(),
        bounds: lm
            .bounds
            .iter()
            .map(|(lo, hi)| (lo.to_bits(), hi.to_bits()))
            .collect(),
        x: bits(&lm.x),
        r: bits(lm.r.as_slice()),
        jac: bits(lm.jac.as_slice()),
        cost: lm.cost.to_bits(),
        mu: lm.mu.to_bits(),
        nu: lm.nu.to_bits(),
        iterations: lm.iterations,
        evaluations: lm.evaluations,
        costs: bits(&lm.costs),
        trusted: lm.trusted,
        secant: lm.secant,
        digest: String::new(),
    };
    saved.digest = saved.digest();
    let text = serde_json::to_string(&saved).map_err(|e| e.to_string())?;
    let written = (|| {
        let mut f = AtomicFile::create(&c.file)?;
        f.write_all(text.as_bytes())
            .map_err(|e| crate::Error::io(&c.file, e))?;
        match keep.load(Ordering::Relaxed) {
            true => f.commit_keeping().map(|_| ()),
            false => f.commit(),
        }
    })();
    written.map_err(|e| format!("cannot write the checkpoint {}: {e}", c.file.display()))?;
    keep.store(false, Ordering::Relaxed);
    Ok(())
}

/// The parts of `here` that `saved` does not have alike, in words: a short value
/// (the tool version, the start) in full, a digest by its first 12 digits.
fn differing(saved: &[(String, String)], here: &[(String, String)]) -> Vec<String> {
    let short = |v: &str| match v.len() > 24 {
        true => format!("{}…", &v[..12.min(v.len())]),
        false => v.to_string(),
    };
    let mut out: Vec<String> = here
        .iter()
        .filter_map(|(name, v)| match saved.iter().find(|(n, _)| n == name) {
            Some((_, s)) if s == v => None,
            Some((_, s)) => Some(format!(
                "{name} ({} in the file, {} here)",
                short(s),
                short(v)
            )),
            None => Some(format!("{name} (absent in the file)")),
        })
        .collect();
    out.extend(
        saved
            .iter()
            .filter(|(n, _)| !here.iter().any(|(h, _)| h == n))
            .map(|(n, _)| format!("{n} (not part of this problem)")),
    );
    out
}

/// Read the checkpoint `c` of a problem with `dims` (residuals, parameters) and
/// `bounds`; a file that is not a whole checkpoint of this format (damaged,
/// truncated, edited: its digest), or one written for another problem
/// ([`Checkpoint::problem`], sizes, bounds), is refused with the reason.
fn load(c: &Checkpoint, (m, n): (usize, usize), bounds: &[(f64, f64)]) -> Result<Lm, String> {
    let file = &c.file;
    let what = |e: String| format!("checkpoint {}: {e}", file.display());
    let text = std::fs::read_to_string(file).map_err(|e| what(e.to_string()))?;
    let damaged = |e: serde_json::Error| {
        what(format!(
            "not a whole checkpoint file (damaged or truncated?): {e}"
        ))
    };
    let head: Head = serde_json::from_str(&text).map_err(damaged)?;
    if head.format != FORMAT {
        return Err(what(format!(
            "format {:?}, expected {FORMAT:?} (written by another version of dea-fit)",
            head.format
        )));
    }
    let mut s: Saved = serde_json::from_str(&text).map_err(damaged)?;
    if s.digest() != s.digest {
        return Err(what(
            "its content does not match its digest: the file was damaged or edited".into(),
        ));
    }
    let other = differing(&s.problem, &c.problem);
    if !other.is_empty() {
        return Err(what(format!(
            "written for another problem: {} differ{}",
            other.join(", "),
            if other.len() == 1 { "s" } else { "" }
        )));
    }
    let same_bounds = s.bounds.len() == bounds.len()
        && s.bounds
            .iter()
            .zip(bounds)
            .all(|(&(a, b), &(lo, hi))| a == lo.to_bits() && b == hi.to_bits());
    if s.residuals != m || s.x.len() != n || !same_bounds {
        return Err(what(format!(
            "written for a problem with {} residuals, {} parameters and other bounds or \
             these; this one has {m} residuals and {n} parameters",
            s.residuals,
            s.x.len()
        )));
    }
    if s.r.len() != m || s.jac.len() != m.saturating_mul(n) {
        return Err(what("residuals or Jacobian of the wrong size".into()));
    }
    let x = unbits(&s.x);
    let finite = |v: &[u64]| v.iter().all(|&b| f64::from_bits(b).is_finite());
    let (cost, mu, nu) = (
        f64::from_bits(s.cost),
        f64::from_bits(s.mu),
        f64::from_bits(s.nu),
    );
    if x.iter().zip(bounds).any(|(&v, &b)| project(v, b) != v)
        || !(finite(&s.x) && finite(&s.r) && finite(&s.jac) && finite(&s.costs))
        || !(cost.is_finite() && mu > 0.0 && mu.is_finite() && nu > 0.0 && nu.is_finite())
        || s.costs.len() > s.iterations.saturating_add(1)
    {
        return Err(what(
            "a value outside its domain (a parameter outside its bounds, a non-finite number)"
                .into(),
        ));
    }
    Ok(Lm {
        settings: LmSettings::default(),
        bounds: bounds.to_vec(),
        x,
        r: DVector::from_vec(unbits(&s.r)),
        jac: DMatrix::from_vec(m, n, unbits(&s.jac)),
        cost,
        mu,
        nu,
        iterations: s.iterations,
        evaluations: s.evaluations,
        costs: unbits(&s.costs),
        jac_trial: DMatrix::zeros(0, 0),
        r_trial: DVector::zeros(0),
        trusted: s.trusted,
        secant: s.secant,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`gram`] is `tr_mul` of the Jacobian with itself, bit for bit, on tall
    /// matrices of several widths (odd lengths included).
    #[test]
    fn gram_is_tr_mul_bit_for_bit() {
        for (m, n) in [(1, 1), (7, 3), (200, 9), (333, 5)] {
            let jac = DMatrix::from_fn(m, n, |i, j| {
                ((3 * i + 11 * j) as f64 * 0.7).sin() * (1.0 + j as f64)
            });
            let want = jac.tr_mul(&jac);
            let got = gram(&jac);
            for (g, w) in got.iter().zip(want.iter()) {
                assert_eq!(g.to_bits(), w.to_bits(), "{m} × {n}");
            }
        }
    }

    /// Rosenbrock as least squares: r = (10(y − x²), 1 − x).
    struct Rosen;
    impl LeastSquares for Rosen {
        fn dims(&self) -> (usize, usize) {
            (2, 2)
        }
        fn eval(
            &mut self,
            p: &[f64],
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> bool {
            r[0] = 10.0 * (p[1] - p[0] * p[0]);
            r[1] = 1.0 - p[0];
            if let Some(j) = jac {
                j[(0, 0)] = -20.0 * p[0];
                j[(0, 1)] = 10.0;
                j[(1, 0)] = -1.0;
                j[(1, 1)] = 0.0;
            }
            true
        }
    }

    /// A fresh search keeps a file already at its checkpoint's name aside at its
    /// first save (the write policy) and replaces its own state after that; the
    /// file names its problem's parts, and a file of other parts, a truncated one
    /// or an edited one is refused with the reason.
    #[test]
    fn checkpoints_keep_a_users_file_and_refuse_what_is_not_theirs() {
        let inf = f64::INFINITY;
        let bounds = [(-inf, inf); 2];
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("mine.0");
        std::fs::write(&file, "the user's notes").unwrap();
        let cp = |part: &str| Checkpoint {
            file: file.clone(),
            every: 1,
            problem: vec![("trace 1".into(), part.into())],
        };
        let mut control = Control {
            checkpoint: Some(cp("a")),
            ..Control::default()
        };
        let res = search(
            &mut Rosen,
            &[-1.2, 1.0],
            &bounds,
            &LmSettings::default(),
            &mut control,
        );
        assert!(
            matches!(res.termination, Termination::Converged(_)),
            "{res:?}"
        );
        assert!(res.iterations > 2, "saved more than once: {res:?}");
        let kept = dir.path().join("mine.previous-1.0");
        assert_eq!(std::fs::read_to_string(&kept).unwrap(), "the user's notes");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            2,
            "one file kept aside"
        );
        assert_eq!(cp("a").check((2, 2), &bounds), Ok(()));
        let other = cp("b").check((2, 2), &bounds).unwrap_err();
        assert!(
            other.contains("another problem") && other.contains("trace 1"),
            "{other}"
        );
        let good = std::fs::read_to_string(&file).unwrap();
        for (what, text) in [
            ("truncated", good[..good.len() / 2].to_string()),
            (
                "edited",
                good.replacen("\"iterations\":", "\"iterations\":1", 1),
            ),
            ("empty", String::new()),
        ] {
            std::fs::write(&file, &text).unwrap();
            let why = cp("a").check((2, 2), &bounds).unwrap_err();
            assert!(why.contains("mine.0"), "{what}: {why}");
        }
    }

    #[test]
    fn solves_rosenbrock_and_respects_bounds() {
        let inf = f64::INFINITY;
        let res = minimize(
            &mut Rosen,
            &[-1.2, 1.0],
            &[(-inf, inf); 2],
            &LmSettings::default(),
        );
        assert!(
            (res.x[0] - 1.0).abs() < 1e-8 && (res.x[1] - 1.0).abs() < 1e-8,
            "{res:?}"
        );
        // With x ≤ 0.5 the constrained optimum is on the bound, y = x².
        let res = minimize(
            &mut Rosen,
            &[-1.2, 1.0],
            &[(-inf, 0.5), (-inf, inf)],
            &LmSettings::default(),
        );
        assert!(
            (res.x[0] - 0.5).abs() < 1e-12 && (res.x[1] - 0.25).abs() < 1e-6,
            "{res:?}"
        );
    }

    /// A linear valley: r = (10·(x + y − 1), 0.1·(x − y)), steep across the line
    /// x + y = 1 and shallow along it.
    struct Valley;
    impl LeastSquares for Valley {
        fn dims(&self) -> (usize, usize) {
            (2, 2)
        }
        fn eval(
            &mut self,
            p: &[f64],
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> bool {
            r[0] = 10.0 * (p[0] + p[1] - 1.0);
            r[1] = 0.1 * (p[0] - p[1]);
            if let Some(j) = jac {
                j.copy_from_slice(&[10.0, 0.1, 10.0, -0.1]);
            }
            true
        }
    }

    /// A trial the bounds turn uphill in the linear model is never evaluated: from
    /// (0, 1) the step along the valley to (0.5, 0.5), clipped at x ≤ 0.1, leaves
    /// the valley (x + y = 0.6). The problem is linear, so every trial evaluated
    /// with a predicted decrease > 0 is accepted (ρ = 1): the evaluations are the
    /// start's and two per iteration (trial, then the Jacobian there), none wasted.
    #[test]
    fn a_step_the_bounds_turn_uphill_is_rejected_without_an_evaluation() {
        let inf = f64::INFINITY;
        let res = minimize(
            &mut Valley,
            &[0.0, 1.0],
            &[(-inf, 0.1), (-inf, inf)],
            &LmSettings::default(),
        );
        assert_eq!(res.x[0], 0.1, "{res:?}");
        // y from the 1-D least squares at x = 0.1: 100·(y − 0.9) + 0.01·(y − 0.1) = 0
        let y = (100.0 * 0.9 + 0.01 * 0.1) / 100.01;
        assert!((res.x[1] - y).abs() < 1e-9, "{res:?}");
        assert_eq!(res.evaluations, 1 + 2 * res.iterations, "{res:?}");
    }

    /// r = atan(x), whose Gauss-Newton step −atan(x)(1 + x²) from x = 3 lands at
    /// −9.5, where |r| is larger: the trial points it was asked to evaluate.
    struct Arctan(Vec<f64>);
    impl LeastSquares for Arctan {
        fn dims(&self) -> (usize, usize) {
            (1, 1)
        }
        fn eval(
            &mut self,
            p: &[f64],
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> bool {
            self.0.push(p[0]);
            r[0] = p[0].atan();
            if let Some(j) = jac {
                j[(0, 0)] = 1.0 / (1.0 + p[0] * p[0]);
            }
            true
        }
    }

    #[test]
    fn a_rejected_step_is_shrunk_by_at_least_half_before_the_next_trial() {
        // The overshoot is rejected; the damped step is δ_GN/(1 + μ) here, so blind
        // doubling of μ from 10⁻³ hardly changes it and is rejected again and again
        // (the test fails on it): every trial after a rejection must lie at most half
        // as far from the point as the rejected one.
        let mut w = Arctan(Vec::new());
        let res = minimize(&mut w, &[3.0], &[(-20.0, 20.0)], &LmSettings::default());
        assert!(
            matches!(res.termination, Termination::Converged(_)),
            "{res:?}"
        );
        assert!(res.x[0].abs() < 1e-6, "{res:?}");
        let cost = |x: f64| 0.5 * x.atan().powi(2);
        // walk the evaluations: x_k the current point, a trial worse than it rejected
        let pts = &w.0;
        let mut x = pts[0];
        let mut last_rejected: Option<f64> = None;
        let mut rejections = 0;
        for &p in &pts[1..] {
            if p == x {
                continue; // the Jacobian at an accepted point
            }
            if let Some(d) = last_rejected {
                assert!(
                    (p - x).abs() <= SHRINK_RANGE.1 * d * (1.0 + 1e-12),
                    "trial {p} from {x}: rejected step was {d}"
                );
            }
            if cost(p) < cost(x) {
                x = p;
                last_rejected = None;
            } else {
                last_rejected = Some((p - x).abs());
                rejections += 1;
            }
        }
        assert!(rejections > 0, "the wall rejects some step: {pts:?}");
    }

    /// Rosenbrock taking secant Jacobians when allowed, counting the evaluations
    /// with the Jacobian.
    struct SecantRosen {
        allowed: bool,
        jacobians: usize,
    }
    impl LeastSquares for SecantRosen {
        fn dims(&self) -> (usize, usize) {
            (2, 2)
        }
        fn eval(
            &mut self,
            p: &[f64],
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> bool {
            self.jacobians += usize::from(jac.is_some());
            Rosen.eval(p, r, jac)
        }
        fn secant_jacobian(&self) -> bool {
            self.allowed
        }
    }

    #[test]
    fn secant_jacobians_save_evaluations_and_the_search_ends_on_an_exact_one() {
        let run = |allowed| {
            let mut p = SecantRosen {
                allowed,
                jacobians: 0,
            };
            let inf = f64::INFINITY;
            let res = minimize(
                &mut p,
                &[-1.2, 1.0],
                &[(-inf, inf); 2],
                &LmSettings::default(),
            );
            (res, p.jacobians)
        };
        let (exact, exact_jacobians) = run(false);
        let (secant, secant_jacobians) = run(true);
        for res in [&exact, &secant] {
            assert!(
                matches!(res.termination, Termination::Converged(_)),
                "{res:?}"
            );
            assert!((res.x[0] - 1.0).abs() < 1e-8 && (res.x[1] - 1.0).abs() < 1e-8);
        }
        assert!(
            secant_jacobians < exact_jacobians,
            "{secant_jacobians} Jacobians with secant updates, {exact_jacobians} without"
        );
        // the Jacobian returned is the one at x, not a secant update (Rosen's is exact)
        let mut want = DMatrix::zeros(2, 2);
        Rosen.eval(&secant.x, &mut DVector::zeros(2), Some(&mut want));
        assert_eq!(secant.jacobian, want);
    }

    #[test]
    fn broyden_maps_the_step_onto_the_change_and_leaves_the_orthogonal_part() {
        let mut j = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]);
        let dx = DVector::from_vec(vec![1.0, 0.0]);
        let dr = DVector::from_vec(vec![5.0, -1.0]);
        broyden(&mut j, &dx, &dr);
        // the secant condition J·Δx = Δr, and J·v unchanged for v ⊥ Δx
        assert_eq!(&j * &dx, dr);
        assert_eq!(j.column(1).as_slice(), &[2.0, 4.0]);
        let before = j.clone();
        broyden(&mut j, &DVector::zeros(2), &dr);
        assert_eq!(j, before, "a zero step changes nothing");
    }

    #[test]
    fn the_rejected_shrink_follows_the_parabola_within_its_range() {
        // f0 = 1, slope −1, f1 = 2: curvature 2, minimiser t* = 1/4
        assert_eq!(rejected_shrink(true, 1.0, 2.0, -1.0), 0.25);
        // a trial far worse: the smallest factor; a mild one: at most ½
        assert_eq!(rejected_shrink(true, 1.0, 1e6, -1.0), SHRINK_RANGE.0);
        assert_eq!(rejected_shrink(true, 1.0, 0.2, -1.0), SHRINK_RANGE.1);
        // no usable trial value or slope: the smallest factor
        assert_eq!(rejected_shrink(false, 1.0, 0.5, -1.0), SHRINK_RANGE.0);
        assert_eq!(rejected_shrink(true, 1.0, f64::NAN, -1.0), SHRINK_RANGE.0);
        assert_eq!(rejected_shrink(true, 1.0, 2.0, 0.0), SHRINK_RANGE.0);
    }

    #[test]
    fn the_damping_is_the_first_doubling_that_shrinks_the_step_enough() {
        // |δ(μ)| = 1/(1 + μ): from μ = 1 the doublings 2, 4, 8 give 1/3, 1/5, 1/9;
        // 1/17 at μ = 16 is the first ≤ 0.1
        assert_eq!(damping_for(1.0, 0.1, |mu| Some(1.0 / (1.0 + mu))), 16.0);
        // at least one doubling even when the target already holds
        assert_eq!(damping_for(1.0, 10.0, |mu| Some(1.0 / (1.0 + mu))), 2.0);
        // a system singular at every damping: μ runs past 10³⁰⁰ (the caller stops)
        assert!(damping_for(1.0, 0.1, |_| None) > 1e300);
        assert!(damping_for(1.0, 0.1, |_| Some(f64::NAN)) > 1e300);
    }

    /// Bounds that `f64::clamp` panics on (the Gent limit's lower end above its upper
    /// end, NaN) and a non-finite start end the search as failed, never in a panic.
    #[test]
    fn unusable_bounds_or_start_fail_without_panic() {
        let inf = f64::INFINITY;
        for (x0, bounds) in [
            ([-1.2, 1.0], [(2.0, 1.0), (-inf, inf)]),
            ([-1.2, 1.0], [(f64::NAN, 1.0), (-inf, inf)]),
            ([f64::NAN, 1.0], [(-inf, inf), (-inf, inf)]),
            ([inf, 1.0], [(-inf, inf), (-inf, inf)]),
        ] {
            let res = minimize(&mut Rosen, &x0, &bounds, &LmSettings::default());
            assert!(
                matches!(res.termination, Termination::Failed(_)),
                "{x0:?} {bounds:?}: {res:?}"
            );
        }
        let res = minimize(&mut Rosen, &[0.0], &[(-inf, inf)], &LmSettings::default());
        assert!(matches!(res.termination, Termination::Failed(_)), "{res:?}");
    }

    /// Rosenbrock that evaluates its Jacobian with the first trial of each
    /// iteration ([`LeastSquares::jacobian_with_trial`]).
    struct RosenTrial;
    impl LeastSquares for RosenTrial {
        fn dims(&self) -> (usize, usize) {
            (2, 2)
        }
        fn eval(
            &mut self,
            p: &[f64],
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> bool {
            Rosen.eval(p, r, jac)
        }
        fn jacobian_with_trial(&self) -> bool {
            true
        }
    }

    /// A Jacobian taken with the trial, and a start whose residuals and Jacobian
    /// are given, change the evaluations, never the search: bit for bit the same
    /// iterates and cost (the same numbers enter every step).
    #[test]
    fn jacobian_with_the_trial_and_a_known_start_change_only_the_evaluations() {
        let inf = f64::INFINITY;
        let b = [(-inf, 0.5), (-inf, inf)];
        let plain = minimize(&mut Rosen, &[-1.2, 1.0], &b, &LmSettings::default());
        let trial = minimize(&mut RosenTrial, &[-1.2, 1.0], &b, &LmSettings::default());
        assert_eq!((trial.x.clone(), trial.cost), (plain.x.clone(), plain.cost));
        assert_eq!(trial.iterations, plain.iterations);
        assert!(
            trial.evaluations < plain.evaluations,
            "{} vs {}",
            trial.evaluations,
            plain.evaluations
        );
        // from a point the first search stopped on the way, given its r and J
        let mid = [0.0, 0.0];
        let (mut r, mut j) = (DVector::zeros(2), DMatrix::zeros(2, 2));
        Rosen.eval(&mid, &mut r, Some(&mut j));
        let fresh = minimize(&mut Rosen, &mid, &b, &LmSettings::default());
        let mut c = Control {
            known_start: Some((r, j)),
            ..Control::default()
        };
        let known = search(&mut Rosen, &mid, &b, &LmSettings::default(), &mut c);
        assert_eq!((known.x.clone(), known.cost), (fresh.x.clone(), fresh.cost));
        assert_eq!(known.evaluations + 1, fresh.evaluations);
        // a known start of the wrong shape is not used
        let mut c = Control {
            known_start: Some((DVector::zeros(3), DMatrix::zeros(3, 2))),
            ..Control::default()
        };
        let wrong = search(&mut Rosen, &mid, &b, &LmSettings::default(), &mut c);
        assert_eq!(wrong.evaluations, fresh.evaluations);
    }

    /// Rosenbrock forming its own normal equations (JᵀJ and Jᵀr of the point of
    /// its last Jacobian evaluation, remembered with that point), the trial
    /// evaluated with them.
    #[derive(Default)]
    struct RosenNormal {
        at: Vec<f64>,
        normal: Option<(DMatrix<f64>, DVector<f64>)>,
        /// Never has the normal equations of any point.
        forgetful: bool,
    }
    impl LeastSquares for RosenNormal {
        fn dims(&self) -> (usize, usize) {
            (2, 2)
        }
        fn eval(
            &mut self,
            p: &[f64],
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> bool {
            assert!(jac.as_ref().is_none_or(|j| j.is_empty()), "a tall Jacobian");
            let mut j = DMatrix::zeros(2, 2);
            Rosen.eval(p, r, Some(&mut j));
            if jac.is_some() {
                self.at = p.to_vec();
                self.normal = Some((j.tr_mul(&j), j.tr_mul(r)));
            }
            true
        }
        fn jacobian_with_trial(&self) -> bool {
            true
        }
        fn forms_normal_equations(&self) -> bool {
            true
        }
        fn normal_equations(&self, p: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
            (self.at == p && !self.forgetful)
                .then(|| self.normal.clone())
                .flatten()
        }
    }

    /// A problem that forms its normal equations but has none for the point the
    /// search stands on stops the search as failed, with the reason (never a step
    /// from a made-up gradient, never converged).
    #[test]
    fn missing_normal_equations_fail_the_search() {
        let inf = f64::INFINITY;
        let b = [(-inf, inf), (-inf, inf)];
        let res = minimize(
            &mut RosenNormal {
                forgetful: true,
                ..RosenNormal::default()
            },
            &[-1.2, 1.0],
            &b,
            &LmSettings::default(),
        );
        match res.termination {
            Termination::Failed(why) => assert!(why.contains("normal equations"), "{why}"),
            other => panic!("expected a failed search, got {other:?}"),
        }
    }

    /// A problem that forms its normal equations itself is searched exactly as the
    /// one that hands over its Jacobian (the same products enter every step: bit for
    /// bit the same iterates, cost and iterations), with no tall Jacobian asked for
    /// or returned.
    #[test]
    fn normal_equations_formed_by_the_problem_give_the_same_search() {
        let inf = f64::INFINITY;
        let b = [(-inf, 0.5), (-inf, inf)];
        let plain = minimize(&mut RosenTrial, &[-1.2, 1.0], &b, &LmSettings::default());
        let normal = minimize(
            &mut RosenNormal::default(),
            &[-1.2, 1.0],
            &b,
            &LmSettings::default(),
        );
        assert_eq!(
            (normal.x.clone(), normal.cost),
            (plain.x.clone(), plain.cost)
        );
        assert_eq!(normal.iterations, plain.iterations);
        assert_eq!(normal.termination, plain.termination);
        assert!(normal.jacobian.is_empty());
    }

    /// The reach rule by hand: cost 150 against a reference of 100 (margin 1 +
    /// 2·floor 0.5 = 1.5 above it: a gap of 48.5), falling 1 per iteration over the
    /// last 5 with 20 left: 2 × 1 × 20 = 40 < 48.5, given up; with 30 left
    /// (60 ≥ 48.5) not yet; within the margin, never; before 5 iterations, never.
    #[test]
    fn out_of_reach_follows_its_rule() {
        let costs = [160.0, 158.0, 155.0, 154.0, 153.0, 152.0, 151.0, 150.0];
        let reach = |cost| Reach { cost, margin: 1.0 };
        assert!(out_of_reach(&costs, reach(100.0), 0.25, 20).is_some());
        assert!(out_of_reach(&costs, reach(100.0), 0.25, 30).is_none());
        assert!(out_of_reach(&[101.0; 8], reach(100.0), 0.25, 20).is_none());
        assert!(out_of_reach(&costs[..5], reach(100.0), 0.25, 1).is_none());
        assert!(out_of_reach(&costs, reach(f64::NAN), 0.25, 20).is_none());
        // a search on a plateau far above: given up
        assert!(out_of_reach(&[1e6; 6], reach(100.0), 0.0, 95).is_some());
    }

    #[test]
    fn project_never_panics() {
        assert_eq!(project(5.0, (0.0, 1.0)), 1.0);
        assert_eq!(project(-5.0, (0.0, 1.0)), 0.0);
        // Inverted or NaN bounds give some value instead of a panic.
        assert!(!project(0.5, (2.0, 1.0)).is_nan());
        assert_eq!(project(0.5, (f64::NAN, 1.0)), 0.5);
    }
}
