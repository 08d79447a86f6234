//! The diffsol adapter: one [`OdeBuilder`] problem per run, built from closures over
//! the [`System`] (right-hand side with the input's left limit at the segment end,
//! the analytic Jacobian applied to a vector, the event as a root function), and one
//! driver loop shared by every diffsol method.
//!
//! Restarts: at each interior bound the solver stops exactly there (`set_stop_time`),
//! the caller's `restart` may change the state, the derivative is re-evaluated with
//! the input's right limit, and diffsol reinitialises the method to first order
//! (it does so whenever the state is touched through `state_mut`).

use super::{
    budget_exhausted, left_limit, non_finite, End, EventFn, Extra, Method, Options, SampleFn,
    Stats, StepFn, System, NEWTON_TOLERANCE,
};
use ::diffsol::{
    NalgebraLU, NalgebraMat, NalgebraVec, OdeBuilder, OdeEquations, OdeSolverMethod,
    OdeSolverStopReason, Vector, VectorCommon,
};
use std::cell::{Cell, RefCell};

type M = NalgebraMat<f64>;
type LS = NalgebraLU<f64>;

/// Mutable slice of a diffsol nalgebra vector.
fn slice_mut(v: &mut NalgebraVec<f64>) -> &mut [f64] {
    v.inner_mut().as_mut_slice()
}

/// Slice of a diffsol nalgebra vector.
fn slice(v: &NalgebraVec<f64>) -> &[f64] {
    v.inner().as_slice()
}

/// Counters the closures update (they only get `&self`).
#[derive(Default)]
struct Counts {
    rhs: Cell<usize>,
    jac: Cell<usize>,
}

/// The closures' shared view of the system: right-hand side, Jacobian-vector and
/// parameter-Jacobian-vector products with the left limit at `t_end`.
struct Adapter<'s, S> {
    sys: &'s S,
    t_end: Cell<f64>,
    counts: Counts,
    /// The Jacobians at the state they were last asked at.
    cache: RefCell<Cache>,
}

/// The dense Jacobians ∂f/∂y and ∂f/∂θ at one (t, x). A sensitivity run asks for
/// J·s at one state once per parameter lane and Newton iteration (the sensitivity
/// solve after each step), and for ∂f/∂θ·e_k for every k at each state: the dense
/// matrices, each one multi-lane evaluation of the right-hand side
/// ([`System::jacobian`], [`System::param_jacobian`]), turn those into cheap
/// products. ∂f/∂y is built when a state is asked for a second J·v (diffsol
/// builds its own dense Jacobian from n products at one state, so in a plain run
/// the cache turns those into one multi-lane evaluation too); ∂f/∂θ when first
/// asked.
struct Cache {
    t: f64,
    x: Vec<f64>,
    /// Whether `jac` and `dfdp` hold the Jacobians at (t, x).
    jac_built: bool,
    dfdp_built: bool,
    /// Row-major n × n.
    jac: Vec<f64>,
    /// Row-major n × nθ.
    dfdp: Vec<f64>,
}

impl Cache {
    /// Point the cache at (t, x); true if it was there already.
    fn at(&mut self, t: f64, x: &[f64]) -> bool {
        if self.t == t && self.x == x {
            return true;
        }
        self.t = t;
        self.x.copy_from_slice(x);
        self.jac_built = false;
        self.dfdp_built = false;
        false
    }
}

/// out = A·v for a row-major A with v.len() columns.
#[inline]
fn mat_vec(a: &[f64], v: &[f64], out: &mut [f64]) {
    let m = v.len();
    for (i, o) in out.iter_mut().enumerate() {
        *o = a[i * m..(i + 1) * m]
            .iter()
            .zip(v)
            .map(|(a, b)| a * b)
            .sum();
    }
}

impl<S: System> Adapter<'_, S> {
    #[inline]
    fn rhs(&self, t: f64, x: &[f64], dy: &mut [f64]) {
        self.counts.rhs.set(self.counts.rhs.get() + 1);
        self.sys.rhs(t.min(self.t_end.get()), x, dy);
    }

    /// J(x)·v (diffsol builds its dense Jacobian column by column from this).
    #[inline]
    fn jac_vec(&self, t: f64, x: &[f64], v: &[f64], out: &mut [f64]) {
        let t = t.min(self.t_end.get());
        let c = &mut *self.cache.borrow_mut();
        if !c.at(t, x) {
            self.counts.jac.set(self.counts.jac.get() + 1);
            return self.sys.jacobian_times(t, x, v, out);
        }
        if !c.jac_built {
            self.sys.jacobian(t, x, &mut c.jac);
            self.counts.jac.set(self.counts.jac.get() + x.len());
            c.jac_built = true;
        }
        mat_vec(&c.jac, v, out);
    }

    /// (∂f/∂θ)·v (diffsol assembles ∂f/∂θ column by column from unit vectors).
    #[inline]
    fn sens_vec(&self, t: f64, x: &[f64], v: &[f64], out: &mut [f64]) {
        let t = t.min(self.t_end.get());
        let c = &mut *self.cache.borrow_mut();
        c.at(t, x);
        if !c.dfdp_built {
            self.sys.param_jacobian(t, x, &mut c.dfdp);
            c.dfdp_built = true;
        }
        mat_vec(&c.dfdp, v, out);
    }

    /// ds = J·s + ∂f/∂θ for every parameter column of `s` (after a restart).
    fn sens_rate(&self, t: f64, x: &[f64], s: &[f64], ds: &mut [f64]) {
        let n = x.len();
        for p in 0..self.sys.n_params() {
            let col = p * n..(p + 1) * n;
            self.sys
                .sensitivity_rate(t, x, &s[col.clone()], p, &mut ds[col]);
        }
    }
}

/// Integrate with a diffsol method (see [`super::run`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn run<S: System>(
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
    let n = y.len();
    let np = sys.n_params();
    let ad = Adapter {
        sys,
        t_end: Cell::new(left_limit(bounds[0], bounds[1])),
        counts: Counts::default(),
        cache: RefCell::new(Cache {
            t: f64::NAN,
            x: vec![0.0; n],
            jac_built: false,
            dfdp_built: false,
            jac: vec![0.0; n * n],
            dfdp: vec![0.0; n * np],
        }),
    };
    if let Some(g) = event {
        if g(bounds[0], y) <= 0.0 {
            return End::Event(bounds[0]);
        }
    }
    let y0 = y.to_vec();
    let mut s0 = vec![0.0; n * np];
    sys.initial_sensitivity(&mut s0);
    let atol: Vec<f64> = scale.iter().map(|s| o.atol * s).collect();
    // The parameters live in the system; p only tells diffsol how many there are
    // and their magnitudes (each sensitivity's absolute tolerance is the state's
    // divided by its parameter's magnitude).
    let magnitudes: Vec<f64> = match extra {
        Extra::Sensitivities(m) => m.iter().map(|v| v.abs().max(1e-300)).collect(),
        Extra::None => vec![1.0; np],
    };
    let problem = OdeBuilder::<M>::new()
        .t0(bounds[0])
        .rtol(o.rtol)
        .atol(atol)
        .p(magnitudes.clone())
        .param_scales(magnitudes)
        .rhs_sens_implicit(
            |x: &[f64], _p: &[f64], t: f64, dy: &mut [f64]| ad.rhs(t, x, dy),
            |x: &[f64], _p: &[f64], t: f64, v: &[f64], jv: &mut [f64]| ad.jac_vec(t, x, v, jv),
            |x: &[f64], _p: &[f64], t: f64, v: &[f64], sv: &mut [f64]| ad.sens_vec(t, x, v, sv),
        )
        .init_sens(
            move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&y0),
            move |_p: &[f64], _t: f64, v: &[f64], out: &mut [f64]| {
                for i in 0..n {
                    out[i] = (0..np).map(|j| s0[i * np + j] * v[j]).sum();
                }
            },
            n,
        )
        .build();
    let mut problem = match problem {
        Ok(p) => p,
        Err(e) => return End::Failed(format!("diffsol problem setup: {e}")),
    };
    // diffsol counts Newton failures over the whole run, not per step; a long run
    // recovers from many (each costs a Jacobian update and a smaller step), so the
    // run's step budget is the limit, as for the error test.
    problem.ode_options.max_nonlinear_solver_failures = o.max_steps;
    problem.ode_options.nonlinear_solver_tolerance = NEWTON_TOLERANCE;
    let sens = matches!(extra, Extra::Sensitivities(_));
    let mut drv = Driver {
        ad: &ad,
        sens,
        event,
        o,
        bounds,
        samples,
        out,
        step,
        restart,
        stats,
    };
    let end = match (m, sens) {
        (Method::Esdirk34, false) => problem.esdirk34::<LS>().map(|s| drv.drive(s, y)),
        (Method::Esdirk34, true) => problem.esdirk34_sens::<LS>().map(|s| drv.drive(s, y)),
        (Method::TrBdf2, false) => problem.tr_bdf2::<LS>().map(|s| drv.drive(s, y)),
        (Method::TrBdf2, true) => problem.tr_bdf2_sens::<LS>().map(|s| drv.drive(s, y)),
        (Method::Tsit45, false) => problem.tsit45().map(|s| drv.drive(s, y)),
        (Method::Tsit45, true) => problem.tsit45_sens().map(|s| drv.drive(s, y)),
        (Method::Bdf | Method::Dp54 | Method::Dop853, _) => {
            unreachable!("{m} is not a diffsol method")
        }
    };
    let end = end.unwrap_or_else(|e| End::Failed(format!("diffsol solver setup: {e}")));
    stats.rhs_evals += ad.counts.rhs.get();
    stats.jacobians += ad.counts.jac.get() / n.max(1);
    end
}

/// The driver loop over restart intervals, for any diffsol method.
struct Driver<'d, 's, S> {
    ad: &'d Adapter<'s, S>,
    sens: bool,
    event: Option<EventFn<'d>>,
    o: &'d Options,
    bounds: &'d [f64],
    samples: &'d [f64],
    out: &'d mut SampleFn<'d>,
    step: &'d mut StepFn<'d>,
    restart: &'d mut dyn FnMut(f64, &mut [f64]),
    stats: &'d mut Stats,
}

impl<S: System> Driver<'_, '_, S> {
    fn drive<'a, Eqn, Sv>(&mut self, mut s: Sv, y: &mut [f64]) -> End
    where
        Eqn: OdeEquations<T = f64, V = NalgebraVec<f64>> + 'a,
        Sv: OdeSolverMethod<'a, Eqn>,
    {
        let end = self.segments(&mut s, y);
        let st = s.get_statistics();
        self.stats.steps += st.number_of_steps;
        self.stats.rejected +=
            st.number_of_error_test_failures + st.number_of_nonlinear_solver_fails;
        self.stats.factorizations += st.number_of_linear_solver_setups;
        end
    }

    fn segments<'a, Eqn, Sv>(&mut self, s: &mut Sv, y: &mut [f64]) -> End
    where
        Eqn: OdeEquations<T = f64, V = NalgebraVec<f64>> + 'a,
        Sv: OdeSolverMethod<'a, Eqn>,
    {
        let mut buf = s.state().y.clone();
        // The last accepted finite state (what `y` holds if the state goes non-finite).
        let mut last_ok = slice(s.state().y).to_vec();
        let mut sbuf = s.state().s.clone();
        let h = s.state().h.min(self.o.h_init);
        *s.state_mut().h = h;
        let mut next = 0;
        let mut t_prev = self.bounds[0];
        let mut g_old = self.event.map_or(1.0, |g| g(t_prev, slice(s.state().y)));
        for k in 1..self.bounds.len() {
            let b = self.bounds[k];
            if k > 1 {
                let a = self.bounds[k - 1];
                self.stats.restarts += 1;
                self.ad.t_end.set(left_limit(a, b));
                let st = s.state_mut();
                (self.restart)(a, slice_mut(st.y));
                self.ad.rhs(a, slice(st.y), slice_mut(st.dy));
                if self.sens {
                    self.ad
                        .sens_rate(a, slice(st.y), slice(st.s), slice_mut(st.ds));
                }
                *st.h = st.h.min(self.o.h_init);
                if let Some(g) = self.event {
                    g_old = g(a, slice(st.y));
                    if g_old <= 0.0 {
                        // the input's jump at the restart is already past the event
                        y.copy_from_slice(slice(st.y));
                        return End::Event(a);
                    }
                }
            }
            if let Err(e) = s.set_stop_time(b) {
                return self.fail(s, y, format!("cannot stop at t = {b:.6e} s: {e}"));
            }
            loop {
                if s.get_statistics().number_of_steps >= self.o.max_steps {
                    y.copy_from_slice(slice(s.state().y));
                    return budget_exhausted(s.state().t, self.o.max_steps);
                }
                let reason = match s.step() {
                    Ok(r) => r,
                    Err(e) => {
                        let t = s.state().t;
                        return self.fail(
                            s,
                            y,
                            format!("{} failed at t = {t:.6e} s: {e}", "diffsol"),
                        );
                    }
                };
                let t_now = s.state().t;
                // diffsol's error test accepts a step whose norm is NaN: stop here.
                if let Some(end) = non_finite(t_now, slice(s.state().y)) {
                    y.copy_from_slice(&last_ok);
                    return end;
                }
                last_ok.copy_from_slice(slice(s.state().y));
                // event: a sign change of g over the step, located by bisection on
                // the method's dense output
                let mut event_at = None;
                if let Some(g) = self.event {
                    let g1 = g(t_now.min(self.ad.t_end.get()), slice(s.state().y));
                    if g_old > 0.0 && g1 <= 0.0 {
                        let (mut lo, mut hi) = (t_prev, t_now);
                        for _ in 0..60 {
                            let mid = 0.5 * (lo + hi);
                            if mid <= lo
                                || mid >= hi
                                || s.interpolate_inplace(mid, &mut buf).is_err()
                            {
                                break;
                            }
                            if g(mid, slice(&buf)) > 0.0 {
                                lo = mid;
                            } else {
                                hi = mid;
                            }
                        }
                        event_at = Some(hi);
                    }
                    g_old = g1;
                }
                let upto = event_at.unwrap_or(t_now);
                while next < self.samples.len()
                    && (self.samples[next] < upto
                        || (self.samples[next] <= upto && event_at.is_none()))
                {
                    let ts = self.samples[next];
                    if ts == t_now {
                        buf.copy_from(s.state().y);
                        if self.sens {
                            sbuf.copy_from(s.state().s);
                        }
                    } else if s.interpolate_inplace(ts, &mut buf).is_err()
                        || (self.sens && s.interpolate_sens_inplace(ts, &mut sbuf).is_err())
                    {
                        break;
                    }
                    (self.out)(ts, slice(&buf), slice(&sbuf));
                    next += 1;
                }
                if let Some(te) = event_at {
                    if te == t_now || s.interpolate_inplace(te, &mut buf).is_err() {
                        buf.copy_from(s.state().y);
                    }
                    y.copy_from_slice(slice(&buf));
                    return End::Event(te);
                }
                (self.step)(t_now, slice(s.state().y));
                t_prev = t_now;
                if reason == OdeSolverStopReason::TstopReached {
                    break;
                }
            }
        }
        y.copy_from_slice(slice(s.state().y));
        End::Done
    }

    fn fail<'a, Eqn, Sv>(&mut self, s: &Sv, y: &mut [f64], why: String) -> End
    where
        Eqn: OdeEquations<T = f64, V = NalgebraVec<f64>> + 'a,
        Sv: OdeSolverMethod<'a, Eqn>,
    {
        y.copy_from_slice(slice(s.state().y));
        End::Failed(why)
    }
}
