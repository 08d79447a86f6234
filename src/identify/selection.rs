//! Model no more than the traces need: `--arms auto` fits 0 … [`MAX_ARMS`] Maxwell
//! arms and keeps the fewest whose AICc is within [`DELTA_AICC`] of the smallest,
//! among the candidates whose status does not block (a redundant arm is not
//! identifiable, so its candidate is `ill_posed` and not eligible).
//!
//! The criteria compare χ² of one data set, so every candidate must weigh the
//! residuals with the same σ: the largest candidate is fitted first (σ of the
//! channels not given estimated from its residuals), and its σ are given to the
//! others. Candidate arms start at relaxation times spread geometrically from 5
//! sample intervals to half the longest trace (the time scales a trace can show),
//! their springs sharing the scene's total arm stiffness (μ0 without arms).

use super::noise::Sigma;
use super::problem::Experiment;
use super::{identify_with, Run, Settings};
use crate::error::{Error, Result};
use crate::fit::lm::Control;
use crate::material::file::Arm;
use serde::Serialize;

/// Most arms `--arms auto` tries.
pub const MAX_ARMS: usize = 4;

/// AICc margin within which the fewer-arm candidate is preferred.
pub const DELTA_AICC: f64 = 2.0;

/// One candidate of the comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// Number of arms.
    pub arms: usize,
    /// Free constants.
    pub free: usize,
    /// χ²/(N − p) at the common σ (None: the candidate failed).
    pub chi2_per_dof: Option<f64>,
    /// AICc (None when undefined or the candidate failed).
    pub aicc: Option<f64>,
    /// BIC (None: the candidate failed).
    pub bic: Option<f64>,
    /// Its status.
    pub status: crate::fit::Status,
    /// Eligible (a status that does not block, AICc defined).
    pub eligible: bool,
}

/// The arms of candidate `n` for `experiments` (see the module documentation).
fn arms(experiments: &[Experiment], n: usize) -> Vec<Arm> {
    let scene = &experiments[0].scene;
    let m = &scene.material;
    let total = match m.viscous.arms.iter().map(|a| a.k_pa).sum::<f64>() {
        k if k > 0.0 => k,
        _ => m.model.initial_shear_modulus(&m.params).abs(),
    };
    let dt = experiments
        .iter()
        .flat_map(|e| e.scene.time.samples.windows(2).map(|w| w[1] - w[0]))
        .fold(f64::INFINITY, f64::min);
    let span = experiments
        .iter()
        .map(|e| e.scene.time.span)
        .fold(0.0, f64::max);
    let (lo, hi) = (5.0 * dt, 0.5 * span);
    (0..n)
        .map(|j| {
            let f = if n == 1 {
                0.5
            } else {
                j as f64 / (n - 1) as f64
            };
            let tau = lo * (hi / lo).powf(f);
            let k = total / n as f64;
            Arm {
                k_pa: k,
                eta_pa_s: k * tau,
            }
        })
        .collect()
}

/// Fit 0 … [`MAX_ARMS`] arms and choose (module documentation): the chosen
/// identification and the comparison. A candidate that fails is not eligible; when
/// the largest fails there is no common σ, and the selection is that failure (with
/// no comparison).
pub fn select_arms(
    experiments: Vec<Experiment>,
    settings: &Settings,
    control: &(dyn Fn(usize) -> Control + Sync),
) -> Result<(Run, Vec<Candidate>)> {
    if settings
        .fix
        .iter()
        .chain(settings.free.iter().flatten())
        .any(|n| n.starts_with("arm"))
    {
        return Err(Error::settings(
            "--arms auto chooses the arms: --free and --fix cannot name arm constants",
        )
        .with_hint(
            "drop the armN names, or give the arms in the scene and leave out --arms auto",
        ));
    }
    let with_arms = |n: usize| -> Vec<Experiment> {
        let a = arms(&experiments, n);
        experiments
            .iter()
            .cloned()
            .map(|mut e| {
                e.scene.material.viscous.arms = a.clone();
                e
            })
            .collect()
    };
    let settings_for = |n: usize, s: &Settings| -> Settings {
        let mut s = s.clone();
        if let Some(list) = &mut s.free {
            for j in 1..=n {
                list.push(format!("arm{j}.k"));
                list.push(format!("arm{j}.tau"));
            }
        }
        s
    };
    let largest = match identify_with(
        with_arms(MAX_ARMS),
        &settings_for(MAX_ARMS, settings),
        control,
    )? {
        Run::Identified(id) => id,
        failed => return Ok((failed, Vec::new())),
    };
    // The common σ: the largest candidate's, per channel kind (the first experiment
    // that has the channel).
    let mut common = settings.clone();
    for e in &largest.experiments {
        for c in &e.channels {
            if !common.sigma.iter().any(|(k, _)| *k == c.channel) {
                common.sigma.push((c.channel, Sigma::Absolute(c.sigma)));
            }
        }
    }
    let mut fits = Vec::new();
    for n in 0..MAX_ARMS {
        fits.push(identify_with(
            with_arms(n),
            &settings_for(n, &common),
            control,
        )?);
    }
    fits.push(Run::Identified(largest));
    let table: Vec<Candidate> = fits
        .iter()
        .enumerate()
        .map(|(n, f)| match f {
            Run::Identified(f) => Candidate {
                arms: n,
                free: f.parameters.len(),
                chi2_per_dof: Some(f.chi2_per_dof),
                aicc: f.aicc,
                bic: Some(f.bic),
                status: f.status,
                eligible: !f.status.is_blocking() && f.aicc.is_some(),
            },
            Run::Failed(f) => Candidate {
                arms: n,
                free: f.free.len(),
                chi2_per_dof: None,
                aicc: None,
                bic: None,
                status: f.status,
                eligible: false,
            },
        })
        .collect();
    let best = table
        .iter()
        .filter(|c| c.eligible)
        .filter_map(|c| c.aicc)
        .fold(f64::INFINITY, f64::min);
    let chosen = table
        .iter()
        .position(|c| c.eligible && c.aicc.is_some_and(|a| a <= best + DELTA_AICC))
        .ok_or_else(|| {
            Error::settings(
                "--arms auto: no candidate (0 to 4 arms) is identifiable from these traces",
            )
            .with_hint("fix more constants, measure more channels, or give the arms in the scene")
        })?;
    Ok((fits.swap_remove(chosen), table))
}
