//! The ±1σ confidence band of an identified model's trace: the parameter
//! covariance propagated through the simulator's output sensitivities.
//!
//! At sample i of channel c the simulated value m_i(θ) has the first-order (delta
//! method) standard deviation σ_i = √(g_iᵀ Σ g_i), with g_i = ∂m_i/∂θ over the free
//! constants (the forward sensitivities of the run at the optimum, times dεr/dw for
//! a filler mass fraction, [`Constant::dsim_dvalue`]) and Σ the covariance of the
//! free constants, Σ_ab = ρ_ab·σ_a·σ_b from their standard errors and correlation
//! ([`covariance`]). These are the rows of the search's Jacobian times the
//! channel's noise σ_c (the Jacobian's rows are residuals scaled by 1/σ_c, its
//! columns the search coordinates, and the covariance there is Σ transformed by
//! the same dθ/dx), so the band is in the channel's own unit, at every sample,
//! measured or not.

use super::params::{constants, Constant};
use super::problem::{sensitivity, ChannelKind, Experiment};
use super::Identification;
use crate::fit::diagnostics::{covariance, gradient_std};

impl Identification {
    /// The standard deviation of the identified model's `kind` channel at every
    /// sample of experiment `ei` (`e`, as identified), in the channel's SI unit; None
    /// when the run has no sensitivities or a free constant has no standard error
    /// (not identifiable, or held at a bound: no band can be drawn).
    pub fn model_std(&self, e: &Experiment, ei: usize, kind: ChannelKind) -> Option<Vec<f64>> {
        let run = self.runs.get(ei)?;
        let se = run.sensitivities.as_ref()?;
        let std_error: Vec<Option<f64>> = self.parameters.iter().map(|p| p.std_error).collect();
        let cov = covariance(&std_error, &self.assessment.correlation)?;
        let all = constants(&e.scene);
        let free: Vec<&Constant> = self
            .parameters
            .iter()
            .map(|p| all.iter().find(|c| c.name == p.name))
            .collect::<Option<_>>()?;
        let grads: Vec<Vec<f64>> = free
            .iter()
            .zip(&self.parameters)
            .map(|(c, p)| {
                let d = c.dsim_dvalue(p.value);
                let k = se.column(c.index)?;
                Some(
                    (0..run.samples.len())
                        .map(|i| sensitivity(kind, se, i, k) * d)
                        .collect(),
                )
            })
            .collect::<Option<_>>()?;
        gradient_std(&grads, &cov)
    }
}
