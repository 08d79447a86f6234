//! The tangent dP/dλ of a mode as a sum of powers of the stretch, T(λ) = Σ a_k·λ^e_k,
//! the form in which the Drucker check (`src/fit/drucker.rs`) bounds its sign on
//! whole stretch intervals.
//!
//! Every model here has that form in every mode: the principal stretches of a mode
//! are powers of λ (see [`super::loadcase`]), so the polynomial models' stress
//! P = f·(W1 + λ2²·W2) is a Laurent polynomial in λ and T = dP/dλ is one too; Gent's
//! T is a positive factor μ·Jm/(2·gap²) times a Laurent polynomial; Ogden's is a sum
//! of real powers, Σ μi·ki·[(αi − 1)·λ^(αi−2) + (q·αi + 1)·λ^(−q·αi−2)] with λ3 = λ^−q.

use super::Mode;
use std::sync::OnceLock;

/// Exponents a [`Laurent`] polynomial can hold: [`LO`, `LO` + [`SPAN`]) (the
/// models here need −14 to 5).
const SPAN: usize = 32;
/// The smallest exponent a [`Laurent`] polynomial can hold.
const LO: i32 = -20;

/// A Laurent polynomial Σ c_e·λ^e with integer exponents in [−20, 12), stored densely
/// over the exponents in use (no allocation).
#[derive(Debug, Clone, Copy)]
pub struct Laurent {
    c: [f64; SPAN],
    /// Lowest and highest exponent in use (lo > hi: the zero polynomial).
    lo: i32,
    hi: i32,
}

impl Laurent {
    /// The zero polynomial.
    pub const ZERO: Laurent = Laurent {
        c: [0.0; SPAN],
        lo: i32::MAX,
        hi: i32::MIN,
    };

    /// a·λ^e (None when e is outside the range held).
    pub fn monomial(a: f64, e: i32) -> Option<Laurent> {
        let mut l = Laurent::ZERO;
        l.add_term(a, e)?;
        Some(l)
    }

    fn add_term(&mut self, a: f64, e: i32) -> Option<()> {
        if !(LO..LO + SPAN as i32).contains(&e) {
            return None;
        }
        self.c[(e - LO) as usize] += a;
        self.lo = self.lo.min(e);
        self.hi = self.hi.max(e);
        Some(())
    }

    /// The exponents in use, low to high, with their coefficients.
    pub fn terms(&self) -> impl Iterator<Item = (i32, f64)> + '_ {
        (self.lo..=self.hi).map(|e| (e, self.c[(e - LO) as usize]))
    }

    /// self + k·other.
    pub fn add_scaled(&self, k: f64, other: &Laurent) -> Laurent {
        let mut out = *self;
        out.add_assign_scaled(k, other);
        out
    }

    /// self += k·other.
    pub fn add_assign_scaled(&mut self, k: f64, other: &Laurent) {
        if other.lo > other.hi {
            return;
        }
        let used = (other.lo - LO) as usize..=(other.hi - LO) as usize;
        for (a, b) in self.c[used.clone()].iter_mut().zip(&other.c[used]) {
            *a += k * b;
        }
        self.lo = self.lo.min(other.lo);
        self.hi = self.hi.max(other.hi);
    }

    /// self·other (None when an exponent of the product is out of range).
    pub fn mul(&self, other: &Laurent) -> Option<Laurent> {
        let mut out = Laurent::ZERO;
        for (e, a) in self.terms() {
            for (f, b) in other.terms() {
                out.add_term(a * b, e + f)?;
            }
        }
        Some(out)
    }

    /// self^n, n ≥ 0.
    pub fn pow(&self, n: i32) -> Option<Laurent> {
        let mut out = Laurent::monomial(1.0, 0)?;
        for _ in 0..n {
            out = out.mul(self)?;
        }
        Some(out)
    }

    /// d/dλ.
    pub fn derivative(&self) -> Option<Laurent> {
        let mut out = Laurent::ZERO;
        for (e, c) in self.terms() {
            if e != 0 {
                out.add_term(c * f64::from(e), e - 1)?;
            }
        }
        Some(out)
    }

    /// Value at λ (Horner over the exponents in use).
    pub fn eval(&self, lam: f64) -> f64 {
        if self.lo > self.hi {
            return 0.0;
        }
        let mut acc = 0.0;
        for e in (self.lo..=self.hi).rev() {
            acc = acc * lam + self.c[(e - LO) as usize];
        }
        acc * lam.powi(self.lo)
    }
}

/// The kinematic quantities of a mode as Laurent polynomials in λ.
#[derive(Debug, Clone, Copy)]
pub struct LaurentKinematics {
    /// I1 − 3.
    pub x: Laurent,
    /// I2 − 3.
    pub y: Laurent,
    /// λ2².
    pub l2sq: Laurent,
    /// The geometric factor f = 2(λ1² − λ3²)/λ1 of P = f·(W1 + λ2²·W2).
    pub f: Laurent,
}

impl LaurentKinematics {
    /// The quantities of `mode` (computed once).
    pub fn of(mode: Mode) -> &'static LaurentKinematics {
        static ALL: OnceLock<[LaurentKinematics; 3]> = OnceLock::new();
        let all = ALL.get_or_init(|| Mode::ALL.map(Self::build));
        &all[mode.index()]
    }

    /// The quantities of `mode` (λ1 = λ; λ2², λ3² powers of λ as in [`super::loadcase`]).
    fn build(mode: Mode) -> LaurentKinematics {
        // Exponents of λ2² and λ3².
        let (e2, e3) = match mode {
            Mode::Uniaxial => (-1, -1),
            Mode::Equibiaxial => (2, -4),
            Mode::Planar => (0, -2),
        };
        let m = |a: f64, e: i32| Laurent::monomial(a, e).expect("small exponents");
        let sum = |terms: &[(f64, i32)]| {
            terms
                .iter()
                .fold(Laurent::ZERO, |acc, &(a, e)| acc.add_scaled(a, &m(1.0, e)))
        };
        LaurentKinematics {
            x: sum(&[(1.0, 2), (1.0, e2), (1.0, e3), (-3.0, 0)]),
            y: sum(&[(1.0, -2), (1.0, -e2), (1.0, -e3), (-3.0, 0)]),
            l2sq: m(1.0, e2),
            f: sum(&[(2.0, 1), (-2.0, e3 - 1)]),
        }
    }
}

/// A sum of powers of λ.
// The Laurent variant is held inline: one is built per mode and check, without an
// allocation, and never stored in bulk.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum PowerSum {
    /// Integer exponents (polynomial models, Gent).
    Integer(Laurent),
    /// Real exponents: (coefficient, exponent) pairs (Ogden).
    Real(Vec<(f64, f64)>),
}

/// The tangent of one mode as T(λ) = w(λ)·S(λ), w > 0 wherever T is finite.
#[derive(Debug, Clone)]
pub struct TangentPowers {
    /// S(λ).
    pub sum: PowerSum,
    /// False when T is finite at every stretch; true when it is finite only on an
    /// interval of stretch around λ = 1 and not finite outside it (Gent's limit).
    pub bounded: bool,
}

/// The value (P, N) and s-derivatives (P′, N′) of the positive and negative parts of
/// a power sum at s = ln λ: S = P − N, with P = Σ_{a>0} a·e^{e·s} and
/// N = Σ_{a<0} |a|·e^{e·s} both convex in s.
#[derive(Debug, Clone, Copy, Default)]
pub struct Parts {
    /// Positive part P.
    pub p: f64,
    /// dP/ds.
    pub dp: f64,
    /// Negative part N.
    pub n: f64,
    /// dN/ds.
    pub dn: f64,
}

impl PowerSum {
    /// Sign changes of the coefficients taken in order of exponent (zeros skipped).
    /// By Descartes' rule of signs, which holds for real exponents too (Laguerre),
    /// the sum has at most this many zeros in λ > 0, counted with multiplicity.
    pub fn sign_changes(&self) -> usize {
        let mut changes = 0;
        let mut last = 0.0;
        let mut step = |a: f64| {
            if a != 0.0 {
                if last != 0.0 && (a > 0.0) != (last > 0.0) {
                    changes += 1;
                }
                last = a;
            }
        };
        match self {
            PowerSum::Integer(l) => l.terms().for_each(|(_, a)| step(a)),
            PowerSum::Real(terms) => {
                // Terms of equal exponent counted apart can only add changes: the
                // count stays an upper bound.
                let mut sorted = terms.clone();
                sorted.sort_by(|x, y| x.1.total_cmp(&y.1));
                sorted.iter().for_each(|&(a, _)| step(a));
            }
        }
        changes
    }

    /// The sum split by the sign of its coefficients, once, for evaluating
    /// [`Parts`] at many stretches ([`Split::parts`]).
    pub fn split(&self) -> Split<'_> {
        match self {
            PowerSum::Integer(l) => {
                let mut coef = [[0.0; 4]; SPAN];
                let mut len = 0;
                for ((e, a), c) in l.terms().zip(coef.iter_mut()) {
                    let ae = a * f64::from(e);
                    // [P, P′, N, N′] coefficients of λ^e: the term in one part, zero
                    // in the other (−a·e = −(a·e) exactly, as the sum's own sign).
                    *c = if a > 0.0 {
                        [a, ae, 0.0, 0.0]
                    } else {
                        [0.0, 0.0, -a, -ae]
                    };
                    len += 1;
                }
                Split::Integer {
                    lo: l.lo,
                    len,
                    coef,
                }
            }
            PowerSum::Real(terms) => Split::Real(terms),
        }
    }
}

/// A [`PowerSum`] split by the sign of its coefficients ([`PowerSum::split`]).
// The Integer variant is held inline, as in `PowerSum`: one is built per mode and
// check, without an allocation, and never stored in bulk.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum Split<'a> {
    /// Integer exponents lo, lo + 1, … (`len` of them), each with its coefficients
    /// in [P, P′, N, N′]: no branch on the sign at each evaluation.
    Integer {
        /// Lowest exponent.
        lo: i32,
        /// Exponents in use.
        len: usize,
        /// Coefficients of λ^(lo + i) in P, P′, N and N′.
        coef: [[f64; 4]; SPAN],
    },
    /// Real exponents: (coefficient, exponent) pairs.
    Real(&'a [(f64, f64)]),
}

impl Split<'_> {
    /// (P, P′, N, N′) at s = ln λ (λ = e^s, given too so as not to recompute it).
    pub fn parts(&self, s: f64, lam: f64) -> Parts {
        let mut out = Parts::default();
        match self {
            Split::Integer { lo, len, coef } => {
                let mut pw = lam.powi(*lo);
                for c in &coef[..*len] {
                    out.p += c[0] * pw;
                    out.dp += c[1] * pw;
                    out.n += c[2] * pw;
                    out.dn += c[3] * pw;
                    pw *= lam;
                }
            }
            Split::Real(terms) => {
                for &(a, e) in terms.iter() {
                    let pw = (e * s).exp();
                    if a > 0.0 {
                        out.p += a * pw;
                        out.dp += a * e * pw;
                    } else {
                        out.n -= a * pw;
                        out.dn -= a * e * pw;
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn laurent_arithmetic_matches_values() {
        let k = LaurentKinematics::of(Mode::Equibiaxial);
        let lam = 1.7_f64;
        let x = 2.0 * lam * lam + lam.powi(-4) - 3.0;
        assert!((k.x.eval(lam) - x).abs() < 1e-14);
        let x3 = k.x.pow(3).unwrap();
        assert!((x3.eval(lam) - x.powi(3)).abs() < 1e-12 * x.powi(3));
        let dx = k.x.derivative().unwrap();
        assert!((dx.eval(lam) - (4.0 * lam - 4.0 * lam.powi(-5))).abs() < 1e-13);
        // Out-of-range exponents are refused, not wrapped.
        assert!(Laurent::monomial(1.0, 40).is_none());
        // λ² − 3 + 2λ⁻²: two sign changes; (λ − 1)²·… has its two zeros at λ = 1, √2.
        let q = Laurent::monomial(1.0, 2)
            .unwrap()
            .add_scaled(-3.0, &Laurent::monomial(1.0, 0).unwrap())
            .add_scaled(2.0, &Laurent::monomial(1.0, -2).unwrap());
        assert_eq!(PowerSum::Integer(q).sign_changes(), 2);
        assert_eq!(
            PowerSum::Real(vec![(1.0, 3.0), (-2.0, -1.5), (0.0, 0.0), (-1.0, 2.0)]).sign_changes(),
            1
        );
        assert!(k.x.pow(20).is_none());
    }

    #[test]
    fn parts_split_the_sum_by_sign() {
        let l = Laurent::monomial(2.0, 1)
            .unwrap()
            .add_scaled(-1.0, &Laurent::monomial(1.0, -2).unwrap());
        let lam = 1.3_f64;
        for sum in [
            PowerSum::Integer(l),
            PowerSum::Real(vec![(2.0, 1.0), (-1.0, -2.0)]),
        ] {
            let q = sum.split().parts(lam.ln(), lam);
            assert!((q.p - q.n - l.eval(lam)).abs() < 1e-14);
            // d/ds = λ·d/dλ
            let d = lam * l.derivative().unwrap().eval(lam);
            assert!((q.dp - q.dn - d).abs() < 1e-13);
        }
    }
}
