//! The viscous part of a material file: the seed's generalised Kelvin–Maxwell
//! model (a Kelvin–Voigt dashpot Nv and Maxwell arms), read from a relaxation fit
//! (its arms) or an identified material (arms and Nv).

use super::{by_name, err, join, violation, FileParam, ParamUncertainty};
use crate::error::Result;
use crate::material::check::{ARM_MODULUS, ARM_TIME, DASHPOT, MODULUS, SHEAR_MODULUS};
use crate::material::viscoelastic::{Formulation, TimeTemperature};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One Maxwell arm: spring k in series with dashpot η (τ = η/k), seed Eq. 3.16.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Arm {
    /// Spring modulus (Pa).
    pub k_pa: f64,
    /// Dashpot viscosity (Pa·s).
    pub eta_pa_s: f64,
}

/// Viscous part of the seed's generalised Kelvin-Maxwell model: Kelvin-Voigt dashpot
/// Nv (σ = Nv·dλ/dt, Eq. 3.14 read as strain rate) and Maxwell arms.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Viscous {
    /// Kelvin-Voigt dashpot (Pa·s).
    pub nv_pa_s: f64,
    /// Maxwell arms.
    pub arms: Vec<Arm>,
}

/// The parameter names and SI units of a viscous part with `arms` arms, in file
/// order: `nv` [Pa s], then `armJ.k` [Pa], `armJ.tau` [s] (the names of the
/// simulator's sensitivities).
fn expected(arms: usize) -> Vec<(String, &'static str)> {
    let mut e = vec![("nv".to_string(), "Pa s")];
    for j in 1..=arms {
        e.push((format!("arm{j}.k"), "Pa"));
        e.push((format!("arm{j}.tau"), "s"));
    }
    e
}

/// The viscous part as an identified file holds it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct ViscousJson {
    parameters: Vec<FileParam>,
}

impl ViscousJson {
    /// The parameters as written.
    pub(super) fn parameters(&self) -> &[FileParam] {
        &self.parameters
    }
}

impl Viscous {
    /// The part as a file holds it, each parameter with its uncertainty by name.
    pub(super) fn to_json(&self, uncertainty: &[ParamUncertainty]) -> ViscousJson {
        let mut values = vec![self.nv_pa_s];
        for a in &self.arms {
            values.extend([a.k_pa, a.eta_pa_s / a.k_pa]);
        }
        ViscousJson {
            parameters: expected(self.arms.len())
                .iter()
                .zip(values)
                .map(|((n, u), v)| FileParam::with(n, u, v, uncertainty))
                .collect(),
        }
    }

    /// The part from its file shape: `nv` and, for each of its arms J = 1…N (N
    /// from the count of `armJ.k` names), `armJ.k` and `armJ.tau`, each once, in
    /// SI and plausible (`material::check`).
    pub(super) fn from_json(path: &Path, prefix: &str, j: &ViscousJson) -> Result<Self> {
        let key = join(prefix, "parameters");
        let n = j
            .parameters
            .iter()
            .filter(|p| p.name.starts_with("arm") && p.name.ends_with(".k"))
            .count();
        let what = format!(
            "a viscous part with {n} arm{}",
            if n == 1 { "" } else { "s" }
        );
        // by name: each expected once and nothing else, so the count is right too
        let v = by_name(path, &j.parameters, &key, &expected(n), &what)?;
        let check = |dom: &crate::material::check::Domain, name: &str, x: f64| {
            dom.check(&format!("{key}.{name}"), x)
                .map_err(|e| violation(path, e))
        };
        let nv = check(&DASHPOT, "nv", v[0])?;
        let mut arms = Vec::with_capacity(n);
        for a in 0..n {
            let k = check(&ARM_MODULUS, &format!("arm{}.k", a + 1), v[1 + 2 * a])?;
            let tau = check(&ARM_TIME, &format!("arm{}.tau", a + 1), v[2 + 2 * a])?;
            arms.push(Arm {
                k_pa: k,
                eta_pa_s: k * tau,
            });
        }
        Ok(Viscous { nv_pa_s: nv, arms })
    }
}

/// The material part of a relaxation fit file: its parameters, Prony terms,
/// Kelvin–Maxwell arms, the formulation they belong to and, for a QLV fit, the
/// hyperelastic reference (the rest of the file is the estimator's report).
#[derive(Debug, Clone, Deserialize)]
pub(super) struct RelaxationJson {
    parameters: Vec<FileParam>,
    prony: Vec<PronyJson>,
    kelvin_maxwell: Vec<ArmJson>,
    formulation: Formulation,
    #[serde(default)]
    qlv: Option<QlvJson>,
}

#[derive(Debug, Clone, Deserialize)]
struct PronyJson {
    tau_s: f64,
    #[serde(rename = "modulus_Pa")]
    modulus_pa: f64,
}

#[derive(Debug, Clone, Deserialize)]
struct ArmJson {
    #[serde(rename = "k_Pa")]
    k_pa: f64,
    #[serde(rename = "n_Pa_s")]
    n_pa_s: f64,
}

#[derive(Debug, Clone, Deserialize)]
struct QlvJson {
    hyperelastic_model: String,
    #[serde(rename = "reference_modulus_Pa")]
    reference_modulus_pa: f64,
    instantaneous_scale: f64,
}

/// The hyperelastic fit a QLV relaxation fit relaxes: σ(t) = ∫ G(t − s) dσₑ(s) with
/// G(t) = E(t)/E_ref, σₑ the uniaxial stress of that fit and E_ref = 3μ0 its
/// small-strain Young's modulus.
#[derive(Debug, Clone, PartialEq)]
pub struct QlvReference {
    /// Its model (`yeoh`, `ogden3`, …).
    pub hyperelastic_model: String,
    /// E_ref = 3μ0 of that fit (Pa): the modulus the Prony moduli are relative to.
    pub reference_modulus_pa: f64,
    /// G(0) = (E∞ + ΣEᵢ)/E_ref: the instantaneous response is G(0)·σₑ.
    pub instantaneous_scale: f64,
}

/// The material part of a relaxation fit or a DMA fit: the Prony series E(t) = E∞ + Σ Eᵢ·e^(−t/τᵢ)
/// (its terms as the seed's Maxwell arms kⱼ = Eⱼ, ηⱼ = Eⱼ·τⱼ) and the formulation
/// it belongs to (`material::viscoelastic::Formulation`).
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxationPart {
    /// E∞ (Pa): in the parallel reading the equilibrium (secant) modulus at the
    /// tested strain; in the QLV reading g∞·E_ref.
    pub long_term_pa: f64,
    /// The terms, in the file's order (sorted by τ).
    pub arms: Vec<Arm>,
    /// Parallel (the seed's arms) or QLV.
    pub formulation: Formulation,
    /// The hyperelastic reference of a QLV fit (None for a parallel fit).
    pub qlv: Option<QlvReference>,
    /// The time–temperature shift of a DMA fit (None for a relaxation fit, and
    /// for a DMA fit of a master curve given without temperatures).
    pub shift: Option<TimeTemperature>,
    /// The schema of the file it was read from ([`super::RELAXATION_SCHEMA`] or
    /// [`super::DMA_SCHEMA`]).
    pub schema: &'static str,
}

/// The Prony series of a relaxation fit, read by name: `E_inf`, `E1…EN` (Pa) and
/// `tau1…tauN` (s), plausible, agreeing with the file's `prony` and
/// `kelvin_maxwell` lists (see docs/scenes.md for how the arms enter the
/// simulator), and, for a QLV fit, with its stated G(0) = (E∞ + ΣEᵢ)/E_ref.
pub(super) fn relaxation_part(path: &Path, fit: &RelaxationJson) -> Result<RelaxationPart> {
    let n = fit.prony.len();
    let mut expected: Vec<(String, &str)> = vec![("E_inf".into(), "Pa")];
    expected.extend((1..=n).map(|i| (format!("E{i}"), "Pa")));
    expected.extend((1..=n).map(|i| (format!("tau{i}"), "s")));
    let what = format!("a {n}-term Prony series");
    let vals = by_name(path, &fit.parameters, "parameters", &expected, &what)?;
    let e_inf = MODULUS
        .check("parameters.E_inf", vals[0])
        .map_err(|e| violation(path, e))?;
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    let mut arms = Vec::with_capacity(n);
    for j in 0..n {
        let (e, tau) = (vals[1 + j], vals[1 + n + j]);
        ARM_MODULUS
            .check(&format!("parameters.E{}", j + 1), e)
            .map_err(|x| violation(path, x))?;
        ARM_TIME
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
        arms.push(Arm {
            k_pa: a.k_pa,
            eta_pa_s: a.n_pa_s,
        });
    }
    let qlv = match (fit.formulation, &fit.qlv) {
        (Formulation::Parallel, _) => None,
        (Formulation::Qlv, None) => {
            return Err(err(
                path,
                "qlv",
                "missing: a QLV fit names its hyperelastic reference",
            )
            .with_hint("the file was edited: fit the data again with --hyperelastic"))
        }
        (Formulation::Qlv, Some(q)) => {
            let e_ref = SHEAR_MODULUS
                .check("qlv.reference_modulus_Pa", q.reference_modulus_pa / 3.0)
                .map_err(|e| violation(path, e))?
                * 3.0;
            let e0 = e_inf + arms.iter().map(|a| a.k_pa).sum::<f64>();
            if !same(q.instantaneous_scale, e0 / e_ref) {
                return Err(err(
                    path,
                    "qlv.instantaneous_scale",
                    format!(
                        "{} is not (E∞ + ΣEᵢ)/E_ref = {e0} Pa / {e_ref} Pa",
                        q.instantaneous_scale
                    ),
                )
                .with_hint("the file was edited: fit the data again"));
            }
            Some(QlvReference {
                hyperelastic_model: q.hyperelastic_model.clone(),
                reference_modulus_pa: e_ref,
                instantaneous_scale: q.instantaneous_scale,
            })
        }
    };
    Ok(RelaxationPart {
        long_term_pa: e_inf,
        arms,
        formulation: fit.formulation,
        qlv,
        shift: None,
        schema: super::RELAXATION_SCHEMA,
    })
}
