//! The lumped electromechanical model shared by the stack and the helix, as the
//! Lagrange equation in the thickness stretch λ (one axial degree of freedom):
//!
//! ```text
//! M·λ̈ = −Vol·[P(λ) + Nv·λ̇ + Σσj + kf·(λ − λf)] + F_load·L0 + ½·V²·dC/dλ
//! dσj/dt = kj·λ̇ − σj/τj                                   (seed Eq. 3.16)
//! ```
//! with M = m_eff·L0² (Z = L0·λ), P the nominal stress of the hyperelastic model in
//! the layer's mode (uniaxial compression for a stack, planar for the seed's helix),
//! Vol the strained volume, F_load = (m_load + f·m_act)·g + F (Eq. 3.9–3.10) and
//! ½V²·dC/dλ the electrostatic generalised force, which for the stack is exactly the
//! Maxwell pressure ε(V/z)² on the current area (Eq. 3.1, 3.7) and for the helix
//! contains the projection on z (Eq. 4.24). kf, λf: Maxwell arms lumped as frozen
//! springs by the fidelity choice. Quasi-static fidelity drops M and solves the force
//! balance for λ̇ (needs Nv > 0).
//!
//! Quadrature states accumulate electrical work in, viscous and leakage dissipation
//! and source losses, for the energy balance.

use super::input::Waveform;
use super::scene::{Actuator, Pid, Scene, Source};
use crate::material::hyperelastic::{Mode, StrainEnergy};
use std::sync::Arc;

/// Vacuum permittivity (F/m).
pub const EPS0: f64 = 8.854_187_812_8e-12;

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
    /// Absolute permittivity (F/m).
    pub eps: f64,
    /// Leakage conductance per capacitance 1/(ρ·ε) (1/s); 0 without leakage.
    pub g_per_c: f64,
    /// Kelvin-Voigt dashpot (Pa·s), including arms lumped as dashpots.
    pub nv: f64,
    /// Active arms (k in Pa, τ in s).
    pub arms: Vec<(f64, f64)>,
    /// Stiffness of arms lumped as frozen springs (Pa), about `lam_f`.
    pub frozen_k: f64,
    /// Reference stretch of the frozen springs.
    pub lam_f: f64,
    /// With inertia (dynamic) or without (quasi-static).
    pub inertia: bool,
    /// Source model.
    pub source: Source,
    /// Input voltage.
    pub input: Waveform,
    /// Initial (loaded, relaxed) stretch.
    pub lam0: f64,
    /// Closed loop, if any.
    pub control: Option<Pid>,
    /// Capacitance at the rest state (the self-sensing calibration).
    pub c_rest: f64,
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
}

impl Plant {
    /// Build the plant of a scene with given lumping (arms kept, Nv add, frozen k).
    pub fn new(scene: &Scene, inertia: bool, keep: &[bool]) -> Plant {
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
        let eps = EPS0 * m.eps_r;
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
            eps,
            g_per_c: m.resistivity.map(|r| 1.0 / (r * eps)).unwrap_or(0.0),
            nv,
            arms,
            frozen_k,
            lam_f: 1.0,
            inertia,
            source: scene.source,
            input: scene.input.clone(),
            lam0: 1.0,
            control: scene.control.clone(),
            c_rest: 0.0,
        };
        p.lam0 = p.static_stretch(0.0, 1.0).unwrap_or(1.0);
        p.lam_f = p.lam0;
        p.c_rest = p.capacitance(p.lam0).0;
        p
    }

    /// PID (Eq. 3.29): (clamped command in V, error, unclamped output).
    #[inline]
    pub fn pid(&self, pid: &Pid, t: f64, y: &[f64]) -> (f64, f64, f64) {
        let i = self.layout().ctl.unwrap_or(0);
        let e = pid.reference.eval(t).0 - self.sensed_contraction(y[0]);
        let u = pid.kp * e + pid.ki * y[i] + pid.kd * (e - y[i + 1]) / pid.tau_d;
        (u.clamp(0.0, pid.v_max), e, u)
    }

    /// Contraction estimated from the capacitance with the stack law C ∝ λ⁻²
    /// (self-sensing, Eq. 3.22): 1 − sqrt(C_rest/C).
    #[inline]
    pub fn sensed_contraction(&self, lam: f64) -> f64 {
        1.0 - (self.c_rest / self.capacitance(lam).0).sqrt()
    }

    /// The source's open-circuit voltage and its rate: the input or the PID command.
    #[inline]
    pub fn command(&self, t: f64, y: &[f64]) -> (f64, f64) {
        match &self.control {
            Some(pid) => (self.pid(pid, t, y).0, 0.0),
            None => self.input.eval(t),
        }
    }

    /// Nominal stress P(λ) of the layer (Pa).
    #[inline]
    pub fn stress(&self, lam: f64) -> f64 {
        self.model.nominal_stress(&self.params, self.mode, lam)
    }
    /// Tangent dP/dλ (Pa).
    #[inline]
    pub fn tangent(&self, lam: f64) -> f64 {
        self.model.tangent(&self.params, self.mode, lam)
    }
    /// Capacitance and its λ-derivatives.
    #[inline]
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
        let (_, dc, _) = self.capacitance(lam);
        -self.vol * self.stress(lam) + self.f_load * self.l0 + 0.5 * v * v * dc
    }
    /// Long-term stiffness −∂(static force)/∂λ at (λ, V).
    pub fn static_stiffness(&self, lam: f64, v: f64) -> f64 {
        let (_, _, d2c) = self.capacitance(lam);
        self.vol * self.tangent(lam) - 0.5 * v * v * d2c
    }
    /// Instantaneous stiffness (arms act as springs): pull-in when it reaches zero.
    pub fn instant_stiffness(&self, lam: f64, v: f64) -> f64 {
        let k: f64 = self.arms.iter().map(|a| a.0).sum::<f64>() + self.frozen_k;
        self.static_stiffness(lam, v) + self.vol * k
    }
    /// Stable static equilibrium reached from `start` at voltage `v` (fully relaxed),
    /// by damped Newton along the stable branch; None if none exists there.
    pub fn static_stretch(&self, v: f64, start: f64) -> Option<f64> {
        let mut lam = start;
        for _ in 0..200 {
            let f = self.static_force(lam, v);
            let k = self.static_stiffness(lam, v);
            if k <= 0.0 {
                return None;
            }
            let step = (f / k).clamp(-0.05 * lam, 0.05 * lam);
            lam += step;
            if lam <= 0.05 {
                return None;
            }
            if step.abs() < 1e-14 * lam {
                return (self.static_stiffness(lam, v) > 0.0).then_some(lam);
            }
        }
        None
    }

    /// State layout.
    pub fn layout(&self) -> Layout {
        let v = self.inertia.then_some(1);
        let sig = if self.inertia { 2 } else { 1 };
        let after = sig + self.arms.len();
        let src = (!matches!(self.source, Source::Ideal)).then_some(after);
        let after = after + src.is_some() as usize;
        let ctl = self.control.is_some().then_some(after);
        let quad = after + 2 * ctl.is_some() as usize;
        Layout {
            v,
            sig,
            src,
            ctl,
            quad,
            n: quad + 4,
        }
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
            let u = match self.control {
                Some(_) => self.command(0.0, &y).0,
                None => self.input.eval(-f64::MIN_POSITIVE).0,
            };
            y[i] = match self.source {
                Source::RiseTime { .. } => u,
                Source::Resistance { .. } => u * self.capacitance(self.lam0).0,
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

    /// Terminal voltage, its rate, and the current into the actuator (incl. leakage).
    #[inline]
    pub fn electrical(&self, t: f64, y: &[f64], lam_dot: f64) -> Electrical {
        let l = self.layout();
        let lam = y[0];
        let (c, dc, _) = self.capacitance(lam);
        let g = self.g_per_c * c;
        let (u, du) = self.command(t, y);
        let (v, dv, current) = match self.source {
            Source::Ideal => (u, du, dc * lam_dot * u + c * du + g * u),
            Source::RiseTime { tau_s } => {
                let v = y[l.src.unwrap_or(0)];
                let dv = (u - v) / tau_s;
                (v, dv, dc * lam_dot * v + c * dv + g * v)
            }
            Source::Resistance { ohm } => {
                let v = y[l.src.unwrap_or(0)] / c;
                let i = (u - v) / ohm;
                let dv = (i - g * v - dc * lam_dot * v) / c;
                (v, dv, i)
            }
        };
        Electrical {
            u,
            voltage: v,
            voltage_rate: dv,
            capacitance: c,
            dc,
            current,
            leakage: g * v * v,
        }
    }

    /// λ̇, the generalised acceleration force and the electrical state (with the
    /// current evaluated at λ̇) at a state.
    #[inline]
    fn kinematics(&self, t: f64, y: &[f64], l: &Layout) -> (f64, f64, Electrical) {
        let lam = y[0];
        let sig: f64 = y[l.sig..l.sig + self.arms.len()].iter().sum();
        let elastic = self.stress(lam) + sig + self.frozen_k * (lam - self.lam_f);
        // the terminal voltage does not depend on λ̇; the current does (dC/dt·V)
        let mut e = self.electrical(t, y, 0.0);
        let drive =
            -self.vol * elastic + self.f_load * self.l0 + 0.5 * e.voltage * e.voltage * e.dc;
        let (lam_dot, force) = match l.v {
            Some(i) => (y[i], drive - self.vol * self.nv * y[i]),
            None => (drive / (self.vol * self.nv), 0.0),
        };
        match self.source {
            Source::Resistance { .. } => {
                e.voltage_rate -= e.dc * lam_dot * e.voltage / e.capacitance
            }
            _ => e.current += e.dc * lam_dot * e.voltage,
        }
        (lam_dot, force, e)
    }

    /// λ̇ at a state (both fidelities).
    pub fn lam_dot(&self, t: f64, y: &[f64]) -> f64 {
        self.kinematics(t, y, &self.layout()).0
    }
}

/// Electrical quantities at an instant.
#[derive(Debug, Clone, Copy)]
pub struct Electrical {
    /// Input (source open-circuit) voltage (V).
    pub u: f64,
    /// Terminal voltage (V).
    pub voltage: f64,
    /// Its rate (V/s).
    pub voltage_rate: f64,
    /// Capacitance (F).
    pub capacitance: f64,
    /// dC/dλ (F).
    pub dc: f64,
    /// Current into the actuator incl. dC/dt·V and leakage (A).
    pub current: f64,
    /// Leakage power G·V² (W).
    pub leakage: f64,
}

impl super::integrate::System for Plant {
    fn dim(&self) -> usize {
        self.layout().n
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let l = self.layout();
        let (lam_dot, force, e) = self.kinematics(t, y, &l);
        dy[0] = lam_dot;
        if let Some(i) = l.v {
            dy[i] = force / self.mass;
        }
        let mut d_visc = self.nv * lam_dot * lam_dot;
        for (j, &(k, tau)) in self.arms.iter().enumerate() {
            let s = y[l.sig + j];
            dy[l.sig + j] = k * lam_dot - s / tau;
            d_visc += s * s / (k * tau);
        }
        if let Some(i) = l.src {
            dy[i] = match self.source {
                Source::RiseTime { .. } => e.voltage_rate,
                Source::Resistance { .. } => e.current - self.g_per_c * e.capacitance * e.voltage,
                Source::Ideal => 0.0,
            };
        }
        if let (Some(i), Some(pid)) = (l.ctl, &self.control) {
            let (_, e, u) = self.pid(pid, t, y);
            let wind = (u > pid.v_max && e > 0.0) || (u < 0.0 && e < 0.0);
            dy[i] = if wind { 0.0 } else { e };
            dy[i + 1] = (e - y[i + 1]) / pid.tau_d;
        }
        let q = l.quad;
        match self.source {
            Source::Resistance { ohm } => {
                dy[q] = e.u * e.current;
                dy[q + 3] = (e.u - e.voltage).powi(2) / ohm;
            }
            _ => {
                dy[q] = e.voltage * e.current;
                dy[q + 3] = 0.0;
            }
        }
        dy[q + 1] = self.vol * d_visc;
        dy[q + 2] = e.leakage;
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) {
        // TEMPORARY central differences (replaced by the analytic Jacobian)
        let n = y.len();
        let mut yp = y.to_vec();
        let mut fp = vec![0.0; n];
        let mut fm = vec![0.0; n];
        for j in 0..n {
            let d = 1e-7 * y[j].abs().max(1e-6);
            yp[j] = y[j] + d;
            self.rhs(t, &yp, &mut fp);
            yp[j] = y[j] - d;
            self.rhs(t, &yp, &mut fm);
            yp[j] = y[j];
            for i in 0..n {
                jac[i * n + j] = (fp[i] - fm[i]) / (2.0 * d);
            }
        }
    }
}
