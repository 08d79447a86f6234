//! Forward simulation of stacked (seed Chapter 3) and helical (Chapter 4) dielectric
//! elastomer actuators.
//!
//! ```text
//! scene.toml ──scene::Scene::read (units → SI, validation)──► Scene (Send + Sync)
//! Scene ──fidelity::choose──► Fidelity ──plant::Plant──► ODE ──integrate──► Outcome
//! Plant ──static_curve──► static V(λ) and pull-in
//! ```
//! [`simulate`] is a pure function of the scene: identification can run many scenes
//! in parallel (rayon) and re-run one with changed `scene.material.params`.

pub mod breakdown;
pub mod budget;
pub mod derivatives;
pub mod fidelity;
pub mod helix;
pub mod input;
pub mod integrate;
pub mod plant;
pub mod presets;
pub mod sampling;
pub mod scene;
pub mod stack;
pub mod static_curve;

use fidelity::{AxialMode, Fidelity};
use integrate::{End, Extra, Method, Options, Stats};
use plant::Plant;
use scene::{Actuator, Scene, Source};
use serde::Serialize;

/// One output sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// Time (s).
    pub time_s: f64,
    /// Input (open-circuit source) voltage (V).
    pub input_v: f64,
    /// Terminal voltage (V).
    pub voltage_v: f64,
    /// Thickness stretch λ.
    pub stretch: f64,
    /// Actuator length (m).
    pub length_m: f64,
    /// Capacitance (F).
    pub capacitance_f: f64,
    /// Current into the actuator incl. dC/dt·V and leakage (A).
    pub current_a: f64,
    /// Electrical power V·I (W).
    pub power_w: f64,
    /// Leakage part of the power (W).
    pub leakage_w: f64,
    /// Helix complementary angle α (rad); NaN for a stack.
    pub alpha_rad: f64,
    /// Reference contraction of a closed loop (NaN without one).
    pub reference: f64,
    /// Contraction sensed from the capacitance (1 − sqrt(C_rest/C)).
    pub sensed_contraction: f64,
}

/// An event during the run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Event {
    /// `pull_in`.
    pub kind: String,
    /// Time (s).
    pub time_s: f64,
    /// Terminal voltage (V).
    #[serde(rename = "voltage_V")]
    pub voltage_v: f64,
    /// Stretch.
    pub stretch: f64,
}

/// Energy bookkeeping (J) from t = 0 to the end of the run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Energy {
    /// Electrical work delivered by the source.
    pub input_j: f64,
    /// Electrostatic energy ½CV² at the end minus at the start.
    pub field_j: f64,
    /// Hyperelastic energy change.
    pub elastic_j: f64,
    /// Energy stored in Maxwell arm springs (and frozen springs).
    pub arms_j: f64,
    /// Kinetic energy at the end.
    pub kinetic_j: f64,
    /// Work done against the load (F_load·ΔZ shortening).
    pub load_j: f64,
    /// Dissipated in dashpots.
    pub viscous_j: f64,
    /// Dissipated by leakage.
    pub leakage_j: f64,
    /// Dissipated in the source (resistance, ideal-step charging).
    pub source_j: f64,
    /// input − everything else.
    pub residual_j: f64,
}

/// Status of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// Reached the end time with a finite state throughout.
    Completed,
    /// Stopped at pull-in: a result (the actuator does not survive this input).
    PullIn,
    /// No result past the failure time: the integrator failed, ran out of its step
    /// budget, or the state or an output became non-finite.
    Failed,
}

impl std::fmt::Display for RunStatus {
    /// The name the JSON uses (`completed`, `pull_in`, `failed`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RunStatus::Completed => "completed",
            RunStatus::PullIn => "pull_in",
            RunStatus::Failed => "failed",
        })
    }
}

/// Integrator report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IntegratorReport {
    /// Method.
    pub method: Method,
    /// Why it was chosen.
    pub reason: String,
    /// Relative tolerance.
    pub rtol: f64,
    /// Counts.
    pub stats: Stats,
    /// Status.
    pub status: RunStatus,
    /// Reason of the status.
    pub message: String,
}

/// Result of [`simulate`].
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// Scene name.
    pub scene: String,
    /// What model ran.
    pub fidelity: Fidelity,
    /// Axial mode about the rest state.
    pub mode: AxialMode,
    /// Events (pull-in).
    pub events: Vec<Event>,
    /// Integrator report.
    pub integrator: IntegratorReport,
    /// Energy balance.
    pub energy: Energy,
    /// Rest stretch under the load.
    pub rest_stretch: f64,
    /// Rest length (m).
    pub rest_length_m: f64,
    /// Closed loop: %RMSE of the true contraction against the reference, normalised
    /// by the reference's range (seed Eq. 3.28).
    pub tracking_rmse_pct: Option<f64>,
    /// Warnings (extrapolated material model, undetermined damping, ...).
    pub warnings: Vec<String>,
    /// Samples (not in the JSON summary): every one ([`simulate`]), or every
    /// `decimation`-th and the last ([`simulate_streaming`]).
    #[serde(skip)]
    pub samples: Vec<Sample>,
    /// Number of samples the run produced (`samples` may hold fewer).
    pub sample_count: usize,
    /// Every how many samples one is in `samples` (1: all).
    pub decimation: usize,
    /// Extremes over each kept sample's output intervals, aligned with `samples`,
    /// when the samples do not resolve the motion or were decimated ([`sampling`]).
    #[serde(skip)]
    pub envelope: Option<Vec<sampling::Interval>>,
    /// Extremes over the whole integration: every output sample and every accepted
    /// step ([`Outcome::extremes`]).
    #[serde(skip)]
    extremes: Extremes,
    /// The same over the output samples only ([`Outcome::extremes_at_samples`]).
    #[serde(skip)]
    extremes_sampled: Extremes,
    /// Forward sensitivities at the samples, if asked for ([`RunOptions::sensitivities`]).
    #[serde(skip)]
    pub sensitivities: Option<Sensitivities>,
}

/// Forward sensitivities of the sampled trajectory to the parameters θ of the plant
/// that ran (`Plant::sensitivity_params`): the hyperelastic constants, each
/// integrated arm's k and τ, the dashpot Nv and εr. Arms lumped away by the
/// fidelity choice are not parameters of that plant. One row per sample, one
/// column per θj, for every channel a trace can measure; a pull-in sample's row is
/// NaN (the event time itself moves with θ). A run asked for some entries only
/// ([`RunOptions::sensitivities_of`]) has a column for each of those.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sensitivities {
    /// Parameter names with units, one per column.
    pub params: Vec<String>,
    /// The θ entry of each column (indices into `theta`).
    pub columns: Vec<usize>,
    /// Parameter values θ (SI), every entry.
    pub theta: Vec<f64>,
    /// ∂λ/∂θj (`Sample::stretch`).
    pub stretch: Rows,
    /// ∂L/∂θj (m per unit of θj; `Sample::length_m`).
    pub length: Rows,
    /// ∂C/∂θj (F per unit of θj; `Sample::capacitance_f`).
    pub capacitance: Rows,
    /// ∂I/∂θj (A per unit of θj; `Sample::current_a`, which depends on λ̇, V and
    /// the source state: [`Plant::output_sensitivities`]); no rows in a run
    /// without them ([`RunOptions::no_current_sensitivity`]).
    pub current: Rows,
    /// Over every sample (kept or not), the largest finite |θj·∂λ/∂θj|.
    pub peak_stretch: Vec<f64>,
    /// Over every sample, the largest finite |θj·∂C/∂θj| (F).
    pub peak_capacitance: Vec<f64>,
    /// Whether the current's sensitivities are computed
    /// ([`RunOptions::no_current_sensitivity`]).
    #[serde(skip)]
    with_current: bool,
    /// Row of [`Plant::output_sensitivities`] at the last sample (no allocation per
    /// sample).
    #[serde(skip)]
    scratch: Vec<derivatives::OutputSensitivity>,
}

/// One channel's sensitivities: a row of nθ values per sample (`rows[k][j]` =
/// ∂(channel)/∂θj at sample k), stored flat; serialised as a list of rows.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Rows {
    width: usize,
    len: usize,
    data: Vec<f64>,
}

impl Rows {
    fn new(width: usize, rows: usize) -> Rows {
        Rows {
            width,
            len: 0,
            data: Vec::with_capacity(width * rows),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The rows, sample by sample.
    pub fn iter(&self) -> impl Iterator<Item = &[f64]> + '_ {
        (0..self.len).map(|k| &self[k])
    }

    fn push(&mut self, row: impl Iterator<Item = f64>) {
        self.data.extend(row);
        self.len += 1;
        debug_assert_eq!(self.data.len(), self.len * self.width);
    }
}

impl std::ops::Index<usize> for Rows {
    type Output = [f64];
    fn index(&self, k: usize) -> &[f64] {
        &self.data[k * self.width..(k + 1) * self.width]
    }
}

impl Serialize for Rows {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(self.iter())
    }
}

impl Sensitivities {
    /// The column of θ entry `k`, if the run carried it.
    pub fn column(&self, k: usize) -> Option<usize> {
        self.columns.iter().position(|&c| c == k)
    }

    /// The sensitivities at the rest state (∂y0/∂θ, `Plant::initial_state_sensitivity`),
    /// recorded as the row of sample 0; room for `rows` kept rows.
    fn at_start(p: &Plant, y0: &[f64], rows: usize, with_current: bool) -> Sensitivities {
        let columns = p.sensitivity_columns().to_vec();
        let (n, np) = (y0.len(), columns.len());
        let ns = integrate::System::dynamic_dim(p);
        let mut s0 = vec![0.0; n * np];
        p.initial_state_sensitivity(&mut s0);
        // row-major n × nθ → column per parameter, the leading ns states
        let cols: Vec<f64> = (0..np * ns).map(|k| s0[(k % ns) * np + k / ns]).collect();
        let zero = derivatives::OutputSensitivity {
            stretch: 0.0,
            length: 0.0,
            capacitance: 0.0,
            current: 0.0,
        };
        let names = p.sensitivity_params();
        let mut se = Sensitivities {
            params: columns.iter().map(|&k| names[k].clone()).collect(),
            columns,
            theta: p.theta(),
            stretch: Rows::new(np, rows),
            length: Rows::new(np, rows),
            capacitance: Rows::new(np, rows),
            current: Rows::new(np, if with_current { rows } else { 0 }),
            peak_stretch: vec![0.0; np],
            peak_capacitance: vec![0.0; np],
            with_current,
            scratch: vec![zero; np],
        };
        se.compute(p, 0.0, y0, &cols);
        se
    }

    /// The row of a sample at (t, y) from the state sensitivities `s` (column by
    /// column, `s[j·ns + i]` = ∂yi/∂θj of the leading ns states), into the scratch row and the peaks.
    fn compute(&mut self, p: &Plant, t: f64, y: &[f64], s: &[f64]) {
        match self.with_current {
            true => p.output_sensitivities(t, y, s, &mut self.scratch),
            false => p.state_output_sensitivities(y, s, &mut self.scratch),
        }
        for (j, d) in self.scratch.iter().enumerate() {
            let th = self.theta[self.columns[j]];
            let peak = |v: f64, m: &mut f64| {
                let v = (th * v).abs();
                if v.is_finite() {
                    *m = m.max(v);
                }
            };
            peak(d.stretch, &mut self.peak_stretch[j]);
            peak(d.capacitance, &mut self.peak_capacitance[j]);
        }
    }

    /// Keep the scratch row (the last computed).
    fn keep(&mut self) {
        let d = &self.scratch;
        self.stretch.push(d.iter().map(|d| d.stretch));
        self.length.push(d.iter().map(|d| d.length));
        self.capacitance.push(d.iter().map(|d| d.capacitance));
        if self.with_current {
            self.current.push(d.iter().map(|d| d.current));
        }
    }

    /// The NaN row of a pull-in sample (the event time itself moves with θ).
    fn unknown(&mut self) {
        self.scratch.fill(derivatives::OutputSensitivity {
            stretch: f64::NAN,
            length: f64::NAN,
            capacitance: f64::NAN,
            current: f64::NAN,
        });
    }
}

/// Run settings that are not part of the scene.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunOptions {
    /// Override the scene's integrator.
    pub method: Option<Method>,
    /// Override the scene's relative tolerance.
    pub rtol: Option<f64>,
    /// Fixed step (convergence tests only).
    pub fixed_step: Option<f64>,
    /// Integrate the forward sensitivities to the plant's parameters too.
    pub sensitivities: bool,
    /// With `sensitivities`, leave out the current's ([`Sensitivities::current`]
    /// gets no rows): stretch, length and capacitance then come in closed form
    /// from the state's ([`Plant::state_output_sensitivities`]), a search that fits
    /// no current saving the forward pass through the output code at every sample.
    pub no_current_sensitivity: bool,
    /// A step budget tighter than the guard's estimate (`budget::Cost::step_budget`);
    /// a run that reaches it fails and says so.
    pub max_steps: Option<usize>,
    /// The largest |V| of the drive over the span ([`drive_max`]), when the caller
    /// already has it: a search that runs one input thousands of times computes it
    /// once (sampling a sine drive costs a quarter of a plain run).
    pub v_max: Option<f64>,
    /// Let `auto` choose as for a run with sensitivities, whether or not this one
    /// has them: a search that compares plain runs with sensitivity runs
    /// (identification) needs one integrator for both.
    pub auto_as_with_sensitivities: bool,
    /// With `sensitivities`, carry only the θ entries of this mask (bit k: entry
    /// k, [`Sensitivities::columns`]; none beyond the 128th); None: every entry. A search that holds
    /// some constants (a profile, a reduced model) integrates no column it does
    /// not read: each column costs a lane of ∂f/∂θ and a right-hand side of the
    /// corrector's solve at every step.
    pub sensitivities_of: Option<u128>,
}

/// The largest |V| the scene drives over its span: the PID's ceiling, or the
/// input's [`Waveform::max_abs`]. It sets the tolerance scales of the source state
/// and the energy quadratures ([`Plant::scales`]).
pub fn drive_max(scene: &Scene) -> f64 {
    match &scene.control {
        Some(pid) => pid.v_max,
        None => scene.input.max_abs(0.0, scene.time.span),
    }
}

fn sample(p: &Plant, t: f64, y: &[f64]) -> Sample {
    let e = p.output(t, y);
    Sample {
        time_s: t,
        input_v: e.u,
        voltage_v: e.voltage,
        stretch: y[0],
        length_m: p.length(y[0]),
        capacitance_f: e.capacitance,
        current_a: e.current,
        power_w: e.voltage * e.current,
        leakage_w: e.leakage,
        alpha_rad: match p.actuator {
            Actuator::Helix(h) => h.alpha(y[0]),
            Actuator::Stack(_) => f64::NAN,
        },
        reference: p
            .control
            .as_ref()
            .map(|c| c.reference.eval(t).0)
            .unwrap_or(f64::NAN),
        sensed_contraction: p.sensed_contraction(y[0]),
    }
}

/// The quantities every run reports are finite (α and the reference are NaN by
/// design where they do not apply).
fn sample_finite(s: &Sample) -> bool {
    [
        s.time_s,
        s.input_v,
        s.voltage_v,
        s.stretch,
        s.length_m,
        s.capacitance_f,
        s.current_a,
        s.power_w,
        s.leakage_w,
    ]
    .iter()
    .all(|v| v.is_finite())
}

/// Hyperelastic energy Vol·∫P dλ from a to b (200-panel composite 3-point Gauss–Legendre).
pub fn elastic_energy(p: &Plant, a: f64, b: f64) -> f64 {
    const X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let n = 200;
    let h = (b - a) / n as f64;
    let mut s = 0.0;
    for i in 0..n {
        let m = a + (i as f64 + 0.5) * h;
        for k in 0..3 {
            s += W[k] * p.stress(m + 0.5 * h * X[k]);
        }
    }
    p.vol * s * 0.5 * h
}

/// Simulate a scene: [`prepare`] the run, [`integrate`] it, [`summarise`] it
/// (energy balance, sampling, range and damping warnings, tracking error). Every
/// sample is kept in [`Outcome::samples`].
pub fn simulate(scene: &Scene, opts: &RunOptions) -> crate::Result<Outcome> {
    simulate_with(scene, opts, usize::MAX, None)
}

/// [`simulate`], each sample sent to `sink` (if any) as the run reaches it, and only
/// every k-th kept in [`Outcome::samples`] (k the smallest that keeps at most
/// `charted` of them; the last is kept too), with the extremes over the samples in
/// between in [`Outcome::envelope`]: memory does not grow with the sample count.
/// The summary (extremes, warnings, tracking error, energy) is over every sample.
/// The first error of `sink` stops the writing and is returned after the run.
pub fn simulate_streaming(
    scene: &Scene,
    opts: &RunOptions,
    charted: usize,
    sink: Option<&mut Sink>,
) -> crate::Result<Outcome> {
    simulate_with(scene, opts, charted, sink)
}

fn simulate_with(
    scene: &Scene,
    opts: &RunOptions,
    charted: usize,
    sink: Option<&mut Sink>,
) -> crate::Result<Outcome> {
    let run = prepare(scene, opts)?;
    let every = (scene.time.samples.len() + 1).div_ceil(charted.max(2) - 1);
    let mut env = sampling::Envelope::new(
        run.cost.fidelity.inertia,
        &run.cost.mode,
        &scene.time.samples,
    );
    if every > 1 {
        env = env.grouped();
    }
    let mut ran = integrate(scene, &run, opts, every, Some(env), sink);
    if let Some(e) = ran.record.sink_error.take() {
        return Err(e);
    }
    Ok(summarise(scene, run, ran))
}

/// One sample as the run reaches it, for a [`Sink`].
#[derive(Debug, Clone, Copy)]
pub struct Row<'a> {
    /// The sample.
    pub sample: &'a Sample,
    /// Rest length (m): the stroke is the rest length minus the length.
    pub rest_length_m: f64,
    /// With sensitivities: the parameter names ([`Sensitivities::params`]) and the
    /// outputs' derivatives to each (NaN at a pull-in sample).
    pub sensitivities: Option<(&'a [String], &'a [derivatives::OutputSensitivity])>,
}

/// Where [`simulate_streaming`] sends each sample.
pub type Sink<'a> = dyn FnMut(&Row) -> crate::Result<()> + 'a;

/// The trajectory of a scene without the report-only work of [`simulate`]: the
/// same guard, plant, integrator and samples (bit for bit), the same check that a
/// `Completed` run has finite outputs, no energy balance or warnings. What
/// identification runs in its inner loop (issue 10).
pub fn trajectory(scene: &Scene, opts: &RunOptions) -> crate::Result<Trajectory> {
    let run = prepare(scene, opts)?;
    Ok(integrate(scene, &run, opts, 1, None, None).trajectory)
}

/// The trajectory of a run (see [`trajectory`]).
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// `samples[0]` is t = 0, then one per `scene.time.samples` reached (plus the
    /// pull-in sample of a run stopped there).
    pub samples: Vec<Sample>,
    /// Forward sensitivities at the samples, if asked for.
    pub sensitivities: Option<Sensitivities>,
    /// Status.
    pub status: RunStatus,
    /// Reason of the status.
    pub message: String,
    /// Integrator that ran.
    pub method: Method,
    /// Its counts.
    pub stats: Stats,
    /// Rest stretch under the load.
    pub rest_stretch: f64,
    /// Rest length (m).
    pub rest_length_m: f64,
}

/// A run made ready by [`prepare`].
struct Prepared {
    /// The guard's estimate, with the fidelity and axial mode it chose.
    cost: budget::Cost,
    /// The plant of that fidelity.
    plant: Plant,
    /// Integrator and why.
    method: Method,
    reason: String,
    /// Relative tolerance.
    rtol: f64,
    /// Tolerances and limits.
    options: Options,
    /// Restart times [0, input kinks…, span].
    bounds: Vec<f64>,
    /// Typical state magnitudes (absolute tolerances).
    scale: Vec<f64>,
    /// Where `auto` chose BDF for a plain run: the steps after which BDF stalls
    /// and gives way to Tsitouras ([`budget::Cost::explicit_steps`], see
    /// [`integrate`]).
    stall_steps: Option<usize>,
}

/// The guard ([`budget::check`]: domain, rest state, cost; it chooses the fidelity
/// and the axial mode once), the plant, the integrator (requested, or
/// [`auto_method`]), its options and the restart times.
fn prepare(scene: &Scene, opts: &RunOptions) -> crate::Result<Prepared> {
    let cost = budget::check(scene)?;
    let mut plant = Plant::new(scene, cost.fidelity.inertia, &cost.fidelity.keep)
        .map_err(|why| budget::no_rest_state(scene, why))?;
    if let Some(mask) = opts.sensitivities_of {
        plant.keep_sensitivities(mask);
    }
    let mode = &cost.mode;
    let rtol = opts.rtol.unwrap_or(scene.time.rtol);
    let requested = opts.method.or(scene.time.method);
    let (method, reason) = match (requested, &cost.auto) {
        (Some(m), _) => (m, "requested".to_string()),
        (None, Some((m, why))) => {
            // Dormand–Prince 8(5,3) has no sensitivities: Tsitouras 5(4) has, at
            // its own stability limit
            let (m, why, stability) = match *m == Method::Dop853
                && (opts.sensitivities || opts.auto_as_with_sensitivities)
            {
                true => (
                    Method::Tsit45,
                    format!("{why}; with sensitivities, which it has not: explicit Tsitouras 5(4)"),
                    cost.stability_steps * budget::DOP853_STABILITY / budget::EXPLICIT_STABILITY,
                ),
                false => (*m, why.clone(), cost.stability_steps),
            };
            match opts.max_steps {
                // an explicit method cannot step past its stability limit: where
                // that alone needs more steps than the caller's budget, it cannot
                // complete, while BDF may (it damps a ringing it need not resolve)
                Some(cap) if stability > cap as f64 => (
                    Method::Bdf,
                    format!(
                        "{why}; stability alone needs more than the run's budget of {cap} steps: variable-order BDF"
                    ),
                ),
                _ => (m, why),
            }
        }
        (None, None) => unreachable!("budget::estimate chooses for a scene without an integrator"),
    };
    let span = scene.time.span;
    let v_max = opts.v_max.unwrap_or_else(|| drive_max(scene));
    let options = Options {
        rtol,
        atol: scene.time.atol * rtol / scene.time.rtol,
        h_max: span / 10.0,
        h_init: 0.01
            * span
                .min(1.0 / mode.frequency_hz)
                .min(match scene.input.time_scale() {
                    t if t > 0.0 => t,
                    _ => f64::INFINITY,
                }),
        max_steps: opts
            .max_steps
            .map_or(cost.step_budget(), |m| m.min(cost.step_budget())),
        fixed_step: opts.fixed_step,
    };
    let mut kinks = match &scene.control {
        Some(pid) => pid.reference.kinks(0.0, span),
        None => scene.input.kinks(0.0, span),
    };
    kinks.dedup();
    // BDF is auto's choice where it takes fewer steps than the explicit method's
    // stability limit allows; one that takes more than the explicit run would
    // (a controller chattering on its clamp collapses its step) has lost that
    // bet. Not with sensitivities: Tsitouras's start from ∂y/∂θ mid-run is not
    // supported.
    let stall_steps = (requested.is_none()
        && cost.auto.as_ref().is_some_and(|(m, _)| *m == Method::Bdf)
        && method == Method::Bdf
        && !opts.sensitivities
        && opts.fixed_step.is_none())
    .then_some(cost.explicit_steps.ceil() as usize)
    .filter(|&cap| cap < options.max_steps);
    let mut bounds = vec![0.0];
    bounds.extend(kinks);
    bounds.push(span);
    Ok(Prepared {
        scale: plant.scales(v_max),
        cost,
        plant,
        method,
        reason,
        rtol,
        options,
        bounds,
        stall_steps,
    })
}

/// Whether auto's BDF, stopped by `why` after the steps in `stats`, stalled: it
/// reached `cap` steps ([`Prepared::stall_steps`]) or its step size collapsed.
fn stalled(why: &str, stats: &Stats, cap: usize) -> bool {
    (why.starts_with("step budget exhausted") && stats.steps + stats.rejected >= cap)
        || why.starts_with("step size underflow")
}

/// What [`integrate`] leaves: the trajectory, the events and where the run ended.
struct Integrated {
    trajectory: Trajectory,
    events: Vec<Event>,
    /// Time and state at the end of the run (pull-in, failure or the span).
    t_end: f64,
    y_end: Vec<f64>,
    /// What was gathered over every sample.
    record: Recorded,
    /// Number of samples recorded.
    sample_count: usize,
    /// Every how many samples one was kept.
    decimation: usize,
}

/// The sensitivities of a sample handed to [`Recorder::record`].
enum SensAt<'a> {
    /// None to compute: the run has none, or the scratch row already holds them
    /// (sample 0, [`Sensitivities::at_start`]).
    Ready,
    /// The state sensitivities, column by column.
    At(&'a [f64]),
    /// A pull-in sample: not defined.
    Unknown,
}

/// Takes each sample as the run reaches it: keeps every `every`-th (and the last),
/// sends each to the sink, and gathers what the summary needs over all of them.
struct Recorder<'s, 'k> {
    every: usize,
    count: usize,
    /// Whether the last sample recorded was kept.
    last_kept: bool,
    last: Option<Sample>,
    kept: Vec<Sample>,
    sens: Option<Sensitivities>,
    env: Option<sampling::Envelope>,
    rest_length_m: f64,
    sink: Option<&'s mut Sink<'k>>,
    done: Recorded,
}

/// What a [`Recorder`] gathered over every sample.
struct Recorded {
    /// Over the output samples ([`Outcome::extremes_at_samples`]); after the run,
    /// [`integrate`] keeps the union with the accepted steps' in `extremes`.
    sampled: Extremes,
    /// Over the samples and the accepted steps ([`Outcome::extremes`]).
    extremes: Extremes,
    /// Σ (contraction − reference)², the reference's range (closed loop).
    tracking: (f64, f64, f64),
    first_bad: Option<Sample>,
    /// The envelope's bands and warning ([`sampling::Envelope::finish`]).
    envelope: (Option<Vec<sampling::Interval>>, Option<String>),
    sink_error: Option<crate::Error>,
}

impl Recorder<'_, '_> {
    fn record(
        &mut self,
        p: &Plant,
        t: f64,
        y: &[f64],
        s: SensAt,
        steps: sampling::Interval,
        force: bool,
    ) {
        let x = sample(p, t, y);
        let keep = force || self.count.is_multiple_of(self.every);
        self.count += 1;
        if let Some(se) = &mut self.sens {
            match s {
                SensAt::Ready => {}
                SensAt::At(s) => se.compute(p, t, y, s),
                SensAt::Unknown => se.unknown(),
            }
            if keep {
                se.keep();
            }
        }
        let d = &mut self.done;
        d.sampled.add(&p.actuator, self.rest_length_m, &x);
        if p.control.is_some() {
            let (ss, lo, hi) = &mut d.tracking;
            *ss += (1.0 - x.length_m / self.rest_length_m - x.reference).powi(2);
            *lo = lo.min(x.reference);
            *hi = hi.max(x.reference);
        }
        if d.first_bad.is_none() && !sample_finite(&x) {
            d.first_bad = Some(x);
        }
        if let Some(env) = &mut self.env {
            env.sample(&x, steps, keep);
        }
        if let (Some(sink), None) = (&mut self.sink, &d.sink_error) {
            let row = Row {
                sample: &x,
                rest_length_m: self.rest_length_m,
                sensitivities: self
                    .sens
                    .as_ref()
                    .map(|se| (&se.params[..], &se.scratch[..])),
            };
            if let Err(e) = sink(&row) {
                d.sink_error = Some(e);
            }
        }
        if keep {
            self.kept.push(x);
        }
        self.last_kept = keep;
        self.last = Some(x);
    }

    /// Keep the last sample if it was not, and close the envelope.
    fn finish(mut self) -> (Vec<Sample>, Option<Sensitivities>, usize, Recorded) {
        let add_last = !self.last_kept;
        if add_last {
            self.kept.extend(self.last);
            if let Some(se) = &mut self.sens {
                se.keep();
            }
        }
        if let Some(env) = self.env {
            self.done.envelope = env.finish(add_last);
        }
        (self.kept, self.sens, self.count, self.done)
    }
}

/// Integrate a prepared run from the rest state: the samples (and their
/// sensitivities), the pull-in event (the instantaneous stiffness reaching zero),
/// an ideal source's charging losses at its jumps, the status. Keeps every
/// `every`-th sample (and the last), sends each to `sink`; `env` (if any) takes the
/// samples and, where it wants them, the accepted steps between them.
fn integrate<'s, 'k>(
    scene: &Scene,
    run: &Prepared,
    opts: &RunOptions,
    every: usize,
    env: Option<sampling::Envelope>,
    sink: Option<&'s mut Sink<'k>>,
) -> Integrated {
    let p = &run.plant;
    let l = p.layout();
    let span = scene.time.span;
    let sensitivities = opts.sensitivities;
    let mut y = p.initial_state();
    let mut stats = Stats::default();
    let wants_steps = env.as_ref().is_some_and(|e| e.wants_steps());
    // A run with a report (an envelope) also takes its extremes at every accepted
    // step; a bare trajectory (identification's inner loop) does not.
    let track_steps = env.is_some();
    let kept = (scene.time.samples.len() + 2).div_ceil(every) + 1;
    let mut rec = Recorder {
        every,
        count: 0,
        last_kept: false,
        last: None,
        kept: Vec::with_capacity(kept),
        sens: sensitivities
            .then(|| Sensitivities::at_start(p, &y, kept, !opts.no_current_sensitivity)),
        env,
        rest_length_m: p.length(p.lam0),
        sink,
        done: Recorded {
            sampled: Extremes::NONE,
            extremes: Extremes::NONE,
            tracking: (0.0, f64::INFINITY, f64::NEG_INFINITY),
            first_bad: None,
            envelope: (None, None),
            sink_error: None,
        },
    };
    let none = sampling::Interval::EMPTY;
    rec.record(p, 0.0, &y, SensAt::Ready, none, true);
    let e_scale = p.vol * p.tangent(p.lam0).abs().max(1.0);
    let event = |t: f64, y: &[f64]| {
        let v = p.voltage(t, y);
        p.instant_stiffness(y[0], v) / e_scale
    };
    // An ideal source jumping by ΔV charges C through zero resistance: it delivers
    // V⁺·C·ΔV, of which ½C·ΔV² is lost in the wiring (also at t = 0 from 0 V).
    let ideal = matches!(scene.source, Source::Ideal);
    let jump = |y: &mut [f64], vm: f64, vp: f64| {
        let (c, _, _) = p.capacitance(y[0]);
        y[l.quad] += vp * c * (vp - vm);
        y[l.quad + 3] += 0.5 * c * (vp - vm).powi(2);
    };
    if ideal {
        jump(&mut y, 0.0, scene.input.eval(0.0).0);
    }
    let mut at_kink = |t: f64, y: &mut [f64]| {
        if ideal {
            let vm = scene.input.eval(t - 1e-12 * span.max(1.0)).0;
            let vp = scene.input.eval(t).0;
            jump(y, vm, vp);
        }
    };
    // the magnitudes of the carried sensitivity columns' parameters
    let theta: Vec<f64> = {
        let all = p.theta();
        p.sensitivity_columns().iter().map(|&k| all[k]).collect()
    };
    // The accepted steps since the last sample (when the envelope wants them).
    let steps = std::cell::Cell::new(none);
    let last_sample = std::cell::Cell::new(0.0);
    // The end of the last accepted step (where auto's BDF hands over).
    let last_step = std::cell::Cell::new(0.0);
    // The extremes over the accepted steps.
    let step_extremes = std::cell::Cell::new(Extremes::NONE);
    let rest_length_m = p.length(p.lam0);
    let mut step = |t: f64, y: &[f64]| {
        last_step.set(t);
        if !track_steps {
            return;
        }
        let x = sample(p, t, y);
        let mut e = step_extremes.get();
        e.add(&p.actuator, rest_length_m, &x);
        step_extremes.set(e);
        if wants_steps && t > last_sample.get() {
            let mut i = steps.get();
            i.add(&x);
            steps.set(i);
        }
    };
    let mut out = |t: f64, y: &[f64], s: &[f64]| {
        let s = match sensitivities {
            true => SensAt::At(s),
            false => SensAt::Ready,
        };
        rec.record(p, t, y, s, steps.replace(none), false);
        last_sample.set(t);
    };
    let options = Options {
        max_steps: run.stall_steps.unwrap_or(run.options.max_steps),
        ..run.options
    };
    let end = integrate::run(
        p,
        run.method,
        &options,
        &run.scale,
        &run.bounds,
        &mut y,
        &scene.time.samples,
        match sensitivities {
            true => Extra::Sensitivities(&theta),
            false => Extra::None,
        },
        &mut out,
        &mut step,
        Some(&event),
        &mut at_kink,
        &mut stats,
    );
    // auto's BDF stalled: Tsitouras 5(4) goes on from its last accepted step
    // (the samples up to there are out) with what is left of the budget
    let mut method = run.method;
    let mut handover = String::new();
    let end = match (end, run.stall_steps) {
        (End::Failed(why), Some(cap)) if stalled(&why, &stats, cap) => {
            let t0 = last_step.get();
            let bounds: Vec<f64> = std::iter::once(t0)
                .chain(run.bounds.iter().copied().filter(|&b| b > t0))
                .collect();
            let samples = &scene.time.samples;
            let samples = &samples[samples.partition_point(|&t| t <= t0)..];
            method = Method::Tsit45;
            handover = format!(
                "; auto's BDF stalled at t = {t0:.6e} s ({} steps, the explicit method's estimate for the whole run): explicit Tsitouras 5(4) from there",
                stats.steps + stats.rejected
            );
            integrate::run(
                p,
                method,
                &run.options,
                &run.scale,
                &bounds,
                &mut y,
                samples,
                Extra::None,
                &mut out,
                &mut step,
                Some(&event),
                &mut at_kink,
                &mut stats,
            )
        }
        (end, _) => end,
    };
    let (status, message, t_end, events) = match end {
        End::Done => (
            RunStatus::Completed,
            format!("reached the end time{handover}"),
            span,
            Vec::new(),
        ),
        End::Event(te) => {
            let s = match sensitivities {
                true => SensAt::Unknown,
                false => SensAt::Ready,
            };
            rec.record(p, te, &y, s, steps.replace(none), true);
            (
                RunStatus::PullIn,
                format!("pull-in at t = {te:.6} s: the instantaneous stiffness vanished"),
                te,
                vec![Event {
                    kind: "pull_in".into(),
                    time_s: te,
                    voltage_v: p.voltage(te, &y),
                    stretch: y[0],
                }],
            )
        }
        End::Failed(why) => {
            let t = rec.last.map(|s| s.time_s).unwrap_or(0.0);
            let why = if why.starts_with("step budget exhausted") {
                // an explicit method held at its stability limit wants an implicit
                // one; an implicit one that many steps past the estimate (rejected
                // steps, Newton failing) stalls on a right-hand side that is not
                // smooth, such as a controller chattering on its clamp, which an
                // explicit method steps through
                let advice = match method {
                    Method::Tsit45 | Method::Dp54 | Method::Dop853 => "dynamics that much stiffer than the axial mode (high control gains, a fast source) want the implicit integrator = \"bdf\"",
                    _ => "an implicit method stalls on a right-hand side that is not smooth (a controller switching on its clamp, a source saturating): check the controller's gains and limits, or try the explicit integrator = \"tsit45\"",
                };
                format!(
                    "{why}: the run was estimated at {} steps before it started (sim::budget); {advice}{handover}",
                    budget::fmt_g(run.cost.steps.round())
                )
            } else {
                format!("{why}{handover}")
            };
            (RunStatus::Failed, why, t, Vec::new())
        }
    };
    let (samples, sens, count, mut record) = rec.finish();
    record.extremes = record.sampled;
    record.extremes.union(&step_extremes.get());
    // A finite state can still give a non-finite output (a stretch outside the
    // model's domain): such a run has no result either.
    let (status, message) = match &record.first_bad {
        Some(bad) if status != RunStatus::Failed => (
            RunStatus::Failed,
            format!(
                "a non-finite output at t = {:.6e} s (stretch {}, voltage {} V, capacitance {} F)",
                bad.time_s, bad.stretch, bad.voltage_v, bad.capacitance_f
            ),
        ),
        _ => (status, message),
    };
    Integrated {
        trajectory: Trajectory {
            samples,
            sensitivities: sens,
            status,
            message,
            method,
            stats,
            rest_stretch: p.lam0,
            rest_length_m: p.length(p.lam0),
        },
        events,
        t_end,
        y_end: y,
        record,
        sample_count: count,
        decimation: every,
    }
}

/// The report of an integrated run: energy balance, the sampling envelope and
/// warnings, the tracking error.
fn summarise(scene: &Scene, run: Prepared, ran: Integrated) -> Outcome {
    let p = &run.plant;
    let tr = ran.trajectory;
    let rec = ran.record;
    let energy = energy_balance(p, ran.t_end, &ran.y_end);
    let (envelope, undersampled) = rec.envelope;
    let mut warnings: Vec<String> = undersampled.into_iter().collect();
    let x = rec.extremes;
    warnings.extend(model_warnings(
        scene,
        p,
        &run.cost.mode,
        (x.stretch_min, x.stretch_max),
    ));
    // Closed loop: %RMSE of the true contraction 1 − Z/Z_rest against the
    // reference, normalised by the reference's range (seed Eq. 3.28).
    let tracking_rmse_pct = scene.control.as_ref().map(|_| {
        let (ss, lo, hi) = rec.tracking;
        100.0 * (ss / ran.sample_count as f64).sqrt() / (hi - lo)
    });
    Outcome {
        tracking_rmse_pct,
        scene: scene.name.clone(),
        fidelity: run.cost.fidelity,
        mode: run.cost.mode,
        events: ran.events,
        integrator: IntegratorReport {
            method: tr.method,
            reason: run.reason,
            rtol: run.rtol,
            stats: tr.stats,
            status: tr.status,
            message: tr.message,
        },
        energy,
        rest_stretch: tr.rest_stretch,
        rest_length_m: tr.rest_length_m,
        warnings,
        samples: tr.samples,
        sample_count: ran.sample_count,
        decimation: ran.decimation,
        envelope,
        extremes: x,
        extremes_sampled: rec.sampled,
        sensitivities: tr.sensitivities,
    }
}

/// Energy bookkeeping from the rest state to (t_end, y): the quadratures (work in,
/// dashpot and arm dissipation, leakage, source losses) against the stored energies
/// (field ½CV², hyperelastic Vol·∫P dλ, arm springs Vol·σj²/(2kj) and frozen
/// springs, kinetic ½M·λ̇², the load's work); the residual closes the balance.
fn energy_balance(p: &Plant, t_end: f64, y: &[f64]) -> Energy {
    let l = p.layout();
    let y0 = p.initial_state();
    let (c0, _, _) = p.capacitance(y0[0]);
    let v_start = p.voltage(0.0, &y0);
    let e = p.output(t_end, y);
    let kinetic = l.v.map(|i| 0.5 * p.mass * y[i] * y[i]).unwrap_or(0.0);
    let arms_j: f64 = p
        .arms
        .iter()
        .enumerate()
        .map(|(j, &(k, _))| p.vol * y[l.sig + j].powi(2) / (2.0 * k))
        .sum::<f64>()
        + p.vol * 0.5 * p.frozen_k * (y[0] - p.lam_f).powi(2);
    let field = 0.5 * e.capacitance * e.voltage.powi(2) - 0.5 * c0 * v_start * v_start;
    let q = l.quad;
    let mut energy = Energy {
        input_j: y[q],
        field_j: field + 0.5 * c0 * v_start * v_start,
        elastic_j: elastic_energy(p, p.lam0, y[0]),
        arms_j,
        kinetic_j: kinetic,
        load_j: -p.f_load * p.l0 * (y[0] - p.lam0),
        viscous_j: y[q + 1],
        leakage_j: y[q + 2],
        source_j: y[q + 3],
        residual_j: 0.0,
    };
    energy.residual_j = energy.input_j
        - energy.field_j
        - energy.elastic_j
        - energy.arms_j
        - energy.kinetic_j
        - energy.load_j
        - energy.viscous_j
        - energy.leakage_j
        - energy.source_j;
    energy
}

/// Warnings about the model rather than the run: the material's
/// ([`Scene::material_warnings`]: a fit used outside its data's stretch range,
/// constants its file calls not identifiable), damping that relaxation tests do not
/// determine, an ideal step.
fn model_warnings(scene: &Scene, p: &Plant, mode: &AxialMode, stretch: (f64, f64)) -> Vec<String> {
    let mut warnings = scene.material_warnings(p.mode, stretch);
    if mode.damping_ratio < 0.05 && mode.dashpot_share < 0.5 {
        warnings.push(format!(
            "the axial mode ({:.0} Hz) is damped only by Maxwell arms far above their relaxation frequencies (ζ = {:.1e}, Q = {:.0}); relaxation tests do not pin this damping down, so ringing after fast inputs depends on a number the data do not determine",
            mode.frequency_hz, mode.damping_ratio, mode.q_factor
        ));
    }
    if matches!(scene.source, Source::Ideal) && scene.input.time_scale() == 0.0 {
        warnings.push("ideal voltage step: a real supply has a finite rise time (give source.rise_time or source.resistance_ohm)".into());
    }
    warnings
}

/// The plant a scene runs with (full model, all arms, with inertia), or the error
/// of a scene without a stable rest state.
pub fn full_plant(scene: &Scene) -> crate::Result<Plant> {
    Plant::new(scene, true, &vec![true; scene.material.viscous.arms.len()])
        .map_err(|why| budget::no_rest_state(scene, why))
}

impl Outcome {
    /// The run's extremes over the whole integration: every output sample and every
    /// accepted step of the integrator, so a peak between samples (a fast source
    /// rise, ringing) is in them. What every command reports.
    pub fn extremes(&self) -> Extremes {
        self.extremes
    }

    /// The same over the output samples only: what the trajectory CSV shows, never
    /// more than [`Outcome::extremes`].
    pub fn extremes_at_samples(&self) -> Extremes {
        self.extremes_sampled
    }
}

/// Extremes of a run: the one place that takes them ([`Extremes::add`]), at the
/// output samples and, for a run with a report, at every accepted step of the
/// integrator. Between accepted steps the solution is the integrator's
/// interpolant, accurate to the step's tolerance; a peak inside a step is missed by
/// at most the change of the quantity over that step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Extremes {
    /// Smallest stretch.
    pub stretch_min: f64,
    /// Largest stretch.
    pub stretch_max: f64,
    /// Largest stroke, the rest length minus the length (m).
    #[serde(rename = "stroke_max_m")]
    pub stroke_max_m: f64,
    /// Largest |current| (A).
    #[serde(rename = "current_max_A")]
    pub current_max_a: f64,
    /// Largest power (W).
    #[serde(rename = "power_max_W")]
    pub power_max_w: f64,
    /// Largest leakage power (W).
    #[serde(rename = "leakage_max_W")]
    pub leakage_max_w: f64,
    /// Largest true field in a layer, E = V/h(λ) (`Actuator::field`), and where.
    #[serde(rename = "field_max")]
    pub field: breakdown::FieldPeak,
}

impl Extremes {
    /// Nothing seen yet.
    pub const NONE: Extremes = Extremes {
        stretch_min: f64::INFINITY,
        stretch_max: f64::NEG_INFINITY,
        stroke_max_m: f64::NEG_INFINITY,
        current_max_a: 0.0,
        power_max_w: f64::NEG_INFINITY,
        leakage_max_w: 0.0,
        field: breakdown::FieldPeak::NONE,
    };

    /// Widen by the values of `x` (a sample, or the state of an accepted step as a
    /// sample) of actuator `a` with rest length `rest_length_m`. Non-finite values
    /// are left out (`f64::max` and `min` skip NaN).
    pub fn add(&mut self, a: &Actuator, rest_length_m: f64, x: &Sample) {
        self.stretch_min = self.stretch_min.min(x.stretch);
        self.stretch_max = self.stretch_max.max(x.stretch);
        self.stroke_max_m = self.stroke_max_m.max(rest_length_m - x.length_m);
        self.current_max_a = self.current_max_a.max(x.current_a.abs());
        self.power_max_w = self.power_max_w.max(x.power_w);
        self.leakage_max_w = self.leakage_max_w.max(x.leakage_w);
        self.field.widen(a, Some(x.time_s), x.voltage_v, x.stretch);
    }

    /// Widen by the extremes of another part of the same run.
    fn union(&mut self, o: &Extremes) {
        self.stretch_min = self.stretch_min.min(o.stretch_min);
        self.stretch_max = self.stretch_max.max(o.stretch_max);
        self.stroke_max_m = self.stroke_max_m.max(o.stroke_max_m);
        self.current_max_a = self.current_max_a.max(o.current_max_a);
        self.power_max_w = self.power_max_w.max(o.power_max_w);
        self.leakage_max_w = self.leakage_max_w.max(o.leakage_max_w);
        if o.field.field > self.field.field {
            self.field = o.field;
        }
    }
}
