//! The Prony core shared by the time domain ([`super::relaxation`]: a stress-relaxation
//! curve under a loading history) and the frequency domain ([`frequency`]: storage
//! and loss moduli of a DMA sweep or master curve).
//!
//! Both fit the same generalized Maxwell model, E(t) = E∞ + Σ Eᵢ·e^(−t/τᵢ)
//! (Ferry, *Viscoelastic Properties of Polymers*, 3rd ed., 1980, ch. 3), observed
//! through a linear map: every data row k is E∞·xₖ + Σ Eᵢ·hₖ(τᵢ) for an input xₖ
//! and a kernel hₖ(τ) that a domain supplies ([`Kernels`]). The estimation is the
//! same for both:
//! 1. [`grid`]: non-negative least squares over a log-spaced τ grid (Lawson–Hanson,
//!    [`super::nnls`]): where the spectrum lives.
//! 2. [`starts`]: the grid spectrum's peaks merged or split into N terms, several
//!    deterministic ways (the multi-start).
//! 3. [`refine`]: variable projection over ln τᵢ ([`projection`], Golub & Pereyra
//!    1973 with Kaufman's 1975 Jacobian) with E∞, Eᵢ ≥ 0 by NNLS at each τ, then a
//!    joint Levenberg-Marquardt polish of ([`problem`]) (E∞, Eᵢ, ln τᵢ).
//! 4. [`assess`]: statistics, σ of every parameter, identifiability by the one rule
//!    ([`super::identifiability`]), terms outside the window the data support.
//! 5. [`select`]: the term count, given or by AICc (or BIC, or a tolerance) among
//!    counts whose terms are all identifiable.
//!
//! [`interconvert`] holds what a fitted series gives in the other domains (E(t),
//! E′, E″, tan δ, creep compliance).

pub mod assess;
pub mod frequency;
pub mod grid;
pub mod interconvert;
pub mod kernels;
pub mod problem;
pub mod projection;
pub mod refine;
pub mod select;
pub mod starts;

pub use kernels::{Kernels, ShiftCovariance};

/// The normal equations (JᵀJ, Jᵀr) a problem formed at its last point p, for
/// [`crate::fit::lm::LeastSquares::normal_equations`]: handed out only at that p.
#[derive(Debug, Clone, Default)]
pub(crate) struct NormalCache(Option<(Vec<f64>, nalgebra::DMatrix<f64>, nalgebra::DVector<f64>)>);

impl NormalCache {
    /// Keep (JᵀJ, Jᵀr) formed at p.
    pub(crate) fn keep(
        &mut self,
        p: &[f64],
        jtj: nalgebra::DMatrix<f64>,
        jtr: nalgebra::DVector<f64>,
    ) {
        self.0 = Some((p.to_vec(), jtj, jtr));
    }

    /// Forget them (the next evaluation forms none).
    pub(crate) fn clear(&mut self) {
        self.0 = None;
    }

    /// (JᵀJ, Jᵀr) if they were formed at p.
    pub(crate) fn at(&self, p: &[f64]) -> Option<(nalgebra::DMatrix<f64>, nalgebra::DVector<f64>)> {
        match &self.0 {
            Some((at, jtj, jtr)) if at.as_slice() == p => Some((jtj.clone(), jtr.clone())),
            _ => None,
        }
    }
}
pub use select::{Candidate, Criterion, Selection};

use crate::error::{Error, Result};
use problem::Problem;
use serde::{Deserialize, Serialize};

/// Estimation method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Grid NNLS, merge/prune, then bounded LM refinement of τ and E (default).
    #[default]
    Refined,
    /// Grid NNLS and merge/prune only: τ stay where the merged grid peaks put them,
    /// moduli by NNLS at those τ (for comparison: `dea-fit bench relaxation`).
    Grid,
}

/// What the Prony search is asked to do, in either domain (checked by
/// [`Search::check`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    /// Number of Prony terms, or `None` for automatic choice.
    pub terms: Option<usize>,
    /// Largest term count tried by the automatic choice (default 6).
    pub max_terms: usize,
    /// Score of the automatic choice (default AICc).
    pub criterion: Criterion,
    /// With a tolerance, `auto` takes the fewest terms whose relative RMSE is at most
    /// this fraction (e.g. 0.01) instead of using the criterion.
    pub tolerance: Option<f64>,
    /// Method (default refined).
    pub method: Method,
    /// τ grid density of the NNLS stage, points per decade (default 6; 2–50).
    pub grid_per_decade: usize,
    /// Iteration limit of each LM search (default 200).
    pub max_iterations: usize,
    /// Relative cost tolerance of the LM searches (default 1e-10).
    pub ftol: f64,
    /// Largest number of starts per term count (default 3).
    pub max_starts: usize,
}

impl Default for Search {
    fn default() -> Self {
        Search {
            terms: None,
            max_terms: 6,
            criterion: Criterion::Aicc,
            tolerance: None,
            method: Method::Refined,
            grid_per_decade: 6,
            max_iterations: 200,
            ftol: 1e-10,
            max_starts: 3,
        }
    }
}

impl Search {
    /// Reject settings that cannot work (at most 12 terms: a relaxation record
    /// covers 3–8 decades).
    pub fn check(&self) -> Result<()> {
        self.check_terms(12)
    }

    /// [`Search::check`] with at most `max` terms.
    pub fn check_terms(&self, max: usize) -> Result<()> {
        if self.terms.is_some_and(|n| n > max) || self.max_terms > max {
            return Err(
                Error::settings(format!("at most {max} Prony terms are supported")).with_hint(
                    "real relaxation spectra rarely support more than one term per decade of data",
                ),
            );
        }
        if !(2..=50).contains(&self.grid_per_decade) {
            return Err(Error::settings(format!(
                "the τ grid density must be 2–50 per decade, found {}",
                self.grid_per_decade
            )));
        }
        if self.max_iterations == 0 || self.max_starts == 0 {
            return Err(Error::settings(
                "the iteration limit and the number of starts must be at least 1",
            ));
        }
        if !(self.ftol > 0.0 && self.ftol < 1.0) {
            return Err(Error::settings(format!(
                "tolerance must be in (0, 1), found {}",
                self.ftol
            )));
        }
        if let Some(t) = self.tolerance {
            if !(t > 0.0 && t < 1.0) {
                return Err(Error::settings(format!(
                    "--tolerance is a relative RMSE in (0, 1), e.g. 0.01, found {t}"
                )));
            }
        }
        Ok(())
    }
}

/// A domain's data made ready for the search: the problem (in scaled units), the
/// window of τ the data support and the bounds of the τ search.
#[derive(Debug, Clone)]
pub struct Setup<K: Kernels> {
    /// The weighted problem, no terms yet.
    pub prob: Problem<K>,
    /// The τ the data support: [first positive time, last time] of a relaxation
    /// curve, [1/ω_max, 1/ω_min] of a frequency sweep (s).
    pub window: (f64, f64),
    /// ln τ search bounds (the window widened ×10 at each end).
    pub bounds: (f64, f64),
    /// Moduli unit: Pa per unit of the scaled coefficient·S (1 but for QLV, 3μ0).
    pub unit: f64,
}

impl<K: Kernels> Setup<K> {
    /// The setup of `prob` for the window `window`: the τ search runs over the window
    /// widened ×10 at each end.
    pub fn new(prob: Problem<K>, window: (f64, f64), unit: f64) -> Setup<K> {
        let bounds = ((window.0 / 10.0).ln(), (window.1 * 10.0).ln());
        Setup {
            prob,
            window,
            bounds,
            unit,
        }
    }
}

/// Seconds with an SI prefix, for messages.
pub(crate) fn fmt_s(t: f64) -> String {
    crate::report::format::si(t, "s")
}

/// Parameter names and units in the order of the SI parameters: E_inf, E1…, tau1….
pub fn param_names(n: usize) -> Vec<(String, &'static str)> {
    let mut v = vec![("E_inf".to_string(), "Pa")];
    v.extend((1..=n).map(|i| (format!("E{i}"), "Pa")));
    v.extend((1..=n).map(|i| (format!("tau{i}"), "s")));
    v
}
