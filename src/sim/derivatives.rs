//! Exact derivatives of the plant's right-hand side for implicit integrators and
//! forward sensitivities: the Jacobian ∂f/∂y, the parameter Jacobian ∂f/∂θ and the
//! initial-state sensitivity ∂y0/∂θ.
//!
//! **How.** The right-hand side is one generic code (`Plant::rhs_with`). Evaluated
//! in dual numbers x + ẋ·ε (ε² = 0) with one state or parameter seeded (ẋ = 1), it
//! returns f and the directional derivative of every row along that seed: one
//! column of the Jacobian, exact to rounding, through every branch the `f64` code
//! takes (the PID clamp and anti-windup, the source models, the pull-in floor of
//! the quasi-static rate: the derivative is that of the active branch). No
//! allocation: a column is written straight into the caller's matrix.
//!
//! **Primitives** (what the dual evaluation needs besides arithmetic):
//! * P(λ): ∂P/∂λ = `StrainEnergy::tangent`, ∂P/∂p = `StrainEnergy::stress_jacobian`;
//! * P'(λ) (only in the quasi-static rate without dashpot): P'' and ∂P'/∂p by central
//!   differences of `tangent` and `stress_jacobian` with h = 10⁻⁵·λ (truncation
//!   ≈ h²·P⁗/6 and rounding ≈ 10⁻¹⁶·P'/h, both ≈ 10⁻¹¹ relative);
//! * C(λ): ∂C/∂λ and ∂C'/∂λ are the C' and C'' that `capacitance()` returns (closed
//!   form for the stack, 5-point stencils for the helix, so the Jacobian is that of
//!   the right-hand side as computed); C''' (only in the quasi-static rate without
//!   dashpot, through the instantaneous stiffness): −4·C''/λ for the stack
//!   (C ∝ λ⁻²), for the helix a central difference of the returned C'' with
//!   h = 10⁻³·λ (C'' carries ≈ 10⁻¹⁰ relative rounding from its own stencil, so a
//!   smaller h would amplify it; truncation ≈ h²/6 relative: ≈ 10⁻⁷ either way);
//! * C ∝ ε for both geometries, so ∂(C, C', C'')/∂εr = (C, C', C'')/εr.
//!
//! **Parameters θ** ([`Plant::theta`]): the hyperelastic parameters (SI, model
//! order), then per integrated arm kj (Pa) and τj (s), then Nv (Pa·s), then εr. The
//! derived quantities follow θ as [`Plant::with_theta`] recomputes them:
//! G/C = 1/(ρ·ε0·εr); λ0 solves F(λ0) = −Vol·P(λ0; p) + F_load·L0 = 0 (V = 0), so
//! dλ0/dp = −(∂P/∂p)/P'(λ0) (independent of kj, τj, Nv, εr); λf = λ0; and
//! C_rest = C(λ0), dC_rest/dθ = C'(λ0)·dλ0/dθ + ∂C/∂θ. The Baumgarte constant τc is
//! a numerical setting, held fixed (see `Plant::tau_c`). For a quasi-static plant
//! without dashpot the rate does not contain Nv (the model with Nv > 0 is a
//! different, singular perturbation of it), so its Nv column holds only the
//! dissipation quadrature's Vol·λ̇².

use super::plant::{Eval, NoEquilibrium, Num, Plant};
use super::scene::Source;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Largest number of hyperelastic parameters the allocation-free derivatives handle
/// (Ogden-4 has 8).
pub const MAX_MODEL_PARAMS: usize = 16;

/// A dual number v + d·ε with ε² = 0: a value and one directional derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Dual {
    v: f64,
    d: f64,
}

impl Dual {
    #[inline]
    fn new(v: f64, d: f64) -> Dual {
        Dual { v, d }
    }
}

impl Add for Dual {
    type Output = Dual;
    #[inline]
    fn add(self, o: Dual) -> Dual {
        Dual::new(self.v + o.v, self.d + o.d)
    }
}
impl Sub for Dual {
    type Output = Dual;
    #[inline]
    fn sub(self, o: Dual) -> Dual {
        Dual::new(self.v - o.v, self.d - o.d)
    }
}
impl Mul for Dual {
    type Output = Dual;
    #[inline]
    fn mul(self, o: Dual) -> Dual {
        Dual::new(self.v * o.v, self.d * o.v + self.v * o.d)
    }
}
impl Div for Dual {
    type Output = Dual;
    #[inline]
    fn div(self, o: Dual) -> Dual {
        let q = self.v / o.v;
        Dual::new(q, (self.d - q * o.d) / o.v)
    }
}
impl Neg for Dual {
    type Output = Dual;
    #[inline]
    fn neg(self) -> Dual {
        Dual::new(-self.v, -self.d)
    }
}
impl Add<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn add(self, o: f64) -> Dual {
        Dual::new(self.v + o, self.d)
    }
}
impl Sub<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn sub(self, o: f64) -> Dual {
        Dual::new(self.v - o, self.d)
    }
}
impl Mul<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn mul(self, o: f64) -> Dual {
        Dual::new(self.v * o, self.d * o)
    }
}
impl Div<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn div(self, o: f64) -> Dual {
        Dual::new(self.v / o, self.d / o)
    }
}

impl Num for Dual {
    #[inline]
    fn cst(v: f64) -> Dual {
        Dual::new(v, 0.0)
    }
    #[inline]
    fn val(self) -> f64 {
        self.v
    }
    #[inline]
    fn sqrt(self) -> Dual {
        let s = self.v.sqrt();
        Dual::new(s, 0.5 * self.d / s)
    }
}

/// One entry of θ besides the hyperelastic parameters (which come first, in the
/// model's order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Theta {
    /// kj of integrated arm j.
    ArmK(usize),
    /// τj of integrated arm j.
    ArmTau(usize),
    /// Kelvin-Voigt Nv.
    Nv,
    /// Relative permittivity.
    EpsR,
}

/// Total derivatives of the measured outputs along one parameter θk
/// ([`Plant::output_sensitivity`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputSensitivity {
    /// dλ/dθk.
    pub stretch: f64,
    /// dL/dθk (m per unit of θk).
    pub length: f64,
    /// dC/dθk (F per unit of θk).
    pub capacitance: f64,
    /// dI/dθk (A per unit of θk).
    pub current: f64,
}

/// Relative step of the central differences of P' and ∂P/∂p in λ (see module doc).
const H_STRESS: f64 = 1e-5;
/// Relative step of the central difference of the helix's C'' (see module doc).
const H_CAP: f64 = 1e-3;

/// Direction in state space of a seed.
#[derive(Clone, Copy)]
enum StateSeed<'a> {
    /// No state direction.
    None,
    /// ∂/∂y_k.
    Unit(usize),
    /// The directional derivative along v (J·v in one evaluation).
    Along(&'a [f64]),
}

/// Direction in parameter space of a seed.
#[derive(Clone, Copy)]
enum ThetaSeed<'a> {
    /// No parameter direction.
    None,
    /// ∂/∂θ_k.
    Unit(usize),
    /// The directional derivative along w: every θk seeded with wk in one
    /// evaluation, (∂f/∂θ)·w (as J·v is for the state).
    Along(&'a [f64]),
}

/// The plant read with one derivative direction in state space (∂/∂y_k or along a
/// vector) and one in parameter space (∂/∂θ_k or along a vector, with the chain
/// through λ0 into λf and C_rest): the dual part is the sum of both.
struct Seeded<'a> {
    p: &'a Plant,
    /// Seeded state direction.
    state: StateSeed<'a>,
    /// Seeded parameter direction.
    theta: ThetaSeed<'a>,
    /// Whether the parameter direction moves a hyperelastic parameter (else P does
    /// not depend on it and `stress_jacobian` is not needed).
    model: bool,
    /// dλ0/dθ along the seed (= dλf/dθ).
    dlam0: f64,
    /// dC_rest/dθ along the seed.
    dc_rest: f64,
}

impl<'a> Seeded<'a> {
    /// Seeded along `state` in state space and `theta` in parameter space.
    fn new(p: &'a Plant, state: StateSeed<'a>, theta: ThetaSeed<'a>) -> Seeded<'a> {
        let np = p.params.len();
        let model = match theta {
            ThetaSeed::None => false,
            ThetaSeed::Unit(k) => k < np,
            ThetaSeed::Along(w) => w[..np].iter().any(|&x| x != 0.0),
        };
        let (dlam0, dc_rest) = match theta {
            ThetaSeed::None => (0.0, 0.0),
            ThetaSeed::Unit(k) => p.rest_derivatives[k],
            ThetaSeed::Along(w) => p
                .rest_derivatives
                .iter()
                .zip(w)
                .fold((0.0, 0.0), |(a, b), (d, w)| (a + w * d.0, b + w * d.1)),
        };
        Seeded {
            p,
            state,
            theta,
            model,
            dlam0,
            dc_rest,
        }
    }

    /// The weight of θ entry `th` in the parameter direction.
    #[inline]
    fn is(&self, th: Theta) -> f64 {
        match self.theta {
            ThetaSeed::None => 0.0,
            ThetaSeed::Unit(k) => (self.p.theta_index(th) == k) as u8 as f64,
            ThetaSeed::Along(w) => w[self.p.theta_index(th)],
        }
    }

    /// ∂P/∂p·w at λ (Pa): P's derivative along the parameter direction.
    #[inline]
    fn stress_param(&self, lam: f64) -> f64 {
        if !self.model {
            return 0.0;
        }
        let np = self.p.params.len();
        let mut buf = [0.0; MAX_MODEL_PARAMS];
        self.p.stress_jacobian(lam, &mut buf[..np]);
        match self.theta {
            ThetaSeed::Unit(k) => buf[k],
            ThetaSeed::Along(w) => buf[..np].iter().zip(w).map(|(a, b)| a * b).sum(),
            ThetaSeed::None => 0.0,
        }
    }
}

impl Eval for Seeded<'_> {
    type T = Dual;
    #[inline]
    fn y(&self, y: &[f64], i: usize) -> Dual {
        let d = match self.state {
            StateSeed::None => 0.0,
            StateSeed::Unit(k) => (k == i) as u8 as f64,
            StateSeed::Along(v) => v[i],
        };
        Dual::new(y[i], d)
    }
    #[inline]
    fn arm(&self, j: usize) -> (Dual, Dual) {
        let (k, tau) = self.p.arms[j];
        (
            Dual::new(k, self.is(Theta::ArmK(j))),
            Dual::new(tau, self.is(Theta::ArmTau(j))),
        )
    }
    #[inline]
    fn nv(&self) -> Dual {
        Dual::new(self.p.nv, self.is(Theta::Nv))
    }
    #[inline]
    fn g_per_c(&self) -> Dual {
        let g = self.p.g_per_c;
        Dual::new(g, -g / self.p.eps_r * self.is(Theta::EpsR))
    }
    #[inline]
    fn lam_f(&self) -> Dual {
        Dual::new(self.p.lam_f, self.dlam0)
    }
    #[inline]
    fn c_rest(&self) -> Dual {
        Dual::new(self.p.c_rest, self.dc_rest)
    }
    #[inline]
    fn stress(&self, lam: Dual) -> Dual {
        let d = self.p.tangent(lam.v) * lam.d + self.stress_param(lam.v);
        Dual::new(self.p.stress(lam.v), d)
    }
    #[inline]
    fn tangent(&self, lam: Dual) -> Dual {
        let h = H_STRESS * lam.v;
        let mut d = 0.0;
        if lam.d != 0.0 {
            d += (self.p.tangent(lam.v + h) - self.p.tangent(lam.v - h)) / (2.0 * h) * lam.d;
        }
        if self.model {
            d += (self.stress_param(lam.v + h) - self.stress_param(lam.v - h)) / (2.0 * h);
        }
        Dual::new(self.p.tangent(lam.v), d)
    }
    #[inline]
    fn capacitance(&self, lam: Dual) -> [Dual; 3] {
        let (c, c1, c2) = self.p.capacitance(lam.v);
        let c3 = if lam.d != 0.0 {
            self.p.capacitance_d3(lam.v, c2)
        } else {
            0.0
        };
        let de = self.is(Theta::EpsR) / self.p.eps_r;
        [
            Dual::new(c, c1 * lam.d + c * de),
            Dual::new(c1, c2 * lam.d + c1 * de),
            Dual::new(c2, c3 * lam.d + c2 * de),
        ]
    }
}

impl Plant {
    /// C'''(λ) given C''(λ): −4·C''/λ for the stack (C ∝ λ⁻²), a central difference
    /// of `capacitance()`'s C'' for the helix (see the module documentation).
    fn capacitance_d3(&self, lam: f64, d2c: f64) -> f64 {
        match self.actuator {
            super::scene::Actuator::Stack(_) => -4.0 * d2c / lam,
            super::scene::Actuator::Helix(_) => {
                let h = H_CAP * lam;
                (self.capacitance(lam + h).2 - self.capacitance(lam - h).2) / (2.0 * h)
            }
        }
    }

    /// ∂P/∂p at λ (Pa per unit of each p_k) into `out` (the model's parameter count,
    /// at most [`MAX_MODEL_PARAMS`]), allocation-free.
    fn stress_jacobian(&self, lam: f64, out: &mut [f64]) {
        assert!(
            out.len() <= MAX_MODEL_PARAMS,
            "{} hyperelastic parameters: more than MAX_MODEL_PARAMS",
            out.len()
        );
        self.model()
            .stress_jacobian(&self.params, self.mode, lam, out);
    }

    /// (dλ0/dθk, dC_rest/dθk) for every entry of θ: λ0 solves
    /// −Vol·P(λ0) + F_load·L0 = 0, so dλ0/dp = −(∂P/∂p)/P'(λ0) (zero for the other
    /// parameters); dC_rest/dθ = C'(λ0)·dλ0/dθ + ∂C/∂θ, ∂C/∂εr = C/εr.
    pub(super) fn rest_state_derivatives(&self) -> Vec<(f64, f64)> {
        let np = self.params.len();
        let mut dp = [0.0; MAX_MODEL_PARAMS];
        self.stress_jacobian(self.lam0, &mut dp[..np]);
        let (tangent, dc) = (self.tangent(self.lam0), self.capacitance(self.lam0).1);
        (0..self.n_theta())
            .map(|k| {
                let dlam0 = if k < np { -dp[k] / tangent } else { 0.0 };
                let eps = (k == self.n_theta() - 1) as u8 as f64 * self.c_rest / self.eps_r;
                (dlam0, dc * dlam0 + eps)
            })
            .collect()
    }

    /// Index in θ of an entry.
    #[inline]
    fn theta_index(&self, th: Theta) -> usize {
        let (np, na) = (self.params.len(), self.arms.len());
        match th {
            Theta::ArmK(j) => np + 2 * j,
            Theta::ArmTau(j) => np + 2 * j + 1,
            Theta::Nv => np + 2 * na,
            Theta::EpsR => np + 2 * na + 1,
        }
    }

    /// Number of parameters nθ.
    pub fn n_theta(&self) -> usize {
        self.params.len() + 2 * self.arms.len() + 2
    }

    /// Names (with SI units) of the entries of θ: the hyperelastic parameters, then
    /// `armJ.k (Pa)`, `armJ.tau (s)` for the integrated arms (numbered among them),
    /// `nv (Pa s)`, `eps_r`.
    pub fn sensitivity_params(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .model()
            .params()
            .iter()
            .map(|p| match p.unit {
                "1" => p.name.clone(),
                u => format!("{} ({u})", p.name),
            })
            .collect();
        for j in 1..=self.arms.len() {
            names.push(format!("arm{j}.k (Pa)"));
            names.push(format!("arm{j}.tau (s)"));
        }
        names.push("nv (Pa s)".into());
        names.push("eps_r".into());
        names
    }

    /// The parameter vector θ (see [`Plant::sensitivity_params`]).
    pub fn theta(&self) -> Vec<f64> {
        let mut th = self.params.clone();
        for &(k, tau) in &self.arms {
            th.push(k);
            th.push(tau);
        }
        th.push(self.nv);
        th.push(self.eps_r);
        th
    }

    /// The plant with parameters θ, every derived quantity (ε, G/C, λ0, λf, C_rest)
    /// recomputed as [`Plant::new`] does; τc is kept. Err when θ has no stable rest
    /// state (no run starts from it).
    pub fn with_theta(&self, theta: &[f64]) -> Result<Plant, NoEquilibrium> {
        assert_eq!(theta.len(), self.n_theta(), "θ length");
        let mut p = self.clone();
        let np = p.params.len();
        p.params.copy_from_slice(&theta[..np]);
        for (j, a) in p.arms.iter_mut().enumerate() {
            *a = (theta[np + 2 * j], theta[np + 2 * j + 1]);
        }
        p.nv = theta[theta.len() - 2];
        p.eps_r = theta[theta.len() - 1];
        p.derive()?;
        Ok(p)
    }

    /// The Jacobian ∂f/∂y of the right-hand side at (t, y), row-major n×n into `jac`
    /// (∂f_i/∂y_j at `jac[i·n + j]`); the quadrature columns are zero. Exact forward
    /// differentiation of the right-hand side (module documentation). No allocation.
    pub fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) {
        let l = self.layout();
        let n = l.n;
        assert_eq!(jac.len(), n * n, "jacobian: n×n buffer");
        for k in 0..n {
            if k < l.quad {
                let e = Seeded::new(self, StateSeed::Unit(k), ThetaSeed::None);
                self.rhs_with(&e, t, y, |i, v| jac[i * n + k] = v.d);
            } else {
                (0..n).for_each(|i| jac[i * n + k] = 0.0);
            }
        }
    }

    /// J·v, the Jacobian applied to `v`, in one forward evaluation (what implicit
    /// integrators need); `out` has n entries. No allocation.
    pub fn jacobian_times(&self, t: f64, y: &[f64], v: &[f64], out: &mut [f64]) {
        let e = Seeded::new(self, StateSeed::Along(v), ThetaSeed::None);
        self.rhs_with(&e, t, y, |i, d| out[i] = d.d);
    }

    /// (∂f/∂θ)·w at fixed (t, y), including the chain through λ0 into λf and C_rest,
    /// in one forward evaluation with every θk seeded with wk (what forward
    /// sensitivities need per parameter direction); `out` has n entries. No
    /// allocation.
    pub fn param_jacobian_times(&self, t: f64, y: &[f64], w: &[f64], out: &mut [f64]) {
        let e = Seeded::new(self, StateSeed::None, ThetaSeed::Along(w));
        self.rhs_with(&e, t, y, |i, d| out[i] = d.d);
    }

    /// J·s + ∂f/∂θk, the rate of the sensitivity column s = ∂y/∂θk, in one forward
    /// evaluation seeded along s in state space and θk in parameter space. No
    /// allocation.
    pub fn sensitivity_rate(&self, t: f64, y: &[f64], s: &[f64], k: usize, out: &mut [f64]) {
        let e = Seeded::new(self, StateSeed::Along(s), ThetaSeed::Unit(k));
        self.rhs_with(&e, t, y, |i, d| out[i] = d.d);
    }

    /// The total derivatives d/dθk of the measured outputs at (t, y) given the state
    /// sensitivity s = ∂y/∂θk: dλ/dθk = s0, dL/dθk = L0·s0, and the capacitance and
    /// the current (which depends on λ̇, V and the source state) as
    /// ∂out/∂y·s + ∂out/∂θk, by one forward evaluation of the same output code that
    /// writes the samples ([`Plant::output`]), seeded along s
    /// and θk. No allocation.
    pub fn output_sensitivity(&self, t: f64, y: &[f64], s: &[f64], k: usize) -> OutputSensitivity {
        let e = Seeded::new(self, StateSeed::Along(s), ThetaSeed::Unit(k));
        let el = self.output_with(&e, t, y, &self.layout());
        OutputSensitivity {
            stretch: s[0],
            length: self.l0 * s[0],
            capacitance: el.capacitance.d,
            current: el.current.d,
        }
    }

    /// ∂f/∂θ at fixed (t, y), row-major n×nθ into `dfdp` (∂f_i/∂θ_k at
    /// `dfdp[i·nθ + k]`), including the chain through λ0 into λf and C_rest. No
    /// allocation.
    pub fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut [f64]) {
        let (n, m) = (self.layout().n, self.n_theta());
        assert_eq!(dfdp.len(), n * m, "param_jacobian: n×nθ buffer");
        for k in 0..m {
            let e = Seeded::new(self, StateSeed::None, ThetaSeed::Unit(k));
            self.rhs_with(&e, t, y, |i, v| dfdp[i * m + k] = v.d);
        }
    }

    /// ∂y0/∂θ of [`Plant::initial_state`], row-major n×nθ into `out`:
    /// * λ0: dλ0/dp = −(∂P/∂p)/P'(λ0) for the hyperelastic parameters;
    /// * the derivative filter D0 = r(0) − ŷ(λ0) = r(0): ŷ(λ0) = 1 − sqrt(C_rest/C(λ0))
    ///   is zero for every θ (C_rest is C(λ0)), so its row is zero, as is the
    ///   rise-time source's V0 = u0 (the input, or the PID's Kp·r(0) clamped);
    /// * the resistance source's charge q0 = u0·C(λ0):
    ///   dq0/dθ = u0·(C'(λ0)·dλ0/dθ + ∂C/∂θ), ∂C/∂εr = C/εr;
    /// * arm stresses, integrator state and quadratures start at zero.
    pub fn initial_state_sensitivity(&self, out: &mut [f64]) {
        let l = self.layout();
        let (n, m) = (l.n, self.n_theta());
        assert_eq!(out.len(), n * m, "initial_state_sensitivity: n×nθ buffer");
        out.fill(0.0);
        let y0 = self.initial_state();
        let (c, dc, _) = self.capacitance(self.lam0);
        for k in 0..m {
            let e = Seeded::new(self, StateSeed::None, ThetaSeed::Unit(k));
            out[k] = e.dlam0;
            if let (Some(i), Source::Resistance { .. }) = (l.src, self.source) {
                let u0 = y0[i] / c;
                out[i * m + k] = u0 * (dc * e.dlam0 + e.is(Theta::EpsR) * c / self.eps_r);
            }
        }
    }
}
