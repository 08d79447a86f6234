//! Our own variable-order (1–5), variable-step BDF in Nordsieck-free difference
//! form with the numerical differentiation formulas (NDF) of Shampine & Reichelt
//! (1997, "The MATLAB ODE suite", SIAM J. Sci. Comput. 18(1), ode15s), as
//! formulated in SciPy's `BDF` (backward differences of the interpolating
//! polynomial, step changes by the R·U transform), with forward sensitivities by
//! the *staggered direct* method (Caracotsios & Stewart 1985; CVODES).
//!
//! Why our own: the sensitivity equations s' = J·s + ∂f/∂θ are linear, so once a
//! step's state is accepted, the NDF corrector for every column s_k is one linear
//! solve with I − c·J(t_{n+1}, y_{n+1}) (c = h/α_q). For the small dense plants of
//! this project that is one multi-lane evaluation of J and ∂f/∂θ
//! ([`System::jacobian`], [`System::param_jacobian`]), one LU and nθ
//! back-substitutions per step. diffsol's sensitivity BDF instead runs a Newton
//! iteration per parameter through its generic vector machinery, which cost 5× the
//! plain run on the rig scene (docs/architecture.md).
//!
//! Properties the rest of the project relies on:
//! * The sensitivities are not part of the error test or the order choice, so a
//!   run with sensitivities takes exactly the steps of the run without, and its
//!   state is bit for bit the same (the identification's residual and Jacobian
//!   belong to one function).
//! * Between restart times it writes the state (and ∂y/∂θ) at requested sample
//!   times from the interpolating polynomial of the last step, locates the first
//!   change of the event function from positive to non-positive by bisection on
//!   it, and allocates nothing per step.
//! * At each restart (input kink) the method starts again at order 1 from the
//!   current state; the sensitivities carry on.

use super::{
    budget_exhausted, initial_step, left_limit, non_finite, End, EventFn, Left, Options, SampleFn,
    Stats, StepFn, System, NEWTON_TOLERANCE,
};

/// Largest order.
const MAX_ORDER: usize = 5;
/// Newton iterations per attempt (diffsol's `max_nonlinear_solver_iterations`;
/// SciPy's 4 goes with its looser Newton tolerance): at [`NEWTON_TOLERANCE`]
/// 10⁻³ a modified Newton contracting at 0.3–0.7 needs more than 4, and with 4 the
/// damped stack at rtol 1e-10 took 49 416 steps and 12 767 rejections (1800 and 9
/// with 10).
const NEWTON_MAXITER: usize = 10;
/// Fraction of Newton's tolerance below which one correction ends the iteration.
const NEWTON_FLOOR: f64 = 0.1;
/// A correction that no longer contracts ends the iteration as converged when it is
/// below this fraction of the error tolerance (see `Bdf::newton`).
const STALL: f64 = 0.1;
/// The step-size policy follows diffsol's BDF (0.18: `BdfConfig` and
/// `OdeSolverOptions` defaults) rather than SciPy's (exponent 1/(q + 1), any
/// change in 0.2…10 taken). On the rig scene (datasets/scenes/stack_rig_7s.toml)
/// SciPy's took 1063 steps with 115 rejections: the error estimate of the
/// dashpot-damped velocity, a stiff component that follows the slow solution, does
/// not fall with the step as h^(q+1), and a full-gain controller chases it. With a
/// gain below 1, growth of at most 2× and a dead band, 1041 steps and 9 rejections
/// (956 and 4 with [`NEWTON_MAXITER`] 10), at a 5× smaller error against an rtol
/// 1e-11 reference.
///
/// Integral gain: the factor is (1/err)^(GAIN/(q + 1)). diffsol's default is 0.5;
/// over the 13 shipped scenes 0.7 took 3–31 % fewer steps than 0.5 (rig: 1041
/// against 1319) with every output still within its tolerance of the reference.
const GAIN: f64 = 0.7;
/// Smallest factor after a failed error test.
const MIN_FACTOR: f64 = 0.5;
/// Largest growth, and the dead band (MAX_SHRINK, MAX_GROWTH) of factors not
/// taken at the same order (each change costs a rescale of the differences and
/// restarts the count of equal steps).
const MAX_GROWTH: f64 = 2.0;
const MAX_SHRINK: f64 = 0.9;
/// Relative change of c = h/α_q beyond which Newton's matrix I − c·J is factored
/// again (diffsol's `threshold_to_update_jacobian`, CVODE's 0.3): modified Newton
/// converges with a somewhat stale c.
const REFACTOR: f64 = 0.3;
/// The NDF coefficients κ_q (Shampine & Reichelt 1997, Table 1; κ_5 = 0: BDF5).
const KAPPA: [f64; MAX_ORDER + 1] = [0.0, -0.1850, -1.0 / 9.0, -0.0823, -0.0415, 0.0];

/// γ_q = Σ_{j≤q} 1/j, α_q = (1 − κ_q)·γ_q, and the error constants
/// κ_q·γ_q + 1/(q + 1) of the NDFs.
struct Coefficients {
    gamma: [f64; MAX_ORDER + 1],
    alpha: [f64; MAX_ORDER + 1],
    error: [f64; MAX_ORDER + 1],
}

impl Coefficients {
    fn new() -> Self {
        let mut c = Coefficients {
            gamma: [0.0; MAX_ORDER + 1],
            alpha: [0.0; MAX_ORDER + 1],
            error: [0.0; MAX_ORDER + 1],
        };
        for q in 0..=MAX_ORDER {
            c.gamma[q] = (1..=q).map(|j| 1.0 / j as f64).sum();
            c.alpha[q] = (1.0 - KAPPA[q]) * c.gamma[q];
            c.error[q] = KAPPA[q] * c.gamma[q] + 1.0 / (q + 1) as f64;
        }
        c
    }
}

/// The method's state and every buffer, made once per run.
struct Bdf {
    /// States.
    n: usize,
    /// Parameters with sensitivities (0 in a plain run).
    np: usize,
    /// States with sensitivities ([`System::dynamic_dim`]).
    ns: usize,
    /// Length of the propagated vector z = (y, s_1, …, s_np): n + ns·np.
    m: usize,
    coef: Coefficients,
    /// Backward differences D_0 … D_{MAX_ORDER+2} of z, row k at `k·m`.
    d: Vec<f64>,
    /// Scratch rows for the step-change transform.
    rows: Vec<f64>,
    order: usize,
    /// Step the differences are spaced by.
    h: f64,
    /// Steps taken at the current order and step.
    n_equal: usize,
    /// Newton's Jacobian (row-major n × n), whether it is at the current step, and
    /// the LU of I − c·J (valid for `lu_c`).
    jac: Vec<f64>,
    jac_current: bool,
    lu: Vec<f64>,
    piv: Vec<usize>,
    lu_valid: bool,
    /// The c of the factored matrix.
    lu_c: f64,
    /// The staggered sensitivity corrector: J and ∂f/∂θ at the new state, LU of
    /// I − c·J there (its leading ns × ns block).
    jac_new: Vec<f64>,
    dfdp: Vec<f64>,
    lu_s: Vec<f64>,
    piv_s: Vec<usize>,
    /// Predicted S, its Ψ and the corrector's right-hand sides (row-major ns × nθ).
    sp: Vec<f64>,
    ps: Vec<f64>,
    rs: Vec<f64>,
    /// Newton's vectors (length n) and the correction of z (length m).
    y_pred: Vec<f64>,
    y_new: Vec<f64>,
    psi: Vec<f64>,
    f: Vec<f64>,
    dy: Vec<f64>,
    scale: Vec<f64>,
    corr: Vec<f64>,
    /// z at interpolated times.
    z: Vec<f64>,
    /// Newton's convergence tolerance in units of the error tolerance:
    /// [`NEWTON_TOLERANCE`]. SciPy's max(10ε/rtol, min(0.03, √rtol))
    /// asks 2·10⁻⁵ at rtol 10⁻¹⁰, below the rounding floor of the dashpot-damped
    /// velocity (its rate is a small difference of large forces over a small
    /// mass): Newton then failed at every step size on the damped stack.
    newton_tol: f64,
}

impl Bdf {
    fn new(n: usize, ns: usize, np: usize) -> Self {
        let m = n + ns * np;
        let v = |len: usize| vec![0.0; len];
        Bdf {
            n,
            np,
            ns,
            m,
            coef: Coefficients::new(),
            d: v((MAX_ORDER + 3) * m),
            rows: v((MAX_ORDER + 1) * m),
            order: 1,
            h: 0.0,
            n_equal: 0,
            jac: v(n * n),
            jac_current: false,
            lu: v(n * n),
            piv: vec![0; n],
            lu_valid: false,
            lu_c: 0.0,
            jac_new: v(n * n),
            dfdp: v(n * np),
            lu_s: v(ns * ns),
            piv_s: vec![0; ns],
            sp: v(ns * np),
            ps: v(ns * np),
            rs: v(ns * np),
            y_pred: v(n),
            y_new: v(n),
            psi: v(n),
            f: v(n),
            dy: v(n),
            scale: v(n),
            corr: v(m),
            z: v(m),
            newton_tol: NEWTON_TOLERANCE,
        }
    }

    fn row(&self, k: usize) -> &[f64] {
        &self.d[k * self.m..(k + 1) * self.m]
    }

    /// Rescale the differences of the polynomial of order `order` from step h to
    /// factor·h (SciPy's `change_D`: D ← (R·U)ᵀ·D).
    fn change_step(&mut self, order: usize, factor: f64) {
        let q = order + 1;
        let r = transform(order, factor);
        let u = transform(order, 1.0);
        let m = self.m;
        self.rows[..q * m].fill(0.0);
        for i in 0..q {
            for j in 0..q {
                let ru: f64 = (0..q).map(|k| r[i][k] * u[k][j]).sum();
                if ru != 0.0 {
                    let (src, dst) = (
                        &self.d[i * m..(i + 1) * m],
                        &mut self.rows[j * m..(j + 1) * m],
                    );
                    for (o, s) in dst.iter_mut().zip(src) {
                        *o += ru * s;
                    }
                }
            }
        }
        self.d[..q * m].copy_from_slice(&self.rows[..q * m]);
        self.h *= factor;
        self.n_equal = 0;
    }

    /// Start at order 1 from z = (y, s) with derivative z' and step h.
    fn restart(&mut self, z: &[f64], dz: &[f64], h: f64) {
        let m = self.m;
        self.d.fill(0.0);
        self.d[..m].copy_from_slice(z);
        for (o, v) in self.d[m..2 * m].iter_mut().zip(dz) {
            *o = h * v;
        }
        self.order = 1;
        self.h = h;
        self.n_equal = 0;
        self.lu_valid = false;
    }

    /// Weighted RMS norm of c·v over the states.
    fn norm(&self, c: f64, v: &[f64]) -> f64 {
        let s: f64 = v[..self.n]
            .iter()
            .zip(&self.scale)
            .map(|(v, s)| (c * v / s).powi(2))
            .sum();
        (s / self.n as f64).sqrt()
    }

    /// The interpolating polynomial of the last step (ending at `t_new`, spacing
    /// `h`, current order) at t, for the first `len` components of z, into `out`.
    fn interpolate(&self, t_new: f64, t: f64, len: usize, out: &mut [f64]) {
        out[..len].copy_from_slice(&self.row(0)[..len]);
        let mut p = 1.0;
        for j in 1..=self.order {
            p *= (t - (t_new - (j - 1) as f64 * self.h)) / (j as f64 * self.h);
            for (o, dj) in out[..len].iter_mut().zip(&self.row(j)[..len]) {
                *o += p * dj;
            }
        }
    }

    /// Newton's iteration on y − c·f(t_new, y) + ψ = y_pred (SciPy's
    /// `solve_bdf_system`): converged?, iterations. y_new and corr[..n] hold the
    /// result.
    fn newton<S: System>(
        &mut self,
        sys: &Left<S>,
        t_new: f64,
        c: f64,
        stats: &mut Stats,
    ) -> (bool, usize) {
        let n = self.n;
        self.y_new.copy_from_slice(&self.y_pred);
        self.corr[..n].fill(0.0);
        let mut dy_norm_old: Option<f64> = None;
        for k in 0..NEWTON_MAXITER {
            sys.rhs(t_new, &self.y_new, &mut self.f);
            stats.rhs_evals += 1;
            if !self.f.iter().all(|v| v.is_finite()) {
                return (false, k + 1);
            }
            for i in 0..n {
                self.dy[i] = c * self.f[i] - self.psi[i] - self.corr[i];
            }
            lu_solve_one(&self.lu, n, &self.piv, &mut self.dy);
            let dy_norm = self.norm(1.0, &self.dy);
            let rate = dy_norm_old.map(|o| dy_norm / o);
            // A correction below a tenth of the tolerance ends the iteration whatever
            // the rate: at tight tolerances the corrections reach the rounding floor,
            // where their ratio is noise (≈ 1) and the rate test alone would fail
            // Newton at every step size (the damped stack at rtol 1e-10).
            if dy_norm <= NEWTON_FLOOR * self.newton_tol {
                for i in 0..n {
                    self.y_new[i] += self.dy[i];
                    self.corr[i] += self.dy[i];
                }
                return (true, k + 1);
            }
            if let Some(r) = rate {
                let stalled = r.is_nan() || r >= 1.0;
                // Stalled at the rounding floor: the stiff velocity's corrections stop
                // contracting at ≈ 1e-15 s⁻¹ (a small difference of large forces),
                // which at rtol 1e-10 is 10⁻² of its error tolerance and far above
                // Newton's. The iterate is then as close to the corrector's solution
                // as the arithmetic allows; a correction below STALL of the error
                // tolerance cannot decide the error test, which still judges the step.
                if stalled && dy_norm <= STALL {
                    return (true, k + 1);
                }
                if stalled
                    || r.powi((NEWTON_MAXITER - k) as i32) / (1.0 - r) * dy_norm > self.newton_tol
                {
                    return (false, k + 1);
                }
            }
            for i in 0..n {
                self.y_new[i] += self.dy[i];
                self.corr[i] += self.dy[i];
            }
            if dy_norm == 0.0 || rate.is_some_and(|r| r / (1.0 - r) * dy_norm < self.newton_tol) {
                return (true, k + 1);
            }
            if !dy_norm.is_finite() {
                return (false, k + 1);
            }
            dy_norm_old = Some(dy_norm);
        }
        (false, NEWTON_MAXITER)
    }

    /// Factor I − c·J into `lu`.
    fn factor(&mut self, c: f64, stats: &mut Stats) -> bool {
        stats.factorizations += 1;
        identity_minus(&self.jac, c, self.n, &mut self.lu);
        self.lu_c = c;
        self.lu_valid = lu_factor(&mut self.lu, self.n, &mut self.piv);
        self.lu_valid
    }

    /// One accepted step from t towards `t_end`: the new time, the step-size
    /// safety factor of its Newton iteration count, and its error norm; or why no
    /// step can be taken.
    fn step<S: System>(
        &mut self,
        sys: &Left<S>,
        o: &Options,
        atol: &[f64],
        t: f64,
        t_end: f64,
        stats: &mut Stats,
    ) -> Result<(f64, f64, f64), End> {
        let (n, m) = (self.n, self.m);
        let min_step = 10.0 * (f64::EPSILON * t.abs()).max(f64::MIN_POSITIVE);
        if self.h > o.h_max {
            self.change_step(self.order, o.h_max / self.h);
        }
        loop {
            if stats.steps + stats.rejected >= o.max_steps {
                return Err(budget_exhausted(t, o.max_steps));
            }
            if self.h.is_nan() || self.h < min_step {
                return Err(non_finite(t, &self.y_new).unwrap_or_else(|| {
                    End::Failed(format!("step size underflow at t = {t:.6e} s"))
                }));
            }
            let mut t_new = t + self.h;
            if t_new >= left_limit(t, t_end) {
                t_new = t_end;
                let factor = (t_new - t) / self.h;
                if factor != 1.0 {
                    self.change_step(self.order, factor);
                }
            }
            let q = self.order;
            let c = self.h / self.coef.alpha[q];
            for i in 0..n {
                let mut pred = 0.0;
                let mut psi = 0.0;
                for k in 0..=q {
                    let dk = self.d[k * m + i];
                    pred += dk;
                    psi += self.coef.gamma[k] * dk;
                }
                self.y_pred[i] = pred;
                self.psi[i] = psi / self.coef.alpha[q];
                self.scale[i] = atol[i] + o.rtol * pred.abs();
            }
            if (c / self.lu_c - 1.0).abs() > REFACTOR {
                self.lu_valid = false;
            }
            let (converged, iterations) = loop {
                if !self.lu_valid && !self.factor(c, stats) {
                    if self.jac_current {
                        break (false, NEWTON_MAXITER);
                    }
                } else {
                    let (ok, it) = self.newton(sys, t_new, c, stats);
                    if ok || self.jac_current {
                        break (ok, it);
                    }
                }
                sys.jacobian(t_new, &self.y_pred, &mut self.jac);
                stats.jacobians += 1;
                self.jac_current = true;
                self.lu_valid = false;
            };
            if !converged {
                stats.rejected += 1;
                self.change_step(q, 0.5);
                continue;
            }
            let safety =
                0.9 * (2 * NEWTON_MAXITER + 1) as f64 / (2 * NEWTON_MAXITER + iterations) as f64;
            for i in 0..n {
                self.scale[i] = atol[i] + o.rtol * self.y_new[i].abs();
            }
            let error = self.norm(self.coef.error[q], &self.corr);
            if error.is_nan() || error > 1.0 {
                stats.rejected += 1;
                let factor = if error.is_finite() {
                    MIN_FACTOR.max(safety * error.powf(-GAIN / (q + 1) as f64))
                } else {
                    MIN_FACTOR
                };
                self.change_step(q, factor);
                continue;
            }
            if self.np > 0 {
                self.sensitivities(sys, t_new, c)?;
            }
            self.accept();
            stats.steps += 1;
            self.jac_current = false;
            return Ok((t_new, safety, error));
        }
    }

    /// The staggered direct corrector of every sensitivity column at the accepted
    /// state: (I − c·J)·δS = c·(J·S_pred + ∂f/∂θ) − Ψ_S, S = S_pred + δS, all
    /// columns at once (S row-major ns × nθ in `sp`, `ps`, `rs`; J's leading
    /// ns × ns block, the states after it feeding back into none of these).
    fn sensitivities<S: System>(&mut self, sys: &Left<S>, t_new: f64, c: f64) -> Result<(), End> {
        let (n, ns, m, np) = (self.n, self.ns, self.m, self.np);
        sys.jacobian(t_new, &self.y_new, &mut self.jac_new);
        sys.param_jacobian(t_new, &self.y_new, &mut self.dfdp);
        for i in 0..ns {
            for j in 0..ns {
                self.lu_s[i * ns + j] = f64::from(u8::from(i == j)) - c * self.jac_new[i * n + j];
            }
        }
        if !lu_factor(&mut self.lu_s, ns, &mut self.piv_s) {
            return Err(End::Failed(format!(
                "the sensitivity corrector is singular at t = {t_new:.6e} s"
            )));
        }
        let q = self.order;
        let alpha = self.coef.alpha[q];
        for i in 0..ns {
            for p in 0..np {
                let (mut pred, mut psi) = (0.0, 0.0);
                for k in 0..=q {
                    let dk = self.d[k * m + n + p * ns + i];
                    pred += dk;
                    psi += self.coef.gamma[k] * dk;
                }
                self.sp[i * np + p] = pred;
                self.ps[i * np + p] = psi / alpha;
            }
        }
        for i in 0..ns {
            let row = &mut self.rs[i * np..(i + 1) * np];
            for ((r, g), psi) in row
                .iter_mut()
                .zip(&self.dfdp[i * np..(i + 1) * np])
                .zip(&self.ps[i * np..(i + 1) * np])
            {
                *r = c * g - psi;
            }
            for (l, &jl) in self.jac_new[i * n..i * n + ns].iter().enumerate() {
                if jl != 0.0 {
                    let cj = c * jl;
                    for (r, s) in row.iter_mut().zip(&self.sp[l * np..(l + 1) * np]) {
                        *r += cj * s;
                    }
                }
            }
        }
        lu_solve(&self.lu_s, ns, &self.piv_s, &mut self.rs, np);
        for i in 0..ns {
            for p in 0..np {
                self.corr[n + p * ns + i] = self.rs[i * np + p];
            }
        }
        Ok(())
    }

    /// Update the differences with the accepted correction (D_{q+2} = δ − D_{q+1},
    /// D_{q+1} = δ, D_k += D_{k+1} down to D_0 = z_new).
    fn accept(&mut self) {
        let (m, q) = (self.m, self.order);
        for i in 0..m {
            let c = self.corr[i];
            self.d[(q + 2) * m + i] = c - self.d[(q + 1) * m + i];
            self.d[(q + 1) * m + i] = c;
        }
        for k in (0..=q).rev() {
            let (lo, hi) = self.d.split_at_mut((k + 1) * m);
            for (a, b) in lo[k * m..].iter_mut().zip(&hi[..m]) {
                *a += b;
            }
        }
        self.n_equal += 1;
    }

    /// After the step's outputs: a new order and step once q + 1 equal steps were
    /// taken (the error estimates of orders q − 1, q, q + 1; SciPy's rule), with
    /// diffsol's gain, growth limit and dead band (see [`GAIN`]).
    fn adapt(&mut self, safety: f64, error: f64) {
        let (m, q) = (self.m, self.order);
        if self.n_equal < q + 1 {
            return;
        }
        let e_minus = if q > 1 {
            self.norm(self.coef.error[q - 1], &self.d[q * m..(q + 1) * m])
        } else {
            f64::INFINITY
        };
        let e_plus = if q < MAX_ORDER {
            self.norm(self.coef.error[q + 1], &self.d[(q + 2) * m..(q + 3) * m])
        } else {
            f64::INFINITY
        };
        let factors = [
            e_minus.powf(-GAIN / q as f64),
            error.powf(-GAIN / (q + 1) as f64),
            e_plus.powf(-GAIN / (q + 2) as f64),
        ];
        let mut best = 1;
        for (i, f) in factors.iter().enumerate() {
            if *f > factors[best] {
                best = i;
            }
        }
        let new_order = q + best - 1;
        let factor = (safety * factors[best]).clamp(MIN_FACTOR, MAX_GROWTH);
        if !factor.is_finite() || (new_order == q && factor > MAX_SHRINK && factor < MAX_GROWTH) {
            return;
        }
        self.order = new_order;
        self.change_step(new_order, factor);
    }
}

/// R(q, f) of SciPy's `compute_R`: R = cumprod over rows of M, M_0j = 1,
/// M_ij = (i − 1 − f·j)/i (i, j ≥ 1), M_i0 = 0.
fn transform(order: usize, factor: f64) -> [[f64; MAX_ORDER + 1]; MAX_ORDER + 1] {
    let mut r = [[0.0; MAX_ORDER + 1]; MAX_ORDER + 1];
    for j in 0..=order {
        r[0][j] = 1.0;
    }
    for i in 1..=order {
        for j in 1..=order {
            let mij = (i as f64 - 1.0 - factor * j as f64) / i as f64;
            r[i][j] = r[i - 1][j] * mij;
        }
    }
    r
}

/// out = I − c·J (row-major n × n).
fn identity_minus(jac: &[f64], c: f64, n: usize, out: &mut [f64]) {
    for i in 0..n {
        for j in 0..n {
            out[i * n + j] = f64::from(u8::from(i == j)) - c * jac[i * n + j];
        }
    }
}

/// LU with partial pivoting in place (row-major n × n, unit lower L below the
/// diagonal); false if singular or not finite.
fn lu_factor(a: &mut [f64], n: usize, piv: &mut [usize]) -> bool {
    for k in 0..n {
        let (mut p, mut max) = (k, -1.0);
        for i in k..n {
            let v = a[i * n + k].abs();
            if v > max {
                (p, max) = (i, v);
            }
        }
        if !(max > 0.0 && max.is_finite()) {
            return false;
        }
        piv[k] = p;
        if p != k {
            let (top, bottom) = a.split_at_mut(p * n);
            top[k * n..(k + 1) * n].swap_with_slice(&mut bottom[..n]);
        }
        let (upper, lower) = a.split_at_mut((k + 1) * n);
        let pivot = &upper[k * n..];
        let inv = 1.0 / pivot[k];
        for row in lower.chunks_exact_mut(n) {
            let l = row[k] * inv;
            row[k] = l;
            if l != 0.0 {
                for (r, u) in row[k + 1..].iter_mut().zip(&pivot[k + 1..]) {
                    *r -= l * u;
                }
            }
        }
    }
    true
}

/// Solve (L·U)·x = P·b in place for one right-hand side (Newton's).
fn lu_solve_one(a: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    for (i, &p) in piv.iter().enumerate() {
        b.swap(i, p);
    }
    for i in 1..n {
        let (done, rest) = b.split_at_mut(i);
        let s: f64 = a[i * n..i * n + i]
            .iter()
            .zip(done.iter())
            .map(|(l, y)| l * y)
            .sum();
        rest[0] -= s;
    }
    for i in (0..n).rev() {
        let (head, tail) = b.split_at_mut(i + 1);
        let s: f64 = a[i * n + i + 1..(i + 1) * n]
            .iter()
            .zip(tail.iter())
            .map(|(u, y)| u * y)
            .sum();
        head[i] = (head[i] - s) / a[i * n + i];
    }
}

/// Solve (L·U)·X = P·B in place for the `k` right-hand sides of B (row-major
/// n × k) with the factors of [`lu_factor`].
fn lu_solve(a: &[f64], n: usize, piv: &[usize], b: &mut [f64], k: usize) {
    for (i, &p) in piv.iter().enumerate() {
        if p != i {
            let (top, bottom) = b.split_at_mut(p * k);
            top[i * k..(i + 1) * k].swap_with_slice(&mut bottom[..k]);
        }
    }
    for i in 1..n {
        let (done, rest) = b.split_at_mut(i * k);
        let bi = &mut rest[..k];
        for (j, &l) in a[i * n..i * n + i].iter().enumerate() {
            if l != 0.0 {
                for (x, y) in bi.iter_mut().zip(&done[j * k..(j + 1) * k]) {
                    *x -= l * y;
                }
            }
        }
    }
    for i in (0..n).rev() {
        let (head, tail) = b.split_at_mut((i + 1) * k);
        let bi = &mut head[i * k..];
        for (j, &u) in a[i * n + i + 1..(i + 1) * n].iter().enumerate() {
            if u != 0.0 {
                for (x, y) in bi.iter_mut().zip(&tail[j * k..(j + 1) * k]) {
                    *x -= u * y;
                }
            }
        }
        let inv = 1.0 / a[i * n + i];
        for x in bi {
            *x *= inv;
        }
    }
}

/// Integrate over the restart intervals `bounds` (see [`super::run`]); `np` > 0
/// propagates the sensitivities of the system's parameters.
#[allow(clippy::too_many_arguments)]
pub(super) fn run<S: System>(
    sys: &S,
    o: &Options,
    scale: &[f64],
    bounds: &[f64],
    y: &mut [f64],
    samples: &[f64],
    sensitivities: bool,
    out: &mut SampleFn,
    step: &mut StepFn,
    event: Option<EventFn>,
    restart: &mut dyn FnMut(f64, &mut [f64]),
    stats: &mut Stats,
) -> End {
    let n = y.len();
    let np = if sensitivities { sys.n_params() } else { 0 };
    let ns = sys.dynamic_dim().min(n);
    let mut w = Bdf::new(n, ns, np);
    let atol: Vec<f64> = scale.iter().map(|s| o.atol * s).collect();
    // z = (y, s): the sensitivities of the leading ns states start at ∂y0/∂θ
    // (row-major dim × np there).
    let mut z = vec![0.0; w.m];
    if np > 0 {
        let mut s0 = vec![0.0; n * np];
        sys.initial_sensitivity(&mut s0);
        for p in 0..np {
            for i in 0..ns {
                z[n + p * ns + i] = s0[i * np + p];
            }
        }
    }
    let mut dz = vec![0.0; w.m];
    let mut si = 0;
    for (k, win) in bounds.windows(2).enumerate() {
        let (a, b) = (win[0], win[1]);
        if k > 0 {
            stats.restarts += 1;
            restart(a, y);
        }
        z[..n].copy_from_slice(y);
        let left = Left {
            sys,
            t_end: left_limit(a, b),
        };
        // z' = (f, J·s + ∂f/∂θ) at the segment's start (the input's right limit)
        left.rhs(a, y, &mut dz[..n]);
        stats.rhs_evals += 1;
        left.jacobian(a, y, &mut w.jac);
        stats.jacobians += 1;
        w.jac_current = true;
        if np > 0 {
            left.param_jacobian(a, y, &mut w.dfdp);
            for p in 0..np {
                for i in 0..ns {
                    let js: f64 = (0..ns).map(|j| w.jac[i * n + j] * z[n + p * ns + j]).sum();
                    dz[n + p * ns + i] = js + w.dfdp[i * np + p];
                }
            }
        }
        let h = initial_step(y, &dz[..n], scale, o)
            .min(o.h_init)
            .min(o.h_max)
            .min(b - a);
        w.restart(&z, &dz, h);
        let s_end = samples[si..].partition_point(|&t| t <= b) + si;
        let end = segment(
            &left,
            &mut w,
            o,
            &atol,
            a,
            b,
            y,
            &samples[si..s_end],
            out,
            step,
            event,
            stats,
        );
        si = s_end;
        if end != End::Done {
            return end;
        }
        z.copy_from_slice(w.row(0));
    }
    End::Done
}

/// Integrate from `t0` to `t1` (one segment between restarts); `y` holds the state
/// at the end (or at the event, or the last accepted state on failure).
#[allow(clippy::too_many_arguments)]
fn segment<S: System>(
    sys: &Left<S>,
    w: &mut Bdf,
    o: &Options,
    atol: &[f64],
    t0: f64,
    t1: f64,
    y: &mut [f64],
    samples: &[f64],
    out: &mut SampleFn,
    step: &mut StepFn,
    event: Option<EventFn>,
    stats: &mut Stats,
) -> End {
    let n = w.n;
    let mut t = t0;
    let mut next = 0;
    let mut g_old = event.map(|g| g(t, y));
    if g_old.is_some_and(|g| g <= 0.0) {
        // already past the event (e.g. an input jump at the restart)
        return End::Event(t);
    }
    while t < t1 {
        let (t_new, safety, error) = match w.step(sys, o, atol, t, t1, stats) {
            Ok(r) => r,
            Err(end) => return end,
        };
        // An infinite state may pass the error test (its tolerance is infinite too).
        if let Some(end) = non_finite(t_new, &w.row(0)[..n]) {
            return end;
        }
        // event: sign change of g over the step, located on the polynomial
        if let (Some(g), Some(g0)) = (event, g_old) {
            let g1 = g(t_new, &w.row(0)[..n]);
            if g0 > 0.0 && g1 <= 0.0 {
                let (mut lo, mut hi) = (t, t_new);
                let mut z = std::mem::take(&mut w.z);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    w.interpolate(t_new, mid, n, &mut z);
                    if g(mid, &z[..n]) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                while next < samples.len() && samples[next] < hi {
                    let ts = samples[next];
                    w.interpolate(t_new, ts, w.m, &mut z);
                    out(ts, &z[..n], &z[n..]);
                    next += 1;
                }
                w.interpolate(t_new, hi, n, &mut z);
                y.copy_from_slice(&z[..n]);
                w.z = z;
                return End::Event(hi);
            }
            g_old = Some(g1);
        }
        let mut z = std::mem::take(&mut w.z);
        while next < samples.len() && samples[next] <= t_new {
            let ts = samples[next];
            if ts == t_new {
                z.copy_from_slice(w.row(0));
            } else {
                w.interpolate(t_new, ts, w.m, &mut z);
            }
            out(ts, &z[..n], &z[n..]);
            next += 1;
        }
        w.z = z;
        y.copy_from_slice(&w.row(0)[..n]);
        t = t_new;
        step(t, y);
        w.adapt(safety, error);
    }
    End::Done
}
