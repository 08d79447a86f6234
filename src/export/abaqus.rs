//! Abaqus keyword cards (Abaqus Keywords Reference: *HYPERELASTIC, *VISCOELASTIC),
//! and the CalculiX cards written in the same keywords (CalculiX User's Manual,
//! *HYPERELASTIC; the differences below measured with ccx 2.20).
//!
//! * `*HYPERELASTIC, NEO HOOKE`: U = C10(Ī1 − 3) + (J − 1)²/D1, C10 = μ/2.
//! * `MOONEY-RIVLIN`: C10, C01, D1; `YEOH`: C10, C20, C30, D1, D2, D3 (El Atrache Ceballos (2021)'s
//!   polynomial coefficients as they are).
//! * `OGDEN, N=n`: U = Σ 2μᵢ/αᵢ²(λ̄₁^αᵢ + λ̄₂^αᵢ + λ̄₃^αᵢ − 3), the abaqus form:
//!   μᵢ, αᵢ as fitted (an original-form fit converted, μ = μ_orig·α/2).
//! * Dᵢ = 0: incompressible. No Gent model: refused.
//! * `*VISCOELASTIC, TIME=PRONY`: gᵢ, kᵢ, τᵢ with g_R(t) = 1 − Σ gᵢ(1 − e^(−t/τᵢ))
//!   relative to the instantaneous modulus (gᵢ = Eᵢ/E0); the hyperelastic constants
//!   are then the instantaneous response (`MODULI=INSTANTANEOUS`), the fit's scaled
//!   by E0/R. kᵢ = 0: the volumetric response of an incompressible solid does not
//!   relax.
//! * `*TRS` after it for a DMA fit's shift law ([`trs`]).
//!
//! CalculiX:
//! * D = 0 is not incompressible: ccx replaces a D1 below 10⁻¹⁰ 1/Pa by a
//!   compressible default (ν = 0.475), which makes a rubber too soft (Neo-Hookean,
//!   λ = 1.5: 2.7 % uniaxial, 5.0 % equibiaxial).
//!   The card writes D1 = 2/K with K = `bulk_ratio`·μ0 (U's volumetric term
//!   (J − 1)²/D1, K = 2/D1), refused where D1 would fall below 10⁻¹⁰; the higher
//!   Dᵢ (Yeoh, Ogden N ≥ 2) are 1 1/Pa, terms (J − 1)^(2i) negligible, since ccx
//!   replaces a 0 by its defaults (10⁻¹², 10⁻¹⁸).
//! * OGDEN takes N ≤ 3; no Gent; no hybrid (C3D8H) elements.
//! * `*VISCOELASTIC` and `MODULI=` are ignored (a warning in ccx's output): the
//!   card holds the long-term hyperelastic response, the fit's scaled by E∞/R,
//!   and no Prony block.

use super::{
    alone_warning, mu0, num, ogden_n, ogden_terms, scaled, Draft, Material, Options, Relaxation,
    Target, Trs,
};
use crate::dma::law::{LawKind, GAS_CONSTANT};
use crate::error::{Error, Result};
use crate::material::hyperelastic::OgdenForm;

/// Values per data line of *HYPERELASTIC.
const PER_LINE: usize = 8;

/// The smallest D1 (1/Pa) ccx 2.20 reads as given (measured: 1.0E-10 is kept,
/// 9.9E-11 replaced by the compressible default).
const CALCULIX_MIN_D: f64 = 1e-10;

/// Largest number of Ogden terms of CalculiX's *HYPERELASTIC, OGDEN.
const CALCULIX_MAX_OGDEN: usize = 3;

pub(super) fn write(m: &Material, target: Target, opts: &Options, d: &mut Draft) -> Result<()> {
    let ccx = target == Target::Calculix;
    d.line(format!("*MATERIAL, NAME={}", m.name));
    if let Some(rho) = opts.density {
        d.line("*DENSITY");
        let rho = d.field("density", rho, "kg/m^3");
        d.line(rho);
    }
    if ccx {
        d.note("CalculiX ignores *VISCOELASTIC (ccx 2.20: the card image cannot be interpreted): a viscoelastic fit is written as its long-term hyperelastic response only");
        if m.hyperelastic.is_none() {
            return Err(Error::settings(
                "CalculiX has no viscoelastic hyperelastic material (it ignores *VISCOELASTIC): a relaxation fit alone has nothing to write",
            )
            .with_hint("export it --to abaqus, ansys or comsol, or give a hyperelastic fit for its long-term response"));
        }
    }
    let scale = m.relaxation.as_ref().map_or(1.0, |r| {
        if ccx {
            r.long_term_pa / r.reference_pa
        } else {
            r.instantaneous_pa() / r.reference_pa
        }
    });
    let moduli = if m.relaxation.is_some() && !ccx {
        ", MODULI=INSTANTANEOUS"
    } else {
        ""
    };
    if let Some(h0) = &m.hyperelastic {
        let h = scaled(h0, scale)?;
        let p = &h.params;
        let mu = mu0(&h)?;
        // D1, and the higher D_i, of the card (docs at the top)
        let (d1, dn) = if ccx {
            if !(mu > 0.0 && mu.is_finite()) {
                return Err(Error::settings(format!(
                    "CalculiX: the small-strain shear modulus mu0 = {} Pa gives no bulk modulus K = (K/mu0)*mu0 > 0 for D1 = 2/K",
                    num(mu)
                ))
                .with_hint("check the fit: a rubber has mu0 > 0"));
            }
            let d1 = 2.0 / (opts.bulk_ratio * mu);
            if d1 < CALCULIX_MIN_D {
                return Err(Error::settings(format!(
                    "CalculiX: D1 = 2/(K/mu0 * mu0) = {} 1/Pa (mu0 = {} Pa, K/mu0 = {}) is below 1e-10, which ccx reads as D = 0 and replaces by its compressible default (nu = 0.475)",
                    num(d1), num(mu), opts.bulk_ratio
                ))
                .with_hint(format!(
                    "give --bulk-ratio {} or less",
                    (2.0 / (CALCULIX_MIN_D * mu)).floor()
                )));
            }
            (d1, 1.0)
        } else {
            (0.0, 0.0)
        };
        let (keyword, values): (String, Vec<(String, f64, &'static str)>) = match h
            .spec
            .name
            .as_str()
        {
            "neo-hookean" => (
                "NEO HOOKE".into(),
                vec![("C10".into(), p[0] / 2.0, "Pa"), ("D1".into(), d1, "1/Pa")],
            ),
            "mooney-rivlin" => (
                "MOONEY-RIVLIN".into(),
                vec![
                    ("C10".into(), p[0], "Pa"),
                    ("C01".into(), p[1], "Pa"),
                    ("D1".into(), d1, "1/Pa"),
                ],
            ),
            "yeoh" => (
                "YEOH".into(),
                vec![
                    ("C10".into(), p[0], "Pa"),
                    ("C20".into(), p[1], "Pa"),
                    ("C30".into(), p[2], "Pa"),
                    ("D1".into(), d1, "1/Pa"),
                    ("D2".into(), dn, "1/Pa"),
                    ("D3".into(), dn, "1/Pa"),
                ],
            ),
            "gent" => return Err(super::no_model(target, "Gent", "ansys, febio or comsol")),
            name => {
                let n = ogden_n(name).expect("a known model");
                if ccx && n > CALCULIX_MAX_OGDEN {
                    return Err(Error::settings(format!(
                        "CalculiX's OGDEN takes N = 1, 2 or 3 terms: a {n}-term Ogden fit cannot be written for it"
                    ))
                    .with_hint("fit ogden1..ogden3 for CalculiX (dea-fit hyperelastic --model ogden3), or export to abaqus, ansys, lsdyna, febio or comsol"));
                }
                let mut v = Vec::new();
                for (i, (mu, a)) in ogden_terms(&h, OgdenForm::Abaqus).into_iter().enumerate() {
                    v.push((format!("MU{}", i + 1), mu, "Pa"));
                    v.push((format!("ALPHA{}", i + 1), a, "1"));
                }
                v.extend((1..=n).map(|i| (format!("D{i}"), if i == 1 { d1 } else { dn }, "1/Pa")));
                if h0.spec.form == Some(OgdenForm::Original) {
                    d.note(format!("Ogden: the fit's original-form mu_i (mu/alpha) converted to {}'s form (2mu/alpha^2): mu_i = mu_orig*alpha_i/2, exact", target.title()));
                }
                (format!("OGDEN, N={n}"), v)
            }
        };
        d.line(format!("*HYPERELASTIC, {keyword}{moduli}"));
        let written: Vec<String> = values
            .into_iter()
            .map(|(name, v, unit)| d.field(name, v, unit))
            .collect();
        for chunk in written.chunks(PER_LINE) {
            d.line(chunk.join(", "));
        }
        if ccx {
            d.warn(format!(
                "nearly incompressible: CalculiX has no incompressible rubber (D = 0 is replaced by a compressible default, nu = 0.475) and no hybrid elements; D1 = 2/K with K = {} mu0 = {} Pa (--bulk-ratio), higher D_i = 1 1/Pa (negligible); the card's stress differs from the incompressible fit's by O(stress/K)",
                opts.bulk_ratio,
                num(opts.bulk_ratio * mu)
            ));
            d.note(format!("small-strain shear modulus mu0 = {} Pa", num(mu)));
        } else {
            d.note(format!(
                "D = 0: incompressible (Abaqus/Standard, hybrid elements; Abaqus/Explicit needs D > 0); small-strain shear modulus mu0 = {} Pa",
                num(mu)
            ));
        }
        if let Some(r) = m.relaxation.as_ref().filter(|_| ccx) {
            d.warn(format!(
                "CalculiX ignores *VISCOELASTIC: the {} relaxation terms are not written; the hyperelastic constants are the long-term response, the fit's x E_inf/R = {} (the instantaneous response would be x E0/R = {})",
                r.terms.len(),
                num(scale),
                num(r.instantaneous_pa() / r.reference_pa)
            ));
        } else if scale != 1.0 {
            d.note(format!(
                "hyperelastic constants = the fit's x E0/R = {}: the instantaneous response, as Abaqus takes it with a Prony series",
                num(scale)
            ));
        }
    }
    if let Some(r) = m.relaxation.as_ref().filter(|_| !ccx) {
        if m.hyperelastic.is_none() {
            d.warn(alone_warning(r, false));
        }
        let e0 = r.instantaneous_pa();
        d.line("*VISCOELASTIC, TIME=PRONY");
        for (i, &(tau, e)) in r.terms.iter().enumerate() {
            let g = d.field(format!("g{}", i + 1), e / e0, "1");
            let k = d.field(format!("k{}", i + 1), 0.0, "1");
            let t = d.field(format!("tau{}", i + 1), tau, "s");
            d.line(format!("{g}, {k}, {t}"));
        }
        d.note(format!(
            "Prony g_i = E_i/E0 relative to the instantaneous modulus E0 = {} Pa (g_inf = {}); k_i = 0: no volumetric relaxation (incompressible)",
            num(e0),
            num(r.long_term_pa / e0)
        ));
        trs(r, d);
    }
    if let Some(r) = m.relaxation.as_ref().filter(|_| ccx) {
        super::trs(r, "CalculiX (it ignores *VISCOELASTIC)", |_| false, d);
    }
    Ok(())
}

/// The time–temperature shift of a DMA fit after its Prony series (Abaqus
/// Keywords Reference, *TRS; Abaqus Analysis User's Guide, "Time domain
/// viscoelasticity", thermorheologically simple temperature effects):
/// * `*TRS, DEFINITION=WLF`, data line θ0, C1, C2 with
///   log10 A = −C1(θ − θ0)/(C2 + θ − θ0), A the factor of the relaxation times
///   (reduced time dτ/dt = 1/A), the fit's aT and constants as they are;
/// * `*TRS, DEFINITION=ARRHENIUS`, data line θ0, E0 with
///   ln A = E0/R·(1/(θ − θZ) − 1/(θ0 − θZ)): E0 = Ea, and the model's
///   `*PHYSICAL CONSTANTS, ABSOLUTE ZERO=0, UNIVERSAL GAS CONSTANT=R` (in K), which
///   Abaqus needs for it (model data: it ends the material definition);
/// * free shifts: no card (DEFINITION=USER needs a user subroutine), a comment.
///
/// Temperatures in K (a comment line in the card says so).
fn trs(r: &Relaxation, d: &mut Draft) {
    match super::trs(r, "Abaqus", |_| true, d) {
        Some(Trs::Law(law)) => {
            d.line("** time-temperature shift of the DMA fit; temperatures in K (theta0 = Tr)");
            let t0 = d.field("theta0", law.reference_temperature_k, "K");
            match law.kind {
                LawKind::Wlf => {
                    d.line("*TRS, DEFINITION=WLF");
                    let c1 = d.field("C1", law.c1.unwrap_or(f64::NAN), "1");
                    let c2 = d.field("C2", law.c2.unwrap_or(f64::NAN), "K");
                    d.line(format!("{t0}, {c1}, {c2}"));
                }
                LawKind::Arrhenius => {
                    d.line("*TRS, DEFINITION=ARRHENIUS");
                    let e0 = d.field("E0", law.activation_energy.unwrap_or(f64::NAN), "J/mol");
                    d.line(format!("{t0}, {e0}"));
                    d.line("** model data for ARRHENIUS (once per model; it ends the material definition)");
                    // model data, not a constant of the material
                    d.line(format!(
                        "*PHYSICAL CONSTANTS, ABSOLUTE ZERO=0., UNIVERSAL GAS CONSTANT={}",
                        Target::Abaqus.field(GAS_CONSTANT)
                    ));
                }
            }
        }
        Some(Trs::Free) => d.line(
            "** no *TRS: the DMA fit's shifts are free, tabulated in its shift_factors (DEFINITION=USER would need a user subroutine): the card is the material at Tr",
        ),
        None => {}
    }
}
