//! Ogden N-term model, stretch-based (separable).
//!
//! * Seed form (Eq. 2.9, as FE codes write it): W = Σ 2μi/αi²·(λ1^αi + λ2^αi + λ3^αi − 3),
//!   μ0 = Σμi.
//! * Original form (Ogden 1972): W = Σ μi/αi·(λ1^αi + λ2^αi + λ3^αi − 3), μ0 = ½Σμiαi.
//!
//! With a = ln λ1, b = ln λ3 the nominal stress is P = Σ ci(μi, αi)·(e^{αi·a} − e^{αi·b})/λ1,
//! ci = 2μi/αi (seed) or μi (original). The seed form's term (e^{αa} − e^{αb})/α stays
//! finite as α → 0 (it tends to a − b), so the seed form is the better-conditioned one
//! to search in. Parameters are ordered μ1, α1, μ2, α2, …; the stress is linear in the μi.

use super::loadcase::Mode;
use super::powers::{PowerSum, TangentPowers};
use super::{OgdenForm, ParamInfo, Points, StrainEnergy};
use crate::numerics;

/// Ogden model with `n` terms in a chosen coefficient form.
#[derive(Debug, Clone)]
pub struct Ogden {
    n: usize,
    form: OgdenForm,
    params: Vec<ParamInfo>,
}

/// Bounds of the exponents searched.
pub const ALPHA_BOUND: f64 = 20.0;

impl Ogden {
    /// An `n`-term Ogden model.
    pub fn new(n: usize, form: OgdenForm) -> Self {
        let mut params = Vec::with_capacity(2 * n);
        for i in 1..=n {
            params.push(ParamInfo::modulus(format!("mu{i}")));
            params.push(ParamInfo {
                name: format!("alpha{i}"),
                unit: "1",
                lower: -ALPHA_BOUND,
                upper: ALPHA_BOUND,
                linear: false,
            });
        }
        Ogden { n, form, params }
    }

    /// The coefficient form.
    pub fn form(&self) -> OgdenForm {
        self.form
    }

    /// The (μi, αi) pairs of `p`, or None when `p` is not 2n values (or the model
    /// has no term): the evaluators then give NaN rather than index past the end
    /// of a short vector.
    #[inline]
    fn terms<'p>(&self, p: &'p [f64]) -> Option<std::slice::ChunksExact<'p, f64>> {
        (self.n > 0 && p.len() == 2 * self.n).then(|| p.chunks_exact(2))
    }

    /// Convert parameters from this model's form to the other form (same function).
    pub fn convert(p: &[f64], from: OgdenForm, to: OgdenForm) -> Vec<f64> {
        let mut q = p.to_vec();
        for t in q.chunks_exact_mut(2) {
            let (mu, alpha) = (t[0], t[1]);
            t[0] = match (from, to) {
                (OgdenForm::Abaqus, OgdenForm::Original) => 2.0 * mu / alpha,
                (OgdenForm::Original, OgdenForm::Abaqus) => mu * alpha / 2.0,
                _ => mu,
            };
        }
        q
    }

    /// Per-term basis B(α) = k(α)·(e^{αa} − e^{αb}) and its α-derivative in every
    /// lane of `x`, where k = 2/α (seed) or 1 (original), a = ln λ1 and
    /// b = ln λ3 = −q·a ([`lateral_power`]): e^{αa} by [`numerics::exp`] and
    /// e^{αb} = (e^{αa})^(−q) from it by a square root or a division
    /// ([`lateral_exp`]), one exponential a term instead of two, all of it
    /// straight-line arithmetic the lanes compute in vector registers. The seed
    /// form's α → 0 limit (|α| < 10⁻⁶, the same for every lane) by its series.
    #[inline(always)]
    fn basis<const L: usize>(&self, alpha: f64, x: &Lanes<L>) -> ([f64; L], [f64; L]) {
        let (mut v, mut dv) = ([0.0; L], [0.0; L]);
        match self.form {
            OgdenForm::Abaqus if alpha.abs() < 1e-6 => {
                for i in 0..L {
                    // Series of 2(e^{αa} − e^{αb})/α about α = 0.
                    let (a, b) = (x.a[i], x.b[i]);
                    let (d1, d2, d3) = (a - b, a * a - b * b, a * a * a - b * b * b);
                    v[i] = 2.0 * (d1 + alpha * d2 / 2.0 + alpha * alpha * d3 / 6.0);
                    dv[i] = 2.0 * (d2 / 2.0 + alpha * d3 / 3.0);
                }
            }
            OgdenForm::Abaqus => {
                for i in 0..L {
                    let (ea, eb) = x.exps(alpha, i);
                    v[i] = 2.0 * (ea - eb) / alpha;
                    dv[i] = 2.0 * (x.a[i] * ea - x.b[i] * eb) / alpha - v[i] / alpha;
                }
            }
            OgdenForm::Original => {
                for i in 0..L {
                    let (ea, eb) = x.exps(alpha, i);
                    v[i] = ea - eb;
                    dv[i] = x.a[i] * ea - x.b[i] * eb;
                }
            }
        }
        (v, dv)
    }

    /// The nominal stress P = Σ μi·Bi/λ1 in every lane of `x` (`p` holds 2n values).
    #[inline(always)]
    fn stress_lanes<const L: usize>(&self, p: &[f64], x: &Lanes<L>) -> [f64; L] {
        let mut sum = [0.0; L];
        for t in p.chunks_exact(2) {
            let (v, _) = self.basis(t[1], x);
            for i in 0..L {
                sum[i] += t[0] * v[i];
            }
        }
        std::array::from_fn(|i| sum[i] / x.lam[i])
    }

    /// ∂P/∂p of the first `out.len() / p.len()` lanes of `x`, a row of `p.len()`
    /// values each: ∂P/∂μi = Bi/λ1, ∂P/∂αi = μi·∂Bi/∂αi/λ1 (`p` holds 2n values).
    #[inline(always)]
    fn jacobian_lanes<const L: usize>(&self, p: &[f64], x: &Lanes<L>, out: &mut [f64]) {
        let k = p.len();
        for (j, t) in p.chunks_exact(2).enumerate() {
            let (v, dv) = self.basis(t[1], x);
            let dmu: [f64; L] = std::array::from_fn(|i| v[i] / x.lam[i]);
            let dalpha: [f64; L] = std::array::from_fn(|i| t[0] * dv[i] / x.lam[i]);
            for (i, row) in out.chunks_exact_mut(k).enumerate() {
                row[2 * j] = dmu[i];
                row[2 * j + 1] = dalpha[i];
            }
        }
    }

    /// [`StrainEnergy::nominal_stresses`] over [`LANES`] points at a time.
    #[inline(always)]
    fn stresses_portable(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        for (c, o) in out.chunks_mut(LANES).enumerate() {
            let s = self.stress_lanes(p, &Lanes::<LANES>::of(&pts, c * LANES));
            o.copy_from_slice(&s[..o.len()]);
        }
    }

    /// [`StrainEnergy::stress_jacobians`] over [`LANES`] points at a time.
    #[inline(always)]
    fn jacobians_portable(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        for (c, rows) in out.chunks_mut(LANES * p.len()).enumerate() {
            self.jacobian_lanes(p, &Lanes::<LANES>::of(&pts, c * LANES), rows);
        }
    }

    /// [`Ogden::stresses_portable`] compiled for AVX2 (four f64 a vector register).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn stresses_avx2(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        self.stresses_portable(p, pts, out)
    }

    /// [`Ogden::jacobians_portable`] compiled for AVX2 (four f64 a vector register).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn jacobians_avx2(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        self.jacobians_portable(p, pts, out)
    }

    /// d(λ·∂w/∂λ)/dλ per unit μ: seed 2λ^(α−1), original α·λ^(α−1).
    #[inline]
    fn dg(&self, mu: f64, alpha: f64, lam: f64) -> f64 {
        let k = match self.form {
            OgdenForm::Abaqus => 2.0,
            OgdenForm::Original => alpha,
        };
        k * mu * lam.powf(alpha - 1.0)
    }
}

/// The power q of a mode's traction-free stretch λ3 = λ1^(−q): uniaxial ½,
/// equibiaxial 2, planar 1 (incompressibility, [`Mode::kinematics`]).
#[inline(always)]
fn lateral_power(mode: Mode) -> f64 {
    match mode {
        Mode::Uniaxial => 0.5,
        Mode::Equibiaxial => 2.0,
        Mode::Planar => 1.0,
    }
}

/// e^{αb} = (e^{αa})^(−q) from `ea` = e^{αa}, q = [`lateral_power`]: 1/√ea
/// (uniaxial), 1/ea² (equibiaxial) or 1/ea (planar), chosen by value (every
/// candidate computed, one selected), so that lanes of mixed modes stay in vector
/// registers.
#[inline(always)]
fn lateral_exp(ea: f64, q: f64) -> f64 {
    let (root, square) = (ea.sqrt(), ea * ea);
    // Two selects of two values each, which the vectoriser turns into blends.
    let g = if q == 2.0 { square } else { ea };
    let g = if q == 0.5 { root } else { g };
    1.0 / g
}

/// Points in the evaluators' lanes: `L` = [`LANES`] over a block of a fit's points,
/// 1 for a single point (the per-point methods: the same arithmetic, so the same
/// bits as the block's).
struct Lanes<const L: usize> {
    /// a = ln λ1.
    a: [f64; L],
    /// b = ln λ3 = −q·a.
    b: [f64; L],
    /// The mode's lateral power q ([`lateral_power`]).
    q: [f64; L],
    /// λ1.
    lam: [f64; L],
}

impl<const L: usize> Lanes<L> {
    /// Points `at..at + L` of `pts`; lanes past its end hold λ = 1 (computed and
    /// never written out).
    #[inline(always)]
    fn of(pts: &Points<'_>, at: usize) -> Self {
        let mut x = Lanes {
            a: [0.0; L],
            b: [0.0; L],
            q: [1.0; L],
            lam: [1.0; L],
        };
        for i in 0..L.min(pts.len().saturating_sub(at)) {
            let (q, a) = (lateral_power(pts.mode(at + i)), pts.ln_stretch(at + i));
            x.a[i] = a;
            x.b[i] = -q * a;
            x.q[i] = q;
            x.lam[i] = pts.stretch(at + i);
        }
        x
    }

    /// (e^{αa}, e^{αb}) of lane `i`.
    #[inline(always)]
    fn exps(&self, alpha: f64, i: usize) -> (f64, f64) {
        let ea = numerics::exp(alpha * self.a[i]);
        (ea, lateral_exp(ea, self.q[i]))
    }
}

impl Lanes<1> {
    /// One point of `mode` at stretch `lam`.
    #[inline(always)]
    fn one(mode: Mode, lam: f64) -> Self {
        let (q, a) = (lateral_power(mode), lam.ln());
        Lanes {
            a: [a],
            b: [-q * a],
            q: [q],
            lam: [lam],
        }
    }
}

/// Points a block evaluator carries at once: two AVX2 registers of four f64 (two
/// independent chains of each exponential's Horner steps), four SSE2 ones on the
/// baseline.
const LANES: usize = 8;

impl StrainEnergy for Ogden {
    fn name(&self) -> String {
        format!("ogden{}", self.n)
    }
    fn params(&self) -> &[ParamInfo] {
        &self.params
    }
    fn nominal_stress(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        if self.terms(p).is_none() {
            return f64::NAN;
        }
        self.stress_lanes(p, &Lanes::one(mode, lam))[0]
    }
    fn tangent(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        // P = (g(λ1) − g(λ3))/λ1 ⇒ dP/dλ = (g'(λ1)λ1' − g'(λ3)λ3')/λ1 − P·λ1'/λ1.
        let Some(terms) = self.terms(p) else {
            return f64::NAN;
        };
        let k = mode.kinematics(lam);
        let stress = self.nominal_stress(p, mode, lam);
        let dg: f64 = terms
            .map(|t| self.dg(t[0], t[1], k.l[0]) * k.dl[0] - self.dg(t[0], t[1], k.l[2]) * k.dl[2])
            .sum();
        dg / k.l[0] - stress * k.dl[0] / k.l[0]
    }
    fn tangent_powers(&self, p: &[f64], mode: Mode) -> Option<TangentPowers> {
        // P = Σ μi·ki·(λ^(αi−1) − λ^(−q·αi−1)) with λ3 = λ^−q and ki = 2/αi (seed) or 1
        // (original), so T = Σ μi·ki·[(αi − 1)·λ^(αi−2) + (q·αi + 1)·λ^(−q·αi−2)]. The
        // seed form's ki has no power-sum limit as αi → 0 (the pair tends to a
        // logarithm): none then.
        let q = lateral_power(mode);
        let mut terms = Vec::with_capacity(p.len());
        for t in self.terms(p)? {
            let (mu, alpha) = (t[0], t[1]);
            let k = match self.form {
                OgdenForm::Abaqus if alpha.abs() < 1e-6 => return None,
                OgdenForm::Abaqus => 2.0 / alpha,
                OgdenForm::Original => 1.0,
            };
            terms.push((mu * k * (alpha - 1.0), alpha - 2.0));
            terms.push((mu * k * (q * alpha + 1.0), -q * alpha - 2.0));
        }
        Some(TangentPowers {
            sum: PowerSum::Real(terms),
            bounded: false,
        })
    }
    fn stress_jacobian(&self, p: &[f64], mode: Mode, lam: f64, out: &mut [f64]) {
        if self.terms(p).is_none() || out.len() != p.len() {
            out.fill(f64::NAN);
            return;
        }
        self.jacobian_lanes(p, &Lanes::one(mode, lam), out);
    }
    /// In lanes of [`LANES`] points, compiled for AVX2 where the processor has it
    /// (else for the baseline: the same arithmetic, since Rust never fuses a
    /// multiply and an add, so the same bits), with the fit problem's ln λ; the
    /// bits of [`StrainEnergy::nominal_stress`] at every point.
    fn nominal_stresses(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        if self.terms(p).is_none() || out.len() != pts.len() {
            out.fill(f64::NAN);
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (detected on the line above).
            return unsafe { self.stresses_avx2(p, pts, out) };
        }
        self.stresses_portable(p, pts, out)
    }
    /// As [`Ogden::nominal_stresses`]: the bits of [`StrainEnergy::stress_jacobian`]
    /// at every point.
    fn stress_jacobians(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        if self.terms(p).is_none() || out.len() != pts.len() * p.len() {
            out.fill(f64::NAN);
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (detected on the line above).
            return unsafe { self.jacobians_avx2(p, pts, out) };
        }
        self.jacobians_portable(p, pts, out)
    }
    /// αᵢ (index 2i + 1) enters μᵢ's term (index 2i) alone: ∂P/∂αᵢ = μᵢ·∂Aᵢ/∂αᵢ.
    fn coefficient_of(&self, j: usize) -> Option<usize> {
        (j % 2 == 1 && j < 2 * self.n).then(|| j - 1)
    }
    fn initial_shear_modulus(&self, p: &[f64]) -> f64 {
        let Some(terms) = self.terms(p) else {
            return f64::NAN;
        };
        terms
            .map(|t| match self.form {
                OgdenForm::Abaqus => t[0],
                OgdenForm::Original => 0.5 * t[0] * t[1],
            })
            .sum()
    }
    fn nonlinear_starts(&self, _max_x: f64) -> Vec<Vec<f64>> {
        // Physically informed exponents: small positive ones carry the low-stretch
        // response, large positive ones the upturn, negative ones the biaxial
        // stiffness. Every combination of n distinct values is one start.
        const SET: [f64; 8] = [-4.0, -2.0, -1.0, 0.5, 1.5, 3.0, 5.0, 8.0];
        let mut out = Vec::new();
        let mut idx: Vec<usize> = (0..self.n).collect();
        loop {
            out.push(idx.iter().map(|&i| SET[i]).collect());
            // Next combination in lexicographic order.
            let mut i = self.n;
            while i > 0 && idx[i - 1] == SET.len() - self.n + (i - 1) {
                i -= 1;
            }
            if i == 0 {
                return out;
            }
            idx[i - 1] += 1;
            for j in i..self.n {
                idx[j] = idx[j - 1] + 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points cycling through the three modes over stretches 0.3…7.6 (a
    /// compression branch, λ = 1 exactly, Treloar's largest uniaxial stretch), with
    /// their logarithms as the fit problem takes them.
    fn points(n: usize) -> (Vec<Mode>, Vec<f64>, Vec<f64>) {
        let modes = (0..n).map(|i| Mode::ALL[i % 3]).collect();
        let stretch: Vec<f64> = (0..n)
            .map(|i| match i {
                4 => 1.0,
                _ => 0.3 + 7.3 * i as f64 / n.max(2) as f64,
            })
            .collect();
        let ln = stretch.iter().map(|l| l.ln()).collect();
        (modes, stretch, ln)
    }

    /// Models and parameters that take every branch: both forms, an exponent in
    /// the seed form's series (|α| < 10⁻⁶), exponents at the bounds ±20.
    fn cases() -> Vec<(Ogden, Vec<f64>)> {
        vec![
            (
                Ogden::new(3, OgdenForm::Abaqus),
                vec![3.4e5, 1.92, 3.1, 8.62, 7.3e3, -2.16],
            ),
            (
                Ogden::new(4, OgdenForm::Abaqus),
                vec![3e5, 1.3, 1e3, 4e-7, 5e3, -20.0, 1e-3, 20.0],
            ),
            (
                Ogden::new(2, OgdenForm::Original),
                vec![6.18e5, 1.3, -9.81e3, -2.0],
            ),
        ]
    }

    /// The block evaluators give the per-point methods' values bit for bit (the
    /// same lane arithmetic at one lane and at [`LANES`]), at lengths that leave a
    /// partial last block; a parameter vector of the wrong length gives NaN.
    #[test]
    fn blocks_are_the_points_bit_for_bit() {
        for n in [1, 7, 8, 9, 3 * LANES + 5] {
            let (modes, stretch, ln) = points(n);
            let pts = Points::new(&modes, &stretch, &ln).unwrap();
            for (m, p) in cases() {
                let k = p.len();
                let (mut s, mut jac) = (vec![0.0; n], vec![0.0; n * k]);
                m.nominal_stresses(&p, pts, &mut s);
                m.stress_jacobians(&p, pts, &mut jac);
                let mut row = vec![0.0; k];
                for i in 0..n {
                    let want = m.nominal_stress(&p, modes[i], stretch[i]);
                    assert_eq!(
                        s[i].to_bits(),
                        want.to_bits(),
                        "{} n = {n}, i = {i}",
                        m.name()
                    );
                    m.stress_jacobian(&p, modes[i], stretch[i], &mut row);
                    let got = jac[i * k..(i + 1) * k].iter().map(|v| v.to_bits());
                    let want = row.iter().map(|v| v.to_bits());
                    assert!(got.eq(want), "{} n = {n}, i = {i}", m.name());
                }
                m.nominal_stresses(&p[1..], pts, &mut s);
                assert!(s.iter().all(|v| v.is_nan()));
                m.stress_jacobians(&p, pts, &mut jac[1..]);
                assert!(jac[1..].iter().all(|v| v.is_nan()));
            }
        }
    }

    /// The stress is the model's equation evaluated with the library's `powf`,
    /// P = Σ kᵢ·(λ^αᵢ − λ3^αᵢ)/λ (kᵢ = 2μᵢ/αᵢ seed, μᵢ original), to rounding: the
    /// tolerance is (2·|α·ln λ| + 8)·2⁻⁵² of Σ|kᵢ|·(λ^αᵢ + λ3^αᵢ)/λ per term, since
    /// ln λ and α·ln λ are each rounded (a relative error of ε·|α·ln λ| in
    /// e^{α·ln λ} each), the exponential is within 3·2⁻⁵³ ([`numerics::exp`]),
    /// λ3^α follows by a square root or a division and the sum and quotients
    /// round a few times more. Terms in the seed form's series are left out
    /// (the series is its own approximation, tested against differences of the
    /// stress in tests/models.rs).
    #[test]
    fn stress_is_the_power_law_to_rounding() {
        let (modes, stretch, _) = points(301);
        for (m, p) in cases() {
            for (&mode, &lam) in modes.iter().zip(&stretch) {
                let l3 = lam.powf(-lateral_power(mode));
                let (mut want, mut scale, mut tol) = (0.0, 0.0, 0.0);
                for t in p.chunks_exact(2).filter(|t| t[1].abs() >= 1e-6) {
                    let k = match m.form {
                        OgdenForm::Abaqus => 2.0 * t[0] / t[1],
                        OgdenForm::Original => t[0],
                    };
                    let (x, y) = (lam.powf(t[1]), l3.powf(t[1]));
                    want += k * (x - y) / lam;
                    let size = (k * (x + y) / lam).abs();
                    scale += size;
                    tol += (2.0 * (t[1] * lam.ln()).abs() + 8.0) * f64::EPSILON * size;
                }
                let kept: Vec<f64> = p
                    .chunks_exact(2)
                    .flat_map(|t| match t[1].abs() >= 1e-6 {
                        true => [t[0], t[1]],
                        false => [0.0, t[1]],
                    })
                    .collect();
                let got = m.nominal_stress(&kept, mode, lam);
                assert!(
                    (got - want).abs() <= tol,
                    "{} {mode} λ = {lam}: {got} vs {want} (tolerance {tol}, scale {scale})",
                    m.name()
                );
            }
        }
    }

    /// The block evaluators compiled for AVX2 and for the baseline give the same
    /// bits (every case, a partial last block), where the processor has AVX2 to
    /// compare.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn vector_and_baseline_blocks_agree_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let n = 5 * LANES + 3;
        let (modes, stretch, ln) = points(n);
        let pts = Points::new(&modes, &stretch, &ln).unwrap();
        for (m, p) in cases() {
            let k = p.len();
            let (mut s, mut sv) = (vec![0.0; n], vec![0.0; n]);
            let (mut j, mut jv) = (vec![0.0; n * k], vec![0.0; n * k]);
            m.stresses_portable(&p, pts, &mut s);
            m.jacobians_portable(&p, pts, &mut j);
            // SAFETY: AVX2 detected above.
            unsafe {
                m.stresses_avx2(&p, pts, &mut sv);
                m.jacobians_avx2(&p, pts, &mut jv);
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&s), bits(&sv), "{}", m.name());
            assert_eq!(bits(&j), bits(&jv), "{}", m.name());
        }
    }
}
