//! The viscoelastic estimator: Prony / Kelvin-Maxwell constants from a stress-relaxation
//! curve (seed Chapter 3, Tables 3.3 and 4.2).
//!
//! Model: σ(t) = E∞·x(t) + Σ Eᵢ·hᵢ(t), with hᵢ the exact hereditary state of
//! e^(−t/τᵢ) for the loading history x ([`Schedule`]): the strain in the small-strain
//! reading ([`Formulation::Parallel`], modulus = stress/ε0 after a step), or the
//! instantaneous hyperelastic stress σₑ(λ(s)) in the QLV reading.
//!
//! Two stages:
//! 1. Non-negative least squares over a log-spaced τ grid (default 6 per decade over
//!    the sampled window widened by ×3 at each end; Lawson–Hanson active set on
//!    the normal equations, `fit/nnls.rs`): where the relaxation spectrum lives. On a
//!    curve of more than 400 points, on an even subsample of 400 (where the starts
//!    are searched).
//! 2. For a term count N: the grid spectrum's peaks are merged or split into N terms
//!    (several deterministic ways: the multi-start), and the τᵢ refined by variable
//!    projection: bounded Levenberg-Marquardt over ln τᵢ (within the window widened
//!    ×10) with E∞, Eᵢ ≥ 0 the non-negative least-squares solution at each τ; a last
//!    LM search over (E∞, Eᵢ, ln τᵢ) together polishes the optimum. E∞ and E0 are
//!    fitted, never pinned to the last and first points.
//!
//! Residuals are chosen by the loading unless the settings name them ([`Settings::residual`]):
//! relative (floor: 1 % of the largest |stress|) for a relaxation test, whose strain is
//! held, so that the long-time tail counts as much as the first second; absolute for a
//! recorded history that unloads (a load-unload cycle), whose stress passes through
//! zero where 1/|σ| would weight the slack end of the cycle 100 × its peak. The fit's
//! misfit (`rel_rmse`) is the RMS of those same scaled residuals. `terms = None` (auto) fits
//! N = 0 … max_terms and takes the fewest terms whose fit is as good as more by AICc
//! (or BIC, or a tolerance on the relative RMSE), among fits whose terms are
//! identifiable and inside the sampled window.

use super::diagnostics;
use super::lm::{self, LeastSquares, LmResult, LmSettings, Termination};
use super::nnls::{dot, nnls, NnlsWork};
use super::problem::{Residual, REL_FLOOR};
use super::{Parameter, SolverReport, Status};
use crate::error::{Error, Result};
use crate::io::relaxation::{RelaxationData, RelaxationSource};
use crate::material::file::HyperelasticPart;
use crate::material::hyperelastic::Mode;
use crate::material::viscoelastic::{
    Formulation, History, KelvinMaxwell, MaxwellArm, Prony, Schedule,
};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A fit that leaves more than half of the data's weighted sum of squares (against
/// zero stress, the series with all moduli 0) explains nothing: its residual RMS is
/// above 1/√2 ≈ 71 % of the data's, so no constant of it can be trusted. A fit of
/// real data leaves a few % (0.1 % of the sum of squares); noise alone never leaves
/// half unless it is as large as the stress.
const EXPLAINS_NOTHING: f64 = 0.5;

/// Most decades of time the τ search spans, counted back from the last sample: a
/// relaxation record covers 3–8 decades (a 1 ms rig to a day); a first time of
/// 1e-300 s would put 300 decades of columns in the NNLS grid and stall the fit.
const MAX_DECADES: i32 = 12;

/// Lag-1 autocorrelation of residuals above which they are systematic rather than
/// noise: white noise gives 0 ± 1/√n (±0.1 for 100 points), a misfit left by the
/// model gives values near 1; 0.5 is halfway.
const SYSTEMATIC: f64 = 0.5;

/// Schema tag of relaxation fit files (the material files' reader knows it).
pub const SCHEMA: &str = crate::material::file::RELAXATION_SCHEMA;

/// How `auto` scores term counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Criterion {
    /// Corrected Akaike information criterion (default).
    #[default]
    Aicc,
    /// Bayesian information criterion (stricter for n > 7).
    Bic,
}

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

/// Estimator settings (checked by [`Settings::check`] before use).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Settings {
    /// Number of Prony terms, or `None` for automatic choice.
    pub terms: Option<usize>,
    /// Largest term count tried by the automatic choice (default 6).
    pub max_terms: usize,
    /// Score of the automatic choice (default AICc).
    pub criterion: Criterion,
    /// With a tolerance, `auto` takes the fewest terms whose relative RMSE is at most
    /// this fraction (e.g. 0.01) instead of using the criterion.
    pub tolerance: Option<f64>,
    /// Residuals; `None` (default): chosen by the loading, relative for a held strain
    /// (the long-time tail counts), absolute for a recorded history that unloads
    /// ([`unloads`]).
    pub residual: Option<Residual>,
    /// Method (default refined).
    pub method: Method,
    /// τ grid density of the NNLS stage, points per decade (default 6, which puts
    /// about three grid points between VHB 4910's two modes half a decade apart; range
    /// 2–50). The NNLS's cost grows with the grid size (the normal equations are
    /// k² per point).
    pub grid_per_decade: usize,
    /// Iteration limit of each LM search (default 200).
    pub max_iterations: usize,
    /// Relative cost tolerance of the LM searches (default 1e-10).
    pub ftol: f64,
    /// Largest number of starts per term count (default 3).
    pub max_starts: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            terms: None,
            max_terms: 6,
            criterion: Criterion::Aicc,
            tolerance: None,
            residual: None,
            method: Method::Refined,
            grid_per_decade: 6,
            max_iterations: 200,
            ftol: 1e-10,
            max_starts: 3,
        }
    }
}

impl Settings {
    /// Reject settings that cannot work.
    pub fn check(&self) -> Result<()> {
        if self.terms.is_some_and(|n| n > 12) || self.max_terms > 12 {
            return Err(
                Error::settings("at most 12 Prony terms are supported").with_hint(
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

/// The test's loading: held strain and how it was applied. A strain or stretch column
/// in the file, when present, gives the history instead.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Loading {
    /// Held engineering strain ε0 (stretch λ0 = 1 + ε0); from the file when `None`.
    pub strain: Option<f64>,
    /// Duration of a linear loading ramp from t = 0 (s); `None`: an ideal step.
    pub ramp_time: Option<f64>,
}

/// A file a fit depends on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileRef {
    /// Path as given.
    pub path: String,
    /// SHA-256 of its bytes (hex).
    pub sha256: String,
}

/// The hyperelastic fit that gives the instantaneous response of a QLV fit.
#[derive(Debug, Clone)]
pub struct QlvInput {
    /// The hyperelastic material of a fit file (its uniaxial stress is σₑ).
    pub fit: HyperelasticPart,
    /// Its file.
    pub file: FileRef,
}

/// One Prony term of a fit, in the units the issue's fit file names.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PronyEntry {
    /// Relaxation time τ (s).
    pub tau_s: f64,
    /// Modulus Eᵢ (Pa).
    #[serde(rename = "modulus_Pa")]
    pub modulus_pa: f64,
    /// Normalised fraction gᵢ = Eᵢ/E0.
    pub g: f64,
    /// Standard error of τ (s).
    pub tau_std_s: Option<f64>,
    /// Standard error of Eᵢ (Pa).
    #[serde(rename = "modulus_std_Pa")]
    pub modulus_std_pa: Option<f64>,
}

/// One Maxwell arm of a fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArmEntry {
    /// Spring kⱼ (Pa).
    #[serde(rename = "k_Pa")]
    pub k_pa: f64,
    /// Dashpot nⱼ = kⱼ·τⱼ (Pa·s).
    #[serde(rename = "n_Pa_s")]
    pub n_pa_s: f64,
}

/// A point of the grid NNLS spectrum.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpectrumPoint {
    /// Grid relaxation time (s).
    pub tau_s: f64,
    /// Non-negative modulus at that τ (Pa).
    #[serde(rename = "modulus_Pa")]
    pub modulus_pa: f64,
}

/// QLV details of a fit with a hyperelastic instantaneous response.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QlvInfo {
    /// Hyperelastic model.
    pub hyperelastic_model: String,
    /// Its small-strain Young's modulus 3μ0 (Pa): the reference of the moduli.
    #[serde(rename = "reference_modulus_Pa")]
    pub reference_modulus_pa: f64,
    /// G(0): the factor by which the hyperelastic stress must be scaled to be the
    /// instantaneous response of these data (1 if the hyperelastic fit is it).
    pub instantaneous_scale: f64,
    /// Hyperelastic stress at the held stretch (at the peak stretch of a history that
    /// unloads) (Pa).
    #[serde(rename = "held_stress_Pa")]
    pub held_stress_pa: f64,
}

/// One row of the term-count comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Number of Prony terms.
    pub terms: usize,
    /// Number of parameters (2N + 1).
    pub k: usize,
    /// RMSE (Pa).
    #[serde(rename = "rmse_Pa")]
    pub rmse_pa: f64,
    /// Relative RMSE (fraction).
    pub rel_rmse: f64,
    /// AICc (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC.
    pub bic: f64,
    /// Score minus the smallest score.
    pub delta: f64,
    /// Relaxation times (s).
    pub tau_s: Vec<f64>,
    /// Whether the automatic choice may take it.
    pub eligible: bool,
    /// Why not, if not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// How the term count was chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// The rule, in words.
    pub rule: String,
    /// Why this count.
    pub reason: String,
    /// Every count tried.
    pub candidates: Vec<Candidate>,
}

/// Inputs and settings of a fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The relaxation file.
    pub files: Vec<RelaxationSource>,
    /// The hyperelastic fit of a QLV fit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hyperelastic_fit: Option<FileRef>,
    /// Loading.
    pub loading: Loading,
    /// Settings used.
    pub settings: serde_json::Value,
}

/// A relaxation fit: what `--json` prints and what the fit file holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelaxationFit {
    /// Schema tag.
    pub schema: String,
    /// dea-fit version that wrote it.
    pub tool_version: String,
    /// Formulation the constants belong to.
    pub formulation: Formulation,
    /// Engineering strain at the end of the record: the held strain ε0 of a relaxation
    /// test (the loading describes a history that unloads).
    pub held_strain: f64,
    /// How the strain was applied (step, ramp, recorded history with its peak).
    pub loading: String,
    /// Prony terms, sorted by τ.
    pub prony: Vec<PronyEntry>,
    /// E∞ (Pa).
    #[serde(rename = "long_term_modulus_Pa")]
    pub long_term_modulus_pa: f64,
    /// E0 = E∞ + ΣEᵢ (Pa).
    #[serde(rename = "instantaneous_modulus_Pa")]
    pub instantaneous_modulus_pa: f64,
    /// g∞ = E∞/E0.
    pub g_inf: f64,
    /// The seed's Maxwell arms kⱼ = Eⱼ, nⱼ = Eⱼτⱼ (equilibrium spring E∞; the
    /// Kelvin-Voigt dashpot Nv is not identifiable from a relaxation curve).
    pub kelvin_maxwell: Vec<ArmEntry>,
    /// QLV details (QLV fits only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub qlv: Option<QlvInfo>,
    /// Parameters in SI (E_inf, E1…, tau1…).
    pub parameters: Vec<Parameter>,
    /// RMSE (Pa, unweighted).
    #[serde(rename = "rmse_Pa")]
    pub rmse_pa: f64,
    /// Relative RMSE (fraction): the RMS of the fit's own scaled residuals, i.e. of
    /// (model − data)/max(|data|, 1 % of the peak) for relative residuals and of
    /// (model − data)/peak |data| for absolute ones.
    pub rel_rmse: f64,
    /// R².
    pub r2: f64,
    /// AICc of the fitted objective (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC of the fitted objective.
    pub bic: f64,
    /// Residual definition of the objective.
    pub residual: Residual,
    /// Number of points.
    pub points: usize,
    /// Sampled window [first positive time, last time] (s).
    pub time_window_s: [f64; 2],
    /// The grid NNLS spectrum (stage 1; of an even 400-point subsample of a longer
    /// curve).
    pub spectrum: Vec<SpectrumPoint>,
    /// Parameter correlation matrix.
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Condition number of the column-normalised Jacobian.
    pub condition_number: Option<f64>,
    /// Overall status.
    pub status: Status,
    /// Everything the user should know.
    pub warnings: Vec<String>,
    /// Solver report.
    pub solver: SolverReport,
    /// How the term count was chosen (auto only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selection: Option<Selection>,
    /// Inputs and settings.
    pub provenance: Provenance,
}

impl RelaxationFit {
    /// Parameter values in the order of [`Self::parameters`] (E∞, E₁…E_N, τ₁…τ_N).
    pub fn values(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.value).collect()
    }

    /// The fitted Prony series (Pa).
    pub fn prony_series(&self) -> Result<Prony> {
        let terms: Vec<(f64, f64)> = self.prony.iter().map(|p| (p.tau_s, p.modulus_pa)).collect();
        Prony::new(self.long_term_modulus_pa, &terms)
    }

    /// The seed's Kelvin-Maxwell model of the fit (Nv = 0).
    pub fn kelvin_maxwell_model(&self) -> KelvinMaxwell {
        KelvinMaxwell {
            k_inf: self.long_term_modulus_pa,
            arms: self
                .kelvin_maxwell
                .iter()
                .map(|a| MaxwellArm {
                    k: a.k_pa,
                    n: a.n_pa_s,
                })
                .collect(),
            n_v: 0.0,
        }
    }
}

/// The fitting problem: p = [e∞, e₁…e_N, ln τ₁…ln τ_N] in scaled units (stress =
/// S·(e∞·x + Σ eᵢ·hᵢ)), residuals rₖ = wₖ·(model − yₖ).
#[derive(Debug, Clone)]
struct Problem {
    sched: Schedule,
    /// The loading and the times `sched` merges (kept to build subsamples).
    history: History,
    times: Vec<f64>,
    y: Vec<f64>,
    w: Vec<f64>,
    scale: f64,
    /// wₖ·S: the factor of every column of the design (and of the Jacobian).
    ws: Vec<f64>,
    n_terms: usize,
    /// The terms' kernels and their τ-derivatives of the last evaluation, one block
    /// of [`Problem::len`] values a term ([`Schedule::kernels`]), and their τᵢ.
    h: Vec<f64>,
    dh: Vec<f64>,
    taus: Vec<f64>,
    /// The τᵢ whose kernels `h` holds, and whether `dh` holds their derivatives: an
    /// evaluation at the same τ (the polish's start at the projection's optimum,
    /// the assessment at the polish's) takes them instead of a pass over the data.
    kernel_taus: Vec<f64>,
    kernel_derivatives: bool,
    evaluations: usize,
}

impl Problem {
    /// The problem of the points (`times`, `y`) with weights `w` and scale S, no
    /// terms yet.
    fn new(
        sched: Schedule,
        history: History,
        times: Vec<f64>,
        y: Vec<f64>,
        w: Vec<f64>,
        scale: f64,
    ) -> Problem {
        let ws = w.iter().map(|w| w * scale).collect();
        Problem {
            sched,
            history,
            times,
            y,
            w,
            scale,
            ws,
            n_terms: 0,
            h: Vec::new(),
            dh: Vec::new(),
            taus: Vec::new(),
            kernel_taus: Vec::new(),
            kernel_derivatives: false,
            evaluations: 0,
        }
    }

    fn len(&self) -> usize {
        self.y.len()
    }

    /// The same objective on `count` of the points, spread evenly over their order
    /// (both ends kept; a log-spaced curve stays log-spaced), with their weights and
    /// the same scale; `None` when there are no more points than that.
    fn subsample(&self, count: usize) -> Option<Problem> {
        let (m, count) = (self.len(), count.max(2));
        if m <= count {
            return None;
        }
        let idx: Vec<usize> = (0..count)
            .map(|q| (q * (m - 1) + (count - 1) / 2) / (count - 1))
            .collect();
        let times: Vec<f64> = idx.iter().map(|&i| self.times[i]).collect();
        let sched = Schedule::new(&self.history, &times).ok()?;
        let mut sub = Problem::new(
            sched,
            self.history.clone(),
            times,
            idx.iter().map(|&i| self.y[i]).collect(),
            idx.iter().map(|&i| self.w[i]).collect(),
            self.scale,
        );
        sub.n_terms = self.n_terms;
        Some(sub)
    }

    /// Model stress at every point into `m`, from the kernels of the last evaluation
    /// (which must have been at `p`).
    fn model(&self, p: &[f64], m: &mut [f64]) {
        self.combine(p, m);
        for mk in m.iter_mut() {
            *mk *= self.scale;
        }
    }

    /// e∞·x + Σ eᵢ·hᵢ at every point into `out` (the model stress over S), from the
    /// kernels of the last evaluation.
    fn combine(&self, p: &[f64], out: &mut [f64]) {
        let m = self.len();
        for (o, x) in out.iter_mut().zip(self.sched.input()) {
            *o = p[0] * x;
        }
        for (e, h) in p[1..=self.n_terms].iter().zip(self.h.chunks_exact(m)) {
            for (o, h) in out.iter_mut().zip(h) {
                *o += e * h;
            }
        }
    }

    /// Every term's kernel at the τᵢ = e^(ln τᵢ) of `p` into `h` (and their
    /// τ-derivatives into `dh` when `derivatives`), in one pass over the data.
    fn kernels_at(&mut self, p: &[f64], derivatives: bool) {
        let n = self.n_terms;
        self.kernels_at_log_taus(&p[1 + n..1 + 2 * n], derivatives);
    }

    /// [`Problem::kernels_at`] of the terms' ln τᵢ alone; nothing to compute when
    /// `h` (and `dh` if asked for) hold the kernels of these τ already, bit for bit
    /// the values a pass would give (each τ's kernel depends on that τ alone).
    fn kernels_at_log_taus(&mut self, ln_taus: &[f64], derivatives: bool) {
        let m = self.len();
        let n = ln_taus.len();
        self.taus.clear();
        self.taus.extend(ln_taus.iter().map(|lt| lt.exp()));
        if self.kernel_taus == self.taus && (self.kernel_derivatives || !derivatives) {
            return;
        }
        self.h.resize(n * m, 0.0);
        if derivatives {
            self.dh.resize(n * m, 0.0);
        }
        self.sched.kernels(
            &self.taus,
            &mut self.h,
            derivatives.then_some(&mut self.dh[..]),
        );
        self.kernel_taus.clone_from(&self.taus);
        self.kernel_derivatives = derivatives;
    }

    /// The weighted data w·y: the right-hand side of the moduli's least squares.
    fn targets(&self) -> DVector<f64> {
        DVector::from_iterator(self.len(), self.y.iter().zip(&self.w).map(|(y, w)| y * w))
    }

    /// The design's first column, w·S·x (the E∞ term), into `out`.
    fn input_column(&self, out: &mut [f64]) {
        for ((o, x), ws) in out.iter_mut().zip(self.sched.input()).zip(&self.ws) {
            *o = x * ws;
        }
    }

    /// The design's columns of the terms at the τᵢ of the last evaluation,
    /// [`Problem::kernel_columns`] from its kernels `h` (and `dh`, which must hold
    /// their derivatives when `dout` is given): the same products, so the same bits.
    fn design_columns(&self, out: &mut [f64], dout: Option<&mut [f64]>) {
        let m = self.len();
        for (i, a) in out.chunks_exact_mut(m).enumerate() {
            for ((a, ws), h) in a.iter_mut().zip(&self.ws).zip(&self.h[i * m..]) {
                *a = h * ws;
            }
        }
        if let Some(d) = dout {
            for ((i, a), tau) in d.chunks_exact_mut(m).enumerate().zip(&self.taus) {
                for ((a, ws), dh) in a.iter_mut().zip(&self.ws).zip(&self.dh[i * m..]) {
                    *a = dh * (ws * tau);
                }
            }
        }
    }

    /// The design's columns of the terms at `taus`, w·S·h(τᵢ), end to end into `out`
    /// (one pass over the data, [`Schedule::kernels`]), and their derivatives
    /// w·S·τᵢ·∂h/∂τ(τᵢ) = ∂aᵢ/∂ln τᵢ into `dout` if given.
    fn kernel_columns(&self, taus: &[f64], out: &mut [f64], mut dout: Option<&mut [f64]>) {
        let m = self.len();
        self.sched.kernels(taus, out, dout.as_deref_mut());
        for (i, &tau) in taus.iter().enumerate() {
            for (a, ws) in out[i * m..(i + 1) * m].iter_mut().zip(&self.ws) {
                *a *= ws;
            }
            if let Some(d) = dout.as_deref_mut() {
                for (a, ws) in d[i * m..(i + 1) * m].iter_mut().zip(&self.ws) {
                    *a *= ws * tau;
                }
            }
        }
    }
}

impl LeastSquares for Problem {
    fn dims(&self) -> (usize, usize) {
        (self.len(), 1 + 2 * self.n_terms)
    }
    /// Residuals wₖ·(S·(e∞·xₖ + Σ eᵢ·hᵢₖ) − yₖ); the Jacobian's columns w·S·x,
    /// w·S·hᵢ and w·S·eᵢ·τᵢ·∂hᵢ/∂τ (∂/∂ln τᵢ).
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        self.evaluations += 1;
        let (n, m, s) = (self.n_terms, self.len(), self.scale);
        self.kernels_at(p, jac.is_some());
        let r = r.as_mut_slice();
        self.combine(p, r);
        for ((rk, w), y) in r.iter_mut().zip(&self.w).zip(&self.y) {
            *rk = w * (s * *rk - y);
        }
        let finite = |v: &[f64]| v.iter().all(|v| v.is_finite());
        let Some(jac) = jac else {
            return finite(r);
        };
        let (j0, terms) = jac.as_mut_slice().split_at_mut(m);
        self.input_column(j0);
        let (je, jt) = terms.split_at_mut(n * m);
        for i in 0..n {
            let (e, tau) = (p[1 + i], self.taus[i]);
            let (h, dh) = (&self.h[i * m..(i + 1) * m], &self.dh[i * m..(i + 1) * m]);
            for ((j, ws), h) in je[i * m..(i + 1) * m].iter_mut().zip(&self.ws).zip(h) {
                *j = ws * h;
            }
            for ((j, ws), dh) in jt[i * m..(i + 1) * m].iter_mut().zip(&self.ws).zip(dh) {
                *j = ws * e * tau * dh;
            }
        }
        finite(r) && finite(jac.as_slice())
    }
    /// A trial's Jacobian costs the kernels' derivatives and the columns over the
    /// residuals alone, where evaluating again after an accepted trial costs the
    /// kernels twice.
    fn jacobian_with_trial(&self) -> bool {
        true
    }
}

/// Variable projection of a [`Problem`] (Golub & Pereyra 1973, with Kaufman's 1975
/// Jacobian): the search runs over θ = ln τ only. At each θ the moduli c = (e∞, eᵢ)
/// are the non-negative least-squares solution of A(θ)·c ≈ b ([`NnlsWork`], started
/// from the last solution's positive set), with A = [w·S·x, w·S·h(τ₁), …] and b = w·y,
/// so r(θ) = A·c − b are the residuals of [`Problem`] at the best moduli for these τ.
/// Kaufman's Jacobian is ∂r/∂θᵢ ≈ Jᵢ = cᵢ·P⊥·∂aᵢ/∂θᵢ, with P⊥ the projector off the
/// columns whose modulus is positive (a term at zero modulus moves nothing); its
/// gradient Jᵀr is the exact gradient of ½‖r(θ)‖², since r ⟂ those columns.
/// The amplitudes no longer lie in the search, so neither does the long valley
/// between a modulus and its τ that a joint search walks along.
///
/// The search only uses the Jacobian's normal equations, and those follow from the
/// Gram products of the columns ([`Projected::gram`], one pass over the data):
/// (JᵀJ)ᵢⱼ = cᵢ·cⱼ·(dᵢ·dⱼ − (A_Pᵀdᵢ)ᵀ(A_PᵀA_P)⁻¹(A_Pᵀdⱼ)) with dᵢ = ∂aᵢ/∂θᵢ and A_P
/// the positive columns, and (Jᵀr)ᵢ = cᵢ·dᵢ·r ([`LeastSquares::forms_normal_equations`]),
/// so no m × N Jacobian is formed or projected.
struct Projected<'p> {
    prob: &'p mut Problem,
    /// The columns A(θ) of the last evaluation (the first, w·S·x, fixed).
    a: DMatrix<f64>,
    /// dᵢ = ∂aᵢ/∂ln τᵢ = w·S·τᵢ·∂h/∂τ(τᵢ), filled when a Jacobian is asked for.
    da: DMatrix<f64>,
    b: DVector<f64>,
    /// The Gram products of the columns [A | b | ∂A] of the last evaluation (the ∂A
    /// rows and columns only when it was asked for a Jacobian).
    gram: DMatrix<f64>,
    /// The moduli's normal equations AᵀA and Aᵀb of the last evaluation (copied from
    /// `gram` for [`NnlsWork::solve`]).
    ata: DMatrix<f64>,
    atb: DVector<f64>,
    /// The moduli of the last evaluation.
    c: DVector<f64>,
    /// Which of them are positive: the next solve's start.
    positive: Vec<bool>,
    /// The moduli's NNLS work space (no allocation a solve).
    work: NnlsWork,
    /// x·x and b·x of the fixed first column x = w·S·x and b = w·y, summed over
    /// the blocks of [`Projected::gram`] as it sums them: the same at every θ.
    fixed: [f64; 2],
    /// θ of the last evaluation, whose Gram products of [A | b] `gram` holds.
    theta: Vec<f64>,
    /// θ, JᵀJ and Jᵀr of the last evaluation asked for a Jacobian.
    normal: Option<(Vec<f64>, DMatrix<f64>, DVector<f64>)>,
}

/// Rows of a block of [`Projected::gram`]: the columns of a block (at most 2·12 + 2
/// of 4 kB) stay in the level-2 cache while all their products are taken; a curve
/// of at most this many points (every shipped one, and the starts' subsample) takes
/// each product in one piece, as [`nnls`] does.
const GRAM_ROWS: usize = 512;

/// a·b as [`Projected::gram`] sums it: [`dot`] of each block of [`GRAM_ROWS`]
/// rows added in order to 0.
fn blocked_dot(a: &[f64], b: &[f64]) -> f64 {
    a.chunks(GRAM_ROWS)
        .zip(b.chunks(GRAM_ROWS))
        .fold(0.0, |g, (a, b)| g + dot(a, b))
}

impl<'p> Projected<'p> {
    fn new(prob: &'p mut Problem) -> Projected<'p> {
        let (m, n) = (prob.len(), prob.n_terms);
        let mut a = DMatrix::zeros(m, 1 + n);
        prob.input_column(a.column_mut(0).as_mut_slice());
        let b = prob.targets();
        let x = &a.as_slice()[..m];
        let fixed = [blocked_dot(x, x), blocked_dot(b.as_slice(), x)];
        Projected {
            prob,
            a,
            da: DMatrix::zeros(m, n),
            b,
            gram: DMatrix::zeros(2 + 2 * n, 2 + 2 * n),
            ata: DMatrix::zeros(1 + n, 1 + n),
            atb: DVector::zeros(1 + n),
            c: DVector::zeros(1 + n),
            positive: vec![false; 1 + n],
            work: NnlsWork::new(1 + n),
            fixed,
            theta: Vec::with_capacity(n),
            normal: None,
        }
    }

    /// The moduli at θ into `c` (a failed solve leaves them as they were), as
    /// [`LeastSquares::eval`] without a Jacobian would set them, counted as an
    /// evaluation: from the Gram products of the last evaluation when it was at θ
    /// (the same products, so the same bits), else from the kernels at θ with their
    /// derivatives, which the joint problem's first evaluation at the same τ then
    /// takes ([`Problem::kernels_at_log_taus`]).
    fn moduli_at(&mut self, theta: &[f64]) {
        self.prob.evaluations += 1;
        if self.theta != theta {
            let m = self.prob.len();
            self.prob.kernels_at_log_taus(theta, true);
            self.prob
                .design_columns(&mut self.a.as_mut_slice()[m..], None);
            self.gram(false);
            self.theta.clear();
            self.theta.extend_from_slice(theta);
        }
        self.solve_moduli();
    }

    /// The moduli's NNLS on the Gram products of the last evaluation, started from
    /// the positive set of the one before, into `c` and `positive`; false (both
    /// unchanged) when it fails.
    fn solve_moduli(&mut self) -> bool {
        let n = self.a.ncols() - 1;
        for j in 0..=n {
            for i in 0..=n {
                self.ata[(i, j)] = self.gram[(i, j)];
            }
            self.atb[j] = self.gram[(j, 1 + n)];
        }
        let solved = self.work.solve(
            self.ata.as_slice(),
            self.atb.as_slice(),
            Some(&self.positive),
        );
        if solved.is_err() {
            return false;
        }
        self.c.copy_from_slice(self.work.x());
        for (f, &v) in self.positive.iter_mut().zip(self.c.iter()) {
            *f = v > 0.0;
        }
        true
    }

    /// The parameters of [`Problem`] at θ: [e∞, eᵢ…, ln τᵢ…], the moduli those of the
    /// last evaluation (which must have been at θ).
    fn joint(&self, theta: &[f64]) -> Vec<f64> {
        self.c.iter().chain(theta).copied().collect()
    }

    /// The Gram products kᵢ·kⱼ of the columns k = [A | b | ∂A] (∂A when
    /// `derivatives`; b·b and b·∂A, which nothing uses, left at 0) into the leading
    /// block of `gram`, in one pass over the rows:
    /// blocks of [`GRAM_ROWS`] rows, every product of a block while its columns are
    /// in the cache (column by column, each product of a 10⁵-point curve would read
    /// two 0.8 MB columns from memory). The two products of the fixed columns alone
    /// are `fixed`'s.
    fn gram(&mut self, derivatives: bool) {
        let (m, n) = (self.a.nrows(), self.a.ncols() - 1);
        let k = n + 2 + if derivatives { n } else { 0 };
        let (a, b, da) = (self.a.as_slice(), self.b.as_slice(), self.da.as_slice());
        let col = |i: usize| match i {
            _ if i <= n => &a[i * m..(i + 1) * m],
            _ if i == n + 1 => b,
            _ => &da[(i - n - 2) * m..(i - n - 1) * m],
        };
        let g = self.gram.as_mut_slice();
        let size = 2 + 2 * n;
        g.fill(0.0);
        for lo in (0..m).step_by(GRAM_ROWS) {
            let hi = (lo + GRAM_ROWS).min(m);
            for j in 0..k {
                let cj = &col(j)[lo..hi];
                // b·b and b·∂A are not used (Jᵀr is taken from the residuals);
                // x·x and b·x are `fixed`.
                let fixed = |i: usize| i == 0 && (j == 0 || j == n + 1);
                for i in (0..=j).filter(|&i| i != n + 1 && !fixed(i)) {
                    g[j * size + i] += dot(&col(i)[lo..hi], cj);
                }
            }
        }
        g[0] = self.fixed[0];
        g[(n + 1) * size] = self.fixed[1];
        for j in 0..k {
            for i in 0..j {
                g[i * size + j] = g[j * size + i];
            }
        }
    }

    /// Kaufman's JᵀJ and Jᵀr (type notes) from the Gram products, moduli and
    /// residuals of the last evaluation; None where the positive columns' Gram
    /// matrix is singular.
    fn normal_from_gram(&self, r: &DVector<f64>) -> Option<(DMatrix<f64>, DVector<f64>)> {
        let (m, n) = (self.a.nrows(), self.a.ncols() - 1);
        let gram = &self.gram;
        let pos: Vec<usize> = (0..=n).filter(|&j| self.c[j] > 0.0).collect();
        // (A_PᵀA_P)⁻¹ through the Cholesky factor of the unit-diagonal scaling
        // (as the NNLS solve factors it), u = L⁻¹·A_Pᵀ∂A scaled alike.
        let s: Vec<f64> = pos.iter().map(|&j| 1.0 / gram[(j, j)].sqrt()).collect();
        let gp = DMatrix::from_fn(pos.len(), pos.len(), |p, q| {
            gram[(pos[p], pos[q])] * s[p] * s[q]
        });
        let mut u = DMatrix::from_fn(pos.len(), n, |p, i| gram[(pos[p], n + 2 + i)] * s[p]);
        if !pos.is_empty() && !gp.cholesky()?.l_dirty().solve_lower_triangular_mut(&mut u) {
            return None;
        }
        let jtj = DMatrix::from_fn(n, n, |i, j| {
            let dd = gram[(n + 2 + i, n + 2 + j)];
            self.c[1 + i] * self.c[1 + j] * (dd - u.column(i).dot(&u.column(j)))
        });
        let jtr = DVector::from_fn(n, |i, _| {
            self.c[1 + i] * dot(&self.da.as_slice()[i * m..(i + 1) * m], r.as_slice())
        });
        Some((jtj, jtr))
    }
}

impl LeastSquares for Projected<'_> {
    fn dims(&self) -> (usize, usize) {
        (self.prob.len(), self.prob.n_terms)
    }
    /// Asked for a Jacobian (any matrix: see [`LeastSquares::forms_normal_equations`]),
    /// it forms the normal equations instead.
    fn eval(
        &mut self,
        theta: &[f64],
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> bool {
        let p = &mut *self.prob;
        p.evaluations += 1;
        let m = p.len();
        let derivatives = jac.is_some();
        p.kernels_at_log_taus(theta, derivatives);
        p.design_columns(
            &mut self.a.as_mut_slice()[m..],
            derivatives.then_some(self.da.as_mut_slice()),
        );
        self.gram(derivatives);
        self.theta.clear();
        self.theta.extend_from_slice(theta);
        if !self.solve_moduli() {
            return false;
        }
        r.as_mut_slice().copy_from_slice(self.b.as_slice());
        r.gemv(1.0, &self.a, &self.c, -1.0);
        if !r.as_slice().iter().all(|v| v.is_finite()) {
            return false;
        }
        if !derivatives {
            return true;
        }
        match self.normal_from_gram(r) {
            Some((jtj, jtr)) if jtj.iter().chain(jtr.iter()).all(|v| v.is_finite()) => {
                self.normal = Some((theta.to_vec(), jtj, jtr));
                true
            }
            _ => false,
        }
    }
    fn jacobian_with_trial(&self) -> bool {
        true
    }
    fn forms_normal_equations(&self) -> bool {
        true
    }
    fn normal_equations(&self, p: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
        match &self.normal {
            Some((at, jtj, jtr)) if at.as_slice() == p => Some((jtj.clone(), jtr.clone())),
            _ => None,
        }
    }
}

/// A fit at one term count.
#[derive(Debug, Clone)]
struct TermFit {
    n_terms: usize,
    /// Scaled parameters, terms sorted by τ.
    p: Vec<f64>,
    iterations: usize,
    evaluations: usize,
    termination: Termination,
    starts: usize,
    at_best: usize,
    /// The count's problem, holding the kernels of its last evaluation (the
    /// assessment's evaluation at `p` takes them when they are `p`'s).
    problem: Problem,
}

/// A peak of the grid spectrum: total scaled modulus and its weighted mean ln τ.
#[derive(Debug, Clone, Copy)]
struct Peak {
    e: f64,
    ln_tau: f64,
}

fn merge(a: Peak, b: Peak) -> Peak {
    let e = a.e + b.e;
    Peak {
        e,
        ln_tau: if e > 0.0 {
            (a.e * a.ln_tau + b.e * b.ln_tau) / e
        } else {
            0.5 * (a.ln_tau + b.ln_tau)
        },
    }
}

/// Bring a sorted list of peaks to exactly `n`: merge the closest adjacent pair in ln τ
/// (`closest`) or fold the smallest peak into its nearer neighbour; split the largest
/// into two a factor 3 apart while too few.
fn reshape(mut peaks: Vec<Peak>, n: usize, closest: bool, window: (f64, f64)) -> Vec<Peak> {
    if n == 0 {
        return Vec::new();
    }
    if peaks.is_empty() && n > 0 {
        peaks.push(Peak {
            e: 1.0,
            ln_tau: 0.5 * (window.0 + window.1),
        });
    }
    while peaks.len() > n {
        let i = if closest {
            (0..peaks.len() - 1)
                .min_by(|&a, &b| {
                    (peaks[a + 1].ln_tau - peaks[a].ln_tau)
                        .total_cmp(&(peaks[b + 1].ln_tau - peaks[b].ln_tau))
                })
                .expect("two peaks")
        } else {
            let j = (0..peaks.len())
                .min_by(|&a, &b| peaks[a].e.total_cmp(&peaks[b].e))
                .expect("a peak");
            if j == 0 {
                0
            } else if j == peaks.len() - 1
                || peaks[j].ln_tau - peaks[j - 1].ln_tau < peaks[j + 1].ln_tau - peaks[j].ln_tau
            {
                j - 1
            } else {
                j
            }
        };
        let m = merge(peaks[i], peaks[i + 1]);
        peaks[i] = m;
        peaks.remove(i + 1);
    }
    while peaks.len() < n {
        let j = (0..peaks.len())
            .max_by(|&a, &b| peaks[a].e.total_cmp(&peaks[b].e))
            .expect("a peak");
        let p = peaks[j];
        let d = 0.5 * 3f64.ln();
        peaks[j] = Peak {
            e: 0.5 * p.e,
            ln_tau: p.ln_tau - d,
        };
        peaks.insert(
            j + 1,
            Peak {
                e: 0.5 * p.e,
                ln_tau: p.ln_tau + d,
            },
        );
    }
    peaks
}

/// Everything the estimator derives from data and loading before fitting.
struct Prepared {
    prob: Problem,
    /// [first positive time, last time] (s).
    window: (f64, f64),
    /// ln τ search bounds.
    bounds: (f64, f64),
    /// Moduli unit: Pa per unit of the scaled coefficient·S (1 for the parallel
    /// reading, 3μ0 for QLV).
    unit: f64,
    formulation: Formulation,
    held_strain: f64,
    loading: String,
    /// The residuals used (the settings' or the loading's choice).
    residual: Residual,
    qlv: Option<QlvInfo>,
    notes: Vec<String>,
}

/// Whether a recorded strain history unloads: after its peak |strain| it falls below
/// 90 % of it. A relaxation test holds its strain (within the machine's control
/// error of a few %); a load-unload cycle, a recovery or a second cycle returns
/// towards zero, and its stress with it.
pub fn unloads(strain: &[f64]) -> bool {
    let peak = strain.iter().map(|e| e.abs()).fold(0.0, f64::max);
    // From the first time the peak is reached.
    let first = strain.iter().position(|e| e.abs() == peak).unwrap_or(0);
    strain[first..].iter().any(|e| e.abs() < 0.9 * peak)
}

/// The residual weights wₖ: 1/max(|yₖ|, floor) (relative) or 1/max|y| (absolute).
fn weights(y: &[f64], residual: Residual) -> Vec<f64> {
    let ymax = y.iter().map(|v| v.abs()).fold(0.0, f64::max);
    y.iter()
        .map(|v| match residual {
            Residual::Rel => 1.0 / v.abs().max(REL_FLOOR * ymax),
            Residual::Abs => 1.0 / ymax,
        })
        .collect()
}

fn prepare(
    data: &RelaxationData,
    loading: &Loading,
    qlv: Option<&QlvInput>,
    settings: &Settings,
) -> Result<Prepared> {
    data.check()?;
    let n = data.time.len();
    if n < 3 {
        return Err(Error::settings(format!(
            "{n} points cannot determine even a long-term modulus with an uncertainty"
        ))
        .with_hint("a relaxation curve needs at least 3 points, and 2N + 3 for N terms"));
    }
    let mut notes = Vec::new();
    // The strain history: recorded, ramp, or step; `peak` is the largest |strain|.
    let (strain_hist, held, peak, desc, unloading) = match (&data.strain, loading.ramp_time) {
        (Some(_), Some(_)) => {
            return Err(Error::settings(
                "the file records the strain history; --ramp-time would contradict it",
            )
            .with_hint(
                "drop --ramp-time (the recorded strain is used), or drop the strain column",
            ))
        }
        (Some(eps), None) => {
            let held = *eps.last().expect("non-empty");
            let ip = (0..n)
                .max_by(|&i, &j| eps[i].abs().total_cmp(&eps[j].abs()))
                .expect("non-empty");
            let peak = eps[ip];
            let unloading = unloads(eps);
            if let Some(s) = loading.strain {
                let (what, v) = if unloading {
                    ("peaks", peak)
                } else {
                    ("ends", held)
                };
                if (s - v).abs() > 0.01 * v.abs().max(1e-12) {
                    return Err(Error::settings(format!(
                        "the held strain is given as {s} but the file's strain column {what} at {v:.6}"
                    ))
                    .with_hint("drop --strain/--stretch (the recorded strain is used) or correct it"));
                }
            }
            if eps[0] != 0.0 && data.time[0] > 0.0 {
                notes.push(format!(
                    "the recorded strain is already {} at the first sample (t = {}): the loading before it is taken as a step at that time; start the file at t = 0 to fit the true history",
                    eps[0],
                    fmt_s(data.time[0])
                ));
            }
            let knots: Vec<(f64, f64)> =
                data.time.iter().copied().zip(eps.iter().copied()).collect();
            let desc = if unloading {
                format!(
                    "recorded history (piecewise linear between samples), peak stretch {:.4} at t = {}, unloaded to stretch {:.4}",
                    1.0 + peak,
                    fmt_s(data.time[ip]),
                    1.0 + held
                )
            } else {
                format!(
                    "recorded history (piecewise linear between samples), held at strain {held:.6} (stretch {:.4})",
                    1.0 + held
                )
            };
            (History::from_knots(knots)?, held, peak, desc, unloading)
        }
        (None, ramp) => {
            let Some(s) = loading.strain else {
                return Err(Error::settings("the held strain is needed").with_hint(
                    "pass --strain 0.5 or --stretch 1.5, or add a strain column to the file",
                ));
            };
            match ramp {
                Some(tr) => {
                    if !(tr > 0.0 && tr.is_finite()) {
                        return Err(Error::settings(format!(
                            "--ramp-time must be > 0, found {tr}"
                        )));
                    }
                    if tr >= data.time[n - 1] {
                        return Err(Error::settings(format!(
                            "the ramp ({tr} s) does not end before the last point ({} s): there is no hold to fit",
                            data.time[n - 1]
                        )));
                    }
                    (
                        History::ramp(s, tr),
                        s,
                        s,
                        format!("linear ramp to strain {s} over {tr} s from t = 0, then held"),
                        false,
                    )
                }
                None => (
                    History::step(s),
                    s,
                    s,
                    format!("ideal step to strain {s} at t = 0"),
                    false,
                ),
            }
        }
    };
    if !(peak.is_finite() && peak != 0.0 && peak > -1.0) {
        return Err(Error::settings(format!(
            "the held (or peak) strain must be non-zero and > −1, found {peak}"
        )));
    }
    let residual = match settings.residual {
        Some(r) => {
            if r == Residual::Rel && unloading {
                notes.push(
                    "relative residuals on a history that unloads: its stress passes through zero, where 1/|σ| (floored at 1 % of the peak) weights the slack end of the cycle 100 × its peak; drop --residual (absolute residuals are the automatic choice here)".into(),
                );
            }
            r
        }
        None if unloading => Residual::Abs,
        None => Residual::Rel,
    };
    // Input of the hereditary integral.
    let (history, formulation, unit, qlv_info) = match qlv {
        None => (strain_hist, Formulation::Parallel, 1.0, None),
        Some(q) => {
            let model = q.fit.evaluator()?;
            let p = &q.fit.params;
            let se = |e: f64| model.nominal_stress(p, Mode::Uniaxial, 1.0 + e);
            if let Some(w) = q.fit.range_warning(Mode::Uniaxial, 1.0 + peak) {
                notes.push(format!("hyperelastic fit: {w}"));
            }
            // A ramp in strain is not a ramp in σₑ: resolve it in 64 linear pieces.
            let history = match loading.ramp_time.filter(|_| data.strain.is_none()) {
                Some(tr) => History::from_knots(
                    (0..=64)
                        .map(|i| (tr * i as f64 / 64.0, se(held * i as f64 / 64.0)))
                        .collect(),
                )?,
                None => strain_hist.map(se),
            };
            let e_ref = 3.0 * model.initial_shear_modulus(p);
            let held_stress = se(peak);
            if !(held_stress.is_finite() && held_stress != 0.0 && e_ref > 0.0) {
                return Err(Error::settings(format!(
                    "the hyperelastic fit gives stress {held_stress} Pa at stretch {}: no QLV reference",
                    1.0 + peak
                )));
            }
            (
                history,
                Formulation::Qlv,
                e_ref,
                Some(QlvInfo {
                    hyperelastic_model: q.fit.spec.name.clone(),
                    reference_modulus_pa: e_ref,
                    instantaneous_scale: f64::NAN,
                    held_stress_pa: held_stress,
                }),
            )
        }
    };
    let sched = Schedule::new(&history, &data.time)?;
    let y = data.stress.clone();
    let ymax = y.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let xmax = sched.input().iter().map(|v| v.abs()).fold(0.0, f64::max);
    if xmax.is_nan() || xmax <= 0.0 {
        return Err(Error::settings(
            "the loading is zero at every data point: nothing relaxes",
        ));
    }
    let w = weights(&y, residual);
    let t_pos = data
        .time
        .iter()
        .copied()
        .find(|&t| t > 0.0)
        .expect("times increase from ≥ 0 and n ≥ 3");
    let t_end = data.time[n - 1];
    let window = (t_pos.max(t_end * 10f64.powi(-MAX_DECADES)), t_end);
    if window.0 > t_pos {
        notes.push(format!(
            "the data span more than {MAX_DECADES} decades of time (first positive time {} after a last of {}): relaxation times are searched over the last {MAX_DECADES} decades only",
            fmt_s(t_pos),
            fmt_s(t_end)
        ));
    }
    let bounds = ((window.0 / 10.0).ln(), (window.1 * 10.0).ln());
    Ok(Prepared {
        prob: Problem::new(sched, history, data.time.clone(), y, w, ymax / xmax),
        window,
        bounds,
        unit,
        formulation,
        held_strain: held,
        loading: desc,
        residual,
        qlv: qlv_info,
        notes,
    })
}

/// Stage 1 on the points the starts are searched on ([`START_POINTS`]): the grid
/// spectrum only places the starts of the term counts, and on a longer curve those
/// are searched on its even subsample ([`Problem::subsample`]), so the grid NNLS
/// runs there too instead of on every point (at 10⁵ points that was 37 kernels of
/// 10⁵ points and 703 column products for a spectrum no finer than the subsample's).
/// A curve of at most [`START_POINTS`] points (every shipped one) uses all of it.
fn grid_stage(prep: &mut Prepared, per_decade: usize) -> Result<(Vec<f64>, Vec<f64>, usize)> {
    match prep.prob.subsample(START_POINTS) {
        Some(mut sub) => grid_nnls(&mut sub, prep.window, per_decade),
        None => grid_nnls(&mut prep.prob, prep.window, per_decade),
    }
}

/// NNLS over the τ grid. Returns (grid τ, scaled coefficients [e∞, e_grid…],
/// active-set iterations).
fn grid_nnls(
    prob: &mut Problem,
    window: (f64, f64),
    per_decade: usize,
) -> Result<(Vec<f64>, Vec<f64>, usize)> {
    let (a, b) = ((window.0 / 3.0).log10(), (window.1 * 3.0).log10());
    let count = ((b - a) * per_decade as f64).ceil() as usize + 1;
    let taus: Vec<f64> = (0..count)
        .map(|i| 10f64.powf(a + (b - a) * i as f64 / (count - 1) as f64))
        .collect();
    let (c, it) = nnls_at(prob, &taus)?;
    Ok((taus, c, it))
}

/// Non-negative least squares for E∞ and moduli at fixed τ (scaled units), by
/// Lawson–Hanson ([`nnls`]). Returns the coefficients and the active-set iterations.
fn nnls_at(prob: &mut Problem, taus: &[f64]) -> Result<(Vec<f64>, usize)> {
    let n = prob.len();
    let mut a = DMatrix::zeros(n, taus.len() + 1);
    let (input, terms) = a.as_mut_slice().split_at_mut(n);
    prob.input_column(input);
    prob.kernel_columns(taus, terms, None);
    let sol = nnls(&a, &prob.targets(), None).map_err(|e| {
        Error::settings(format!("the non-negative least-squares stage failed: {e}"))
    })?;
    prob.evaluations += 1;
    Ok((sol.x.iter().copied().collect(), sol.iterations))
}

/// Peaks of the grid spectrum: runs of consecutive non-zero grid moduli.
fn peaks(taus: &[f64], c: &[f64]) -> Vec<Peak> {
    let total: f64 = c[1..].iter().sum();
    // An interior-point solution is never exactly zero: 1 % of the largest grid
    // modulus separates the spectrum from the solver's residue.
    let thr = 1e-2 * c[1..].iter().copied().fold(0.0, f64::max);
    let mut out: Vec<Peak> = Vec::new();
    let mut open = false;
    for (j, &e) in c[1..].iter().enumerate() {
        if e > thr {
            let p = Peak {
                e,
                ln_tau: taus[j].ln(),
            };
            match (open, out.last_mut()) {
                (true, Some(last)) => *last = merge(*last, p),
                _ => out.push(p),
            }
            open = true;
        } else {
            open = false;
        }
    }
    // Prune peaks below 0.1 % of the relaxing modulus: noise, not spectrum.
    out.retain(|p| p.e >= 1e-3 * total);
    out
}

/// Sort the terms of a scaled parameter vector by τ.
fn sort_terms(p: &mut [f64], n: usize) {
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| p[1 + n + a].total_cmp(&p[1 + n + b]));
    let old = p.to_vec();
    for (new, &o) in idx.iter().enumerate() {
        p[1 + new] = old[1 + o];
        p[1 + n + new] = old[1 + n + o];
    }
}

/// Stage 2 for one term count: the [`starts`], then either the moduli at the first
/// start's τ (the grid method) or [`refine`].
fn fit_terms(
    prep: &Prepared,
    grid: &(Vec<f64>, Vec<f64>, usize),
    n: usize,
    settings: &Settings,
) -> Result<TermFit> {
    let mut prob = prep.prob.clone();
    prob.n_terms = n;
    prob.evaluations = 0;
    let starts = starts(prep, grid, n, settings.max_starts);
    if settings.method == Method::Grid {
        let ts: Vec<f64> = starts[0].iter().map(|l| l.exp()).collect();
        let (e, it) = nnls_at(&mut prob, &ts)?;
        let mut p = e;
        p.extend(ts.iter().map(|t| t.ln()));
        return Ok(TermFit {
            n_terms: n,
            p,
            iterations: it,
            evaluations: prob.evaluations,
            termination: Termination::Converged("exact (NNLS at fixed τ)"),
            starts: 1,
            at_best: 1,
            problem: prob,
        });
    }
    Ok(refine(prob, &starts, prep.bounds, settings))
}

/// The starts of a term count's search, as ln τ of each term: the grid spectrum's
/// peaks brought to N by merging the closest pair, then by folding the smallest peak
/// ([`reshape`]), N terms spread evenly over the window, and the first start's terms
/// pushed half a grid step apart (breaks ties between close modes); the distinct
/// ones, at most `max`.
fn starts(
    prep: &Prepared,
    grid: &(Vec<f64>, Vec<f64>, usize),
    n: usize,
    max: usize,
) -> Vec<Vec<f64>> {
    let (taus, c, _) = grid;
    let pk = peaks(taus, c);
    let win = (prep.window.0.ln(), prep.window.1.ln());
    let ln_taus = |closest: bool| -> Vec<f64> {
        reshape(pk.clone(), n, closest, win)
            .iter()
            .map(|q| q.ln_tau)
            .collect()
    };
    let mut starts = vec![ln_taus(true), ln_taus(false)];
    if n > 0 {
        starts.push(
            (0..n)
                .map(|i| win.0 + (win.1 - win.0) * (i as f64 + 0.5) / n as f64)
                .collect(),
        );
        let mut wide = ln_taus(true);
        for (i, l) in wide.iter_mut().enumerate() {
            *l += if i % 2 == 0 { -0.35 } else { 0.35 };
        }
        starts.push(wide);
    }
    starts.dedup_by(|a, b| a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() < 1e-9));
    starts.truncate(max);
    starts
}

/// Stage 3 for one term count: from each start, variable projection over ln τ
/// ([`Projected`]) on a subsample of at most [`START_POINTS`] points (all the data
/// when there are no more); the best end carried through subsamples ten times larger
/// to all the data, each search starting next to its optimum and stopping at the
/// noise floor of the level before ([`NOISE_FLOOR`]); then one LM search over
/// all 2N + 1 parameters of [`Problem`] from the projection's optimum and its moduli,
/// a point of the joint problem's own valley floor: it takes an iteration or two and
/// makes the optimum the joint problem's to the solver's tolerances.
fn refine(
    mut prob: Problem,
    starts: &[Vec<f64>],
    ln_tau: (f64, f64),
    settings: &Settings,
) -> TermFit {
    let n = prob.n_terms;
    let lms = LmSettings {
        max_iterations: settings.max_iterations,
        ftol: settings.ftol,
        ..LmSettings::default()
    };
    let bounds = vec![ln_tau; n];
    let mut iterations = 0;
    let mut evaluations = 0;
    let mut tail = lms;
    let (r, joint, at_best) = match prob.subsample(START_POINTS) {
        // Every point: the starts' projection is the last one; the moduli at the end
        // come from a cold start, as a fresh projection's would.
        None => {
            let mut vp = Projected::new(&mut prob);
            let (r, at_best) = best_start(&mut vp, starts, &bounds, &lms, &mut iterations);
            vp.positive.fill(false);
            vp.c.fill(0.0);
            vp.moduli_at(&r.x);
            let joint = vp.joint(&r.x);
            (r, joint, at_best)
        }
        Some(mut sub) => {
            let (mut r, at_best) = {
                let mut vp = Projected::new(&mut sub);
                best_start(&mut vp, starts, &bounds, &lms, &mut iterations)
            };
            evaluations = sub.evaluations;
            // Past the starts, the searches stop at the noise floor of the level before.
            let floor = |cost: f64, m: usize| match cost.is_finite() {
                true => NOISE_FLOOR * 2.0 * cost / (m - (2 * n + 1)) as f64,
                false => 0.0,
            };
            tail.min_decrease = floor(r.cost, sub.len());
            let mut count = 10 * START_POINTS;
            while let Some(mut level) = prob.subsample(count) {
                r = lm::minimize(&mut Projected::new(&mut level), &r.x, &bounds, &tail);
                iterations += r.iterations;
                evaluations += level.evaluations;
                tail.min_decrease = floor(r.cost, level.len());
                count *= 10;
            }
            let mut vp = Projected::new(&mut prob);
            r = lm::minimize(&mut vp, &r.x, &bounds, &tail);
            iterations += r.iterations;
            // The moduli at the end (the search's last evaluation may have been a
            // rejected trial).
            vp.moduli_at(&r.x);
            let joint = vp.joint(&r.x);
            (r, joint, at_best)
        }
    };
    let mut joint_bounds = vec![(0.0, f64::INFINITY); 1 + n];
    joint_bounds.extend(bounds);
    let polish = lm::minimize(&mut prob, &joint, &joint_bounds, &tail);
    iterations += polish.iterations;
    let termination = match r.termination {
        Termination::Converged(_) => polish.termination,
        t => t,
    };
    let mut p = polish.x;
    sort_terms(&mut p, n);
    TermFit {
        n_terms: n,
        p,
        iterations,
        evaluations: prob.evaluations + evaluations,
        termination,
        starts: starts.len(),
        at_best,
        problem: prob,
    }
}

/// The projection's search from each start (their iterations added to
/// `iterations`): the end of lowest cost (the first of them; the first start's when
/// none is finite), and how many ends are within 10⁻⁶ of its cost.
fn best_start(
    vp: &mut Projected,
    starts: &[Vec<f64>],
    bounds: &[(f64, f64)],
    lms: &LmSettings,
    iterations: &mut usize,
) -> (LmResult, usize) {
    let mut results: Vec<LmResult> = starts
        .iter()
        .map(|s| lm::minimize(vp, s, bounds, lms))
        .collect();
    *iterations += results.iter().map(|r| r.iterations).sum::<usize>();
    let best = results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.cost.is_finite())
        .min_by(|a, b| a.1.cost.total_cmp(&b.1.cost))
        .map(|(i, _)| i)
        .unwrap_or(0);
    let bc = results[best].cost;
    let at_best = results
        .iter()
        .filter(|r| (r.cost - bc).abs() <= 1e-6 * bc.max(f64::MIN_POSITIVE))
        .count();
    (results.swap_remove(best), at_best)
}

/// Points on which the multi-start search of a term count runs: a longer curve is
/// subsampled evenly ([`Problem::subsample`]) and only the best start is carried to all
/// the data. Every shipped curve has fewer points, so its fits search all of it.
const START_POINTS: usize = 400;

/// The noise floor of the searches that carry the best start of a longer curve to
/// all its points ([`LmSettings::min_decrease`]), as a fraction of the residual
/// variance s² = ‖r‖²/(m − 2N − 1) of the level before: they stop when even the
/// Gauss-Newton step would lower ½‖r‖²/s² (half the χ²) by less than 10⁻³, where no
/// estimate can move by more than about √(2·10⁻³) ≈ 0.045 standard errors, instead
/// of walking the flat valleys of a term count the data do not support. The searches
/// of a curve of at most [`START_POINTS`] points (every shipped one) have no floor.
const NOISE_FLOOR: f64 = 1e-3;

/// Diagnostics of one term fit: statistics, uncertainty in SI, problems found.
struct Assessed {
    tf: TermFit,
    /// SI parameters: [E∞, E₁…, τ₁…].
    si: Vec<f64>,
    unc: diagnostics::Uncertainty,
    rmse: f64,
    rel_rmse: f64,
    /// Fraction of the data explained, 1 − ‖r‖²/‖w·y‖², against zero stress.
    explained: f64,
    /// Lag-1 autocorrelation of the scaled residuals in time order: ≈ 0 (±1/√n) for
    /// noise, near 1 for a misfit the model leaves systematically.
    lag1: f64,
    r2: f64,
    aicc: Option<f64>,
    bic: f64,
    /// Problems that make the count ineligible for auto (and raise the status).
    problems: Vec<(Status, String)>,
    /// Softer warnings.
    warnings: Vec<(Status, String)>,
    /// Per parameter ([E∞, E₁…, τ₁…]): whether the data pin it down by the one rule
    /// (fit::identifiability) and it is not at a bound of the τ search.
    identifiable: Vec<bool>,
}

/// Stage 4 for one term count: residual statistics, information criteria and the
/// uncertainty of the SI parameters, and the [`problems`] found.
fn assess(prep: &Prepared, mut tf: TermFit) -> Assessed {
    let prob = &mut tf.problem;
    let n = tf.n_terms;
    let m = prob.len();
    let k = 1 + 2 * n;
    let mut r = DVector::zeros(m);
    let mut jac = DMatrix::zeros(m, k);
    let finite = prob.eval(&tf.p, &mut r, Some(&mut jac));
    let rss = r.norm_squared();
    let s = prob.scale * prep.unit;
    let mut si = vec![tf.p[0] * s];
    si.extend((0..n).map(|i| tf.p[1 + i] * s));
    si.extend((0..n).map(|i| tf.p[1 + n + i].exp()));
    // Jacobian with respect to the SI parameters.
    for c in 0..=n {
        jac.column_mut(c).scale_mut(1.0 / s);
    }
    for i in 0..n {
        jac.column_mut(1 + n + i).scale_mut(1.0 / si[1 + n + i]);
    }
    let unc = diagnostics::uncertainty(&jac, rss);
    let mut pred = vec![0.0; m];
    prob.model(&tf.p, &mut pred);
    let y = &prob.y;
    let nf = m as f64;
    let mean = y.iter().sum::<f64>() / nf;
    let ss_res: f64 = pred.iter().zip(y).map(|(p, y)| (p - y).powi(2)).sum();
    let ss_tot: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    // Against zero stress (all moduli 0, which every series contains), in the fit's
    // own weighting.
    let null: f64 = y.iter().zip(&prob.w).map(|(y, w)| (y * w).powi(2)).sum();
    let lag1 = if rss > 0.0 {
        r.iter()
            .zip(r.iter().skip(1))
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / rss
    } else {
        0.0
    };
    let (aicc, bic) = diagnostics::information_criteria(rss, m, k);

    let (problems, warnings, identifiable) = problems(prep, &tf, &si, &unc, finite, m);
    Assessed {
        tf,
        si,
        unc,
        rmse: (ss_res / nf).sqrt(),
        rel_rmse: (rss / nf).sqrt(),
        explained: 1.0 - rss / null,
        lag1,
        r2: if ss_tot > 0.0 {
            1.0 - ss_res / ss_tot
        } else {
            f64::NAN
        },
        aicc,
        bic,
        problems,
        warnings,
        identifiable,
    }
}

/// Findings about a fit, each with the status it raises.
type Findings = Vec<(Status, String)>;

/// What makes a term fit ineligible for `auto` (and raises its status), and softer
/// warnings: a search that did not converge, a model not finite at the data, terms
/// that are negligible, at a bound, outside the sampled window or within a factor
/// 1.25 of each other, too few points, a parameter that is not identifiable by the
/// one rule (fit::identifiability; E∞ at its physical bound 0, or with an interval
/// reaching it, is judged by its
/// correlations only, and said as a one-sided interval); and per parameter whether
/// it is identifiable.
fn problems(
    prep: &Prepared,
    tf: &TermFit,
    si: &[f64],
    unc: &diagnostics::Uncertainty,
    finite: bool,
    m: usize,
) -> (Findings, Findings, Vec<bool>) {
    let n = tf.n_terms;
    let k = 1 + 2 * n;
    let mut problems = Vec::new();
    let mut warnings = Vec::new();
    if let Some(w) = tf.termination.shortfall() {
        problems.push((Status::NotConverged, w));
    }
    if !finite {
        problems.push((
            Status::NotConverged,
            "the model is not finite at some data points".into(),
        ));
    }
    let e0: f64 = si[..=n].iter().sum();
    // E∞ at the bound 0 its law allows, or with a 95 % interval that reaches it (the
    // non-negative least squares hold it at or next to 0): judged by its
    // correlations only, its interval one-sided
    let t = unc.t95.unwrap_or(1.96);
    let at_floor = unc.std_error[0].is_some_and(|sd| si[0] - t * sd <= 0.0);
    let (lo, hi) = (prep.bounds.0.exp(), prep.bounds.1.exp());
    let at_bound: Vec<bool> = (0..n)
        .map(|i| si[1 + n + i] <= lo * 1.0001 || si[1 + n + i] >= hi / 1.0001)
        .collect();
    for i in 0..n {
        let (tau, e) = (si[1 + n + i], si[1 + i]);
        let name = format!("τ{} = {}", i + 1, fmt_s(tau));
        if e <= 1e-3 * e0 {
            problems.push((
                Status::IllPosed,
                format!("term {} ({name}) is negligible (E{} ≤ 0.1 % of E0): a term too many for these data", i + 1, i + 1),
            ));
        } else if at_bound[i] {
            problems.push((
                Status::IllPosed,
                format!("{name} ran to its bound: the data do not determine it"),
            ));
        } else if tau < prep.window.0 {
            problems.push((
                Status::IllPosed,
                format!(
                    "{name} is shorter than the first sample ({}): this relaxation is over before the data see it, so its τ and modulus are not determined separately",
                    fmt_s(prep.window.0)
                ),
            ));
        } else if tau > prep.window.1 {
            problems.push((
                Status::IllPosed,
                format!(
                    "{name} is longer than the test ({}): the data show only the start of this relaxation, so its τ, its modulus and E∞ are not determined separately",
                    fmt_s(prep.window.1)
                ),
            ));
        }
    }
    for i in 1..n {
        let ratio = si[1 + n + i] / si[n + i];
        if ratio < 1.25 {
            problems.push((
                Status::IllPosed,
                format!(
                    "τ{} and τ{} are within a factor {ratio:.2}: two terms describe one relaxation",
                    i,
                    i + 1
                ),
            ));
        }
    }
    if m <= k + 1 {
        problems.push((
            Status::IllPosed,
            format!("{m} points for {k} parameters: no degrees of freedom left"),
        ));
    } else if unc.std_error.iter().any(Option::is_none) {
        problems.push((
            Status::IllPosed,
            format!(
                "parameters not identifiable from these data (condition number {:.2e})",
                unc.condition
            ),
        ));
    } else {
        if unc.condition > 1e8 {
            warnings.push((
                Status::Warning,
                format!(
                    "ill-conditioned: condition number {:.2e}; the parameters are poorly determined individually",
                    unc.condition
                ),
            ));
        }
        if at_floor {
            warnings.push((
                Status::Warning,
                format!(
                    "E∞ = {} is at its physical bound 0 within its 95 % interval (the data show no equilibrium modulus); its interval is one-sided, [0, {}]",
                    crate::report::format::si(si[0], "Pa"),
                    crate::report::format::si(si[0] + t * unc.std_error[0].unwrap_or(f64::NAN), "Pa")
                ),
            ));
        }
    }
    // The one rule for "identifiable" (fit::identifiability) for every parameter
    // (E∞, Eᵢ, τᵢ: none may change sign); E∞ at or next to the bound 0 its law allows
    // and is judged by its correlations only.
    let names: Vec<String> = param_names(n).into_iter().map(|(name, _)| name).collect();
    let mut floor = vec![false; k];
    floor[0] = at_floor;
    let judgement = diagnostics::judge(&names, si, unc, &vec![false; k], &floor);
    if unc.std_error.iter().all(Option::is_some) && m > k + 1 {
        problems.extend(
            judgement
                .findings
                .iter()
                .map(|w| (Status::IllPosed, w.clone())),
        );
        warnings.extend(
            judgement
                .warnings
                .iter()
                .map(|w| (Status::Warning, w.clone())),
        );
    }
    let identifiable = (0..k)
        .map(|j| judgement.identifiable(j) && !(j > n && at_bound[j - 1 - n]))
        .collect();
    (problems, warnings, identifiable)
}

fn param_names(n: usize) -> Vec<(String, &'static str)> {
    let mut v = vec![("E_inf".to_string(), "Pa")];
    v.extend((1..=n).map(|i| (format!("E{i}"), "Pa")));
    v.extend((1..=n).map(|i| (format!("tau{i}"), "s")));
    v
}

/// Seconds with an SI prefix, for messages.
fn fmt_s(t: f64) -> String {
    crate::report::format::si(t, "s")
}

/// The rule `auto` applies.
pub fn auto_rule(settings: &Settings) -> String {
    let base = "among term counts whose fit converged and whose terms are all identifiable, non-negligible, a factor 1.25 apart and inside the sampled time window";
    let rule = match (settings.tolerance, settings.criterion) {
        (Some(t), _) => format!(
            "{base}, take the fewest whose relative RMSE is at most {:.3} %",
            100.0 * t
        ),
        (None, Criterion::Aicc) => format!(
            "{base}, take the fewest within ΔAICc ≤ 2 of the smallest AICc (BIC where AICc is undefined)"
        ),
        (None, Criterion::Bic) => format!("{base}, take the fewest within ΔBIC ≤ 2 of the smallest BIC"),
    };
    format!(
        "{rule}. Identifiable: {} (E∞ at the bound 0 its law allows, or with an interval reaching it, by its correlations only)",
        super::identifiability::RULE
    )
}

/// Fit a relaxation curve. `qlv`: the hyperelastic fit whose uniaxial stress is the
/// instantaneous response (QLV reading); `None`: the small-strain (parallel) reading.
///
/// Four stages, each a function: [`prepare`] (the loading, the hereditary input,
/// weights and the τ window), [`grid_stage`] (the non-negative spectrum on a fixed τ
/// grid), [`fit_terms`] (each term count, in parallel: its [`starts`] from the grid's
/// peaks and [`refine`], variable projection then a joint polish) and the assessment: [`assess`] (diagnostics of each count), [`choose`] (the count
/// reported), [`verdict`] (status and warnings) and [`report`] (the fit record).
pub fn fit(
    data: &RelaxationData,
    loading: &Loading,
    qlv: Option<&QlvInput>,
    settings: &Settings,
) -> Result<RelaxationFit> {
    settings.check()?;
    let t0 = Instant::now();
    let mut prep = prepare(data, loading, qlv, settings)?;
    let counts = term_counts(settings, data.time.len())?;
    let grid = grid_stage(&mut prep, settings.grid_per_decade)?;
    let fits: Vec<TermFit> = counts
        .par_iter()
        .map(|&nt| fit_terms(&prep, &grid, nt, settings))
        .collect::<Result<Vec<_>>>()?;
    let seconds = t0.elapsed().as_secs_f64();
    let mut assessed: Vec<Assessed> = fits.into_par_iter().map(|f| assess(&prep, f)).collect();
    let mut notes = std::mem::take(&mut prep.notes);
    let choice = choose(&prep, &assessed, settings, &mut notes);
    let a = assessed.swap_remove(choice.index);
    let verdict = verdict(data, loading, &prep, &a, notes, choice.unresolved);
    Ok(report(
        data,
        loading,
        qlv,
        settings,
        &prep,
        &grid,
        a,
        verdict,
        choice.selection,
        seconds,
    ))
}

/// The term counts to fit: the one asked for (refused if the data hold too few
/// points: N terms need 2N + 3), or 0 to `max_terms` as far as the points allow.
fn term_counts(settings: &Settings, m: usize) -> Result<Vec<usize>> {
    let max_by_points = (m.saturating_sub(3)) / 2;
    if let Some(nt) = settings.terms {
        if nt > max_by_points {
            return Err(Error::settings(format!(
                "{nt} term(s) need at least {} points, the file has {m}",
                2 * nt + 3
            ))
            .with_hint("use fewer terms (--terms auto chooses what the data support)"));
        }
    }
    Ok(match settings.terms {
        Some(nt) => vec![nt],
        None => (0..=settings.max_terms.min(max_by_points)).collect(),
    })
}

/// The term count reported and, for `--terms auto`, how it was chosen.
struct Choice {
    /// Index into the assessed counts.
    index: usize,
    selection: Option<Selection>,
    /// Why no Prony series could be reported although the data relax, if so.
    unresolved: Option<String>,
}

/// The score `auto` compares: AICc (BIC where AICc is undefined) or BIC.
fn score(settings: &Settings, a: &Assessed) -> f64 {
    match settings.criterion {
        Criterion::Aicc => a.aicc.unwrap_or(a.bic),
        Criterion::Bic => a.bic,
    }
}

/// Choose among the assessed counts by [`auto_rule`] (the only one when the count was
/// given); notes on what the choice leaves out go to `notes`.
fn choose(
    prep: &Prepared,
    assessed: &[Assessed],
    settings: &Settings,
    notes: &mut Vec<String>,
) -> Choice {
    let score = |a: &Assessed| score(settings, a);
    let mut unresolved: Option<String> = None;
    let (index, selection) = if settings.terms.is_some() {
        (0, None)
    } else {
        let best = assessed.iter().map(score).fold(f64::INFINITY, f64::min);
        let eligible: Vec<usize> = (0..assessed.len())
            .filter(|&i| assessed[i].problems.is_empty())
            .collect();
        let pool = if eligible.is_empty() {
            (0..assessed.len()).collect()
        } else {
            eligible
        };
        let chosen = match settings.tolerance {
            Some(tol) => pool
                .iter()
                .copied()
                .find(|&i| assessed[i].rel_rmse <= tol)
                .unwrap_or_else(|| {
                    notes.push(format!(
                        "no term count reaches the relative RMSE tolerance {:.3} %; the best is used",
                        100.0 * tol
                    ));
                    *pool
                        .iter()
                        .min_by(|&&a, &&b| assessed[a].rel_rmse.total_cmp(&assessed[b].rel_rmse))
                        .expect("non-empty")
                }),
            None => {
                let best_pool = pool
                    .iter()
                    .map(|&i| score(&assessed[i]))
                    .fold(f64::INFINITY, f64::min);
                *pool
                    .iter()
                    .find(|&&i| score(&assessed[i]) <= best_pool + 2.0)
                    .expect("the best is in the pool")
            }
        };
        let best_any = (0..assessed.len())
            .min_by(|&a, &b| score(&assessed[a]).total_cmp(&score(&assessed[b])))
            .expect("non-empty");
        let c = &assessed[chosen];
        let name = if settings.criterion == Criterion::Bic {
            "BIC"
        } else {
            "AICc"
        };
        let mut reason = if let Some(tol) = settings.tolerance {
            format!(
                "{} term(s) {} a relative RMSE of {:.3} %",
                c.tf.n_terms,
                if c.rel_rmse <= tol {
                    "reach"
                } else {
                    "come closest to the tolerance, with"
                },
                100.0 * c.rel_rmse
            )
        } else if chosen == best_any {
            format!(
                "{} term(s) have the smallest {name} and no fewer terms are within 2 of it",
                c.tf.n_terms
            )
        } else {
            format!(
                "{} term(s): the fewest within Δ{name} ≤ 2 of the best eligible count; more terms are not supported by the data",
                c.tf.n_terms
            )
        };
        if assessed[best_any].tf.n_terms > c.tf.n_terms && !assessed[best_any].problems.is_empty() {
            let b = &assessed[best_any];
            reason.push_str(&format!(
                "; {} terms score better ({name} {:.2} lower) but: {}",
                b.tf.n_terms,
                score(c) - score(b),
                b.problems[0].1
            ));
            notes.push(format!(
                "more relaxation may be present than these data resolve: with {} terms, {}",
                b.tf.n_terms, b.problems[0].1
            ));
        }
        if c.tf.n_terms == 0 && c.explained > EXPLAINS_NOTHING {
            if score(c) > score(&assessed[best_any]) + 2.0 {
                unresolved = Some(format!(
                    "no identifiable Prony series: the data relax (a constant modulus leaves a relative RMSE of {:.3} %), but every fit with terms puts them where these data cannot determine them; check the loading (--ramp-time, a strain column) and the time window",
                    100.0 * c.rel_rmse
                ));
            } else if c.lag1 >= SYSTEMATIC {
                notes.push(format!(
                    "no Prony series explains how the stress varies: a constant modulus leaves a relative RMSE of {:.3} % whose residuals are systematic (lag-1 autocorrelation {:.2}), not noise; the stress does not relax as decaying exponentials of this loading: check the loading (--ramp-time, a strain column) and the stress column",
                    100.0 * c.rel_rmse,
                    c.lag1
                ));
            } else {
                notes.push(format!(
                    "no relaxation resolved: a constant modulus fits as well as any Prony series (relative RMSE {:.3} %) — purely elastic within the noise over {}–{}",
                    100.0 * c.rel_rmse,
                    fmt_s(prep.window.0),
                    fmt_s(prep.window.1)
                ));
            }
        }
        let candidates = assessed
            .iter()
            .map(|a| Candidate {
                terms: a.tf.n_terms,
                k: 1 + 2 * a.tf.n_terms,
                rmse_pa: a.rmse,
                rel_rmse: a.rel_rmse,
                aicc: a.aicc,
                bic: a.bic,
                delta: score(a) - best,
                tau_s: a.si[1 + a.tf.n_terms..].to_vec(),
                eligible: a.problems.is_empty(),
                note: a.problems.first().map(|p| p.1.clone()),
            })
            .collect();
        (
            chosen,
            Some(Selection {
                rule: auto_rule(settings),
                reason,
                candidates,
            }),
        )
    };
    Choice {
        index,
        selection,
        unresolved,
    }
}

/// Status and warnings of the chosen count, and the QLV reading's instantaneous scale.
struct Verdict {
    status: Status,
    warnings: Vec<String>,
    qlv: Option<QlvInfo>,
}

/// The status and warnings of the chosen count `a`: the notes so far, its problems,
/// a fit that explains nothing, a step assumed on a ramp, a hyperelastic fit that is
/// not the instantaneous response.
fn verdict(
    data: &RelaxationData,
    loading: &Loading,
    prep: &Prepared,
    a: &Assessed,
    notes: Vec<String>,
    unresolved: Option<String>,
) -> Verdict {
    let (n, m) = (a.tf.n_terms, data.time.len());
    let mut status = Status::Ok;
    let mut escalate = |s: Status| {
        if status == Status::Ok || (status == Status::Warning && s != Status::Warning) {
            status = s;
        }
    };
    let mut warnings = Vec::new();
    for w in notes {
        escalate(Status::Warning);
        warnings.push(w);
    }
    // what the reader did beyond reading (a preamble skipped, a units row read,
    // columns not used): said, as for tensile files, not a warning of the fit
    let name = std::path::Path::new(&data.source.path)
        .file_name()
        .map_or_else(
            || data.source.path.clone(),
            |n| n.to_string_lossy().into_owned(),
        );
    warnings.extend(data.source.notes.iter().map(|n| format!("{name}: {n}")));
    if let Some(w) = unresolved {
        escalate(Status::IllPosed);
        warnings.push(w);
    }
    for (s, w) in a.problems.iter().chain(&a.warnings) {
        escalate(*s);
        warnings.push(w.clone());
    }
    if let Some(w) = diagnostics::worse_than_mean(a.r2) {
        escalate(Status::IllPosed);
        warnings.push(w);
    }
    if a.explained <= EXPLAINS_NOTHING {
        escalate(Status::IllPosed);
        warnings.push(format!(
            "the fit explains nothing: it leaves {:.0} % of the data's weighted sum of squares (relative RMSE {:.3} %, R² {:.3}), where zero stress leaves 100 %; check the stress column (its sign and unit), the loading and --residual",
            100.0 * (1.0 - a.explained),
            100.0 * a.rel_rmse,
            a.r2
        ));
    }
    // A step assumed while the stress builds up: the loading was not a step.
    if data.strain.is_none() && loading.ramp_time.is_none() {
        let y = &data.stress;
        let peak = (0..m)
            .max_by(|&i, &j| y[i].abs().total_cmp(&y[j].abs()))
            .expect("non-empty");
        if peak > 0 && y[peak].abs() > 1.05 * y[0].abs() && data.time[peak] < 0.2 * data.time[m - 1]
        {
            escalate(Status::Warning);
            warnings.push(format!(
                "the stress rises until t = {} although the loading is taken as an ideal step: give the ramp (--ramp-time) or a strain column, or the fit puts spurious stiff short-τ terms on the ramp",
                fmt_s(data.time[peak])
            ));
        }
    }
    let si = &a.si;
    let e0: f64 = si[..=n].iter().sum();
    let mut qlv_info = prep.qlv.clone();
    if let Some(q) = &mut qlv_info {
        q.instantaneous_scale = e0 / prep.unit;
        if let Some(w) = qlv_consistency(q.instantaneous_scale) {
            escalate(Status::Warning);
            warnings.push(w);
        }
    }
    Verdict {
        status,
        warnings,
        qlv: qlv_info,
    }
}

/// What QLV's G(0) (`g0`, the relaxation's start over the hyperelastic stress)
/// says about the two data sets, beyond 10 % of agreement. A tensile test at a
/// finite rate lies between the relaxed and the instantaneous response: its stress
/// is s × the instantaneous one with s ≤ 1, so consistent data have G(0) = 1/s ≥ 1
/// (the finite-rate case, said as such when G(0) > 1.1). G(0) < 1 no rate
/// explains: the tensile and the relaxation data disagree (another specimen or
/// material, strain measure, units, a preload), and the warning says so. (The
/// relaxed end G(∞) is not judged: E∞ is an extrapolation of the data's window.)
fn qlv_consistency(g0: f64) -> Option<String> {
    const TOL: f64 = 0.1;
    if g0 < 1.0 - TOL {
        Some(format!(
            "the tensile and the relaxation data disagree: the relaxation starts at G(0) = {g0:.3} × the hyperelastic stress, below it, while a tensile test at any rate lies at or below the instantaneous response (G(0) ≥ 1); check that both are of one material and specimen, the strain measure, the units and a preload; the instantaneous response is taken as G(0) times the hyperelastic stress"
        ))
    } else if g0 > 1.0 + TOL {
        Some(format!(
            "the hyperelastic fit is not the instantaneous response of these data: the relaxation starts at G(0) = {g0:.3} × its stress (a tensile test at a finite rate lies between the instantaneous and the long-term response); the instantaneous response is G(0) times the hyperelastic stress"
        ))
    } else {
        None
    }
}

/// The fit record of the chosen count `a`.
#[allow(clippy::too_many_arguments)]
fn report(
    data: &RelaxationData,
    loading: &Loading,
    qlv: Option<&QlvInput>,
    settings: &Settings,
    prep: &Prepared,
    grid: &(Vec<f64>, Vec<f64>, usize),
    a: Assessed,
    verdict: Verdict,
    selection: Option<Selection>,
    seconds: f64,
) -> RelaxationFit {
    let (n, m) = (a.tf.n_terms, data.time.len());
    let solver_iterations = a.tf.iterations + grid.2;
    let si = &a.si;
    let e0: f64 = si[..=n].iter().sum();
    let names = param_names(n);
    let parameters: Vec<Parameter> = names
        .iter()
        .zip(si)
        .zip(&a.unc.std_error)
        .zip(&a.identifiable)
        .map(|((((name, unit), &v), se), &identifiable)| Parameter {
            name: name.clone(),
            value: v,
            unit: unit.to_string(),
            std_error: *se,
            // Every parameter is ≥ 0 by its law: an interval reaching below 0 is
            // clipped there (it loses no value the parameter can take).
            ci95: se
                .zip(a.unc.t95)
                .map(|(s, t)| [(v - t * s).max(0.0), v + t * s]),
            identifiable: Some(identifiable),
        })
        .collect();
    let prony: Vec<PronyEntry> = (0..n)
        .map(|i| PronyEntry {
            tau_s: si[1 + n + i],
            modulus_pa: si[1 + i],
            g: if e0 > 0.0 { si[1 + i] / e0 } else { 0.0 },
            tau_std_s: a.unc.std_error[1 + n + i],
            modulus_std_pa: a.unc.std_error[1 + i],
        })
        .collect();
    let kelvin_maxwell = prony
        .iter()
        .map(|p| ArmEntry {
            k_pa: p.modulus_pa,
            n_pa_s: p.modulus_pa * p.tau_s,
        })
        .collect();
    let spectrum = grid
        .0
        .iter()
        .zip(&grid.1[1..])
        .map(|(&t, &e)| SpectrumPoint {
            tau_s: t,
            modulus_pa: e * prep.prob.scale * prep.unit,
        })
        .collect();
    let termination = a.tf.termination.to_string();
    // The grid stage's points (grid_stage).
    let on = match m > START_POINTS {
        true => format!(" on {START_POINTS} of the {m} points"),
        false => String::new(),
    };
    let method = match settings.method {
        Method::Refined => format!(
            "grid NNLS ({} τ, {}/decade, Lawson–Hanson{on}) + merge/prune + variable projection (bounded Levenberg-Marquardt over ln τᵢ, E∞ and Eᵢ by NNLS), multi-start, then LM over (E∞, Eᵢ, ln τᵢ)",
            grid.0.len(),
            settings.grid_per_decade
        ),
        Method::Grid => format!(
            "grid NNLS ({} τ, {}/decade, Lawson–Hanson{on}) + merge/prune, moduli by NNLS at the merged τ (no refinement)",
            grid.0.len(),
            settings.grid_per_decade
        ),
    };
    RelaxationFit {
        schema: SCHEMA.into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        formulation: prep.formulation,
        held_strain: prep.held_strain,
        loading: prep.loading.clone(),
        prony,
        long_term_modulus_pa: si[0],
        instantaneous_modulus_pa: e0,
        g_inf: if e0 > 0.0 { si[0] / e0 } else { 0.0 },
        kelvin_maxwell,
        qlv: verdict.qlv,
        parameters,
        rmse_pa: a.rmse,
        rel_rmse: a.rel_rmse,
        r2: a.r2,
        aicc: a.aicc,
        bic: a.bic,
        residual: prep.residual,
        points: m,
        time_window_s: [prep.window.0, prep.window.1],
        spectrum,
        correlation: a.unc.correlation.clone(),
        condition_number: a.unc.condition.is_finite().then_some(a.unc.condition),
        status: verdict.status,
        warnings: verdict.warnings,
        solver: SolverReport {
            method,
            starts: a.tf.starts,
            starts_at_best: a.tf.at_best,
            iterations: solver_iterations,
            evaluations: a.tf.evaluations,
            seconds,
            termination,
        },
        selection,
        provenance: Provenance {
            files: vec![data.source.clone()],
            hyperelastic_fit: qlv.map(|q| q.file.clone()),
            loading: *loading,
            settings: serde_json::to_value(settings).unwrap_or_default(),
        },
    }
}

/// The fitted model's stress at the data's times: the fit's Prony series applied to
/// the data's loading history (as the fit saw it).
pub fn predict(
    fit: &RelaxationFit,
    data: &RelaxationData,
    qlv: Option<&QlvInput>,
) -> Result<Vec<f64>> {
    let prep = prepare(data, &fit.provenance.loading, qlv, &Settings::default())?;
    response(&prep, &fit.values())
}

/// The first-order standard deviation of the fitted stress (Pa) at the data's times,
/// from the parameter covariance ([`diagnostics::propagated_std`]): the ±1σ
/// confidence band of the fitted curve. None when a parameter has no standard error
/// or correlation.
pub fn predict_std(
    fit: &RelaxationFit,
    data: &RelaxationData,
    qlv: Option<&QlvInput>,
) -> Result<Option<Vec<f64>>> {
    let prep = prepare(data, &fit.provenance.loading, qlv, &Settings::default())?;
    let se: Vec<Option<f64>> = fit.parameters.iter().map(|p| p.std_error).collect();
    Ok(
        diagnostics::covariance(&se, &fit.correlation).and_then(|cov| {
            diagnostics::propagated_std(|p| response(&prep, p).ok(), &fit.values(), &cov)
        }),
    )
}

/// The stress for SI parameters θ = (E∞, E₁…E_N, τ₁…τ_N) (the order of
/// [`RelaxationFit::parameters`]) on the prepared loading history.
fn response(prep: &Prepared, theta: &[f64]) -> Result<Vec<f64>> {
    let n = (theta.len() - 1) / 2;
    // In the prepared input, moduli are per unit of x scaled by `unit`.
    let terms: Vec<(f64, f64)> = (0..n)
        .map(|i| (theta[1 + n + i], theta[1 + i] / prep.unit))
        .collect();
    Ok(Prony::new(theta[0] / prep.unit, &terms)?.response(&prep.prob.sched))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::relaxation::{read, RelaxationOptions};
    use std::path::Path;

    /// Variable projection's residuals are the joint problem's at the moduli it
    /// solved for, and Kaufman's gradient Jᵀr is the exact gradient of ½‖r(θ)‖²:
    /// compared with central differences (step 10⁻⁵ in ln τ, truncation error
    /// ~10⁻¹⁰ of the gradient) at τ near the seed's Table 3.3, where every modulus is
    /// positive and stays so within the step (the active set does not change).
    #[test]
    fn projection_has_the_joint_residuals_and_the_exact_gradient() {
        // The seed's Table 3.3 as a step to strain 0.5, 200 points, 1 % noise.
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/vhb4910/relaxation.csv");
        let data = read(&path, &RelaxationOptions::default()).unwrap();
        let loading = Loading {
            strain: Some(0.5),
            ramp_time: None,
        };
        let mut prob = prepare(&data, &loading, None, &Settings::default())
            .unwrap()
            .prob;
        prob.n_terms = 3;
        let theta = [0.2f64.ln(), 20f64.ln(), 300f64.ln()];
        let m = prob.len();
        let (mut r, mut j) = (DVector::zeros(m), DMatrix::zeros(0, 3));
        let mut vp = Projected::new(&mut prob);
        assert!(vp.eval(&theta, &mut r, Some(&mut j)));
        assert!(vp.c.iter().all(|&c| c > 0.0), "moduli {}", vp.c);
        let joint = vp.joint(&theta);
        let g = vp.normal_equations(&theta).expect("formed at θ").1;
        let mut cost = |th: &[f64]| {
            let mut r = DVector::zeros(m);
            assert!(vp.eval(th, &mut r, None));
            0.5 * r.norm_squared()
        };
        let h = 1e-5;
        for i in 0..3 {
            let (mut a, mut b) = (theta, theta);
            a[i] += h;
            b[i] -= h;
            let fd = (cost(&a) - cost(&b)) / (2.0 * h);
            assert!(
                (g[i] - fd).abs() <= 1e-6 * g.amax(),
                "∂/∂ln τ{}: Kaufman {} vs central difference {fd}",
                i + 1,
                g[i]
            );
        }
        let mut rj = DVector::zeros(m);
        assert!(prob.eval(&joint, &mut rj, None));
        assert!((&rj - &r).amax() <= 1e-12 * r.amax().max(1.0));
    }

    /// The joint problem's residuals are the same bits with and without its Jacobian
    /// (an accepted trial's Jacobian is kept: [`LeastSquares::jacobian_with_trial`]),
    /// its model stress is the residuals' (wₖ·(model − yₖ) to rounding, 10⁻¹² of the
    /// peak stress), and its analytic Jacobian is the residuals' derivative: central
    /// differences (step 10⁻⁶ relative in a modulus, 10⁻⁶ in ln τ; truncation and
    /// rounding ~10⁻⁹ of the largest entry) at the seed's Table 3.3 constants, 4 terms.
    #[test]
    fn joint_problem_has_its_residuals_derivative() {
        let mut prob = long_curve(200).prob;
        prob.n_terms = 4;
        let s = prob.scale;
        let p: Vec<f64> = [43.3e3, 106.1e3, 45.5e3, 16.1e3, 10.9e3]
            .iter()
            .map(|e| e / s)
            .chain([0.153f64, 0.464, 32.0, 216.0].iter().map(|t| t.ln()))
            .collect();
        let m = prob.len();
        let (mut r, mut r_only, mut j) = (
            DVector::zeros(m),
            DVector::zeros(m),
            DMatrix::zeros(m, p.len()),
        );
        assert!(prob.eval(&p, &mut r_only, None));
        assert!(prob.eval(&p, &mut r, Some(&mut j)));
        assert_eq!(r, r_only);
        let mut model = vec![0.0; m];
        prob.model(&p, &mut model);
        let peak = prob.y.iter().fold(0.0f64, |a, y| a.max(y.abs()));
        for k in 0..m {
            let want = r[k] / prob.w[k] + prob.y[k];
            assert!((model[k] - want).abs() <= 1e-12 * peak, "point {k}");
        }
        for c in 0..p.len() {
            let h = if c <= 4 { 1e-6 * p[c] } else { 1e-6 };
            let (mut a, mut b) = (p.clone(), p.clone());
            a[c] += h;
            b[c] -= h;
            let (mut ra, mut rb) = (DVector::zeros(m), DVector::zeros(m));
            assert!(prob.eval(&a, &mut ra, None) && prob.eval(&b, &mut rb, None));
            let fd = (ra - rb) / (2.0 * h);
            let (col, err) = (j.column(c), (j.column(c) - fd).amax());
            assert!(
                err <= 1e-7 * col.amax(),
                "column {c}: {err} vs {}",
                col.amax()
            );
        }
    }

    /// Kernels reused at the same τ are the ones a fresh problem computes: the
    /// joint problem's residuals and Jacobian after a projected evaluation at θ
    /// (kernels with derivatives, taken from the cache), after one without (the
    /// derivatives then computed), and at other τ, each the same bits as a fresh
    /// problem's; and the projection's moduli at θ from its kept Gram products
    /// ([`Projected::moduli_at`]) are a fresh projection's, cold-started, bit for
    /// bit. On a curve of 3000 points (six Gram blocks), 3 terms.
    #[test]
    fn reused_kernels_and_gram_products_are_fresh_ones() {
        let prep = long_curve(3000);
        let mut prob = prep.prob.clone();
        prob.n_terms = 3;
        let (m, theta) = (prob.len(), [0.2f64.ln(), 20f64.ln(), 300f64.ln()]);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let joint_at = |prob: &mut Problem, p: &[f64]| {
            let (mut r, mut j) = (DVector::zeros(m), DMatrix::zeros(m, 7));
            assert!(prob.eval(p, &mut r, Some(&mut j)));
            (bits(r.as_slice()), bits(j.as_slice()))
        };
        let fresh = |p: &[f64]| {
            let mut f = prep.prob.clone();
            f.n_terms = 3;
            joint_at(&mut f, p)
        };
        for derivatives in [true, false] {
            let mut r = DVector::zeros(m);
            let mut none = DMatrix::zeros(0, 3);
            let mut vp = Projected::new(&mut prob);
            assert!(vp.eval(&theta, &mut r, derivatives.then_some(&mut none)));
            let joint = vp.joint(&theta);
            assert_eq!(prob.kernel_taus.len(), 3);
            assert_eq!(joint_at(&mut prob, &joint), fresh(&joint), "{derivatives}");
            let mut moved = joint.clone();
            moved[5] += 0.1;
            assert_eq!(joint_at(&mut prob, &moved), fresh(&moved), "{derivatives}");
        }
        let mut vp = Projected::new(&mut prob);
        let mut r = DVector::zeros(m);
        assert!(vp.eval(&theta, &mut r, None));
        vp.positive.fill(false);
        vp.moduli_at(&theta);
        let kept = vp.c.clone();
        let mut other = prep.prob.clone();
        other.n_terms = 3;
        let mut cold = Projected::new(&mut other);
        assert!(cold.eval(&theta, &mut r, None));
        assert_eq!(bits(kept.as_slice()), bits(cold.c.as_slice()));
    }

    /// The seed's Table 3.3 as a step to strain 0.5, `points` log-spaced over
    /// 0.01–1000 s, 1 % noise, prepared.
    fn long_curve(points: usize) -> Prepared {
        use crate::io::relaxation::{from_table, log_times, RelaxationOptions, Synthetic};
        use crate::io::table::Table;
        use crate::material::viscoelastic::preset;
        let csv = Synthetic {
            prony: preset("elatrache2021-table-3.3").unwrap().prony,
            strain: 0.5,
            ramp_time: None,
            times: log_times(0.01, 1000.0, points, false),
            noise: 0.01,
            seed: 4910,
            record_strain: false,
        }
        .csv(&["test"])
        .unwrap();
        let table = Table::parse(Path::new("long.csv"), csv.as_bytes()).unwrap();
        let data = from_table(&table, &RelaxationOptions::default()).unwrap();
        let loading = Loading {
            strain: Some(0.5),
            ramp_time: None,
        };
        prepare(&data, &loading, None, &Settings::default()).unwrap()
    }

    /// The projection's normal equations, formed from the Gram products in blocks
    /// of [`GRAM_ROWS`] rows, are those of Kaufman's Jacobian Jᵢ = cᵢ·P⊥·dᵢ built
    /// explicitly (P⊥ from a QR factorisation of the positive columns) on a curve of
    /// 3000 points (six blocks), with one modulus at zero (a term at 1 ms, before
    /// the data): JᵀJ to 10⁻⁹ of its largest entry (the Gram route loses about
    /// κ(A_PᵀA_P)·ε ≈ 10⁻¹¹ here), Jᵀr to 10⁻¹⁰ of its largest.
    #[test]
    fn normal_equations_are_kaufmans_from_the_gram_products() {
        let mut prob = long_curve(3000).prob;
        prob.n_terms = 4;
        let theta = [1e-3f64.ln(), 0.2f64.ln(), 20f64.ln(), 300f64.ln()];
        let m = prob.len();
        let mut r = DVector::zeros(m);
        let mut vp = Projected::new(&mut prob);
        assert!(vp.eval(&theta, &mut r, Some(&mut DMatrix::zeros(0, 4))));
        let (jtj, jtr) = vp.normal_equations(&theta).expect("formed at θ");
        assert!(vp.normal_equations(&[0.0; 4]).is_none());
        let pos: Vec<usize> = (0..5).filter(|&j| vp.c[j] > 0.0).collect();
        assert_eq!(pos.len(), 4, "moduli {}", vp.c);
        let ap = DMatrix::from_fn(m, pos.len(), |k, q| vp.a[(k, pos[q])]);
        let q = ap.qr().q();
        let mut j = DMatrix::zeros(m, 4);
        for i in 0..4 {
            let d = vp.da.column(i) * vp.c[1 + i];
            let proj = &q * (q.tr_mul(&d));
            j.set_column(i, &(d - proj));
        }
        let (want, want_g) = (j.tr_mul(&j), j.tr_mul(&r));
        let err = (&jtj - &want).amax() / want.amax();
        assert!(err <= 1e-9, "JᵀJ off by {err:e} of its largest entry");
        let err_g = (&jtr - &want_g).amax() / want_g.amax();
        assert!(err_g <= 1e-10, "Jᵀr off by {err_g:e}");
    }

    /// The grid stage of a curve longer than [`START_POINTS`] is the grid NNLS of
    /// the starts' subsample, bit for bit (the full curve's differs), and the term
    /// fits it starts end where those started from the full curve's grid end: costs
    /// equal within 10⁻⁵ relative (the searches on all the points stop at the noise
    /// floor, Δ½χ² ≈ 10⁻³ of the residual variance, ≈ 10⁻⁶ of the cost at 3000 points).
    #[test]
    fn grid_stage_of_a_long_curve_runs_on_the_start_subsample() {
        let mut prep = long_curve(3000);
        let grid = grid_stage(&mut prep, 6).unwrap();
        let mut sub = prep.prob.subsample(START_POINTS).unwrap();
        assert_eq!(grid, grid_nnls(&mut sub, prep.window, 6).unwrap());
        let full = grid_nnls(&mut prep.prob, prep.window, 6).unwrap();
        assert_ne!(grid.1, full.1);
        let settings = Settings::default();
        let cost = |tf: &TermFit| {
            let mut prob = prep.prob.clone();
            prob.n_terms = tf.n_terms;
            let mut r = DVector::zeros(prob.len());
            assert!(prob.eval(&tf.p, &mut r, None));
            0.5 * r.norm_squared()
        };
        for n in 1..=4 {
            let a = cost(&fit_terms(&prep, &grid, n, &settings).unwrap());
            let b = cost(&fit_terms(&prep, &full, n, &settings).unwrap());
            assert!((a - b).abs() <= 1e-5 * b, "{n} terms: {a} vs {b}");
        }
    }

    /// QLV's G(0) below 1 (the relaxation starting below the tensile stress) says the
    /// two data sets disagree, never the finite-rate explanation, which needs
    /// G(0) ≥ 1; G(0) above 1 is the finite-rate case; within 10 % nothing is said.
    #[test]
    fn qlv_g0_below_one_says_the_data_disagree() {
        let low = qlv_consistency(0.771).expect("a warning");
        assert!(
            low.contains("disagree") && low.contains("G(0) = 0.771"),
            "{low}"
        );
        assert!(!low.contains("finite rate"), "{low}");
        let high = qlv_consistency(1.4).expect("a warning");
        assert!(
            high.contains("finite rate") && !high.contains("disagree"),
            "{high}"
        );
        assert_eq!(qlv_consistency(1.05), None);
        assert_eq!(qlv_consistency(0.95), None);
    }
}
