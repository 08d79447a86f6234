//! The lumped electromechanical model shared by the stack and the helix, as the
//! Lagrange equation in the thickness stretch λ (one axial degree of freedom):
//!
//! ```text
//! M·λ̈ = D(λ, σ, V) − Vol·Nv·λ̇
//! D   = −Vol·[P(λ) + Σσj + kf·(λ − λf)] + F_load·L0 + ½·V²·dC/dλ      (the drive)
//! dσj/dt = kj·λ̇ − σj/τj                                   (seed Eq. 3.16)
//! ```
//! with M = m_eff·L0² (Z = L0·λ), P the nominal stress of the hyperelastic model in
//! the layer's mode (uniaxial compression for a stack, planar for the seed's helix),
//! Vol the strained volume, F_load = (m_load + f·m_act)·g + F (Eq. 3.9–3.10) and
//! ½V²·dC/dλ the electrostatic generalised force, which for the stack is exactly the
//! Maxwell pressure ε(V/z)² on the current area (Eq. 3.1, 3.7) and for the helix
//! contains the projection on z (Eq. 4.24). kf, λf: Maxwell arms lumped as frozen
//! springs by the fidelity choice.
//!
//! Quasi-static fidelity drops M. With a dashpot (Nv > 0) the force balance gives
//! λ̇ = D/(Vol·Nv). Without one, D = 0 is an algebraic constraint, integrated as its
//! time derivative (index reduction, see `Plant::constrained_rate`).
//!
//! Quadrature states accumulate electrical work in, viscous and leakage dissipation
//! and source losses, for the energy balance.
//!
//! The right-hand side is written once, generic over the number type (`Num`) and
//! over where it reads parameters and material/geometry functions (`Eval`): in
//! `f64` it is the ODE, in dual numbers ([`super::derivatives`]) it gives the exact
//! Jacobian and parameter derivatives of the same code.

use super::input::Waveform;
use super::scene::{Actuator, Pid, Scene, Source};
use crate::material::hyperelastic::{AtParams, Mode, StrainEnergy};
use std::ops::{Add, Div, Mul, Neg, Sub};
use std::sync::Arc;

/// Vacuum permittivity (F/m).
pub const EPS0: f64 = 8.854_187_812_8e-12;

/// Baumgarte time constant of the quasi-static constraint without dashpot, as a
/// fraction of the scene's shortest time scale (see [`Plant::tau_c`]).
pub const BAUMGARTE_FRACTION: f64 = 0.1;

/// Quasi-static without dashpot: the denominator K − V·C'·b of λ̇ is floored at this
/// fraction of the elastic stiffness Vol·(P' + Σkj + kf) (see `Plant::constrained_rate`).
pub const PULL_IN_FLOOR: f64 = 1e-3;

/// The plant: a scene turned into numbers and a state layout. `Send + Sync`.
#[derive(Clone)]
pub struct Plant {
    /// Actuator geometry.
    pub actuator: Actuator,
    model: Arc<dyn StrainEnergy>,
    /// Hyperelastic parameters (SI).
    pub params: Vec<f64>,
    /// Deformation mode of the layer material.
    pub mode: Mode,
    /// Strained volume (m³).
    pub vol: f64,
    /// dZ/dλ (m).
    pub l0: f64,
    /// Generalised mass m_eff·L0² (kg·m²).
    pub mass: f64,
    /// Effective moving mass (kg).
    pub m_eff: f64,
    /// Axial load (N, tensile positive).
    pub f_load: f64,
    /// Relative permittivity εr.
    pub eps_r: f64,
    /// Volume resistivity ρ (Ω·m); None = no leakage.
    pub resistivity: Option<f64>,
    /// Kelvin-Voigt dashpot (Pa·s), including arms lumped as dashpots.
    pub nv: f64,
    /// Active arms (k in Pa, τ in s).
    pub arms: Vec<(f64, f64)>,
    /// Stiffness of arms lumped as frozen springs (Pa), about `lam_f`.
    pub frozen_k: f64,
    /// With inertia (dynamic) or without (quasi-static).
    pub inertia: bool,
    /// Source model.
    pub source: Source,
    /// Input voltage.
    pub input: Waveform,
    /// Closed loop, if any.
    pub control: Option<Pid>,
    /// Baumgarte time constant τc (s) of the quasi-static constraint without
    /// dashpot: [`BAUMGARTE_FRACTION`] × the scene's shortest time scale, the least of
    /// * 1/s of the arms' fastest relaxation rate s in the quasi-static plant at rest
    ///   (`fastest_arm_rate`): between the two largest 1/τj, and for one arm its
    ///   retardation time τ·K/(K − Vol·k) (100·τ for an arm 100× stiffer than the
    ///   rest) — the arms' rates there, not the 1/τj;
    /// * the input's time scale incl. the source's (`fidelity::input_time_scale`);
    /// * the span.
    ///
    /// The constraint D = 0 then recovers from drift ten times faster than anything
    /// in the solution moves (the drift, of the order of the integration error, is
    /// held at a tenth of it), while the added eigenvalue −1/τc is only ten times the
    /// fastest physical rate: no stiffer than the arms make the problem by more than
    /// that factor. A numerical setting fixed when the plant is built (not a model
    /// quantity: the exact solution keeps D = 0 whatever τc), so [`Plant::with_theta`]
    /// keeps it.
    pub tau_c: f64,
    // Derived from the above by `derive` (the one place computing them):
    /// Absolute permittivity ε0·εr (F/m).
    pub eps: f64,
    /// Leakage conductance per capacitance 1/(ρ·ε) (1/s); 0 without leakage.
    pub g_per_c: f64,
    /// Initial (loaded, relaxed) stretch: static equilibrium at V = 0.
    pub lam0: f64,
    /// Reference stretch of the frozen springs (= `lam0`).
    pub lam_f: f64,
    /// Capacitance at the rest state (the self-sensing calibration).
    pub c_rest: f64,
    /// (dλ0/dθk, dC_rest/dθk) per entry of θ (`derivatives`), derived with λ0.
    pub(crate) rest_derivatives: Vec<(f64, f64)>,
    /// The entries of θ whose forward sensitivities a run carries, in θ's order:
    /// sensitivity column k is θ entry `sens_columns[k]` (every entry, unless
    /// [`Plant::keep_sensitivities`] chose some).
    pub(crate) sens_columns: Vec<usize>,
    /// The model's stress and tangent at `params` in `mode` ([`AtParams`]).
    at: AtParams,
}

/// Indices into the state vector.
#[derive(Debug, Clone, Copy)]
pub struct Layout {
    /// Velocity slot (dynamic only).
    pub v: Option<usize>,
    /// First arm stress.
    pub sig: usize,
    /// Source state (lag voltage or charge).
    pub src: Option<usize>,
    /// Controller states (integral of the error, derivative filter).
    pub ctl: Option<usize>,
    /// First quadrature: E_in, D_visc, D_leak, D_src.
    pub quad: usize,
    /// Total.
    pub n: usize,
    /// Number of arms (their stresses at `sig`…`sig + arms − 1`).
    pub arms: usize,
}

impl Layout {
    /// The state vector [λ, (λ̇), σ1…σm, (source), (I, D), E_in, D_visc, D_leak,
    /// D_src] of a plant with or without inertia, m = `arms` arms, a source state
    /// (any source but an ideal one) and a controller.
    #[inline(always)]
    pub const fn of(inertia: bool, arms: usize, source: bool, control: bool) -> Layout {
        let sig = if inertia { 2 } else { 1 };
        let after = sig + arms;
        let src = if source { Some(after) } else { None };
        let after = after + source as usize;
        let ctl = if control { Some(after) } else { None };
        let quad = after + 2 * control as usize;
        Layout {
            v: if inertia { Some(1) } else { None },
            sig,
            src,
            ctl,
            quad,
            n: quad + 4,
            arms,
        }
    }
}

/// The numbers the right-hand side is written in: `f64` for the ODE, a dual number
/// (value and one directional derivative) for its exact derivatives.
pub(crate) trait Num:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// A constant.
    fn cst(v: f64) -> Self;
    /// The value.
    fn val(self) -> f64;
    /// Square root.
    fn sqrt(self) -> Self;
}

impl Num for f64 {
    #[inline]
    fn cst(v: f64) -> f64 {
        v
    }
    #[inline]
    fn val(self) -> f64 {
        self
    }
    #[inline]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
}

/// Where the right-hand side reads states, the parameters θ (and what is derived
/// from them) and the material and geometry functions: plainly ([`Plain`]) or seeded
/// with a derivative direction (`derivatives::Seeded`).
pub(crate) trait Eval {
    /// The number type.
    type T: Num;
    /// State `i` of `y`.
    fn y(&self, y: &[f64], i: usize) -> Self::T;
    /// Integrated arm j: (kj in Pa, τj in s).
    fn arm(&self, j: usize) -> (Self::T, Self::T);
    /// Kelvin-Voigt dashpot Nv (Pa·s).
    fn nv(&self) -> Self::T;
    /// Leakage conductance per capacitance 1/(ρε) (1/s).
    fn g_per_c(&self) -> Self::T;
    /// Reference stretch λf of the frozen springs.
    fn lam_f(&self) -> Self::T;
    /// Capacitance at rest C_rest (F).
    fn c_rest(&self) -> Self::T;
    /// Nominal stress P(λ) (Pa).
    fn stress(&self, lam: Self::T) -> Self::T;
    /// Tangent P'(λ) (Pa).
    fn tangent(&self, lam: Self::T) -> Self::T;
    /// C(λ), C'(λ), C''(λ) (F).
    fn capacitance(&self, lam: Self::T) -> [Self::T; 3];
}

/// The plant's own values, in `f64`.
pub(crate) struct Plain<'a>(pub &'a Plant);

impl Eval for Plain<'_> {
    type T = f64;
    #[inline]
    fn y(&self, y: &[f64], i: usize) -> f64 {
        y[i]
    }
    #[inline]
    fn arm(&self, j: usize) -> (f64, f64) {
        self.0.arms[j]
    }
    #[inline]
    fn nv(&self) -> f64 {
        self.0.nv
    }
    #[inline]
    fn g_per_c(&self) -> f64 {
        self.0.g_per_c
    }
    #[inline]
    fn lam_f(&self) -> f64 {
        self.0.lam_f
    }
    #[inline]
    fn c_rest(&self) -> f64 {
        self.0.c_rest
    }
    #[inline]
    fn stress(&self, lam: f64) -> f64 {
        self.0.stress(lam)
    }
    #[inline]
    fn tangent(&self, lam: f64) -> f64 {
        self.0.tangent(lam)
    }
    #[inline]
    fn capacitance(&self, lam: f64) -> [f64; 3] {
        let (c, dc, d2c) = self.0.capacitance(lam);
        [c, dc, d2c]
    }
}

/// The controller's output at a state (seed Eq. 3.29 as coded: e = r(t) − ŷ(λ),
/// u = Kp·e + Ki·I + Kd·(e − D)/τd with the filtered error D, Ḋ = (e − D)/τd, so that
/// (e − D)/τd is the filtered de/dt; u clamped to [0, V_max]; conditional-integration
/// anti-windup İ = 0 while the clamp is active and the error pushes further into it).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PidOut<T> {
    /// Clamped command (V).
    pub u: T,
    /// The command's rate is u̇ = a + b·λ̇ (V/s; a, b zero while clamped).
    pub a: T,
    /// See `a` (V per unit λ̇·s).
    pub b: T,
    /// İ (1/s).
    pub i_dot: T,
    /// Ḋ (1/s).
    pub d_dot: T,
}

/// The source side at a state, before λ̇ is known: the terminal voltage's rate is
/// V̇ = a + b·λ̇ with a, b independent of λ̇.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Terminal<T> {
    /// Source open-circuit voltage u (V).
    pub u: T,
    /// Terminal voltage V (V).
    pub v: T,
    /// a (V/s).
    pub a: T,
    /// b (V·s⁻¹ per unit λ̇).
    pub b: T,
    /// Rate of the source state: V̇ (rise time) or q̇ (resistance); 0 for ideal.
    pub src_rate: T,
    /// C(λ) (F).
    pub c: T,
    /// C'(λ) (F).
    pub dc: T,
    /// C''(λ) (F).
    pub d2c: T,
    /// Leakage conductance G = C/(ρε) (S).
    pub g: T,
    /// Controller output, if any.
    pub pid: Option<PidOut<T>>,
}

/// λ̇, the generalised force on the velocity, the electrical state at λ̇.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Kinematics<T> {
    /// λ̇ (1/s).
    pub lam_dot: T,
    /// M·λ̈ (N·m); 0 quasi-static.
    pub force: T,
    /// Source side.
    pub terminal: Terminal<T>,
    /// Electrical quantities at λ̇.
    pub elec: Electrical<T>,
}

/// Stretch below which a layer counts as collapsed (the static search stops).
const LAM_COLLAPSE: f64 = 0.05;

/// Why [`Plant::static_stretch`] found no stable static equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoEquilibrium {
    /// The stiffness reached zero on the way (past pull-in, or a load beyond the
    /// material's strength).
    Unstable,
    /// The stretch fell below 0.05: the layer collapses.
    Collapsed,
    /// Force or stiffness is not a finite number (parameters outside the model's
    /// domain).
    NotFinite,
    /// Newton did not settle in 200 steps.
    NoConvergence,
}

impl std::fmt::Display for NoEquilibrium {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NoEquilibrium::Unstable => "the stiffness vanishes before an equilibrium is reached",
            NoEquilibrium::Collapsed => "the layer collapses (stretch below 0.05)",
            NoEquilibrium::NotFinite => "the stress or stiffness is not a finite number",
            NoEquilibrium::NoConvergence => "the equilibrium search did not converge",
        })
    }
}

impl Plant {
    /// Build the plant of a scene with given lumping (arms kept, Nv add, frozen k),
    /// or why its parameters have no stable rest state (then there is no run: the
    /// state starts there).
    pub fn new(scene: &Scene, inertia: bool, keep: &[bool]) -> Result<Plant, NoEquilibrium> {
        let m = &scene.material;
        let (mode, vol, l0, m_act) = match scene.actuator {
            Actuator::Stack(s) => (
                Mode::Uniaxial,
                s.volume(),
                s.length0(),
                m.density * s.volume(),
            ),
            Actuator::Helix(h) => (
                match h.lateral {
                    super::scene::Lateral::Planar => Mode::Planar,
                    super::scene::Lateral::Free => Mode::Uniaxial,
                },
                h.volume(),
                h.length0(),
                m.density * h.volume(),
            ),
        };
        let m_act = scene.load.actuator_mass_kg.unwrap_or(m_act);
        let m_eff = scene.load.mass_kg + scene.load.fraction * m_act;
        let f_load = m_eff * scene.load.gravity + scene.load.force_n;
        let mut nv = m.viscous.nv_pa_s;
        let mut arms = Vec::new();
        let mut frozen_k = 0.0;
        for (i, a) in m.viscous.arms.iter().enumerate() {
            match keep.get(i).copied().unwrap_or(true) {
                true => arms.push((a.k_pa, a.eta_pa_s / a.k_pa)),
                false => {
                    // lumped: a relaxed arm becomes a dashpot η, a frozen one a spring k
                    if a.eta_pa_s / a.k_pa < scene.time.span {
                        nv += a.eta_pa_s;
                    } else {
                        frozen_k += a.k_pa;
                    }
                }
            }
        }
        let mut p = Plant {
            actuator: scene.actuator,
            model: m.model.clone(),
            params: m.params.clone(),
            mode,
            vol,
            l0,
            mass: m_eff * l0 * l0,
            m_eff,
            f_load,
            eps_r: m.eps_r,
            resistivity: m.resistivity,
            nv,
            arms,
            frozen_k,
            inertia,
            source: scene.source,
            input: scene.input.clone(),
            control: scene.control.clone(),
            tau_c: 0.0,
            eps: 0.0,
            g_per_c: 0.0,
            lam0: 1.0,
            lam_f: 1.0,
            c_rest: 0.0,
            rest_derivatives: Vec::new(),
            sens_columns: Vec::new(),
            at: AtParams::new(m.model.as_ref(), &m.params, mode),
        };
        p.derive()?;
        p.sens_columns = (0..p.n_theta()).collect();
        let t_in = super::fidelity::input_time_scale(scene, p.c_rest);
        p.tau_c = BAUMGARTE_FRACTION
            * [1.0 / p.fastest_arm_rate(), t_in]
                .into_iter()
                .filter(|&t| t > 0.0)
                .fold(scene.time.span, f64::min);
        Ok(p)
    }

    /// Fastest relaxation rate s (1/s) of the integrated arms in the quasi-static
    /// plant at rest (0 without arms). Linearised at (λ0, V = 0) without inertia and
    /// dashpot, K·λ̇ = Vol·Σσj/τj and σ̇j = kj·λ̇ − σj/τj, so σ̇ = −(T − u·1ᵀT)·σ with
    /// T = diag(1/τj), uj = Vol·kj/K, K the instantaneous stiffness. Its rates are
    /// the roots of the secular equation Σj wj/(1 − s·τj) = 1, wj = Vol·kj/K, which
    /// interlace with the 1/τj: the largest lies between the two largest 1/τj (for one
    /// arm s = (1 − w)/τ, the retardation rate), found by bisection.
    fn fastest_arm_rate(&self) -> f64 {
        let k = self.instant_stiffness(self.lam0, 0.0);
        let mut rates: Vec<f64> = self.arms.iter().map(|a| 1.0 / a.1).collect();
        rates.sort_by(f64::total_cmp);
        let Some(&hi) = rates.last() else {
            return 0.0;
        };
        let lo = if rates.len() > 1 {
            rates[rates.len() - 2]
        } else {
            0.0
        };
        let secular = |s: f64| {
            1.0 - self
                .arms
                .iter()
                .map(|&(kj, tau)| self.vol * kj / k / (1.0 - s * tau))
                .sum::<f64>()
        };
        // secular(0) = static stiffness / K; the bracket's ends are poles
        if k <= 0.0 || secular(0.0) <= 0.0 {
            return hi; // unstable at rest: the bound 1/τmin
        }
        let (mut a, mut b) = (lo, hi);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            match secular(m) > 0.0 {
                true => a = m,
                false => b = m,
            }
        }
        0.5 * (a + b)
    }

    /// The quantities derived from the parameters θ (the one place computing them):
    /// the prepared stress, ε = ε0·εr, G/C = 1/(ρε), λ0 = static equilibrium at
    /// V = 0 (from λ = 1), λf = λ0, C_rest = C(λ0); or why there is no rest state.
    pub(super) fn derive(&mut self) -> Result<(), NoEquilibrium> {
        self.at = AtParams::new(self.model.as_ref(), &self.params, self.mode);
        self.eps = EPS0 * self.eps_r;
        self.g_per_c = self
            .resistivity
            .map(|r| 1.0 / (r * self.eps))
            .unwrap_or(0.0);
        self.lam0 = self.static_stretch(0.0, 1.0)?;
        self.lam_f = self.lam0;
        self.c_rest = self.capacitance(self.lam0).0;
        self.rest_derivatives = self.rest_state_derivatives();
        Ok(())
    }

    /// The hyperelastic model.
    pub(super) fn model(&self) -> &dyn StrainEnergy {
        self.model.as_ref()
    }

    /// Contraction estimated from the capacitance with the stack law C ∝ λ⁻²
    /// (self-sensing, Eq. 3.22): 1 − sqrt(C_rest/C).
    #[inline]
    pub fn sensed_contraction(&self, lam: f64) -> f64 {
        sensed(self.c_rest, self.capacitance(lam).0)
    }

    /// Nominal stress P(λ) of the layer (Pa).
    #[inline(always)]
    pub fn stress(&self, lam: f64) -> f64 {
        self.at.stress(self.model.as_ref(), &self.params, lam)
    }
    /// Tangent dP/dλ (Pa).
    #[inline(always)]
    pub fn tangent(&self, lam: f64) -> f64 {
        self.at.tangent(self.model.as_ref(), &self.params, lam)
    }
    /// Capacitance and its λ-derivatives.
    #[inline(always)]
    pub fn capacitance(&self, lam: f64) -> (f64, f64, f64) {
        match self.actuator {
            Actuator::Stack(s) => s.capacitance(self.eps, lam),
            Actuator::Helix(h) => h.capacitance(self.eps, lam),
        }
    }
    /// Length Z = L0·λ (m).
    pub fn length(&self, lam: f64) -> f64 {
        self.l0 * lam
    }
    /// Static (fully relaxed) generalised force at (λ, V): zero at equilibrium.
    pub fn static_force(&self, lam: f64, v: f64) -> f64 {
        self.relaxed_force(&Plain(self), lam, v, self.capacitance(lam).1)
    }
    /// Long-term stiffness −∂(static force)/∂λ at (λ, V).
    pub fn static_stiffness(&self, lam: f64, v: f64) -> f64 {
        self.stiffness(&Plain(self), lam, v, self.capacitance(lam).2, 0.0)
    }
    /// Instantaneous stiffness (arms act as springs): pull-in when it reaches zero.
    pub fn instant_stiffness(&self, lam: f64, v: f64) -> f64 {
        let e = Plain(self);
        self.stiffness(&e, lam, v, self.capacitance(lam).2, self.springs(&e))
    }

    /// Fully relaxed generalised force −Vol·P(λ) + F_load·L0 + ½V²·C'(λ) (N·m).
    #[inline(always)]
    fn relaxed_force<E: Eval>(&self, e: &E, lam: E::T, v: E::T, dc: E::T) -> E::T {
        e.stress(lam) * -self.vol + v * v * dc * 0.5 + self.f_load * self.l0
    }
    /// Stiffness Vol·(P'(λ) + springs) − ½V²·C''(λ) (N·m): the static one with
    /// springs = 0, the instantaneous one with springs = Σkj + kf.
    #[inline(always)]
    fn stiffness<E: Eval>(&self, e: &E, lam: E::T, v: E::T, d2c: E::T, springs: E::T) -> E::T {
        (e.tangent(lam) + springs) * self.vol - v * v * d2c * 0.5
    }
    /// Σkj + kf (Pa).
    #[inline(always)]
    fn springs<E: Eval>(&self, e: &E) -> E::T {
        (0..self.arms.len()).fold(E::T::cst(self.frozen_k), |s, j| s + e.arm(j).0)
    }

    /// Stable static equilibrium reached from `start` at voltage `v` (fully relaxed),
    /// by damped Newton along the stable branch (steps limited to 5 % of λ). Never
    /// panics: any parameters give either λ or why there is none (a non-finite
    /// force or stiffness, e.g. Gent with Jm ≤ 0, is [`NoEquilibrium::NotFinite`]).
    pub fn static_stretch(&self, v: f64, start: f64) -> Result<f64, NoEquilibrium> {
        if !(start.is_finite() && start > LAM_COLLAPSE) {
            return Err(NoEquilibrium::Collapsed);
        }
        let mut lam = start;
        for _ in 0..200 {
            let f = self.static_force(lam, v);
            let k = self.static_stiffness(lam, v);
            if !(f.is_finite() && k.is_finite()) {
                return Err(NoEquilibrium::NotFinite);
            }
            if k <= 0.0 {
                return Err(NoEquilibrium::Unstable);
            }
            // k > 0 and f finite: the step is a number (±∞ clamps to the limit)
            let step = (f / k).clamp(-0.05 * lam, 0.05 * lam);
            lam += step;
            if lam <= LAM_COLLAPSE {
                return Err(NoEquilibrium::Collapsed);
            }
            if step.abs() < 1e-14 * lam {
                return match self.static_stiffness(lam, v) > 0.0 {
                    true => Ok(lam),
                    false => Err(NoEquilibrium::Unstable),
                };
            }
        }
        Err(NoEquilibrium::NoConvergence)
    }

    /// State layout.
    pub fn layout(&self) -> Layout {
        Layout::of(
            self.inertia,
            self.arms.len(),
            !matches!(self.source, Source::Ideal),
            self.control.is_some(),
        )
    }

    /// Initial state: loaded equilibrium, arms relaxed, source at the input's value.
    pub fn initial_state(&self) -> Vec<f64> {
        let l = self.layout();
        let mut y = vec![0.0; l.n];
        y[0] = self.lam0;
        if let (Some(i), Some(pid)) = (l.ctl, &self.control) {
            y[i + 1] = pid.reference.eval(0.0).0 - self.sensed_contraction(self.lam0);
        }
        if let Some(i) = l.src {
            // the source starts from the input's value just before t = 0, so a step
            // at t = 0 goes through the source's rise time / resistance
            let (c, dc, _) = self.capacitance(self.lam0);
            let u = match &self.control {
                Some(pid) => self.pid_out(&Plain(self), pid, 0.0, &y, &l, c, dc).u,
                None => self.input.eval(-f64::MIN_POSITIVE).0,
            };
            y[i] = match self.source {
                Source::RiseTime { .. } => u,
                Source::Resistance { .. } => u * c,
                Source::Ideal => 0.0,
            };
        }
        y
    }

    /// Typical magnitude of each state (for absolute tolerances).
    pub fn scales(&self, v_max: f64) -> Vec<f64> {
        let l = self.layout();
        let mut s = vec![1.0; l.n];
        let mu = self
            .model
            .initial_shear_modulus(&self.params)
            .abs()
            .max(1.0);
        if let Some(i) = l.v {
            s[i] = 1.0;
        }
        for j in 0..self.arms.len() {
            s[l.sig + j] = mu;
        }
        if let Some(i) = l.src {
            s[i] = match self.source {
                Source::Resistance { .. } => v_max.max(1.0) * self.capacitance(1.0).0,
                _ => v_max.max(1.0),
            };
        }
        // energy quadratures: the field energy at the largest voltage
        let energy = 0.5 * self.capacitance(self.lam0).0 * v_max.max(1.0).powi(2);
        for q in l.quad..l.n {
            s[q] = energy;
        }
        s
    }

    /// The controller (Eq. 3.29, see [`PidOut`]) at a state with capacitance C and
    /// C' at λ. Its rate, while not clamped: u̇ = Kp·ė + Ki·İ + Kd·(ė − Ḋ)/τd with
    /// ė = ṙ − ŷ'(λ)·λ̇, ŷ' = ½(1 − ŷ)·C'/C, so a = (Kp + Kd/τd)·ṙ + Ki·İ − Kd·Ḋ/τd
    /// and b = −(Kp + Kd/τd)·ŷ'.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn pid_out<E: Eval>(
        &self,
        e: &E,
        pid: &Pid,
        t: f64,
        y: &[f64],
        l: &Layout,
        c: E::T,
        dc: E::T,
    ) -> PidOut<E::T> {
        let zero = E::T::cst(0.0);
        let i = l.ctl.unwrap_or(0);
        let (r, r_dot) = pid.reference.eval(t);
        let s = sensed(e.c_rest(), c);
        let err = -s + r;
        let d = e.y(y, i + 1);
        let raw = err * pid.kp + e.y(y, i) * pid.ki + (err - d) * (pid.kd / pid.tau_d);
        let (rv, ev) = (raw.val(), err.val());
        let wind = (rv > pid.v_max && ev > 0.0) || (rv < 0.0 && ev < 0.0);
        let i_dot = if wind { zero } else { err };
        let d_dot = (err - d) / pid.tau_d;
        let gain = pid.kp + pid.kd / pid.tau_d;
        let (u, a, b) = if rv < 0.0 {
            (zero, zero, zero)
        } else if rv > pid.v_max {
            (E::T::cst(pid.v_max), zero, zero)
        } else {
            let s_lam = (-s + 1.0) * dc / c * 0.5;
            (
                raw,
                i_dot * pid.ki - d_dot * (pid.kd / pid.tau_d) + gain * r_dot,
                s_lam * -gain,
            )
        };
        PidOut {
            u,
            a,
            b,
            i_dot,
            d_dot,
        }
    }

    /// The source side at a state (see [`Terminal`]):
    /// * ideal: V = u, V̇ = u̇ (the input's rate, or the PID's a + b·λ̇);
    /// * rise time τ: V the state, V̇ = (u − V)/τ;
    /// * resistance R: charge q the state, V = q/C, q̇ = (u − V)/R − G·V, so
    ///   V̇ = q̇/C − V·C'·λ̇/C: a = q̇/C, b = −V·C'/C.
    #[inline(always)]
    pub(crate) fn terminal<E: Eval>(&self, e: &E, t: f64, y: &[f64], l: &Layout) -> Terminal<E::T> {
        let zero = E::T::cst(0.0);
        let [c, dc, d2c] = e.capacitance(e.y(y, 0));
        let g = e.g_per_c() * c;
        let pid = self
            .control
            .as_ref()
            .map(|pid| self.pid_out(e, pid, t, y, l, c, dc));
        let (u, ua, ub) = match &pid {
            Some(o) => (o.u, o.a, o.b),
            None => {
                let (u, du) = self.input.eval(t);
                (E::T::cst(u), E::T::cst(du), zero)
            }
        };
        let src = l.src.unwrap_or(0);
        let (v, a, b, src_rate) = match self.source {
            Source::Ideal => (u, ua, ub, zero),
            Source::RiseTime { tau_s } => {
                let v = e.y(y, src);
                let dv = (u - v) / tau_s;
                (v, dv, zero, dv)
            }
            Source::Resistance { ohm } => {
                let v = e.y(y, src) / c;
                let dq = (u - v) / ohm - g * v;
                (v, dq / c, -(v * dc / c), dq)
            }
        };
        Terminal {
            u,
            v,
            a,
            b,
            src_rate,
            c,
            dc,
            d2c,
            g,
            pid,
        }
    }

    /// Electrical quantities at λ̇: V̇ = a + b·λ̇; current I = (u − V)/R behind a
    /// resistance, else d(CV)/dt + G·V = C'·λ̇·V + C·V̇ + G·V.
    #[inline(always)]
    fn rates<T: Num>(&self, s: &Terminal<T>, lam_dot: T) -> Electrical<T> {
        let v_dot = s.a + s.b * lam_dot;
        let current = match self.source {
            Source::Resistance { ohm } => (s.u - s.v) / ohm,
            _ => s.dc * lam_dot * s.v + s.c * v_dot + s.g * s.v,
        };
        Electrical {
            u: s.u,
            voltage: s.v,
            voltage_rate: v_dot,
            capacitance: s.c,
            dc: s.dc,
            current,
            leakage: s.g * s.v * s.v,
        }
    }

    /// The drive D = −Vol·[P(λ) + Σσj + kf·(λ − λf)] + F_load·L0 + ½V²·C'(λ) (N·m):
    /// the generalised force without inertia and dashpot.
    #[inline(always)]
    fn drive_with<E: Eval>(&self, e: &E, y: &[f64], l: &Layout, s: &Terminal<E::T>) -> E::T {
        let lam = e.y(y, 0);
        let sig = (0..l.arms).fold(E::T::cst(0.0), |a, j| a + e.y(y, l.sig + j));
        self.relaxed_force(e, lam, s.v, s.dc) - (sig + (lam - e.lam_f()) * self.frozen_k) * self.vol
    }

    /// λ̇ of the quasi-static plant without dashpot, by index reduction of the force
    /// balance D(λ, σ, V) = 0. With σ̇j = kj·λ̇ − σj/τj and V̇ = a + b·λ̇:
    /// dD/dt = −K·λ̇ + Vol·Σσj/τj + V·C'·(a + b·λ̇), K the instantaneous stiffness
    /// Vol·(P' + Σkj + kf) − ½V²C''. Baumgarte stabilisation asks dD/dt = −D/τc, so
    ///
    /// λ̇ = (Vol·Σσj/τj + V·C'·a + D/τc) / (K − V·C'·b).
    ///
    /// D decays as e^(−t/τc) from any drift; on the constraint the solution does not
    /// depend on τc. K → 0 is pull-in (for a voltage-driven source the denominator is
    /// K itself): the denominator is floored at [`PULL_IN_FLOOR`] × the elastic
    /// stiffness Vol·(P' + Σkj + kf), so λ̇ stays finite and keeps its sign through
    /// K = 0, the solution crosses it and the pull-in event (K = 0) fires; the floor
    /// changes the solution only within that fraction of the stiffness of the fold.
    #[inline]
    fn constrained_rate<E: Eval>(
        &self,
        e: &E,
        y: &[f64],
        l: &Layout,
        s: &Terminal<E::T>,
        drive: E::T,
    ) -> E::T {
        let lam = e.y(y, 0);
        let relax = (0..l.arms).fold(E::T::cst(0.0), |acc, j| {
            acc + e.y(y, l.sig + j) / e.arm(j).1
        });
        let k = self.stiffness(e, lam, s.v, s.d2c, self.springs(e));
        let k_el = k + s.v * s.v * s.d2c * 0.5;
        let floor = (if k_el.val() < 0.0 { -k_el } else { k_el }) * PULL_IN_FLOOR;
        let den = k - s.v * s.dc * s.b;
        let den = if den.val() >= floor.val() { den } else { floor };
        (relax * self.vol + s.v * s.dc * s.a + drive / self.tau_c) / den
    }

    /// λ̇, the generalised acceleration force and the electrical state (with the
    /// current evaluated at λ̇) at a state.
    #[inline(always)]
    pub(crate) fn kinematics<E: Eval>(
        &self,
        e: &E,
        t: f64,
        y: &[f64],
        l: &Layout,
    ) -> Kinematics<E::T> {
        let s = self.terminal(e, t, y, l);
        let drive = self.drive_with(e, y, l, &s);
        let (lam_dot, force) = match l.v {
            Some(i) => {
                let w = e.y(y, i);
                (w, drive - e.nv() * w * self.vol)
            }
            None if self.nv > 0.0 => (drive / (e.nv() * self.vol), E::T::cst(0.0)),
            None => (self.constrained_rate(e, y, l, &s, drive), E::T::cst(0.0)),
        };
        Kinematics {
            lam_dot,
            force,
            terminal: s,
            elec: self.rates(&s, lam_dot),
        }
    }

    /// The right-hand side, written once for every number type: `out(i, dy_i)` for
    /// every state i.
    #[inline(always)]
    pub(crate) fn rhs_with<E: Eval>(
        &self,
        e: &E,
        t: f64,
        y: &[f64],
        l: &Layout,
        mut out: impl FnMut(usize, E::T),
    ) {
        let k = self.kinematics(e, t, y, l);
        let (ld, el) = (k.lam_dot, k.elec);
        out(0, ld);
        if let Some(i) = l.v {
            out(i, k.force / self.mass);
        }
        let mut d_visc = e.nv() * ld * ld;
        for j in 0..l.arms {
            let (kj, tau) = e.arm(j);
            let s = e.y(y, l.sig + j);
            out(l.sig + j, kj * ld - s / tau);
            d_visc = d_visc + s * s / (kj * tau);
        }
        if let Some(i) = l.src {
            out(i, k.terminal.src_rate);
        }
        if let (Some(i), Some(o)) = (l.ctl, k.terminal.pid) {
            out(i, o.i_dot);
            out(i + 1, o.d_dot);
        }
        let q = l.quad;
        match self.source {
            Source::Resistance { ohm } => {
                let drop = el.u - el.voltage;
                out(q, el.u * el.current);
                out(q + 3, drop * drop / ohm);
            }
            _ => {
                out(q, el.voltage * el.current);
                out(q + 3, E::T::cst(0.0));
            }
        }
        out(q + 1, d_visc * self.vol);
        out(q + 2, el.leakage);
    }

    /// The terminal voltage V at (t, y): the source's state (a rise-time lag's
    /// voltage, a resistance's charge over C), else the input or the controller's
    /// output; the `v` of [`Plant::terminal`] without its rates (the pull-in event
    /// reads it at every step).
    pub fn voltage(&self, t: f64, y: &[f64]) -> f64 {
        let l = self.layout();
        match (self.source, l.src, &self.control) {
            (Source::RiseTime { .. }, Some(i), _) => y[i],
            (Source::Resistance { .. }, Some(i), _) => y[i] / self.capacitance(y[0]).0,
            (Source::Ideal, _, None) => self.input.eval(t).0,
            _ => self.terminal(&Plain(self), t, y, &l).v,
        }
    }

    /// The drive D (N·m): the generalised force without inertia and dashpot (see
    /// the module documentation). Zero along a quasi-static run without dashpot.
    pub fn drive(&self, t: f64, y: &[f64]) -> f64 {
        let (e, l) = (Plain(self), self.layout());
        self.drive_with(&e, y, &l, &self.terminal(&e, t, y, &l))
    }

    /// The electrical state at a state with the current at the state's own λ̇: what
    /// a sample reports.
    pub fn output(&self, t: f64, y: &[f64]) -> Electrical {
        self.output_with(&Plain(self), t, y, &self.layout())
    }

    /// [`Plant::output`] for every number type: the terminal, λ̇ as the right-hand
    /// side computes it (with inertia the velocity state, so without the force),
    /// the rates at λ̇.
    #[inline]
    pub(crate) fn output_with<E: Eval>(
        &self,
        e: &E,
        t: f64,
        y: &[f64],
        l: &Layout,
    ) -> Electrical<E::T> {
        match l.v {
            Some(i) => self.rates(&self.terminal(e, t, y, l), e.y(y, i)),
            None => self.kinematics(e, t, y, l).elec,
        }
    }
}

/// The most arms a right-hand side fixed per layout has (the seed's tables have four).
const FIXED_ARMS: usize = 4;

impl Plant {
    /// [`System::rhs`](super::integrate::System::rhs) with `ARMS` arms: the rest of
    /// the layout (inertia, source state, controller) chosen here.
    #[inline(always)]
    fn rhs_arms<const ARMS: usize>(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let source = !matches!(self.source, Source::Ideal);
        match (self.inertia, source, self.control.is_some()) {
            (false, false, false) => self.rhs_fixed::<false, ARMS, false, false>(t, y, dy),
            (false, false, true) => self.rhs_fixed::<false, ARMS, false, true>(t, y, dy),
            (false, true, false) => self.rhs_fixed::<false, ARMS, true, false>(t, y, dy),
            (false, true, true) => self.rhs_fixed::<false, ARMS, true, true>(t, y, dy),
            (true, false, false) => self.rhs_fixed::<true, ARMS, false, false>(t, y, dy),
            (true, false, true) => self.rhs_fixed::<true, ARMS, false, true>(t, y, dy),
            (true, true, false) => self.rhs_fixed::<true, ARMS, true, false>(t, y, dy),
            (true, true, true) => self.rhs_fixed::<true, ARMS, true, true>(t, y, dy),
        }
    }

    /// The right-hand side over the layout [`Layout::of`]`(INERTIA, ARMS, SOURCE,
    /// CONTROL)`, which must be the plant's: its state vectors cut to that length,
    /// so that every index is a constant the compiler checks once.
    #[inline(never)]
    fn rhs_fixed<
        const INERTIA: bool,
        const ARMS: usize,
        const SOURCE: bool,
        const CONTROL: bool,
    >(
        &self,
        t: f64,
        y: &[f64],
        dy: &mut [f64],
    ) {
        let l = const { Layout::of(INERTIA, ARMS, SOURCE, CONTROL) };
        let (y, dy) = (&y[..l.n], &mut dy[..l.n]);
        self.rhs_with(&Plain(self), t, y, &l, |i, v| dy[i] = v);
    }
}

/// Sensed contraction ŷ = 1 − sqrt(C_rest/C) (Eq. 3.22).
#[inline]
fn sensed<T: Num>(c_rest: T, c: T) -> T {
    -(c_rest / c).sqrt() + 1.0
}

/// Electrical quantities at an instant.
#[derive(Debug, Clone, Copy)]
pub struct Electrical<T = f64> {
    /// Input (source open-circuit) voltage (V).
    pub u: T,
    /// Terminal voltage (V).
    pub voltage: T,
    /// Its rate (V/s).
    pub voltage_rate: T,
    /// Capacitance (F).
    pub capacitance: T,
    /// dC/dλ (F).
    pub dc: T,
    /// Current into the actuator incl. dC/dt·V and leakage (A).
    pub current: T,
    /// Leakage power G·V² (W).
    pub leakage: T,
}

impl super::integrate::System for Plant {
    fn dim(&self) -> usize {
        self.layout().n
    }
    /// The right-hand side of the plant's layout: a copy fixed when the code is
    /// built for every layout with up to [`FIXED_ARMS`] arms (every index a constant:
    /// no bounds check, no match on the layout, the arms' loops unrolled), else at
    /// run time; the same arithmetic either way.
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        match self.arms.len() {
            0 => self.rhs_arms::<0>(t, y, dy),
            1 => self.rhs_arms::<1>(t, y, dy),
            2 => self.rhs_arms::<2>(t, y, dy),
            3 => self.rhs_arms::<3>(t, y, dy),
            FIXED_ARMS => self.rhs_arms::<FIXED_ARMS>(t, y, dy),
            _ => self.rhs_with(&Plain(self), t, y, &self.layout(), |i, v| dy[i] = v),
        }
    }
    fn jacobian_times(&self, t: f64, y: &[f64], v: &[f64], out: &mut [f64]) {
        Plant::jacobian_times(self, t, y, v, out)
    }
    fn n_params(&self) -> usize {
        self.sens_columns.len()
    }
    /// Every state before the energy-balance quadratures (which feed back into
    /// none).
    fn dynamic_dim(&self) -> usize {
        self.layout().quad
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) {
        Plant::jacobian(self, t, y, jac)
    }
    fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut [f64]) {
        Plant::param_jacobian(self, t, y, dfdp)
    }
    fn sensitivity_rate(&self, t: f64, y: &[f64], s: &[f64], k: usize, out: &mut [f64]) {
        Plant::sensitivity_rate(self, t, y, s, k, out)
    }
    fn initial_sensitivity(&self, out: &mut [f64]) {
        self.initial_state_sensitivity(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn layer(arms: &str) -> Plant {
        let text = format!(
            r#"
[actuator]
kind = "stack"
radius = "5 mm"
layer_thickness = "1 mm"
layers = 1
[material]
hyperelastic = {{ model = "neo-hookean", parameters = {{ mu = "100 kPa" }} }}
viscous = {{ arms = [ {arms} ] }}
relative_permittivity = 4.0
density = "1000 kg/m3"
[[input]]
kind = "step"
amplitude = "1 kV"
[time]
span = "1 s"
"#
        );
        let s = Scene::parse(&text, Path::new("t.toml")).unwrap();
        Plant::new(&s, false, &vec![true; s.material.viscous.arms.len()]).unwrap()
    }

    #[test]
    fn fastest_arm_rate_is_the_largest_eigenvalue_of_the_quasi_static_arms() {
        // one arm: the retardation rate (1 − w)/τ, w = Vol·k/K
        let p = layer(r#"{ k = "1 MPa", tau = "10 ms" }"#);
        let w = p.vol * 1e6 / p.instant_stiffness(p.lam0, 0.0);
        let s = p.fastest_arm_rate();
        assert!((s / ((1.0 - w) / 0.01) - 1.0).abs() < 1e-12, "{s}");
        // two arms: the largest eigenvalue of T − u·1ᵀT (2×2, quadratic formula)
        let p = layer(r#"{ k = "300 kPa", tau = "10 ms" }, { k = "200 kPa", tau = "30 ms" }"#);
        let k = p.instant_stiffness(p.lam0, 0.0);
        let (t1, t2) = (1.0 / 0.01, 1.0 / 0.03);
        let (u1, u2) = (p.vol * 3e5 / k, p.vol * 2e5 / k);
        let (a, b, c, d) = (t1 - u1 * t1, -u1 * t2, -u2 * t1, t2 - u2 * t2);
        let (tr, det) = (a + d, a * d - b * c);
        let largest = 0.5 * (tr + (tr * tr - 4.0 * det).sqrt());
        let s = p.fastest_arm_rate();
        assert!((s / largest - 1.0).abs() < 1e-12, "{s} vs {largest}");
        assert!(s > t2 && s < t1);
        // τc: a tenth of 1/s here (the step input has no time scale, the span is 1 s)
        assert!((p.tau_c * s / BAUMGARTE_FRACTION - 1.0).abs() < 1e-12);
    }

    /// The contract of `dynamic_dim`: no rate reads the quadratures after it
    /// (∂f_i/∂y_j = 0 exactly for every i and ns ≤ j, and the right-hand side is the
    /// same bit for bit with them set to NaN), on every shipped scene
    /// (stacks and helices, ideal, rise-time and resistance sources, PID), with and
    /// without inertia, at the rest state and at a state moved off it.
    #[test]
    fn no_rate_reads_the_quadratures() {
        use crate::sim::integrate::System;
        let mut checked = 0;
        for entry in std::fs::read_dir("datasets/scenes").unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let s = Scene::read(&path).unwrap();
            for inertia in [false, true] {
                let p =
                    Plant::new(&s, inertia, &vec![true; s.material.viscous.arms.len()]).unwrap();
                let (n, ns) = (p.dim(), p.dynamic_dim());
                assert_eq!(ns + 4, n, "{}: four quadratures", path.display());
                let mut y = p.initial_state();
                let mut jac = vec![0.0; n * n];
                for moved in [false, true] {
                    if moved {
                        y[0] *= 0.97;
                        for (j, v) in y.iter_mut().enumerate().skip(1) {
                            *v += 1e-3 * (j as f64);
                        }
                    }
                    let t = 0.3 * s.time.span;
                    p.jacobian(t, &y, &mut jac);
                    for i in 0..n {
                        for j in ns..n {
                            assert_eq!(jac[i * n + j], 0.0, "{}: J[{i}][{j}]", path.display());
                        }
                    }
                    let (mut f, mut f_nan) = (vec![0.0; n], vec![0.0; n]);
                    p.rhs(t, &y, &mut f);
                    let mut y_nan = y.clone();
                    y_nan[ns..].fill(f64::NAN);
                    p.rhs(t, &y_nan, &mut f_nan);
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&f), bits(&f_nan), "{}", path.display());
                    checked += 1;
                }
            }
        }
        assert!(checked >= 40, "{checked} plants checked");
    }

    /// [`Plant::voltage`] is the terminal's V bit for bit, for every source (a
    /// rise-time lag, a resistance, ideal) and under closed-loop control, at the
    /// rest state and at a moved one.
    #[test]
    fn voltage_is_the_terminals() {
        let mut sources = std::collections::BTreeSet::new();
        for name in [
            "stack_step_5kV",
            "stack_pid_triangle",
            "stack_triangle_100Hz",
        ] {
            let text = std::fs::read_to_string(format!("datasets/scenes/{name}.toml")).unwrap();
            let resistance = text.replace("rise_time = \"1 ms\"", "resistance_ohm = 2e6");
            for t in [&text, &resistance] {
                let s = Scene::parse(t, Path::new("v.toml")).unwrap();
                let p = Plant::new(&s, true, &vec![true; s.material.viscous.arms.len()]).unwrap();
                let l = p.layout();
                let mut y = p.initial_state();
                for moved in [false, true] {
                    if moved {
                        y[0] *= 0.97;
                        for (j, v) in y.iter_mut().enumerate().skip(1) {
                            *v += 1e-3 * (j as f64);
                        }
                    }
                    let t = 0.3 * s.time.span;
                    let v = p.terminal(&Plain(&p), t, &y, &l).v;
                    assert_eq!(p.voltage(t, &y).to_bits(), v.to_bits(), "{name}");
                }
                let kind = match p.source {
                    Source::RiseTime { .. } => "rise time",
                    Source::Resistance { .. } => "resistance",
                    Source::Ideal => "ideal",
                };
                sources.insert((kind, p.control.is_some()));
            }
        }
        assert!(sources.len() >= 4, "{sources:?}");
    }

    /// `System::rhs` (a copy fixed per layout up to `FIXED_ARMS` arms) is the
    /// right-hand side over the run-time layout bit for bit, on every layout: the
    /// shipped scenes (ideal, rise-time and resistance sources, PID) with and without
    /// inertia and with 0…4 arms integrated, and a layer of six arms (the run-time
    /// path), at the rest state and at a moved one.
    #[test]
    fn rhs_fixed_per_layout_is_the_run_time_layouts() {
        use crate::sim::integrate::System;
        let mut layouts = std::collections::BTreeSet::new();
        let mut check = |p: &Plant, t: f64| {
            let l = p.layout();
            let mut y = p.initial_state();
            let (mut fixed, mut run_time) = (vec![0.0; l.n], vec![0.0; l.n]);
            for moved in [false, true] {
                if moved {
                    y[0] *= 0.97;
                    for (j, v) in y.iter_mut().enumerate().skip(1) {
                        *v += 1e-3 * (j as f64);
                    }
                }
                p.rhs(t, &y, &mut fixed);
                p.rhs_with(&Plain(p), t, &y, &l, |i, v| run_time[i] = v);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fixed), bits(&run_time), "{l:?}");
            }
            layouts.insert((l.v.is_some(), l.arms, l.src.is_some(), l.ctl.is_some()));
        };
        for name in [
            "stack_step_5kV",
            "stack_pid_triangle",
            "stack_triangle_100Hz",
            "hdea_step_10N",
        ] {
            let text = std::fs::read_to_string(format!("datasets/scenes/{name}.toml")).unwrap();
            let resistance = text.replace("rise_time = \"1 ms\"", "resistance_ohm = 2e6");
            for text in [&text, &resistance] {
                let s = Scene::parse(text, Path::new("r.toml")).unwrap();
                let arms = s.material.viscous.arms.len();
                for (inertia, kept) in [false, true]
                    .into_iter()
                    .flat_map(|i| (0..=arms).map(move |m| (i, m)))
                {
                    let keep: Vec<bool> = (0..arms).map(|j| j < kept).collect();
                    check(&Plant::new(&s, inertia, &keep).unwrap(), 0.3 * s.time.span);
                }
            }
        }
        let arm = r#"{ k = "100 kPa", tau = "10 ms" }"#;
        let six = layer(&[arm; 6].join(", "));
        assert!(six.arms.len() > FIXED_ARMS);
        check(&six, 0.3);
        // every fixed copy's arm count and all four other choices, and the run-time path
        assert!(layouts.len() >= 20, "{layouts:?}");
        assert!((0..=FIXED_ARMS).all(|m| layouts.iter().any(|l| l.1 == m)));
        assert!(layouts.iter().any(|l| l.1 > FIXED_ARMS));
    }
}
