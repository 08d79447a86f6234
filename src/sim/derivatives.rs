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

use super::plant::{Eval, Num, Plant};
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

/// One entry of θ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Theta {
    /// Hyperelastic parameter (index in the model's order).
    Model(usize),
    /// kj of integrated arm j.
    ArmK(usize),
    /// τj of integrated arm j.
    ArmTau(usize),
    /// Kelvin-Voigt Nv.
    Nv,
    /// Relative permittivity.
    EpsR,
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

/// The plant read with one derivative direction: in state space (∂/∂y_k or along a
/// vector) or a parameter (∂/∂θ_k, with the chain through λ0 into λf and C_rest).
struct Seeded<'a> {
    p: &'a Plant,
    /// Seeded state direction.
    state: StateSeed<'a>,
    /// Seeded parameter.
    theta: Option<Theta>,
    /// dλ0/dθ along the seed (= dλf/dθ).
    dlam0: f64,
    /// dC_rest/dθ along the seed.
    dc_rest: f64,
}

impl<'a> Seeded<'a> {
    fn state(p: &'a Plant, k: usize) -> Seeded<'a> {
        Seeded {
            p,
            state: StateSeed::Unit(k),
            theta: None,
            dlam0: 0.0,
            dc_rest: 0.0,
        }
    }

    fn along(p: &'a Plant, v: &'a [f64]) -> Seeded<'a> {
        Seeded {
            state: StateSeed::Along(v),
            ..Seeded::state(p, 0)
        }
    }

    fn theta(p: &'a Plant, k: usize) -> Seeded<'a> {
        let th = p.theta_kind(k);
        let dlam0 = p.rest_stretch_derivative(th);
        let dc_rest = p.capacitance(p.lam0).1 * dlam0
            + match th {
                Theta::EpsR => p.c_rest / p.eps_r,
                _ => 0.0,
            };
        Seeded {
            p,
            state: StateSeed::None,
            theta: Some(th),
            dlam0,
            dc_rest,
        }
    }

    #[inline]
    fn is(&self, th: Theta) -> f64 {
        (self.theta == Some(th)) as u8 as f64
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
        let mut d = self.p.tangent(lam.v) * lam.d;
        if let Some(Theta::Model(k)) = self.theta {
            d += self.p.stress_param_derivative(lam.v, k);
        }
        Dual::new(self.p.stress(lam.v), d)
    }
    #[inline]
    fn tangent(&self, lam: Dual) -> Dual {
        let h = H_STRESS * lam.v;
        let mut d = 0.0;
        if lam.d != 0.0 {
            d += (self.p.tangent(lam.v + h) - self.p.tangent(lam.v - h)) / (2.0 * h) * lam.d;
        }
        if let Some(Theta::Model(k)) = self.theta {
            d += (self.p.stress_param_derivative(lam.v + h, k)
                - self.p.stress_param_derivative(lam.v - h, k))
                / (2.0 * h);
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

    /// ∂P/∂p_k at λ (Pa per unit of p_k), allocation-free.
    fn stress_param_derivative(&self, lam: f64, k: usize) -> f64 {
        let np = self.params.len();
        assert!(
            np <= MAX_MODEL_PARAMS,
            "{np} hyperelastic parameters: more than MAX_MODEL_PARAMS"
        );
        let mut buf = [0.0; MAX_MODEL_PARAMS];
        self.model()
            .stress_jacobian(&self.params, self.mode, lam, &mut buf[..np]);
        buf[k]
    }

    /// dλ0/dθ: λ0 solves −Vol·P(λ0) + F_load·L0 = 0, so dλ0/dp = −(∂P/∂p)/P'(λ0);
    /// zero for the other parameters.
    fn rest_stretch_derivative(&self, th: Theta) -> f64 {
        match th {
            Theta::Model(k) => {
                -self.stress_param_derivative(self.lam0, k) / self.tangent(self.lam0)
            }
            _ => 0.0,
        }
    }

    fn theta_kind(&self, k: usize) -> Theta {
        let (np, na) = (self.params.len(), self.arms.len());
        match k {
            k if k < np => Theta::Model(k),
            k if k < np + 2 * na => match (k - np) % 2 {
                0 => Theta::ArmK((k - np) / 2),
                _ => Theta::ArmTau((k - np) / 2),
            },
            k if k == np + 2 * na => Theta::Nv,
            k if k == np + 2 * na + 1 => Theta::EpsR,
            _ => panic!("θ has {} entries, not {}", np + 2 * na + 2, k + 1),
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

    /// ∂ln C/∂θ at fixed λ: C ∝ ε (Eq. 3.22, 4.47), so 1/εr for εr and zero for the
    /// mechanical parameters.
    pub fn capacitance_log_sensitivity(&self) -> Vec<f64> {
        (0..self.n_theta())
            .map(|k| match self.theta_kind(k) {
                Theta::EpsR => 1.0 / self.eps_r,
                _ => 0.0,
            })
            .collect()
    }

    /// The plant with parameters θ, every derived quantity (ε, G/C, λ0, λf, C_rest)
    /// recomputed as [`Plant::new`] does; τc is kept.
    pub fn with_theta(&self, theta: &[f64]) -> Plant {
        assert_eq!(theta.len(), self.n_theta(), "θ length");
        let mut p = self.clone();
        let np = p.params.len();
        p.params.copy_from_slice(&theta[..np]);
        for (j, a) in p.arms.iter_mut().enumerate() {
            *a = (theta[np + 2 * j], theta[np + 2 * j + 1]);
        }
        p.nv = theta[theta.len() - 2];
        p.eps_r = theta[theta.len() - 1];
        p.derive();
        p
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
                self.rhs_with(&Seeded::state(self, k), t, y, |i, v| jac[i * n + k] = v.d);
            } else {
                (0..n).for_each(|i| jac[i * n + k] = 0.0);
            }
        }
    }

    /// J·v, the Jacobian applied to `v`, in one forward evaluation (what implicit
    /// integrators need); `out` has n entries. No allocation.
    pub fn jacobian_times(&self, t: f64, y: &[f64], v: &[f64], out: &mut [f64]) {
        self.rhs_with(&Seeded::along(self, v), t, y, |i, d| out[i] = d.d);
    }

    /// ∂f/∂θ at fixed (t, y), row-major n×nθ into `dfdp` (∂f_i/∂θ_k at
    /// `dfdp[i·nθ + k]`), including the chain through λ0 into λf and C_rest. No
    /// allocation.
    pub fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut [f64]) {
        let (n, m) = (self.layout().n, self.n_theta());
        assert_eq!(dfdp.len(), n * m, "param_jacobian: n×nθ buffer");
        for k in 0..m {
            self.rhs_with(&Seeded::theta(self, k), t, y, |i, v| dfdp[i * m + k] = v.d);
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
            let th = self.theta_kind(k);
            let dlam0 = self.rest_stretch_derivative(th);
            out[k] = dlam0;
            if let (Some(i), Source::Resistance { .. }) = (l.src, self.source) {
                let u0 = y0[i] / c;
                let dc_dth = match th {
                    Theta::EpsR => c / self.eps_r,
                    _ => 0.0,
                };
                out[i * m + k] = u0 * (dc * dlam0 + dc_dth);
            }
        }
    }
}
