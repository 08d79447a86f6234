//! Abaqus keyword cards (Abaqus Keywords Reference: *HYPERELASTIC, *VISCOELASTIC).
//!
//! * `*HYPERELASTIC, NEO HOOKE`: U = C10(Ī1 − 3) + (J − 1)²/D1, C10 = μ/2.
//! * `MOONEY-RIVLIN`: C10, C01, D1; `YEOH`: C10, C20, C30, D1, D2, D3 (the seed's
//!   polynomial coefficients as they are).
//! * `OGDEN, N=n`: U = Σ 2μᵢ/αᵢ²(λ̄₁^αᵢ + λ̄₂^αᵢ + λ̄₃^αᵢ − 3), the seed form:
//!   μᵢ, αᵢ as fitted (an original-form fit converted, μ = μ_orig·α/2).
//! * Dᵢ = 0: incompressible. No Gent model: refused.
//! * `*VISCOELASTIC, TIME=PRONY`: gᵢ, kᵢ, τᵢ with g_R(t) = 1 − Σ gᵢ(1 − e^(−t/τᵢ))
//!   relative to the instantaneous modulus (gᵢ = Eᵢ/E0); the hyperelastic constants
//!   are then the instantaneous response (`MODULI=INSTANTANEOUS`), the fit's scaled
//!   by E0/R. kᵢ = 0: the volumetric response of an incompressible solid does not
//!   relax.

use super::{
    alone_warning, mu0, num, ogden_n, ogden_terms, scaled, Draft, Material, Options, Target,
};
use crate::error::Result;
use crate::material::hyperelastic::OgdenForm;

/// Values per data line of *HYPERELASTIC.
const PER_LINE: usize = 8;

pub(super) fn write(m: &Material, opts: &Options, d: &mut Draft) -> Result<()> {
    d.line(format!("*MATERIAL, NAME={}", m.name));
    if let Some(rho) = opts.density {
        d.line("*DENSITY");
        let rho = num(d.constant("density", rho, "kg/m^3"));
        d.line(rho);
    }
    let scale = m
        .relaxation
        .as_ref()
        .map_or(1.0, |r| r.instantaneous_pa() / r.reference_pa);
    let moduli = if m.relaxation.is_some() {
        ", MODULI=INSTANTANEOUS"
    } else {
        ""
    };
    if let Some(h0) = &m.hyperelastic {
        let h = scaled(h0, scale)?;
        let p = &h.params;
        let (keyword, values): (String, Vec<(String, f64, &'static str)>) = match h
            .spec
            .name
            .as_str()
        {
            "neo-hookean" => (
                "NEO HOOKE".into(),
                vec![("C10".into(), p[0] / 2.0, "Pa"), ("D1".into(), 0.0, "1/Pa")],
            ),
            "mooney-rivlin" => (
                "MOONEY-RIVLIN".into(),
                vec![
                    ("C10".into(), p[0], "Pa"),
                    ("C01".into(), p[1], "Pa"),
                    ("D1".into(), 0.0, "1/Pa"),
                ],
            ),
            "yeoh" => (
                "YEOH".into(),
                vec![
                    ("C10".into(), p[0], "Pa"),
                    ("C20".into(), p[1], "Pa"),
                    ("C30".into(), p[2], "Pa"),
                    ("D1".into(), 0.0, "1/Pa"),
                    ("D2".into(), 0.0, "1/Pa"),
                    ("D3".into(), 0.0, "1/Pa"),
                ],
            ),
            "gent" => {
                return Err(super::no_model(
                    Target::Abaqus,
                    "Gent",
                    "ansys, febio or comsol",
                ))
            }
            name => {
                let n = ogden_n(name).expect("a known model");
                let mut v = Vec::new();
                for (i, (mu, a)) in ogden_terms(&h, OgdenForm::Seed).into_iter().enumerate() {
                    v.push((format!("MU{}", i + 1), mu, "Pa"));
                    v.push((format!("ALPHA{}", i + 1), a, "1"));
                }
                v.extend((1..=n).map(|i| (format!("D{i}"), 0.0, "1/Pa")));
                if h0.spec.form == Some(OgdenForm::Original) {
                    d.note("Ogden: the fit's original-form mu_i (mu/alpha) converted to Abaqus's form (2mu/alpha^2): mu_i = mu_orig*alpha_i/2, exact");
                }
                (format!("OGDEN, N={n}"), v)
            }
        };
        d.line(format!("*HYPERELASTIC, {keyword}{moduli}"));
        let written: Vec<String> = values
            .into_iter()
            .map(|(name, v, unit)| num(d.constant(name, v, unit)))
            .collect();
        for chunk in written.chunks(PER_LINE) {
            d.line(chunk.join(", "));
        }
        d.note(format!(
            "D = 0: incompressible (Abaqus/Standard, hybrid elements; Abaqus/Explicit needs D > 0); small-strain shear modulus mu0 = {} Pa",
            num(mu0(&h)?)
        ));
        if scale != 1.0 {
            d.note(format!(
                "hyperelastic constants = the fit's x E0/R = {}: the instantaneous response, as Abaqus takes it with a Prony series",
                num(scale)
            ));
        }
    }
    if let Some(r) = &m.relaxation {
        if m.hyperelastic.is_none() {
            d.warn(alone_warning(r, false));
        }
        let e0 = r.instantaneous_pa();
        d.line("*VISCOELASTIC, TIME=PRONY");
        for (i, &(tau, e)) in r.terms.iter().enumerate() {
            let g = d.constant(format!("g{}", i + 1), e / e0, "1");
            let k = d.constant(format!("k{}", i + 1), 0.0, "1");
            let t = d.constant(format!("tau{}", i + 1), tau, "s");
            d.line(format!("{}, {}, {}", num(g), num(k), num(t)));
        }
        d.note(format!(
            "Prony g_i = E_i/E0 relative to the instantaneous modulus E0 = {} Pa (g_inf = {}); k_i = 0: no volumetric relaxation (incompressible)",
            num(e0),
            num(r.long_term_pa / e0)
        ));
    }
    Ok(())
}
