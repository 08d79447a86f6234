//! A composite fit's mixing rule as a scene's permittivity: `dea-fit composite
//! --out` (schema [`COMPOSITE_SCHEMA`]) fits each mixing rule's εm, εf (and Yamada's
//! n) at every frequency; one rule at one frequency, with the phase densities,
//! becomes a [`Mixture`], and with the filler mass fraction w the scene's
//! εr = εr(w) ([`CompositePermittivity`]). Read by name, like every material file.

use super::{by_name, err, read_text, typed, violation, FileParam, Spread, COMPOSITE_SCHEMA};
use crate::error::Result;
use crate::material::check::{fmt_g, MASS_FRACTION, PERMITTIVITY};
use crate::material::dielectric::{MixingRule, Mixture};
use serde::Deserialize;
use std::path::Path;

/// A scene's εr from a composite's mixing rule (`[material] relative_permittivity =
/// { composite = "x.json", mass_fraction = "20 %" }`): εr = εr(w).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompositePermittivity {
    /// The rule with its constants and the phase densities.
    pub mixture: Mixture,
    /// Frequency of the rule's fit (Hz).
    pub freq_hz: f64,
    /// Filler mass fraction w (0 ≤ w < 1).
    pub mass_fraction: f64,
}

impl CompositePermittivity {
    /// εr at the mass fraction.
    pub fn eps_r(&self) -> f64 {
        self.mixture.eps_r(self.mass_fraction)
    }
}

/// A frequency for messages.
fn hz(f: f64) -> String {
    format!("{} Hz", fmt_g(f))
}

/// Share within which a frequency asked for names a fitted one.
const SAME_FREQUENCY: f64 = 0.01;

#[derive(Deserialize)]
struct PhaseJson {
    #[serde(default)]
    density_kg_per_m3: Option<f64>,
}

#[derive(Deserialize)]
struct RuleJson {
    rule: MixingRule,
    parameters: Vec<FileParam>,
    #[serde(default)]
    correlation: serde_json::Value,
    status: String,
}

#[derive(Deserialize)]
struct FrequencyJson {
    #[serde(rename = "freq_Hz")]
    freq_hz: f64,
    rules: Vec<RuleJson>,
}

#[derive(Deserialize)]
struct CompositeJson {
    matrix: PhaseJson,
    filler: PhaseJson,
    fits: Vec<FrequencyJson>,
}

/// Refuse a mixture whose numbers cannot be a composite: εm within the permittivity
/// range, εf and n positive, the densities positive (`key` names it in `path`).
pub(super) fn check_mixture(path: &Path, key: &str, m: &Mixture) -> Result<()> {
    PERMITTIVITY
        .check(&format!("{key}.eps_matrix"), m.eps_matrix)
        .map_err(|v| violation(path, v))?;
    for (name, v) in [
        ("eps_filler", m.eps_filler),
        ("shape_n", m.shape_n),
        ("matrix_density_kg_per_m3", m.rho_matrix),
        ("filler_density_kg_per_m3", m.rho_filler),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(err(
                path,
                &format!("{key}.{name}"),
                format!("{v} must be a finite positive number"),
            ));
        }
    }
    Ok(())
}

/// Check a mass fraction at `key` and give the εr it makes, checked too.
pub(super) fn eps_at(path: &Path, key: &str, m: &Mixture, w: f64) -> Result<f64> {
    MASS_FRACTION
        .check(key, w)
        .map_err(|v| violation(path, v))?;
    PERMITTIVITY
        .check(key, m.eps_r(w))
        .map_err(|v| violation(path, v))
}

/// The mixing rule `rule` (None: the rule the fit ranks first there) of the
/// composite fit `path` at the fitted frequency within 1 % of `freq_hz` (None: the
/// lowest, the one nearest an actuator's drive), and that frequency. A rule whose
/// fit there is not `ok` or `warning`, and phases without densities (a mass
/// fraction needs them), are refused with the key and what to do. The spread is
/// that of the rule's εm, εf (and n), in that order.
pub fn read_mixture(
    path: &Path,
    rule: Option<MixingRule>,
    freq_hz: Option<f64>,
) -> Result<(Mixture, f64, Spread)> {
    let (text, _) = read_text(path, &[COMPOSITE_SCHEMA], "composite")?;
    let j: CompositeJson = typed(path, &text)?;
    let fitted: Vec<String> = j.fits.iter().map(|f| hz(f.freq_hz)).collect();
    let at = match freq_hz {
        None => j
            .fits
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.freq_hz.total_cmp(&b.1.freq_hz)),
        Some(f) => j
            .fits
            .iter()
            .enumerate()
            .find(|(_, x)| (x.freq_hz - f).abs() <= SAME_FREQUENCY * f),
    };
    let Some((fi, fit)) = at else {
        return Err(err(
            path,
            "fits",
            match freq_hz {
                None => "no frequency was fitted".to_string(),
                Some(f) => format!("no fit at {}", hz(f)),
            },
        )
        .with_hint(match fitted.is_empty() {
            true => "fit the series again with dea-fit composite --out".to_string(),
            false => format!("the fitted frequencies: {}", fitted.join(", ")),
        }));
    };
    let found = match rule {
        None => fit.rules.iter().enumerate().next(),
        Some(r) => fit.rules.iter().enumerate().find(|(_, x)| x.rule == r),
    };
    let Some((ri, r)) = found else {
        let names: Vec<&str> = fit.rules.iter().map(|x| x.rule.name()).collect();
        return Err(err(
            path,
            &format!("fits[{fi}].rules"),
            format!(
                "no {} fit at {}",
                rule.map_or("rule", MixingRule::name),
                hz(fit.freq_hz)
            ),
        )
        .with_hint(format!("the rules fitted there: {}", names.join(", "))));
    };
    let key = format!("fits[{fi}].rules[{ri}]");
    if !matches!(r.status.as_str(), "ok" | "warning") {
        return Err(err(
            path,
            &format!("{key}.status"),
            format!(
                "the {} fit at {} is {}: its constants are not usable",
                r.rule.name(),
                hz(fit.freq_hz),
                r.status
            ),
        )
        .with_hint("name another rule (rule = \"...\"; the file ranks them) or frequency"));
    }
    let mut expected = vec![("eps_matrix".to_string(), "1"), ("eps_filler".into(), "1")];
    if r.rule.has_shape() {
        expected.push(("shape_n".into(), "1"));
    }
    let v = by_name(
        path,
        &r.parameters,
        &format!("{key}.parameters"),
        &expected,
        &format!("the {} rule", r.rule.name()),
    )?;
    let density = |phase: &PhaseJson, name: &str| {
        phase.density_kg_per_m3.ok_or_else(|| {
            err(path, &format!("{name}.density_kg_per_m3"), "missing")
                .with_hint("a mass fraction becomes a volume fraction through the densities of both phases: give them in the composite manifest and fit again")
        })
    };
    let mixture = Mixture {
        rule: r.rule,
        eps_matrix: v[0],
        eps_filler: v[1],
        shape_n: v.get(2).copied().unwrap_or(3.0),
        rho_matrix: density(&j.matrix, "matrix")?,
        rho_filler: density(&j.filler, "filler")?,
    };
    check_mixture(path, &key, &mixture)?;
    let names: Vec<String> = expected.into_iter().map(|e| e.0).collect();
    let spread = Spread::by_name(&r.parameters, &names, &r.correlation);
    Ok((mixture, fit.freq_hz, spread))
}
