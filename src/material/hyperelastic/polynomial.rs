//! The polynomial family W = Σ s_k·p_k·(I1 − 3)^i_k·(I2 − 3)^j_k, linear in its
//! parameters p_k.
//!
//! * Neo-Hookean: W = μ/2·(I1 − 3) (s = ½), μ0 = μ.
//! * Mooney-Rivlin (seed Eq. 2.7): W = C10(I1 − 3) + C01(I2 − 3), μ0 = 2(C10 + C01).
//! * Yeoh (seed Eq. 2.8): W = Σ_{i=1..3} Ci0(I1 − 3)^i, μ0 = 2·C10.

use super::loadcase::{InvariantDerivs, Kinematics, Mode};
use super::powers::{Laurent, LaurentKinematics, PowerSum, TangentPowers};
use super::{ParamInfo, Points, StrainEnergy};
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
    /// Each slot's (i, j), (0, 0) after the terms: what [`Prepared`] carries, fixed
    /// by the model (not by its parameters), so found once here.
    exponents: [(i32, i32); MAX_TERMS],
    /// Which of [`FAMILY`] the exponents are, if any.
    model: Option<usize>,
    /// Whether any term has a power of y = I2 − 3.
    uses_i2: bool,
}

/// The largest exponent of x = I1 − 3 or y = I2 − 3 in a term of these models
/// (Yeoh's (I1 − 3)³).
const MAX_POWER: i32 = 3;

/// x^n for n = −2…[`MAX_POWER`], with x^0 = 1 and x^(negative) = 0 (those terms
/// carry a zero coefficient): a table built once per evaluation, so the terms'
/// powers are lookups (x³ = (x·x)·x as the generic product gives it). Eight
/// entries, the index masked to them: a lookup without a bounds check.
struct Powers([f64; 8]);

impl Powers {
    #[inline(always)]
    fn of(x: f64) -> Self {
        Powers([0.0, 0.0, 1.0, x, x * x, x * x * x, 0.0, 0.0])
    }
    #[inline(always)]
    fn get(&self, n: i32) -> f64 {
        self.0[(n + 2) as usize & 7]
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
        assert!(
            terms.len() <= MAX_TERMS,
            "{name}: at most {MAX_TERMS} terms"
        );
        let mut exponents = [(0, 0); MAX_TERMS];
        for (e, &(_, i, j, _)) in exponents.iter_mut().zip(terms) {
            *e = (i, j);
        }
        Polynomial {
            name,
            terms: terms
                .iter()
                .map(|&(_, i, j, scale)| Term { i, j, scale })
                .collect(),
            params: terms.iter().map(|&(n, ..)| ParamInfo::modulus(n)).collect(),
            exponents,
            model: FAMILY.iter().position(|e| *e == exponents),
            uses_i2: terms.iter().any(|&(_, _, j, _)| j > 0),
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

    /// Energy derivatives at (I1, I2), the second ones only if `SECOND`; NaN for a
    /// parameter vector of the wrong length.
    #[inline]
    fn derivs<const SECOND: bool>(&self, p: &[f64], i1: f64, i2: f64) -> InvariantDerivs {
        // the derivatives do not depend on the mode
        match self.prepare(p, Mode::Uniaxial) {
            Some(s) => s.derivs::<SECOND>(i1, i2),
            None => InvariantDerivs::NAN,
        }
    }

    /// The model at parameters `p` in `mode`, prepared for many stretches; None for
    /// a parameter vector of the wrong length.
    #[inline]
    pub fn prepare(&self, p: &[f64], mode: Mode) -> Option<Prepared> {
        if p.len() != self.terms.len() {
            return None;
        }
        let mut terms = [Coefficients::default(); MAX_TERMS];
        for ((t, &c), o) in self.terms.iter().zip(p).zip(&mut terms) {
            let (i, j, c) = (t.i, t.j, c * t.scale);
            let (fi, fj) = (f64::from(i), f64::from(j));
            *o = Coefficients {
                w1: c * fi,
                w2: c * fj,
                w11: c * fi * (fi - 1.0),
                w12: c * fi * fj,
                w22: c * fj * (fj - 1.0),
            };
        }
        Some(Prepared {
            mode,
            terms,
            exponents: self.exponents,
            model: self.model,
            uses_i2: self.uses_i2,
        })
    }
}

/// The most terms a model of the family has (Yeoh's three).
const MAX_TERMS: usize = 3;

/// One term's factors of W1 = Σ c·i·x^(i−1)·y^j, W2 = Σ c·j·x^i·y^(j−1) and the
/// second derivatives (c = s·p the term's coefficient).
#[derive(Debug, Clone, Copy, Default)]
struct Coefficients {
    /// c·i.
    w1: f64,
    /// c·j.
    w2: f64,
    /// c·i·(i − 1).
    w11: f64,
    /// c·i·j.
    w12: f64,
    /// c·j·(j − 1).
    w22: f64,
}

/// A polynomial model at fixed parameters in one mode, prepared once for many
/// stretches (the simulator's right-hand side): each term's factors, and whether
/// any term has a power of y = I2 − 3 (without one, y enters only as y⁰ = 1 and
/// y⁻¹ = y⁻² = 0, so I2 is not computed). The one evaluation of the family's
/// stress and tangent.
#[derive(Debug, Clone, Copy)]
pub struct Prepared {
    mode: Mode,
    /// The terms, then zero slots (no factor) up to [`MAX_TERMS`].
    terms: [Coefficients; MAX_TERMS],
    /// Each slot's (i, j), (0, 0) for a zero slot.
    exponents: [(i32, i32); MAX_TERMS],
    /// Which of [`FAMILY`] the exponents are, if any.
    model: Option<usize>,
    uses_i2: bool,
}

/// The exponents of the family's models, slot by slot (zero slots (0, 0)).
const FAMILY: [[(i32, i32); MAX_TERMS]; 3] = [
    [(1, 0), (2, 0), (3, 0)], // Yeoh
    [(1, 0), (0, 0), (0, 0)], // neo-Hookean
    [(1, 0), (0, 1), (0, 0)], // Mooney-Rivlin
];

impl Prepared {
    /// Energy derivatives at (I1, I2), the second ones only if `SECOND` (the stress
    /// needs W1 and W2 alone: the simulator's right-hand side skips three sums).
    /// A model of the family runs with its exponents as constants, so every power
    /// is resolved when the code is built (the same arithmetic, no table lookups).
    #[inline(always)]
    fn derivs<const SECOND: bool>(&self, i1: f64, i2: f64) -> InvariantDerivs {
        match self.model {
            Some(0) => self.sums::<SECOND>(FAMILY[0], i1, i2),
            Some(1) => self.sums::<SECOND>(FAMILY[1], i1, i2),
            Some(2) => self.sums::<SECOND>(FAMILY[2], i1, i2),
            _ => self.sums::<SECOND>(self.exponents, i1, i2),
        }
    }

    /// The sums of [`Prepared::derivs`] with the slots' exponents `e`.
    #[inline(always)]
    fn sums<const SECOND: bool>(
        &self,
        e: [(i32, i32); MAX_TERMS],
        i1: f64,
        i2: f64,
    ) -> InvariantDerivs {
        let (x, y) = (Powers::of(i1 - 3.0), Powers::of(i2 - 3.0));
        let mut d = InvariantDerivs::default();
        // every slot, the unused ones too: their zero factors meet only the table's
        // constant 0 and 1, and each sum, started at +0, is never −0, so adding
        // their +0 changes nothing (a fixed count the compiler unrolls)
        for (t, (i, j)) in self.terms.iter().zip(e) {
            d.w1 += t.w1 * x.get(i - 1) * y.get(j);
            d.w2 += t.w2 * x.get(i) * y.get(j - 1);
            if !SECOND {
                continue;
            }
            d.w11 += t.w11 * x.get(i - 2) * y.get(j);
            d.w12 += t.w12 * x.get(i - 1) * y.get(j - 1);
            d.w22 += t.w22 * x.get(i) * y.get(j - 2);
        }
        d
    }

    /// (I1, I2) of a state, I2 as 3 (y = 0) where no term reads it.
    #[inline(always)]
    fn invariants(&self, k: &Kinematics) -> (f64, f64) {
        match self.uses_i2 {
            true => k.invariants(),
            false => (k.first_invariant(), 3.0),
        }
    }

    /// Each term's nominal stress at λ (Pa), in parameter order: the terms of
    /// [`Prepared::stress`] before they are summed (at unit parameters, the
    /// Jacobian ∂P/∂p).
    #[inline(always)]
    fn term_stresses(&self, lam: f64, out: &mut [f64]) {
        match self.model {
            Some(0) => self.terms_with(FAMILY[0], lam, out),
            Some(1) => self.terms_with(FAMILY[1], lam, out),
            Some(2) => self.terms_with(FAMILY[2], lam, out),
            _ => self.terms_with(self.exponents, lam, out),
        }
    }

    /// [`Prepared::term_stresses`] with the slots' exponents `e`.
    #[inline(always)]
    fn terms_with(&self, e: [(i32, i32); MAX_TERMS], lam: f64, out: &mut [f64]) {
        let k = self.mode.kinematics(lam);
        let (i1, i2) = self.invariants(&k);
        let (x, y) = (Powers::of(i1 - 3.0), Powers::of(i2 - 3.0));
        for ((t, (i, j)), o) in self.terms.iter().zip(e).zip(out) {
            let w1 = t.w1 * x.get(i - 1) * y.get(j);
            let w2 = t.w2 * x.get(i) * y.get(j - 1);
            *o = k.invariant_stress(w1, w2);
        }
    }

    /// Nominal stress P(λ) (Pa).
    #[inline(always)]
    pub fn stress(&self, lam: f64) -> f64 {
        let k = self.mode.kinematics(lam);
        let (i1, i2) = self.invariants(&k);
        let d = self.derivs::<false>(i1, i2);
        k.invariant_stress(d.w1, d.w2)
    }

    /// Tangent dP/dλ (Pa).
    #[inline(always)]
    pub fn tangent(&self, lam: f64) -> f64 {
        let k = self.mode.kinematics(lam);
        let (i1, i2) = self.invariants(&k);
        k.invariant_tangent(&self.derivs::<true>(i1, i2))
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
        self.prepare(p, mode).map_or(f64::NAN, |s| s.stress(lam))
    }
    fn tangent(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        self.prepare(p, mode).map_or(f64::NAN, |s| s.tangent(lam))
    }
    fn prepared(&self, p: &[f64], mode: Mode) -> Option<Prepared> {
        self.prepare(p, mode)
    }
    fn reads_ln_stretch(&self) -> bool {
        false
    }
    fn tangent_powers(&self, p: &[f64], mode: Mode) -> Option<TangentPowers> {
        if p.len() != self.terms.len() {
            return None;
        }
        let basis = self.tangent_basis(mode)?;
        let mut sum = Laurent::ZERO;
        for (b, &c) in basis.iter().zip(p) {
            sum.add_assign_scaled(c, b);
        }
        Some(TangentPowers {
            sum: PowerSum::Integer(sum),
            bounded: false,
        })
    }
    fn tangent_basis(&self, mode: Mode) -> Option<&'static [Laurent]> {
        Some(&self.tangent_bases()?[mode.index()])
    }
    fn stress_jacobian(&self, p: &[f64], mode: Mode, lam: f64, out: &mut [f64]) {
        // ∂P/∂p_k is term k's stress at p_k = 1 (the model is linear in p).
        let n = self.terms.len();
        match self.prepare(&[1.0; MAX_TERMS][..n], mode) {
            Some(unit) if p.len() == n && out.len() == n => unit.term_stresses(lam, out),
            _ => out.fill(f64::NAN),
        }
    }
    fn stress_jacobians(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        // Each point's row as `stress_jacobian` gives it, the terms at unit parameters
        // prepared once per mode instead of at every point.
        let n = self.terms.len();
        let unit = Mode::ALL.map(|m| self.prepare(&[1.0; MAX_TERMS][..n], m));
        for (i, row) in out
            .chunks_exact_mut(p.len().max(1))
            .enumerate()
            .take(pts.len())
        {
            match &unit[pts.mode(i).index()] {
                Some(u) if p.len() == n && row.len() == n => u.term_stresses(pts.stretch(i), row),
                _ => row.fill(f64::NAN),
            }
        }
    }
    fn initial_shear_modulus(&self, p: &[f64]) -> f64 {
        // μ0 = 2(W1 + W2) at I1 = I2 = 3.
        let d = self.derivs::<false>(p, 3.0, 3.0);
        2.0 * (d.w1 + d.w2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The prepared evaluation's shortcuts change no bit: I2 left out where no
    /// term reads it (the same stress, tangent and Jacobian as with I2 computed),
    /// the zero slots after a model's terms (the same as the terms alone, by the
    /// generic loop of the family, `reference` and `reference_jacobian`), and the
    /// exponents as constants (the same as read at run time). Every model of the
    /// family, every
    /// mode, stretches from deep compression to tension, with mixed-sign
    /// coefficients so that sums cancel.
    /// The block Jacobian (the terms prepared once per mode) is the per-point one
    /// bit for bit: every model of the family, the three modes interleaved,
    /// compression to tension; a parameter vector of the wrong length gives NaN
    /// rows, as the per-point method does.
    #[test]
    fn block_jacobian_is_the_per_point_one() {
        let modes: Vec<Mode> = (0..15).map(|i| Mode::ALL[(i * 7) % 3]).collect();
        let stretch: Vec<f64> = (0..15).map(|i| 0.3 + 0.37 * i as f64).collect();
        let logs = vec![f64::NAN; 15];
        let pts = Points::new(&modes, &stretch, &logs).unwrap();
        for m in [
            Polynomial::neo_hookean(),
            Polynomial::mooney_rivlin(),
            Polynomial::yeoh(),
        ] {
            let k = m.terms.len();
            for p in [vec![1e5, -2e3, 30.0][..k].to_vec(), vec![1.0; k + 1]] {
                let w = p.len();
                let mut block = vec![0.0; 15 * w];
                m.stress_jacobians(&p, pts, &mut block);
                for (i, row) in block.chunks_exact(w).enumerate() {
                    let mut one = vec![0.0; w];
                    m.stress_jacobian(&p, modes[i], stretch[i], &mut one);
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(row), bits(&one), "{} {p:?} point {i}", m.name);
                }
            }
        }
    }

    #[test]
    fn prepared_shortcuts_change_no_bit() {
        /// W1, W2 (and the second derivatives) over the model's own terms only,
        /// with I2 always computed: the family's sums as written.
        fn reference(m: &Polynomial, p: &[f64], mode: Mode, lam: f64) -> (f64, f64) {
            let k = mode.kinematics(lam);
            let (i1, i2) = k.invariants();
            let (x, y) = (Powers::of(i1 - 3.0), Powers::of(i2 - 3.0));
            let mut d = InvariantDerivs::default();
            for (t, &c) in m.terms.iter().zip(p) {
                let (i, j, c) = (t.i, t.j, c * t.scale);
                let (fi, fj) = (f64::from(i), f64::from(j));
                d.w1 += c * fi * x.get(i - 1) * y.get(j);
                d.w2 += c * fj * x.get(i) * y.get(j - 1);
                d.w11 += c * fi * (fi - 1.0) * x.get(i - 2) * y.get(j);
                d.w12 += c * fi * fj * x.get(i - 1) * y.get(j - 1);
                d.w22 += c * fj * (fj - 1.0) * x.get(i) * y.get(j - 2);
            }
            (k.invariant_stress(d.w1, d.w2), k.invariant_tangent(&d))
        }
        /// ∂P/∂p_k as each term's stress at unit coefficient, I2 always computed.
        fn reference_jacobian(m: &Polynomial, mode: Mode, lam: f64) -> Vec<f64> {
            let k = mode.kinematics(lam);
            let (i1, i2) = k.invariants();
            let (x, y) = (Powers::of(i1 - 3.0), Powers::of(i2 - 3.0));
            m.terms
                .iter()
                .map(|t| {
                    let (fi, fj) = (f64::from(t.i), f64::from(t.j));
                    let w1 = t.scale * fi * x.get(t.i - 1) * y.get(t.j);
                    let w2 = t.scale * fj * x.get(t.i) * y.get(t.j - 1);
                    k.invariant_stress(w1, w2)
                })
                .collect()
        }
        let mut checked = 0;
        for m in [
            Polynomial::neo_hookean(),
            Polynomial::mooney_rivlin(),
            Polynomial::yeoh(),
        ] {
            let p: Vec<f64> = [1.3e5, -2.1e3, 47.0][..m.terms.len()].to_vec();
            for mode in Mode::ALL {
                let s = m.prepare(&p, mode).expect("right length");
                assert_eq!(s.uses_i2, m.name == "mooney-rivlin", "{}", m.name);
                assert!(s.model.is_some(), "{}: constant exponents", m.name);
                // the same slots with their exponents read at run time
                let generic = Prepared { model: None, ..s };
                for i in 0..200 {
                    let lam = 0.2 + 0.02 * i as f64;
                    let (stress, tangent) = reference(&m, &p, mode, lam);
                    assert_eq!(
                        s.stress(lam).to_bits(),
                        stress.to_bits(),
                        "{} {mode} {lam}",
                        m.name
                    );
                    assert_eq!(
                        s.tangent(lam).to_bits(),
                        tangent.to_bits(),
                        "{} {mode} {lam}",
                        m.name
                    );
                    assert_eq!(generic.stress(lam).to_bits(), stress.to_bits());
                    assert_eq!(generic.tangent(lam).to_bits(), tangent.to_bits());
                    let mut jac = vec![0.0; p.len()];
                    m.stress_jacobian(&p, mode, lam, &mut jac);
                    let want = reference_jacobian(&m, mode, lam);
                    for (a, b) in jac.iter().zip(&want) {
                        assert_eq!(a.to_bits(), b.to_bits(), "{} {mode} {lam}", m.name);
                    }
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 3 * 3 * 200);
        // a parameter vector of the wrong length has no prepared form (NaN stress)
        assert!(Polynomial::yeoh().prepare(&[1.0], Mode::Uniaxial).is_none());
        assert!(Polynomial::yeoh()
            .nominal_stress(&[1.0], Mode::Uniaxial, 0.9)
            .is_nan());
        // and no Jacobian, however long the vector
        for p in [&[1.0][..], &[1.0; 4][..]] {
            let mut jac = [0.0; 3];
            Polynomial::yeoh().stress_jacobian(p, Mode::Uniaxial, 0.9, &mut jac);
            assert!(jac.iter().all(|v| v.is_nan()), "{p:?}");
        }
    }
}
