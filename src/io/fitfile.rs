//! Fit files read as a scene's material, by parameter NAME, never by position.
//!
//! A hyperelastic fit (`dea-fit hyperelastic --out`) must name a known model and
//! give exactly that model's parameters (`ParamInfo`: names and SI units), in any
//! order, each once; its values must make the model usable (`sim::budget`:
//! finite, plausible, μ0 > 0, Gent Jm in its bounds, Ogden |αi| ≥ 0.01), and the
//! small-strain shear modulus it states must be the one its parameters give (a
//! file whose values were swapped or edited is refused). A relaxation fit
//! (`dea-fit relaxation --out`) must give `E_inf`, `E1…EN` (Pa) and `tau1…tauN`
//! (s) for its N Prony terms, agreeing with its `prony` and `kelvin_maxwell`
//! lists. Every refusal names the file, the key and what was expected.

use crate::error::{Error, Location, Result};
use crate::fit::hyperelastic::{self, HyperelasticFit};
use crate::fit::relaxation::{self, RelaxationFit};
use crate::material::hyperelastic::{ModelSpec, StrainEnergy, MODEL_NAMES};
use crate::material::viscoelastic::MaxwellArm;
use crate::sim::budget::{self, Violation};
use serde_json::Value;
use std::path::Path;

/// The parameters a model expects, for hints: `yeoh: C10 [Pa], C20 [Pa], C30 [Pa]`.
pub fn expected_params(model: &dyn StrainEnergy) -> String {
    let list: Vec<String> = model
        .params()
        .iter()
        .map(|p| format!("{} [{}]", p.name, p.unit))
        .collect();
    format!("{} takes {}", model.name(), list.join(", "))
}

fn err(path: &Path, key: &str, msg: impl std::fmt::Display) -> Error {
    Error::input(Location::file(path), format!("{key}: {msg}"))
}

fn violation(path: &Path, v: Violation) -> Error {
    err(path, &v.key, v.msg).with_hint(v.hint)
}

/// Read the JSON and check its schema tag; `other` names the other fit kind.
fn read_json(path: &Path, schema: &str, what: &str) -> Result<(String, Value)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a {what} fit file: {e}"),
        )
    })?;
    match v.get("schema").and_then(Value::as_str) {
        Some(s) if s == schema => Ok((text, v)),
        Some(s) => {
            let hint = match s {
                relaxation::SCHEMA => {
                    "this is a relaxation fit: use it as material.viscous = { fit = ... }"
                }
                hyperelastic::SCHEMA => {
                    "this is a hyperelastic fit: use it as material.hyperelastic = { fit = ... }"
                }
                _ => "write it with dea-fit hyperelastic --out or dea-fit relaxation --out",
            };
            Err(err(
                path,
                "schema",
                format!("expected \"{schema}\", found \"{s}\""),
            )
            .with_hint(hint))
        }
        None => Err(
            err(path, "schema", format!("missing; expected \"{schema}\""))
                .with_hint(format!("a {what} fit file from dea-fit has a schema tag")),
        ),
    }
}

/// The `parameters` list by name: for each expected (name, unit) its value, in
/// the expected order. Refuses a missing, unknown, repeated or mis-unitised name
/// and a non-finite value.
fn by_name(path: &Path, v: &Value, expected: &[(String, &str)], what: &str) -> Result<Vec<f64>> {
    let names: Vec<&str> = expected.iter().map(|e| e.0.as_str()).collect();
    let want = || {
        let list: Vec<String> = expected.iter().map(|(n, u)| format!("{n} [{u}]")).collect();
        format!("{what} takes {}", list.join(", "))
    };
    let list = v
        .get("parameters")
        .and_then(Value::as_array)
        .ok_or_else(|| err(path, "parameters", "missing or not a list").with_hint(want()))?;
    let mut vals: Vec<Option<f64>> = vec![None; expected.len()];
    for (i, p) in list.iter().enumerate() {
        let key = format!("parameters[{i}]");
        let name = p
            .get("name")
            .and_then(Value::as_str)
            .ok_or_else(|| err(path, &format!("{key}.name"), "missing").with_hint(want()))?;
        let Some(j) = names.iter().position(|n| *n == name) else {
            let near = crate::sim::scene::did_you_mean(name, &names)
                .map(|m| format!("did you mean '{m}'? "))
                .unwrap_or_default();
            return Err(err(
                path,
                &format!("{key}.name"),
                format!("'{name}' is not a parameter of {what}"),
            )
            .with_hint(format!("{near}{}", want())));
        };
        if vals[j].is_some() {
            return Err(err(
                path,
                &format!("{key}.name"),
                format!("'{name}' is given twice"),
            )
            .with_hint(want()));
        }
        let unit = p.get("unit").and_then(Value::as_str).unwrap_or("");
        if unit != expected[j].1 {
            return Err(err(
                path,
                &format!("{key}.unit"),
                format!("{name} is in '{}', found '{unit}'", expected[j].1),
            )
            .with_hint("fit files hold SI values: write them with dea-fit"));
        }
        let x = p
            .get("value")
            .and_then(Value::as_f64)
            .filter(|x| x.is_finite())
            .ok_or_else(|| {
                err(
                    path,
                    &format!("{key}.value"),
                    format!("{name} needs a finite number"),
                )
            })?;
        vals[j] = Some(x);
    }
    expected
        .iter()
        .zip(vals)
        .map(|((n, _), x)| {
            x.ok_or_else(|| {
                err(
                    path,
                    "parameters",
                    format!(
                        "{n} is missing ({} of {} given)",
                        list.len(),
                        expected.len()
                    ),
                )
                .with_hint(want())
            })
        })
        .collect()
}

/// Read a hyperelastic fit file by parameter name (see the module documentation).
/// The returned fit's `parameters` are in the model's order.
pub fn read_hyperelastic(path: &Path) -> Result<HyperelasticFit> {
    let (text, v) = read_json(path, hyperelastic::SCHEMA, "hyperelastic")?;
    let model_name = v.get("model").and_then(Value::as_str).ok_or_else(|| {
        err(path, "model", "missing").with_hint(format!("one of {}", MODEL_NAMES.join(", ")))
    })?;
    if !MODEL_NAMES.contains(&model_name) {
        let near = crate::sim::scene::did_you_mean(model_name, &MODEL_NAMES)
            .map(|m| format!("did you mean '{m}'? "))
            .unwrap_or_default();
        return Err(err(path, "model", format!("unknown model '{model_name}'"))
            .with_hint(format!("{near}known: {}", MODEL_NAMES.join(", "))));
    }
    let mut fit: HyperelasticFit = serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a hyperelastic fit file: {e}"),
        )
    })?;
    let model = ModelSpec {
        name: fit.model.clone(),
        form: fit.form,
    }
    .build()?;
    let expected: Vec<(String, &str)> = model
        .params()
        .iter()
        .map(|p| (p.name.clone(), p.unit))
        .collect();
    let values = by_name(path, &v, &expected, &model.name())?;
    budget::check_hyperelastic(model.as_ref(), &values, "parameters")
        .map_err(|e| violation(path, e))?;
    let mu0 = model.initial_shear_modulus(&values);
    let stated = fit.initial_shear_modulus_pa;
    let agrees = (mu0 - stated).abs() <= 1e-6 * stated.abs().max(mu0.abs());
    if !agrees {
        return Err(err(
            path,
            "initial_shear_modulus_Pa",
            format!(
                "the file states {stated} Pa but its {} parameters give {mu0} Pa",
                model.name()
            ),
        )
        .with_hint("the parameters were edited, swapped or relabelled: fit the data again"));
    }
    fit.parameters
        .sort_by_key(|p| expected.iter().position(|e| e.0 == p.name));
    Ok(fit)
}

/// Read a relaxation fit file by parameter name: the fit and the seed's Maxwell
/// arms kⱼ = Eⱼ, nⱼ = Eⱼ·τⱼ of its Prony terms (see docs/scenes.md for how they
/// enter the simulator).
pub fn read_relaxation(path: &Path) -> Result<(RelaxationFit, Vec<MaxwellArm>)> {
    let (text, v) = read_json(path, relaxation::SCHEMA, "relaxation")?;
    let fit: RelaxationFit = serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a relaxation fit file: {e}"),
        )
    })?;
    let n = fit.prony.len();
    let mut expected: Vec<(String, &str)> = vec![("E_inf".into(), "Pa")];
    expected.extend((1..=n).map(|i| (format!("E{i}"), "Pa")));
    expected.extend((1..=n).map(|i| (format!("tau{i}"), "s")));
    let what = format!("a {n}-term Prony series");
    let vals = by_name(path, &v, &expected, &what)?;
    if vals.len() != expected.len() || fit.parameters.len() != expected.len() {
        return Err(err(
            path,
            "parameters",
            format!(
                "{what} has {} parameters, found {}",
                expected.len(),
                fit.parameters.len()
            ),
        ));
    }
    budget::MODULUS
        .check("parameters.E_inf", vals[0])
        .map_err(|e| violation(path, e))?;
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    let mut arms = Vec::with_capacity(n);
    for j in 0..n {
        let (e, tau) = (vals[1 + j], vals[1 + n + j]);
        budget::ARM_MODULUS
            .check(&format!("parameters.E{}", j + 1), e)
            .map_err(|x| violation(path, x))?;
        budget::ARM_TIME
            .check(&format!("parameters.tau{}", j + 1), tau)
            .map_err(|x| violation(path, x))?;
        let p = &fit.prony[j];
        let km = fit.kelvin_maxwell.get(j);
        let agrees = same(p.modulus_pa, e)
            && same(p.tau_s, tau)
            && km.is_some_and(|a| same(a.k_pa, e) && same(a.n_pa_s, e * tau));
        if !agrees || fit.kelvin_maxwell.len() != n {
            return Err(err(
                path,
                &format!("prony[{j}]"),
                format!("term {} disagrees with parameters E{0} = {e} Pa, tau{0} = {tau} s (or with kelvin_maxwell)", j + 1),
            )
            .with_hint("the file was edited: fit the data again"));
        }
        // the file's own arms (checked above to be Eⱼ and Eⱼ·τⱼ)
        let a = &fit.kelvin_maxwell[j];
        arms.push(MaxwellArm {
            k: a.k_pa,
            n: a.n_pa_s,
        });
    }
    Ok((fit, arms))
}
