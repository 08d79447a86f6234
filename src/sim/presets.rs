//! The seed's material presets needed by the shipped scenes, in ONE place.
//!
//! **Merge note:** the viscous sets below are plain data for the simulator. They will
//! be replaced by the `material::viscoelastic` presets (Prony series / Kelvin-Maxwell
//! arms, written on another branch) when the branches are merged; nothing else in
//! `sim` defines viscoelastic constants.

use super::scene::{Arm, Viscous};

/// Yeoh constants of VHB4910 (seed Table 3.2 = Table 4.2): C10, C20, C30 in Pa.
pub const VHB4910_YEOH_PA: [f64; 3] = [69.3e3, -888.0, 16.7];

/// Reference modulus (Pa) that turns the normalised Prony fractions gi of Table 3.3
/// into arm stiffnesses kj = gi·E_ref. 0.222 MPa is the value Table 4.2's kj imply
/// (k1/g1 = 0.106116/0.478), ≈ Y0 of Table 3.4; the seed's text ("kj = gj in MPa")
/// would give moduli larger than the material's own (see `docs/scenes.md`).
pub const TABLE_3_3_REFERENCE_MODULUS_PA: f64 = 0.222e6;

/// Table 3.3 (Wissler & Mazza 2007): (τi in s, gi dimensionless), Nv = 0.
pub const TABLE_3_3_PRONY: [(f64, f64); 4] = [
    (0.153, 0.478),
    (0.464, 0.205),
    (32.021, 0.0727),
    (215.85, 0.0492),
];

/// Table 4.2 (hand-tuned by the seed's author): (kj in Pa, nj in Pa·s).
pub const TABLE_4_2_ARMS: [(f64, f64); 4] = [
    (0.106116e6, 0.033966e6),
    (0.045510e6, 0.103008e6),
    (0.016139e6, 7.108662e6),
    (0.010922e6, 47.91e6),
];

/// Table 4.2 Kelvin-Voigt dashpot Nv = 1875e-6 MPa·s.
pub const TABLE_4_2_NV_PA_S: f64 = 1875.0;

/// Names accepted by `viscous = { preset = ... }`.
pub const VISCOUS_PRESETS: [&str; 3] = ["seed-table-3.3", "seed-table-4.2", "elastic"];

/// A named viscous preset, or `None` if the name is unknown.
pub fn viscous(name: &str) -> Option<Viscous> {
    match name {
        "seed-table-3.3" | "wissler-mazza-2007" => Some(Viscous {
            nv_pa_s: 0.0,
            arms: TABLE_3_3_PRONY
                .iter()
                .map(|&(tau, g)| {
                    let k = g * TABLE_3_3_REFERENCE_MODULUS_PA;
                    Arm {
                        k_pa: k,
                        eta_pa_s: k * tau,
                    }
                })
                .collect(),
        }),
        "seed-table-4.2" => Some(Viscous {
            nv_pa_s: TABLE_4_2_NV_PA_S,
            arms: TABLE_4_2_ARMS
                .iter()
                .map(|&(k, n)| Arm {
                    k_pa: k,
                    eta_pa_s: n,
                })
                .collect(),
        }),
        "elastic" => Some(Viscous {
            nv_pa_s: 0.0,
            arms: Vec::new(),
        }),
        _ => None,
    }
}
