//! COMSOL parameter file (Global Definitions ▸ Parameters ▸ Load from File: one
//! `name expression "description"` per line, units in brackets), named after the
//! inputs of the Nonlinear Structural Materials Module's Hyperelastic Material
//! (Structural Mechanics Module User's Guide, hyperelastic material models) and
//! its Viscoelasticity subnode (generalized Maxwell).
//!
//! * Neo-Hookean: Ws = μ/2(Ī1 − 3), `mu`; Mooney-Rivlin, two parameters: `C10`,
//!   `C01`; Yeoh: `c1`, `c2`, `c3` (= C10, C20, C30); Gent: Ws = −μJm/2·ln(1 −
//!   (Ī1 − 3)/Jm), `mu`, `Jm`.
//! * Ogden: Ws = Σ μp/αp(λ̄₁^αp + λ̄₂^αp + λ̄₃^αp − 3), the original form: an abaqus-form
//!   fit converted, μ = 2μ_abaqus/α.
//! * Compressibility: Incompressible material.
//! * Viscoelasticity, generalized Maxwell: branches with shear modulus `Gm` and
//!   relaxation time `taum` in parallel with the hyperelastic (long-term) material,
//!   as the arms of El Atrache Ceballos (2021): Gm = Em/3; the hyperelastic constants are the long-term
//!   response, the fit's scaled by E∞/R.

use super::{alone_warning, mu0, num, ogden_n, ogden_terms, scaled, Draft, Material, Options};
use crate::error::Result;
use crate::material::hyperelastic::OgdenForm;

/// COMSOL's unit of each SI unit the cards use.
fn unit(u: &str) -> &'static str {
    match u {
        "Pa" => "[Pa]",
        "s" => "[s]",
        "kg/m^3" => "[kg/m^3]",
        _ => "",
    }
}

/// One parameter line, recorded as a constant.
fn param(d: &mut Draft, name: &str, v: f64, u: &'static str, what: &str) {
    let v = d.field(name, v, u);
    d.line(format!("{name} {v}{} \"{what}\"", unit(u)));
}

pub(super) fn write(m: &Material, opts: &Options, d: &mut Draft) -> Result<()> {
    let scale = m
        .relaxation
        .as_ref()
        .map_or(1.0, |r| r.long_term_pa / r.reference_pa);
    if let Some(h0) = &m.hyperelastic {
        let h = scaled(h0, scale)?;
        let p = &h.params;
        match h.spec.name.as_str() {
            "neo-hookean" => param(d, "mu", p[0], "Pa", "Neo-Hookean: Lame parameter mu"),
            "mooney-rivlin" => {
                param(d, "C10", p[0], "Pa", "Mooney-Rivlin, two parameters: C10");
                param(d, "C01", p[1], "Pa", "Mooney-Rivlin, two parameters: C01");
            }
            "yeoh" => {
                for (i, v) in p.iter().enumerate() {
                    param(
                        d,
                        &format!("c{}", i + 1),
                        *v,
                        "Pa",
                        &format!("Yeoh: c{} (C{}0)", i + 1, i + 1),
                    );
                }
            }
            "gent" => {
                param(d, "mu", p[0], "Pa", "Gent: Lame parameter mu");
                param(d, "Jm", p[1], "1", "Gent: limiting value Jm of I1 - 3");
            }
            name => {
                let n = ogden_n(name).expect("a known model");
                for (i, (mu, a)) in ogden_terms(&h, OgdenForm::Original).into_iter().enumerate() {
                    param(
                        d,
                        &format!("mu{}", i + 1),
                        mu,
                        "Pa",
                        &format!("Ogden ({n} terms): shear modulus mu{}", i + 1),
                    );
                    param(
                        d,
                        &format!("alpha{}", i + 1),
                        a,
                        "1",
                        &format!("Ogden ({n} terms): exponent alpha{}", i + 1),
                    );
                }
                if h0.spec.form != Some(OgdenForm::Original) {
                    d.note("Ogden: the fit's abaqus-form mu_i (2mu/alpha^2) converted to COMSOL's form (mu/alpha): mu_i = 2*mu_abaqus/alpha_i, exact");
                }
            }
        }
        d.note(format!(
            "Hyperelastic Material, Compressibility: Incompressible material; small-strain shear modulus mu0 = {} Pa",
            num(mu0(&h)?)
        ));
        if scale != 1.0 {
            d.note(format!(
                "hyperelastic constants = the fit's x E_inf/R = {}: the long-term response of the QLV fit",
                num(scale)
            ));
        }
    }
    if let Some(r) = &m.relaxation {
        if m.hyperelastic.is_none() {
            d.warn(alone_warning(r, true));
        }
        for (i, &(tau, e)) in r.terms.iter().enumerate() {
            param(
                d,
                &format!("G{}", i + 1),
                e / 3.0,
                "Pa",
                &format!(
                    "Viscoelasticity, generalized Maxwell: branch {} shear modulus",
                    i + 1
                ),
            );
            param(
                d,
                &format!("tau{}", i + 1),
                tau,
                "s",
                &format!(
                    "Viscoelasticity, generalized Maxwell: branch {} relaxation time",
                    i + 1
                ),
            );
        }
        d.note("generalized Maxwell branches G_m = E_m/3 (shear modulus of an incompressible solid) in parallel with the long-term hyperelastic material");
    }
    if let Some(rho) = opts.density {
        param(d, "rho", rho, "kg/m^3", "Density");
    }
    Ok(())
}
