//! `synth dma`: isotherms made from stated constants. The material at the reference
//! temperature Tr is a Prony series, E*(ω) = E∞ + Σ Eᵢ iωτᵢ/(1 + iωτᵢ); at T it is
//! E*_T(ω) = bT · E*(aT·ω) (time–temperature superposition, Ferry 1980 ch. 11), aT
//! from a WLF or Arrhenius [`Law`], bT = ρ(T)·T/(ρ₀·Tr) with ρ(T)/ρ₀ = 1 − α_V (T − Tr)
//! when a vertical shift is asked for (else 1). Relative Gaussian noise on E′ and E″,
//! independent, from a seeded ChaCha8 generator.

use super::law::Law;
use super::temperature::CELSIUS_ZERO_K;
use crate::error::Result;
use crate::material::viscoelastic::Prony;
use std::fmt::Write as _;

/// A synthetic DMA sweep.
#[derive(Debug, Clone)]
pub struct Synthetic {
    /// The series at the reference temperature (Pa, s).
    pub prony: Prony,
    /// The shift law (its reference temperature is Tr).
    pub law: Law,
    /// Volumetric expansion α_V (1/K) of the vertical shift; None: no vertical shift.
    pub vertical: Option<f64>,
    /// Isotherm temperatures (K).
    pub temperatures_k: Vec<f64>,
    /// Frequencies of each sweep (Hz), increasing.
    pub frequencies_hz: Vec<f64>,
    /// Relative noise (standard deviation as a fraction of the modulus).
    pub noise: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl Synthetic {
    /// bT at `t` (K).
    pub fn vertical_factor(&self, t: f64) -> f64 {
        let tr = self.law.reference_temperature_k;
        self.vertical.map_or(1.0, |a| (1.0 - a * (t - tr)) * t / tr)
    }

    /// The CSV text (`temperature_C,frequency_Hz,storage_modulus_MPa,loss_modulus_MPa`),
    /// the generating parameters as `#` lines after `preamble` lines.
    pub fn csv(&self, preamble: &[&str]) -> Result<String> {
        let (mut s, mut normal) = crate::io::synthetic_start(
            self.seed,
            preamble,
            "at the reference temperature",
            &self.prony,
        );
        let l = &self.law;
        let _ = writeln!(
            s,
            "# shift law: {} at Tr = {} K ({} °C){}",
            l.kind.label(),
            l.reference_temperature_k,
            l.reference_temperature_k - CELSIUS_ZERO_K,
            match (l.c1, l.c2, l.activation_energy) {
                (Some(c1), Some(c2), _) => format!(", C1 = {c1}, C2 = {c2} K"),
                (_, _, Some(ea)) => format!(", Ea = {ea} J/mol"),
                _ => String::new(),
            }
        );
        let _ = writeln!(
            s,
            "# vertical shift: {}",
            match self.vertical {
                Some(a) => format!("bT = rho(T) T / (rho0 Tr), rho(T)/rho0 = 1 - {a} /K (T - Tr)"),
                None => "none (bT = 1)".into(),
            }
        );
        let _ = writeln!(
            s,
            "# noise: relative {} on E' and E'' (Gaussian standard deviation), seed {} (ChaCha8)",
            self.noise, self.seed
        );
        let _ = writeln!(
            s,
            "temperature_C,frequency_Hz,storage_modulus_MPa,loss_modulus_MPa"
        );
        let mut rows = Vec::new();
        for &t in &self.temperatures_k {
            let (a, b) = (10f64.powf(l.log_at(t)), self.vertical_factor(t));
            for &f in &self.frequencies_hz {
                let (e1, e2) = self.prony.storage_loss(a * 2.0 * std::f64::consts::PI * f);
                let n1 = 1.0 + self.noise * normal();
                let n2 = 1.0 + self.noise * normal();
                rows.push((t - CELSIUS_ZERO_K, f, b * e1 * n1 / 1e6, b * e2 * n2 / 1e6));
            }
        }
        crate::io::finite_output(
            "the synthetic DMA sweep",
            rows.iter().flat_map(|r| {
                [
                    ("temperature_C", r.0),
                    ("frequency_Hz", r.1),
                    ("storage_modulus_MPa", r.2),
                    ("loss_modulus_MPa", r.3),
                ]
            }),
        )?;
        if let Some(r) = rows.iter().find(|r| r.2 <= 0.0 || r.3 <= 0.0) {
            return Err(crate::Error::settings(format!(
                "the noise makes a modulus ≤ 0 at {} °C, {} Hz: nothing was written",
                r.0, r.1
            ))
            .with_hint("use a smaller --noise (a relative noise of 0.3 leaves a modulus ≤ 0 once in 3·10⁴ draws)"));
        }
        for r in rows {
            let _ = writeln!(s, "{},{:.6e},{:.6e},{:.6e}", round(r.0), r.1, r.2, r.3);
        }
        Ok(s)
    }
}

/// A temperature in °C to 1e-6 (so that 25 reads 25, not 25.000000000000057).
fn round(c: f64) -> f64 {
    (c * 1e6).round() / 1e6
}
