//! The material part of a DMA fit (`dea-fit dma --out`, [`super::DMA_SCHEMA`]): its
//! Prony series, read into the same [`RelaxationPart`] as a relaxation fit's (the
//! parallel reading: the terms are Maxwell arms kⱼ = Eⱼ, ηⱼ = Eⱼ·τⱼ), with the
//! time–temperature shift it was built with ([`TimeTemperature`]).

use super::{by_name, err, violation, Arm, FileParam, RelaxationPart};
use crate::dma::law::{Law, LawKind};
use crate::error::Result;
use crate::material::check::{ARM_MODULUS, ARM_TIME, MODULUS};
use crate::material::viscoelastic::{Formulation, MeasuredShift, TimeTemperature};
use serde::Deserialize;
use std::path::Path;

/// What a DMA fit file holds of the material (the rest is the run's report).
#[derive(Debug, Clone, Deserialize)]
pub(super) struct DmaJson {
    #[serde(rename = "reference_temperature_K")]
    reference_temperature_k: Option<f64>,
    shift: String,
    shift_factors: Vec<FactorJson>,
    shift_model: Option<Law>,
    prony: PronyJson,
}

#[derive(Debug, Clone, Deserialize)]
struct FactorJson {
    #[serde(rename = "temperature_K")]
    temperature_k: f64,
    #[serde(rename = "log10_aT")]
    log10_at: f64,
    #[serde(rename = "log10_bT", default)]
    log10_bt: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
struct PronyJson {
    #[serde(rename = "E_inf")]
    e_inf: f64,
    terms: Vec<TermJson>,
    fit: PronyFitJson,
}

#[derive(Debug, Clone, Deserialize)]
struct TermJson {
    #[serde(rename = "E")]
    e: f64,
    tau: f64,
}

#[derive(Debug, Clone, Deserialize)]
struct PronyFitJson {
    parameters: Vec<FileParam>,
}

/// The Prony series of a DMA fit and its shift law. The terms (`prony.terms`) must
/// agree with the fit's parameters by name (`prony.fit.parameters`: `E_inf`,
/// `E1…EN` in Pa, `tau1…tauN` in s) and be plausible; a term of modulus exactly 0
/// (a bound of the non-negative fit: it carries nothing) is left out. The shift:
/// `shift` names `free`, `wlf` or `arrhenius`, a law needs its `shift_model` with
/// its constants at the file's reference temperature, and the measured shifts are
/// strictly increasing in temperature. A master curve read without temperatures has
/// no shift (None).
pub(super) fn dma_part(path: &Path, f: &DmaJson) -> Result<RelaxationPart> {
    let n = f.prony.terms.len();
    let mut expected: Vec<(String, &str)> = vec![("E_inf".into(), "Pa")];
    expected.extend((1..=n).map(|i| (format!("E{i}"), "Pa")));
    expected.extend((1..=n).map(|i| (format!("tau{i}"), "s")));
    let key = "prony.fit.parameters";
    let vals = by_name(
        path,
        &f.prony.fit.parameters,
        key,
        &expected,
        &format!("a {n}-term Prony series"),
    )?;
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    let edited = |at: &str, what: String| {
        err(path, at, what).with_hint("the file was edited: run dea-fit dma again")
    };
    if !same(vals[0], f.prony.e_inf) {
        return Err(edited(
            "prony.E_inf",
            format!("{} disagrees with {key} E_inf = {}", f.prony.e_inf, vals[0]),
        ));
    }
    let e_inf = MODULUS
        .check("prony.E_inf", f.prony.e_inf)
        .map_err(|e| violation(path, e))?;
    if e_inf < 0.0 {
        return Err(edited(
            "prony.E_inf",
            format!("{e_inf} Pa: a long-term modulus is not negative"),
        ));
    }
    let mut arms = Vec::with_capacity(n);
    for (j, t) in f.prony.terms.iter().enumerate() {
        let at = format!("prony.terms[{j}]");
        if !(same(t.e, vals[1 + j]) && same(t.tau, vals[1 + n + j])) {
            return Err(edited(
                &at,
                format!(
                    "term {} disagrees with {key} E{0} = {}, tau{0} = {}",
                    j + 1,
                    vals[1 + j],
                    vals[1 + n + j]
                ),
            ));
        }
        if t.e == 0.0 {
            continue;
        }
        let e = ARM_MODULUS
            .check(&format!("{at}.E"), t.e)
            .map_err(|x| violation(path, x))?;
        let tau = ARM_TIME
            .check(&format!("{at}.tau"), t.tau)
            .map_err(|x| violation(path, x))?;
        arms.push(Arm {
            k_pa: e,
            eta_pa_s: e * tau,
        });
    }
    Ok(RelaxationPart {
        long_term_pa: e_inf,
        arms,
        formulation: Formulation::Parallel,
        qlv: None,
        shift: shift(path, f)?,
        schema: super::DMA_SCHEMA,
    })
}

/// The file's time–temperature shift, checked (see [`dma_part`]).
fn shift(path: &Path, f: &DmaJson) -> Result<Option<TimeTemperature>> {
    let kind = match f.shift.as_str() {
        "free" => None,
        "wlf" => Some(LawKind::Wlf),
        "arrhenius" => Some(LawKind::Arrhenius),
        s => {
            return Err(err(
                path,
                "shift",
                format!("'{s}' is not free, wlf or arrhenius"),
            )
            .with_hint("the file was edited: run dea-fit dma again"))
        }
    };
    if f.shift_factors.is_empty() && kind.is_none() {
        return Ok(None);
    }
    let tr = f.reference_temperature_k.ok_or_else(|| {
        err(
            path,
            "reference_temperature_K",
            "missing: shifted isotherms have a reference temperature",
        )
        .with_hint("the file was edited: run dea-fit dma again")
    })?;
    crate::dma::temperature::check(tr).map_err(|e| err(path, "reference_temperature_K", e))?;
    let mut measured = Vec::with_capacity(f.shift_factors.len());
    for (j, s) in f.shift_factors.iter().enumerate() {
        let at = format!("shift_factors[{j}]");
        crate::dma::temperature::check(s.temperature_k)
            .map_err(|e| err(path, &format!("{at}.temperature_K"), e))?;
        if !s.log10_at.is_finite() || s.log10_bt.is_some_and(|b| !b.is_finite()) {
            return Err(err(
                path,
                &at,
                "log10_aT and log10_bT must be finite numbers",
            ));
        }
        if measured
            .last()
            .is_some_and(|p: &MeasuredShift| p.temperature_k >= s.temperature_k)
        {
            return Err(err(
                path,
                &format!("{at}.temperature_K"),
                "the shift factors must be in increasing temperature",
            )
            .with_hint("the file was edited: run dea-fit dma again"));
        }
        measured.push(MeasuredShift {
            temperature_k: s.temperature_k,
            log10_at: s.log10_at,
            log10_bt: s.log10_bt,
        });
    }
    if measured.len() < 2 {
        return Err(err(
            path,
            "shift_factors",
            format!(
                "{} shift factor(s): a shift needs at least two isotherms",
                measured.len()
            ),
        )
        .with_hint("the file was edited: run dea-fit dma again"));
    }
    let law = match kind {
        None => None,
        Some(k) => {
            let law = f.shift_model.ok_or_else(|| {
                err(
                    path,
                    "shift_model",
                    format!("missing: shift = \"{}\" names a law", f.shift),
                )
                .with_hint("the file was edited: run dea-fit dma again")
            })?;
            let finite = |x: Option<f64>| x.is_some_and(f64::is_finite);
            let complete = match k {
                LawKind::Wlf => finite(law.c1) && law.c2.is_some_and(|c| c.is_finite() && c > 0.0),
                LawKind::Arrhenius => finite(law.activation_energy),
            };
            if law.kind != k || !complete || law.reference_temperature_k != tr {
                return Err(err(
                    path,
                    "shift_model",
                    format!(
                        "not a {} law at the file's reference temperature {tr} K with its constants (WLF: C1, C2 > 0; Arrhenius: activation_energy_J_mol)",
                        k.label()
                    ),
                )
                .with_hint("the file was edited: run dea-fit dma again"));
            }
            Some(law)
        }
    };
    Ok(Some(TimeTemperature {
        reference_k: tr,
        law,
        measured,
    }))
}
