//! The identification least-squares problem: the simulator inside the residual.
//!
//! For experiment e, channel c and trace row i with a measured value y_eci and noise
//! σ_ec, the residual is r = (m_c(t_i; θ) − y_eci)/σ_ec, with m_c the simulated
//! channel at the trace's own sample times. Scaling by σ makes channels with
//! different units combine correctly (½‖r‖² is half the χ²). The Jacobian is exact:
//! ∂r/∂x_j = (∂m_c/∂θ_k)·(dθ_k/dx_j)/σ_ec with ∂m/∂θ from the simulator's forward
//! sensitivities ([`crate::sim::Sensitivities`]) and dθ/dx from the search
//! coordinates ([`super::params::Space`]).

use super::params::{set_theta, Constant};
use crate::fit::lm::LeastSquares;
use crate::sim::scene::{FidelityChoice, Scene};
use crate::sim::{simulate, Outcome, RunOptions, RunStatus, Sample, Sensitivities};
use nalgebra::{DMatrix, DVector};

/// What a channel measures, and how the simulator's sample gives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Shortening from the trace's first row, L(t0) − L(t) (m).
    Contraction,
    /// Actuator length (m).
    Length,
    /// Thickness stretch λ.
    Stretch,
    /// Capacitance (F).
    Capacitance,
    /// Current into the actuator (A).
    Current,
}

impl Quantity {
    /// SI unit.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::Contraction | Quantity::Length => "m",
            Quantity::Stretch => "1",
            Quantity::Capacitance => "F",
            Quantity::Current => "A",
        }
    }

    /// The simulated value at sample `s`, given the first sample `s0`.
    pub fn value(self, s0: &Sample, s: &Sample) -> f64 {
        match self {
            Quantity::Contraction => s0.length_m - s.length_m,
            Quantity::Length => s.length_m,
            Quantity::Stretch => s.stretch,
            Quantity::Capacitance => s.capacitance_f,
            Quantity::Current => s.current_a,
        }
    }

    /// ∂value/∂θk at row `i` (row 0 is the first sample).
    pub fn sensitivity(self, se: &Sensitivities, i: usize, k: usize) -> f64 {
        match self {
            Quantity::Contraction => se.length[0][k] - se.length[i][k],
            Quantity::Length => se.length[i][k],
            Quantity::Stretch => se.stretch[i][k],
            Quantity::Capacitance => se.capacitance[i][k],
            Quantity::Current => se.current[i][k],
        }
    }
}

impl std::fmt::Display for Quantity {
    /// The name used by `--sigma` and in every output.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Quantity::Contraction => "contraction",
            Quantity::Length => "length",
            Quantity::Stretch => "stretch",
            Quantity::Capacitance => "capacitance",
            Quantity::Current => "current",
        })
    }
}

/// One measured channel of one experiment.
#[derive(Debug, Clone)]
pub struct Channel {
    /// What it measures.
    pub quantity: Quantity,
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

/// Counts of the work done.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Counts {
    /// Simulator runs without sensitivities.
    pub runs: usize,
    /// Simulator runs with sensitivities.
    pub sensitivity_runs: usize,
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
    /// Work done so far.
    pub counts: Counts,
    /// Why the last evaluation failed, if it did.
    pub last_failure: Option<String>,
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
            counts: Counts::default(),
            last_failure: None,
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

    /// Run every experiment at θ (with sensitivities if asked): the outcomes, or why
    /// θ gives no usable trajectory (an error, a failure, a pull-in the trace does not
    /// show, or too few samples).
    pub fn simulate_at(
        &mut self,
        theta: &[f64],
        sensitivities: bool,
    ) -> std::result::Result<Vec<Outcome>, String> {
        let opts = RunOptions {
            sensitivities,
            ..self.run
        };
        let mut out = Vec::with_capacity(self.experiments.len());
        for e in &mut self.experiments {
            set_theta(&mut e.scene, theta);
            match sensitivities {
                true => self.counts.sensitivity_runs += 1,
                false => self.counts.runs += 1,
            }
            let o = simulate(&e.scene, &opts).map_err(|err| format!("{}: {err}", e.name))?;
            match o.integrator.status {
                RunStatus::Completed => {}
                _ => {
                    return Err(format!(
                        "{}: {} ({})",
                        e.name, o.integrator.status, o.integrator.message
                    ))
                }
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

    /// Residuals (and Jacobian) from the outcomes at x.
    fn fill(
        &self,
        x: &[f64],
        runs: &[Outcome],
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
                    let m = ch.quantity.value(s0, &o.samples[i]);
                    r[row] = (m - y) / ch.sigma;
                    if let (Some(j), Some(se)) = (jac.as_deref_mut(), &o.sensitivities) {
                        for (col, c) in self.free.iter().enumerate() {
                            let d = ch.quantity.sensitivity(se, i, c.index);
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
            self.last_failure = Some(format!("{} = {v}", c.name));
            return false;
        }
        match self.simulate_at(&theta, jac.is_some()) {
            Ok(runs) => {
                let ok = self.fill(x, &runs, r, jac);
                if !ok {
                    self.last_failure = Some("a non-finite residual or sensitivity".into());
                }
                ok
            }
            Err(why) => {
                self.last_failure = Some(why);
                false
            }
        }
    }
}
