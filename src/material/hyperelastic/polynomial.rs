//! The polynomial family W = Σ s_k·p_k·(I1 − 3)^i_k·(I2 − 3)^j_k, linear in its
//! parameters p_k.
//!
//! * Neo-Hookean: W = μ/2·(I1 − 3) (s = ½), μ0 = μ.
//! * Mooney-Rivlin (seed Eq. 2.7): W = C10(I1 − 3) + C01(I2 − 3), μ0 = 2(C10 + C01).
//! * Yeoh (seed Eq. 2.8): W = Σ_{i=1..3} Ci0(I1 − 3)^i, μ0 = 2·C10.

use super::loadcase::{InvariantDerivs, Mode};
use super::powers::{Laurent, LaurentKinematics, PowerSum, TangentPowers};
use super::{ParamInfo, StrainEnergy};
use std::sync::OnceLock;

/// One term s·p·x^i·y^j with x = I1 − 3, y = I2 − 3.
#[derive(Debug, Clone, Copy)]
struct Term {
    i: i32,
    j: i32,
    scale: f64,
}

/// A polynomial strain energy (Neo-Hookean, Mooney-Rivlin, Yeoh).
#[derive(Debug, Clone)]
pub struct Polynomial {
    name: &'static str,
    terms: Vec<Term>,
    params: Vec<ParamInfo>,
}

/// The largest exponent of x = I1 − 3 or y = I2 − 3 in a term of these models
/// (Yeoh's (I1 − 3)³).
const MAX_POWER: i32 = 3;

/// x^n for n = −2…[`MAX_POWER`], with x^0 = 1 and x^(negative) = 0 (those terms
/// carry a zero coefficient): a table built once per evaluation, so the terms'
/// powers are lookups (x³ = (x·x)·x as the generic product gives it).
struct Powers([f64; 6]);

impl Powers {
    #[inline]
    fn of(x: f64) -> Self {
        Powers([0.0, 0.0, 1.0, x, x * x, x * x * x])
    }
    #[inline]
    fn get(&self, n: i32) -> f64 {
        self.0[(n + 2) as usize]
    }
}

impl Polynomial {
    fn make(name: &'static str, terms: &[(&str, i32, i32, f64)]) -> Self {
        assert!(
            terms
                .iter()
                .all(|&(_, i, j, _)| (0..=MAX_POWER).contains(&i) && (0..=MAX_POWER).contains(&j)),
            "{name}: exponents within 0…{MAX_POWER} (Powers)"
        );
        Polynomial {
            name,
            terms: terms
                .iter()
                .map(|&(_, i, j, scale)| Term { i, j, scale })
                .collect(),
            params: terms.iter().map(|&(n, ..)| ParamInfo::modulus(n)).collect(),
        }
    }
    /// Neo-Hookean, parameter `mu`.
    pub fn neo_hookean() -> Self {
        Self::make("neo-hookean", &[("mu", 1, 0, 0.5)])
    }
    /// Two-term Mooney-Rivlin, parameters `C10`, `C01`.
    pub fn mooney_rivlin() -> Self {
        Self::make("mooney-rivlin", &[("C10", 1, 0, 1.0), ("C01", 0, 1, 1.0)])
    }
    /// Three-term Yeoh, parameters `C10`, `C20`, `C30`.
    pub fn yeoh() -> Self {
        Self::make(
            "yeoh",
            &[("C10", 1, 0, 1.0), ("C20", 2, 0, 1.0), ("C30", 3, 0, 1.0)],
        )
    }

    /// Energy derivatives at (I1, I2), the second ones only if `SECOND` (the stress
    /// needs W1 and W2 alone: the simulator's right-hand side skips three sums); NaN
    /// for a parameter vector of the wrong length.
    #[inline]
    fn derivs<const SECOND: bool>(&self, p: &[f64], i1: f64, i2: f64) -> InvariantDerivs {
        if p.len() != self.terms.len() {
            return InvariantDerivs::NAN;
        }
        let (x, y) = (Powers::of(i1 - 3.0), Powers::of(i2 - 3.0));
        let mut d = InvariantDerivs::default();
        for (t, &c) in self.terms.iter().zip(p) {
            let (i, j, c) = (t.i, t.j, c * t.scale);
            let (fi, fj) = (f64::from(i), f64::from(j));
            d.w1 += c * fi * x.get(i - 1) * y.get(j);
            d.w2 += c * fj * x.get(i) * y.get(j - 1);
            if !SECOND {
                continue;
            }
            d.w11 += c * fi * (fi - 1.0) * x.get(i - 2) * y.get(j);
            d.w12 += c * fi * fj * x.get(i - 1) * y.get(j - 1);
            d.w22 += c * fj * (fj - 1.0) * x.get(i) * y.get(j - 2);
        }
        d
    }
}

/// The tangent of each parameter's term alone in each mode (order of [`Mode::ALL`]).
type TangentBases = [Vec<Laurent>; 3];

impl Polynomial {
    /// T = Σ p_k·B_k: the bases B_k of this model, computed once for every model of
    /// the family (None if a power falls outside what [`Laurent`] holds).
    fn tangent_bases(&self) -> Option<&'static TangentBases> {
        static ALL: OnceLock<Vec<(&'static str, Option<TangentBases>)>> = OnceLock::new();
        ALL.get_or_init(|| {
            [Self::neo_hookean(), Self::mooney_rivlin(), Self::yeoh()]
                .iter()
                .map(|m| (m.name, m.build_tangent_bases()))
                .collect()
        })
        .iter()
        .find(|(name, _)| *name == self.name)?
        .1
        .as_ref()
    }

    /// P = f·(W1 + λ2²·W2) with W1 = Σ c·i·x^(i−1)·y^j, W2 = Σ c·j·x^i·y^(j−1) is a
    /// Laurent polynomial in λ, and T = dP/dλ; one basis per term (c = 1).
    fn build_tangent_bases(&self) -> Option<TangentBases> {
        let one_mode = |mode: Mode| -> Option<Vec<Laurent>> {
            let k = LaurentKinematics::of(mode);
            self.terms
                .iter()
                .map(|t| {
                    let (mut w1, mut w2) = (Laurent::ZERO, Laurent::ZERO);
                    if t.i > 0 {
                        let b = k.x.pow(t.i - 1)?.mul(&k.y.pow(t.j)?)?;
                        w1.add_assign_scaled(t.scale * f64::from(t.i), &b);
                    }
                    if t.j > 0 {
                        let b = k.x.pow(t.i)?.mul(&k.y.pow(t.j - 1)?)?;
                        w2.add_assign_scaled(t.scale * f64::from(t.j), &b);
                    }
                    k.f.mul(&w1.add_scaled(1.0, &k.l2sq.mul(&w2)?))?
                        .derivative()
                })
                .collect()
        };
        Some([
            one_mode(Mode::ALL[0])?,
            one_mode(Mode::ALL[1])?,
            one_mode(Mode::ALL[2])?,
        ])
    }
}

impl StrainEnergy for Polynomial {
    fn name(&self) -> String {
        self.name.to_string()
    }
    fn params(&self) -> &[ParamInfo] {
        &self.params
    }
    fn nominal_stress(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        let k = mode.kinematics(lam);
        let (i1, i2) = k.invariants();
        let d = self.derivs::<false>(p, i1, i2);
        k.invariant_stress(d.w1, d.w2)
    }
    fn tangent(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        let k = mode.kinematics(lam);
        let (i1, i2) = k.invariants();
        k.invariant_tangent(&self.derivs::<true>(p, i1, i2))
    }
    fn tangent_powers(&self, p: &[f64], mode: Mode) -> Option<TangentPowers> {
        if p.len() != self.terms.len() {
            return None;
        }
        let basis = &self.tangent_bases()?[Mode::ALL.iter().position(|&m| m == mode)?];
        let mut sum = Laurent::ZERO;
        for (b, &c) in basis.iter().zip(p) {
            sum.add_assign_scaled(c, b);
        }
        Some(TangentPowers {
            sum: PowerSum::Integer(sum),
            bounded: false,
        })
    }
    fn stress_jacobian(&self, p: &[f64], mode: Mode, lam: f64, out: &mut [f64]) {
        if p.len() != self.terms.len() || out.len() != self.terms.len() {
            out.fill(f64::NAN);
            return;
        }
        let k = mode.kinematics(lam);
        let (i1, i2) = k.invariants();
        let (x, y) = (Powers::of(i1 - 3.0), Powers::of(i2 - 3.0));
        for (t, o) in self.terms.iter().zip(out.iter_mut()) {
            let (fi, fj) = (f64::from(t.i), f64::from(t.j));
            let w1 = t.scale * fi * x.get(t.i - 1) * y.get(t.j);
            let w2 = t.scale * fj * x.get(t.i) * y.get(t.j - 1);
            *o = k.invariant_stress(w1, w2);
        }
    }
    fn initial_shear_modulus(&self, p: &[f64]) -> f64 {
        // μ0 = 2(W1 + W2) at I1 = I2 = 3.
        let d = self.derivs::<false>(p, 3.0, 3.0);
        2.0 * (d.w1 + d.w2)
    }
}
