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

mod prepare;
mod report;

pub use crate::fit::prony::{Candidate, Criterion, Method, Selection};
pub use prepare::{unloads, TimeKernels};

use super::diagnostics;
use super::problem::Residual;
use super::prony::{assess, grid, refine, select, Search};
use super::Parameter;
use super::{SolverReport, Status};
use crate::error::Result;
use crate::io::relaxation::{RelaxationData, RelaxationSource};
use crate::material::file::HyperelasticPart;
use crate::material::viscoelastic::{Formulation, KelvinMaxwell, MaxwellArm, Prony};
use prepare::{prepare, Prepared};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A fit that leaves more than half of the data's weighted sum of squares (against
/// zero stress, the series with all moduli 0) explains nothing: its residual RMS is
/// above 1/√2 ≈ 71 % of the data's, so no constant of it can be trusted. A fit of
/// real data leaves a few % (0.1 % of the sum of squares); noise alone never leaves
/// half unless it is as large as the stress.
const EXPLAINS_NOTHING: f64 = 0.5;

/// Lag-1 autocorrelation of residuals above which they are systematic rather than
/// noise: white noise gives 0 ± 1/√n (±0.1 for 100 points), a misfit left by the
/// model gives values near 1; 0.5 is halfway.
const SYSTEMATIC: f64 = 0.5;

/// Schema tag of relaxation fit files (the material files' reader knows it).
pub const SCHEMA: &str = crate::material::file::RELAXATION_SCHEMA;

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
        self.search().check()
    }

    /// What these settings ask of the Prony core.
    pub fn search(&self) -> Search {
        Search {
            terms: self.terms,
            max_terms: self.max_terms,
            criterion: self.criterion,
            tolerance: self.tolerance,
            method: self.method,
            grid_per_decade: self.grid_per_decade,
            max_iterations: self.max_iterations,
            ftol: self.ftol,
            max_starts: self.max_starts,
        }
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

/// One Prony term of a fit, in the units the fit file names.
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

/// The rule `auto` applies.
pub fn auto_rule(settings: &Settings) -> String {
    select::auto_rule(
        &settings.search(),
        <TimeKernels as super::prony::Kernels>::WINDOW,
    )
}

/// Fit a relaxation curve. `qlv`: the hyperelastic fit whose uniaxial stress is the
/// instantaneous response (QLV reading); `None`: the small-strain (parallel) reading.
///
/// Stages, each a function: [`prepare`] (the loading, the hereditary input,
/// weights and the τ window), then the Prony core ([`super::prony`]):
/// [`grid::grid_stage`] (the non-negative spectrum on a fixed τ grid),
/// [`refine::fit_counts`] (each term count, in parallel: its starts from the grid's
/// peaks, variable projection then a joint polish), [`assess::assess_all`]
/// (diagnostics of each count), [`select::choose`] (the count reported); then
/// [`report::verdict`] (status and warnings) and [`report::report`] (the fit record).
pub fn fit(
    data: &RelaxationData,
    loading: &Loading,
    qlv: Option<&QlvInput>,
    settings: &Settings,
) -> Result<RelaxationFit> {
    settings.check()?;
    let search = settings.search();
    let t0 = Instant::now();
    let mut prep = prepare(data, loading, qlv, settings)?;
    let counts = select::term_counts(&search, data.time.len())?;
    let grid = grid::grid_stage(&mut prep.setup, settings.grid_per_decade)?;
    let fits = refine::fit_counts(&prep.setup, &grid, &counts, &search)?;
    let seconds = t0.elapsed().as_secs_f64();
    let mut assessed = assess::assess_all(&prep.setup, fits);
    let mut notes = std::mem::take(&mut prep.notes);
    let choice = select::choose(&assessed, &search, &mut notes);
    let unresolved = report::no_terms(&prep, &assessed, &choice, &search, &mut notes);
    let a = assessed.swap_remove(choice.index);
    let verdict = report::verdict(data, loading, &prep, &a, notes, unresolved);
    Ok(report::report(
        report::Inputs {
            data,
            loading,
            qlv,
            settings,
            prep: &prep,
            grid: &grid,
        },
        a,
        verdict,
        choice.selection,
        seconds,
    ))
}

/// The fitted model at the data's times: the stress, and its ±1σ band.
pub struct Prediction {
    /// The fit's Prony series applied to the data's loading history (as the fit saw
    /// it), Pa.
    pub stress: Vec<f64>,
    /// The first-order standard deviation of the fitted stress (Pa), from the
    /// parameter covariance ([`diagnostics::propagated_std`]): the ±1σ confidence
    /// band of the fitted curve. None when a parameter has no standard error or
    /// correlation.
    pub std: Option<Vec<f64>>,
}

/// The fitted model's stress at the data's times and its ±1σ band ([`Prediction`]),
/// on one prepared loading history.
pub fn predict(
    fit: &RelaxationFit,
    data: &RelaxationData,
    qlv: Option<&QlvInput>,
) -> Result<Prediction> {
    let prep = prepare(data, &fit.provenance.loading, qlv, &Settings::default())?;
    let theta = fit.values();
    let se: Vec<Option<f64>> = fit.parameters.iter().map(|p| p.std_error).collect();
    Ok(Prediction {
        stress: response(&prep, &theta)?,
        std: diagnostics::covariance(&se, &fit.correlation)
            .and_then(|cov| diagnostics::propagated_std(|p| response(&prep, p).ok(), &theta, &cov)),
    })
}

/// The stress for SI parameters θ = (E∞, E₁…E_N, τ₁…τ_N) (the order of
/// [`RelaxationFit::parameters`]) on the prepared loading history.
fn response(prep: &Prepared, theta: &[f64]) -> Result<Vec<f64>> {
    let n = (theta.len() - 1) / 2;
    // In the prepared input, moduli are per unit of x scaled by `unit`.
    let terms: Vec<(f64, f64)> = (0..n)
        .map(|i| (theta[1 + n + i], theta[1 + i] / prep.setup.unit))
        .collect();
    Ok(Prony::new(theta[0] / prep.setup.unit, &terms)?.response(&prep.setup.prob.kern.sched))
}

#[cfg(test)]
mod tests {
    use super::report::qlv_consistency;
    use super::*;
    use crate::fit::lm::LeastSquares;
    use crate::fit::prony::grid::{grid_nnls, grid_stage};
    use crate::fit::prony::problem::Problem;
    use crate::fit::prony::projection::Projected;
    use crate::fit::prony::refine::{fit_terms, Levels, TermFit, START_POINTS};
    use crate::io::relaxation::{read, RelaxationOptions};
    use nalgebra::{DMatrix, DVector};
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
            .setup
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
        let (mut prob, p) = four_terms_at_table_3_3(200);
        let m = prob.len();
        let (mut r, mut r_only, mut j) = (
            DVector::zeros(m),
            DVector::zeros(m),
            DMatrix::zeros(m, p.len()),
        );
        assert!(prob.eval(&p, &mut r_only, None));
        assert!(prob.eval(&p, &mut r, Some(&mut j)));
        assert_eq!(r, r_only);
        let (mut model, mut r_again) = (vec![0.0; m], vec![0.0; m]);
        prob.residuals_model_reach(&p, &mut r_again, &mut model);
        assert_eq!(r.as_slice(), r_again);
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

    /// The joint problem's normal equations, formed a block of 512 rows at a time
    /// when asked with an empty Jacobian (the polish's search: no m × (2N + 1)
    /// matrix), are those of its Jacobian: JᵀJ and Jᵀr equal `jac.tr_mul` of the
    /// full Jacobian at the same point to 10⁻¹² of their largest entry (blocked
    /// sums round differently), on a curve of 3000 points (six blocks), 4 terms;
    /// kept for that point only.
    #[test]
    fn joint_normal_equations_are_those_of_its_jacobian() {
        let (mut prob, p) = four_terms_at_table_3_3(3000);
        let m = prob.len();
        let (mut r, mut j) = (DVector::zeros(m), DMatrix::zeros(m, 9));
        assert!(prob.eval(&p, &mut r, Some(&mut j)));
        let mut r2 = DVector::zeros(m);
        assert!(prob.eval(&p, &mut r2, Some(&mut DMatrix::zeros(0, 9))));
        assert_eq!(r, r2);
        let (jtj, jtr) = prob.normal_equations(&p).expect("formed at p");
        let (want, want_g) = (j.tr_mul(&j), j.tr_mul(&r));
        let err = (&jtj - &want).amax() / want.amax();
        assert!(err <= 1e-12, "JᵀJ off by {err:e} of its largest entry");
        let err_g = (&jtr - &want_g).amax() / want_g.amax();
        assert!(err_g <= 1e-12, "Jᵀr off by {err_g:e}");
        let mut q = p.clone();
        q[5] += 0.1;
        assert!(prob.normal_equations(&q).is_none());
    }

    /// Kernels reused at the same τ are the ones a fresh problem computes: the
    /// joint problem's residuals and Jacobian after a projected evaluation at θ
    /// (kernels with derivatives, kept by a problem whose kernels fit
    /// [`KEPT_KERNEL_BYTES`](crate::fit::prony::problem::KEPT_KERNEL_BYTES)), after one
    /// without (the derivatives then computed), and at other τ, each the same bits
    /// as a fresh problem's; and the projection's moduli at θ from its kept Gram
    /// products ([`Projected::moduli_at`]) are a fresh projection's, cold-started,
    /// bit for bit. On curves of 300 points (one block) and 3000 (six blocks, each
    /// computed from the one before), 3 terms, whose kernels a problem keeps.
    #[test]
    fn reused_kernels_and_gram_products_are_fresh_ones() {
        for points in [300, 3000] {
            reused_kernels_are_fresh_ones(points);
        }
    }

    fn reused_kernels_are_fresh_ones(points: usize) {
        let prep = long_curve(points);
        let mut prob = prep.setup.prob.clone();
        prob.n_terms = 3;
        let (m, theta) = (prob.len(), [0.2f64.ln(), 20f64.ln(), 300f64.ln()]);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let joint_at = |prob: &mut Problem<TimeKernels>, p: &[f64]| {
            let (mut r, mut j) = (DVector::zeros(m), DMatrix::zeros(m, 7));
            assert!(prob.eval(p, &mut r, Some(&mut j)));
            (bits(r.as_slice()), bits(j.as_slice()))
        };
        let fresh = |p: &[f64]| {
            let mut f = prep.setup.prob.clone();
            f.n_terms = 3;
            joint_at(&mut f, p)
        };
        for derivatives in [true, false] {
            let mut r = DVector::zeros(m);
            let mut none = DMatrix::zeros(0, 3);
            let mut vp = Projected::new(&mut prob);
            assert!(vp.eval(&theta, &mut r, derivatives.then_some(&mut none)));
            let joint = vp.joint(&theta);
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
        let mut other = prep.setup.prob.clone();
        other.n_terms = 3;
        let mut cold = Projected::new(&mut other);
        assert!(cold.eval(&theta, &mut r, None));
        assert_eq!(bits(kept.as_slice()), bits(cold.c.as_slice()));
    }

    /// The seed's Table 3.3 as a step to strain 0.5, `points` log-spaced over
    /// 0.01–1000 s, 1 % noise, prepared.
    /// The joint problem of `long_curve(points)` with 4 terms, and its parameters
    /// (moduli over the problem's scale, ln τ) at the seed's Table 3.3 constants.
    fn four_terms_at_table_3_3(points: usize) -> (Problem<TimeKernels>, Vec<f64>) {
        let mut prob = long_curve(points).setup.prob;
        prob.n_terms = 4;
        let s = prob.scale;
        let p = [43.3e3, 106.1e3, 45.5e3, 16.1e3, 10.9e3]
            .iter()
            .map(|e| e / s)
            .chain([0.153f64, 0.464, 32.0, 216.0].iter().map(|t| t.ln()))
            .collect();
        (prob, p)
    }

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
    /// of [`BLOCK_ROWS`](crate::fit::prony::problem::BLOCK_ROWS) rows, are those of Kaufman's Jacobian Jᵢ = cᵢ·P⊥·dᵢ built
    /// explicitly (P⊥ from a QR factorisation of the positive columns) on a curve of
    /// 3000 points (six blocks), with one modulus at zero (a term at 1 ms, before
    /// the data): JᵀJ to 10⁻⁹ of its largest entry (the Gram route loses about
    /// κ(A_PᵀA_P)·ε ≈ 10⁻¹¹ here), Jᵀr to 10⁻¹⁰ of its largest.
    #[test]
    fn normal_equations_are_kaufmans_from_the_gram_products() {
        let mut prob = long_curve(3000).setup.prob;
        prob.n_terms = 4;
        let theta = [1e-3f64.ln(), 0.2f64.ln(), 20f64.ln(), 300f64.ln()];
        let m = prob.len();
        // the columns A = [w·S·x, w·S·h(τᵢ)…] and dᵢ = ∂aᵢ/∂ln τᵢ, formed whole
        let taus: Vec<f64> = theta.iter().map(|t| t.exp()).collect();
        let (mut a, mut da) = (DMatrix::zeros(m, 5), DMatrix::zeros(m, 4));
        let (x, terms) = a.as_mut_slice().split_at_mut(m);
        prob.input_column(x);
        prob.kernel_columns(&taus, terms, Some(da.as_mut_slice()));
        let mut r = DVector::zeros(m);
        let mut vp = Projected::new(&mut prob);
        assert!(vp.eval(&theta, &mut r, Some(&mut DMatrix::zeros(0, 4))));
        let (jtj, jtr) = vp.normal_equations(&theta).expect("formed at θ");
        assert!(vp.normal_equations(&[0.0; 4]).is_none());
        let pos: Vec<usize> = (0..5).filter(|&j| vp.c[j] > 0.0).collect();
        assert_eq!(pos.len(), 4, "moduli {}", vp.c);
        let ap = DMatrix::from_fn(m, pos.len(), |k, q| a[(k, pos[q])]);
        let q = ap.qr().q();
        let mut j = DMatrix::zeros(m, 4);
        for i in 0..4 {
            let d = da.column(i) * vp.c[1 + i];
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
        let grid = grid_stage(&mut prep.setup, 6).unwrap();
        let mut sub = prep.setup.prob.subsample(START_POINTS).unwrap();
        assert_eq!(grid, grid_nnls(&mut sub, prep.setup.window, 6).unwrap());
        let full = grid_nnls(&mut prep.setup.prob, prep.setup.window, 6).unwrap();
        assert_ne!(grid.1, full.1);
        let settings = Settings::default().search();
        let cost = |tf: &TermFit<TimeKernels>| {
            let mut prob = prep.setup.prob.clone();
            prob.n_terms = tf.n_terms;
            let mut r = DVector::zeros(prob.len());
            assert!(prob.eval(&tf.p, &mut r, None));
            0.5 * r.norm_squared()
        };
        let levels = Levels::new(&prep.setup.prob);
        for n in 1..=4 {
            let a = cost(&fit_terms(&prep.setup, &levels, &grid, n, &settings).unwrap());
            let b = cost(&fit_terms(&prep.setup, &levels, &full, n, &settings).unwrap());
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
