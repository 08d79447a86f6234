//! The identified material file (`dea-fit identify`, schema `dea-fit/identified/1`):
//! the hyperelastic part, the viscous part (optional), εr (optional; with the
//! filler mass fraction and the mixing rule it came from, when the scene's εr was a
//! composite's), each parameter with value, SI unit, standard error and whether the
//! traces pinned it down, the identification's status (absent in files written
//! before it was recorded: status unknown), and the provenance of the
//! identification. The format is in docs/scenes.md ("Fit files as material").

use super::composite::{check_mixture, eps_at, CompositePermittivity};
use super::hyperelastic::PartJson;
use super::viscous::ViscousJson;
use super::{by_name, err, read_text, typed, violation, FileParam, IDENTIFIED_SCHEMA};
use super::{HyperelasticPart, Viscous};
use crate::error::{Error, Result};
use crate::material::check::PERMITTIVITY;
use crate::material::dielectric::Mixture;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The uncertainty of one free parameter of an identification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamUncertainty {
    /// Name as the simulator's sensitivities use it (`C10`, `arm1.tau`, `nv`, `eps_r`).
    pub name: String,
    /// SI unit (`Pa`, `s`, `Pa s`, `1`).
    pub unit: String,
    /// Identified value (SI).
    pub value: f64,
    /// Standard error (SI; None where the Jacobian gives none).
    pub std_error: Option<f64>,
    /// Whether the traces pin the parameter down.
    pub identifiable: bool,
}

/// An identified material: what a scene can take whole (`[material] identified =
/// "x.json"`) or by part (`hyperelastic = { fit = ... }`, `viscous = { fit = ... }`).
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedMaterial {
    /// Hyperelastic part (its ranges: the stretches the traces covered).
    pub hyperelastic: HyperelasticPart,
    /// Viscous part, if identified.
    pub viscous: Option<Viscous>,
    /// Relative permittivity εr, if identified.
    pub eps_r: Option<f64>,
    /// The mixing rule and filler mass fraction εr is (εr = εr(w)), when the
    /// identification's scene took εr from a composite.
    pub composite: Option<CompositePermittivity>,
    /// The free parameters' uncertainty, by name; a parameter of the parts without
    /// an entry was held fixed.
    pub uncertainty: Vec<ParamUncertainty>,
    /// The identification's status (`ok`, `warning`, `ill_posed`, `not_converged`,
    /// `not_validated`); None in a file written before it was recorded (status
    /// unknown).
    pub status: Option<String>,
    /// Provenance: a JSON object (tool version, trace files with hashes, scene path
    /// and hash, settings).
    pub provenance: serde_json::Value,
}

/// The dielectric part as the file holds it: `eps_r` [1], and with a `composite`
/// rule also `mass_fraction` [1] (εr = εr(w) of the rule).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct DielectricJson {
    parameters: Vec<FileParam>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    composite: Option<RuleJson>,
}

/// The mixing rule εr(w) came from: the rule, its constants, the phase densities
/// and the frequency of its fit.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct RuleJson {
    #[serde(flatten)]
    mixture: Mixture,
    #[serde(rename = "freq_Hz")]
    freq_hz: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct IdentifiedJson {
    schema: String,
    tool_version: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    status: Option<String>,
    #[serde(default)]
    hyperelastic: Option<PartJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    viscous: Option<ViscousJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dielectric: Option<DielectricJson>,
    #[serde(default)]
    provenance: serde_json::Value,
}

impl IdentifiedMaterial {
    /// The status as outputs say it: the identification's, or `unknown` for a file
    /// written before it was recorded.
    pub fn status_text(&self) -> &str {
        self.status.as_deref().unwrap_or("unknown")
    }

    /// The file text (pretty JSON). Refuses (a settings error) an uncertainty entry
    /// that is not a parameter of the parts with the same unit and value and a
    /// provenance that is not a JSON object; the text is read back before it is
    /// returned, so what the reader would refuse (an implausible constant) is never
    /// written.
    pub fn to_json(&self) -> Result<String> {
        let u = &self.uncertainty;
        let j = IdentifiedJson {
            schema: IDENTIFIED_SCHEMA.into(),
            tool_version: env!("CARGO_PKG_VERSION").into(),
            status: self.status.clone(),
            hyperelastic: Some(self.hyperelastic.to_json(u)?),
            viscous: self.viscous.as_ref().map(|v| v.to_json(u)),
            dielectric: self.eps_r.map(|e| DielectricJson {
                parameters: std::iter::once(FileParam::with("eps_r", "1", e, u))
                    .chain(
                        self.composite
                            .map(|c| FileParam::with("mass_fraction", "1", c.mass_fraction, u)),
                    )
                    .collect(),
                composite: self.composite.map(|c| RuleJson {
                    mixture: c.mixture,
                    freq_hz: c.freq_hz,
                }),
            }),
            provenance: self.provenance.clone(),
        };
        if !self.provenance.is_object() {
            return Err(Error::settings(
                "the provenance of an identified material must be a JSON object",
            ));
        }
        let written: Vec<&FileParam> = j
            .hyperelastic
            .iter()
            .flat_map(|h| h.parameters())
            .chain(j.viscous.iter().flat_map(|v| v.parameters()))
            .chain(j.dielectric.iter().flat_map(|d| &d.parameters))
            .collect();
        for e in u {
            let same = written
                .iter()
                .any(|p| p.name == e.name && p.unit == e.unit && p.value == e.value);
            if !same {
                return Err(Error::settings(format!(
                    "uncertainty of '{}' [{}] = {}: not a parameter of the identified material with that unit and value",
                    e.name, e.unit, e.value
                )));
            }
        }
        let text =
            serde_json::to_string_pretty(&j).expect("an identified material serialises") + "\n";
        Self::parse(Path::new("(identified material being written)"), &text)?;
        Ok(text)
    }

    /// Read an identified material file; every part is checked by name and unit
    /// like the estimators' fit files, and refused with the file and key.
    pub fn read(path: &Path) -> Result<Self> {
        let (text, _) = read_text(path, &[IDENTIFIED_SCHEMA], "identified")?;
        Self::parse(path, &text)
    }

    /// The material from the text of a file whose schema tag was checked.
    pub(super) fn parse(path: &Path, text: &str) -> Result<Self> {
        let j: IdentifiedJson = typed(path, text)?;
        let Some(h) = &j.hyperelastic else {
            return Err(err(path, "hyperelastic", "missing").with_hint(
                "an identified material always holds its hyperelastic part: identify again",
            ));
        };
        let hyperelastic = HyperelasticPart::from_json(path, "hyperelastic", h)?;
        let viscous = j
            .viscous
            .as_ref()
            .map(|v| Viscous::from_json(path, "viscous", v))
            .transpose()?;
        let (eps_r, composite) = match &j.dielectric {
            None => (None, None),
            Some(d) => dielectric(path, d)?,
        };
        if !j.provenance.is_object() {
            return Err(
                err(path, "provenance", "missing or not a JSON object").with_hint(
                    "dea-fit identify records the traces, the scene and the settings there",
                ),
            );
        }
        let mut uncertainty = Vec::new();
        let lists = [
            ("hyperelastic.parameters", h.parameters()),
            (
                "viscous.parameters",
                j.viscous.as_ref().map_or(&[][..], |v| v.parameters()),
            ),
            (
                "dielectric.parameters",
                j.dielectric.as_ref().map_or(&[][..], |d| &d.parameters),
            ),
        ];
        for (key, list) in lists {
            for (i, p) in list.iter().enumerate() {
                let at = format!("{key}[{i}]");
                match (p.identifiable, p.std_error) {
                    (Some(identifiable), s) => {
                        if let Some(s) = s.filter(|s| !(s.is_finite() && *s >= 0.0)) {
                            return Err(err(path, &format!("{at}.std_error"), format!("{s} is not a standard error"))
                                .with_hint("expected a finite number ≥ 0, or null where there is none"));
                        }
                        uncertainty.push(ParamUncertainty {
                            name: p.name.clone(),
                            unit: p.unit.clone(),
                            value: p.value,
                            std_error: s,
                            identifiable,
                        });
                    }
                    (None, Some(_)) => {
                        return Err(err(path, &format!("{at}.identifiable"), format!("missing for {}, which has a std_error", p.name))
                            .with_hint("a free parameter states whether it is identifiable (true or false); a fixed one has neither"))
                    }
                    (None, None) => {}
                }
            }
        }
        Ok(IdentifiedMaterial {
            hyperelastic,
            viscous,
            eps_r,
            composite,
            uncertainty,
            status: j.status,
            provenance: j.provenance,
        })
    }
}

/// εr of the dielectric part, and the composite it is the rule of, if any (then
/// εr must be the rule's εr(w) to 10⁻⁹: an edited value is refused).
fn dielectric(
    path: &Path,
    d: &DielectricJson,
) -> Result<(Option<f64>, Option<CompositePermittivity>)> {
    let key = "dielectric.parameters";
    let mut expected = vec![("eps_r".to_string(), "1")];
    if d.composite.is_some() {
        expected.push(("mass_fraction".into(), "1"));
    }
    let what = match d.composite {
        Some(_) => "the dielectric part of a composite",
        None => "the dielectric part",
    };
    let v = by_name(path, &d.parameters, key, &expected, what)?;
    let eps = PERMITTIVITY
        .check(&format!("{key}.eps_r"), v[0])
        .map_err(|e| violation(path, e))?;
    let Some(r) = &d.composite else {
        return Ok((Some(eps), None));
    };
    check_mixture(path, "dielectric.composite", &r.mixture)?;
    let rule = eps_at(path, &format!("{key}.mass_fraction"), &r.mixture, v[1])?;
    if (rule - eps).abs() > 1e-9 * rule {
        return Err(err(
            path,
            &format!("{key}.eps_r"),
            format!(
                "{eps} is not the {} rule's εr at mass_fraction {} ({rule})",
                r.mixture.rule.name(),
                v[1]
            ),
        )
        .with_hint("εr follows from the mass fraction: the file was edited; identify again"));
    }
    Ok((
        Some(eps),
        Some(CompositePermittivity {
            mixture: r.mixture,
            freq_hz: r.freq_hz,
            mass_fraction: v[1],
        }),
    ))
}
