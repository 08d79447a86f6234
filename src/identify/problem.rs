//! The identification least-squares problem: the simulator inside the residual.
//!
//! For experiment e, channel c and trace row i with a measured value y_eci and noise
//! σ_ec, the residual is r = (m_c(t_i; θ) − y_eci)/σ_ec, with m_c the simulated
//! channel at the trace's own sample times. Scaling by σ makes channels with
//! different units combine correctly (½‖r‖² is half the χ²). The Jacobian is exact:
//! ∂r/∂x_j = (∂m_c/∂θ_k)·(dθ_k/dx_j)/σ_ec with ∂m/∂θ from the simulator's forward
//! sensitivities ([`crate::sim::Sensitivities`]) and dθ/dx from the search
//! coordinates ([`super::params::Space`]), times dεr/dw for a filler mass fraction,
//! whose simulator parameter is εr ([`super::params::Constant::dsim_dvalue`]).

use super::params::{set_theta, Constant};
use crate::fit::lm::LeastSquares;
use crate::sim::scene::{FidelityChoice, Scene};
use crate::sim::{
    drive_max, simulate, trajectory, Outcome, RunOptions, RunStatus, Sample, Sensitivities,
    Trajectory,
};
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

pub use crate::io::trace::ChannelKind;

/// The simulated value of a channel at sample `s`, given the first sample `s0` (the
/// rest state at t = 0); NaN for a force, which the simulator does not compute
/// (identification refuses force channels before it starts).
pub fn simulated(kind: ChannelKind, s0: &Sample, s: &Sample) -> f64 {
    kind.simulated(s, s0.length_m).unwrap_or(f64::NAN)
}

/// ∂(simulated value)/∂θk at row `i` (row 0 is the first sample), from column `k`
/// of `se` (that of a θ entry: [`Sensitivities::column`]).
pub fn sensitivity(kind: ChannelKind, se: &Sensitivities, i: usize, k: usize) -> f64 {
    match kind {
        ChannelKind::Contraction => se.length[0][k] - se.length[i][k],
        ChannelKind::Length => se.length[i][k],
        ChannelKind::Stretch => se.stretch[i][k],
        ChannelKind::Capacitance => se.capacitance[i][k],
        ChannelKind::Current => se.current[i][k],
        ChannelKind::Force => f64::NAN,
    }
}

/// One measured channel of one experiment.
#[derive(Debug, Clone)]
pub struct Channel {
    /// What it measures.
    pub kind: ChannelKind,
    /// Values per trace row (SI; NaN where not logged).
    pub values: Vec<f64>,
    /// Noise standard deviation (SI); set by [`super::identify`] from `--sigma` or
    /// from the data.
    pub sigma: f64,
}

impl Channel {
    /// Rows with a value.
    pub fn points(&self) -> usize {
        self.values.iter().filter(|v| v.is_finite()).count()
    }
}

/// One experiment: its scene (input and sample times from the trace) and channels.
#[derive(Clone)]
pub struct Experiment {
    /// Trace file (for reports).
    pub name: String,
    /// The scene that reproduces it: `time.samples` are the trace's times after the
    /// first, so simulated sample i is trace row i.
    pub scene: Scene,
    /// Measured channels.
    pub channels: Vec<Channel>,
}

impl Experiment {
    /// Number of trace rows.
    pub fn rows(&self) -> usize {
        self.scene.time.samples.len() + 1
    }

    /// Refuse an experiment that cannot start at the constants θ: the simulator's
    /// guard ([`crate::sim::budget::check`]: domain, rest state, step and memory
    /// budget) on its scene. Input as given that cannot run is unusable, unlike a
    /// run that starts and fails ([`super::failure`]).
    pub fn check_start(&self, theta: &[f64]) -> crate::Result<()> {
        let mut scene = self.scene.clone();
        set_theta(&mut scene, theta);
        crate::sim::budget::check(&scene)
            .map(|_| ())
            .map_err(|err| {
                crate::Error::settings(format!(
                    "{}: the scene at its starting constants cannot run this trace: {err}",
                    self.name
                ))
            })
    }
}

/// Counts of the work done, shared by every copy of a problem (the starts of a
/// multi-start run on clones, in parallel).
#[derive(Debug, Default)]
pub struct Counts {
    /// Simulator runs without sensitivities.
    pub runs: AtomicUsize,
    /// Simulator runs with sensitivities.
    pub sensitivity_runs: AtomicUsize,
}

impl Counts {
    /// (plain runs, sensitivity runs) so far.
    pub fn get(&self) -> (usize, usize) {
        (
            self.runs.load(Ordering::Relaxed),
            self.sensitivity_runs.load(Ordering::Relaxed),
        )
    }
}

/// A run of the search may take this many times the steps of the run at the
/// starting constants. Far starts and long LM steps reach corners of the box where
/// the scene becomes a different problem for its integrator: a dashpot 50× weaker
/// turns the rig scene (datasets/scenes/stack_rig_7s.toml, 820 BDF steps at its
/// constants) into a lightly damped oscillation that took Tsitouras 5(4) 105 000
/// steps, 6.3 s with sensitivities, and BDF 366 000. Such a run fails at its budget
/// (the LM then shortens its step, or the start is reported failed with the reason)
/// instead of costing seconds; the constants it probed were far from the trace.
pub const WORK_FACTOR: usize = 10;

/// A run that takes more than this many times the integrator steps of its run at
/// the starting constants is heavy: the next trial is evaluated without
/// sensitivities ([`LeastSquares::jacobian_with_trial`]).
pub const HEAVY: usize = 2;

/// A point whose ½χ² exceeds this many times the number of residuals (an RMS
/// residual above √20 ≈ 4.5 σ, where a fit has about 1 σ) is far from the trace:
/// its runs are heavy too. There trials are rejected often and a run with
/// sensitivities costs up to 6× a plain one near the trace (measured on the rig
/// trace: 24 ms against 7 ms a run).
pub const FAR: f64 = 10.0;

/// A start of a multi-start whose cost is above this many times the cost the
/// first start reached ([`LeastSquares::stands_at`]) runs the simulator at
/// [`FAR_RTOL_FACTOR`] × the relative tolerance: it cannot be the best search
/// while it stays there, and its trials need only be ranked against each other.
/// The first start, and every start once within this factor, run at the
/// tolerance asked, so the best search ends on runs at that tolerance.
pub const FAR_ABOVE: f64 = 10.0;

/// The tolerance factor of a search [`FAR_ABOVE`] the first start's cost (at
/// most [`FAR_RTOL_MAX`]): there the RMS residual is several σ and more, and an
/// integration error of 100 × rtol (10⁻⁴ of the signal at the usual 10⁻⁶, ≈ 0.1 σ
/// where the noise is 0.1 % of the signal) changes neither the ranking of its
/// trials nor the step's direction, while its runs at the stiff corners far
/// starts visit take about 0.6× the work (rig trace, 8 starts: 4.1–4.3 s of CPU
/// time → 3.3–3.6 s).
pub const FAR_RTOL_FACTOR: f64 = 100.0;

/// The loosest tolerance of a far run ([`FAR_RTOL_FACTOR`]).
pub const FAR_RTOL_MAX: f64 = 1e-4;

/// The tolerance factor of the runs that check the integration error at the
/// optimum ([`Problem::residuals_more_accurate`]): their error is about 1/100 of the
/// search's (2.5× the steps of a 5th-order method), so their difference from the
/// search's residuals is the search's integration error to within about 1 %.
pub const CHECK_RTOL_FACTOR: f64 = 0.01;

/// The tightest tolerance of a check run ([`CHECK_RTOL_FACTOR`]): a little above
/// the round-off of a double-precision integration.
pub const CHECK_RTOL_MIN: f64 = 1e-13;

/// The smallest step budget (a short trace at its constants may take only a few
/// dozen steps).
const MIN_BUDGET: usize = 2000;

/// The problem the search minimises. Cheap to clone (one per multi-start).
#[derive(Clone)]
pub struct Problem {
    /// Experiments, fitted jointly: they share θ.
    pub experiments: Vec<Experiment>,
    /// The free constants, in search order.
    pub free: Vec<Constant>,
    /// θ with every fixed constant at its value (free entries are overwritten).
    pub theta: Vec<f64>,
    /// Simulator settings.
    pub run: RunOptions,
    /// Step budget of each experiment's runs ([`WORK_FACTOR`] × the steps at the
    /// starting constants; None where that run failed, which the search reports).
    pub budgets: Vec<Option<usize>>,
    /// Each experiment's largest |V| ([`crate::sim::drive_max`]): the drive does not
    /// change with θ.
    v_max: Vec<f64>,
    /// Integrator steps of each experiment's run at the starting constants.
    base_steps: Vec<Option<usize>>,
    /// Whether the last run took more than [`HEAVY`] × its base steps in some
    /// experiment, or its point was [`FAR`] from the trace
    /// ([`LeastSquares::jacobian_with_trial`]).
    heavy: bool,
    /// Whether the search stands [`FAR_ABOVE`] the first start's cost
    /// ([`LeastSquares::stands_at`]): runs are then made at the looser tolerance
    /// of [`FAR_RTOL_FACTOR`].
    far: bool,
    /// Work done so far (shared by clones).
    pub counts: Arc<Counts>,
    /// Why this copy's last evaluation failed ([`LeastSquares::failure`]); each
    /// start's copy keeps its own.
    failure: Option<String>,
    /// Why θ is not a candidate, checked before any run (the hyperelastic law
    /// Drucker-unstable over the traced stretches: [`super::drucker_unstable`]);
    /// such a point is an infeasible step of the search.
    pub infeasible: Option<Infeasible>,
}

/// The physics test of [`Problem::infeasible`]: why θ is not a candidate, if not.
pub type Infeasible = Arc<dyn Fn(&[f64]) -> Option<String> + Send + Sync>;

impl Problem {
    /// The problem of fitting `free` (θ elsewhere at `theta`) to `experiments`. An
    /// `auto` fidelity could lump an arm away, which would drop it from θ, so each
    /// scene's is resolved here to the dynamic or quasi-static model with every arm
    /// integrated.
    pub fn new(
        mut experiments: Vec<Experiment>,
        free: Vec<Constant>,
        theta: Vec<f64>,
        run: RunOptions,
    ) -> crate::Result<Problem> {
        for e in &mut experiments {
            if e.scene.time.fidelity == FidelityChoice::Auto {
                let f = crate::sim::fidelity::choose(&e.scene)?;
                e.scene.time.fidelity = match f.inertia {
                    true => FidelityChoice::Dynamic,
                    false => FidelityChoice::QuasiStatic,
                };
            }
        }
        let v_max: Vec<f64> = experiments.iter().map(|e| drive_max(&e.scene)).collect();
        let base_steps: Vec<Option<usize>> = experiments
            .iter_mut()
            .zip(&v_max)
            .map(|(e, &v_max)| {
                set_theta(&mut e.scene, &theta);
                let run = RunOptions {
                    v_max: Some(v_max),
                    ..run
                };
                let o = trajectory(&e.scene, &run).ok()?;
                (o.status == RunStatus::Completed).then_some(o.stats.steps)
            })
            .collect();
        let budgets = base_steps
            .iter()
            .map(|s| s.map(|s| (WORK_FACTOR * s).max(MIN_BUDGET)))
            .collect();
        Ok(Problem {
            experiments,
            free,
            theta,
            run,
            budgets,
            v_max,
            base_steps,
            heavy: false,
            far: false,
            counts: Arc::default(),
            failure: None,
            infeasible: None,
        })
    }

    /// θ for search coordinates x.
    pub fn theta_at(&self, x: &[f64]) -> Vec<f64> {
        let mut th = self.theta.clone();
        for (c, &xi) in self.free.iter().zip(x) {
            th[c.index] = c.space.theta(xi);
        }
        th
    }

    /// The search coordinates of θ.
    pub fn x_of(&self, theta: &[f64]) -> Vec<f64> {
        self.free
            .iter()
            .map(|c| c.space.x(theta[c.index]))
            .collect()
    }

    /// The free constants' entries of θ as a mask (bit k: entry k), the
    /// sensitivities a run of the search carries
    /// ([`RunOptions::sensitivities_of`]); None (every entry) where one lies beyond
    /// the mask's 128 bits.
    pub fn free_mask(&self) -> Option<u128> {
        self.free.iter().try_fold(0u128, |m, c| {
            (c.index < u128::BITS as usize).then(|| m | 1u128 << c.index)
        })
    }

    /// Bounds in search coordinates.
    pub fn x_bounds(&self) -> Vec<(f64, f64)> {
        self.free
            .iter()
            .map(|c| {
                let (a, b) = (c.space.x(c.bounds.0), c.space.x(c.bounds.1));
                (a.min(b), a.max(b))
            })
            .collect()
    }

    /// Total number of measured values.
    pub fn points(&self) -> usize {
        self.experiments
            .iter()
            .flat_map(|e| &e.channels)
            .map(Channel::points)
            .sum()
    }

    /// Run every experiment at θ (with sensitivities if asked), the lean run without
    /// the report's work ([`crate::sim::trajectory`]): the trajectories, or why θ
    /// gives no usable one ([`unusable`]).
    pub fn simulate_at(
        &mut self,
        theta: &[f64],
        sensitivities: bool,
    ) -> std::result::Result<Vec<Trajectory>, String> {
        let accuracy = match self.far {
            true => Accuracy::Far,
            false => Accuracy::Asked,
        };
        self.runs_at(theta, sensitivities, accuracy)
    }

    /// [`Problem::simulate_at`] at the tolerance `accuracy` says.
    fn runs_at(
        &mut self,
        theta: &[f64],
        sensitivities: bool,
        accuracy: Accuracy,
    ) -> std::result::Result<Vec<Trajectory>, String> {
        let opts = RunOptions {
            sensitivities,
            no_current_sensitivity: !self.fits_current(),
            sensitivities_of: self.free_mask(),
            ..self.run
        };
        let mut out = Vec::with_capacity(self.experiments.len());
        let mut heavy = false;
        for (((e, &budget), &v_max), &base) in self
            .experiments
            .iter_mut()
            .zip(&self.budgets)
            .zip(&self.v_max)
            .zip(&self.base_steps)
        {
            let rtol = opts.rtol.unwrap_or(e.scene.time.rtol);
            let opts = RunOptions {
                max_steps: budget,
                v_max: Some(v_max),
                rtol: Some(accuracy.rtol(rtol)),
                ..opts
            };
            set_theta(&mut e.scene, theta);
            match sensitivities {
                true => &self.counts.sensitivity_runs,
                false => &self.counts.runs,
            }
            .fetch_add(1, Ordering::Relaxed);
            let o = trajectory(&e.scene, &opts).map_err(|err| format!("{}: {err}", e.name))?;
            heavy |= base.is_some_and(|b| o.stats.steps > HEAVY * b);
            if let Some(why) = unusable(e, &RunView::from(&o), theta.len()) {
                return Err(why);
            }
            out.push(o);
        }
        self.heavy = heavy;
        Ok(out)
    }

    /// At the optimum x: the full simulation of every experiment with its
    /// sensitivities (the report draws both), and the residuals and the Jacobian
    /// from them, so one sensitivity run per experiment serves the assessment and
    /// the report. Err: why x gives no usable run.
    pub fn optimum(
        &mut self,
        x: &[f64],
        r: &mut DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) -> std::result::Result<Vec<Outcome>, String> {
        let theta = self.theta_at(x);
        let opts = RunOptions {
            sensitivities: true,
            sensitivities_of: self.free_mask(),
            ..self.run
        };
        let mut out = Vec::with_capacity(self.experiments.len());
        for e in &mut self.experiments {
            set_theta(&mut e.scene, &theta);
            self.counts.sensitivity_runs.fetch_add(1, Ordering::Relaxed);
            let o = simulate(&e.scene, &opts).map_err(|err| format!("{}: {err}", e.name))?;
            if let Some(why) = unusable(e, &RunView::from(&o), theta.len()) {
                return Err(why);
            }
            out.push(o);
        }
        let runs: Vec<RunView> = out.iter().map(RunView::from).collect();
        match self.fill(x, &runs, r, Some(jac)) {
            true => Ok(out),
            false => Err("a non-finite residual or sensitivity at the optimum".into()),
        }
    }

    /// The residuals at x from plain runs at [`CHECK_RTOL_FACTOR`] × each
    /// experiment's tolerance (at least [`CHECK_RTOL_MIN`]): the same model,
    /// integrated more accurately, for [`super::integration_shift`]. Err: why x
    /// gives no usable run there.
    pub fn residuals_more_accurate(
        &mut self,
        x: &[f64],
        r: &mut DVector<f64>,
    ) -> std::result::Result<(), String> {
        let out = self.runs_at(&self.theta_at(x), false, Accuracy::Check)?;
        let runs: Vec<RunView> = out.iter().map(RunView::from).collect();
        match self.fill(x, &runs, r, None) {
            true => Ok(()),
            false => Err("a non-finite residual".into()),
        }
    }

    /// Whether some experiment measures the current (whose sensitivities a run
    /// then computes: [`RunOptions::no_current_sensitivity`]).
    fn fits_current(&self) -> bool {
        self.experiments
            .iter()
            .flat_map(|e| &e.channels)
            .any(|c| c.kind == ChannelKind::Current)
    }

    /// Residuals (and Jacobian) from the runs at x.
    fn fill(
        &self,
        x: &[f64],
        runs: &[RunView],
        r: &mut DVector<f64>,
        mut jac: Option<&mut DMatrix<f64>>,
    ) -> bool {
        // ∂(simulated)/∂θk → ∂r/∂x_col: one factor per column, the same on every row.
        let scale: Vec<(usize, f64)> = self
            .free
            .iter()
            .zip(x)
            .map(|(c, &xc)| {
                (
                    c.index,
                    c.dsim_dvalue(c.space.theta(xc)) * c.space.dtheta_dx(xc),
                )
            })
            .collect();
        let mut row = 0;
        for (e, o) in self.experiments.iter().zip(runs) {
            let s0 = &o.samples[0];
            // each free constant's column in this run's sensitivities
            let columns: Option<Vec<(usize, f64)>> = match (jac.is_some(), o.sensitivities) {
                (true, Some(se)) => scale
                    .iter()
                    .map(|&(k, f)| se.column(k).map(|c| (c, f)))
                    .collect(),
                _ => None,
            };
            if jac.is_some() && columns.is_none() {
                return false;
            }
            for ch in &e.channels {
                for (i, &y) in ch.values.iter().enumerate() {
                    if !y.is_finite() {
                        continue;
                    }
                    let m = simulated(ch.kind, s0, &o.samples[i]);
                    r[row] = (m - y) / ch.sigma;
                    if let (Some(j), Some(se), Some(columns)) =
                        (jac.as_deref_mut(), o.sensitivities, &columns)
                    {
                        for (col, &(k, f)) in columns.iter().enumerate() {
                            j[(row, col)] = sensitivity(ch.kind, se, i, k) * f / ch.sigma;
                        }
                    }
                    row += 1;
                }
            }
        }
        r.iter().all(|v| v.is_finite()) && jac.is_none_or(|j| j.iter().all(|v| v.is_finite()))
    }
}

/// The tolerance of a run of the problem.
#[derive(Debug, Clone, Copy)]
enum Accuracy {
    /// The tolerance asked (`--rtol`, else the scene's).
    Asked,
    /// A far start's ([`FAR_RTOL_FACTOR`], at most [`FAR_RTOL_MAX`]).
    Far,
    /// The integration check's ([`CHECK_RTOL_FACTOR`], at least [`CHECK_RTOL_MIN`]).
    Check,
}

impl Accuracy {
    /// The relative tolerance of a run whose asked tolerance is `rtol`.
    fn rtol(self, rtol: f64) -> f64 {
        match self {
            Accuracy::Asked => rtol,
            Accuracy::Far => (FAR_RTOL_FACTOR * rtol).min(FAR_RTOL_MAX).max(rtol),
            Accuracy::Check => (CHECK_RTOL_FACTOR * rtol).max(CHECK_RTOL_MIN),
        }
    }
}

/// What the residuals need of a run, lean ([`Trajectory`]) or full ([`Outcome`]).
struct RunView<'a> {
    status: RunStatus,
    message: &'a str,
    samples: &'a [Sample],
    sensitivities: Option<&'a Sensitivities>,
}

impl<'a> From<&'a Trajectory> for RunView<'a> {
    fn from(o: &'a Trajectory) -> Self {
        RunView {
            status: o.status,
            message: &o.message,
            samples: &o.samples,
            sensitivities: o.sensitivities.as_ref(),
        }
    }
}

impl<'a> From<&'a Outcome> for RunView<'a> {
    fn from(o: &'a Outcome) -> Self {
        RunView {
            status: o.integrator.status,
            message: &o.integrator.message,
            samples: &o.samples,
            sensitivities: o.sensitivities.as_ref(),
        }
    }
}

/// Why a run of `e` at a θ of `n_theta` constants gives no usable trajectory, if it
/// does not: a failure or a pull-in the trace does not show, sensitivities to
/// another θ (an arm lumped away), or too few samples.
fn unusable(e: &Experiment, run: &RunView, n_theta: usize) -> Option<String> {
    if run.status != RunStatus::Completed {
        return Some(format!("{}: {} ({})", e.name, run.status, run.message));
    }
    let np = run.sensitivities.map(|s| s.theta.len());
    if np.is_some_and(|np| np != n_theta) {
        return Some(format!(
            "{}: sensitivities to {np:?} constants, not the {n_theta} of θ (an arm lumped away?)",
            e.name
        ));
    }
    (run.samples.len() != e.rows()).then(|| {
        format!(
            "{}: {} samples for {} trace rows",
            e.name,
            run.samples.len(),
            e.rows()
        )
    })
}

impl LeastSquares for Problem {
    fn dims(&self) -> (usize, usize) {
        (self.points(), self.free.len())
    }

    fn eval(&mut self, x: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        let theta = self.theta_at(x);
        if let Some((c, v)) = self
            .free
            .iter()
            .map(|c| (c, theta[c.index]))
            .find(|(_, v)| !v.is_finite())
        {
            self.failure = Some(format!("{} = {v}", c.name));
            return false;
        }
        if let Some(why) = self.infeasible.as_ref().and_then(|f| f(&theta)) {
            self.failure = Some(why);
            return false;
        }
        match self.simulate_at(&theta, jac.is_some()) {
            Ok(runs) => {
                let runs: Vec<RunView> = runs.iter().map(RunView::from).collect();
                let ok = self.fill(x, &runs, r, jac);
                self.heavy |= r.norm_squared() > 2.0 * FAR * r.len() as f64;
                if !ok {
                    self.failure = Some("a non-finite residual or sensitivity".into());
                }
                ok
            }
            Err(why) => {
                self.failure = Some(why);
                false
            }
        }
    }

    fn failure(&self) -> Option<String> {
        self.failure.clone()
    }

    /// A run with sensitivities costs ≈ 3.5 plain ones (docs/identify.md), so a
    /// first trial with them beats a trial and a re-run, unless the last run was
    /// heavy: far from the trace (a far start, constants at stiff corners) runs
    /// cost several times their usual work and trials are rejected more often.
    fn jacobian_with_trial(&self) -> bool {
        !self.heavy
    }

    fn stands_at(&mut self, cost: f64, reference: Option<f64>) {
        self.far = reference.is_some_and(|r| cost > FAR_ABOVE * r);
    }

    /// A search [`FAR_ABOVE`] the first start's cost cannot be the best while it
    /// stays there: its steps need a direction, not an exact Jacobian, and a
    /// sensitivity run there costs several plain ones ([`FAR`]), so it takes
    /// Broyden's secant updates between them.
    fn secant_jacobian(&self) -> bool {
        self.far
    }
}

impl Experiment {
    /// The experiment of a measured trace on `base` (its input and sample times from
    /// the trace, [`crate::io::trace::Trace::scene`]), every measured channel kept.
    /// The measured voltage is the actuator's terminal voltage, so the scene's source
    /// model (rise time, resistance) is replaced by an ideal source: the supply's
    /// dynamics are already in the measurement.
    pub fn from_trace(trace: &crate::io::trace::Trace, base: &Scene) -> crate::Result<Experiment> {
        Experiment::from_trace_within(trace, base, None)
    }

    /// [`Experiment::from_trace`] with the measured drive fitted by `deadline`
    /// (the run's time budget; past it, an error).
    pub fn from_trace_within(
        trace: &crate::io::trace::Trace,
        base: &Scene,
        deadline: Option<std::time::Instant>,
    ) -> crate::Result<Experiment> {
        let mut scene = trace.scene(base, deadline)?;
        scene.source = crate::sim::scene::Source::Ideal;
        Ok(Experiment {
            name: trace.provenance.path.clone(),
            scene,
            channels: trace
                .channels
                .iter()
                .map(|c| Channel {
                    kind: c.kind,
                    values: c.values.clone(),
                    sigma: f64::NAN,
                })
                .collect(),
        })
    }
}

impl Experiment {
    /// A synthetic experiment: `scene` simulated at its own constants, each channel
    /// (kind, σ in SI) with Gaussian noise from a seeded generator (ChaCha8). For
    /// tests and benches of identification with a known truth.
    pub fn synthetic(
        scene: &Scene,
        channels: &[(ChannelKind, f64)],
        seed: u64,
    ) -> crate::Result<Experiment> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let o = simulate(scene, &RunOptions::default())?;
        if o.integrator.status != RunStatus::Completed {
            return Err(crate::Error::settings(format!(
                "{}: the scene does not run to its end ({})",
                scene.name, o.integrator.message
            )));
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let s0 = o.samples[0];
        let channels = channels
            .iter()
            .map(|&(kind, sigma)| {
                let n = Normal::new(0.0, sigma).map_err(|e| {
                    crate::Error::settings(format!("noise σ {sigma} of {kind}: {e}"))
                })?;
                Ok(Channel {
                    kind,
                    values: o
                        .samples
                        .iter()
                        .map(|s| simulated(kind, &s0, s) + n.sample(&mut rng))
                        .collect(),
                    sigma: f64::NAN,
                })
            })
            .collect::<crate::Result<_>>()?;
        Ok(Experiment {
            name: format!("{}-synthetic-{seed}", scene.name),
            scene: scene.clone(),
            channels,
        })
    }
}
