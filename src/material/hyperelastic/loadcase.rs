//! Kinematics of the homogeneous test modes, in one place.
//!
//! Every mode is described by its three principal stretches (λ1, λ2, λ3) as functions
//! of the loading stretch λ = λ1, with λ1·λ2·λ3 = 1 (incompressible) and direction 3
//! traction-free. The hydrostatic pressure (seed Eq. 2.10) is eliminated with σ3 = 0,
//! which gives the nominal stress in the loading direction
//!
//! * invariant-based W(I1, I2): P = 2(λ1² − λ3²)/λ1 · (W1 + λ2²·W2)
//! * separable stretch-based W = Σ w(λi): P = (λ1·w'(λ1) − λ3·w'(λ3))/λ1
//!
//! | mode        | λ2      | λ3      |
//! |-------------|---------|---------|
//! | uniaxial    | λ^-1/2  | λ^-1/2  |
//! | equibiaxial | λ       | λ^-2    |
//! | planar      | 1       | λ^-1    |
//!
//! Uniaxial compression (λ < 1) is the same state as equibiaxial tension at λ^-1/2,
//! which is how a stack layer is loaded (see `docs/model.md`).

use serde::{Deserialize, Serialize};
use std::fmt;

/// A homogeneous deformation mode of a test coupon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Uniaxial tension (λ > 1) or compression (λ < 1), lateral faces free.
    Uniaxial,
    /// Equal biaxial tension, thickness free.
    Equibiaxial,
    /// Planar tension (pure shear): width held, thickness free.
    Planar,
}

impl Mode {
    /// All modes, in display order.
    pub const ALL: [Mode; 3] = [Mode::Uniaxial, Mode::Equibiaxial, Mode::Planar];

    /// The position of this mode in [`Mode::ALL`].
    #[inline]
    pub fn index(self) -> usize {
        match self {
            Mode::Uniaxial => 0,
            Mode::Equibiaxial => 1,
            Mode::Planar => 2,
        }
    }

    /// Parse a mode name as written in data files (`uniaxial`, `tension`,
    /// `compression`, `equibiaxial`, `biaxial`, `planar`, `pure_shear`, `shear`).
    pub fn parse(s: &str) -> Option<Mode> {
        match s
            .trim()
            .to_ascii_lowercase()
            .replace(['-', ' '], "_")
            .as_str()
        {
            "uniaxial" | "tension" | "compression" | "uniaxial_tension" | "ut" => {
                Some(Mode::Uniaxial)
            }
            "equibiaxial" | "biaxial" | "equi_biaxial" | "et" | "bt" => Some(Mode::Equibiaxial),
            "planar" | "pure_shear" | "shear" | "ps" => Some(Mode::Planar),
            _ => None,
        }
    }

    /// Principal stretches and their derivatives with respect to λ.
    #[inline]
    pub fn kinematics(self, lam: f64) -> Kinematics {
        match self {
            Mode::Uniaxial => {
                let s = 1.0 / lam.sqrt();
                let ds = -0.5 * s / lam;
                Kinematics {
                    l: [lam, s, s],
                    dl: [1.0, ds, ds],
                }
            }
            Mode::Equibiaxial => {
                let t = 1.0 / (lam * lam);
                Kinematics {
                    l: [lam, lam, t],
                    dl: [1.0, 1.0, -2.0 * t / lam],
                }
            }
            Mode::Planar => Kinematics {
                l: [lam, 1.0, 1.0 / lam],
                dl: [1.0, 0.0, -1.0 / (lam * lam)],
            },
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Mode::Uniaxial => "uniaxial",
            Mode::Equibiaxial => "equibiaxial",
            Mode::Planar => "planar",
        })
    }
}

/// Principal stretches `l` of a mode at one loading stretch and their derivatives
/// `dl` = dλi/dλ.
#[derive(Debug, Clone, Copy)]
pub struct Kinematics {
    /// λ1 (loading), λ2, λ3 (traction-free).
    pub l: [f64; 3],
    /// dλi/dλ.
    pub dl: [f64; 3],
}

/// First and second derivatives of an invariant-based strain energy W(I1, I2).
#[derive(Debug, Clone, Copy, Default)]
pub struct InvariantDerivs {
    /// ∂W/∂I1.
    pub w1: f64,
    /// ∂W/∂I2.
    pub w2: f64,
    /// ∂²W/∂I1².
    pub w11: f64,
    /// ∂²W/∂I1∂I2.
    pub w12: f64,
    /// ∂²W/∂I2².
    pub w22: f64,
}

impl InvariantDerivs {
    /// Every derivative NaN: what a model returns outside its domain (a parameter
    /// vector of the wrong length, Gent beyond its limit), so stress and tangent are
    /// NaN and the callers' finiteness checks see it.
    pub const NAN: InvariantDerivs = InvariantDerivs {
        w1: f64::NAN,
        w2: f64::NAN,
        w11: f64::NAN,
        w12: f64::NAN,
        w22: f64::NAN,
    };
}

impl Kinematics {
    /// (I1, I2) = (Σλi², Σλi⁻²) for an incompressible state.
    #[inline]
    pub fn invariants(&self) -> (f64, f64) {
        let [a, b, c] = self.l;
        (
            self.first_invariant(),
            1.0 / (a * a) + 1.0 / (b * b) + 1.0 / (c * c),
        )
    }

    /// I1 = Σλi².
    #[inline]
    pub fn first_invariant(&self) -> f64 {
        let [a, b, c] = self.l;
        a * a + b * b + c * c
    }

    /// (dI1/dλ, dI2/dλ).
    #[inline]
    pub fn invariant_rates(&self) -> (f64, f64) {
        let mut d1 = 0.0;
        let mut d2 = 0.0;
        for i in 0..3 {
            d1 += 2.0 * self.l[i] * self.dl[i];
            d2 -= 2.0 * self.dl[i] / (self.l[i] * self.l[i] * self.l[i]);
        }
        (d1, d2)
    }

    /// The geometric factor f = 2(λ1² − λ3²)/λ1 of the invariant formula.
    #[inline]
    pub fn invariant_factor(&self) -> f64 {
        let [a, _, c] = self.l;
        2.0 * (a * a - c * c) / a
    }

    /// Nominal stress P = f·(W1 + λ2²·W2).
    #[inline]
    pub fn invariant_stress(&self, w1: f64, w2: f64) -> f64 {
        self.invariant_factor() * (w1 + self.l[1] * self.l[1] * w2)
    }

    /// Tangent dP/dλ of the invariant formula (product rule on f·h).
    pub fn invariant_tangent(&self, d: &InvariantDerivs) -> f64 {
        let [a, b, c] = self.l;
        let [da, db, dc] = self.dl;
        let f = self.invariant_factor();
        let df = 2.0 * ((2.0 * a * da - 2.0 * c * dc) * a - (a * a - c * c) * da) / (a * a);
        let (di1, di2) = self.invariant_rates();
        let h = d.w1 + b * b * d.w2;
        let dw1 = d.w11 * di1 + d.w12 * di2;
        let dw2 = d.w12 * di1 + d.w22 * di2;
        let dh = dw1 + 2.0 * b * db * d.w2 + b * b * dw2;
        df * h + f * dh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mode_indexes_its_place_in_all() {
        for (i, m) in Mode::ALL.iter().enumerate() {
            assert_eq!(m.index(), i, "{m}");
        }
    }

    #[test]
    fn kinematics_are_incompressible_and_rates_match_differences() {
        for mode in Mode::ALL {
            for lam in [0.3, 0.9, 1.0, 1.7, 6.0] {
                let k = mode.kinematics(lam);
                assert!((k.l[0] * k.l[1] * k.l[2] - 1.0).abs() < 1e-14);
                let h = 1e-6 * lam;
                let kp = mode.kinematics(lam + h);
                let km = mode.kinematics(lam - h);
                for i in 0..3 {
                    let fd = (kp.l[i] - km.l[i]) / (2.0 * h);
                    assert!(
                        (fd - k.dl[i]).abs() < 1e-7 * (1.0 + fd.abs()),
                        "{mode} {lam} {i}"
                    );
                }
            }
        }
    }

    #[test]
    fn mode_names_parse() {
        assert_eq!(Mode::parse("Pure shear"), Some(Mode::Planar));
        assert_eq!(Mode::parse("tension"), Some(Mode::Uniaxial));
        assert_eq!(Mode::parse("biaxial"), Some(Mode::Equibiaxial));
        assert_eq!(Mode::parse("torsion"), None);
    }
}
