//! Shift laws fitted to the free shifts, and how well they fit them.
//!
//! - WLF (Williams, Landel & Ferry, J. Am. Chem. Soc. 77, 3701, 1955):
//!   log10 aT = −C1 (T − Tr)/(C2 + T − Tr);
//! - Arrhenius: log10 aT = Ea/(R ln 10) · (1/T − 1/Tr) (Ferry, Viscoelastic
//!   Properties of Polymers, 3rd ed., 1980, ch. 11).
//!
//! A law is fitted to the pair shifts dᵢ = log aT(Tᵢ) − log aT(Tᵢ₊₁) (weighted by
//! 1/σᵢ²), so the unknown offset of the free shifts never enters. Arrhenius is
//! linear in Ea; WLF is linear in C1 at fixed C2, so C2 is found by golden-section
//! search on the profile χ²(C2) (log-spaced in C2 + T_min − Tr, which must stay > 0
//! over the data). The constants' covariance is (JᵀWJ)⁻¹ scaled by max(1, χ²/dof),
//! J the pair shifts' derivatives by the constants ([`Law::gradient`]).
//!
//! That covariance takes the pairs as independent, and it is conservative: over 40
//! replicates C1 and C2 have rms z 0.62 and 0.71 (tests/dma.rs). Adjacent pairs share
//! an isotherm and their errors correlate (ρ ≈ −0.4 … −0.49,
//! [`super::shift::adjacent_correlations`]); the sandwich with that correlation,
//! (JᵀWJ)⁻¹JᵀWΣWJ(JᵀWJ)⁻¹, came out narrow instead (rms z 1.27 and 1.22, 37 of 40
//! intervals holding C1): each pair shift also carries a systematic error of its
//! interpolated overlap, the same in every replicate (up to 0.005 decades, 0.4 σ, on
//! 200 replicates of the synthetic sweep), which no noise model of the pairs holds
//! and a nearly singular Σ (ρ → −½) trusts least. The wider interval is kept: it
//! does not claim more than the shifts show. The law's shifts at the isotherms,
//! which the master curve is built with, take the sandwich
//! ([`LawFit::shift_covariance`]): along the data the pairs' systematic errors
//! largely cancel, and the Prony series' σ that carry it hold their truth.

use super::shift::PairShift;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// The molar gas constant R (J/(mol·K)), exact in the SI since 2019.
pub const GAS_CONSTANT: f64 = 8.314_462_618;

/// The largest C2 + T_min − Tr searched (K): beyond it WLF is a straight line in T
/// over any DMA range, and C2 is not determined.
pub const C2_SPAN_MAX: f64 = 1e4;

/// The rms misfit of a law to the free shifts (decades) above which it is a warning.
pub const RMS_WARNING_DECADES: f64 = 0.25;

/// A shift law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LawKind {
    /// Williams–Landel–Ferry.
    Wlf,
    /// Arrhenius.
    Arrhenius,
}

impl LawKind {
    /// The law's name for people.
    pub fn label(self) -> &'static str {
        match self {
            LawKind::Wlf => "WLF",
            LawKind::Arrhenius => "Arrhenius",
        }
    }
}

/// A shift law with its constants: the horizontal shift at any temperature.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Law {
    /// Which law.
    pub kind: LawKind,
    /// Reference temperature Tr (K).
    #[serde(rename = "reference_temperature_K")]
    pub reference_temperature_k: f64,
    /// WLF C1 (decades).
    #[serde(rename = "C1", default, skip_serializing_if = "Option::is_none")]
    pub c1: Option<f64>,
    /// WLF C2 (K).
    #[serde(rename = "C2", default, skip_serializing_if = "Option::is_none")]
    pub c2: Option<f64>,
    /// Arrhenius activation energy Ea (J/mol).
    #[serde(
        rename = "activation_energy_J_mol",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub activation_energy: Option<f64>,
}

impl Law {
    /// WLF with C1, C2 (K) at Tr (K).
    pub fn wlf(tr: f64, c1: f64, c2: f64) -> Law {
        Law {
            kind: LawKind::Wlf,
            reference_temperature_k: tr,
            c1: Some(c1),
            c2: Some(c2),
            activation_energy: None,
        }
    }

    /// Arrhenius with Ea (J/mol) at Tr (K).
    pub fn arrhenius(tr: f64, ea: f64) -> Law {
        Law {
            kind: LawKind::Arrhenius,
            reference_temperature_k: tr,
            c1: None,
            c2: None,
            activation_energy: Some(ea),
        }
    }

    /// log10 aT at `t` (K); NaN for WLF at or below its Vogel temperature Tr − C2.
    pub fn log_at(&self, t: f64) -> f64 {
        let tr = self.reference_temperature_k;
        match self.kind {
            LawKind::Wlf => {
                let (c1, c2) = (self.c1.unwrap_or(f64::NAN), self.c2.unwrap_or(f64::NAN));
                let u = t - tr;
                if c2 + u > 0.0 {
                    -c1 * u / (c2 + u)
                } else {
                    f64::NAN
                }
            }
            LawKind::Arrhenius => {
                self.activation_energy.unwrap_or(f64::NAN)
                    / (GAS_CONSTANT * std::f64::consts::LN_10)
                    * (1.0 / t - 1.0 / tr)
            }
        }
    }
}

impl Law {
    /// ∂ log10 aT/∂(constants) at `t` (K), one entry per constant: WLF
    /// (−u/(C2 + u), C1·u/(C2 + u)²) with u = T − Tr; Arrhenius
    /// (1/T − 1/Tr)/(R ln 10).
    pub fn gradient(&self, t: f64) -> Vec<f64> {
        let tr = self.reference_temperature_k;
        match self.kind {
            LawKind::Wlf => {
                let (c1, c2) = (self.c1.unwrap_or(f64::NAN), self.c2.unwrap_or(f64::NAN));
                let u = t - tr;
                vec![-u / (c2 + u), c1 * u / (c2 + u).powi(2)]
            }
            LawKind::Arrhenius => {
                vec![(1.0 / t - 1.0 / tr) / (GAS_CONSTANT * std::f64::consts::LN_10)]
            }
        }
    }
}

/// A law fitted to free shifts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LawFit {
    /// The law.
    #[serde(flatten)]
    pub law: Law,
    /// Standard error of C1.
    #[serde(
        rename = "C1_std_error",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub c1_std_error: Option<f64>,
    /// Standard error of C2 (K).
    #[serde(
        rename = "C2_std_error",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub c2_std_error: Option<f64>,
    /// The correlation of C1 and C2 (WLF): close to ±1 where the shifts span a
    /// narrow range of T − Tr.
    #[serde(
        rename = "C1_C2_correlation",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub c1_c2_correlation: Option<f64>,
    /// Standard error of Ea (J/mol).
    #[serde(
        rename = "activation_energy_std_error",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub activation_energy_std_error: Option<f64>,
    /// χ² of the pair shifts against the law.
    pub chi2: f64,
    /// Its degrees of freedom (pairs − constants).
    pub dof: usize,
    /// The 99 % point of χ² with `dof` degrees of freedom: above it the law misses
    /// by more than the shifts' own uncertainty.
    pub chi2_99: f64,
    /// RMS of the law's misfit to the free shifts (decades), per temperature below.
    pub rms_decades: f64,
    /// Largest misfit (decades).
    pub max_decades: f64,
    /// Misfit at each isotherm (decades): free log aT − law, offset by their mean.
    pub residual_decades: Vec<f64>,
    /// C2 ran to the end of its range: the shifts are straight in T and do not
    /// determine it.
    #[serde(default)]
    pub c2_at_bound: bool,
}

impl LawFit {
    /// The covariance of the law's log10 aT at `temps` (K; decades²), the law
    /// fitted to `pairs` whose adjacent errors correlate by `rho`
    /// ([`super::shift::adjacent_correlations`]): G C Gᵀ, G the law's
    /// [`Law::gradient`] at each temperature and C the sandwich covariance of the
    /// constants ([`constants_covariance`]). The constants' reported σ take the
    /// pairs as independent, which is conservative for them (module docs); the
    /// sandwich, narrow for C1 and C2 singly, holds the law's shifts within the data
    /// (they are what the constants' errors do along the data, where the pairs'
    /// systematic errors largely cancel): with it the master curve's Prony τ have
    /// rms z 0.96 over 40 replicates, with the conservative one 0.77 (tests/dma.rs).
    /// None where the constants are not determined.
    pub fn shift_covariance(
        &self,
        temps: &[f64],
        pairs: &[PairShift],
        rho: &[f64],
    ) -> Option<DMatrix<f64>> {
        let c = constants_covariance(&self.law, pairs, self.chi2, Some(rho))?;
        let g = DMatrix::from_fn(temps.len(), c.nrows(), |i, k| {
            self.law.gradient(temps[i])[k]
        });
        Some(&g * c * g.transpose())
    }
}

/// The covariance of a law's constants fitted to `pairs` by weights 1/σᵢ² with
/// misfit `chi2`: (JᵀWJ)⁻¹, J the pair shifts' derivatives by the constants, or with
/// the adjacent pairs' correlations `rho` the sandwich
/// (JᵀWJ)⁻¹JᵀWΣWJ(JᵀWJ)⁻¹, Σ the pairs' covariance (σᵢ², ρᵢσᵢσᵢ₊₁ next to the
/// diagonal); either scaled by max(1, χ²/dof). None where JᵀWJ is singular.
fn constants_covariance(
    law: &Law,
    pairs: &[PairShift],
    chi2: f64,
    rho: Option<&[f64]>,
) -> Option<DMatrix<f64>> {
    let n = pairs.len();
    let k = law.gradient(law.reference_temperature_k).len();
    let jac = DMatrix::from_fn(n, k, |i, c| {
        law.gradient(pairs[i].cold_k)[c] - law.gradient(pairs[i].warm_k)[c]
    });
    let sd: Vec<f64> = pairs.iter().map(|p| p.std_error.max(1e-6)).collect();
    let wj = DMatrix::from_fn(n, k, |i, c| jac[(i, c)] / sd[i].powi(2));
    let dof = n.saturating_sub(k);
    let scale = if dof > 0 {
        (chi2 / dof as f64).max(1.0)
    } else {
        1.0
    };
    let bread = (jac.transpose() * &wj).try_inverse()?;
    let cov = match rho {
        None => bread,
        Some(rho) => {
            let sigma = DMatrix::from_fn(n, n, |a, b| match a.abs_diff(b) {
                0 => sd[a].powi(2),
                1 => rho.get(a.min(b)).copied().unwrap_or(0.0) * sd[a] * sd[b],
                _ => 0.0,
            });
            &bread * (wj.transpose() * sigma * &wj) * &bread
        }
    };
    Some(cov * scale)
}

/// Weighted linear least squares through the origin: b for Δ ≈ b·h.
fn through_origin(delta: &[f64], h: &[f64], w: &[f64]) -> f64 {
    let shh: f64 = h.iter().zip(w).map(|(h, w)| w * h * h).sum();
    let sdh: f64 = delta
        .iter()
        .zip(h)
        .zip(w)
        .map(|((d, h), w)| w * d * h)
        .sum();
    sdh / shh
}

/// Fit `kind` to the pair shifts (temperatures `temps`, coldest first) at
/// reference `tr` (K), and compare it with the accumulated free shifts `free`.
pub fn fit(
    kind: LawKind,
    temps: &[f64],
    pairs: &[PairShift],
    free: &[f64],
    tr: f64,
) -> Option<LawFit> {
    let delta: Vec<f64> = pairs.iter().map(|p| p.log_shift).collect();
    let w: Vec<f64> = pairs
        .iter()
        .map(|p| 1.0 / p.std_error.max(1e-6).powi(2))
        .collect();
    let n = pairs.len();
    let chi2_of = |pred: &[f64]| {
        delta
            .iter()
            .zip(pred)
            .zip(&w)
            .map(|((d, p), w)| w * (d - p).powi(2))
            .sum::<f64>()
    };
    let (law, c2_at_bound) = match kind {
        LawKind::Arrhenius => {
            let k = 1.0 / (GAS_CONSTANT * std::f64::consts::LN_10);
            let h: Vec<f64> = (0..n)
                .map(|i| k * (1.0 / temps[i] - 1.0 / temps[i + 1]))
                .collect();
            let ea = through_origin(&delta, &h, &w);
            (Law::arrhenius(tr, ea), false)
        }
        LawKind::Wlf => {
            if n < 2 {
                return None;
            }
            let u: Vec<f64> = temps.iter().map(|t| t - tr).collect();
            let umin = u[0];
            // g_i(C2): Δ = C1·g_i, g_i = C2/(C2+u_{i+1})·… from −u/(C2+u)
            let g = |c2: f64| -> Vec<f64> {
                (0..n)
                    .map(|i| -u[i] / (c2 + u[i]) + u[i + 1] / (c2 + u[i + 1]))
                    .collect()
            };
            let profile = |s: f64| {
                let c2 = s.exp() - umin;
                let gi = g(c2);
                let c1 = through_origin(&delta, &gi, &w);
                let pred: Vec<f64> = gi.iter().map(|x| c1 * x).collect();
                chi2_of(&pred)
            };
            let (s0, s1) = (1f64.ln(), C2_SPAN_MAX.ln());
            let steps = 200;
            let best = (0..=steps)
                .map(|k| s0 + (s1 - s0) * k as f64 / steps as f64)
                .min_by(|a, b| profile(*a).total_cmp(&profile(*b)))
                .expect("a grid");
            let h = (s1 - s0) / steps as f64;
            let s = crate::sim::static_curve::golden_max(
                &|s| -profile(s),
                (best - h).max(s0),
                (best + h).min(s1),
                1e-9,
            );
            let c2 = s.exp() - umin;
            let c1 = through_origin(&delta, &g(c2), &w);
            (Law::wlf(tr, c1, c2), s > s1 - 2.0 * h)
        }
    };
    let pred: Vec<f64> = (0..n)
        .map(|i| law.log_at(temps[i]) - law.log_at(temps[i + 1]))
        .collect();
    let chi2 = chi2_of(&pred);
    let dof = n.saturating_sub(law.gradient(tr).len());
    let cov = constants_covariance(&law, pairs, chi2, None);
    let se = |c: usize| {
        cov.as_ref()
            .map(|v| v[(c, c)].sqrt())
            .filter(|v| v.is_finite())
    };
    let (mut c1_se, mut c2_se, mut ea_se, mut rho12) = (None, None, None, None);
    match law.kind {
        LawKind::Arrhenius => ea_se = se(0),
        LawKind::Wlf => {
            (c1_se, c2_se) = (se(0), se(1));
            rho12 = c1_se
                .zip(c2_se)
                .zip(cov.as_ref())
                .map(|((a, b), v)| v[(0, 1)] / (a * b))
                .filter(|r| r.is_finite());
        }
    }
    let chi2_99 = {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        ChiSquared::new(dof.max(1) as f64).map_or(f64::INFINITY, |c| c.inverse_cdf(0.99))
    };
    let diff: Vec<f64> = temps
        .iter()
        .zip(free)
        .map(|(t, f)| f - law.log_at(*t))
        .collect();
    let mean = diff.iter().sum::<f64>() / diff.len() as f64;
    let residual_decades: Vec<f64> = diff.iter().map(|d| d - mean).collect();
    let rms = (residual_decades.iter().map(|r| r * r).sum::<f64>() / residual_decades.len() as f64)
        .sqrt();
    let max = residual_decades.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    Some(LawFit {
        law,
        c1_std_error: c1_se,
        c2_std_error: c2_se,
        c1_c2_correlation: rho12,
        activation_energy_std_error: ea_se,
        chi2,
        dof,
        chi2_99,
        rms_decades: rms,
        max_decades: max,
        residual_decades,
        c2_at_bound,
    })
}
