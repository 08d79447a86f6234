//! The hyperelastic estimator: coefficients of a strain-energy function from
//! uniaxial, equibiaxial and planar test data.
//!
//! * Models linear in their parameters (Neo-Hookean, Mooney-Rivlin, Yeoh): exact
//!   weighted linear least squares (SVD); with `stable`, a Clarabel QP keeps
//!   dP/dλ ≥ 0 over [`DRUCKER_RANGE`] in every mode.
//! * Ogden and Gent: bounded Levenberg-Marquardt over the nonlinear parameters with
//!   the linear ones solved exactly inside (variable projection), from a
//!   deterministic set of physically informed starts, then a full LM polish of all
//!   parameters from the best start.

use super::diagnostics;
use super::drucker::{self, DruckerCheck, DRUCKER_RANGE};
use super::identifiability;
use super::linear::{constrained_least_squares, RowQr};
use super::lm::{self, LeastSquares, LmSettings, Termination};
use super::multistart;
use super::problem::{HyperProblem, Residual, VarPro, PARALLEL_ROWS};
use super::{Parameter, SolverReport, Status};
use crate::data::{Dataset, Sample, Source};
use crate::error::{Error, Result};
use crate::material::file::{FittedRanges, HyperelasticPart, StretchRange};
use crate::material::hyperelastic::{
    AtParams, Mode, ModelSpec, OgdenForm, StrainEnergy, MODEL_NAMES,
};
use crate::report::format::Fixed;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::time::Instant;

/// Schema tag of hyperelastic fit files (the material files' reader knows it).
pub const SCHEMA: &str = crate::material::file::HYPERELASTIC_SCHEMA;

/// Estimator settings (checked by [`Settings::check`] before use).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Residual definition (default absolute, see [`Residual`]).
    pub residual: Residual,
    /// Constrain linear models to Drucker stability; pick the best stable start for
    /// nonlinear ones.
    pub stable: bool,
    /// Ogden coefficient form.
    pub ogden_form: OgdenForm,
    /// Iteration limit of each LM search.
    pub max_iterations: usize,
    /// Relative cost tolerance of the LM searches.
    pub ftol: f64,
    /// Use at most this many multi-start points (None: all).
    pub max_starts: Option<usize>,
    /// How nonlinear models search from each start (default variable projection).
    #[serde(default)]
    pub method: Search,
}

/// How a nonlinear model is searched from each multi-start point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Search {
    /// Variable projection (Golub & Pereyra 1973): LM over the nonlinear parameters
    /// only, the linear ones solved exactly at every step (default).
    #[default]
    VarPro,
    /// Plain LM over all parameters together, the linear ones started at their exact
    /// least-squares values for the start's nonlinear ones: the baseline variable
    /// projection is measured against (`dea-fit bench hyperelastic`).
    Full,
}

impl Search {
    /// The method as the solver report names it.
    pub fn describe(self) -> &'static str {
        match self {
            Search::VarPro => "variable projection + bounded Levenberg-Marquardt",
            Search::Full => "bounded Levenberg-Marquardt over all parameters",
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            residual: Residual::Abs,
            stable: false,
            ogden_form: OgdenForm::Abaqus,
            max_iterations: 200,
            ftol: 1e-12,
            max_starts: None,
            method: Search::VarPro,
        }
    }
}

impl Settings {
    /// Reject settings that cannot work.
    pub fn check(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::settings("the iteration limit must be at least 1"));
        }
        if !(self.ftol > 0.0 && self.ftol < 1.0) {
            return Err(Error::settings(format!(
                "tolerance must be in (0, 1), found {}",
                self.ftol
            )));
        }
        if self.max_starts == Some(0) {
            return Err(Error::settings("at least one start is needed"));
        }
        Ok(())
    }

    /// The settings as a fit's provenance records them (a JSON value), built once
    /// for the settings of the last fit on this thread and cloned after: the
    /// serializer costs some 3 k instructions, a clone a third of that (a run of
    /// fits mostly has the same settings).
    fn recorded(&self) -> serde_json::Value {
        thread_local! {
            static LAST: std::cell::RefCell<Option<(Settings, serde_json::Value)>> =
                const { std::cell::RefCell::new(None) };
        }
        LAST.with_borrow_mut(|last| match last {
            Some((s, v)) if s == self => v.clone(),
            _ => {
                let v = serde_json::to_value(self).unwrap_or_default();
                *last = Some((self.clone(), v.clone()));
                v
            }
        })
    }
}

/// Residual statistics of one mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeStats {
    /// Mode.
    pub mode: Mode,
    /// Points.
    pub points: usize,
    /// Smallest stretch of the data.
    pub stretch_min: f64,
    /// Largest stretch of the data.
    pub stretch_max: f64,
    /// Root-mean-square absolute error (Pa).
    #[serde(rename = "rmse_Pa")]
    pub rmse_pa: f64,
    /// Coefficient of determination of this mode (None when its stresses do not
    /// vary, e.g. one point: R² is undefined).
    pub r2: Option<f64>,
    /// The lack-of-fit test of the mode's residuals (None with fewer than
    /// [`RUNS_MIN`] residuals of either sign).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lack_of_fit: Option<LackOfFit>,
}

/// A model prediction in a mode the data does not cover.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Extrapolation {
    /// Mode without data.
    pub mode: Mode,
    /// Stretch.
    pub stretch: f64,
    /// Predicted nominal stress (Pa).
    #[serde(rename = "stress_Pa")]
    pub stress_pa: f64,
    /// Range predicted by the other models fitted to the same data (Pa), when known.
    #[serde(
        default,
        rename = "other_models_Pa",
        skip_serializing_if = "Option::is_none"
    )]
    pub other_models_pa: Option<[f64; 2]>,
}

/// One row of the `--model auto` comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Model.
    pub model: String,
    /// Number of parameters.
    pub k: usize,
    /// RMSE (Pa).
    #[serde(rename = "rmse_Pa")]
    pub rmse_pa: f64,
    /// R² (None where undefined).
    pub r2: Option<f64>,
    /// AICc (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC.
    pub bic: f64,
    /// AICc minus the smallest AICc of the models `auto` could choose from (negative
    /// for a model that fits better but is not eligible).
    pub delta_aicc: Option<f64>,
    /// Fit status.
    pub status: Status,
    /// Whether the rule ([`AUTO_RULE`]) let `auto` choose it: enough points away
    /// from λ = 1 for its parameters, and a status that does not block.
    #[serde(default)]
    pub eligible: bool,
}

/// How `--model auto` chose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// The rule, in words.
    pub rule: String,
    /// Why this model.
    pub reason: String,
    /// Every model tried.
    pub candidates: Vec<Candidate>,
}

/// Data provenance and settings of a fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// Input files with hashes, modes and stretch ranges.
    pub files: Vec<Source>,
    /// Settings used.
    pub settings: serde_json::Value,
}

/// A hyperelastic fit: what `--json` prints and what the fit file holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HyperelasticFit {
    /// Schema tag.
    pub schema: String,
    /// dea-fit version that wrote it.
    pub tool_version: String,
    /// Model name.
    pub model: String,
    /// Ogden coefficient form (Ogden models only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub form: Option<OgdenForm>,
    /// Parameters in SI.
    pub parameters: Vec<Parameter>,
    /// Small-strain shear modulus μ0 (Pa).
    #[serde(rename = "initial_shear_modulus_Pa")]
    pub initial_shear_modulus_pa: f64,
    /// RMSE over all points (Pa, unweighted).
    #[serde(rename = "rmse_Pa")]
    pub rmse_pa: f64,
    /// R² over all points (None when the stresses do not vary: undefined).
    pub r2: Option<f64>,
    /// Seed Eq. 3.28 %RMSE (RMSE over the data's stress range).
    pub rmse_pct: Option<f64>,
    /// AICc of the fitted objective (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC of the fitted objective.
    pub bic: f64,
    /// Residual definition of the objective.
    pub residual: Residual,
    /// Number of points.
    pub points: usize,
    /// Per-mode residual statistics and fitted stretch ranges.
    pub per_mode: Vec<ModeStats>,
    /// Drucker stability per mode over stretch 0.1–10.
    pub drucker: Vec<DruckerCheck>,
    /// Parameter correlation matrix (None where undefined).
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Condition number of the column-normalised Jacobian.
    pub condition_number: Option<f64>,
    /// Predictions in modes without data.
    pub extrapolation: Vec<Extrapolation>,
    /// Overall status.
    pub status: Status,
    /// Everything the user should know.
    pub warnings: Vec<String>,
    /// Solver report.
    pub solver: SolverReport,
    /// How `auto` chose this model (auto only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selection: Option<Selection>,
    /// Inputs and settings.
    pub provenance: Provenance,
}

impl HyperelasticFit {
    /// Parameter values in model order.
    pub fn values(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.value).collect()
    }

    /// The model evaluator, after checking that the parameters are the model's own:
    /// the same names in the same order, each a finite number (see [`Self::values`]).
    pub fn evaluator(&self) -> Result<Box<dyn StrainEnergy>> {
        let model = ModelSpec {
            name: self.model.clone(),
            form: self.form,
        }
        .build()?;
        let want: Vec<&str> = model.params().iter().map(|p| p.name.as_str()).collect();
        let got: Vec<&str> = self.parameters.iter().map(|p| p.name.as_str()).collect();
        if want != got {
            return Err(Error::settings(format!(
                "a {} fit needs the parameters {}, found {}",
                self.model,
                want.join(", "),
                if got.is_empty() {
                    "none".to_string()
                } else {
                    got.join(", ")
                }
            )));
        }
        model.check_params(&self.values())?;
        Ok(model)
    }

    /// The first-order standard deviation of the fitted nominal stress (Pa) in `mode`
    /// at each stretch, from the parameter covariance
    /// ([`diagnostics::propagated_std`]): the ±1σ confidence band of the fitted
    /// curve. None when a parameter has no standard error or correlation.
    pub fn stress_std(&self, mode: Mode, stretches: &[f64]) -> Option<Vec<f64>> {
        let model = self.evaluator().ok()?;
        let se: Vec<Option<f64>> = self.parameters.iter().map(|p| p.std_error).collect();
        let cov = diagnostics::covariance(&se, &self.correlation)?;
        diagnostics::propagated_std(
            |p| {
                Some(
                    stretches
                        .iter()
                        .map(|&l| model.nominal_stress(p, mode, l))
                        .collect(),
                )
            },
            &self.values(),
            &cov,
        )
    }

    /// The material part of the fit: what a scene reads from its file (model,
    /// parameters in model order, fitted stretch range per mode).
    pub fn material(&self) -> HyperelasticPart {
        HyperelasticPart {
            spec: ModelSpec::new(&self.model, self.form.unwrap_or_default()),
            params: self.values(),
            ranges: Some(FittedRanges {
                per_mode: self
                    .per_mode
                    .iter()
                    .map(|s| StretchRange {
                        mode: s.mode,
                        stretch_min: s.stretch_min,
                        stretch_max: s.stretch_max,
                    })
                    .collect(),
            }),
        }
    }
}

/// Result of the numerical search alone.
struct Estimate {
    params: Vec<f64>,
    method: String,
    starts: usize,
    starts_at_best: usize,
    iterations: usize,
    evaluations: usize,
    termination: Termination,
    notes: Vec<String>,
    /// The triangular factor of the Jacobian at `params` when the search has it
    /// (a linear model: its design matrix, the Jacobian at any parameters).
    factor: Option<RowQr>,
}

/// One start of the [`Search::Full`] baseline: LM over all parameters from the
/// start's nonlinear values, the linear ones first solved exactly at them (so both
/// methods begin at the same point). Returns (cost, parameters) if the search ended
/// finite, and the iterations taken.
fn full_search(
    prob: &mut HyperProblem,
    nonlin: &[usize],
    start: &[f64],
    bounds: &[(f64, f64)],
    lm_settings: &LmSettings,
) -> (Option<(f64, Vec<f64>)>, usize) {
    let mut full = vec![1.0; bounds.len()];
    for (&j, &v) in nonlin.iter().zip(start) {
        full[j] = v;
    }
    let mut vp = VarPro::new(prob, &full);
    let mut r = DVector::zeros(vp.inner.len());
    if !vp.eval(start, &mut r, None) {
        return (None, 0);
    }
    let p0 = vp.full.clone();
    let res = lm::minimize(prob, &p0, bounds, lm_settings);
    (
        res.cost.is_finite().then_some((res.cost, res.x)),
        res.iterations,
    )
}

/// ("n points", " (m of them away from λ = 1, ...)" when not all are, else "").
fn points_phrase(data: &Dataset) -> (String, String) {
    let (n, m) = (data.samples.len(), data.informative_points());
    (
        format!("{n} point{}", if n == 1 { "" } else { "s" }),
        if m < n {
            format!(" ({m} of them away from λ = 1, where every model gives zero stress)")
        } else {
            String::new()
        },
    )
}

/// Fewer informative points (away from λ = 1) than parameters: the design is
/// rank-deficient whatever the data say.
fn too_few(data: &Dataset, model: &dyn StrainEnergy) -> Option<Error> {
    let k = model.params().len();
    (data.informative_points() < k).then(|| {
        let (n, why) = points_phrase(data);
        Error::settings(format!(
            "{n} cannot determine {k} parameters of {}{why}",
            model.name()
        ))
        .with_hint("add data or choose a model with fewer parameters (neo-hookean has 1)")
    })
}

/// The search on `full`, the problem of all the data: a linear model is solved
/// exactly on it; a nonlinear one searches it with repeated points merged.
fn estimate(
    model: &dyn StrainEnergy,
    full: &mut HyperProblem,
    data: &Dataset,
    s: &Settings,
) -> Result<Estimate> {
    if let Some(e) = too_few(data, model) {
        return Err(e);
    }
    let k = model.params().len();
    if model.linear_in_params() && !s.stable {
        // One pass over the rows: the factor of [A | b] is the whole problem, and A is
        // the Jacobian the diagnostics need.
        let factor = full.factor(&vec![0.0; k]);
        let c = factor.solve().ok_or_else(|| {
            Error::settings("the data determine none of the model's parameters (all-zero design)")
        })?;
        return Ok(Estimate {
            params: c.iter().copied().collect(),
            method: "linear least squares (QR, SVD of R)".into(),
            starts: 1,
            starts_at_best: 1,
            iterations: 0,
            evaluations: 1,
            termination: Termination::Converged("exact"),
            notes: Vec::new(),
            factor: Some(factor),
        });
    }
    let mut merged = full.merge_repeats();
    let prob = merged.as_mut().unwrap_or(full);
    let n = prob.len();
    if model.linear_in_params() {
        // --stable: the least-squares problem under the Drucker constraints.
        let mut a = DMatrix::zeros(n, k);
        prob.jacobian(&vec![0.0; k], &mut a);
        let b = prob.scaled_targets();
        {
            let grid = drucker::drucker_grid();
            let mut g = DMatrix::zeros(grid.len(), k);
            let mut e = vec![0.0; k];
            for j in 0..k {
                e.iter_mut().for_each(|v| *v = 0.0);
                e[j] = 1.0;
                for (i, &(m, l)) in grid.iter().enumerate() {
                    g[(i, j)] = model.tangent(&e, m, l);
                }
            }
            let qp = constrained_least_squares(&a, &b, &g).map_err(|e| {
                Error::settings(format!("the stability-constrained fit failed: {e}"))
            })?;
            let mut notes = Vec::new();
            if qp.active > 0 {
                notes.push(format!(
                    "--stable: {} stability constraint(s) active; the fit is stable by construction but worse than the unconstrained optimum",
                    qp.active
                ));
            }
            return Ok(Estimate {
                params: qp.x.iter().copied().collect(),
                method: "stability-constrained linear least squares (Clarabel QP)".into(),
                starts: 1,
                starts_at_best: 1,
                iterations: qp.iterations as usize,
                evaluations: 1,
                termination: Termination::Converged("interior point"),
                notes,
                factor: None,
            });
        }
    }

    // Nonlinear: variable projection over the nonlinear parameters, multi-start.
    let max_x = prob.max_i1_minus_3();
    let bounds = model.bounds(max_x);
    let mut starts = model.nonlinear_starts(max_x);
    if let Some(m) = s.max_starts {
        starts.truncate(m);
    }
    let lm_settings = LmSettings {
        max_iterations: s.max_iterations,
        ftol: s.ftol,
        ..LmSettings::default()
    };
    let nonlin: Vec<usize> = (0..k).filter(|&j| !model.params()[j].linear).collect();
    let theta_bounds: Vec<(f64, f64)> = nonlin.iter().map(|&j| bounds[j]).collect();
    // The starts search a subsample of at most STARTS_PER_MODE points per mode (all
    // the data when no mode has more): their cost no longer grows with n.
    let mut sub = prob.subsample(STARTS_PER_MODE);
    let mut results = Vec::with_capacity(starts.len());
    let mut iterations = 0;
    {
        let prob = sub.as_mut().unwrap_or(&mut *prob);
        let n = prob.len();
        for start in &starts {
            if s.method == Search::Full {
                let (found, its) = full_search(prob, &nonlin, start, &bounds, &lm_settings);
                iterations += its;
                results.extend(found);
                continue;
            }
            let mut theta = start.clone();
            let mut escapes = 0;
            loop {
                let mut full = vec![1.0; k];
                for (&j, &v) in nonlin.iter().zip(&theta) {
                    full[j] = v;
                }
                let mut vp = VarPro::new(prob, &full);
                let res = lm::minimize(&mut vp, &theta, &theta_bounds, &lm_settings);
                iterations += res.iterations;
                // Recompute the projected linear coefficients at the final θ.
                let mut r = DVector::zeros(n);
                let ok = vp.eval(&res.x, &mut r, None);
                // Coinciding exponents make the basis (nearly) rank-deficient: an
                // (N−1)-term model in disguise, a saddle of the N-term objective.
                // Separate them and search on.
                if ok && escapes < MAX_ESCAPES {
                    if let Some(split) = split_coincident(&res.x, &theta_bounds) {
                        theta = split;
                        escapes += 1;
                        continue;
                    }
                }
                if ok && res.cost.is_finite() {
                    results.push((res.cost, vp.full.clone()));
                }
                break;
            }
        }
    }
    if results.is_empty() {
        return Ok(Estimate {
            params: vec![f64::NAN; k],
            method: s.method.describe().into(),
            starts: starts.len(),
            starts_at_best: 0,
            iterations,
            evaluations: prob.evaluations,
            termination: Termination::Failed("no start gave a finite fit".into()),
            notes: Vec::new(),
            factor: None,
        });
    }
    let mut notes = Vec::new();
    let stable_ok = |p: &[f64]| drucker::drucker(model, p).iter().all(|d| d.stable);
    let best_cost = results.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
    let at_best = multistart::starts_at_best(
        &results.iter().map(|r| r.0).collect::<Vec<_>>(),
        lm_settings.min_decrease,
    );
    let chosen = if s.stable {
        let mut stable: Vec<&(f64, Vec<f64>)> =
            results.iter().filter(|r| stable_ok(&r.1)).collect();
        stable.sort_by(|a, b| a.0.total_cmp(&b.0));
        match stable.first() {
            Some(r) => {
                if r.0 > best_cost * (1.0 + multistart::AT_BEST_REL) {
                    notes.push(format!(
                        "--stable: the best Drucker-stable start has cost {:.4e}, above the unconstrained best {:.4e}",
                        r.0, best_cost
                    ));
                }
                r.1.clone()
            }
            None => {
                notes.push(
                    "--stable: no start ended Drucker-stable; the best fit is reported".into(),
                );
                results
                    .iter()
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .expect("non-empty")
                    .1
                    .clone()
            }
        }
    } else {
        results
            .iter()
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("non-empty")
            .1
            .clone()
    };
    // The starts searched a subsample: carry the chosen point to all the data by the
    // same search (variable projection from its nonlinear parameters; the full-LM
    // polish below does it for a full search), kept if it lowers the cost there.
    let mut evaluations_sub = sub.as_ref().map_or(0, |p| p.evaluations);
    let chosen = match &sub {
        Some(_) if s.method != Search::Full && !s.stable => {
            // The subsample's best basins (its REFINED best distinct ends), each carried
            // through subsamples ten times larger (each level starts next to its
            // optimum); the lowest cost on the largest subsample wins, and only that
            // point is carried to all the data: the work on all n points is one search.
            let mut ends: Vec<&(f64, Vec<f64>)> = results.iter().collect();
            ends.sort_by(|a, b| a.0.total_cmp(&b.0));
            ends.dedup_by(|b, a| (b.0 - a.0).abs() <= 1e-9 * a.0.abs());
            let mut best: Option<(f64, Vec<f64>)> = None;
            for (cost, end) in ends.into_iter().take(REFINED) {
                let (mut point, mut cost) = (end.clone(), *cost);
                let mut per_mode = 10 * STARTS_PER_MODE;
                while let Some(mut level) = prob.subsample(per_mode) {
                    let its;
                    (point, its) = refine(&mut level, point, &nonlin, &theta_bounds, &lm_settings);
                    iterations += its;
                    evaluations_sub += level.evaluations;
                    let mut r = DVector::zeros(level.len());
                    level.residuals(&point, &mut r);
                    // Costs compare only on one level: the last one reached, the same
                    // for every end.
                    cost = r.norm_squared();
                    per_mode *= 10;
                }
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, point));
                }
            }
            match best {
                Some((_, point)) => {
                    let (point, its) = refine(prob, point, &nonlin, &theta_bounds, &lm_settings);
                    iterations += its;
                    point
                }
                None => chosen,
            }
        }
        Some(_) if s.method != Search::Full => {
            // --stable: the chosen stable point, carried to all the data.
            refine(prob, chosen, &nonlin, &theta_bounds, &lm_settings).0
        }
        _ => chosen,
    };
    // Polish all parameters together from the chosen point.
    let polish = lm::minimize(prob, &chosen, &bounds, &lm_settings);
    let params = if polish.cost.is_finite()
        && polish.cost
            <= 0.5
                * {
                    let mut r = DVector::zeros(n);
                    prob.residuals(&chosen, &mut r);
                    r.norm_squared()
                }
                * (1.0 + 1e-9)
    {
        polish.x.clone()
    } else {
        chosen
    };
    Ok(Estimate {
        params,
        method: format!("{}, multi-start, full LM polish", s.method.describe()),
        starts: starts.len(),
        starts_at_best: at_best,
        iterations: iterations + polish.iterations,
        evaluations: prob.evaluations + evaluations_sub,
        termination: polish.termination,
        notes,
        factor: None,
    })
}

/// RMSE relative to the largest |stress| below which a fit is too good to be a fit of
/// measured data: a 24-bit load-cell reading resolves 6e-8 of full scale and the
/// scatter of a tensile test is ≥ 1e-5 of its largest force, while the rounding of an
/// exact synthetic set is ≈ 1e-15. 1e-9 lies orders below the first two and above
/// the last, so it flags both interpolation and noise-free data.
pub const TOO_GOOD: f64 = 1e-9;

/// Points per mode on which the multi-start search runs: a mode with more is
/// subsampled evenly in stretch ([`HyperProblem::subsample`]) and only the chosen start
/// is carried to all the data. Every shipped dataset has fewer points per mode, so its
/// fits are searched on all of it.
pub const STARTS_PER_MODE: usize = 40;

/// Distinct ends of the subsample's search carried through the larger subsamples:
/// the landscape of an Ogden model is flat and several-basined, and the smallest
/// subsample's best basin need not be the data's. The best of them on the largest
/// subsample goes on to all the data.
const REFINED: usize = 3;

/// The variable-projection search on `prob` from the full parameter vector `start`
/// (its nonlinear parameters are the start; the linear ones are projected): the
/// point it ends at if that lowers the cost on `prob`, else `start`; and the
/// iterations taken.
fn refine(
    prob: &mut HyperProblem,
    start: Vec<f64>,
    nonlin: &[usize],
    theta_bounds: &[(f64, f64)],
    lm_settings: &LmSettings,
) -> (Vec<f64>, usize) {
    let theta: Vec<f64> = nonlin.iter().map(|&j| start[j]).collect();
    let mut vp = VarPro::new(prob, &start);
    let res = lm::minimize(&mut vp, &theta, theta_bounds, lm_settings);
    let mut r = DVector::zeros(vp.dims().0);
    let ok = vp.eval(&res.x, &mut r, None) && res.cost.is_finite();
    let refined = vp.full.clone();
    let mut cost = |p: &[f64]| {
        prob.residuals(p, &mut r);
        r.norm_squared()
    };
    if ok && cost(&refined) <= cost(&start) {
        (refined, res.iterations)
    } else {
        (start, res.iterations)
    }
}

/// Restarts allowed per start to escape a degenerate (coinciding-exponent) point.
const MAX_ESCAPES: usize = 2;

/// Move the second of each pair of coinciding nonlinear parameters to the candidate
/// value farthest from all others (within bounds); None if nothing coincides.
fn split_coincident(x: &[f64], bounds: &[(f64, f64)]) -> Option<Vec<f64>> {
    const CANDIDATES: [f64; 5] = [-2.0, 1.0, 2.5, 5.0, 8.0];
    let mut y = x.to_vec();
    let mut changed = false;
    for i in 0..y.len() {
        for j in i + 1..y.len() {
            if (y[i] - y[j]).abs() <= 1e-3 * (1.0 + y[i].abs()) {
                let best = CANDIDATES
                    .iter()
                    .map(|&c| lm::project(c, bounds[j]))
                    .max_by(|a, b| {
                        let d = |c: f64| {
                            y.iter()
                                .enumerate()
                                .filter(|&(m, _)| m != j)
                                .map(|(_, v)| (v - c).abs())
                                .fold(f64::INFINITY, f64::min)
                        };
                        d(*a).total_cmp(&d(*b))
                    })?;
                y[j] = best;
                changed = true;
            }
        }
    }
    changed.then_some(y)
}

/// Unweighted absolute-residual statistics of (prediction, measurement) pairs, read
/// twice in order (the count, Σy and Σ(p − y)² in the first pass, each summed in
/// the order of the pairs; Σ(y − ȳ)² in the second): (points, rmse, r², None when
/// y does not vary).
fn stats(pairs: impl Iterator<Item = (f64, f64)> + Clone) -> (usize, f64, Option<f64>) {
    let (count, sum_y, ss_res) = pairs.clone().fold((0usize, 0.0, 0.0), |(c, s, r), (p, y)| {
        (c + 1, s + y, r + (p - y).powi(2))
    });
    let n = count as f64;
    let mean = sum_y / n;
    let ss_tot: f64 = pairs.map(|(_, y)| (y - mean).powi(2)).sum();
    (
        count,
        (ss_res / n).sqrt(),
        (ss_tot > 0.0).then(|| 1.0 - ss_res / ss_tot),
    )
}

/// The largest |p_j·∂P/∂p_j| of each parameter over the data, in one pass: for a
/// linear coefficient, the largest stress its term contributes (P = Σ c_j·∂P/∂c_j).
fn largest_contributions(model: &dyn StrainEnergy, p: &[f64], data: &Dataset) -> Vec<f64> {
    let mut row = vec![0.0; p.len()];
    let mut largest = vec![0.0f64; p.len()];
    for s in &data.samples {
        model.stress_jacobian(p, s.mode, s.stretch, &mut row);
        for ((m, d), v) in largest.iter_mut().zip(&row).zip(p) {
            *m = m.max((d * v).abs());
        }
    }
    largest
}

/// The model's nominal stress at every sample ([`AtParams::stress`], made once per
/// mode).
fn predictions(model: &dyn StrainEnergy, p: &[f64], samples: &[Sample]) -> Vec<f64> {
    let at = Mode::ALL.map(|m| AtParams::new(model, p, m));
    let one = |s: &Sample| at[s.mode.index()].stress(model, p, s.stretch);
    if samples.len() < PARALLEL_ROWS {
        samples.iter().map(one).collect()
    } else {
        samples.par_iter().map(one).collect()
    }
}

/// Fit one model to the data.
pub fn fit(data: &Dataset, spec: &ModelSpec, settings: &Settings) -> Result<HyperelasticFit> {
    settings.check()?;
    data.check()?;
    let model = spec.build()?;
    let model = model.as_ref();
    let t0 = Instant::now();
    let mut prob = HyperProblem::new(model, data, settings.residual);
    let mut est = estimate(model, &mut prob, data, settings)?;
    let seconds = t0.elapsed().as_secs_f64();
    let p = est.params.clone();
    let (n, k) = (prob.len(), p.len());
    // Predictions once: the residuals and every statistic below come from them.
    let factor = est.factor.take().unwrap_or_else(|| prob.factor(&p));
    let pred = predictions(model, &p, &data.samples);
    // The measured stresses, as the problem holds them.
    let y = &prob.stress;
    let r = DVector::from_fn(n, |i, _| prob.scale[i] * (pred[i] - y[i]));
    let finite = r.iter().all(|v| v.is_finite());
    let rss = r.norm_squared();
    let unc = diagnostics::factor_uncertainty(&factor, rss);
    let (_, rmse, r2) = stats(pred.iter().copied().zip(y.iter().copied()));
    let (aicc, bic) = diagnostics::information_criteria(rss, n, k);
    let mut warnings = est.notes.clone();
    let mut status = Status::Ok;

    // Per-mode statistics and fitted ranges.
    let per_mode: Vec<ModeStats> = data
        .modes()
        .into_iter()
        .map(|m| {
            let (points, rm, r2m) = stats(
                data.samples
                    .iter()
                    .zip(pred.iter().zip(y))
                    .filter(move |(s, _)| s.mode == m)
                    .map(|(_, (&p, &y))| (p, y)),
            );
            let (lo, hi) = data.stretch_range(m).expect("mode present");
            let in_mode = || {
                data.samples
                    .iter()
                    .zip(pred.iter().zip(y))
                    .filter(move |(s, _)| s.mode == m)
            };
            let lack_of_fit = runs_test(in_mode().map(|(s, (p, y))| (s.stretch, p - y)).collect())
                .map(|runs| {
                    let noise_pa = noise_sigma(
                        &in_mode()
                            .map(|(s, (_, y))| (s.stretch, *y))
                            .collect::<Vec<_>>(),
                    );
                    LackOfFit {
                        runs,
                        noise_pa,
                        lacks_fit: runs.p < RUNS_ALPHA
                            && noise_pa.is_none_or(|s| rm > LACK_OF_FIT_RATIO * s),
                    }
                });
            ModeStats {
                mode: m,
                points,
                stretch_min: lo,
                stretch_max: hi,
                rmse_pa: rm,
                r2: r2m,
                lack_of_fit,
            }
        })
        .collect();
    // What the reader and the sanity checks found ([`prepare`]).
    for source in &data.sources {
        let name = std::path::Path::new(&source.path)
            .file_name()
            .map_or_else(|| source.path.clone(), |n| n.to_string_lossy().into_owned());
        warnings.extend(source.notes.iter().map(|n| format!("{name}: {n}")));
        for w in &source.warnings {
            status.escalate(Status::Warning);
            warnings.push(format!("{name}: {w}"));
        }
    }
    // Lack of fit: structured residuals well above the noise.
    for s in &per_mode {
        let Some(l) = s.lack_of_fit.filter(|l| l.lacks_fit) else {
            continue;
        };
        status.escalate(Status::Warning);
        let noise = match l.noise_pa {
            Some(n) => format!(
                ", and the RMSE {} Pa is {:.1} times the noise σ = {} Pa of the data",
                Fixed(s.rmse_pa, 4),
                s.rmse_pa / n.max(f64::MIN_POSITIVE),
                Fixed(n, 3)
            ),
            None => String::new(),
        };
        warnings.push(format!(
            "lack of fit in {}: the residuals keep their sign over long stretches of the curve (runs test: {} runs where {:.1} are expected of noise, z = {:.2}, p = {:.1e}){noise}; {} misses the shape of the data (R² {}): a break, a load–unload cycle, a preload, or a model too simple?",
            s.mode,
            l.runs.runs,
            l.runs.expected_runs,
            l.runs.z,
            l.runs.p,
            model.name(),
            s.r2.map_or("n/a".into(), |v| format!("{v:.4}"))
        ));
    }

    // Convergence.
    if let Some(w) = est.termination.shortfall() {
        status.escalate(Status::NotConverged);
        warnings.push(w);
    }
    if !finite {
        status.escalate(Status::NotConverged);
        warnings.push("the model gives no finite stress at some data points".into());
    }

    // Identifiability.
    let params_info = model.params();
    if unc.std_error.iter().any(Option::is_none) && n > k {
        status.escalate(Status::IllPosed);
        warnings.push(format!(
            "parameters not identifiable from these data (condition number {:.2e}); fewer parameters or more modes are needed",
            unc.condition
        ));
    } else if unc.condition > 1e6 {
        status.escalate(Status::Warning);
        warnings.push(format!(
            "ill-conditioned: condition number {:.2e}; the parameters are poorly determined individually",
            unc.condition
        ));
    }
    if let Some(w) = r2.and_then(diagnostics::worse_than_mean) {
        status.escalate(Status::IllPosed);
        warnings.push(w);
    }
    if data.informative_points() <= k {
        status.escalate(Status::IllPosed);
        let (n, why) = points_phrase(data);
        warnings.push(format!(
            "{n} for {k} parameters{why}: no degrees of freedom left for uncertainty, and the model may pass through every point"
        ));
    }
    // Residuals below what any real test resolves: the data are model-generated
    // (synthetic, smoothed) or the model interpolates them.
    let y_max = y.iter().map(|v| v.abs()).fold(0.0, f64::max);
    if rmse < TOO_GOOD * y_max {
        status.escalate(Status::Warning);
        warnings.push(format!(
            "the model reproduces the data to {:.1e} of the largest stress, far below the noise of any real test: the data are model-generated (synthetic or smoothed) or the model interpolates them, and the standard errors do not measure a test's scatter",
            rmse / y_max
        ));
    }
    // The one rule for "identifiable" (fit::identifiability), for every parameter:
    // a coefficient the law lets take either sign (every linear one: C01, C20, an
    // Ogden μᵢ; and an Ogden αᵢ) must also have an interval that excludes 0.
    let names: Vec<String> = params_info.iter().map(|i| i.name.clone()).collect();
    let sign_free: Vec<bool> = params_info
        .iter()
        .map(|i| i.lower < 0.0 && i.upper > 0.0)
        .collect();
    let judgement = diagnostics::judge(&names, &p, &unc, &sign_free, &vec![false; k]);
    for w in &judgement.findings {
        status.escalate(Status::IllPosed);
        warnings.push(w.clone());
    }
    for w in &judgement.warnings {
        status.escalate(Status::Warning);
        warnings.push(w.clone());
    }
    // The bounds of the nonlinear parameters (a pass over the data: only when any).
    let nonlinear = params_info.iter().any(|info| !info.linear);
    let bounds = if nonlinear {
        model.bounds(prob.max_i1_minus_3())
    } else {
        Vec::new()
    };
    let mut ran_to_bound = vec![false; k];
    for (j, info) in params_info.iter().enumerate() {
        if info.linear {
            continue;
        }
        let (lo, hi) = bounds[j];
        let span = (hi - lo).abs();
        if span.is_finite() && ((p[j] - lo).abs() < 1e-6 * span || (hi - p[j]).abs() < 1e-6 * span)
        {
            ran_to_bound[j] = true;
            status.escalate(Status::IllPosed);
            warnings.push(format!(
                "{} ran to its bound ({}): the data do not determine it (ill_posed)",
                info.name,
                Fixed(p[j], 4)
            ));
        }
    }
    // Vanishing terms: a linear coefficient whose contribution is negligible.
    if k > 1 && model.name().starts_with("ogden") {
        let largest = largest_contributions(model, &p, data);
        for (info, contrib) in params_info.iter().zip(&largest) {
            if info.linear && *contrib < 1e-3 * y_max {
                status.escalate(Status::IllPosed);
                warnings.push(format!(
                    "{} is negligible (its term contributes < 0.1 % of the largest stress): a term too many for these data",
                    info.name
                ));
            }
        }
    }

    // Drucker stability.
    let drucker = drucker::drucker(model, &p);
    for d in &drucker {
        if d.stable {
            continue;
        }
        let in_data = per_mode.iter().find(|s| s.mode == d.mode).is_some_and(|s| {
            d.unstable
                .iter()
                .any(|[a, b]| *a <= s.stretch_max && *b >= s.stretch_min)
        });
        let ranges: Vec<String> = d
            .unstable
            .iter()
            .map(|[a, b]| format!("{}–{}", Fixed(*a, 3), Fixed(*b, 3)))
            .collect();
        if in_data {
            status.escalate(Status::Unstable);
            warnings.push(format!(
                "Drucker-unstable in {} within the data's stretch range (dP/dλ ≤ 0 at {})",
                d.mode,
                ranges.join(", ")
            ));
        } else {
            status.escalate(Status::Warning);
            warnings.push(format!(
                "Drucker-unstable in {} at stretch {} (outside the data; checked {}–{}); stable for {}–{}",
                d.mode,
                ranges.join(", "),
                DRUCKER_RANGE.0,
                DRUCKER_RANGE.1,
                Fixed(d.stretch_min, 3),
                Fixed(d.stretch_max, 3)
            ));
        }
    }

    // Extrapolation to modes without data.
    let lam_max = data.samples.iter().map(|s| s.stretch).fold(1.0, f64::max);
    let mut extrapolation = Vec::new();
    for m in Mode::ALL {
        if per_mode.iter().any(|s| s.mode == m) {
            continue;
        }
        let top = if m == Mode::Equibiaxial {
            lam_max.min(4.0)
        } else {
            lam_max
        };
        for i in 1..=4 {
            let l = 1.0 + (top - 1.0) * i as f64 / 4.0;
            let stress_pa = model.nominal_stress(&p, m, l);
            if !stress_pa.is_finite() {
                // Beyond the model's extensibility limit (Gent): no stress to list.
                status.escalate(Status::Warning);
                warnings.push(format!(
                    "{} gives no finite {m} stress from λ = {} on (beyond its extensibility limit): the fitted limit lies inside the {m} range of interest",
                    model.name(),
                    Fixed(l, 2)
                ));
                break;
            }
            extrapolation.push(Extrapolation {
                mode: m,
                stretch: l,
                stress_pa,
                other_models_pa: None,
            });
        }
        if m == Mode::Equibiaxial {
            status.escalate(Status::Warning);
            let mut w = String::from(
                "no equibiaxial data: equibiaxial stress (the state of a compressed stack layer) is extrapolated",
            );
            if let Some(e) = extrapolation.iter().rfind(|e| e.mode == m) {
                // Writing to a String cannot fail.
                let _ = write!(
                    w,
                    " — the model predicts {} MPa at λ = {}",
                    Fixed(e.stress_pa / 1e6, 4),
                    Fixed(e.stretch, 2)
                );
            }
            warnings.push(w);
        }
    }

    let parameters = params_info
        .iter()
        .zip(&p)
        .zip(&unc.std_error)
        .enumerate()
        .map(|(j, ((info, &v), se))| Parameter {
            name: info.name.clone(),
            value: v,
            unit: info.unit.to_string(),
            std_error: *se,
            ci95: se.zip(unc.t95).map(|(s, t)| [v - t * s, v + t * s]),
            identifiable: Some(judgement.identifiable(j) && !ran_to_bound[j]),
        })
        .collect();
    if let Some(what) = [
        ("a parameter", p.iter().all(|v| v.is_finite())),
        ("the RMSE", rmse.is_finite()),
        ("μ0", model.initial_shear_modulus(&p).is_finite()),
    ]
    .iter()
    .find_map(|(what, ok)| (!ok).then_some(*what))
    {
        let why = match &est.termination {
            Termination::Failed(w) => format!(" ({w})"),
            _ => String::new(),
        };
        return Err(Error::settings(format!(
            "the {} fit gave no finite result: {what} is not finite{why}",
            model.name()
        ))
        .with_hint("check the data for outliers or choose another model"));
    }
    let termination = est.termination.to_string();
    Ok(HyperelasticFit {
        schema: SCHEMA.into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        model: model.name(),
        form: spec.form,
        parameters,
        initial_shear_modulus_pa: model.initial_shear_modulus(&p),
        rmse_pa: rmse,
        r2,
        rmse_pct: diagnostics::rmse_percent(rmse, y),
        aicc,
        bic,
        residual: settings.residual,
        points: n,
        per_mode,
        drucker,
        correlation: unc.correlation,
        condition_number: unc.condition.is_finite().then_some(unc.condition),
        extrapolation,
        status,
        warnings,
        solver: SolverReport {
            method: est.method,
            starts: est.starts,
            starts_at_best: est.starts_at_best,
            iterations: est.iterations,
            evaluations: est.evaluations,
            seconds,
            termination,
        },
        selection: None,
        provenance: Provenance {
            files: data.sources.clone(),
            settings: settings.recorded(),
        },
    })
}

/// The rule `auto` applies ("identifiable": every parameter by
/// [`identifiability::RULE`], which the selection's rule states after it).
pub const AUTO_RULE: &str = "among models with at least k + 2 points away from λ = 1 (AICc defined, and at least two degrees of freedom beyond an interpolation of the data) that converged, are identifiable and are Drucker-stable over the data, take the fewest parameters within ΔAICc ≤ 2 of the smallest AICc";

/// [`AUTO_RULE`] with the rule for "identifiable" ([`identifiability::RULE`]; a
/// parameter the law lets take either sign also with an interval that excludes 0).
pub fn auto_rule() -> String {
    format!(
        "{AUTO_RULE}. Identifiable: {}; a parameter that may take either sign also needs a 95 % interval that excludes 0",
        identifiability::RULE
    )
}

/// ΔAICc below which models count as fitting the data about equally well when their
/// extrapolations are compared (Burnham & Anderson: ΔAIC > 10 means essentially no support).
pub const EQUALLY_GOOD: f64 = 10.0;

/// Why `auto` may not choose a fitted model, if it may not: too few informative
/// points for its k (AICc needs n > k + 1; with n ≤ k + 1 points away from λ = 1 a
/// model comes within one degree of freedom of passing through every point, and
/// its residuals say nothing about the noise), or a blocking status.
fn ineligible(f: &HyperelasticFit, informative: usize) -> Option<String> {
    let k = f.parameters.len();
    if informative < k + 2 {
        Some(format!(
            "{informative} points away from λ = 1 for {k} parameters; it needs at least {}",
            k + 2
        ))
    } else {
        f.status
            .is_blocking()
            .then(|| format!("status {}", f.status))
    }
}

/// Fit every model (in parallel) and choose the simplest the data support.
/// Returns the chosen fit (with its `selection`) and all fits.
pub fn fit_auto(
    data: &Dataset,
    settings: &Settings,
) -> Result<(HyperelasticFit, Vec<HyperelasticFit>)> {
    settings.check()?;
    data.check()?;
    let m = data.informative_points();
    let specs: Vec<ModelSpec> = MODEL_NAMES
        .iter()
        .map(|name| ModelSpec::new(name, settings.ogden_form))
        .collect();
    // Models with k ≤ m are fitted (and shown); only those with k + 2 ≤ m may be chosen.
    let results: Vec<(String, Result<HyperelasticFit>)> = specs
        .par_iter()
        .filter(|s| s.build().map(|x| x.params().len() <= m).unwrap_or(false))
        .map(|s| (s.name.clone(), fit(data, s, settings)))
        .collect();
    // A model that gives no usable fit drops out of the comparison and says why.
    let mut fits = Vec::new();
    let mut failed = Vec::new();
    for (name, r) in results {
        match r {
            Ok(f) => fits.push(f),
            Err(e) => failed.push(format!("{name} ({e})")),
        }
    }
    let counted: Vec<&HyperelasticFit> = fits
        .iter()
        .filter(|f| f.parameters.len() + 2 <= m)
        .collect();
    if counted.is_empty() && m >= 3 {
        return Err(Error::settings(format!(
            "no model gave a usable fit: {}",
            failed.join("; ")
        )));
    }
    if counted.is_empty() {
        let (n, why) = points_phrase(data);
        return Err(Error::settings(format!(
            "{n}{why} are too few to choose a model: the simplest (neo-hookean, 1 parameter) needs 3 away from λ = 1"
        ))
        .with_hint("add data, or name a model with --model (its fit is then marked ill_posed)"));
    }
    // Every model in `counted` has n ≥ m ≥ k + 2 points, so its AICc is defined.
    let aicc = |f: &HyperelasticFit| f.aicc.unwrap_or(f64::INFINITY);
    let eligible: Vec<&HyperelasticFit> = counted
        .iter()
        .copied()
        .filter(|f| !f.status.is_blocking())
        .collect();
    let all_blocked = eligible.is_empty();
    let pool = if all_blocked { &counted } else { &eligible };
    let best = pool
        .iter()
        .copied()
        .min_by(|a, b| aicc(a).total_cmp(&aicc(b)))
        .expect("the pool is not empty");
    let chosen = pool
        .iter()
        .copied()
        .filter(|f| aicc(f) <= aicc(best) + 2.0)
        .min_by(|a, b| {
            a.parameters
                .len()
                .cmp(&b.parameters.len())
                .then(aicc(a).total_cmp(&aicc(b)))
        })
        .expect("best is within 2 of itself");
    let mut reason = if std::ptr::eq(chosen, best) {
        format!(
            "{} has the smallest AICc ({:.2}) of the {} models, and none with fewer parameters is within ΔAICc ≤ 2 of it",
            chosen.model,
            aicc(chosen),
            if all_blocked { "sufficiently sampled" } else { "eligible" }
        )
    } else {
        format!(
            "{} ({} parameter{}) is within ΔAICc = {:.2} of the smallest AICc ({}, {} parameters); the extra parameters are not supported by the data",
            chosen.model,
            chosen.parameters.len(),
            if chosen.parameters.len() == 1 { "" } else { "s" },
            aicc(chosen) - aicc(best),
            best.model,
            best.parameters.len()
        )
    };
    if all_blocked {
        reason.push_str(&format!(
            "; no model passed every check, so the choice carries its status ({})",
            chosen.status
        ));
    }
    let excluded: Vec<String> = fits
        .iter()
        .filter_map(|f| ineligible(f, m).map(|why| format!("{} ({why})", f.model)))
        .chain(failed)
        .collect();
    if !excluded.is_empty() {
        reason.push_str(&format!("; not eligible: {}", excluded.join(", ")));
    }
    let candidates = fits
        .iter()
        .map(|f| Candidate {
            model: f.model.clone(),
            k: f.parameters.len(),
            rmse_pa: f.rmse_pa,
            r2: f.r2,
            aicc: f.aicc,
            bic: f.bic,
            delta_aicc: f.aicc.map(|a| a - aicc(best)),
            status: f.status,
            eligible: ineligible(f, m).is_none(),
        })
        .collect();
    let mut out = (*chosen).clone();
    // Spread of the other models' predictions where the data say nothing.
    for e in &mut out.extrapolation {
        let preds: Vec<f64> = eligible
            .iter()
            .filter(|f| aicc(f) <= aicc(best) + EQUALLY_GOOD)
            .filter_map(|f| {
                f.evaluator()
                    .ok()
                    .map(|m| m.nominal_stress(&f.values(), e.mode, e.stretch))
            })
            .filter(|v| v.is_finite())
            .collect();
        if !preds.is_empty() {
            e.other_models_pa = Some([
                preds.iter().copied().fold(f64::INFINITY, f64::min),
                preds.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ]);
        }
    }
    if let Some(e) = out
        .extrapolation
        .iter()
        .rfind(|e| e.mode == Mode::Equibiaxial)
    {
        if let Some([lo, hi]) = e
            .other_models_pa
            .filter(|[lo, hi]| hi - lo > 1e-6 * hi.abs())
        {
            out.warnings.push(format!(
                "the models that fit these data equally well disagree in equibiaxial: {:.4}–{:.4} MPa at λ = {:.2}",
                lo / 1e6,
                hi / 1e6,
                e.stretch
            ));
        }
    }
    out.selection = Some(Selection {
        rule: auto_rule(),
        reason,
        candidates,
    });
    Ok((out, fits))
}

// ---------------------------------------------------------------------------------
// Data sanity: breaks, load–unload cycles, preload offsets, a stretch window, and
// the lack-of-fit test of the residuals.
// ---------------------------------------------------------------------------------

/// Which part of a record whose stretch reverses (a load–unload cycle) is fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Branch {
    /// From the start to the largest stretch (default).
    #[default]
    Loading,
    /// From the largest stretch to the end.
    Unloading,
    /// Every point.
    All,
}

impl std::fmt::Display for Branch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Branch::Loading => "loading",
            Branch::Unloading => "unloading",
            Branch::All => "all",
        })
    }
}

/// What to do with a curve that is not one clean loading curve (`dea-fit
/// hyperelastic --branch --until-break --zero-offset --stretch-range`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sanity {
    /// The branch to fit of a record whose stretch reverses; None: the loading
    /// branch, and a warning says so.
    pub branch: Option<Branch>,
    /// Cut a curve that ends in a break after its peak stress.
    pub until_break: bool,
    /// Remove the stress at λ = 1 (a preload) from each curve.
    pub zero_offset: bool,
    /// Fit only the points with a stretch in this closed range.
    pub stretch_range: Option<(f64, f64)>,
}

/// A drop of the stress after its peak that counts as a break: more than this
/// fraction of the peak stress (and more than [`SIGMAS`] noise σ), with the stretch
/// still increasing. An elastomer's loading curve rises monotonically (Drucker
/// stability of the material); a rupture drops it to near zero within a few samples.
pub const BREAK_DROP: f64 = 0.1;

/// Multiples of the noise σ a preload offset or a break drop must exceed to be
/// reported: beyond 3σ a Gaussian reading lies with probability 0.3 %.
pub const SIGMAS: f64 = 3.0;

/// A reversal of the stretch smaller than this fraction of the record's stretch
/// span is jitter of the crosshead reading, not an unloading branch.
pub const REVERSAL: f64 = 0.01;

/// Points within this stretch of λ = 1 estimate the stress there (a preload
/// offset) by a straight line when no point lies at λ = 1: 2 % strain is where
/// every model's stress is linear in λ − 1 to within about 3 % (the quadratic term
/// of the uniaxial Neo-Hookean stress is −3/2·(λ − 1)² against 3·(λ − 1)).
pub const OFFSET_WINDOW: f64 = 0.02;

/// The noise standard deviation of y(x) estimated without a model from the local
/// second differences of the points sorted by x (Gasser, Sroka & Jennen-Steinmetz,
/// "Residual variance and residual pattern in nonlinear regression", Biometrika 73,
/// 1986): for each interior point the pseudo-residual
/// eᵢ = aᵢ·yᵢ₋₁ + bᵢ·yᵢ₊₁ − yᵢ, aᵢ = (xᵢ₊₁ − xᵢ)/(xᵢ₊₁ − xᵢ₋₁), bᵢ = 1 − aᵢ,
/// and σ² = Σ eᵢ²/(aᵢ² + bᵢ² + 1) / (n − 2). A smooth curve's second difference is
/// small against the noise when the points are dense; None for fewer than 3 points
/// with distinct neighbours.
pub fn noise_sigma(points: &[(f64, f64)]) -> Option<f64> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut sum, mut count) = (0.0, 0usize);
    for w in p.windows(3) {
        let ((x0, y0), (x1, y1), (x2, y2)) = (w[0], w[1], w[2]);
        if x2 <= x0 {
            continue;
        }
        let a = (x2 - x1) / (x2 - x0);
        let b = 1.0 - a;
        let e = a * y0 + b * y2 - y1;
        sum += e * e / (a * a + b * b + 1.0);
        count += 1;
    }
    (count > 0).then(|| (sum / count as f64).sqrt())
}

/// The Wald–Wolfowitz runs test of the signs of residuals in stretch order (zeros
/// dropped): the number of runs R, its expectation under independent signs
/// E = 2·n₊·n₋/n + 1, variance V = 2·n₊·n₋·(2·n₊·n₋ − n)/(n²·(n − 1)), z = (R − E)/√V
/// and the one-sided p = Φ(z) of so few runs (Wald & Wolfowitz, Ann. Math. Stat. 11,
/// 1940). Too few runs mean residuals that keep their sign over stretches of the
/// curve: the model misses its shape. None below [`RUNS_MIN`] signs of either kind
/// (the normal approximation needs them).
pub fn runs_test(mut residuals: Vec<(f64, f64)>) -> Option<RunsTest> {
    residuals.sort_by(|a, b| a.0.total_cmp(&b.0));
    let signs: Vec<bool> = residuals
        .iter()
        .filter(|r| r.1 != 0.0)
        .map(|r| r.1 > 0.0)
        .collect();
    let pos = signs.iter().filter(|s| **s).count() as f64;
    let neg = signs.len() as f64 - pos;
    if pos < RUNS_MIN || neg < RUNS_MIN {
        return None;
    }
    let n = pos + neg;
    let runs = 1 + signs.windows(2).filter(|w| w[0] != w[1]).count();
    let expected = 2.0 * pos * neg / n + 1.0;
    let var = 2.0 * pos * neg * (2.0 * pos * neg - n) / (n * n * (n - 1.0));
    let z = (runs as f64 - expected) / var.sqrt();
    let p = 0.5 * statrs::function::erf::erfc(-z / std::f64::consts::SQRT_2);
    Some(RunsTest {
        runs,
        expected_runs: expected,
        z,
        p,
    })
}

/// Fewest residuals of each sign for the runs test's normal approximation (Wald &
/// Wolfowitz 1940; tables of the exact distribution stop at 20 of each, and the
/// approximation is within 0.01 in p from about 10).
pub const RUNS_MIN: f64 = 10.0;

/// The one-sided p below which the runs test rejects independent residual signs.
pub const RUNS_ALPHA: f64 = 1e-3;

/// The RMSE over the model-free noise σ ([`noise_sigma`]) above which structured
/// residuals matter: a model error twice the noise (four times its variance) is a
/// misfit a reader sees in the residual chart; below it, dense data show a runs
/// test's rejection for a deviation smaller than the noise.
pub const LACK_OF_FIT_RATIO: f64 = 2.0;

/// The runs test of one mode's residuals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RunsTest {
    /// Runs of equal sign in stretch order.
    pub runs: usize,
    /// Runs expected of independent signs.
    pub expected_runs: f64,
    /// Standard score of the runs.
    pub z: f64,
    /// One-sided p of so few runs.
    pub p: f64,
}

/// The lack-of-fit test of one mode: the runs test and the RMSE against the noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LackOfFit {
    /// The runs test of the residual signs.
    pub runs: RunsTest,
    /// The model-free noise σ of the mode's data (Pa), when it has one.
    #[serde(rename = "noise_Pa")]
    pub noise_pa: Option<f64>,
    /// Whether the fit lacks fit: p < [`RUNS_ALPHA`] and RMSE >
    /// [`LACK_OF_FIT_RATIO`]·σ (or no σ).
    pub lacks_fit: bool,
}

/// The position in `group` (sample indices of one file and mode, in file order) of
/// the largest stretch, when the stretch reverses after it by more than
/// [`REVERSAL`] of its span (a load–unload cycle): the loading branch ends there,
/// the unloading branch starts there.
fn branches(samples: &[Sample], group: &[usize]) -> Option<usize> {
    let lam = |i: usize| samples[group[i]].stretch;
    let (lo, hi) = group
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| {
            (a.min(samples[i].stretch), b.max(samples[i].stretch))
        });
    let top = (0..group.len()).find(|&i| lam(i) == hi)?;
    let tol = REVERSAL * (hi - lo);
    (tol > 0.0 && (top + 1..group.len()).any(|i| lam(i) < hi - tol)).then_some(top)
}

/// The stress at λ = 1 of a curve (`pts` (stretch, stress) of one file and mode):
/// the mean of its points at λ = 1, else the straight line through its points within
/// [`OFFSET_WINDOW`] of it (at least two with distinct stretches), at λ = 1; None when
/// neither exists.
fn offset_at_one(pts: &[(f64, f64)]) -> Option<f64> {
    let at: Vec<f64> = pts
        .iter()
        .filter(|p| (p.0 - 1.0).abs() <= crate::data::REFERENCE_TOL)
        .map(|p| p.1)
        .collect();
    if !at.is_empty() {
        return Some(at.iter().sum::<f64>() / at.len() as f64);
    }
    let near: Vec<(f64, f64)> = pts
        .iter()
        .copied()
        .filter(|p| (p.0 - 1.0).abs() <= OFFSET_WINDOW)
        .collect();
    let n = near.len() as f64;
    let (mx, my) = near
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let sxx: f64 = near.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if near.len() < 2 || sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = near.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    Some(my + sxy / sxx * (1.0 - mx))
}

/// The data to fit after the sanity checks of each file and mode, in this order: the
/// stretch window (`--stretch-range`), the branch of a load–unload cycle
/// (`--branch`), a break at the end (`--until-break`) and a preload offset
/// (`--zero-offset`). Each finding is a warning with its numbers in the file's
/// [`Source::warnings`] (which make the fit's status a warning), or, when the option
/// that acts on it was given, a note of what was done in [`Source::notes`].
pub fn prepare(data: &Dataset, sanity: &Sanity) -> Result<Dataset> {
    if let Some((lo, hi)) = sanity.stretch_range {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(Error::settings(format!(
                "--stretch-range: expected MIN:MAX with MIN < MAX, found {lo}:{hi}"
            )));
        }
    }
    let mut out = Dataset {
        samples: Vec::with_capacity(data.samples.len()),
        sources: data.sources.clone(),
    };
    for f in 0..data.sources.len() {
        for m in Mode::ALL {
            let mut group: Vec<usize> = (0..data.samples.len())
                .filter(|&i| data.samples[i].source == f && data.samples[i].mode == m)
                .collect();
            if group.is_empty() {
                continue;
            }
            let (notes, warnings) = {
                let s = &mut out.sources[f];
                (&mut s.notes, &mut s.warnings)
            };
            let at = |i: usize| &data.samples[i];
            if let Some((lo, hi)) = sanity.stretch_range {
                let before = group.len();
                group.retain(|&i| (lo..=hi).contains(&at(i).stretch));
                if group.len() < before {
                    notes.push(format!(
                        "{m}: {} of {before} points outside --stretch-range {lo}:{hi} not fitted",
                        before - group.len()
                    ));
                }
            }
            if let Some(top) = branches(&data.samples, &group) {
                let branch = sanity.branch.unwrap_or_default();
                let (load, unload) = (top + 1, group.len() - top);
                let peak = at(group[top]);
                let what = format!(
                    "{m}: the stretch reverses at λ = {:.4} (line {}): a load–unload cycle of {load} loading and {unload} unloading points",
                    peak.stretch, peak.line
                );
                match branch {
                    Branch::Loading => group.truncate(top + 1),
                    Branch::Unloading => {
                        group.drain(..top);
                    }
                    Branch::All => {}
                }
                match sanity.branch {
                    None => warnings.push(format!(
                        "{what}; the loading branch was fitted (--branch loading|unloading|all)"
                    )),
                    Some(b) => notes.push(format!("{what}; --branch {b} fitted")),
                }
            }
            let pts = |g: &[usize]| -> Vec<(f64, f64)> {
                g.iter().map(|&i| (at(i).stretch, at(i).stress)).collect()
            };
            let sigma = noise_sigma(&pts(&group));
            // A break: the stress falls after its peak while the stretch goes on.
            if sanity.branch.unwrap_or_default() != Branch::Unloading && group.len() >= 3 {
                let top = (0..group.len())
                    .max_by(|&a, &b| at(group[a]).stress.total_cmp(&at(group[b]).stress))
                    .expect("non-empty");
                let (peak, last) = (at(group[top]), at(*group.last().expect("non-empty")));
                let drop = peak.stress - last.stress;
                let floor = BREAK_DROP * peak.stress.abs() + SIGMAS * sigma.unwrap_or(0.0);
                if top + 1 < group.len() && last.stretch >= peak.stretch && drop > floor {
                    let what = format!(
                        "{m}: the curve ends in a break: the stress falls from {} Pa at λ = {:.4} (line {}) to {} Pa at λ = {:.4} (line {}), {:.0} % of the peak, over the last {} points",
                        Fixed(peak.stress, 4),
                        peak.stretch,
                        peak.line,
                        Fixed(last.stress, 4),
                        last.stretch,
                        last.line,
                        100.0 * drop / peak.stress.abs(),
                        group.len() - top - 1
                    );
                    if sanity.until_break {
                        notes.push(format!("{what}; cut after the peak (--until-break)"));
                        group.truncate(top + 1);
                    } else {
                        warnings.push(format!(
                            "{what}; they were fitted (--until-break cuts them)"
                        ));
                    }
                }
            }
            // A preload offset: stress at λ = 1, against the noise.
            let curve = pts(&group);
            let scale = curve.iter().fold(0.0f64, |a, p| a.max(p.1.abs()));
            let mut shift = 0.0;
            if let Some(offset) = offset_at_one(&curve) {
                let sigma = noise_sigma(&curve);
                let big =
                    offset.abs() > 1e-6 * scale && sigma.is_none_or(|s| offset.abs() > SIGMAS * s);
                if big {
                    let against = match sigma {
                        Some(s) if s > 0.0 => format!(
                            "{:.1} times the noise σ = {} Pa",
                            offset.abs() / s,
                            Fixed(s, 3)
                        ),
                        _ => "the noise σ is unknown".into(),
                    };
                    let what = format!(
                        "{m}: the stress at λ = 1 is {} Pa ({:.2} % of the largest stress; {against}): a preload or a load cell not zeroed",
                        Fixed(offset, 4),
                        100.0 * offset.abs() / scale.max(f64::MIN_POSITIVE)
                    );
                    if sanity.zero_offset {
                        notes.push(format!("{what}; removed from every point (--zero-offset)"));
                        shift = offset;
                    } else {
                        warnings.push(format!(
                            "{what}; it biases the fit (--zero-offset removes it)"
                        ));
                    }
                }
            }
            out.samples.extend(group.iter().map(|&i| Sample {
                stress: at(i).stress - shift,
                ..*at(i)
            }));
        }
    }
    // Back to file order within each file (the modes were taken one after another).
    out.samples
        .sort_by_key(|s| (s.source, s.line, s.mode as usize));
    Ok(out)
}
