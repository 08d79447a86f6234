//! FEBio `<Material>` section (FEBio User's Manual, uncoupled materials; the
//! energies below are those of the FEBio source, FEBioMech/FE*.cpp).
//!
//! * `Mooney-Rivlin`: W = c1(Ĩ1 − 3) + c2(Ĩ2 − 3) + U(J): c1 = C10, c2 = C01;
//!   Neo-Hookean as c1 = μ/2, c2 = 0.
//! * `Ogden`: W = Σ cᵢ/mᵢ²(λ̃₁^mᵢ + λ̃₂^mᵢ + λ̃₃^mᵢ − 3) + U(J): the abaqus form with
//!   cᵢ = 2μᵢ, mᵢ = αᵢ (at most 6 terms).
//! * `Gent`: W = −G·Jm/2·ln(1 − (Ĩ1 − 3)/Jm) + U(J): G = μ, Jm.
//! * Yeoh has no FEBio material of its own: `uncoupled hyperelastic` with the
//!   energy W(I1, I2) written out (FEBio 4).
//! * `k`: bulk modulus of the uncoupled penalty, K = `bulk_ratio`·μ0 (no fully
//!   incompressible option).
//! * `uncoupled viscoelastic`: S = g0·Sₑ + Σ gᵢ·Hᵢ with Hᵢ the hereditary integral of
//!   the elastic stress Sₑ with kernel e^(−t/τᵢ): G(t) = g0 + Σ gᵢ·e^(−t/τᵢ) scales
//!   the elastic stress, as QLV does; with the fit's constants as the elastic
//!   material, g0 = E∞/R, gᵢ = Eᵢ/R (at most 6 terms).

use super::{
    mu0, needs_hyperelastic, num, ogden_terms, plain, too_many_terms, Draft, Material, Options,
    Target,
};
use crate::error::Result;
use crate::material::hyperelastic::OgdenForm;

/// Terms of FEBio's Ogden and viscoelastic materials.
const MAX_TERMS: usize = 6;

/// The document: XML declaration, the header as one comment, the section.
pub(super) fn document(header: &[String], body: &str) -> String {
    let mut s = String::from("<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>\n<!--\n");
    for h in header {
        for l in super::wrap(h, 100) {
            // "--" may not appear inside an XML comment
            s.push_str(&format!("  {}\n", l.replace("--", "- -")));
        }
    }
    s.push_str("-->\n<Material>\n");
    s.push_str(body);
    s.push_str("</Material>\n");
    s
}

/// `<name>value</name>` at `indent` tabs, the value recorded as a constant.
fn param(d: &mut Draft, indent: usize, name: &str, v: f64, unit: &'static str) {
    let v = d.field(name, v, unit);
    d.line(format!("{}<{name}>{v}</{name}>", "\t".repeat(indent)));
}

pub(super) fn write(m: &Material, opts: &Options, d: &mut Draft) -> Result<()> {
    let Some(h0) = &m.hyperelastic else {
        return Err(needs_hyperelastic(Target::Febio));
    };
    if let Some(r) = &m.relaxation {
        if r.terms.len() > MAX_TERMS {
            return Err(too_many_terms(Target::Febio, r.terms.len(), MAX_TERMS));
        }
    }
    let h = h0;
    let p = &h.params;
    let k = opts.bulk_ratio * mu0(h)?;
    let (ty, elastic_indent) = match &m.relaxation {
        Some(_) => ("uncoupled viscoelastic", 3),
        None => ("", 2),
    };
    let elastic_type = match h.spec.name.as_str() {
        "neo-hookean" | "mooney-rivlin" => "Mooney-Rivlin",
        "yeoh" => "uncoupled hyperelastic",
        "gent" => "Gent",
        _ => "Ogden",
    };
    let open = |ty: &str| format!("\t<material id=\"1\" name=\"{}\" type=\"{ty}\">", m.name);
    match &m.relaxation {
        Some(_) => d.line(open(ty)),
        None => d.line(open(elastic_type)),
    }
    if let Some(rho) = opts.density {
        param(d, 2, "density", rho, "kg/m^3");
    }
    if let Some(r) = &m.relaxation {
        param(d, 2, "g0", r.long_term_pa / r.reference_pa, "1");
        for (i, &(_, e)) in r.terms.iter().enumerate() {
            param(d, 2, &format!("g{}", i + 1), e / r.reference_pa, "1");
        }
        for (i, &(tau, _)) in r.terms.iter().enumerate() {
            param(d, 2, &format!("t{}", i + 1), tau, "s");
        }
        d.line(format!("\t\t<elastic type=\"{elastic_type}\">"));
        d.note(format!(
            "viscoelastic G(t) = g0 + sum g_i exp(-t/t_i) scales the elastic stress: g0 = E_inf/R, g_i = E_i/R with R = {} Pa, the elastic material the fit's hyperelastic constants as they are",
            num(r.reference_pa)
        ));
    }
    let ind = elastic_indent;
    match h.spec.name.as_str() {
        "neo-hookean" => {
            param(d, ind, "c1", p[0] / 2.0, "Pa");
            param(d, ind, "c2", 0.0, "Pa");
        }
        "mooney-rivlin" => {
            param(d, ind, "c1", p[0], "Pa");
            param(d, ind, "c2", p[1], "Pa");
        }
        "yeoh" => {
            for (n, v) in ["C10", "C20", "C30"].iter().zip(p) {
                d.constant(*n, *v, "Pa");
            }
            d.line(format!(
                "{}<W>({})*(I1-3)+({})*(I1-3)^2+({})*(I1-3)^3</W>",
                "\t".repeat(ind),
                plain(p[0]),
                plain(p[1]),
                plain(p[2])
            ));
            d.note("Yeoh as FEBio 4's 'uncoupled hyperelastic' with W = C10(I1-3) + C20(I1-3)^2 + C30(I1-3)^3 written out");
        }
        "gent" => {
            param(d, ind, "G", p[0], "Pa");
            param(d, ind, "Jm", p[1], "1");
        }
        _ => {
            for (i, (mu, a)) in ogden_terms(h, OgdenForm::Abaqus).into_iter().enumerate() {
                param(d, ind, &format!("c{}", i + 1), 2.0 * mu, "Pa");
                param(d, ind, &format!("m{}", i + 1), a, "1");
            }
            d.note("Ogden: FEBio's W = sum c_i/m_i^2 (...) is the abaqus form with c_i = 2 mu_i, m_i = alpha_i, exact");
        }
    }
    param(d, ind, "k", k, "Pa");
    if let Some(r) = &m.relaxation {
        d.line("\t\t</elastic>");
        // `uncoupled viscoelastic` takes no temperature shift
        super::trs(r, "FEBio (uncoupled viscoelastic)", |_| false, d);
    }
    d.line("\t</material>");
    d.warn(format!(
        "nearly incompressible: FEBio's uncoupled materials enforce incompressibility by a penalty, k = {} mu0 = {} Pa (the bulk-ratio option of the export); the card's stress differs from the incompressible fit's by O(stress/k)",
        opts.bulk_ratio,
        num(k)
    ));
    Ok(())
}
