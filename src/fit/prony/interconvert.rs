//! What a fitted Prony series gives in every domain: E(t), E′(ω), E″(ω), tan δ and
//! the creep compliance J(t), for the reports of both domains.
//!
//! E(t) = E∞ + Σ Eᵢ·e^(−t/τᵢ); E′, E″ of the generalized Maxwell body (Ferry 1980,
//! eq. 3-44, 3-45; [`Prony::storage_loss`]); tan δ = E″/E′. The creep compliance is
//! the exact interconversion of [`Prony::creep`]: J's Laplace transform is
//! 1/(s²·Ē(s)), whose poles, the zeros of s·Ē(s) = E∞ + Σ Eᵢ·sτᵢ/(1 + sτᵢ)
//! between consecutive −1/τᵢ (one in each interval, s·Ē increasing), give the
//! retardation times (Tschoegl, *The Phenomenological Theory of Linear Viscoelastic
//! Behavior*, 1989, §4.6; the Prony–Prony route of Park & Schapery 1999, done with
//! the roots instead of collocation, so with no collocation error): J(t) =
//! 1/E0 + Σ Jⱼ·(1 − e^(−t/λⱼ)) (+ t/η0 for E∞ = 0). It satisfies
//! ∫₀ᵗ E(t − s) dJ(s) = 1, J(0) = 1/E0, J(∞) = 1/E∞ and E(t)·J(t) ≤ 1
//! (tests/prony_frequency.rs).

use crate::material::viscoelastic::Prony;

/// Relaxation modulus E(t) (Pa) at each of `times` (s).
pub fn relaxation_modulus(prony: &Prony, times: &[f64]) -> Vec<f64> {
    times.iter().map(|&t| prony.relaxation_modulus(t)).collect()
}

/// Storage and loss moduli (E′, E″) (Pa) and tan δ = E″/E′ at each of `omega`
/// (rad/s).
pub fn complex_modulus(prony: &Prony, omega: &[f64]) -> Vec<(f64, f64, f64)> {
    omega
        .iter()
        .map(|&w| {
            let (s, l) = prony.storage_loss(w);
            (s, l, l / s)
        })
        .collect()
}

/// Creep compliance J(t) (1/Pa) at each of `times` (s), by the exact
/// interconversion (module docs).
pub fn creep_compliance(prony: &Prony, times: &[f64]) -> Vec<f64> {
    let creep = prony.creep();
    times.iter().map(|&t| creep.compliance(t)).collect()
}
