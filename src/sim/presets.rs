//! The material presets of El Atrache Ceballos (2021) used by scenes. The viscoelastic constants live in
//! one place, [`crate::material::viscoelastic::preset`]; this module only turns them
//! into the simulator's plain [`Viscous`] data and adds the hyperelastic spring.

use crate::material::file::{Arm, Viscous};
use crate::material::viscoelastic::{self, PRESET_NAMES};

/// Yeoh constants of VHB4910 (El Atrache Ceballos (2021) Table 3.2 = Table 4.2): C10, C20, C30 in Pa.
pub const VHB4910_YEOH_PA: [f64; 3] = [69.3e3, -888.0, 16.7];

/// Names accepted by `viscous = { preset = ... }`: the viscoelastic presets and
/// `elastic` (no dashpot, no arms).
pub fn viscous_preset_names() -> Vec<&'static str> {
    PRESET_NAMES.iter().copied().chain(["elastic"]).collect()
}

/// A named viscous preset, or `None` if the name is unknown. Table 3.3's normalised
/// gi become arms kj = gi·0.222 MPa with nj = kj·τj, Nv = 0; Table 4.2's arms and
/// Nv are taken as printed (see `material::viscoelastic::preset`, which also takes
/// the presets' former names).
pub fn viscous(name: &str) -> Option<Viscous> {
    let name = if name == "wissler-mazza-2007" {
        "elatrache2021-table-3.3"
    } else {
        name
    };
    if name == "elastic" {
        return Some(Viscous {
            nv_pa_s: 0.0,
            arms: Vec::new(),
        });
    }
    let km = viscoelastic::preset(name).ok()?.kelvin_maxwell;
    Some(Viscous {
        nv_pa_s: km.n_v,
        arms: km
            .arms
            .iter()
            .map(|a| Arm {
                k_pa: a.k,
                eta_pa_s: a.n,
            })
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_presets_give_the_dissertations_arms() {
        // Table 3.3: k1 = 0.478 × 0.222 MPa, n1 = k1 × 0.153 s.
        let v = viscous("elatrache2021-table-3.3").unwrap();
        assert_eq!(v.nv_pa_s, 0.0);
        assert!((v.arms[0].k_pa - 0.478 * 0.222e6).abs() < 1e-6);
        assert!((v.arms[0].eta_pa_s - 0.478 * 0.222e6 * 0.153).abs() < 1e-6);
        // Table 4.2 as printed.
        let v = viscous("elatrache2021-table-4.2").unwrap();
        assert_eq!(v.nv_pa_s, 1875.0);
        assert_eq!((v.arms[3].k_pa, v.arms[3].eta_pa_s), (0.010922e6, 47.91e6));
        // The former names give the same arms.
        assert_eq!(viscous("seed-table-4.2"), Some(v));
        assert_eq!(
            viscous("seed-table-3.3"),
            viscous("elatrache2021-table-3.3")
        );
        assert!(viscous("nonsense").is_none());
        assert!(viscous_preset_names().contains(&"elastic"));
    }
}
