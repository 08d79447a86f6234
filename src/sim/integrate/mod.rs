//! Adaptive integrators behind one thin interface ([`run`]).
//!
//! * diffsol 0.18 (pinned; Robinson et al. 2026, JOSS 11(117) 9384):
//!   [`Method::Bdf`] (variable-order NDF/BDF after ode15s, for stiff scenes: a
//!   Kelvin-Voigt dashpot, a fast source, arms from ms to ks), [`Method::Esdirk34`]
//!   and [`Method::TrBdf2`] (L-stable singly diagonally implicit Runge–Kutta), and
//!   the forward sensitivities of [`Method::Tsit45`]. The implicit ones use the
//!   system's exact Jacobian-vector product ([`System::jacobian_times`]).
//! * Our own explicit 5(4) pairs with a PI step controller ([`dopri`]):
//!   [`Method::Tsit45`] (Tsitouras 5(4), for lightly damped, oscillatory scenes;
//!   plain runs) and [`Method::Dp54`] (Dormand–Prince 5(4), kept as an independent
//!   test oracle and for fixed-step convergence tests), and on the same driver
//!   [`Method::Dop853`] (Dormand–Prince 8(5,3), [`dop853`]: long, lightly damped
//!   ringing at tight tolerances).
//!
//! Every method integrates between *restart times* (input kinks: triangle corners,
//! ramp ends, steps), where the caller may change the state (energy bookkeeping of
//! an ideal source's jump) and the method restarts from first order; writes the state
//! at requested sample times from its dense output; and stops at the first change of
//! an event function from positive to non-positive (pull-in), with the state at the
//! event. The right-hand side and the Jacobian allocate nothing.

mod bdf;
mod diffsol;
mod dop853;
mod dopri;

/// Newton's convergence test, as a fraction of the error tolerance (diffsol's
/// default is 0.2). The modified Newton iteration runs on a Jacobian up to 20 steps
/// old; on a stiff component (the dashpot-damped inertial mode of a dynamic stack,
/// h·λ ≈ −10³) it stops with that component off its slow manifold by tens of
/// tolerances, and the next steps' error tests then fail in a cascade while the step
/// resolves the spurious transient (the rig scene, datasets/scenes/stack_rig_7s.toml,
/// at rtol 1e-4: 22 rejections in a row at t = 2.111 s, 252 error-test failures in
/// 732 steps). At 10⁻³: 27 rejections in 819 steps at rtol 1e-6 (407 in 1483
/// before), the plain run 1.57× and the sensitivity run 2× fewer instructions;
/// scenes without the cascade pay 0–9 % more Newton iterations
/// (docs/architecture.md). Our BDF uses it too (`bdf::Bdf::newton_tol`).
pub(super) const NEWTON_TOLERANCE: f64 = 1e-3;

/// A first-order system y' = f(t, y).
pub trait System {
    /// Number of states.
    fn dim(&self) -> usize;
    /// Right-hand side; must not allocate.
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]);
    /// The Jacobian applied to a vector, (∂f/∂y)·v; must not allocate.
    fn jacobian_times(&self, t: f64, y: &[f64], v: &[f64], out: &mut [f64]);
    /// The dense Jacobian ∂f/∂y, row-major `dim × dim`; must not allocate.
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]);
    /// Number of parameters θ for forward sensitivities.
    fn n_params(&self) -> usize;
    /// The leading states the rates read (the default: all). The states after them
    /// are quadratures (of the energy balance): no rate reads them (∂f_i/∂y_j = 0
    /// for every i and j ≥ this, and f does not look at them at all). So the
    /// sensitivities of the leading block are exact without the rest, which an
    /// integrator may then leave out, and an explicit method forms only the leading
    /// block of a stage's argument (the rest of the vector it passes to
    /// [`System::rhs`] holds values that must not matter).
    fn dynamic_dim(&self) -> usize {
        self.dim()
    }
    /// The dense parameter Jacobian ∂f/∂θ at fixed y, row-major `dim × n_params`;
    /// must not allocate.
    fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut [f64]);
    /// (∂f/∂y)·s + ∂f/∂θk, the rate of the sensitivity column s = ∂y/∂θk; must not
    /// allocate.
    fn sensitivity_rate(&self, t: f64, y: &[f64], s: &[f64], k: usize, out: &mut [f64]);
    /// ∂y0/∂θ, row-major `dim × n_params`.
    fn initial_sensitivity(&self, out: &mut [f64]);
}

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// diffsol's variable-order BDF (NDF), orders 1–5.
    Bdf,
    /// diffsol's ESDIRK3(4) (Jørgensen et al. 2018).
    Esdirk34,
    /// diffsol's TR-BDF2 (Hosea & Shampine 1996).
    TrBdf2,
    /// Explicit Tsitouras 5(4): ours ([`dopri`]), diffsol's with sensitivities.
    Tsit45,
    /// Our explicit Dormand–Prince 5(4) (test oracle).
    Dp54,
    /// Our explicit Dormand–Prince 8(5,3) ([`dop853`]: long, lightly damped
    /// ringing at tight tolerances).
    Dop853,
}

impl Method {
    /// Every method, in the order benches chart them.
    pub const ALL: [Method; 6] = [
        Method::Bdf,
        Method::Esdirk34,
        Method::TrBdf2,
        Method::Tsit45,
        Method::Dp54,
        Method::Dop853,
    ];

    /// Name as written in scene files and reports (also its `Display`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Bdf => "bdf",
            Method::Esdirk34 => "esdirk34",
            Method::TrBdf2 => "tr-bdf2",
            Method::Tsit45 => "tsit45",
            Method::Dp54 => "dp54",
            Method::Dop853 => "dop853",
        }
    }

    /// Parse a scene-file name.
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s || (s == "trbdf2" && *m == Method::TrBdf2))
    }

    /// Classical order of the propagated solution (BDF: its largest order).
    pub fn order(self) -> u32 {
        match self {
            Method::Bdf => 5,
            Method::Esdirk34 => 3,
            Method::TrBdf2 => 2,
            Method::Tsit45 | Method::Dp54 => 5,
            Method::Dop853 => 8,
        }
    }

    /// Implicit (uses the Jacobian; suits stiff scenes).
    pub fn implicit(self) -> bool {
        matches!(self, Method::Bdf | Method::Esdirk34 | Method::TrBdf2)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Tolerances and limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per state, multiplied by the caller's state scales.
    pub atol: f64,
    /// Largest step (s); our Dormand–Prince only (diffsol has no such limit).
    pub h_max: f64,
    /// Largest first step after every (re)start (s): a method started from rest
    /// must not step over an input that starts smoothly from zero.
    pub h_init: f64,
    /// Step budget over the whole run.
    pub max_steps: usize,
    /// Fixed step without error control (dp54 and dop853 only; convergence-order
    /// tests).
    pub fixed_step: Option<f64>,
}

/// Counts of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps (error test or Newton failure).
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
    /// Jacobian evaluations (implicit methods).
    pub jacobians: usize,
    /// LU factorisations (implicit methods).
    pub factorizations: usize,
    /// Restarts at input kinks.
    pub restarts: usize,
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum End {
    /// Reached the last restart bound.
    Done,
    /// The event function crossed zero at this time (state left in `y`).
    Event(f64),
    /// The method failed or the state went non-finite (reason, with the time);
    /// `y` holds the last accepted finite state.
    Failed(String),
}

/// The first state that is not finite, if any: a run whose state has gone NaN or
/// infinite has no result past that point, so every method stops there with
/// [`End::Failed`] (an error test on a NaN norm would otherwise accept the step).
fn non_finite(t: f64, y: &[f64]) -> Option<End> {
    y.iter().position(|v| !v.is_finite()).map(|i| {
        End::Failed(format!(
            "the state became non-finite at t = {t:.6e} s (state {i} = {})",
            y[i]
        ))
    })
}

/// The step-budget failure, with where the run stood.
fn budget_exhausted(t: f64, max_steps: usize) -> End {
    End::Failed(format!(
        "step budget exhausted at t = {t:.6e} s ({max_steps} steps)"
    ))
}

/// A first step from the scale of the state and its derivative (Hairer, Nørsett &
/// Wanner, Solving ODEs I, §II.4, simplified): 1 % of ‖y‖/‖y'‖ in the tolerance's
/// weighted norm, or 1 µs when either is negligible.
fn initial_step(y: &[f64], dy: &[f64], scale: &[f64], o: &Options) -> f64 {
    let n = y.len();
    let (mut d0, mut d1) = (0.0, 0.0);
    for i in 0..n {
        let sc = o.atol * scale[i] + o.rtol * y[i].abs();
        d0 += (y[i] / sc).powi(2);
        d1 += (dy[i] / sc).powi(2);
    }
    let (d0, d1) = ((d0 / n as f64).sqrt(), (d1 / n as f64).sqrt());
    if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    }
}

/// The right-hand side and its Jacobians with the input's left limit at the
/// segment end (inputs are right-continuous, and the segment ends at a kink).
pub(super) struct Left<'a, S> {
    pub(super) sys: &'a S,
    pub(super) t_end: f64,
}

impl<S: System> Left<'_, S> {
    #[inline]
    pub(super) fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.sys.rhs(t.min(self.t_end), y, dy)
    }
    pub(super) fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) {
        self.sys.jacobian(t.min(self.t_end), y, jac)
    }
    pub(super) fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut [f64]) {
        self.sys.param_jacobian(t.min(self.t_end), y, dfdp)
    }
}

/// The time just before `b` at which the right-hand side of the interval [a, b]
/// is evaluated for t ≥ b: inputs are right-continuous, and `b` is a kink.
fn left_limit(a: f64, b: f64) -> f64 {
    b - 1e-12 * (b - a)
}

/// The sample callback: (t, y, ∂y/∂θ column by column, empty without them).
pub type SampleFn<'a> = dyn FnMut(f64, &[f64], &[f64]) + 'a;

/// The step callback: (t, y) at the end of every accepted step, after the samples
/// within it (not past an event): the integrator's own points between samples.
pub type StepFn<'a> = dyn FnMut(f64, &[f64]) + 'a;

/// An event function g(t, y); the event is its first change from > 0 to ≤ 0.
pub type EventFn<'a> = &'a dyn Fn(f64, &[f64]) -> f64;

/// What to integrate besides the state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Extra<'a> {
    /// The state only.
    None,
    /// Forward sensitivities ∂y/∂θ (every method but dp54), with the parameters' magnitudes
    /// (each sensitivity's absolute tolerance is the state's divided by it).
    Sensitivities(&'a [f64]),
}

/// Integrate `y` over `bounds` = [t0, kink1, …, t_end] with method `m`.
///
/// `samples` are output times in (t0, t_end] (sorted); `out(t, y, s)` is called for
/// each one reached, `step(t, y)` at the end of every accepted step, `s` the sensitivities ∂y/∂θ column by column, of the leading
/// ns states (`s[j·ns + i]` = ∂yi/∂θj, ns = `s.len()`/nθ: bdf integrates those of
/// [`System::dynamic_dim`] only, the diffsol methods every state's; empty without
/// them). At a restart the sensitivities carry on unchanged
/// (the caller's `restart` may only change states that do not feed back, such as
/// quadratures, whose sensitivities are then not meaningful). At each interior bound `restart(t, y)` may change the state before the
/// method restarts. `event(t, y)` (if any) stops the run where it turns non-positive.
/// `scale[i]` multiplies `o.atol` for state i.
#[allow(clippy::too_many_arguments)]
pub fn run<S: System>(
    sys: &S,
    m: Method,
    o: &Options,
    scale: &[f64],
    bounds: &[f64],
    y: &mut [f64],
    samples: &[f64],
    extra: Extra,
    out: &mut SampleFn,
    step: &mut StepFn,
    event: Option<EventFn>,
    restart: &mut dyn FnMut(f64, &mut [f64]),
    stats: &mut Stats,
) -> End {
    if matches!(m, Method::Dp54 | Method::Dop853) && extra != Extra::None {
        return End::Failed(format!(
            "forward sensitivities need bdf, esdirk34, tr-bdf2 or tsit45, not {m}"
        ));
    }
    if o.fixed_step.is_some() && !matches!(m, Method::Dp54 | Method::Dop853) {
        return End::Failed(format!(
            "a fixed step is available with dp54 and dop853 only, not {}",
            m.name()
        ));
    }
    match m {
        Method::Dp54 | Method::Tsit45 | Method::Dop853 if extra == Extra::None => dopri::run(
            match m {
                Method::Dp54 => dopri::Scheme::Pair(&dopri::DP54),
                Method::Dop853 => dopri::Scheme::Dop853,
                _ => dopri::Scheme::Pair(&dopri::TSIT45),
            },
            sys,
            o,
            scale,
            bounds,
            y,
            samples,
            &mut |t, y| out(t, y, &[]),
            step,
            event,
            restart,
            stats,
        ),
        Method::Bdf => bdf::run(
            sys,
            o,
            scale,
            bounds,
            y,
            samples,
            matches!(extra, Extra::Sensitivities(_)),
            out,
            step,
            event,
            restart,
            stats,
        ),
        _ => diffsol::run(
            sys, m, o, scale, bounds, y, samples, extra, out, step, event, restart, stats,
        ),
    }
}
