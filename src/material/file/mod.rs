//! Material files: what a scene can reference as its material, read by parameter
//! NAME (never by position) with each unit checked, and refused with the file, the
//! key and what was expected when edited inconsistently.
//!
//! - a hyperelastic fit (`dea-fit hyperelastic --out`, schema [`HYPERELASTIC_SCHEMA`])
//!   holds a [`HyperelasticPart`];
//! - a relaxation fit (`dea-fit relaxation --out`, [`RELAXATION_SCHEMA`]) holds the
//!   Maxwell arms of a [`Viscous`] part (its own model has no Kelvin–Voigt dashpot);
//! - a DMA fit (`dea-fit dma --out`, [`DMA_SCHEMA`]) is a relaxation fit too: its
//!   Prony series read into the same [`RelaxationPart`], with the time–temperature
//!   shift it was built with ([`crate::material::viscoelastic::TimeTemperature`]);
//! - an identified material (`dea-fit identify`, [`IDENTIFIED_SCHEMA`]) holds all
//!   of them and εr (and the filler mass fraction it came from, when the scene's εr
//!   was a composite's mixing rule), each parameter with its uncertainty
//!   ([`IdentifiedMaterial`]);
//! - a composite fit (`dea-fit composite --out`, [`COMPOSITE_SCHEMA`]) holds the
//!   mixing rules a scene's εr(w) can come from ([`CompositePermittivity`]);
//! - a breakdown fit (`dea-fit breakdown --out`, [`BREAKDOWN_SCHEMA`]) holds the
//!   Weibull law of the breakdown field a scene or a ranking checks against
//!   ([`BreakdownFit`]).
//!
//! The estimators (`fit::`) write the first two and the last; this module, below both `fit` and
//! `sim`, defines the material part of each and reads it.

mod breakdown;
mod composite;
mod dma;
mod hyperelastic;
mod identified;
mod spread;
mod viscous;

pub use breakdown::{read_breakdown, BreakdownFit, BreakdownParameter, BreakdownPercentile};
pub use composite::{read_mixture, CompositePermittivity};
pub use hyperelastic::{expected_params, FittedRanges, HyperelasticPart, StretchRange};
pub use identified::{IdentifiedMaterial, ParamUncertainty};
pub use spread::{gradient, Spread};
pub use viscous::{Arm, QlvReference, RelaxationPart, Viscous};

use crate::error::{Error, Location, Result};
use crate::material::check::{did_you_mean, Violation};
use crate::material::viscoelastic::TimeTemperature;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Schema tag of hyperelastic fit files.
pub const HYPERELASTIC_SCHEMA: &str = "dea-fit/hyperelastic-fit/1";
/// Schema tag of relaxation fit files.
pub const RELAXATION_SCHEMA: &str = "dea-fit/relaxation-fit/1";
/// Schema tag of DMA fit files (`dea-fit dma`): shifts, shift law, master curve
/// and its Prony series.
pub const DMA_SCHEMA: &str = "dea-fit/dma/1";
/// Schema tag of identified material files.
pub const IDENTIFIED_SCHEMA: &str = "dea-fit/identified/1";
/// Schema tag of composite fit files.
pub const COMPOSITE_SCHEMA: &str = "dea-fit/composite-fit/1";
/// Schema tag of breakdown fit files.
pub const BREAKDOWN_SCHEMA: &str = "dea-fit/breakdown/1";

/// Read the hyperelastic part of a hyperelastic fit or an identified material file.
/// Its parameters are in the model's order.
pub fn read_hyperelastic(path: &Path) -> Result<HyperelasticPart> {
    Ok(hyperelastic_file(path)?.0)
}

/// The hyperelastic part of a file, with the file's text and schema tag.
fn hyperelastic_file(path: &Path) -> Result<(HyperelasticPart, String, &'static str)> {
    let (text, schema) = read_text(
        path,
        &[HYPERELASTIC_SCHEMA, IDENTIFIED_SCHEMA],
        "hyperelastic",
    )?;
    let part = match schema {
        HYPERELASTIC_SCHEMA => HyperelasticPart::from_json(path, "", &typed(path, &text)?)?,
        _ => IdentifiedMaterial::parse(path, &text)?.hyperelastic,
    };
    Ok((part, text, schema))
}

/// [`read_hyperelastic`], with the standard errors and correlation the file states
/// for the parameters (model order): a hyperelastic fit states both, an identified
/// material the standard errors only.
pub fn read_hyperelastic_spread(path: &Path) -> Result<(HyperelasticPart, Spread)> {
    let (part, text, schema) = hyperelastic_file(path)?;
    let v: serde_json::Value = typed(path, &text)?;
    let node = match schema {
        IDENTIFIED_SCHEMA => &v["hyperelastic"],
        _ => &v,
    };
    let params: Vec<FileParam> =
        serde_json::from_value(node["parameters"].clone()).unwrap_or_default();
    let names: Vec<String> = part
        .evaluator()?
        .params()
        .iter()
        .map(|p| p.name.clone())
        .collect();
    let spread = Spread::by_name(&params, &names, &v["correlation"]);
    Ok((part, spread))
}

/// Read the viscous part of a relaxation fit, a DMA fit or an identified material
/// file: the Maxwell arms, and the Kelvin–Voigt dashpot Nv (Pa·s) when the file
/// states it (an identified file does, a relaxation or DMA fit does not), at the
/// reference temperature of a DMA fit ([`read_viscous_shift`] gives its shift). A
/// file without a viscous part is refused.
pub fn read_viscous(path: &Path) -> Result<(Vec<Arm>, Option<f64>)> {
    let (arms, nv, _) = read_viscous_shift(path)?;
    Ok((arms, nv))
}

/// [`read_viscous`], with the time–temperature shift of a DMA fit (None for the
/// other files, and for a DMA fit of a master curve without temperatures).
pub fn read_viscous_shift(path: &Path) -> Result<(Vec<Arm>, Option<f64>, Option<TimeTemperature>)> {
    let (text, schema) = read_text(
        path,
        &[RELAXATION_SCHEMA, DMA_SCHEMA, IDENTIFIED_SCHEMA],
        "viscous",
    )?;
    match schema {
        RELAXATION_SCHEMA | DMA_SCHEMA => {
            let r = relaxation_kind(path, &text, schema)?;
            Ok((r.arms, None, r.shift))
        }
        _ => match IdentifiedMaterial::parse(path, &text)?.viscous {
            Some(v) => Ok((v.arms, Some(v.nv_pa_s), None)),
            None => Err(err(path, "viscous", "missing: this identified material has no viscous part")
                .with_hint("give the scene's material.viscous another way (preset, arms) or identify with arms")),
        },
    }
}

/// The Prony series of a relaxation-kind file (a relaxation fit or a DMA fit), by
/// its schema tag.
fn relaxation_kind(path: &Path, text: &str, schema: &str) -> Result<RelaxationPart> {
    match schema {
        DMA_SCHEMA => dma::dma_part(path, &typed(path, text)?),
        _ => viscous::relaxation_part(path, &typed(path, text)?),
    }
}

/// The material parts a file holds, by its schema tag: a hyperelastic fit's
/// hyperelastic part, a relaxation fit's Prony series (with its formulation), or
/// an identified material whole.
#[derive(Debug, Clone, PartialEq)]
pub enum MaterialFile {
    /// A hyperelastic fit (`dea-fit hyperelastic`).
    Hyperelastic(HyperelasticPart),
    /// A relaxation fit (`dea-fit relaxation`) or a DMA fit (`dea-fit dma`).
    Relaxation(RelaxationPart),
    /// An identified material (`dea-fit identify`).
    Identified(IdentifiedMaterial),
}

/// The schema tags of the files with mechanical constants.
const MECHANICAL: &[&str] = &[
    HYPERELASTIC_SCHEMA,
    RELAXATION_SCHEMA,
    DMA_SCHEMA,
    IDENTIFIED_SCHEMA,
];

/// The material parts of a hyperelastic fit, a relaxation or DMA fit or an identified
/// material file, each checked as the scene readers check it, and the status the
/// estimator gave the fit (`ok`, `warning`, `ill_posed`, …; None for an identified
/// material written before its status was recorded: status unknown). A composite fit holds no mechanical constants and
/// is refused.
pub fn read_material(path: &Path) -> Result<(MaterialFile, Option<String>)> {
    let (text, schema) = read_text(path, MECHANICAL, "mechanical")?;
    #[derive(Deserialize)]
    struct StatusJson {
        #[serde(default)]
        status: Option<String>,
    }
    let status = typed::<StatusJson>(path, &text)?.status;
    let part = match schema {
        HYPERELASTIC_SCHEMA => {
            MaterialFile::Hyperelastic(HyperelasticPart::from_json(path, "", &typed(path, &text)?)?)
        }
        RELAXATION_SCHEMA | DMA_SCHEMA => {
            MaterialFile::Relaxation(relaxation_kind(path, &text, schema)?)
        }
        _ => MaterialFile::Identified(IdentifiedMaterial::parse(path, &text)?),
    };
    Ok((part, status))
}

/// What a material file says against its own constants: the constants the file
/// calls not identifiable and a blocking status ([`doubts`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Doubts {
    /// The file, as given.
    pub file: String,
    /// The constants the file calls not identifiable (`identifiable: false`).
    pub names: Vec<String>,
    /// A blocking status of the file (`ill_posed`, `unstable`, `not_converged`,
    /// `not_validated`, `failed`).
    pub status: Option<String>,
}

impl Doubts {
    /// The finding in one sentence, ending with what the reader does with the
    /// constants (`consequence`, e.g. "the card carries them as they are").
    pub fn sentence(&self, consequence: &str) -> String {
        let names = match self.names.is_empty() {
            true => String::new(),
            false => format!(
                "it calls {} not identifiable from the data it was fitted to; ",
                self.names.join(", ")
            ),
        };
        match &self.status {
            Some(s) => format!(
                "{} has status {s}: {names}its constants are not all what the data determine (see the file's warnings); {consequence}",
                self.file
            ),
            None => format!("{}: {names}{consequence}", self.file),
        }
    }
}

/// What a reader that takes the `parts` (`hyperelastic`, `viscous`, `dielectric`)
/// of the material file `path` is to be told: the constants of those parts the file
/// calls not identifiable (`identifiable: false`, written by `identify` and, per
/// parameter, by the hyperelastic and relaxation estimators under the one rule of
/// `fit::identifiability`; a hyperelastic or relaxation fit holds one part, at its
/// top level) and a blocking status of the file. None when the file states neither
/// (a file written before they were recorded states nothing: status unknown).
pub fn doubts(path: &Path, parts: &[&str]) -> Result<Option<Doubts>> {
    let (text, schema) = read_text(path, MECHANICAL, "mechanical")?;
    let v: serde_json::Value = typed(path, &text)?;
    let nodes: Vec<&serde_json::Value> = match schema {
        IDENTIFIED_SCHEMA => parts.iter().map(|p| &v[*p]).collect(),
        // a DMA fit's Prony parameters are those of its frequency-domain fit
        DMA_SCHEMA => vec![&v["prony"]["fit"]],
        _ => vec![&v],
    };
    let names: Vec<String> = nodes
        .iter()
        .flat_map(|n| {
            serde_json::from_value::<Vec<FileParam>>(n["parameters"].clone()).unwrap_or_default()
        })
        // a relaxation (or DMA) fit's E∞ is not a constant its readers take (its arms are)
        .filter(|p| {
            p.identifiable == Some(false)
                && !(matches!(schema, RELAXATION_SCHEMA | DMA_SCHEMA) && p.name == "E_inf")
        })
        .map(|p| p.name)
        .collect();
    let status = v["status"]
        .as_str()
        .filter(|s| !matches!(*s, "ok" | "warning"))
        .map(str::to_string);
    Ok((!names.is_empty() || status.is_some()).then(|| Doubts {
        file: path.display().to_string(),
        names,
        status,
    }))
}

/// One parameter as a material file holds it: name, SI unit and value, and, in an
/// identified file, its standard error and whether the data pinned it down
/// (both `null` for a parameter that was held fixed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct FileParam {
    name: String,
    #[serde(default)]
    unit: String,
    value: f64,
    #[serde(default)]
    std_error: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    identifiable: Option<bool>,
}

impl FileParam {
    /// A parameter with the uncertainty `uncertainty` gives it by name (none: fixed).
    pub(super) fn with(
        name: &str,
        unit: &str,
        value: f64,
        uncertainty: &[ParamUncertainty],
    ) -> Self {
        let u = uncertainty.iter().find(|u| u.name == name);
        FileParam {
            name: name.to_string(),
            unit: unit.to_string(),
            value,
            std_error: u.and_then(|u| u.std_error),
            identifiable: u.map(|u| u.identifiable),
        }
    }
}

/// An error at `key` of a material file (no line: JSON keys are named by path).
fn err(path: &Path, key: &str, msg: impl std::fmt::Display) -> Error {
    Error::input(Location::file(path), format!("{key}: {msg}"))
}

fn violation(path: &Path, v: Violation) -> Error {
    err(path, &v.key, v.msg).with_hint(v.hint)
}

/// `prefix.key`, or `key` at the top level.
fn join(prefix: &str, key: &str) -> String {
    match prefix {
        "" => key.to_string(),
        p => format!("{p}.{key}"),
    }
}

/// The file's text once it is JSON with one of the `accepted` schema tags (the
/// tag returned); `what` names the material part the caller wants.
fn read_text(path: &Path, accepted: &[&'static str], what: &str) -> Result<(String, &'static str)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a {what} material file: {e}"),
        )
    })?;
    let want = accepted
        .iter()
        .map(|s| format!("\"{s}\""))
        .collect::<Vec<_>>()
        .join(" or ");
    match v.get("schema").and_then(serde_json::Value::as_str) {
        Some(s) => match accepted.iter().find(|a| **a == s) {
            Some(a) => Ok((text, *a)),
            None => {
                let hint = match s {
                    RELAXATION_SCHEMA => {
                        "this is a relaxation fit: use it as material.viscous = { fit = ... }"
                    }
                    DMA_SCHEMA => {
                        "this is a DMA fit: use it as material.viscous = { fit = ... } (with material.temperature = \"40 C\" to shift it)"
                    }
                    HYPERELASTIC_SCHEMA => {
                        "this is a hyperelastic fit: use it as material.hyperelastic = { fit = ... }"
                    }
                    COMPOSITE_SCHEMA => {
                        "this is a composite fit: use it as material.relative_permittivity = { composite = ..., mass_fraction = ... }"
                    }
                    BREAKDOWN_SCHEMA => {
                        "this is a breakdown fit: use it as material.breakdown = { fit = ... }"
                    }
                    _ => "write it with dea-fit hyperelastic --out, relaxation --out, dma --out, composite --out, breakdown --out or identify",
                };
                Err(err(path, "schema", format!("expected {want}, found \"{s}\"")).with_hint(hint))
            }
        },
        None => Err(err(path, "schema", format!("missing; expected {want}"))
            .with_hint("a material file from dea-fit has a schema tag")),
    }
}

/// The file's text as the typed shape `T`; a wrong type is located at its line
/// and column.
fn typed<T: serde::de::DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    serde_json::from_str(text).map_err(|e| {
        Error::input(
            Location::at(path, e.line(), e.column()),
            format!("not a material file of its schema: {e}"),
        )
    })
}

/// The values of `list` by name: for each expected (name, unit) its value, in the
/// expected order. Refuses a missing, unknown, repeated or mis-unitised name and a
/// non-finite value; `key` names the list in messages, `what` the model.
fn by_name(
    path: &Path,
    list: &[FileParam],
    key: &str,
    expected: &[(String, &str)],
    what: &str,
) -> Result<Vec<f64>> {
    let names: Vec<&str> = expected.iter().map(|e| e.0.as_str()).collect();
    let want = || {
        let list: Vec<String> = expected.iter().map(|(n, u)| format!("{n} [{u}]")).collect();
        format!("{what} takes {}", list.join(", "))
    };
    let mut vals: Vec<Option<f64>> = vec![None; expected.len()];
    for (i, p) in list.iter().enumerate() {
        let at = format!("{key}[{i}]");
        let name = p.name.as_str();
        let Some(j) = names.iter().position(|n| *n == name) else {
            let near = did_you_mean(name, &names)
                .map(|m| format!("did you mean '{m}'? "))
                .unwrap_or_default();
            return Err(err(
                path,
                &format!("{at}.name"),
                format!("'{name}' is not a parameter of {what}"),
            )
            .with_hint(format!("{near}{}", want())));
        };
        if vals[j].is_some() {
            return Err(err(
                path,
                &format!("{at}.name"),
                format!("'{name}' is given twice"),
            )
            .with_hint(want()));
        }
        if p.unit != expected[j].1 {
            return Err(err(
                path,
                &format!("{at}.unit"),
                format!("{name} is in '{}', found '{}'", expected[j].1, p.unit),
            )
            .with_hint("material files hold SI values: write them with dea-fit"));
        }
        if !p.value.is_finite() {
            return Err(err(
                path,
                &format!("{at}.value"),
                format!("{name} needs a finite number"),
            ));
        }
        vals[j] = Some(p.value);
    }
    expected
        .iter()
        .zip(vals)
        .map(|((n, _), x)| {
            x.ok_or_else(|| {
                err(
                    path,
                    key,
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
