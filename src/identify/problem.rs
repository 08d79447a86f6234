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
    simulate, trajectory, Outcome, RunOptions, RunStatus, Sample, Sensitivities, Trajectory,
};
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

pub use crate::io::trace::ChannelKind;

/// The simulated value of a channel at sample `s`, given the first sample `s0` (the
/// rest state at t = 0); NaN for a force, which the simulator does not compute
/// (identification refuses force channels before it starts).
pub fn simulated(kind: ChannelKind, s0: &Sample, s: &Sample) -> f64 {
    kind.simulated(s, s0.length_m).unwrap_or(f64::NAN)
}

/// ∂(simulated value)/∂θk at row `i` (row 0 is the first sample).
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
}

/// Counts of the work done, shared by every copy of a problem (the starts of a
/// multi-start run on clones, in parallel).
#[derive(Debug, Default)]
pub struct Counts {
    /// Simulator runs without sensitivities.
    pub runs: AtomicUsize,
    /// Simulator runs with sensitivities.
    pub sensitivity_runs: AtomicUsize,
    /// Why the last evaluation that failed did (any copy).
    pub last_failure: Mutex<Option<String>>,
}

impl Counts {
    /// (plain runs, sensitivity runs) so far.
    pub fn get(&self) -> (usize, usize) {
        (
            self.runs.load(Ordering::Relaxed),
            self.sensitivity_runs.load(Ordering::Relaxed),
        )
    }

    /// Why the last failed evaluation failed.
    pub fn last_failure(&self) -> Option<String> {
        self.last_failure.lock().ok().and_then(|g| g.clone())
    }

    fn fail(&self, why: String) {
        if let Ok(mut g) = self.last_failure.lock() {
            *g = Some(why);
        }
    }
}

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
    /// Work done so far (shared by clones).
    pub counts: Arc<Counts>,
}

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
        Ok(Problem {
            experiments,
            free,
            theta,
            run,
            counts: Arc::default(),
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
    /// gives no usable one (an error, a failure, a pull-in the trace does not show,
    /// or too few samples).
    pub fn simulate_at(
        &mut self,
        theta: &[f64],
        sensitivities: bool,
    ) -> std::result::Result<Vec<Trajectory>, String> {
        let opts = RunOptions {
            sensitivities,
            ..self.run
        };
        let mut out = Vec::with_capacity(self.experiments.len());
        for e in &mut self.experiments {
            set_theta(&mut e.scene, theta);
            match sensitivities {
                true => &self.counts.sensitivity_runs,
                false => &self.counts.runs,
            }
            .fetch_add(1, Ordering::Relaxed);
            let o = trajectory(&e.scene, &opts).map_err(|err| format!("{}: {err}", e.name))?;
            if o.status != RunStatus::Completed {
                return Err(format!("{}: {} ({})", e.name, o.status, o.message));
            }
            let np = o.sensitivities.as_ref().map(|s| s.theta.len());
            if np.is_some_and(|np| np != theta.len()) {
                return Err(format!(
                    "{}: sensitivities to {np:?} constants, not the {} of θ (an arm lumped away?)",
                    e.name,
                    theta.len()
                ));
            }
            if o.samples.len() != e.rows() {
                return Err(format!(
                    "{}: {} samples for {} trace rows",
                    e.name,
                    o.samples.len(),
                    e.rows()
                ));
            }
            out.push(o);
        }
        Ok(out)
    }

    /// The full simulations (with the report's warnings) of every experiment at θ.
    pub fn outcomes_at(&mut self, theta: &[f64]) -> crate::Result<Vec<Outcome>> {
        let opts = self.run;
        self.experiments
            .iter_mut()
            .map(|e| {
                set_theta(&mut e.scene, theta);
                simulate(&e.scene, &opts)
            })
            .collect()
    }

    /// Residuals (and Jacobian) from the outcomes at x.
    fn fill(
        &self,
        x: &[f64],
        runs: &[Trajectory],
        r: &mut DVector<f64>,
        mut jac: Option<&mut DMatrix<f64>>,
    ) -> bool {
        let mut row = 0;
        for (e, o) in self.experiments.iter().zip(runs) {
            let s0 = &o.samples[0];
            for ch in &e.channels {
                for (i, &y) in ch.values.iter().enumerate() {
                    if !y.is_finite() {
                        continue;
                    }
                    let m = simulated(ch.kind, s0, &o.samples[i]);
                    r[row] = (m - y) / ch.sigma;
                    if let (Some(j), Some(se)) = (jac.as_deref_mut(), &o.sensitivities) {
                        for (col, c) in self.free.iter().enumerate() {
                            let d = sensitivity(ch.kind, se, i, c.index)
                                * c.dsim_dvalue(c.space.theta(x[col]));
                            j[(row, col)] = d * c.space.dtheta_dx(x[col]) / ch.sigma;
                        }
                    }
                    row += 1;
                }
            }
        }
        r.iter().all(|v| v.is_finite()) && jac.is_none_or(|j| j.iter().all(|v| v.is_finite()))
    }
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
            self.counts.fail(format!("{} = {v}", c.name));
            return false;
        }
        match self.simulate_at(&theta, jac.is_some()) {
            Ok(runs) => {
                let ok = self.fill(x, &runs, r, jac);
                if !ok {
                    self.counts
                        .fail("a non-finite residual or sensitivity".into());
                }
                ok
            }
            Err(why) => {
                self.counts.fail(why);
                false
            }
        }
    }
}

impl Experiment {
    /// The experiment of a measured trace on `base` (its input and sample times from
    /// the trace, [`crate::io::trace::Trace::scene`]), every measured channel kept.
    /// The measured voltage is the actuator's terminal voltage, so the scene's source
    /// model (rise time, resistance) is replaced by an ideal source: the supply's
    /// dynamics are already in the measurement.
    pub fn from_trace(trace: &crate::io::trace::Trace, base: &Scene) -> crate::Result<Experiment> {
        let mut scene = trace.scene(base)?;
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
