//! Inverse identification: the material constants that make the simulator reproduce
//! measured actuator traces, how sure we are of each, and which of them the traces
//! do not pin down.
//!
//! ```text
//! traces (io::trace) + scene ──Experiment per trace──► Problem (params, problem)
//! Problem ──multi-start bounded LM (search)──► best x
//! best x ──σ from residuals (noise), polish──► optimum
//! optimum ──Jacobian from forward sensitivities──► Assessment (σ, CI, identifiable, why)
//! ```
//! Modules: [`params`] (names, θ in a scene, search coordinates), [`problem`]
//! (residuals and exact Jacobian with the simulator inside), [`noise`] (σ per
//! channel), [`search`] (multi-start), [`assessment`] (what the traces pin down),
//! [`band`] (the ±1σ band of the model's traces), [`failure`] (a run without a result).

pub mod assessment;
pub mod band;
pub mod checkpoint;
pub mod failure;
pub mod geometry;
pub mod material;
pub mod noise;
pub mod params;
pub mod problem;
pub mod profile;
pub mod reduce;
pub mod search;
pub mod selection;

use crate::error::{Error, Result};
use crate::fit::diagnostics::{information_criteria, rmse_percent};
use crate::fit::linear::RowQr;
use crate::fit::lm::{Control, LeastSquares, LmSettings, Termination};
use crate::fit::Status;
use crate::sim::RunOptions;
use assessment::{Assessment, Context, Estimate, WARN_CORRELATION};
use failure::Failure;
use nalgebra::{DMatrix, DVector};
use noise::{Sigma, SigmaSource};
use problem::{ChannelKind, Experiment, Problem};
use serde::Serialize;
use std::time::Instant;

/// Checked identification settings.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Constants to fit (None: every material constant of the scene).
    pub free: Option<Vec<String>>,
    /// Constants held (`NAME` or `NAME=VALUE`).
    pub fix: Vec<String>,
    /// Noise per channel; a channel not named has σ estimated from its residuals.
    pub sigma: Vec<(ChannelKind, Sigma)>,
    /// Number of starts (the scene's values are the first).
    pub starts: usize,
    /// Seed of the start design.
    pub seed: u64,
    /// Stopping rules of each search.
    pub lm: LmSettings,
    /// Relative tolerance of the simulator (None: the scene's).
    pub rtol: Option<f64>,
    /// Free constants to profile ([`profile`]).
    pub profiles: Vec<String>,
    /// Values by name the first start takes in place of the scene's (a refit
    /// warm-started from a previous optimum, [`reduce`]); the scene's values are
    /// then the second start. A name that is not free is ignored; a value outside
    /// its search box is moved onto the box.
    pub warm: Vec<(String, f64)>,
    /// A model the default reduction ([`reduce`]) may still shrink: when the
    /// linear assessment of its optimum leaves a constant the reduction drops or
    /// holds, the profile checks of its intervals are skipped (the fit serves only
    /// that decision; the model reported is checked).
    pub reducing: bool,
}

/// The smallest decrease of ½χ² a search step must promise
/// ([`LmSettings::min_decrease`]): 10⁻³, so no estimate can still move by more
/// than ≈ 0.045 of its standard error. Below it the trials chase the integration
/// noise of the cost (≈ 10⁻⁴ at rtol 10⁻⁶ on the rig scene): 9 of 14 trials of a
/// start and all 6 of the polish were rejected there before this test.
pub const MIN_DECREASE: f64 = 1e-3;

impl Default for Settings {
    fn default() -> Self {
        Settings {
            free: None,
            fix: Vec::new(),
            sigma: Vec::new(),
            starts: 8,
            seed: 1,
            lm: LmSettings {
                max_iterations: 100,
                ftol: 1e-10,
                xtol: 1e-10,
                gtol: 1e-10,
                min_decrease: MIN_DECREASE,
            },
            rtol: None,
            profiles: Vec::new(),
            warm: Vec::new(),
            reducing: false,
        }
    }
}

impl Settings {
    /// Refuse settings that cannot run.
    pub fn check(&self) -> Result<()> {
        if self.starts == 0 || self.starts > 10_000 {
            return Err(Error::settings(format!(
                "--starts {}: give 1 to 10000 starts",
                self.starts
            )));
        }
        for (q, s) in &self.sigma {
            let v = match s {
                Sigma::Absolute(v) | Sigma::Relative(v) => *v,
            };
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::settings(format!(
                    "--sigma {q}: the noise must be finite and positive, not {v}"
                )));
            }
        }
        if let Some(r) = self.rtol {
            if !(1e-12..=1e-2).contains(&r) {
                return Err(Error::settings(format!("--rtol {r}: give 1e-12 to 1e-2")));
            }
        }
        Ok(())
    }
}

/// Fit of one channel of one experiment.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelFit {
    /// Channel name.
    pub channel: ChannelKind,
    /// SI unit of the values below.
    pub unit: &'static str,
    /// Measured values used.
    pub points: usize,
    /// Noise σ used (SI).
    pub sigma: f64,
    /// Where σ came from.
    pub sigma_source: SigmaSource,
    /// Root-mean-square residual (SI).
    pub rmse: f64,
    /// Seed Eq. 3.28: RMSE over the measured range, %.
    pub rmse_pct: Option<f64>,
}

/// Fit of one experiment.
#[derive(Debug, Clone, Serialize)]
pub struct ExperimentFit {
    /// Trace file.
    pub file: String,
    /// Trace rows.
    pub rows: usize,
    /// Channels.
    pub channels: Vec<ChannelFit>,
}

/// What the search did.
#[derive(Debug, Clone, Serialize)]
pub struct SolverSummary {
    /// Method.
    pub method: String,
    /// Starts run.
    pub starts: usize,
    /// Starts that reached the best cost ([`crate::fit::multistart::starts_at_best`]).
    pub starts_at_best: usize,
    /// Starts given up as out of reach of the first start's cost
    /// ([`crate::fit::lm::out_of_reach`]).
    pub starts_abandoned: usize,
    /// Iterations over all starts and the polish.
    pub iterations: usize,
    /// Simulator runs (plain and with sensitivities).
    pub simulator_runs: usize,
    /// Of which with sensitivities.
    pub sensitivity_runs: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Why the best search stopped.
    pub termination: String,
    /// Final ½χ² of every start, sorted (the waterfall); ∞ for a start that failed,
    /// the cost where it stopped for one abandoned.
    pub final_costs: Vec<f64>,
    /// The integration check at the optimum ([`integration_shift`]): the largest
    /// move of an identified constant, in its standard errors, when the simulator
    /// runs at 1/100 of the tolerance (None when not checked: no identified
    /// constant, or the more accurate run failed, which a warning says).
    pub integration_shift: Option<f64>,
    /// Wall-clock seconds of the interval stage ([`profile::assess`]: the
    /// covariance, the profile checks and intervals, the `--profiles` grids), part
    /// of `seconds`.
    pub interval_seconds: f64,
}

/// The result of [`identify`].
#[derive(Debug, Clone, Serialize)]
pub struct Identification {
    /// Status (blocking under `--strict`: `ill_posed`, `not_converged`; the CLI
    /// makes it `not_validated` when a held-out trace is missed).
    pub status: Status,
    /// The free constants.
    pub parameters: Vec<Estimate>,
    /// The constants not fitted: fixed by `--fix NAME=VALUE` (stated), held at
    /// the scene's values, or dropped by the model reduction ([`reduce`]).
    pub held: Vec<reduce::Held>,
    /// The held constants every estimate's interval is conditional on (the held
    /// ones but those dropped): the intervals assume these values exact.
    pub conditional_on: Vec<String>,
    /// The default model reduction, when it reduced the scene's model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reduction: Option<reduce::Reduction>,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Per experiment and channel.
    pub experiments: Vec<ExperimentFit>,
    /// Search report.
    pub solver: SolverSummary,
    /// ½χ² at the optimum.
    pub cost: f64,
    /// χ²/(N − p).
    pub chi2_per_dof: f64,
    /// Corrected Akaike criterion on χ² (None when N ≤ p + 1).
    pub aicc: Option<f64>,
    /// Bayesian criterion on χ².
    pub bic: f64,
    /// Uncertainty and identifiability.
    pub assessment: Assessment,
    /// Constants that follow from the free ones: εr of a free filler mass fraction
    /// (σ by dεr/dw, the interval the rule's image of w's).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub derived: Vec<Estimate>,
    /// What the scene's geometry tolerances add to σ and the intervals, or that the
    /// intervals exclude them ([`geometry`]).
    pub geometry: geometry::Geometry,
    /// Profile likelihoods asked for (`--profiles`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub profiles: Vec<profile::Profile>,
    /// θ at the optimum (the whole vector, SI), for the material file and reports.
    #[serde(skip)]
    pub theta: Vec<f64>,
    /// Smallest and largest stretch the traces' simulations reached at the optimum
    /// (the range the constants were identified over).
    #[serde(skip)]
    pub stretch_range: (f64, f64),
    /// The simulations at the optimum, one per experiment, with their sensitivities
    /// (for reports).
    #[serde(skip)]
    pub runs: Vec<crate::sim::Outcome>,
    /// A model the default reduction shrinks further ([`Settings::reducing`]): its
    /// Wald intervals were not checked against profiles and its integration error
    /// not measured, since no output reports it; a reduction that stops at it
    /// identifies it again with both ([`reduce::identify`]).
    #[serde(skip)]
    pub provisional: bool,
}

/// What an identification of usable input gives: the identified constants, or a
/// run without a result (status `failed`, [`failure`]).
#[derive(Debug, Clone)]
pub enum Run {
    /// Constants with their uncertainty (any status but `failed`).
    Identified(Box<Identification>),
    /// Nothing estimated.
    Failed(Box<Failure>),
}

impl Run {
    /// The status of the run.
    pub fn status(&self) -> Status {
        match self {
            Run::Identified(id) => id.status,
            Run::Failed(f) => f.status,
        }
    }

    /// The identification, or the failure.
    pub fn identified(self) -> std::result::Result<Identification, Box<Failure>> {
        match self {
            Run::Identified(id) => Ok(*id),
            Run::Failed(f) => Err(f),
        }
    }
}

/// Identify the material constants of `experiments` (one scene per trace, sharing
/// the material) under `settings`, without observers.
pub fn identify(experiments: Vec<Experiment>, settings: &Settings) -> Result<Run> {
    identify_with(experiments, settings, &|_| Control::default())
}

/// [`identify`] with the [`Control`] (progress, trace, checkpoint, wall time) that
/// `control` makes for each start (index `settings.starts` is the polish).
///
/// `Err` is unusable input: refused settings, traces the problem cannot be posed
/// on, and a scene that the simulator refuses to start on a trace at the starting
/// constants (its guard: domain, rest state, step and memory budget), since then
/// the input as given cannot run. A run that starts and fails numerically (a
/// pull-in the trace does not show, an integrator failure) at every start of the
/// search is a [`Run::Failed`] with each start's reason.
pub fn identify_with(
    experiments: Vec<Experiment>,
    settings: &Settings,
    control: &(dyn Fn(usize) -> Control + Sync),
) -> Result<Run> {
    settings.check()?;
    let t0 = Instant::now();
    let (mut problem, all, stated, given) = prepare(experiments, settings)?;
    let profiled = profile_indices(&problem, settings)?;
    let (n, k) = problem.dims();
    let parts = checkpoint::parts(&problem, settings);
    let control = &checkpoint::stamped(control, &parts);
    refuse_foreign_checkpoints(&problem, settings, control)?;
    let x_scene = problem.x_of(&problem.theta);
    let x_start = warm_start(&problem, &settings.warm).unwrap_or_else(|| x_scene.clone());
    let mut design = search::starts(&problem, x_start, settings.starts, settings.seed)?;
    if !settings.warm.is_empty() && design.len() > 1 {
        design[1] = x_scene;
    }
    let ms = search::run_all(&problem, &design, &settings.lm, control);
    let mut iterations: usize = ms.runs.iter().map(|r| r.1.iterations).sum();
    let solver = |problem: &Problem, iterations: usize, termination: String| {
        let (plain, sens) = problem.counts.get();
        SolverSummary {
            method:
                "multi-start bounded Levenberg-Marquardt (argmin), forward-sensitivity Jacobian"
                    .into(),
            starts: settings.starts,
            starts_at_best: ms.at_best,
            starts_abandoned: ms.abandoned,
            iterations,
            simulator_runs: plain + sens,
            sensitivity_runs: sens,
            seconds: t0.elapsed().as_secs_f64(),
            termination,
            final_costs: ms.waterfall(),
            integration_shift: None,
            interval_seconds: 0.0,
        }
    };
    let Some(best) = ms.best().cloned() else {
        let s = solver(&problem, iterations, "every start failed".into());
        return Ok(Run::Failed(Box::new(Failure::no_start(&problem, &ms, s))));
    };
    let failed_at_best = |problem: &Problem, iterations: usize, why: String| {
        let s = solver(problem, iterations, best.termination.to_string());
        Ok(Run::Failed(Box::new(Failure::at_best(problem, why, s))))
    };
    let (mut x, termination, polished) = polish(&mut problem, &given, &best, settings, control);
    iterations += polished;
    // Interchangeable arms in the order of their relaxation times.
    params::order_arms(&problem.free, &mut x);
    // The optimum: residuals, Jacobian, assessment.
    let mut r = DVector::zeros(n);
    let mut jac = DMatrix::zeros(n, k);
    let runs = match problem.optimum(&x, &mut r, &mut jac) {
        Ok(runs) => runs,
        Err(why) => return failed_at_best(&problem, iterations, why),
    };
    let theta = problem.theta_at(&x);
    let rss = r.norm_squared();
    let ctx = context(&problem, &runs);
    // σ, intervals (Wald, or profile where the linearisation fails), identifiability
    let started = Instant::now();
    let model = problem.experiments[0].scene.material.spec.name.clone();
    let converged = matches!(termination, Termination::Converged(_));
    // not at an optimum: no interval is reported (below), so none is checked; nor
    // in a model the reduction shrinks further (provisional)
    let provisional = |e: &[assessment::Estimate]| {
        settings.reducing && reduce::next_step(e, &all, &model).is_some()
    };
    let unchecked = |e: &[assessment::Estimate]| !converged || provisional(e);
    let (assessment, profiles) = profile::assess(
        &problem,
        &x,
        &jac,
        rss,
        &ctx,
        &profiled,
        &settings.lm,
        &unchecked,
    );
    let interval_seconds = started.elapsed().as_secs_f64();
    let experiments = channel_fits(&problem, &given, &r);
    // the scene's geometry tolerances into σ and the intervals (identify::geometry)
    let mut assessment = assessment;
    let geometry = geometry::include(&problem, &x, &jac, &mut assessment.estimates);
    let mut warnings = warnings(
        &problem,
        &assessment,
        &runs,
        ms.at_best,
        ms.abandoned,
        settings.starts,
    );
    warnings.extend(structured_residuals(&problem, &r));
    warnings.extend(assessment.warnings.iter().cloned());
    warnings.extend(geometry.warning());
    let provisional = converged && provisional(&assessment.estimates);
    let shift = match provisional {
        true => Ok(None),
        false => integration_shift(&mut problem, &x, &r, &jac, &assessment.estimates),
    };
    warnings.extend(shift_warning(&shift));
    let shift = shift.ok().flatten();
    let stretch_range = stretch_range(&runs);
    let unstable = drucker_unstable(&problem.experiments[0].scene, &theta, stretch_range);
    warnings.extend(unstable.clone());
    let status = status(
        &termination,
        shift.as_ref(),
        unstable.is_some(),
        &assessment,
        &warnings,
    );
    if status == Status::NotConverged {
        warnings.push(not_at_optimum(&mut assessment, &termination));
    }
    let (aicc, bic) = information_criteria(rss, n, k);
    let held = reduce::held(&all, &problem.free, &stated, &theta);
    Ok(Run::Identified(Box::new(Identification {
        status,
        conditional_on: reduce::conditional_on(&held),
        held,
        reduction: None,
        parameters: assessment.estimates.clone(),
        derived: derived(&problem.free, &assessment.estimates),
        warnings,
        experiments,
        solver: SolverSummary {
            integration_shift: shift.map(|s| s.sigmas),
            interval_seconds,
            ..solver(&problem, iterations, termination.to_string())
        },
        cost: 0.5 * rss,
        chi2_per_dof: rss / (n - k) as f64,
        aicc,
        bic,
        assessment,
        geometry,
        profiles,
        theta,
        stretch_range,
        runs,
        provisional,
    })))
}

/// Refuse the run when a start is to resume from a checkpoint file that exists
/// but is not one of this problem's ([`crate::fit::lm::Checkpoint::check`]:
/// damaged, edited, another format, or written for another trace, scene, free
/// set, constants, σ, settings, tool version or start): resuming it would report
/// another problem's constants as this one's. (The polish's σ are known only
/// after the search: its checkpoint is checked then, [`checkpoint::for_polish`].)
fn refuse_foreign_checkpoints(
    problem: &Problem,
    settings: &Settings,
    control: &(dyn Fn(usize) -> Control + Sync),
) -> Result<()> {
    let bounds = problem.x_bounds();
    for i in 0..settings.starts {
        let c = control(i);
        let Some(cp) = c.checkpoint.filter(|cp| c.resume && cp.file.exists()) else {
            continue;
        };
        cp.check(problem.dims(), &bounds).map_err(|why| {
            Error::settings(why).with_hint(
                "resume with the traces, scene and settings the checkpoint was written for, \
                 or give another --checkpoint name (or delete the file) to start afresh",
            )
        })?;
    }
    Ok(())
}

/// A run that did not reach an optimum reports no constant identifiable: σ and the
/// intervals are the curvature and profile about the point where the search
/// stopped, which is not the estimate the trace supports (slow-arm study,
/// tests/identify_coverage.rs: two replicates whose search stopped at the
/// iteration limit with Yeoh's C20 and C30 on their search bounds gave the fast
/// arm's modulus 95 % intervals 3–4 σ wide of the truth). Each estimate keeps its
/// value and its σ for orientation, with the reason (and what the assessment said
/// at the point where the search stopped); the one warning returned says what to
/// do.
fn not_at_optimum(assessment: &mut Assessment, termination: &Termination) -> String {
    let why = match termination {
        Termination::Converged(_) => {
            "the integration error moves the optimum by more than its standard errors".to_string()
        }
        t => format!("the search did not converge ({t})"),
    };
    let reason = format!(
        "{why}: the estimate is not an optimum, so its σ and interval describe where the search stopped, not what the trace supports"
    );
    for e in assessment.estimates.iter_mut() {
        e.identifiable = false;
        e.reason = Some(match e.reason.take() {
            Some(there) => format!("{reason} (there: {there})"),
            None => reason.clone(),
        });
    }
    format!(
        "no constant is reported identifiable: {why}; rerun with more iterations (--max-iterations), more starts (--starts), a finer integration (--rtol) or a scene nearer the answer"
    )
}

/// The status of an identification: `not_converged` when the search did not
/// converge or the integration error moved the optimum by more than
/// [`MAX_INTEGRATION_SHIFT`] standard errors, `unstable` when the hyperelastic law
/// at the optimum is not Drucker-stable over the traced stretches
/// ([`drucker_unstable`]), `ill_posed` when a constant is not identified (a
/// constant at a bound of its search box is not), else `warning` with any warning
/// and `ok` without.
fn status(
    termination: &Termination,
    shift: Option<&Shift>,
    unstable: bool,
    assessment: &Assessment,
    warnings: &[String],
) -> Status {
    if !matches!(termination, Termination::Converged(_))
        || shift.is_some_and(|s| s.sigmas > MAX_INTEGRATION_SHIFT)
    {
        Status::NotConverged
    } else if unstable {
        Status::Unstable
    } else if assessment.estimates.iter().any(|e| !e.identifiable) {
        Status::IllPosed
    } else if warnings.is_empty() {
        Status::Ok
    } else {
        Status::Warning
    }
}

/// The first start of a warm-started search ([`Settings::warm`]): the named
/// values in search coordinates (moved onto the box when outside), the scene's
/// for a constant not named; None when nothing is named.
fn warm_start(problem: &Problem, warm: &[(String, f64)]) -> Option<Vec<f64>> {
    if warm.is_empty() {
        return None;
    }
    let scene = problem.x_of(&problem.theta);
    Some(
        problem
            .free
            .iter()
            .zip(problem.x_bounds())
            .zip(scene)
            .map(|((c, (lo, hi)), x0)| {
                warm.iter()
                    .find(|(n, _)| *n == c.name)
                    .map(|&(_, v)| c.space.x(v))
                    .filter(|x| x.is_finite())
                    .map_or(x0, |x| x.clamp(lo, hi))
            })
            .collect(),
    )
}

/// Relative margin in stretch beyond the traced range over which the identified
/// hyperelastic law must be Drucker-stable: [λmin/(1 + m), λmax·(1 + m)], m = 0.1
/// (a scene run a little past the traces must not meet an instability the fit put
/// there).
pub const DRUCKER_MARGIN: f64 = 0.1;

/// The finding when the hyperelastic law of `scene`'s material at θ is not
/// Drucker-stable (dP/dλ ≤ 0, [`crate::fit::drucker`]) in the actuator's mode
/// anywhere over the traced stretches `range` widened by [`DRUCKER_MARGIN`].
pub fn drucker_unstable(
    scene: &crate::sim::scene::Scene,
    theta: &[f64],
    range: (f64, f64),
) -> Option<String> {
    let mode = crate::sim::full_plant(scene).ok()?.mode;
    let m = &scene.material;
    let bad = unstable_within(m.model.as_ref(), &theta[..m.params.len()], mode, range)?;
    Some(format!(
        "the identified hyperelastic law is Drucker-unstable in {mode} at stretch {bad} within the traced range {:.4}–{:.4} widened by {:.0} %: not a material law; fix the higher terms (e.g. at 0) or add a trace that reaches the stretches where it stiffens",
        range.0,
        range.1,
        100.0 * DRUCKER_MARGIN
    ))
}

/// The stretches (as text) where the law `model` at `p` is Drucker-unstable in
/// `mode` within `range` widened by [`DRUCKER_MARGIN`] (and always about λ = 1).
fn unstable_within(
    model: &dyn crate::material::hyperelastic::StrainEnergy,
    p: &[f64],
    mode: crate::material::hyperelastic::Mode,
    range: (f64, f64),
) -> Option<String> {
    let (lo, hi) = (
        range.0.min(1.0) / (1.0 + DRUCKER_MARGIN),
        range.1.max(1.0) * (1.0 + DRUCKER_MARGIN),
    );
    let d = crate::fit::drucker::drucker(model, p)
        .into_iter()
        .find(|d| d.mode == mode)?;
    let bad: Vec<String> = d
        .unstable
        .iter()
        .filter(|[a, b]| *a <= hi && *b >= lo)
        .map(|[a, b]| format!("{a:.3}–{b:.3}"))
        .collect();
    (!bad.is_empty()).then(|| bad.join(", "))
}

/// The search's physics bound ([`Problem::infeasible`]): a trial θ whose law is
/// Drucker-unstable over the stretches the traces reach at the starting constants
/// (widened by [`DRUCKER_MARGIN`]) is infeasible. None when the starting law is
/// itself unstable there (the status at the optimum says so) or the traces do
/// not run at the start (the start check says why).
fn drucker_bound(problem: &Problem) -> Option<problem::Infeasible> {
    let scene = &problem.experiments[0].scene;
    let model = scene.material.model.clone();
    let np = scene.material.params.len();
    let mode = crate::sim::full_plant(scene).ok()?.mode;
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    for e in &problem.experiments {
        let o = crate::sim::trajectory(&e.scene, &problem.run).ok()?;
        for s in &o.samples {
            range = (range.0.min(s.stretch), range.1.max(s.stretch));
        }
    }
    if !(range.0.is_finite() && range.1.is_finite())
        || unstable_within(model.as_ref(), &problem.theta[..np], mode, range).is_some()
    {
        return None;
    }
    Some(std::sync::Arc::new(move |theta: &[f64]| {
        unstable_within(model.as_ref(), &theta[..np], mode, range).map(|at| {
            format!("the hyperelastic law is Drucker-unstable in {mode} at stretch {at}, within the traced stretches {:.4}–{:.4} widened by {:.0} %", range.0, range.1, 100.0 * DRUCKER_MARGIN)
        })
    }))
}

/// Smallest and largest stretch over every sample of the runs.
fn stretch_range(runs: &[crate::sim::Outcome]) -> (f64, f64) {
    runs.iter()
        .flat_map(|o| &o.samples)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            (a.min(s.stretch), b.max(s.stretch))
        })
}

/// σ from the residuals for the channels whose σ was not given, then a polish from
/// the best search (its residuals and Jacobian, rescaled to the new σ, start the
/// polish without another run at its point): the point, its termination and the
/// polish's iterations; the best search's own when every σ was given or the polish
/// failed.
fn polish(
    problem: &mut Problem,
    given: &[Vec<bool>],
    best: &crate::fit::lm::LmResult,
    settings: &Settings,
    control: &(dyn Fn(usize) -> Control + Sync),
) -> (Vec<f64>, Termination, usize) {
    let own = (best.x.clone(), best.termination.clone(), 0);
    if given.iter().flatten().all(|&g| g) {
        return own;
    }
    let old = row_sigmas(problem);
    reestimate_sigma(problem, given, &best.residuals, problem.dims().1);
    let (mut r0, mut j0) = (best.residuals.clone(), best.jacobian.clone());
    for (row, (o, s)) in old.iter().zip(row_sigmas(problem)).enumerate() {
        r0[row] *= o / s;
        j0.row_mut(row).scale_mut(o / s);
    }
    let mut p = problem.clone();
    let mut c = control(settings.starts);
    checkpoint::for_polish(&mut c, problem);
    c.known_start = Some((r0, j0));
    let polish = crate::fit::lm::search(&mut p, &best.x, &problem.x_bounds(), &settings.lm, &mut c);
    match polish.cost.is_finite() {
        true => (polish.x, polish.termination, polish.iterations),
        false => (own.0, own.1, polish.iterations),
    }
}

/// The problem: constants chosen, fixed values set, σ of every channel (given, or
/// from the data to start with); also every constant, and which σ were given.
#[allow(clippy::type_complexity)]
fn prepare(
    mut experiments: Vec<Experiment>,
    settings: &Settings,
) -> Result<(Problem, Vec<params::Constant>, Vec<usize>, Vec<Vec<bool>>)> {
    let first = experiments
        .first()
        .ok_or_else(|| Error::settings("no trace to identify from"))?;
    let all = params::constants(&first.scene);
    let params::Chosen { free, fixed } =
        params::choose(&all, settings.free.as_deref(), &settings.fix)?;
    let mut theta0 = params::theta(&first.scene);
    for &(k, v) in &fixed {
        theta0[k] = v;
    }
    let mut given = Vec::new();
    for e in &mut experiments {
        let times: Vec<f64> = std::iter::once(0.0)
            .chain(e.scene.time.samples.iter().copied())
            .collect();
        let mut g = Vec::new();
        for ch in &mut e.channels {
            if ch.kind == ChannelKind::Force {
                return Err(Error::settings(format!(
                    "{}: a force channel cannot be identified from: the simulator drives a given load and computes no force",
                    e.name
                ))
                .with_hint("remove the force column, or use the contraction, capacitance or current"));
            }
            let s = settings.sigma.iter().find(|(q, _)| *q == ch.kind);
            ch.sigma = match s {
                Some((_, s)) => s.resolve(&ch.values),
                None => noise::from_data(&times, &ch.values),
            };
            g.push(s.is_some());
        }
        given.push(g);
    }
    let problem = Problem::new(
        experiments,
        free,
        theta0,
        RunOptions {
            rtol: settings.rtol,
            auto_as_with_sensitivities: true,
            ..RunOptions::default()
        },
    )?;
    let (n, k) = problem.dims();
    if n <= k {
        return Err(Error::settings(format!(
            "{n} measured values for {k} free constants: nothing to estimate"
        ))
        .with_hint("fix some constants (--fix) or give longer traces"));
    }
    // The input as given must start at the starting constants.
    for e in &problem.experiments {
        e.check_start(&problem.theta)?;
    }
    let mut problem = problem;
    problem.infeasible = drucker_bound(&problem);
    let stated = fixed.iter().map(|&(k, _)| k).collect();
    Ok((problem, all, stated, given))
}

/// The warnings of an identification: correlated pairs, constants at a bound, the
/// constants not identified and why, the simulator's own (extrapolation), and a
/// multi-start whose best was reached only once.
fn warnings(
    problem: &Problem,
    assessment: &Assessment,
    runs: &[crate::sim::Outcome],
    at_best: usize,
    abandoned: usize,
    starts: usize,
) -> Vec<String> {
    let free = &problem.free;
    let mut w = Vec::new();
    for (a, row) in assessment.correlation.iter().enumerate() {
        for (b, rho) in row.iter().enumerate().skip(a + 1) {
            if let Some(rho) = rho.filter(|r| r.abs() > WARN_CORRELATION) {
                w.push(format!(
                    "{} and {} are correlated (ρ = {rho:.4})",
                    free[a].name, free[b].name
                ));
            }
        }
    }
    for e in assessment.estimates.iter().filter(|e| !e.identifiable) {
        w.push(format!(
            "{} is not identifiable: {}",
            e.name,
            e.reason.as_deref().unwrap_or("")
        ));
    }
    for o in runs {
        w.extend(o.warnings.iter().cloned());
    }
    for e in &problem.experiments {
        w.extend(unresolved_drive(e));
    }
    w.dedup();
    if starts > 1 && at_best == 1 {
        let given_up = match abandoned {
            0 => String::new(),
            n => format!(" ({n} abandoned as out of reach of the first start's cost)"),
        };
        w.push(format!(
            "only 1 of {starts} starts reached the best cost{given_up}: the cost has other minima, and more starts (--starts) may find a better one"
        ));
    }
    w
}

/// An integration error that moves an identified constant by more than this many
/// of its standard errors ([`integration_shift`]) is reported as a warning: the
/// intervals then hold the integrator's error as well as the trace's noise.
pub const WARN_INTEGRATION_SHIFT: f64 = 0.2;

/// An integration error that moves an identified constant by more than this many
/// standard errors makes the identification `not_converged`: the estimates are
/// then set by the integrator's error more than by the trace (the rig trace,
/// datasets/scenes/stack_rig_7s.toml, at rtol 10⁻² moves by 0.72 σ of arm1.k, at
/// 10⁻³ by 0.021 σ, at its own 10⁻⁶ by 10⁻⁵ σ).
pub const MAX_INTEGRATION_SHIFT: f64 = 1.0;

/// The integration check at the optimum: how far it moves when the model is
/// integrated more accurately.
#[derive(Debug, Clone, PartialEq)]
pub struct Shift {
    /// Largest |Δθ|/σ over the identified constants.
    pub sigmas: f64,
    /// The constant it belongs to.
    pub name: String,
    /// RMS change of the scaled residuals (in σ of the noise).
    pub rms: f64,
}

/// The integration check: the residuals r′ at the optimum x from runs at
/// [`problem::CHECK_RTOL_FACTOR`] × the tolerance, and the Gauss–Newton step
/// Δx = −J⁺·(r′ − r) that the more accurate model takes from x (J over the
/// identified constants, the others held at their values); each identified
/// constant's move |θ(x + Δx) − θ(x)| in its standard errors, the largest returned.
/// The search's own optimum has Jᵀr ≈ 0, so the step is the move of the optimum
/// that the integration error made, to first order. Ok(None) when no constant is
/// identified; Err: why the more accurate run gave no residuals.
pub fn integration_shift(
    problem: &mut Problem,
    x: &[f64],
    r: &DVector<f64>,
    jac: &DMatrix<f64>,
    estimates: &[Estimate],
) -> std::result::Result<Option<Shift>, String> {
    let cols: Vec<usize> = (0..estimates.len())
        .filter(|&j| estimates[j].identifiable && estimates[j].std_error.is_some())
        .collect();
    if cols.is_empty() {
        return Ok(None);
    }
    let mut accurate = DVector::zeros(r.len());
    problem.residuals_more_accurate(x, &mut accurate)?;
    let d = accurate - r;
    let rms = d.norm() / (d.len() as f64).sqrt();
    let mut qr = RowQr::with_rows(cols.len(), d.len());
    let mut row = vec![0.0; cols.len()];
    for (i, &di) in d.iter().enumerate() {
        for (v, &c) in row.iter_mut().zip(&cols) {
            *v = jac[(i, c)];
        }
        qr.push(&row, -di);
    }
    let step = qr
        .solve()
        .ok_or("no Gauss-Newton step (a rank-0 or non-finite Jacobian)")?;
    let mut worst = Shift {
        sigmas: 0.0,
        name: String::new(),
        rms,
    };
    for (&c, dx) in cols.iter().zip(step.iter()) {
        let e = &estimates[c];
        let moved = problem.free[c].space.theta(x[c] + dx) - e.value;
        let z = (moved / e.std_error.expect("identified")).abs();
        if !z.is_finite() {
            return Err(format!("a non-finite move of {}", e.name));
        }
        if z > worst.sigmas {
            worst.sigmas = z;
            worst.name = e.name.clone();
        }
    }
    Ok(Some(worst))
}

/// The warning of an integration check ([`integration_shift`]) that moved a
/// constant by more than [`WARN_INTEGRATION_SHIFT`] standard errors or could not run.
fn shift_warning(shift: &std::result::Result<Option<Shift>, String>) -> Option<String> {
    match shift {
        Ok(Some(s)) if s.sigmas > WARN_INTEGRATION_SHIFT => Some(format!(
            "the simulator's integration error matters: run at 1/100 of its tolerance, the model moves the optimum by {:.3} standard errors of {} (the residuals change by {:.3} σ RMS); {}",
            s.sigmas,
            s.name,
            s.rms,
            match s.sigmas > MAX_INTEGRATION_SHIFT {
                true => "the estimates and intervals are the integrator's, not the trace's: rerun with a tighter --rtol (e.g. 1/100 of this one)",
                false => "the intervals are wider than they say: a tighter --rtol (e.g. 1/10 of this one) removes this",
            }
        )),
        Ok(_) => None,
        Err(why) => Some(format!(
            "the integration error at the optimum could not be checked (the run at 1/100 of the tolerance: {why})"
        )),
    }
}

/// Lag-1 autocorrelation of a channel's residuals above which they hold structure
/// the model does not explain (white noise gives ρ₁ ≈ 0 ± 1/√n; the warning also
/// needs 5/√n, so chance never reaches it).
pub const MAX_RESIDUAL_CORRELATION: f64 = 0.5;

/// Channels whose residuals at the optimum are correlated from one sample to the
/// next (ρ₁ above [`MAX_RESIDUAL_CORRELATION`] and 5/√n): the fit misses something
/// the trace shows (a drive it did not record, a fixed constant that is wrong, a
/// model too simple), or the noise is not white. Either way σ taken from these
/// residuals is not the noise, and the intervals are too narrow.
fn structured_residuals(problem: &Problem, r: &DVector<f64>) -> Vec<String> {
    channel_rows(problem)
        .into_iter()
        .filter_map(|(ei, ci, rows)| {
            let n = rows.len();
            let x = &r.as_slice()[rows];
            let ss: f64 = x.iter().map(|v| v * v).sum();
            let lag: f64 = x.windows(2).map(|w| w[0] * w[1]).sum();
            let rho = lag / ss;
            (n >= 20 && rho > MAX_RESIDUAL_CORRELATION.max(5.0 / (n as f64).sqrt())).then(|| {
                let e = &problem.experiments[ei];
                format!(
                    "{} {}: the residuals are correlated from sample to sample (lag-1 ρ = {rho:.2}): they hold structure the model does not explain (a drive the trace did not record, a fixed constant that is wrong, a model too simple) or the noise is not white; σ taken from them is then not the noise, and the intervals are too narrow",
                    e.name, e.channels[ci].kind
                )
            })
        })
        .collect()
}

/// A measured drive that changes faster than the trace samples it: a step of the
/// measured input (a jump within one or two sample intervals,
/// [`crate::sim::input::Measured::steps`]). The rise within it was not recorded,
/// so the constants that act at that rate (the dashpot nv, fast arms) are fitted
/// to a guessed shape of it.
fn unresolved_drive(e: &Experiment) -> Option<String> {
    use crate::report::format::si;
    let measured = e.scene.input.terms.iter().find_map(|t| match t {
        crate::sim::input::Term::Measured(m) => Some(m),
        _ => None,
    })?;
    let &(t0, t1) = measured.steps().first()?;
    let more = match measured.steps().len() {
        1 => String::new(),
        k => format!(" (and {} more)", k - 1),
    };
    Some(format!(
        "{}: the drive jumps at {} within {}{more}, one or two sample intervals: the shape of that rise was not recorded, so nv and the fast arms are fitted to a guess of it; sample faster or drive with a slower ramp",
        e.name,
        si(t0, "s"),
        si(t1 - t0, "s"),
    ))
}

/// εr of every free constant that sets it through a mixing rule (a filler mass
/// fraction w): εr(w), σ = |dεr/dw|·σ_w, the interval [εr(w₋), εr(w₊)] of w's (w
/// within its domain), identifiable when w is.
fn derived(free: &[params::Constant], estimates: &[Estimate]) -> Vec<Estimate> {
    use crate::material::check::MASS_FRACTION;
    let inside = |w: f64| w.clamp(MASS_FRACTION.min, MASS_FRACTION.max);
    free.iter()
        .zip(estimates)
        .filter_map(|(c, e)| {
            let m = c.mixture?;
            Some(Estimate {
                name: "eps_r".into(),
                value: m.eps_r(e.value),
                unit: "1".into(),
                std_error: e.std_error.map(|s| (m.deps_dw(e.value) * s).abs()),
                ci95: e.ci95.map(|[a, b]| {
                    let (a, b) = (m.eps_r(inside(a)), m.eps_r(inside(b)));
                    [a.min(b), a.max(b)]
                }),
                identifiable: e.identifiable,
                reason: e.reason.clone(),
                start: m.eps_r(e.start),
                at_bound: e.at_bound,
                ..e.clone()
            })
        })
        .collect()
}

/// The free constants `settings.profiles` names, as indices into the free list; a
/// name that is not a free constant is refused (before the search).
fn profile_indices(problem: &Problem, settings: &Settings) -> Result<Vec<usize>> {
    settings
        .profiles
        .iter()
        .map(|n| {
            problem
                .free
                .iter()
                .position(|c| c.name == *n)
                .ok_or_else(|| {
                    let free: Vec<&str> = problem.free.iter().map(|c| c.name.as_str()).collect();
                    Error::settings(format!("--profiles {n}: not a free constant"))
                        .with_hint(format!("the free constants: {}", free.join(", ")))
                })
        })
        .collect()
}

/// The σ of each residual row's channel, in problem order.
fn row_sigmas(problem: &Problem) -> Vec<f64> {
    let mut out = Vec::new();
    for (ei, ci, rows) in channel_rows(problem) {
        let s = problem.experiments[ei].channels[ci].sigma;
        out.extend(rows.map(|_| s));
    }
    out
}

/// Rows of the residual vector per (experiment, channel), in problem order.
fn channel_rows(problem: &Problem) -> Vec<(usize, usize, std::ops::Range<usize>)> {
    let mut at = 0;
    let mut out = Vec::new();
    for (ei, e) in problem.experiments.iter().enumerate() {
        for (ci, c) in e.channels.iter().enumerate() {
            let n = c.points();
            out.push((ei, ci, at..at + n));
            at += n;
        }
    }
    out
}

/// σ of every channel not given, from its residuals r (scaled by the old σ):
/// σ² = Σ(σ_old·r)² / (n_c − p·n_c/N) (module [`noise`]).
fn reestimate_sigma(problem: &mut Problem, given: &[Vec<bool>], r: &DVector<f64>, p: usize) {
    let total = r.len() as f64;
    for (ei, ci, rows) in channel_rows(problem) {
        if given[ei][ci] {
            continue;
        }
        let ch = &mut problem.experiments[ei].channels[ci];
        let nc = rows.len() as f64;
        let ss: f64 = rows.map(|i| (ch.sigma * r[i]).powi(2)).sum();
        let dof = (nc - p as f64 * nc / total).max(1.0);
        let s = (ss / dof).sqrt();
        if s.is_finite() && s > 0.0 {
            ch.sigma = s;
        }
    }
}

/// RMSE and %RMSE per channel from the scaled residuals at the optimum.
fn channel_fits(problem: &Problem, given: &[Vec<bool>], r: &DVector<f64>) -> Vec<ExperimentFit> {
    let rows = channel_rows(problem);
    problem
        .experiments
        .iter()
        .enumerate()
        .map(|(ei, e)| ExperimentFit {
            file: e.name.clone(),
            rows: e.rows(),
            channels: e
                .channels
                .iter()
                .enumerate()
                .map(|(ci, c)| {
                    let range = rows
                        .iter()
                        .find(|(a, b, _)| *a == ei && *b == ci)
                        .map(|x| x.2.clone())
                        .unwrap_or(0..0);
                    let n = range.len().max(1) as f64;
                    let rmse = c.sigma * (range.map(|i| r[i] * r[i]).sum::<f64>() / n).sqrt();
                    let measured: Vec<f64> =
                        c.values.iter().copied().filter(|v| v.is_finite()).collect();
                    ChannelFit {
                        channel: c.kind,
                        unit: c.kind.unit(),
                        points: c.points(),
                        sigma: c.sigma,
                        sigma_source: match given[ei][ci] {
                            true => SigmaSource::Given,
                            false => SigmaSource::Residuals,
                        },
                        rmse,
                        rmse_pct: rmse_percent(rmse, &measured),
                    }
                })
                .collect(),
        })
        .collect()
}

/// What the traces show (for the identifiability explanations).
fn context(problem: &Problem, runs: &[crate::sim::Outcome]) -> Context {
    let mut ctx = Context {
        capacitance: false,
        max_strain: 0.0,
        span: 0.0,
        min_dt: f64::INFINITY,
        arm_tau: params::constants(&problem.experiments[0].scene)
            .iter()
            .filter(|c| matches!(c.role, params::Role::ArmTau(_)))
            .map(|c| c.start)
            .collect(),
    };
    for (e, o) in problem.experiments.iter().zip(runs) {
        ctx.capacitance |= e
            .channels
            .iter()
            .any(|c| c.kind == ChannelKind::Capacitance);
        ctx.span = ctx.span.max(e.scene.time.span);
        let rest = o.rest_stretch;
        for s in &o.samples {
            ctx.max_strain = ctx.max_strain.max(((s.stretch - rest) / rest).abs());
        }
        for w in o.samples.windows(2) {
            ctx.min_dt = ctx.min_dt.min(w[1].time_s - w[0].time_s);
        }
    }
    ctx
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped damped stack (Yeoh) as a noisy contraction trace.
    fn experiment() -> Experiment {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("datasets/scenes/stack_step_5kV_damped.toml");
        let mut scene = crate::sim::scene::Scene::read(&path).expect("shipped scene");
        scene.time.span = 0.2;
        scene.time.samples = (1..=50).map(|i| 0.004 * i as f64).collect();
        Experiment::synthetic(&scene, &[(ChannelKind::Contraction, 1e-7)], 3).expect("runs")
    }

    /// A trial θ whose Yeoh law is Drucker-unstable over the traced stretches
    /// (C20 = −100·C10 softens it at once past λ = 1) is an infeasible point of
    /// the search, rejected with the reason before any simulation; the scene's own
    /// (stable) θ is evaluated.
    #[test]
    fn an_unstable_law_is_an_infeasible_trial() {
        let settings = Settings {
            free: Some(vec!["C10".into(), "C20".into()]),
            ..Settings::default()
        };
        let (mut problem, ..) = prepare(vec![experiment()], &settings).expect("prepares");
        assert!(problem.infeasible.is_some(), "the starting law is stable");
        let (n, k) = problem.dims();
        let mut r = DVector::zeros(n);
        let x0 = problem.x_of(&problem.theta);
        assert!(problem.eval(&x0, &mut r, None), "{:?}", problem.failure());
        let mut theta = problem.theta.clone();
        theta[1] = -100.0 * theta[0];
        let runs = problem.counts.get();
        let x = problem.x_of(&theta);
        assert_eq!(x.len(), k);
        assert!(!problem.eval(&x, &mut r, None));
        let why = problem.failure().unwrap_or_default();
        assert!(why.contains("Drucker-unstable"), "{why}");
        assert_eq!(problem.counts.get(), runs, "rejected before any run");
        let scene = &problem.experiments[0].scene;
        assert!(drucker_unstable(scene, &theta, (1.0, 1.01)).is_some());
        assert!(drucker_unstable(scene, &problem.theta, (1.0, 1.01)).is_none());
    }
}
