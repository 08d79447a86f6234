//! LS-DYNA keyword cards (Keyword User's Manual, Vol. II: *MAT_HYPERELASTIC_RUBBER,
//! MAT_077_H, and *MAT_OGDEN_RUBBER, MAT_077_O), in long format (`*KEYWORD LONG=Y`,
//! 20-character fields, numbers in at most 19: 12 or more significant digits, so the
//! card holds the fit's values to 5·10⁻¹², [`super::precision`]).
//!
//! * MAT_077_H: W = Σ Cpq(Ī1 − 3)^p(Ī2 − 3)^q + bulk term; Neo-Hookean C10 = μ/2,
//!   Mooney-Rivlin C10, C01, Yeoh C10, C20, C30.
//! * MAT_077_O: W = Σᵢ Σⱼ μⱼ/αⱼ(λ̄ᵢ^αⱼ − 1) + bulk term, the original Ogden form:
//!   a abaqus-form fit converted, μ = 2μ_abaqus/α.
//! * No Gent: refused. No fully incompressible option: PR from K = `bulk_ratio`·μ0.
//! * Viscoelasticity: GI, BETAI with g(t) = Σ Gᵢ·e^(−βᵢt) convolved with the strain
//!   rate and added to the hyperelastic (long-term) stress, as the arms of El Atrache Ceballos (2021):
//!   Gᵢ = Eᵢ/3 (shear modulus of an incompressible solid), βᵢ = 1/τᵢ; the
//!   hyperelastic constants are the long-term response, the fit's scaled by E∞/R.
//!   At most 6 terms.

use super::{
    mu0, needs_hyperelastic, num, ogden_n, ogden_terms, scaled, too_many_terms, Draft, Material,
    Options, Target, LSDYNA_WIDTH as WIDTH,
};
use crate::error::{Error, Result};
use crate::material::hyperelastic::OgdenForm;

/// Viscoelastic cards MAT_077 takes.
const MAX_TERMS: usize = 6;

/// A card of fields, with a `$#` line naming them above.
fn card(d: &mut Draft, names: &[&str], values: &[String]) {
    let head: String = names.iter().map(|n| format!("{n:>WIDTH$}")).collect();
    d.line(format!("$#{}", &head[2..]));
    d.line(values.concat());
}

pub(super) fn write(m: &Material, opts: &Options, d: &mut Draft) -> Result<()> {
    let Some(h0) = &m.hyperelastic else {
        return Err(needs_hyperelastic(Target::Lsdyna));
    };
    let Some(rho) = opts.density else {
        return Err(
            Error::settings("an LS-DYNA material card holds the mass density (RO)")
                .with_hint("give --density, e.g. --density 1000kg/m3"),
        );
    };
    if let Some(r) = &m.relaxation {
        if r.terms.len() > MAX_TERMS {
            return Err(too_many_terms(Target::Lsdyna, r.terms.len(), MAX_TERMS));
        }
    }
    let scale = m
        .relaxation
        .as_ref()
        .map_or(1.0, |r| r.long_term_pa / r.reference_pa);
    let h = scaled(h0, scale)?;
    let mu = mu0(&h)?;
    // ν of K = bulk_ratio·μ0: ν = (3K − 2μ)/(2(3K + μ))
    let k = opts.bulk_ratio;
    let pr = (3.0 * k - 2.0) / (2.0 * (3.0 * k + 1.0));
    let p = &h.params;
    let ogden = ogden_n(&h.spec.name);
    let keyword = match (h.spec.name.as_str(), ogden) {
        ("gent", _) => {
            return Err(super::no_model(
                Target::Lsdyna,
                "Gent",
                "ansys, febio or comsol",
            ))
        }
        (_, Some(_)) => "*MAT_OGDEN_RUBBER_TITLE",
        _ => "*MAT_HYPERELASTIC_RUBBER_TITLE",
    };
    d.line(keyword);
    d.line(&m.name);
    let first = [
        format!("{:>WIDTH$}", 1),
        d.field("RO", rho, "kg/m^3"),
        d.field("PR", pr, "1"),
        Target::Lsdyna.field(0.0),
    ];
    card(d, &["mid", "ro", "pr", "n"], &first);
    match ogden {
        None => {
            let c = match h.spec.name.as_str() {
                "neo-hookean" => [p[0] / 2.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                "mooney-rivlin" => [p[0], p[1], 0.0, 0.0, 0.0, 0.0],
                _ => [p[0], 0.0, 0.0, p[1], 0.0, p[2]],
            };
            let names = ["C10", "C01", "C11", "C20", "C02", "C30"];
            let values: Vec<String> = names
                .iter()
                .zip(c)
                .map(|(n, v)| d.field(*n, v, "Pa"))
                .collect();
            card(d, &["c10", "c01", "c11", "c20", "c02", "c30"], &values);
        }
        Some(_) => {
            let terms = ogden_terms(&h, OgdenForm::Original);
            let mus: Vec<String> = terms
                .iter()
                .enumerate()
                .map(|(i, t)| d.field(format!("MU{}", i + 1), t.0, "Pa"))
                .collect();
            let names: Vec<String> = (1..=terms.len()).map(|i| format!("mu{i}")).collect();
            card(
                d,
                &names.iter().map(String::as_str).collect::<Vec<_>>(),
                &mus,
            );
            let alphas: Vec<String> = terms
                .iter()
                .enumerate()
                .map(|(i, t)| d.field(format!("ALPHA{}", i + 1), t.1, "1"))
                .collect();
            let names: Vec<String> = (1..=terms.len()).map(|i| format!("alpha{i}")).collect();
            card(
                d,
                &names.iter().map(String::as_str).collect::<Vec<_>>(),
                &alphas,
            );
            if h0.spec.form != Some(OgdenForm::Original) {
                d.note("Ogden: the fit's abaqus-form mu_i (2mu/alpha^2) converted to LS-DYNA's original form (mu/alpha): mu_i = 2*mu_abaqus/alpha_i, exact");
            }
        }
    }
    if let Some(r) = &m.relaxation {
        for (i, &(tau, e)) in r.terms.iter().enumerate() {
            let g = d.field(format!("GI{}", i + 1), e / 3.0, "Pa");
            let b = d.field(format!("BETAI{}", i + 1), 1.0 / tau, "1/s");
            card(d, &["gi", "betai"], &[g, b]);
        }
        d.note("viscoelastic G_i = E_i/3 (shear modulus of an incompressible solid), BETA_i = 1/tau_i; the hyperelastic constants are the long-term response");
        // MAT_077's viscoelastic cards take no temperature shift
        super::trs(r, "LS-DYNA (MAT_077)", |_| false, d);
        if scale != 1.0 {
            d.note(format!(
                "hyperelastic constants = the fit's x E_inf/R = {}: the long-term response of the QLV fit",
                num(scale)
            ));
        }
    }
    d.warn(format!(
        "nearly incompressible: LS-DYNA has no incompressible rubber, PR = {} (K = {k} mu0 = {} Pa, --bulk-ratio); the card's stress differs from the incompressible fit's by O(stress/K)",
        num(pr),
        num(k * mu)
    ));
    Ok(())
}
