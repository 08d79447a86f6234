//! The identified constants as a material file a scene can reference
//! ([`crate::material::file::IdentifiedMaterial`]), and a held-out trace predicted
//! with them (`--validate`).

use super::problem::{simulated, Experiment};
use super::{params, Identification};
use crate::error::Result;
use crate::fit::diagnostics::rmse_percent;
use crate::material::file::{
    FittedRanges, HyperelasticPart, IdentifiedMaterial, ParamUncertainty, StretchRange, Viscous,
};
use crate::sim::scene::Scene;
use crate::sim::{simulate, RunOptions, RunStatus};
use serde::Serialize;

/// The material file of an identification on `scene` (the scene the traces ran on),
/// with its status and each constant's identifiability (so that a scene using a
/// constant the traces did not pin down warns, and `export` reports a blocking
/// status), the stretch range the traces covered (so that a scene using the file
/// warns when it extrapolates) and `provenance`.
pub fn material_file(
    id: &Identification,
    scene: &Scene,
    provenance: serde_json::Value,
) -> Result<IdentifiedMaterial> {
    let mut s = scene.clone();
    params::set_theta(&mut s, &id.theta);
    let m = &s.material;
    let plant = crate::sim::full_plant(&s)?;
    // The values as the file states them (an arm's τ is written as η/k: take it
    // back the same way, so that each entry names the file's own number).
    let written = params::theta(&s);
    let constants = params::constants(&s);
    let uncertainty = id
        .parameters
        .iter()
        .chain(&id.derived)
        .map(|p| ParamUncertainty {
            name: p.name.clone(),
            unit: p.unit.clone(),
            value: constants
                .iter()
                .find(|c| c.name == p.name)
                .map_or(p.value, |c| written[c.index]),
            std_error: p.std_error,
            identifiable: p.identifiable,
        })
        .collect();
    Ok(IdentifiedMaterial {
        hyperelastic: HyperelasticPart {
            spec: m.spec.clone(),
            params: m.params.clone(),
            ranges: Some(FittedRanges {
                per_mode: vec![StretchRange {
                    mode: plant.mode,
                    stretch_min: id.stretch_range.0,
                    stretch_max: id.stretch_range.1,
                }],
            }),
        },
        viscous: Some(Viscous {
            nv_pa_s: m.viscous.nv_pa_s,
            arms: m.viscous.arms.clone(),
        }),
        eps_r: Some(m.eps_r),
        composite: m.composite,
        uncertainty,
        status: Some(id.status.to_string()),
        provenance,
    })
}

/// A channel of a held-out trace predicted with the identified constants.
#[derive(Debug, Clone, Serialize)]
pub struct Prediction {
    /// Channel.
    pub channel: crate::io::trace::ChannelKind,
    /// SI unit.
    pub unit: &'static str,
    /// Root-mean-square error of the prediction (SI).
    pub rmse: f64,
    /// Seed Eq. 3.28 (%).
    pub rmse_pct: Option<f64>,
    /// Noise σ of the held-out channel, estimated from its own data as the fit's
    /// channels are ([`super::noise::from_data`]; SI).
    pub sigma: f64,
    /// The RMS error in units of that σ: about 1 for a prediction within the noise.
    pub rms_sigmas: f64,
    /// The largest `rms_sigmas` a passing prediction has ([`allowed_rms_sigmas`]).
    pub allowed_rms_sigmas: f64,
}

impl Prediction {
    /// Whether the prediction is within [`Prediction::allowed_rms_sigmas`].
    pub fn passed(&self) -> bool {
        self.rms_sigmas <= self.allowed_rms_sigmas
    }
}

/// How far a held-out prediction may miss, as its RMS error over the channel's
/// noise σ: [`VALIDATION_RMS_SIGMAS`] times the fit's own RMS residual in σ,
/// √(χ²/dof), or times 1 when the fit is within its noise. A prediction within the
/// noise has about 1, and one that misses by as much again as the fit misses its
/// own traces about √(χ²/dof); three times either is a model or constants that
/// do not carry over to the held-out drive.
pub fn allowed_rms_sigmas(id: &Identification) -> f64 {
    VALIDATION_RMS_SIGMAS * id.chi2_per_dof.sqrt().max(1.0)
}

/// The factor of [`allowed_rms_sigmas`].
pub const VALIDATION_RMS_SIGMAS: f64 = 3.0;

/// A held-out trace predicted (`--validate`).
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    /// Trace file.
    pub file: String,
    /// Per channel (none when the prediction failed).
    pub channels: Vec<Prediction>,
    /// Why the identified constants could not run this trace (a pull-in it does not
    /// show, a failed run): a result about the constants, not a refused input.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failed: Option<String>,
}

impl Validation {
    /// Whether the held-out trace is predicted: the run completed and every channel
    /// is within its allowed error ([`Prediction::passed`]).
    pub fn passed(&self) -> bool {
        self.failed.is_none() && self.channels.iter().all(Prediction::passed)
    }

    /// The warning of a failed prediction, or of each channel missed, with its
    /// numbers.
    pub fn warning(&self) -> Option<String> {
        if let Some(why) = &self.failed {
            return Some(format!(
                "{}: the identified constants do not predict this held-out trace: {why}",
                self.file
            ));
        }
        let missed: Vec<String> = self
            .channels
            .iter()
            .filter(|c| !c.passed())
            .map(|c| {
                format!(
                    "{} RMS error {:.3e} {} = {:.1} σ (σ {:.3e} {} from its data; at most {:.1} σ passes)",
                    c.channel, c.rmse, c.unit, c.rms_sigmas, c.sigma, c.unit, c.allowed_rms_sigmas
                )
            })
            .collect();
        (!missed.is_empty()).then(|| {
            format!(
                "{}: the identified constants miss this held-out trace: {}",
                self.file,
                missed.join("; ")
            )
        })
    }
}

/// Predict `exp` (a trace not used in the fit, checked to start before the search:
/// [`Experiment::check_start`]) with the identified θ. Its scene must hold the
/// material as identified (the model and arms a selection chose, see
/// [`super::selection`]), so that θ fits its layout.
pub fn validate(id: &Identification, exp: &Experiment) -> Result<Validation> {
    let mut scene = exp.scene.clone();
    params::set_theta(&mut scene, &id.theta);
    let o = simulate(&scene, &RunOptions::default())?;
    if o.integrator.status != RunStatus::Completed || o.samples.len() != exp.rows() {
        return Ok(Validation {
            file: exp.name.clone(),
            channels: Vec::new(),
            failed: Some(format!(
                "{} ({})",
                o.integrator.status, o.integrator.message
            )),
        });
    }
    let s0 = o.samples[0];
    let times: Vec<f64> = std::iter::once(0.0)
        .chain(exp.scene.time.samples.iter().copied())
        .collect();
    let allowed = allowed_rms_sigmas(id);
    let channels = exp
        .channels
        .iter()
        .map(|c| {
            let (mut ss, mut n) = (0.0, 0usize);
            for (y, s) in c.values.iter().zip(&o.samples) {
                if y.is_finite() {
                    ss += (simulated(c.kind, &s0, s) - y).powi(2);
                    n += 1;
                }
            }
            let rmse = (ss / n.max(1) as f64).sqrt();
            let measured: Vec<f64> = c.values.iter().copied().filter(|v| v.is_finite()).collect();
            let sigma = super::noise::from_data(&times, &c.values);
            Prediction {
                channel: c.kind,
                unit: c.kind.unit(),
                rmse,
                rmse_pct: rmse_percent(rmse, &measured),
                sigma,
                // a NaN (no value to compare) never passes
                rms_sigmas: rmse / sigma,
                allowed_rms_sigmas: allowed,
            }
        })
        .collect();
    Ok(Validation {
        file: exp.name.clone(),
        channels,
        failed: None,
    })
}
