//! Exact derivatives of the plant's right-hand side for implicit integrators and
//! forward sensitivities: the Jacobian ∂f/∂y, the parameter Jacobian ∂f/∂θ and the
//! initial-state sensitivity ∂y0/∂θ.
//!
//! **How.** The right-hand side is one generic code (`Plant::rhs_with`). Evaluated
//! in dual numbers x + Σ ẋ_l·ε_l (ε_l·ε_m = 0) with one state or parameter direction
//! seeded per lane, it returns f and the directional derivative of every row along
//! each lane's seed: one column of the Jacobian per lane, exact to rounding, through
//! every branch the `f64` code takes (the PID clamp and anti-windup, the source
//! models, the pull-in floor of the quasi-static rate: the derivative is that of the
//! active branch). A dense Jacobian ∂f/∂y or ∂f/∂θ, or the outputs' derivatives to
//! every θk, take one evaluation of up to 16 lanes ([`width`]): the material
//! functions, the input and the capacitance are evaluated once, only the lanes'
//! arithmetic repeats (∂f/∂θ with 9 constants: 3 single-direction evaluations' worth
//! of instructions instead of 9). No allocation: a column is written straight into
//! the caller's matrix.
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

/// A dual number with `L` lanes, v + Σ d_l·ε_l with ε_l·ε_m = 0: a value and `L`
/// directional derivatives carried through one evaluation. One lane is the classic
/// dual number (J·v, (∂f/∂θ)·w); several lanes give several columns of a Jacobian
/// for the price of one value evaluation (the material functions, the input and the
/// capacitance are evaluated once; only the lanes' arithmetic repeats).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Dual<const L: usize> {
    v: f64,
    d: [f64; L],
}

impl<const L: usize> Dual<L> {
    #[inline]
    fn new(v: f64, d: [f64; L]) -> Dual<L> {
        Dual { v, d }
    }
    /// Every lane of `self.d` mapped with `f(lane, d)`.
    #[inline]
    fn map(self, v: f64, f: impl Fn(usize, f64) -> f64) -> Dual<L> {
        Dual::new(v, std::array::from_fn(|l| f(l, self.d[l])))
    }
}

impl<const L: usize> Add for Dual<L> {
    type Output = Dual<L>;
    #[inline]
    fn add(self, o: Dual<L>) -> Dual<L> {
        self.map(self.v + o.v, |l, d| d + o.d[l])
    }
}
impl<const L: usize> Sub for Dual<L> {
    type Output = Dual<L>;
    #[inline]
    fn sub(self, o: Dual<L>) -> Dual<L> {
        self.map(self.v - o.v, |l, d| d - o.d[l])
    }
}
impl<const L: usize> Mul for Dual<L> {
    type Output = Dual<L>;
    /// The product rule.
    #[allow(clippy::suspicious_arithmetic_impl)]
    #[inline]
    fn mul(self, o: Dual<L>) -> Dual<L> {
        self.map(self.v * o.v, |l, d| d * o.v + self.v * o.d[l])
    }
}
impl<const L: usize> Div for Dual<L> {
    type Output = Dual<L>;
    /// The quotient rule.
    #[allow(clippy::suspicious_arithmetic_impl)]
    #[inline]
    fn div(self, o: Dual<L>) -> Dual<L> {
        let q = self.v / o.v;
        self.map(q, |l, d| (d - q * o.d[l]) / o.v)
    }
}
impl<const L: usize> Neg for Dual<L> {
    type Output = Dual<L>;
    #[inline]
    fn neg(self) -> Dual<L> {
        self.map(-self.v, |_, d| -d)
    }
}
impl<const L: usize> Add<f64> for Dual<L> {
    type Output = Dual<L>;
    #[inline]
    fn add(self, o: f64) -> Dual<L> {
        Dual::new(self.v + o, self.d)
    }
}
impl<const L: usize> Sub<f64> for Dual<L> {
    type Output = Dual<L>;
    #[inline]
    fn sub(self, o: f64) -> Dual<L> {
        Dual::new(self.v - o, self.d)
    }
}
impl<const L: usize> Mul<f64> for Dual<L> {
    type Output = Dual<L>;
    #[inline]
    fn mul(self, o: f64) -> Dual<L> {
        self.map(self.v * o, |_, d| d * o)
    }
}
impl<const L: usize> Div<f64> for Dual<L> {
    type Output = Dual<L>;
    #[inline]
    fn div(self, o: f64) -> Dual<L> {
        self.map(self.v / o, |_, d| d / o)
    }
}

impl<const L: usize> Num for Dual<L> {
    #[inline]
    fn cst(v: f64) -> Dual<L> {
        Dual::new(v, [0.0; L])
    }
    #[inline]
    fn val(self) -> f64 {
        self.v
    }
    #[inline]
    fn sqrt(self) -> Dual<L> {
        let s = self.v.sqrt();
        self.map(s, |_, d| 0.5 * d / s)
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
enum ThetaSeed {
    /// No parameter direction.
    None,
    /// ∂/∂θ_k.
    Unit(usize),
}

/// The seed of one lane: a direction in state space and one in parameter space
/// (the lane's derivative is the sum of both).
#[derive(Clone, Copy)]
struct Seed<'a> {
    state: StateSeed<'a>,
    theta: ThetaSeed,
}

/// No direction (an unused lane).
const UNSEEDED: Seed<'static> = Seed {
    state: StateSeed::None,
    theta: ThetaSeed::None,
};

/// The plant read with `L` derivative lanes, each seeded with a direction in state
/// space (∂/∂y_k or along a vector) and one in parameter space (∂/∂θ_k or along a
/// vector, with the chain through λ0 into λf and C_rest).
struct Seeded<'a, const L: usize> {
    p: &'a Plant,
    /// The lanes' seeds.
    seeds: [Seed<'a>; L],
    /// Whether some lane's parameter direction moves a hyperelastic parameter (else
    /// P does not depend on the seeds and `stress_jacobian` is not needed).
    model: bool,
    /// dλ0/dθ along each lane (= dλf/dθ).
    dlam0: [f64; L],
    /// dC_rest/dθ along each lane.
    dc_rest: [f64; L],
}

impl<'a, const L: usize> Seeded<'a, L> {
    /// Lane l seeded with `seed(l)` for l < `lanes` (at most L), the others unused.
    fn new(p: &'a Plant, lanes: usize, seed: impl Fn(usize) -> Seed<'a>) -> Seeded<'a, L> {
        let seeds: [Seed; L] = std::array::from_fn(|l| if l < lanes { seed(l) } else { UNSEEDED });
        let np = p.params.len();
        let model = seeds.iter().any(|s| match s.theta {
            ThetaSeed::None => false,
            ThetaSeed::Unit(k) => k < np,
        });
        let rest = |l: usize| match seeds[l].theta {
            ThetaSeed::None => (0.0, 0.0),
            ThetaSeed::Unit(k) => p.rest_derivatives[k],
        };
        Seeded {
            p,
            seeds,
            model,
            dlam0: std::array::from_fn(|l| rest(l).0),
            dc_rest: std::array::from_fn(|l| rest(l).1),
        }
    }

    /// The weight of θ entry `th` in each lane's parameter direction.
    #[inline]
    fn is(&self, th: Theta) -> [f64; L] {
        let i = self.p.theta_index(th);
        std::array::from_fn(|l| match self.seeds[l].theta {
            ThetaSeed::Unit(k) if k == i => 1.0,
            _ => 0.0,
        })
    }

    /// ∂P/∂p·w at λ (Pa) for each lane: P's derivative along its parameter direction.
    #[inline]
    fn stress_param(&self, lam: f64) -> [f64; L] {
        if !self.model {
            return [0.0; L];
        }
        let np = self.p.params.len();
        let mut buf = [0.0; MAX_MODEL_PARAMS];
        self.p.stress_jacobian(lam, &mut buf[..np]);
        std::array::from_fn(|l| match self.seeds[l].theta {
            ThetaSeed::Unit(k) if k < np => buf[k],
            _ => 0.0,
        })
    }
}

impl<const L: usize> Eval for Seeded<'_, L> {
    type T = Dual<L>;
    #[inline]
    fn y(&self, y: &[f64], i: usize) -> Dual<L> {
        Dual::new(
            y[i],
            std::array::from_fn(|l| match self.seeds[l].state {
                StateSeed::None => 0.0,
                StateSeed::Unit(k) => (k == i) as u8 as f64,
                // a direction shorter than the state leaves the trailing states
                // (quadratures no rate reads) unmoved
                StateSeed::Along(v) => v.get(i).copied().unwrap_or(0.0),
            }),
        )
    }
    #[inline]
    fn arm(&self, j: usize) -> (Dual<L>, Dual<L>) {
        let (k, tau) = self.p.arms[j];
        (
            Dual::new(k, self.is(Theta::ArmK(j))),
            Dual::new(tau, self.is(Theta::ArmTau(j))),
        )
    }
    #[inline]
    fn nv(&self) -> Dual<L> {
        Dual::new(self.p.nv, self.is(Theta::Nv))
    }
    #[inline]
    fn g_per_c(&self) -> Dual<L> {
        let g = self.p.g_per_c;
        let k = -g / self.p.eps_r;
        Dual::new(g, self.is(Theta::EpsR).map(|w| k * w))
    }
    #[inline]
    fn lam_f(&self) -> Dual<L> {
        Dual::new(self.p.lam_f, self.dlam0)
    }
    #[inline]
    fn c_rest(&self) -> Dual<L> {
        Dual::new(self.p.c_rest, self.dc_rest)
    }
    #[inline]
    fn stress(&self, lam: Dual<L>) -> Dual<L> {
        let t = self.p.tangent(lam.v);
        let sp = self.stress_param(lam.v);
        lam.map(self.p.stress(lam.v), |l, d| t * d + sp[l])
    }
    #[inline]
    fn tangent(&self, lam: Dual<L>) -> Dual<L> {
        let h = H_STRESS * lam.v;
        let mut d = [0.0; L];
        if lam.d.iter().any(|&x| x != 0.0) {
            let dt = (self.p.tangent(lam.v + h) - self.p.tangent(lam.v - h)) / (2.0 * h);
            d = lam.d.map(|x| dt * x);
        }
        if self.model {
            let (up, down) = (self.stress_param(lam.v + h), self.stress_param(lam.v - h));
            for l in 0..L {
                d[l] += (up[l] - down[l]) / (2.0 * h);
            }
        }
        Dual::new(self.p.tangent(lam.v), d)
    }
    #[inline]
    fn capacitance(&self, lam: Dual<L>) -> [Dual<L>; 3] {
        let (c, c1, c2) = self.p.capacitance(lam.v);
        let c3 = if lam.d.iter().any(|&x| x != 0.0) {
            self.p.capacitance_d3(lam.v, c2)
        } else {
            0.0
        };
        let de = self.is(Theta::EpsR).map(|w| w / self.p.eps_r);
        [
            lam.map(c, |l, d| c1 * d + c * de[l]),
            lam.map(c1, |l, d| c2 * d + c1 * de[l]),
            lam.map(c2, |l, d| c3 * d + c2 * de[l]),
        ]
    }
}

/// Lanes per evaluation for `count` directions: the smallest of 4, 8 and 16 that
/// holds them (more are done 16 at a time).
fn width(count: usize) -> usize {
    match count {
        0..=4 => 4,
        5..=8 => 8,
        9..=12 => 12,
        _ => 16,
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

    /// Carry the forward sensitivities of the θ entries in `mask` only (bit k:
    /// entry k; bits beyond θ ignored), in θ's order: a search that holds some
    /// constants propagates no columns it does not read. The integrators' error
    /// control looks at the states alone, so the columns carried are the same
    /// numbers as in a run that carries every column.
    pub fn keep_sensitivities(&mut self, mask: u128) {
        self.sens_columns = (0..self.n_theta().min(u128::BITS as usize))
            .filter(|&k| mask >> k & 1 == 1)
            .collect();
    }

    /// The θ entries whose sensitivities a run carries (column k is entry
    /// `sensitivity_columns()[k]`).
    pub fn sensitivity_columns(&self) -> &[usize] {
        &self.sens_columns
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

    /// `pass` over `count` lanes seeded with `seed(lane)`, in evaluations of
    /// [`width`]`(count)` lanes each. No allocation.
    fn in_lanes<'a, P: LanePass>(
        &'a self,
        count: usize,
        seed: impl Fn(usize) -> Seed<'a> + Copy,
        pass: &mut P,
    ) {
        match width(count) {
            4 => self.chunks::<4, P>(count, seed, pass),
            8 => self.chunks::<8, P>(count, seed, pass),
            12 => self.chunks::<12, P>(count, seed, pass),
            _ => self.chunks::<16, P>(count, seed, pass),
        }
    }

    fn chunks<'a, const L: usize, P: LanePass>(
        &'a self,
        count: usize,
        seed: impl Fn(usize) -> Seed<'a> + Copy,
        pass: &mut P,
    ) {
        for first in (0..count).step_by(L) {
            let lanes = (count - first).min(L);
            let e = Seeded::<L>::new(self, lanes, |l| seed(first + l));
            pass.run(self, &e, first, lanes);
        }
    }

    /// The Jacobian ∂f/∂y of the right-hand side at (t, y), row-major n×n into `jac`
    /// (∂f_i/∂y_j at `jac[i·n + j]`); the quadrature columns are zero. Exact forward
    /// differentiation of the right-hand side (module documentation), every column
    /// a lane of one evaluation. No allocation.
    pub fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) {
        let l = self.layout();
        let n = l.n;
        assert_eq!(jac.len(), n * n, "jacobian: n×n buffer");
        jac.fill(0.0);
        let seed = |k| Seed {
            state: StateSeed::Unit(k),
            theta: ThetaSeed::None,
        };
        self.in_lanes(
            l.quad,
            seed,
            &mut Columns {
                t,
                y,
                out: jac,
                cols: n,
            },
        );
    }

    /// J·v, the Jacobian applied to `v`, in one forward evaluation (what implicit
    /// integrators need); `out` has n entries. No allocation.
    pub fn jacobian_times(&self, t: f64, y: &[f64], v: &[f64], out: &mut [f64]) {
        self.one_lane(t, y, StateSeed::Along(v), ThetaSeed::None, out);
    }

    /// J·s + ∂f/∂θ, the rate of the sensitivity column k, s = ∂y/∂θ for θ entry
    /// [`Plant::sensitivity_columns`]`[k]`, in one forward evaluation seeded along s
    /// in state space and that entry in parameter space. No allocation.
    pub fn sensitivity_rate(&self, t: f64, y: &[f64], s: &[f64], k: usize, out: &mut [f64]) {
        let th = ThetaSeed::Unit(self.sens_columns[k]);
        self.one_lane(t, y, StateSeed::Along(s), th, out);
    }

    /// The right-hand side's derivative along one seed into `out`.
    fn one_lane(&self, t: f64, y: &[f64], state: StateSeed, theta: ThetaSeed, out: &mut [f64]) {
        let e = Seeded::<1>::new(self, 1, |_| Seed { state, theta });
        self.rhs_with(&e, t, y, &self.layout(), |i, d| out[i] = d.d[0]);
    }

    /// The total derivatives d/dθk of the measured outputs at (t, y), for every
    /// carried column k (θk the entry [`Plant::sensitivity_columns`]`[k]`), given
    /// the state sensitivities `s` (column by column, `s[k·ns + i]` = ∂yi/∂θk for
    /// the leading ns = `s.len()`/m states, see
    /// [`super::integrate::System::dynamic_dim`]) into `out` (m entries): dλ/dθk = s0, dL/dθk = L0·s0, and the
    /// capacitance and the current (which depends on λ̇, V and the source state) as
    /// ∂out/∂y·s + ∂out/∂θk, by forward evaluation of the same output code that
    /// writes the samples ([`Plant::output`]), lane k seeded along s_k and θk. No
    /// allocation.
    pub fn output_sensitivities(
        &self,
        t: f64,
        y: &[f64],
        s: &[f64],
        out: &mut [OutputSensitivity],
    ) {
        if out.is_empty() {
            return; // no column carried
        }
        let ns = stride(y, s, out.len());
        let cols = &self.sens_columns;
        let seed = |k: usize| Seed {
            state: StateSeed::Along(&s[k * ns..(k + 1) * ns]),
            theta: ThetaSeed::Unit(cols[k]),
        };
        self.in_lanes(out.len(), seed, &mut Outputs { t, y, s, out });
    }

    /// [`Plant::output_sensitivities`] without the current, in closed form from
    /// the stretch's sensitivities alone: dλ/dθk = s0, dL/dθk = L0·s0 and
    /// dC/dθk = C'(λ)·s0 + C/εr·[θk = εr] (C depends on θ only through λ and εr),
    /// the same numbers the lane evaluation gives; the current is NaN. For a
    /// search that fits no current: the lanes through the output code were most of
    /// a sample's sensitivity work. No allocation.
    pub fn state_output_sensitivities(&self, y: &[f64], s: &[f64], out: &mut [OutputSensitivity]) {
        if out.is_empty() {
            return; // no column carried
        }
        let ns = stride(y, s, out.len());
        let (c, c1, _) = self.capacitance(y[0]);
        let eps = self.theta_index(Theta::EpsR);
        for (k, o) in out.iter_mut().enumerate() {
            let s0 = s[k * ns];
            let de = if self.sens_columns[k] == eps {
                1.0 / self.eps_r
            } else {
                0.0
            };
            *o = OutputSensitivity {
                stretch: s0,
                length: self.l0 * s0,
                capacitance: c1 * s0 + c * de,
                current: f64::NAN,
            };
        }
    }

    /// ∂f/∂θ at fixed (t, y) for the carried columns
    /// ([`Plant::sensitivity_columns`], m of them), row-major n×m into `dfdp`
    /// (∂f_i/∂θ_{c_k} at `dfdp[i·m + k]`), including the chain through λ0 into λf
    /// and C_rest, every column a lane of one evaluation. No allocation.
    pub fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut [f64]) {
        let cols = &self.sens_columns;
        let (n, m) = (self.layout().n, cols.len());
        assert_eq!(dfdp.len(), n * m, "param_jacobian: n×m buffer");
        let seed = |k: usize| Seed {
            state: StateSeed::None,
            theta: ThetaSeed::Unit(cols[k]),
        };
        self.in_lanes(
            m,
            seed,
            &mut Columns {
                t,
                y,
                out: dfdp,
                cols: m,
            },
        );
    }

    /// ∂y0/∂θ of [`Plant::initial_state`] for the carried columns
    /// ([`Plant::sensitivity_columns`], m of them), row-major n×m into `out`:
    /// * λ0: dλ0/dp = −(∂P/∂p)/P'(λ0) for the hyperelastic parameters;
    /// * the derivative filter D0 = r(0) − ŷ(λ0) = r(0): ŷ(λ0) = 1 − sqrt(C_rest/C(λ0))
    ///   is zero for every θ (C_rest is C(λ0)), so its row is zero, as is the
    ///   rise-time source's V0 = u0 (the input, or the PID's Kp·r(0) clamped);
    /// * the resistance source's charge q0 = u0·C(λ0):
    ///   dq0/dθ = u0·(C'(λ0)·dλ0/dθ + ∂C/∂θ), ∂C/∂εr = C/εr;
    /// * arm stresses, integrator state and quadratures start at zero.
    pub fn initial_state_sensitivity(&self, out: &mut [f64]) {
        let l = self.layout();
        let (n, m) = (l.n, self.sens_columns.len());
        assert_eq!(out.len(), n * m, "initial_state_sensitivity: n×m buffer");
        out.fill(0.0);
        let y0 = self.initial_state();
        let (c, dc, _) = self.capacitance(self.lam0);
        let eps = self.theta_index(Theta::EpsR);
        for (k, &th) in self.sens_columns.iter().enumerate() {
            let dlam0 = self.rest_derivatives[th].0;
            out[k] = dlam0;
            if let (Some(i), Source::Resistance { .. }) = (l.src, self.source) {
                let u0 = y0[i] / c;
                let de = (th == eps) as u8 as f64 / self.eps_r;
                out[i * m + k] = u0 * (dc * dlam0 + de * c);
            }
        }
    }
}

/// The column length ns of sensitivities `s` of `cols` columns for the state `y`
/// (every state, or the leading ones with sensitivities: at least the stretch).
fn stride(y: &[f64], s: &[f64], cols: usize) -> usize {
    let ns = s.len() / cols.max(1);
    assert!(
        ns * cols == s.len() && (1..=y.len()).contains(&ns),
        "sensitivities: {} values for {cols} columns of at most {} states",
        s.len(),
        y.len()
    );
    ns
}

/// What an evaluation of several lanes writes ([`Plant::in_lanes`]).
trait LanePass {
    /// Lanes `first..first + lanes` evaluated as `e`.
    fn run<const L: usize>(&mut self, p: &Plant, e: &Seeded<'_, L>, first: usize, lanes: usize);
}

/// Columns of a row-major matrix with `cols` columns: the right-hand side's
/// derivative along lane l is column first + l.
struct Columns<'a> {
    t: f64,
    y: &'a [f64],
    out: &'a mut [f64],
    cols: usize,
}

impl LanePass for Columns<'_> {
    fn run<const L: usize>(&mut self, p: &Plant, e: &Seeded<'_, L>, first: usize, lanes: usize) {
        let (out, cols) = (&mut *self.out, self.cols);
        p.rhs_with(e, self.t, self.y, &p.layout(), |i, v| {
            out[i * cols + first..i * cols + first + lanes].copy_from_slice(&v.d[..lanes])
        });
    }
}

/// The outputs' total derivatives, lane k for θk ([`Plant::output_sensitivities`]).
struct Outputs<'a> {
    t: f64,
    y: &'a [f64],
    s: &'a [f64],
    out: &'a mut [OutputSensitivity],
}

impl LanePass for Outputs<'_> {
    fn run<const L: usize>(&mut self, p: &Plant, e: &Seeded<'_, L>, first: usize, lanes: usize) {
        let el = p.output_with(e, self.t, self.y, &p.layout());
        let ns = self.s.len() / self.out.len();
        for l in 0..lanes {
            let s0 = self.s[(first + l) * ns];
            self.out[first + l] = OutputSensitivity {
                stretch: s0,
                length: p.l0 * s0,
                capacitance: el.capacitance.d[l],
                current: el.current.d[l],
            };
        }
    }
}
