//! The hyperelastic part of a material file: a model by name, its parameters by
//! name in SI, and the stretch ranges per mode its constants were fitted over.

use super::{by_name, err, join, violation, FileParam, ParamUncertainty};
use crate::error::Result;
use crate::material::check::{check_hyperelastic, did_you_mean};
use crate::material::hyperelastic::{Mode, ModelSpec, OgdenForm, StrainEnergy, MODEL_NAMES};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The parameters a model expects, for hints: `yeoh takes C10 [Pa], C20 [Pa], C30 [Pa]`.
pub fn expected_params(model: &dyn StrainEnergy) -> String {
    let list: Vec<String> = model
        .params()
        .iter()
        .map(|p| format!("{} [{}]", p.name, p.unit))
        .collect();
    format!("{} takes {}", model.name(), list.join(", "))
}

/// The stretch range of the data in one mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StretchRange {
    /// Mode.
    pub mode: Mode,
    /// Smallest stretch of the data.
    pub stretch_min: f64,
    /// Largest stretch of the data.
    pub stretch_max: f64,
}

/// The stretch ranges per mode a set of constants was fitted over: outside them
/// the model is extrapolated.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedRanges {
    /// One range per mode with data.
    pub per_mode: Vec<StretchRange>,
}

impl FittedRanges {
    /// A warning if `stretch` in `mode` lies outside what the data covered. Uniaxial
    /// compression at λ is equibiaxial tension at λ^-1/2 and is checked as such.
    pub fn range_warning(&self, mode: Mode, stretch: f64) -> Option<String> {
        let (m, l) = if mode == Mode::Uniaxial && stretch < 1.0 {
            match self.per_mode.iter().find(|s| s.mode == Mode::Uniaxial) {
                Some(s) if s.stretch_min <= stretch => return None,
                _ => (Mode::Equibiaxial, stretch.powf(-0.5)),
            }
        } else {
            (mode, stretch)
        };
        match self.per_mode.iter().find(|s| s.mode == m) {
            Some(s) if l >= s.stretch_min - 1e-12 && l <= s.stretch_max + 1e-12 => None,
            Some(s) => Some(format!(
                "{mode} stretch {stretch:.3} lies outside the fitted {m} range {:.3}–{:.3}: the model is extrapolated",
                s.stretch_min, s.stretch_max
            )),
            None => Some(format!(
                "{mode} stretch {stretch:.3} needs {m} behaviour, for which the fit had no data: the model is extrapolated"
            )),
        }
    }
}

/// Hyperelastic material constants: a model, its parameters (SI, model order) and,
/// when they were fitted, the stretch ranges of the data.
#[derive(Debug, Clone, PartialEq)]
pub struct HyperelasticPart {
    /// Model and Ogden form.
    pub spec: ModelSpec,
    /// Parameters (SI, in the model's order).
    pub params: Vec<f64>,
    /// Fitted stretch ranges (None: constants not fitted here, no range warnings).
    pub ranges: Option<FittedRanges>,
}

/// The hyperelastic part as a file holds it (a hyperelastic fit at its top level,
/// an identified material under `hyperelastic`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct PartJson {
    #[serde(default)]
    model: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    form: Option<OgdenForm>,
    parameters: Vec<FileParam>,
    #[serde(rename = "initial_shear_modulus_Pa")]
    initial_shear_modulus_pa: f64,
    #[serde(default)]
    per_mode: Vec<StretchRange>,
}

impl PartJson {
    /// The parameters as written.
    pub(super) fn parameters(&self) -> &[FileParam] {
        &self.parameters
    }
}

impl HyperelasticPart {
    /// The model evaluator, after checking the parameters against it (count, finite,
    /// within the model's bounds).
    pub fn evaluator(&self) -> Result<Box<dyn StrainEnergy>> {
        let model = self.spec.build()?;
        model.check_params(&self.params)?;
        Ok(model)
    }

    /// A warning if `stretch` in `mode` lies outside the fitted ranges (none for
    /// constants that were not fitted).
    pub fn range_warning(&self, mode: Mode, stretch: f64) -> Option<String> {
        self.ranges.as_ref()?.range_warning(mode, stretch)
    }

    /// The part as a file holds it, each parameter with the standard error and
    /// the identifiability `uncertainty` gives it by name (null: held fixed).
    pub(super) fn to_json(&self, uncertainty: &[ParamUncertainty]) -> Result<PartJson> {
        let model = self.evaluator()?;
        Ok(PartJson {
            model: Some(self.spec.name.clone()),
            form: self.spec.form,
            parameters: model
                .params()
                .iter()
                .zip(&self.params)
                .map(|(p, &value)| FileParam::with(&p.name, p.unit, value, uncertainty))
                .collect(),
            initial_shear_modulus_pa: model.initial_shear_modulus(&self.params),
            per_mode: self
                .ranges
                .as_ref()
                .map(|r| r.per_mode.clone())
                .unwrap_or_default(),
        })
    }

    /// The part from its file shape: a known model, exactly its parameters by name
    /// in SI, values the model can use (`material::check`: finite, plausible,
    /// μ0 > 0, Gent Jm in its bounds, Ogden |αi| ≥ 0.01), the stated small-strain
    /// shear modulus equal to the one the parameters give (a file whose values were
    /// swapped or edited is refused), and finite stretch ranges. `prefix` is the key
    /// of the part in the file (empty at the top level).
    pub(super) fn from_json(path: &Path, prefix: &str, j: &PartJson) -> Result<Self> {
        let key = |k: &str| join(prefix, k);
        let Some(name) = j.model.as_deref() else {
            return Err(err(path, &key("model"), "missing")
                .with_hint(format!("one of {}", MODEL_NAMES.join(", "))));
        };
        if !MODEL_NAMES.contains(&name) {
            let near = did_you_mean(name, &MODEL_NAMES)
                .map(|m| format!("did you mean '{m}'? "))
                .unwrap_or_default();
            return Err(err(path, &key("model"), format!("unknown model '{name}'"))
                .with_hint(format!("{near}known: {}", MODEL_NAMES.join(", "))));
        }
        // an Ogden file without a form is in the seed's (the default form)
        let spec = ModelSpec::new(name, j.form.unwrap_or_default());
        let model = spec.build()?;
        let expected: Vec<(String, &str)> = model
            .params()
            .iter()
            .map(|p| (p.name.clone(), p.unit))
            .collect();
        let params = by_name(
            path,
            &j.parameters,
            &key("parameters"),
            &expected,
            &model.name(),
        )?;
        check_hyperelastic(model.as_ref(), &params, &key("parameters"))
            .map_err(|e| violation(path, e))?;
        let mu0 = model.initial_shear_modulus(&params);
        let stated = j.initial_shear_modulus_pa;
        if (mu0 - stated).abs() > 1e-6 * stated.abs().max(mu0.abs()) {
            return Err(err(
                path,
                &key("initial_shear_modulus_Pa"),
                format!(
                    "the file states {stated} Pa but its {} parameters give {mu0} Pa",
                    model.name()
                ),
            )
            .with_hint("the parameters were edited, swapped or relabelled: fit the data again"));
        }
        for (i, r) in j.per_mode.iter().enumerate() {
            let ok = r.stretch_min.is_finite()
                && r.stretch_max.is_finite()
                && 0.0 < r.stretch_min
                && r.stretch_min <= r.stretch_max;
            if !ok {
                return Err(err(
                    path,
                    &key(&format!("per_mode[{i}]")),
                    format!(
                        "stretch range {}–{} is not a range of stretches",
                        r.stretch_min, r.stretch_max
                    ),
                )
                .with_hint("expected 0 < stretch_min ≤ stretch_max: the file was edited, fit the data again"));
            }
        }
        Ok(HyperelasticPart {
            spec,
            params,
            ranges: Some(FittedRanges {
                per_mode: j.per_mode.clone(),
            }),
        })
    }
}
