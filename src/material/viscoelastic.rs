//! Linear viscoelasticity: Prony series, Kelvin-Maxwell arms, their conversions,
//! El Atrache Ceballos (2021)'s presets, and the predictions a fit or a simulator needs (relaxation
//! modulus, response to a strain history, creep compliance, storage/loss moduli).
//!
//! # Equations
//! * Prony series (relaxation modulus): E(t) = E∞ + Σ Eᵢ·exp(−t/τᵢ); instantaneous
//!   modulus E0 = E∞ + Σ Eᵢ; normalised fractions gᵢ = Eᵢ/E0, g∞ = E∞/E0.
//! * El Atrache Ceballos (2021)'s generalized Kelvin-Maxwell rheology (Eq. 3.14–3.16): an equilibrium spring
//!   in parallel with a Kelvin-Voigt dashpot Nv and N Maxwell arms (spring kⱼ in series
//!   with dashpot nⱼ), dσⱼ/dt = kⱼ·dε/dt − σⱼ/τⱼ with τⱼ = nⱼ/kⱼ. Its relaxation
//!   modulus is the Prony series with Eⱼ = kⱼ, τⱼ = nⱼ/kⱼ, E∞ = the equilibrium spring,
//!   plus Nv·δ(t) (which no Prony term represents).
//! * Hereditary integral (Boltzmann superposition): σ(t) = ∫ E(t − s) dx(s), with x the
//!   strain (linear, [`Formulation::Parallel`]) or the instantaneous hyperelastic stress
//!   (QLV, [`Formulation::Qlv`], Fung 1981). For a piecewise-linear x it is exact for
//!   exponentials: over an interval Δ with constant rate r, each term's state hᵢ obeys
//!   hᵢ ← hᵢ·e^(−Δ/τᵢ) + r·τᵢ·(1 − e^(−Δ/τᵢ)); after a linear ramp of duration t_r to x0
//!   a term holds x0·(τᵢ/t_r)(1 − e^(−t_r/τᵢ)), i.e. the step response scaled by
//!   (τᵢ/t_r)(e^(t_r/τᵢ) − 1) at t = t_r onwards.
//! * Storage and loss moduli: E'(ω) = E∞ + Σ Eᵢ ω²τᵢ²/(1 + ω²τᵢ²),
//!   E''(ω) = Σ Eᵢ ωτᵢ/(1 + ω²τᵢ²) + ω·Nv.
//! * Creep compliance by exact interconversion (Laplace: s²Ē(s)·J̄(s) = 1): with
//!   F(s) = sĒ(s) = E∞ + Nv·s + Σ Eᵢ sτᵢ/(1 + sτᵢ), the retardation rates are the real
//!   negative zeros pⱼ of F (one between consecutive poles −1/τᵢ, one in (−1/τ_max, 0)
//!   when E∞ > 0, one below −1/τ_min when Nv > 0), and
//!   J(t) = 1/E0 + Σ Rⱼ·λⱼ·(1 − e^(−t/λⱼ)) (+ t/η0 when E∞ = 0), λⱼ = −1/pⱼ,
//!   Rⱼ = 1/F'(pⱼ); 1/E0 is 0 when Nv > 0 (Park & Schapery 1999 give the same
//!   interconversion by collocation; this is its exact form for a Prony series).

use crate::error::{Error, Result};
use crate::numerics;
use serde::{Deserialize, Serialize};

/// Which constitutive reading the constants belong to (`docs/model.md`): conversion
/// between Prony and Kelvin-Maxwell constants is exact only within one formulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Formulation {
    /// El Atrache Ceballos (2021)'s parallel lumped model (Eq. 3.14–3.16): Maxwell arms driven by the
    /// strain, in parallel with the equilibrium spring. In the small-strain reading
    /// σ(t) = ∫E(t − s)dε(s) and E∞ is the equilibrium (secant) modulus at the tested
    /// strain; at large strain the simulator puts the hyperelastic spring in its place.
    Parallel,
    /// Quasi-linear viscoelasticity (Fung; Abaqus-style normalised Prony series): the
    /// normalised relaxation function g(t) relaxes the instantaneous hyperelastic
    /// stress, σ(t) = ∫ g(t − s) dσₑ(λ(s)). Moduli are g·E0 with E0 the instantaneous
    /// small-strain Young's modulus.
    Qlv,
}

impl std::fmt::Display for Formulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Formulation::Parallel => "parallel",
            Formulation::Qlv => "qlv",
        })
    }
}

/// One Prony term: relaxation time τ (s) and modulus E (Pa).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PronyTerm {
    /// Relaxation time τ (s).
    pub tau: f64,
    /// Modulus E (Pa).
    pub modulus: f64,
}

/// A Prony series E(t) = E∞ + Σ Eᵢ·exp(−t/τᵢ) (Pa), terms sorted by τ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Prony {
    /// Long-term (equilibrium) modulus E∞ (Pa).
    pub e_inf: f64,
    /// Terms, sorted by increasing τ.
    pub terms: Vec<PronyTerm>,
}

fn check_finite_nonneg(v: f64, what: &str) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::settings(format!(
            "{what} must be a finite number ≥ 0, found {v}"
        )))
    }
}

impl Prony {
    /// The terms as written into generated files' `#` lines: `(τ s, E Pa), …` in
    /// full precision (`{:e}`).
    pub fn terms_text(&self) -> String {
        let terms: Vec<String> = self
            .terms
            .iter()
            .map(|t| format!("({:e} s, {:e} Pa)", t.tau, t.modulus))
            .collect();
        terms.join(", ")
    }

    /// A checked series from E∞ and (τ, E) pairs (τ > 0, E ≥ 0, E∞ ≥ 0); terms are
    /// sorted by τ.
    pub fn new(e_inf: f64, terms: &[(f64, f64)]) -> Result<Prony> {
        check_finite_nonneg(e_inf, "the long-term modulus")?;
        let mut t = Vec::with_capacity(terms.len());
        for (i, &(tau, e)) in terms.iter().enumerate() {
            if !(tau.is_finite() && tau > 0.0) {
                return Err(Error::settings(format!(
                    "relaxation time {} must be > 0, found {tau}",
                    i + 1
                )));
            }
            check_finite_nonneg(e, &format!("modulus {}", i + 1))?;
            t.push(PronyTerm { tau, modulus: e });
        }
        t.sort_by(|a, b| a.tau.total_cmp(&b.tau));
        Ok(Prony { e_inf, terms: t })
    }

    /// From normalised fractions: Eᵢ = gᵢ·E0 and E∞ = (1 − Σgᵢ)·E0 (requires Σgᵢ ≤ 1).
    pub fn from_normalized(e0: f64, g: &[(f64, f64)]) -> Result<Prony> {
        let sum: f64 = g.iter().map(|p| p.1).sum();
        if sum > 1.0 + 1e-12 {
            return Err(Error::settings(format!(
                "normalised Prony fractions sum to {sum} > 1: no non-negative long-term modulus"
            )));
        }
        let terms: Vec<(f64, f64)> = g.iter().map(|&(tau, gi)| (tau, gi * e0)).collect();
        Prony::new((1.0 - sum).max(0.0) * e0, &terms)
    }

    /// Instantaneous modulus E0 = E∞ + Σ Eᵢ (Pa).
    pub fn instantaneous(&self) -> f64 {
        self.e_inf + self.terms.iter().map(|t| t.modulus).sum::<f64>()
    }

    /// Normalised fractions (g∞, gᵢ for each term) with gᵢ = Eᵢ/E0 (all 0 if E0 = 0).
    pub fn normalized(&self) -> (f64, Vec<f64>) {
        let e0 = self.instantaneous();
        let f = |v: f64| if e0 > 0.0 { v / e0 } else { 0.0 };
        (
            f(self.e_inf),
            self.terms.iter().map(|t| f(t.modulus)).collect(),
        )
    }

    /// Relaxation modulus E(t) (Pa), t ≥ 0 (s).
    pub fn relaxation_modulus(&self, t: f64) -> f64 {
        self.e_inf
            + self
                .terms
                .iter()
                .map(|p| p.modulus * (-t / p.tau).exp())
                .sum::<f64>()
    }

    /// Storage and loss moduli (E', E'') in Pa at angular frequency ω (rad/s).
    pub fn storage_loss(&self, omega: f64) -> (f64, f64) {
        storage_loss(self.e_inf, &self.terms, 0.0, omega)
    }

    /// Creep compliance by exact interconversion (see the module docs).
    pub fn creep(&self) -> Creep {
        creep(self.e_inf, &self.terms, 0.0)
    }

    /// El Atrache Ceballos (2021)'s Kelvin-Maxwell arms of this series (kⱼ = Eⱼ, nⱼ = Eⱼ·τⱼ, equilibrium
    /// spring E∞, Nv = 0: a relaxation curve cannot see a Kelvin-Voigt dashpot).
    pub fn to_kelvin_maxwell(&self) -> KelvinMaxwell {
        KelvinMaxwell {
            k_inf: self.e_inf,
            arms: self
                .terms
                .iter()
                .map(|t| MaxwellArm {
                    k: t.modulus,
                    n: t.modulus * t.tau,
                })
                .collect(),
            n_v: 0.0,
        }
    }

    /// Stress response σ(tₖ) = E∞·x(tₖ) + Σ Eᵢ·hᵢ(tₖ) to a history at the schedule's
    /// times (exact hereditary integral for piecewise-linear x).
    pub fn response(&self, schedule: &Schedule) -> Vec<f64> {
        let mut out: Vec<f64> = schedule.input().iter().map(|x| self.e_inf * x).collect();
        let mut h = vec![0.0; out.len()];
        for t in &self.terms {
            schedule.kernel(t.tau, &mut h, None);
            for (o, hv) in out.iter_mut().zip(&h) {
                *o += t.modulus * hv;
            }
        }
        out
    }
}

/// One Maxwell arm of El Atrache Ceballos (2021)'s rheology: spring k (Pa) in series with dashpot n (Pa·s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MaxwellArm {
    /// Spring constant kⱼ (Pa).
    pub k: f64,
    /// Dashpot viscosity nⱼ (Pa·s); τⱼ = nⱼ/kⱼ.
    pub n: f64,
}

/// El Atrache Ceballos (2021)'s generalized Kelvin-Maxwell model (Eq. 3.14–3.16, Table 4.2), linear part:
/// equilibrium spring, Kelvin-Voigt dashpot Nv and Maxwell arms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KelvinMaxwell {
    /// Equilibrium spring (Pa): the small-strain modulus of the hyperelastic spring in
    /// El Atrache Ceballos (2021)'s model, E∞ of the Prony series.
    pub k_inf: f64,
    /// Maxwell arms.
    pub arms: Vec<MaxwellArm>,
    /// Kelvin-Voigt dashpot Nv (Pa·s) in parallel with the spring (El Atrache Ceballos (2021) Eq. 3.14).
    pub n_v: f64,
}

impl KelvinMaxwell {
    /// The Prony series of the spring and arms (Eⱼ = kⱼ, τⱼ = nⱼ/kⱼ). Nv is not part of
    /// it (it is an impulse Nv·δ(t) in the relaxation modulus): see [`Self::n_v`].
    pub fn to_prony(&self) -> Result<Prony> {
        let terms: Vec<(f64, f64)> = self.arms.iter().map(|a| (a.n / a.k, a.k)).collect();
        Prony::new(self.k_inf, &terms)
    }

    /// Storage and loss moduli (Pa) at ω (rad/s), including ω·Nv in the loss.
    pub fn storage_loss(&self, omega: f64) -> Result<(f64, f64)> {
        let p = self.to_prony()?;
        Ok(storage_loss(p.e_inf, &p.terms, self.n_v, omega))
    }

    /// Creep compliance including the Kelvin-Voigt dashpot (no instantaneous
    /// compliance when Nv > 0).
    pub fn creep(&self) -> Result<Creep> {
        let p = self.to_prony()?;
        Ok(creep(p.e_inf, &p.terms, self.n_v))
    }
}

fn storage_loss(e_inf: f64, terms: &[PronyTerm], n_v: f64, omega: f64) -> (f64, f64) {
    let mut s = e_inf;
    let mut l = omega * n_v;
    for t in terms {
        let wt = omega * t.tau;
        let d = 1.0 + wt * wt;
        s += t.modulus * wt * wt / d;
        l += t.modulus * wt / d;
    }
    (s, l)
}

/// One retardation term of a creep compliance: J·(1 − e^(−t/λ)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RetardationTerm {
    /// Retardation time λ (s).
    pub lambda: f64,
    /// Compliance J (1/Pa).
    pub compliance: f64,
}

/// Creep compliance J(t) = J_g + Σ Jⱼ(1 − e^(−t/λⱼ)) + φ·t (1/Pa).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Creep {
    /// Instantaneous (glassy) compliance J_g = 1/E0 (0 with a Kelvin-Voigt dashpot).
    pub j_g: f64,
    /// Retardation terms, sorted by λ.
    pub terms: Vec<RetardationTerm>,
    /// Steady flow term φ = 1/η0 (1/(Pa·s)); 0 unless E∞ = 0.
    pub fluidity: f64,
}

impl Creep {
    /// J(t) (1/Pa), t ≥ 0 (s).
    pub fn compliance(&self, t: f64) -> f64 {
        self.j_g
            + self.fluidity * t
            + self
                .terms
                .iter()
                .map(|r| r.compliance * -(-t / r.lambda).exp_m1())
                .sum::<f64>()
    }

    /// Long-term compliance (1/E∞), ∞ for a fluid.
    pub fn long_term(&self) -> f64 {
        if self.fluidity > 0.0 {
            f64::INFINITY
        } else {
            self.j_g + self.terms.iter().map(|r| r.compliance).sum::<f64>()
        }
    }
}

fn creep(e_inf: f64, terms: &[PronyTerm], n_v: f64) -> Creep {
    let act: Vec<PronyTerm> = terms.iter().copied().filter(|t| t.modulus > 0.0).collect();
    let f = |s: f64| {
        e_inf
            + n_v * s
            + act
                .iter()
                .map(|t| t.modulus * s * t.tau / (1.0 + s * t.tau))
                .sum::<f64>()
    };
    let fp = |s: f64| {
        n_v + act
            .iter()
            .map(|t| t.modulus * t.tau / (1.0 + s * t.tau).powi(2))
            .sum::<f64>()
    };
    // Poles of F at −1/τ, sorted increasingly (most negative first).
    let mut poles: Vec<f64> = act.iter().map(|t| -1.0 / t.tau).collect();
    poles.sort_by(f64::total_cmp);
    poles.dedup();
    // F increases between poles (F' > 0): one zero in each bracket where it changes
    // sign. Brackets: (pᵢ, pᵢ₊₁); (p_last, 0] when E∞ > 0; (−∞, p_first) when Nv > 0.
    let mut brackets: Vec<(f64, f64)> = poles.windows(2).map(|w| (w[0], w[1])).collect();
    let mut fluidity = 0.0;
    if let Some(&last) = poles.last() {
        if e_inf > 0.0 {
            brackets.push((last, 0.0));
        } else if fp(0.0) > 0.0 {
            fluidity = 1.0 / fp(0.0);
        }
    } else if e_inf <= 0.0 && n_v > 0.0 {
        fluidity = 1.0 / n_v;
    }
    if n_v > 0.0 {
        let first = poles.first().copied().unwrap_or(0.0);
        // F(s) → −∞ as s → −∞: walk left until F < 0.
        let mut lo = first - 1.0 / act.iter().map(|t| t.tau).fold(1.0, f64::min).max(1e-300);
        while f(lo) > 0.0 && lo.is_finite() {
            lo = first + 2.0 * (lo - first);
        }
        if !(poles.is_empty() && e_inf <= 0.0) {
            brackets.insert(0, (lo, first));
        }
    }
    let mut out = Vec::new();
    for (a, b) in brackets {
        // Bisection in the open bracket (F → −∞ just right of a pole, → +∞ just left).
        let (mut lo, mut hi) = (a, b);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if f(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let p = 0.5 * (lo + hi);
        if p < 0.0 {
            let lambda = -1.0 / p;
            out.push(RetardationTerm {
                lambda,
                compliance: lambda / fp(p),
            });
        }
    }
    out.sort_by(|a, b| a.lambda.total_cmp(&b.lambda));
    let e0 = e_inf + act.iter().map(|t| t.modulus).sum::<f64>();
    Creep {
        j_g: if n_v > 0.0 || e0 <= 0.0 {
            0.0
        } else {
            1.0 / e0
        },
        terms: out,
        fluidity,
    }
}

/// A piecewise-linear input history x(s): zero before the first knot, linear between
/// knots, constant after the last; two knots at the same time make a jump.
#[derive(Debug, Clone, PartialEq)]
pub struct History {
    knots: Vec<(f64, f64)>,
}

impl History {
    /// An ideal step to `x0` at t = 0.
    pub fn step(x0: f64) -> History {
        History {
            knots: vec![(0.0, x0)],
        }
    }

    /// A linear ramp from 0 at t = 0 to `x0` at t = `t_ramp` (> 0), then held.
    pub fn ramp(x0: f64, t_ramp: f64) -> History {
        History {
            knots: vec![(0.0, 0.0), (t_ramp, x0)],
        }
    }

    /// Knots (time s, value), times non-decreasing and finite.
    pub fn from_knots(knots: Vec<(f64, f64)>) -> Result<History> {
        if knots.is_empty() {
            return Err(Error::settings("a history needs at least one point"));
        }
        for w in knots.windows(2) {
            if w[1].0.is_nan() || w[1].0 < w[0].0 {
                return Err(Error::settings(format!(
                    "history times must not decrease: {} after {}",
                    w[1].0, w[0].0
                )));
            }
        }
        if knots.iter().any(|k| !(k.0.is_finite() && k.1.is_finite())) {
            return Err(Error::settings("history values must be finite"));
        }
        Ok(History { knots })
    }

    /// The knots.
    pub fn knots(&self) -> &[(f64, f64)] {
        &self.knots
    }

    /// Map the values through `f` (e.g. strain → hyperelastic stress), keeping times.
    pub fn map(&self, f: impl Fn(f64) -> f64) -> History {
        History {
            knots: self.knots.iter().map(|&(t, x)| (t, f(x))).collect(),
        }
    }

    /// Time at which the history reaches its final value (end of loading).
    pub fn loading_end(&self) -> f64 {
        let last = self.knots.last().expect("non-empty").1;
        self.knots
            .iter()
            .find(|k| k.1 == last)
            .map(|k| k.0)
            .unwrap_or(0.0)
    }
}

/// One interval of a [`Schedule`]: duration, input rate over it, jump at its end, and
/// the output index recorded after the jump.
#[derive(Debug, Clone, Copy)]
struct Interval {
    dt: f64,
    rate: f64,
    jump: f64,
    out: Option<usize>,
}

/// A history merged with sorted evaluation times: evaluates the hereditary state of an
/// exponential kernel exactly, in one pass (O(knots + times) per τ).
///
/// The intervals up to the final hold are held as [`Interval`]s (40 B each). Those of
/// the final hold (input rate and jump +0, each ending at an evaluation time: all
/// of a relaxation curve after its step) are not stored: interval k of the hold runs
/// from the time before it to `times[hold_first + k]`, the same subtraction that
/// made the stored ones, so the same bits. A schedule then holds 16 B an evaluation
/// time (its time and input) instead of 56 (10⁶ points: 16 MB, not 56).
#[derive(Debug, Clone)]
pub struct Schedule {
    /// The intervals before the final hold.
    intervals: Vec<Interval>,
    /// The first evaluation time of the final hold (the number of times when there
    /// is none): the hold's interval k ends at `times[hold_first + k]`.
    hold_first: usize,
    /// The time at which the final hold's first interval starts.
    hold_start: f64,
    times: Vec<f64>,
    input: Vec<f64>,
}

impl Schedule {
    /// Merge `history` with evaluation `times` (non-decreasing, s). The value at a jump
    /// time is taken after the jump.
    pub fn new(history: &History, times: &[f64]) -> Result<Schedule> {
        if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
            return Err(Error::settings(
                "evaluation times must be finite and non-decreasing",
            ));
        }
        let k = &history.knots;
        let mut intervals = Vec::new();
        let (mut i, mut j) = (0, 0);
        let mut now = k[0].0.min(times.first().copied().unwrap_or(k[0].0));
        let mut rate = 0.0;
        let mut x = 0.0;
        let mut input = vec![0.0; times.len()];
        // After the last knot the input holds (rate +0, no jump): the final hold,
        // whose intervals are not stored.
        while i < k.len() {
            // Knots come first at equal times, so outputs see the value after a jump.
            let knot_next = j >= times.len() || k[i].0 <= times[j];
            let at = if knot_next { k[i].0 } else { times[j] };
            let dt = at - now;
            x += rate * dt;
            if knot_next {
                let jump = k[i].1 - x;
                intervals.push(Interval {
                    dt,
                    rate,
                    jump,
                    out: None,
                });
                x = k[i].1;
                rate = match k.get(i + 1) {
                    Some(n) if n.0 > k[i].0 => (n.1 - k[i].1) / (n.0 - k[i].0),
                    _ => 0.0,
                };
                i += 1;
            } else {
                intervals.push(Interval {
                    dt,
                    rate,
                    jump: 0.0,
                    out: Some(j),
                });
                input[j] = x;
                j += 1;
            }
            now = at;
        }
        // the final hold: x += 0·dt, as for an interval before it (x + 0 is x but at
        // x = −0)
        if j < times.len() {
            input[j..].fill(x + 0.0);
        }
        Ok(Schedule {
            intervals,
            hold_first: j,
            hold_start: now,
            times: times.to_vec(),
            input,
        })
    }

    /// The evaluation times.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The input x at each evaluation time.
    pub fn input(&self) -> &[f64] {
        &self.input
    }

    /// Number of evaluation times.
    pub fn len(&self) -> usize {
        self.input.len()
    }

    /// True if there are no evaluation times.
    pub fn is_empty(&self) -> bool {
        self.input.is_empty()
    }

    /// State h(tₖ; τ) = ∫ e^(−(tₖ−s)/τ) dx(s) at every evaluation time into `h`, and
    /// ∂h/∂τ into `dh` if given (exact recursion, see the module docs): [`Schedule::kernels`]
    /// of one τ.
    pub fn kernel(&self, tau: f64, h: &mut [f64], dh: Option<&mut [f64]>) {
        self.kernels(&[tau], h, dh);
    }

    /// [`Schedule::kernel`] for several τ in one pass over the intervals: `h` (and
    /// `dh`) hold one block of [`Schedule::len`] values per τ, end to end (the columns
    /// of a column-major matrix). The τ's recursions are independent chains of
    /// dependent operations that the processor overlaps, where one τ at a time waits
    /// on each; every value is the same arithmetic for any number of τ, bit for bit.
    /// Up to [`KERNEL_CHUNK`] τ share a pass, their states on the stack (no
    /// allocation); more take one pass a chunk.
    pub fn kernels(&self, taus: &[f64], h: &mut [f64], dh: Option<&mut [f64]>) {
        let rows = 0..self.len();
        self.kernel_rows(taus, rows, &mut KernelCarry::default(), h, dh);
    }

    /// [`Schedule::kernels`] of the evaluation times `rows` alone: `h` (and `dh`)
    /// hold one block of `rows.len()` values per τ, end to end. `carry` is where the
    /// pass stands: a fresh one ([`KernelCarry::default`]) starts at the first time,
    /// and each call leaves it at the end of its rows, where the next call (the same
    /// τ, with derivatives or not alike) must start. The pass over the rows a block
    /// at a time is the pass over all of them, the same arithmetic in the same
    /// order, so the same bits, with nothing of the data's length formed.
    pub fn kernel_rows(
        &self,
        taus: &[f64],
        rows: std::ops::Range<usize>,
        carry: &mut KernelCarry,
        h: &mut [f64],
        mut dh: Option<&mut [f64]>,
    ) {
        assert_eq!(carry.row, rows.start, "kernel rows taken out of order");
        let len = rows.len();
        if len == 0 {
            // No evaluation time: nothing to record (and no column to split).
            return;
        }
        carry.state.resize(taus.len(), 0.0);
        carry.derivative.resize(taus.len(), 0.0);
        let mut next = carry.interval;
        for (c, chunk) in taus.chunks(KERNEL_CHUNK).enumerate() {
            let (at, end) = (
                c * KERNEL_CHUNK * len,
                (c * KERNEL_CHUNK + chunk.len()) * len,
            );
            let s = &mut carry.state[c * KERNEL_CHUNK..][..chunk.len()];
            let d = &mut carry.derivative[c * KERNEL_CHUNK..][..chunk.len()];
            let from = Stand {
                interval: carry.interval,
                row: rows.start,
                s,
                d,
            };
            let h = &mut h[at..end];
            next = match dh.as_deref_mut() {
                Some(dh) => self.kernel_chunk::<true>(chunk, from, h, &mut dh[at..end]),
                None => self.kernel_chunk::<false>(chunk, from, h, &mut []),
            };
        }
        carry.interval = next;
        carry.row = rows.end;
    }

    /// One pass of [`Schedule::kernels`] over 1 to [`KERNEL_CHUNK`] τ, in a fixed
    /// number of lanes (4 or 8, the τ padded with copies of the first) so that the
    /// lanes' arithmetic, [`numerics::exp`] included, compiles to vector
    /// instructions, recording exactly as many columns as there are τ (a constant
    /// of the pass, so that each output's stores are a fixed sequence); from
    /// `from`, which it leaves at its last row, returning the interval after it.
    fn kernel_chunk<const D: bool>(
        &self,
        taus: &[f64],
        from: Stand,
        h: &mut [f64],
        dh: &mut [f64],
    ) -> usize {
        match taus.len() {
            1 => self.lanes::<4, 1, D>(taus, from, h, dh),
            2 => self.lanes::<4, 2, D>(taus, from, h, dh),
            3 => self.lanes::<4, 3, D>(taus, from, h, dh),
            4 => self.lanes::<4, 4, D>(taus, from, h, dh),
            5 => self.lanes::<8, 5, D>(taus, from, h, dh),
            6 => self.lanes::<8, 6, D>(taus, from, h, dh),
            7 => self.lanes::<8, 7, D>(taus, from, h, dh),
            _ => self.lanes::<8, 8, D>(taus, from, h, dh),
        }
    }

    /// [`Schedule::lanes_portable`] compiled for AVX2 (four f64 a vector register)
    /// where the processor has it, else for the baseline (two): the same arithmetic
    /// (Rust never fuses a multiply and an add), so the same bits either way.
    fn lanes<const L: usize, const K: usize, const D: bool>(
        &self,
        taus: &[f64],
        from: Stand,
        h: &mut [f64],
        dh: &mut [f64],
    ) -> usize {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (detected on the line above).
            return unsafe { self.lanes_avx2::<L, K, D>(taus, from, h, dh) };
        }
        self.lanes_portable::<L, K, D>(taus, from, h, dh)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn lanes_avx2<const L: usize, const K: usize, const D: bool>(
        &self,
        taus: &[f64],
        from: Stand,
        h: &mut [f64],
        dh: &mut [f64],
    ) -> usize {
        self.lanes_portable::<L, K, D>(taus, from, h, dh)
    }

    /// The pass itself: from the interval and the states of `from`, every interval
    /// advances all `L` lanes' states ([`Interval::advance`]); the first `K`
    /// (= `taus.len()`) are recorded at the outputs, into their columns of `h` (of
    /// `h.len() / K` rows from `from.row`), with their τ-derivatives into `dh` when
    /// `D`, up to the last of those rows. The lanes' states there go back into
    /// `from` (a padding lane, a copy of the first τ, has the first's state), and
    /// the interval after it is returned.
    #[inline(always)]
    fn lanes_portable<const L: usize, const K: usize, const D: bool>(
        &self,
        taus: &[f64],
        from: Stand,
        h: &mut [f64],
        dh: &mut [f64],
    ) -> usize {
        let m = h.len() / K;
        let (lo, last) = (from.row, from.row + m - 1);
        let mut tau = [taus[0]; L];
        tau[..K].copy_from_slice(taus);
        let inv = tau.map(|t| 1.0 / t);
        // Columns of exactly m values (one bounds check an output for all of them).
        let (mut hc, mut dc) = (h.chunks_exact_mut(m), dh.chunks_exact_mut(m));
        let mut hc: [&mut [f64]; K] = std::array::from_fn(|_| hc.next().expect("a column a τ"));
        let mut dc: [&mut [f64]; K] = std::array::from_fn(|_| match D {
            true => dc.next().expect("a derivative column a τ"),
            false => &mut [],
        });
        let (mut s, mut d) = ([from.s[0]; L], [from.d[0]; L]);
        s[..K].copy_from_slice(from.s);
        d[..K].copy_from_slice(from.d);
        // The exponential's constants as operands from memory (see `ExpTable`).
        let table = std::hint::black_box(&numerics::ExpTable::<L>::SPLAT);
        let mut next = from.interval;
        // The intervals before the final hold, then those of the hold, each loop of
        // one kind of interval (the same arithmetic either way: `Interval::hold`).
        // Interval `intervals.len() + k` is the hold's k-th.
        let stored = self.intervals.len();
        let mut done = false;
        for iv in &self.intervals[from.interval.min(stored)..] {
            next += 1;
            iv.advance::<L, D>(&tau, &inv, table, &mut s, &mut d);
            if let Some(o) = iv.out {
                record::<L, K, D>(&mut hc, &mut dc, &s, &d, o - lo);
                if o == last {
                    done = true;
                    break;
                }
            }
        }
        if !done {
            let first = self.hold_first + (next - stored);
            let mut before = match first.checked_sub(1) {
                Some(p) if first > self.hold_first => self.times[p],
                _ => self.hold_start,
            };
            for o in first..=last {
                next += 1;
                let at = self.times[o];
                Interval::hold::<L>(at - before, &inv, table, &mut s, &mut d);
                before = at;
                record::<L, K, D>(&mut hc, &mut dc, &s, &d, o - lo);
            }
        }
        from.s.copy_from_slice(&s[..K]);
        if D {
            from.d.copy_from_slice(&d[..K]);
        }
        next
    }
}

/// The first `K` lanes' states `s` (and derivatives `d` when `D`) into row `row` of
/// their columns.
#[inline(always)]
fn record<const L: usize, const K: usize, const D: bool>(
    hc: &mut [&mut [f64]; K],
    dc: &mut [&mut [f64]; K],
    s: &[f64; L],
    d: &[f64; L],
    row: usize,
) {
    for (c, v) in hc.iter_mut().zip(s) {
        c[row] = *v;
    }
    if D {
        for (c, v) in dc.iter_mut().zip(d) {
            c[row] = *v;
        }
    }
}

/// Where a pass of [`Schedule::kernel_rows`] stands between calls: the next
/// evaluation time and interval, and each τ's state and τ-derivative there (all 0
/// at the start).
#[derive(Debug, Clone, Default)]
pub struct KernelCarry {
    row: usize,
    interval: usize,
    state: Vec<f64>,
    derivative: Vec<f64>,
}

/// One chunk's share of a [`KernelCarry`]: its next interval and row, its τ's
/// states and derivatives.
struct Stand<'a> {
    interval: usize,
    row: usize,
    s: &'a mut [f64],
    d: &'a mut [f64],
}

/// The most τ one pass of [`Schedule::kernels`] carries (a relaxation fit has at most
/// a few terms; the grid stage's dozens take a pass each eight).
const KERNEL_CHUNK: usize = 8;

impl Interval {
    /// The states `s` of the lanes' τ kernels (`inv` = 1/τ) carried across this
    /// interval, and their τ-derivatives `d` when `D`: over dt at input rate ṙ,
    /// s ← a·s + ṙτ·b, d ← a·(d + (s − ṙτ)·dt/τ²) + ṙ·b, a = e^(−dt/τ)
    /// ([`numerics::exp`], its constants from `table`) and b = 1 − a without
    /// cancellation ([`numerics::one_minus_exp_neg`]: at dt/τ = 10⁻¹⁶, 1 − a is 0
    /// or 2⁻⁵³, and a 10⁻¹⁷ s ramp would lose its whole strain); then the input's
    /// jump.
    #[inline(always)]
    fn advance<const L: usize, const D: bool>(
        &self,
        tau: &[f64; L],
        inv: &[f64; L],
        table: &numerics::ExpTable<L>,
        s: &mut [f64; L],
        d: &mut [f64; L],
    ) {
        if self.dt > 0.0 {
            for i in 0..L {
                let x = self.dt * inv[i];
                let a = table.exp(-x, i);
                // 1 − a without its cancellation at small dt/τ (a ramp that is a step)
                let b = numerics::one_minus_exp_neg(x, a);
                let rt = self.rate * tau[i];
                if D {
                    d[i] = a * (d[i] + (s[i] - rt) * self.dt * inv[i] * inv[i]) + self.rate * b;
                }
                s[i] = a * s[i] + rt * b;
            }
        }
        for v in s.iter_mut() {
            *v += self.jump;
        }
    }

    /// [`Interval::advance`] of an interval of length `dt` of the final hold (rate
    /// and jump +0): ṙτ·b and ṙ·b are +0 (b is finite), so b, a third of the
    /// arithmetic, is not formed: s ← a·s + 0, d ← a·(d + s·dt/τ²) + 0, then s + 0
    /// (a no-op after the first + 0 but where dt = 0), the same bits. The
    /// derivatives are formed even when not asked for (where they are not, the
    /// vectoriser left the four lanes of a pass of four τ scalar: twice the time).
    #[inline(always)]
    fn hold<const L: usize>(
        dt: f64,
        inv: &[f64; L],
        table: &numerics::ExpTable<L>,
        s: &mut [f64; L],
        d: &mut [f64; L],
    ) {
        if dt > 0.0 {
            for i in 0..L {
                let a = table.exp(-(dt * inv[i]), i);
                d[i] = a * (d[i] + s[i] * dt * inv[i] * inv[i]) + 0.0;
                s[i] = a * s[i] + 0.0;
            }
        } else {
            for v in s.iter_mut() {
                *v += 0.0;
            }
        }
    }
}

/// A named set of published viscoelastic constants.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Preset {
    /// Name (`elatrache2021-table-3.3`, `elatrache2021-table-4.2`).
    pub name: &'static str,
    /// Where the numbers come from and how they are read.
    pub source: &'static str,
    /// Formulation the constants belong to.
    pub formulation: Formulation,
    /// Reference modulus (Pa) that turns normalised fractions into moduli (the
    /// instantaneous modulus E0 for QLV, the equilibrium spring for the parallel model).
    pub reference_modulus: f64,
    /// The Prony series in Pa.
    pub prony: Prony,
    /// The Kelvin-Maxwell arms (with Nv).
    pub kelvin_maxwell: KelvinMaxwell,
}

/// Names accepted by [`preset`]: the dissertation's author and year and its table
/// (El Atrache Ceballos (2021)).
pub const PRESET_NAMES: [&str; 2] = ["elatrache2021-table-3.3", "elatrache2021-table-4.2"];

/// Former names of the presets, (old, new): still accepted by [`preset`], which
/// says once per run that the name changed (the word "seed" is kept for random
/// seeds; issue 35, section 6).
pub const FORMER_PRESET_NAMES: [(&str, &str); 2] = [
    ("seed-table-3.3", PRESET_NAMES[0]),
    ("seed-table-4.2", PRESET_NAMES[1]),
];

/// The current name of preset `name` and, when `name` is a former name
/// ([`FORMER_PRESET_NAMES`]), the note that says so; any other name is returned
/// as it is, with no note.
pub fn current_preset_name(name: &str) -> (&str, Option<String>) {
    match FORMER_PRESET_NAMES.iter().find(|(old, _)| *old == name) {
        Some((old, new)) => (
            new,
            Some(format!(
                "viscoelastic preset '{old}' is now called '{new}' (El Atrache Ceballos (2021)); the old name still works but is deprecated: use '{new}'"
            )),
        ),
        None => (name, None),
    }
}

/// Print the note of a former preset name on stderr, once per name and run (a
/// rank manifest or a search may resolve the same name many times).
fn note_former_name(name: &str) {
    use std::sync::atomic::{AtomicBool, Ordering};
    static SAID: [AtomicBool; FORMER_PRESET_NAMES.len()] =
        [AtomicBool::new(false), AtomicBool::new(false)];
    let Some(i) = FORMER_PRESET_NAMES.iter().position(|(old, _)| *old == name) else {
        return;
    };
    if let (_, Some(note)) = current_preset_name(name) {
        if !SAID[i].swap(true, Ordering::Relaxed) {
            eprintln!("note: {note}");
        }
    }
}

/// Table 3.3 relaxation times τᵢ (s) and fractions gᵢ (Wissler & Mazza 2007, VHB 4910).
pub const TABLE_3_3: [(f64, f64); 4] = [
    (0.153, 0.478),
    (0.464, 0.205),
    (32.021, 0.0727),
    (215.85, 0.0492),
];

/// The reference modulus of El Atrache Ceballos (2021) Table 4.2: its kⱼ equal gⱼ × 0.222 MPa for all
/// four arms (≈ Y0 = 220 kPa of Table 3.4).
pub const TABLE_4_2_REFERENCE: f64 = 0.222e6;

/// Table 4.2 Maxwell arms (kⱼ Pa, nⱼ Pa·s), tuned by hand by the dissertation's author.
pub const TABLE_4_2_ARMS: [(f64, f64); 4] = [
    (0.106116e6, 0.033966e6),
    (0.045510e6, 0.103008e6),
    (0.016139e6, 7.108662e6),
    (0.010922e6, 47.91e6),
];

/// Table 4.2 Kelvin-Voigt dashpot Nv = 1875e-6 MPa·s.
pub const TABLE_4_2_NV: f64 = 1875.0;

/// Table 4.2 (= Table 3.2) Yeoh C10 (Pa); the dissertation's equilibrium spring has the
/// small-strain Young's modulus 6·C10.
pub const TABLE_4_2_C10: f64 = 0.0693e6;

/// A named preset:
/// * `elatrache2021-table-3.3`: Table 3.3's normalised Prony pairs in the QLV reading, with the
///   reference E0 = 0.222 MPa that Table 4.2 multiplies them by; g∞ = 1 − Σgᵢ = 0.1951;
///   Nv = 0 as the table says.
/// * `elatrache2021-table-4.2`: Table 4.2's arms and Nv in the dissertation's parallel model, with the
///   Yeoh spring's small-strain modulus 6·C10 = 415.8 kPa as the equilibrium spring.
///   Its τⱼ = nⱼ/kⱼ (0.32, 2.26, 440, 4386 s) are not Table 3.3's.
///
/// A former name ([`FORMER_PRESET_NAMES`]) gives the same preset, under its new
/// name, with a note on stderr.
pub fn preset(name: &str) -> Result<Preset> {
    note_former_name(name);
    match current_preset_name(name).0 {
        "elatrache2021-table-3.3" => {
            let prony = Prony::from_normalized(TABLE_4_2_REFERENCE, &TABLE_3_3)?;
            Ok(Preset {
                name: "elatrache2021-table-3.3",
                source: "El Atrache Ceballos (2021) Table 3.3 (Wissler & Mazza 2007, VHB 4910): normalised Prony pairs (τᵢ, gᵢ); the table's 'MPa' on gᵢ is read as a fraction of E0 = 0.222 MPa (the multiplier of Table 4.2)",
                formulation: Formulation::Qlv,
                reference_modulus: TABLE_4_2_REFERENCE,
                kelvin_maxwell: prony.to_kelvin_maxwell(),
                prony,
            })
        }
        "elatrache2021-table-4.2" => {
            let km = KelvinMaxwell {
                k_inf: 6.0 * TABLE_4_2_C10,
                arms: TABLE_4_2_ARMS
                    .iter()
                    .map(|&(k, n)| MaxwellArm { k, n })
                    .collect(),
                n_v: TABLE_4_2_NV,
            };
            Ok(Preset {
                name: "elatrache2021-table-4.2",
                source: "El Atrache Ceballos (2021) Table 4.2 (hand-tuned by its author): Maxwell arms kⱼ, nⱼ and Nv = 1875 Pa·s in the parallel model; equilibrium spring = Yeoh small-strain modulus 6·C10",
                formulation: Formulation::Parallel,
                reference_modulus: 6.0 * TABLE_4_2_C10,
                prony: km.to_prony()?,
                kelvin_maxwell: km,
            })
        }
        other => Err(
            Error::settings(format!("unknown viscoelastic preset '{other}'"))
                .with_hint(format!("use one of {}", PRESET_NAMES.join(", "))),
        ),
    }
}

/// One isotherm's measured shift in a DMA fit file: its temperature (K), its free
/// log10 aT referred to Tr and, with a vertical shift, log10 bT.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredShift {
    /// The isotherm's temperature (K).
    pub temperature_k: f64,
    /// Free log10 aT (reduced frequency = aT·ω).
    pub log10_at: f64,
    /// log10 bT (the isotherm's moduli are bT times the master curve's); None
    /// without a vertical shift.
    pub log10_bt: Option<f64>,
}

/// The time–temperature superposition of a DMA fit (`dea-fit dma`): its Prony
/// series holds at the reference temperature Tr, and at T
///
///   E(t; T) = bT · [E∞ + Σ Eᵢ·exp(−t/(aT·τᵢ))],
///
/// i.e. every relaxation time is τᵢ(T) = aT(T)·τᵢ(Tr) and every modulus bT(T)·Eᵢ
/// (Ferry, *Viscoelastic Properties of Polymers*, 3rd ed., Wiley 1980, ch. 11,
/// eq. 11-9 for the horizontal shift, the vertical factor of §11.B). aT is the
/// horizontal shift of the fit file (reduced frequency = aT·ω): at a higher
/// temperature aT < 1 and the material relaxes faster.
///
/// * WLF (Williams, Landel & Ferry, J. Am. Chem. Soc. 77, 3701, 1955; Ferry eq.
///   11-26 at Tr): log10 aT = −C1 (T − Tr)/(C2 + T − Tr), defined for C2 + T − Tr > 0;
/// * Arrhenius: log10 aT = Ea/(R ln 10)·(1/T − 1/Tr);
/// * free shifts: log10 aT (and log10 bT) linear in T between the measured
///   temperatures (linear, not PCHIP: it never overshoots the measured shifts and
///   stays monotonic where they are), extrapolated from the nearest two outside.
///
/// With a law the vertical shift, when the fit has one, is the free log10 bT
/// interpolated the same way (a law is fitted to the horizontal shifts only).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeTemperature {
    /// Tr (K).
    pub reference_k: f64,
    /// The fitted law; None: the free shifts.
    pub law: Option<crate::dma::law::Law>,
    /// The measured shifts, coldest first (at least two).
    pub measured: Vec<MeasuredShift>,
}

/// The shift at one temperature ([`TimeTemperature::at`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ShiftAt {
    /// log10 aT.
    pub log10_at: f64,
    /// log10 bT (0 without a vertical shift).
    pub log10_bt: f64,
    /// The temperature lies outside the measured ones: the shift is extrapolated.
    pub warning: Option<String>,
}

impl ShiftAt {
    /// A Maxwell arm (kⱼ, ηⱼ = kⱼ·τⱼ) at the temperature: kⱼ·bT, τⱼ·aT, so
    /// ηⱼ·aT·bT. At Tr (aT = bT = 1) the arm is returned unchanged, bit for bit.
    pub fn arm(&self, a: &crate::material::file::Arm) -> crate::material::file::Arm {
        let (at, bt) = (10f64.powf(self.log10_at), 10f64.powf(self.log10_bt));
        crate::material::file::Arm {
            k_pa: a.k_pa * bt,
            eta_pa_s: a.eta_pa_s * at * bt,
        }
    }
}

impl TimeTemperature {
    /// The measured temperatures, lowest and highest (K).
    pub fn measured_range(&self) -> (f64, f64) {
        let t = |m: Option<&MeasuredShift>| m.map_or(f64::NAN, |m| m.temperature_k);
        (t(self.measured.first()), t(self.measured.last()))
    }

    /// The shift at `t` (K): Err with the reason at or below the WLF singularity
    /// (C2 + T − Tr ≤ 0, where aT is infinite); a warning with the numbers outside
    /// the measured temperatures.
    pub fn at(&self, t: f64) -> std::result::Result<ShiftAt, String> {
        use crate::dma::temperature::celsius;
        let tr = self.reference_k;
        let log10_at = match &self.law {
            Some(law) => {
                if let (Some(c1), Some(c2)) = (law.c1, law.c2) {
                    if c2 + t - tr <= 0.0 {
                        return Err(format!(
                            "{} is at or below the WLF singularity Tr − C2 = {} (C1 = {c1:.4}, C2 = {c2:.4} K, Tr = {}): aT is infinite there, the material is glassy and WLF does not hold",
                            celsius(t),
                            celsius(tr - c2),
                            celsius(tr)
                        ));
                    }
                }
                law.log_at(t)
            }
            // aT(Tr) = bT(Tr) = 1 by definition, whatever the interpolation's rounding
            None if t == tr => 0.0,
            None => self.interpolated(t, |m| Some(m.log10_at)),
        };
        let log10_bt = match self.measured.iter().any(|m| m.log10_bt.is_some()) {
            true if t != tr => self.interpolated(t, |m| m.log10_bt),
            _ => 0.0,
        };
        let (lo, hi) = self.measured_range();
        let warning = (t < lo || t > hi).then(|| {
            let how = match &self.law {
                Some(l) => format!("by the {} law", l.kind.label()),
                None => "from the nearest two measured shifts".to_string(),
            };
            format!(
                "temperature {} is outside the DMA fit's measured temperatures {} … {}: aT = 10^{log10_at:.3} is extrapolated {how}, and the Prony series is assumed to hold there",
                celsius(t),
                celsius(lo),
                celsius(hi)
            )
        });
        Ok(ShiftAt {
            log10_at,
            log10_bt,
            warning,
        })
    }

    /// `y` of the measured shifts (0 where None) linear in T at `t`, extrapolated
    /// from the nearest two outside.
    fn interpolated(&self, t: f64, y: impl Fn(&MeasuredShift) -> Option<f64>) -> f64 {
        let m = &self.measured;
        let n = m.len();
        if n < 2 {
            return m.first().and_then(&y).unwrap_or(0.0);
        }
        let j = m
            .iter()
            .position(|p| p.temperature_k > t)
            .unwrap_or(n - 1)
            .clamp(1, n - 1);
        let (a, b) = (&m[j - 1], &m[j]);
        let (ya, yb) = (y(a).unwrap_or(0.0), y(b).unwrap_or(0.0));
        ya + (yb - ya) * (t - a.temperature_k) / (b.temperature_k - a.temperature_k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-pass kernels of several τ (every count a pass records, and more than
    /// one chunk of them) are each τ's own kernel and derivative, bit for bit, on a
    /// history with a ramp, a hold and an unloading (rates and jumps).
    #[test]
    fn kernels_are_each_taus_kernel_exactly() {
        let times: Vec<f64> = (0..60)
            .map(|i| 0.05 * i as f64 * (1.0 + 0.1 * i as f64))
            .collect();
        let history =
            History::from_knots(vec![(0.0, 0.0), (0.4, 1.5), (3.0, 1.5), (3.5, 0.2)]).unwrap();
        let sched = Schedule::new(&history, &times).unwrap();
        let all = [0.03, 0.7, 2.0, 45.0, 1e4, 0.2, 0.9, 3.3, 11.0, 0.05, 600.0];
        assert!(all.len() > KERNEL_CHUNK, "the τ cross a chunk boundary");
        let m = times.len();
        // Every count of τ a pass records (1 to 8) and past a chunk boundary.
        for count in 1..=all.len() {
            let taus = &all[..count];
            let (mut h, mut dh) = (vec![0.0; m * count], vec![0.0; m * count]);
            sched.kernels(taus, &mut h, Some(&mut dh));
            let mut h_only = vec![0.0; m * count];
            sched.kernels(taus, &mut h_only, None);
            for (i, &tau) in taus.iter().enumerate() {
                let (mut h1, mut d1) = (vec![0.0; m], vec![0.0; m]);
                sched.kernel(tau, &mut h1, Some(&mut d1));
                assert_eq!(h[i * m..(i + 1) * m], h1[..], "τ = {tau} of {count}");
                assert_eq!(dh[i * m..(i + 1) * m], d1[..], "τ = {tau} of {count}");
                assert_eq!(h_only[i * m..(i + 1) * m], h1[..], "τ = {tau} of {count}");
            }
        }
    }

    /// The kernels' pass compiled for AVX2 and for the baseline give the same bits
    /// (both chunk widths, with derivatives and without), where the processor has
    /// AVX2 to compare.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn vector_and_baseline_kernels_agree_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let times: Vec<f64> = (0..300).map(|i| 1e-3 * 1.05f64.powi(i)).collect();
        let history =
            History::from_knots(vec![(0.0, 0.0), (0.4, 1.5), (3.0, 1.5), (3.5, 0.2)]).unwrap();
        let sched = Schedule::new(&history, &times).unwrap();
        agree::<3>(&sched, &[0.02, 0.7, 30.0]);
        agree::<7>(&sched, &[0.01, 0.1, 1.0, 3.0, 10.0, 100.0, 1e3]);
    }

    /// [`vector_and_baseline_kernels_agree_bit_for_bit`] for `K` τ: 8 lanes with
    /// and without derivatives, 4 lanes too where they hold the τ.
    #[cfg(target_arch = "x86_64")]
    fn agree<const K: usize>(sched: &Schedule, taus: &[f64; K]) {
        let n = K * sched.len();
        let (mut h, mut d, mut hv, mut dv) =
            (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let (mut h1, mut h1v) = (vec![0.0; n], vec![0.0; n]);
        // each pass from the start: its own zero states
        let (mut s, mut sd) = ([[0.0; K]; 5], [[0.0; K]; 5]);
        let mut starts = s.iter_mut().zip(&mut sd).map(|(s, d)| Stand {
            interval: 0,
            row: 0,
            s,
            d,
        });
        let mut start = || starts.next().expect("a start a pass");
        // SAFETY: the caller detected AVX2.
        unsafe {
            sched.lanes_avx2::<8, K, true>(taus, start(), &mut hv, &mut dv);
            sched.lanes_avx2::<8, K, false>(taus, start(), &mut h1v, &mut []);
        }
        sched.lanes_portable::<8, K, true>(taus, start(), &mut h, &mut d);
        sched.lanes_portable::<8, K, false>(taus, start(), &mut h1, &mut []);
        assert_eq!(h, hv);
        assert_eq!(d, dv);
        assert_eq!(h1, h1v);
        assert_eq!(h1, h);
        if K <= 4 {
            let (mut h4, mut d4) = (vec![0.0; n], vec![0.0; n]);
            // SAFETY: the caller detected AVX2.
            unsafe { sched.lanes_avx2::<4, K, true>(taus, start(), &mut h4, &mut d4) };
            assert_eq!(h4, h);
            assert_eq!(d4, d);
        }
    }

    /// The kernels of a schedule that ends in a hold, its intervals there not stored
    /// and taken by [`Interval::hold`], are those of stored intervals and
    /// [`Interval::advance`] for every interval,
    /// bit for bit (with and without derivatives, 3 τ and 11), on a ramp, a hold,
    /// an unloading to a negative value (negative states) and a final hold with
    /// repeated times (intervals of dt = 0).
    #[test]
    fn the_final_hold_is_the_general_interval_bit_for_bit() {
        let mut times: Vec<f64> = (0..80).map(|i| 0.1 * i as f64).collect();
        times.extend([7.9, 7.9, 8.5]);
        let history =
            History::from_knots(vec![(0.0, 0.0), (0.4, 1.5), (3.0, 1.5), (3.5, -0.2)]).unwrap();
        let held = Schedule::new(&history, &times).unwrap();
        assert!(times.len() - held.hold_first > 40, "a long final hold");
        // the hold's intervals stored as general ones
        let mut general = held.clone();
        let mut before = held.hold_start;
        for (o, &at) in times.iter().enumerate().skip(held.hold_first) {
            general.intervals.push(Interval {
                dt: at - before,
                rate: 0.0,
                jump: 0.0,
                out: Some(o),
            });
            before = at;
        }
        general.hold_first = times.len();
        let m = times.len();
        let all = [0.03, 0.7, 2.0, 45.0, 1e4, 0.2, 0.9, 3.3, 11.0, 0.05, 600.0];
        for taus in [&all[..3], &all[..]] {
            let n = taus.len();
            let bits = |sched: &Schedule, derivatives: bool| {
                let (mut h, mut dh) = (vec![0.0; n * m], vec![0.0; n * m]);
                sched.kernels(taus, &mut h, derivatives.then_some(&mut dh[..]));
                let b = |v: Vec<f64>| v.into_iter().map(f64::to_bits).collect::<Vec<_>>();
                (b(h), b(dh))
            };
            for derivatives in [true, false] {
                assert_eq!(bits(&held, derivatives), bits(&general, derivatives));
            }
        }
    }

    /// The kernels taken a block of rows at a time ([`Schedule::kernel_rows`], the
    /// pass resumed from its [`KernelCarry`]: blocks of 1, 7 and 64 rows, the last
    /// one short) are the one-pass kernels bit for bit, with and without
    /// derivatives, on a history with a ramp, a hold and an unloading whose knots
    /// fall between rows inside the blocks, for 3 τ (one chunk) and 11 (two).
    #[test]
    fn kernels_a_block_of_rows_at_a_time_are_the_one_pass_kernels() {
        let times: Vec<f64> = (0..150).map(|i| 0.04 * i as f64).collect();
        let history =
            History::from_knots(vec![(0.0, 0.0), (0.41, 1.5), (2.8, 1.5), (3.5, 0.2)]).unwrap();
        let sched = Schedule::new(&history, &times).unwrap();
        let m = times.len();
        let all = [0.03, 0.7, 2.0, 45.0, 1e4, 0.2, 0.9, 3.3, 11.0, 0.05, 600.0];
        for taus in [&all[..3], &all[..]] {
            let n = taus.len();
            let (mut h, mut dh, mut h_only) =
                (vec![0.0; n * m], vec![0.0; n * m], vec![0.0; n * m]);
            sched.kernels(taus, &mut h, Some(&mut dh));
            sched.kernels(taus, &mut h_only, None);
            for block in [1, 7, 64] {
                let (mut carry, mut carry_only) = (KernelCarry::default(), KernelCarry::default());
                for lo in (0..m).step_by(block) {
                    let hi = (lo + block).min(m);
                    let len = hi - lo;
                    let (mut hb, mut db, mut hob) =
                        (vec![0.0; n * len], vec![0.0; n * len], vec![0.0; n * len]);
                    sched.kernel_rows(taus, lo..hi, &mut carry, &mut hb, Some(&mut db));
                    sched.kernel_rows(taus, lo..hi, &mut carry_only, &mut hob, None);
                    for i in 0..n {
                        let (want, got) = (i * m + lo..i * m + hi, i * len..(i + 1) * len);
                        assert_eq!(
                            h[want.clone()],
                            hb[got.clone()],
                            "{n} τ, block {block} at {lo}"
                        );
                        assert_eq!(
                            dh[want.clone()],
                            db[got.clone()],
                            "{n} τ, block {block} at {lo}"
                        );
                        assert_eq!(h_only[want], hob[got], "{n} τ, block {block} at {lo}");
                    }
                }
            }
        }
    }

    /// The limits of the ramp kernel against their closed forms (issue 32: 1 − e^(−dt/τ)
    /// by subtraction lost a 10⁻¹⁷ s ramp's whole strain): ramp → step (t_r → 0), the
    /// ramp's own interval dt → 0, and τ → ∞. Tolerance 1e-13 relative: the kernel's
    /// recursion is exact for a linear ramp, so only rounding differs (a few 2⁻⁵³ a
    /// step over ≤ 60 steps, and the 5·10⁻¹⁵ of `one_minus_exp_neg`).
    #[test]
    fn ramp_kernel_limits_match_closed_forms() {
        let rel = |a: f64, b: f64| match a == b {
            true => 0.0,
            false => ((a - b) / b).abs(),
        };
        // up to 100 s: e^(−t/τ) stays a normal number for every τ ≥ 0.153 s
        // (`numerics::exp` is 0 below e^(−708), libm's is subnormal there)
        let times: Vec<f64> = (0..44).map(|i| 1e-3 * 1.3f64.powi(i)).collect();
        let x0 = 0.5;
        for tau in [0.153, 0.464, 32.0, 215.85] {
            let mut step = vec![0.0; times.len()];
            Schedule::new(&History::step(x0), &times)
                .unwrap()
                .kernel(tau, &mut step, None);
            // ramp → step: h(t ≥ t_r) = x0·(τ/t_r)(e^(t_r/τ) − 1)·e^(−t/τ), the step's
            // response times a factor 1 + t_r/(2τ) + …, which is 1 to rounding here
            for tr in [1e-17, 1e-14, 1e-9] {
                let mut h = vec![0.0; times.len()];
                Schedule::new(&History::ramp(x0, tr), &times)
                    .unwrap()
                    .kernel(tau, &mut h, None);
                for ((t, v), s) in times.iter().zip(&h).zip(&step) {
                    let exact = x0 * (tau / tr) * (tr / tau).exp_m1() * (-t / tau).exp();
                    assert!(
                        rel(*v, exact) < 1e-13,
                        "τ {tau} t_r {tr} t {t}: {v} vs {exact}"
                    );
                    assert!(
                        rel(*v, *s) < 1e-13 + tr / tau,
                        "τ {tau} t_r {tr}: {v} vs step {s}"
                    );
                }
            }
            // dt → 0 inside the ramp: h(t ≤ t_r) = (x0/t_r)·τ·(1 − e^(−t/τ)) → x0·t/t_r
            let tr = 1e-12;
            let inside = [1e-17, 1e-15, 2.5e-13, 1e-12];
            let mut h = vec![0.0; inside.len()];
            Schedule::new(&History::ramp(x0, tr), &inside)
                .unwrap()
                .kernel(tau, &mut h, None);
            for (t, v) in inside.iter().zip(&h) {
                let exact = x0 / tr * tau * -(-t / tau).exp_m1();
                assert!(rel(*v, exact) < 1e-13, "τ {tau} t {t}: {v} vs {exact}");
            }
        }
        // τ → ∞: nothing relaxes; h = x0·(τ/t_r)(e^(t_r/τ) − 1)·e^(−t/τ) → x0
        for tau in [1e9, 1e12, 1e15] {
            let tr = 0.8;
            let mut h = vec![0.0; times.len()];
            Schedule::new(&History::ramp(x0, tr), &times)
                .unwrap()
                .kernel(tau, &mut h, None);
            for (t, v) in times.iter().zip(&h) {
                let exact = match *t <= tr {
                    true => x0 / tr * tau * -(-t / tau).exp_m1(),
                    false => x0 * (tau / tr) * (tr / tau).exp_m1() * (-t / tau).exp(),
                };
                assert!(rel(*v, exact) < 1e-13, "τ {tau} t {t}: {v} vs {exact}");
            }
        }
        // the creep compliance's retardation terms as λ → ∞: R·(1 − e^(−t/λ)) ≈ R·t/λ
        let c = Creep {
            j_g: 0.0,
            terms: vec![RetardationTerm {
                lambda: 1e15,
                compliance: 2.0,
            }],
            fluidity: 0.0,
        };
        assert!(rel(c.compliance(1e-3), 2.0 * 1e-3 / 1e15) < 1e-15);
    }

    #[test]
    fn step_and_ramp_kernels_match_closed_forms() {
        let times: Vec<f64> = (0..50).map(|i| 0.1 * i as f64).collect();
        let tau = 0.7;
        let s = Schedule::new(&History::step(2.0), &times).unwrap();
        let mut h = vec![0.0; times.len()];
        s.kernel(tau, &mut h, None);
        for (t, v) in times.iter().zip(&h) {
            assert!((v - 2.0 * (-t / tau).exp()).abs() < 1e-13, "{t} {v}");
        }
        let tr = 1.0;
        let s = Schedule::new(&History::ramp(2.0, tr), &times).unwrap();
        s.kernel(tau, &mut h, None);
        for (t, v) in times.iter().zip(&h) {
            let exact = if *t <= tr {
                2.0 / tr * tau * (1.0 - (-t / tau).exp())
            } else {
                // Step response scaled by (τ/t_r)(e^(t_r/τ) − 1).
                2.0 * (tau / tr) * ((tr / tau).exp() - 1.0) * (-t / tau).exp()
            };
            assert!((v - exact).abs() < 1e-12, "{t} {v} {exact}");
        }
        assert!((s.input()[20] - 2.0).abs() < 1e-15 && (s.input()[5] - 1.0).abs() < 1e-12);
    }

    /// Free shifts with a vertical shift: log10 aT and log10 bT linear in T between
    /// the measured temperatures, exactly 0 at Tr, extrapolated outside with a
    /// warning; an arm's k times bT and η times aT·bT. WLF: its formula, and an
    /// error at the singularity C2 + T − Tr ≤ 0.
    #[test]
    fn time_temperature_shift() {
        let m = |t: f64, a: f64, b: f64| MeasuredShift {
            temperature_k: t,
            log10_at: a,
            log10_bt: Some(b),
        };
        let free = TimeTemperature {
            reference_k: 300.0,
            law: None,
            measured: vec![
                m(290.0, 1.0, 0.02),
                m(310.0, -1.0, -0.02),
                m(320.0, -1.5, -0.03),
            ],
        };
        let s = free.at(305.0).unwrap();
        assert!((s.log10_at + 0.5).abs() < 1e-15 && (s.log10_bt + 0.01).abs() < 1e-15);
        assert!(s.warning.is_none());
        let s0 = free.at(300.0).unwrap();
        assert_eq!((s0.log10_at, s0.log10_bt), (0.0, 0.0));
        let arm = crate::material::file::Arm {
            k_pa: 1e5,
            eta_pa_s: 2e5,
        };
        assert_eq!(s0.arm(&arm), arm);
        let a = s.arm(&arm);
        assert!((a.k_pa / (1e5 * 10f64.powf(-0.01)) - 1.0).abs() < 1e-15);
        assert!((a.eta_pa_s / (2e5 * 10f64.powf(-0.51)) - 1.0).abs() < 1e-15);
        // beyond 320 K: the last two, extrapolated
        let hot = free.at(330.0).unwrap();
        assert!((hot.log10_at + 2.0).abs() < 1e-12, "{}", hot.log10_at);
        assert!(hot.warning.unwrap().contains("outside"));
        let wlf = TimeTemperature {
            law: Some(crate::dma::law::Law::wlf(300.0, 8.0, 100.0)),
            ..free
        };
        let w = wlf.at(320.0).unwrap();
        assert!((w.log10_at + 8.0 * 20.0 / 120.0).abs() < 1e-15);
        assert!(wlf.at(200.0).unwrap_err().contains("WLF singularity"));
    }
}
