//! Axial mode of a scene and the choice of model fidelity.
//!
//! Axial mode: the linearised single-degree-of-freedom model about the loaded rest
//! state, with complex stiffness K(ω) = Vol·[P'(λ0) + iωNv + Σ kj·iωτj/(1+iωτj)] and
//! mass m_eff·L0²; ω solves ω² = Re K(ω)/M (fixed point), ζ = Im K/(2·Re K), Q = 1/(2ζ).
//!
//! Fidelity (`auto`):
//! * a Maxwell arm is lumped as a *frozen spring* when τ ≥ 100·span (estimated error
//!   (span/τ)·k/E, E the instantaneous modulus), or as a *dashpot* η when
//!   τ ≤ 0.01·t_in, t_in the input's shortest time scale (error (τ/t_in)·k/E); lumped
//!   only if the estimate is ≤ 1e-4;
//! * inertia is dropped (quasi-static) when ζ ≥ 0.5 and the input is far below
//!   resonance: with r = f_in/f_n the second-order transfer function differs from its
//!   static value by ≈ r·sqrt(r² + 4ζ²), required ≤ 1e-3.
//!
//! The criteria hold with or without a Kelvin-Voigt dashpot. The quasi-static model
//! keeps every damping element exactly (dashpot and arms) and drops only the inertia;
//! ζ is that of the axial mode including the arms at the mode's own frequency, the
//! frequency at which an input kink would make the dynamic model ring, so ζ ≥ 0.5
//! says such ringing dies within a period whatever provides the damping. Without a
//! dashpot and without arms ζ = 0 and quasi-static is never chosen. Without a
//! dashpot the quasi-static force balance is an algebraic constraint on λ (see
//! `plant`): it cannot follow a jump of the terminal voltage (an ideal source with a
//! step input, input time scale 0), which is refused; `auto` never meets it (r = ∞).

use super::plant::Plant;
use super::scene::{FidelityChoice, Scene, Source};
use crate::error::{Error, Result};
use serde::Serialize;
use std::f64::consts::PI;

/// The axial mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AxialMode {
    /// Frequency (Hz).
    #[serde(rename = "frequency_Hz")]
    pub frequency_hz: f64,
    /// Damping ratio ζ.
    pub damping_ratio: f64,
    /// Quality factor Q = 1/(2ζ).
    pub q_factor: f64,
    /// Share of the damping from the Kelvin-Voigt dashpot Nv (rest from the arms).
    pub dashpot_share: f64,
}

/// Axial mode of a plant about its rest state.
pub fn axial_mode(p: &Plant) -> AxialMode {
    let k_re = |w: f64| {
        p.vol
            * (p.tangent(p.lam0)
                + p.frozen_k
                + p.arms
                    .iter()
                    .map(|&(k, t)| k * (w * t).powi(2) / (1.0 + (w * t).powi(2)))
                    .sum::<f64>())
    };
    let mut w = (k_re(1e9) / p.mass).sqrt();
    for _ in 0..100 {
        w = (k_re(w) / p.mass).sqrt();
    }
    let dash = p.vol * w * p.nv;
    let arms = p.vol
        * p.arms
            .iter()
            .map(|&(k, t)| k * w * t / (1.0 + (w * t).powi(2)))
            .sum::<f64>();
    let zeta = (dash + arms) / (2.0 * k_re(w));
    AxialMode {
        frequency_hz: w / (2.0 * PI),
        damping_ratio: zeta,
        q_factor: if zeta > 0.0 {
            1.0 / (2.0 * zeta)
        } else {
            f64::INFINITY
        },
        dashpot_share: if dash + arms > 0.0 {
            dash / (dash + arms)
        } else {
            0.0
        },
    }
}

/// What ran and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fidelity {
    /// `dynamic` or `quasi-static`.
    pub model: String,
    /// Why.
    pub reason: String,
    /// Arms kept / lumped, one line each.
    pub arms: Vec<String>,
    /// Estimated relative error of the simplifications (fraction of the stroke).
    pub estimated_error: f64,
    /// Per-arm flags: true = integrated.
    #[serde(skip)]
    pub keep: Vec<bool>,
    /// With inertia.
    #[serde(skip)]
    pub inertia: bool,
    /// The axial mode of the full plant the choice rests on.
    #[serde(skip)]
    pub mode: AxialMode,
}

/// The input's shortest time scale (s), including the source's rise time; 0 for a jump.
pub fn input_time_scale(scene: &Scene, c0: f64) -> f64 {
    let t = match &scene.control {
        Some(pid) => pid.reference.time_scale().min(pid.tau_d),
        None => scene.input.time_scale(),
    };
    match scene.source {
        Source::Ideal => t,
        Source::RiseTime { tau_s } => t.max(tau_s),
        Source::Resistance { ohm } => t.max(ohm * c0),
    }
}

/// Choose the fidelity of a scene.
pub fn choose(scene: &Scene) -> Result<Fidelity> {
    let n = scene.material.viscous.arms.len();
    let full = super::full_plant(scene)?;
    let mode = axial_mode(&full);
    let t_in = input_time_scale(scene, full.capacitance(full.lam0).0);
    let e_inst = full.tangent(full.lam0) + full.arms.iter().map(|a| a.0).sum::<f64>();
    let span = scene.time.span;
    let mut keep = vec![true; n];
    let mut notes = Vec::new();
    let mut err = 0.0;
    let auto = scene.time.fidelity == FidelityChoice::Auto;
    for (i, &(k, tau)) in full.arms.iter().enumerate() {
        let frozen = (span / tau) * k / e_inst;
        let relaxed = if t_in > 0.0 {
            (tau / t_in) * k / e_inst
        } else {
            f64::INFINITY
        };
        if auto && tau >= 100.0 * span && frozen <= 1e-4 {
            keep[i] = false;
            err += frozen;
            notes.push(format!("arm {} (τ = {tau:.4} s) frozen over the {span} s span: lumped as a spring (est. error {frozen:.1e})", i + 1));
        } else if auto && tau <= 0.01 * t_in && relaxed <= 1e-4 {
            keep[i] = false;
            err += relaxed;
            notes.push(format!("arm {} (τ = {tau:.4} s) relaxed on the input's {t_in:.3e} s time scale: lumped as a dashpot (est. error {relaxed:.1e})", i + 1));
        } else {
            notes.push(format!("arm {} (τ = {tau:.4} s) integrated", i + 1));
        }
    }
    let lumped =
        Plant::new(scene, false, &keep).map_err(|why| super::budget::no_rest_state(scene, why))?;
    let f_in = if t_in > 0.0 {
        1.0 / (2.0 * PI * t_in)
    } else {
        f64::INFINITY
    };
    let r = f_in / mode.frequency_hz;
    let z = mode.damping_ratio;
    let qs_err = r * (r * r + 4.0 * z * z).sqrt();
    // No moving mass (load.mass 0 and effective_mass_fraction 0): the axial mode
    // is infinitely fast and the motion quasi-static exactly; an equation of motion
    // with zero mass cannot be integrated.
    let massless = full.mass.is_nan() || full.mass <= 0.0;
    if massless {
        if scene.time.fidelity == FidelityChoice::Dynamic || scene.control.is_some() {
            return Err(Error::settings(format!(
                "scene '{}': load.effective_mass_fraction: the actuator has no moving mass (load.mass = 0 and load.effective_mass_fraction = 0): its equation of motion cannot be integrated (dynamic fidelity, closed loop)",
                scene.name
            ))
            .with_hint("give load.effective_mass_fraction > 0 (El Atrache Ceballos (2021): ½) or a load.mass"));
        }
        if lumped.nv <= 0.0 && t_in == 0.0 {
            return Err(Error::settings(format!(
                "scene '{}': load.effective_mass_fraction: the actuator has no moving mass (load.mass = 0 and load.effective_mass_fraction = 0), so it is quasi-static, and without a Kelvin-Voigt dashpot it cannot follow a jump of the terminal voltage (ideal source, step input)",
                scene.name
            ))
            .with_hint("give load.effective_mass_fraction > 0 (El Atrache Ceballos (2021): ½), source.rise_time, or material.viscous.nv > 0"));
        }
    }
    let (inertia, reason) = match scene.time.fidelity {
        _ if massless => (
            false,
            "quasi-static: no moving mass (load.mass = 0, effective_mass_fraction = 0)".to_string(),
        ),
        FidelityChoice::Dynamic => (true, "dynamic: requested by the scene".to_string()),
        FidelityChoice::QuasiStatic => {
            if lumped.nv <= 0.0 && t_in == 0.0 {
                return Err(Error::settings(
                    "quasi-static fidelity without a Kelvin-Voigt dashpot cannot follow a jump of the terminal voltage (ideal source, step input)",
                )
                .with_hint("give source.rise_time or source.resistance_ohm, material.viscous.nv > 0, or use fidelity = \"dynamic\""));
            }
            err += qs_err;
            (false, format!("quasi-static: requested by the scene (input/resonance ratio {r:.2e}, ζ = {z:.3}, est. error {qs_err:.1e})"))
        }
        FidelityChoice::Auto if scene.control.is_some() => (
            true,
            "dynamic: closed loop (the controller acts on the motion)".to_string(),
        ),
        FidelityChoice::Auto => {
            if z >= 0.5 && qs_err <= 1e-3 {
                err += qs_err;
                (false, format!("quasi-static: the input ({f_in:.3e} Hz) is far below the axial mode ({:.1} Hz, ζ = {z:.3}); est. error {qs_err:.1e}", mode.frequency_hz))
            } else if z < 0.5 {
                (true, format!("dynamic: the axial mode ({:.1} Hz) is lightly damped (ζ = {z:.2e}), so inertia matters", mode.frequency_hz))
            } else {
                (true, format!("dynamic: the input ({f_in:.3e} Hz) is not far enough below the axial mode ({:.1} Hz): quasi-static would err by ≈{qs_err:.1e}", mode.frequency_hz))
            }
        }
    };
    Ok(Fidelity {
        model: if inertia { "dynamic" } else { "quasi-static" }.into(),
        reason,
        arms: notes,
        estimated_error: err,
        keep,
        inertia,
        mode,
    })
}
