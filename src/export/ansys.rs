//! ANSYS Mechanical APDL commands (Material Reference: TB,HYPER and TB,PRONY).
//!
//! * `TB,HYPER,,,,NEO`: W = μ/2(Ī1 − 3) + (J − 1)²/d; constants μ, d.
//! * `MOONEY` (NPTS = 2): C10, C01, d; `YEOH` (NPTS = 3): C10, C20, C30, d1..d3.
//! * `OGDEN` (NPTS = N): W = Σ μᵢ/αᵢ(λ̄₁^αᵢ + λ̄₂^αᵢ + λ̄₃^αᵢ − 3), the original
//!   form (μ0 = ½Σμᵢαᵢ): a abaqus-form fit converted, μ = 2μ_abaqus/α.
//! * `GENT`: W = −μJm/2·ln(1 − (Ī1 − 3)/Jm); μ, Jm, d.
//! * dᵢ = 0: incompressible (mixed u-P elements).
//! * `TB,PRONY,,,N,SHEAR`: relative moduli aᵢ = Gᵢ/G0 and τᵢ, G0 the
//!   instantaneous modulus; the hyperelastic constants are the instantaneous
//!   response, the fit's scaled by E0/R.
//! * `TB,SHIFT` after it for a DMA fit's shift law ([`shift`]).

use super::{
    alone_warning, mu0, num, ogden_n, ogden_terms, scaled, Draft, Material, Options, Relaxation,
    Trs,
};
use crate::dma::law::{LawKind, GAS_CONSTANT};
use crate::error::Result;
use crate::material::hyperelastic::OgdenForm;

/// Constants per TBDATA command.
const PER_COMMAND: usize = 6;

/// `TBDATA` commands for `values`, six per command from location 1.
fn tbdata(d: &mut Draft, values: &[(String, f64, &'static str)]) {
    let written: Vec<String> = values
        .iter()
        .map(|(n, v, u)| d.field(n.clone(), *v, u))
        .collect();
    for (i, chunk) in written.chunks(PER_COMMAND).enumerate() {
        d.line(format!(
            "TBDATA,{},{}",
            1 + i * PER_COMMAND,
            chunk.join(",")
        ));
    }
}

pub(super) fn write(m: &Material, opts: &Options, d: &mut Draft) -> Result<()> {
    d.line("MAT,1");
    if let Some(rho) = opts.density {
        let rho = d.field("DENS", rho, "kg/m^3");
        d.line(format!("MP,DENS,1,{rho}"));
    }
    let scale = m
        .relaxation
        .as_ref()
        .map_or(1.0, |r| r.instantaneous_pa() / r.reference_pa);
    if let Some(h0) = &m.hyperelastic {
        let h = scaled(h0, scale)?;
        let p = &h.params;
        let s = |n: &str, v: f64, u: &'static str| (n.to_string(), v, u);
        let (head, values) = match h.spec.name.as_str() {
            "neo-hookean" => (
                "TB,HYPER,1,,,NEO".to_string(),
                vec![s("mu", p[0], "Pa"), s("d", 0.0, "1/Pa")],
            ),
            "mooney-rivlin" => (
                "TB,HYPER,1,,2,MOONEY".into(),
                vec![
                    s("C10", p[0], "Pa"),
                    s("C01", p[1], "Pa"),
                    s("d", 0.0, "1/Pa"),
                ],
            ),
            "yeoh" => (
                "TB,HYPER,1,,3,YEOH".into(),
                vec![
                    s("C10", p[0], "Pa"),
                    s("C20", p[1], "Pa"),
                    s("C30", p[2], "Pa"),
                    s("d1", 0.0, "1/Pa"),
                    s("d2", 0.0, "1/Pa"),
                    s("d3", 0.0, "1/Pa"),
                ],
            ),
            "gent" => (
                "TB,HYPER,1,,,GENT".into(),
                vec![s("mu", p[0], "Pa"), s("Jm", p[1], "1"), s("d", 0.0, "1/Pa")],
            ),
            name => {
                let n = ogden_n(name).expect("a known model");
                let mut v = Vec::new();
                for (i, (mu, a)) in ogden_terms(&h, OgdenForm::Original).into_iter().enumerate() {
                    v.push((format!("mu{}", i + 1), mu, "Pa"));
                    v.push((format!("alpha{}", i + 1), a, "1"));
                }
                v.extend((1..=n).map(|i| (format!("d{i}"), 0.0, "1/Pa")));
                if h0.spec.form != Some(OgdenForm::Original) {
                    d.note("Ogden: the fit's abaqus-form mu_i (2mu/alpha^2) converted to ANSYS's original form (mu/alpha): mu_i = 2*mu_abaqus/alpha_i, exact");
                }
                (format!("TB,HYPER,1,,{n},OGDEN"), v)
            }
        };
        d.line(head);
        tbdata(d, &values);
        d.note(format!(
            "d = 0: incompressible (mixed u-P element formulation); small-strain shear modulus mu0 = {} Pa",
            num(mu0(&h)?)
        ));
        if scale != 1.0 {
            d.note(format!(
                "hyperelastic constants = the fit's x E0/R = {}: the instantaneous response, as ANSYS takes it with a Prony series",
                num(scale)
            ));
        }
    }
    if let Some(r) = &m.relaxation {
        if m.hyperelastic.is_none() {
            d.warn(alone_warning(r, false));
        }
        let e0 = r.instantaneous_pa();
        d.line(format!("TB,PRONY,1,,{},SHEAR", r.terms.len()));
        let mut v = Vec::new();
        for (i, &(tau, e)) in r.terms.iter().enumerate() {
            v.push((format!("a{}", i + 1), e / e0, "1"));
            v.push((format!("tau{}", i + 1), tau, "s"));
        }
        tbdata(d, &v);
        d.note(format!(
            "Prony shear a_i = G_i/G0 = E_i/E0 relative to the instantaneous modulus E0 = {} Pa (a_inf = {}); no TB,PRONY,,,,BULK: the volumetric response of an incompressible solid does not relax",
            num(e0),
            num(r.long_term_pa / e0)
        ));
        shift(r, d);
    }
    Ok(())
}

/// The time–temperature shift of a DMA fit (Mechanical APDL Material Reference,
/// Viscoelasticity: Shift Function, `TB,SHIFT`), whose shift A multiplies the time
/// (reduced time dξ/dt = A(T), so A = 1/aT):
/// * `TB,SHIFT,1,,3,WLF`: constants Tr, C1, C2 with
///   log10 A = C1(T − Tr)/(C2 + T − Tr): the fit's C1, C2 as they are;
/// * `TB,SHIFT,1,,2,TN` (Tool–Narayanaswamy without fictive temperature, the
///   Arrhenius form): constants Tr, H/R with A = exp(H/R·(1/Tr − 1/T)): H = Ea;
/// * free shifts: no TB,SHIFT (USER needs a user subroutine), a comment.
///
/// Temperatures in K.
fn shift(r: &Relaxation, d: &mut Draft) {
    match super::trs(r, "ANSYS", |_| true, d) {
        Some(Trs::Law(law)) => {
            d.warn(
                "the TB,SHIFT fields (WLF: Tr, C1, C2 with log10 A = C1(T - Tr)/(C2 + T - Tr) and A = 1/aT multiplying the time; TN: Tr, H/R) follow the Mechanical APDL Material Reference's Shift Function section, which could not be read to check them: compare TBLIST and a one-element relaxation at a second temperature with the fit's shift_factors before relying on the shift",
            );
            d.line("! time-temperature shift of the DMA fit; temperatures in K");
            let v = match law.kind {
                LawKind::Wlf => {
                    d.line("TB,SHIFT,1,,3,WLF");
                    vec![
                        ("Tr".to_string(), law.reference_temperature_k, "K"),
                        ("C1".into(), law.c1.unwrap_or(f64::NAN), "1"),
                        ("C2".into(), law.c2.unwrap_or(f64::NAN), "K"),
                    ]
                }
                LawKind::Arrhenius => {
                    d.line("TB,SHIFT,1,,2,TN");
                    vec![
                        ("Tr".to_string(), law.reference_temperature_k, "K"),
                        (
                            "H/R".into(),
                            law.activation_energy.unwrap_or(f64::NAN) / GAS_CONSTANT,
                            "K",
                        ),
                    ]
                }
            };
            tbdata(d, &v);
        }
        Some(Trs::Free) => d.line(
            "! no TB,SHIFT: the DMA fit's shifts are free, tabulated in its shift_factors (USER would need a user subroutine): the card is the material at Tr",
        ),
        None => {}
    }
}
