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
use super::{OgdenForm, ParamInfo, StrainEnergy};

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

    /// The (μi, αi) pairs of `p`, or None when `p` is not 2n values: the evaluators
    /// then give NaN rather than index past the end of a short vector.
    #[inline]
    fn terms<'p>(&self, p: &'p [f64]) -> Option<std::slice::ChunksExact<'p, f64>> {
        (p.len() == 2 * self.n).then(|| p.chunks_exact(2))
    }

    /// Convert parameters from this model's form to the other form (same function).
    pub fn convert(p: &[f64], from: OgdenForm, to: OgdenForm) -> Vec<f64> {
        let mut q = p.to_vec();
        for t in q.chunks_exact_mut(2) {
            let (mu, alpha) = (t[0], t[1]);
            t[0] = match (from, to) {
                (OgdenForm::Seed, OgdenForm::Original) => 2.0 * mu / alpha,
                (OgdenForm::Original, OgdenForm::Seed) => mu * alpha / 2.0,
                _ => mu,
            };
        }
        q
    }

    /// Per-term basis B(α) = k(α)·(e^{αa} − e^{αb}) and its α-derivative, where
    /// k = 2/α (seed) or 1 (original), a = ln λ1 and b = ln λ3 = −q·a
    /// ([`lateral_power`]): e^{αb} = (e^{αa})^(−q) comes from e^{αa} by a square root
    /// or a division, one exponential a term instead of two.
    #[inline]
    fn basis(&self, alpha: f64, a: f64, mode: Mode) -> (f64, f64) {
        let b = -lateral_power(mode) * a;
        let ea = (alpha * a).exp();
        let eb = match mode {
            Mode::Uniaxial => 1.0 / ea.sqrt(),
            Mode::Equibiaxial => 1.0 / (ea * ea),
            Mode::Planar => 1.0 / ea,
        };
        match self.form {
            OgdenForm::Original => (ea - eb, a * ea - b * eb),
            OgdenForm::Seed => {
                if alpha.abs() < 1e-6 {
                    // Series of 2(e^{αa} − e^{αb})/α about α = 0.
                    let (d1, d2, d3) = (a - b, a * a - b * b, a * a * a - b * b * b);
                    (
                        2.0 * (d1 + alpha * d2 / 2.0 + alpha * alpha * d3 / 6.0),
                        2.0 * (d2 / 2.0 + alpha * d3 / 3.0),
                    )
                } else {
                    let v = 2.0 * (ea - eb) / alpha;
                    (v, 2.0 * (a * ea - b * eb) / alpha - v / alpha)
                }
            }
        }
    }

    /// d(λ·∂w/∂λ)/dλ per unit μ: seed 2λ^(α−1), original α·λ^(α−1).
    #[inline]
    fn dg(&self, mu: f64, alpha: f64, lam: f64) -> f64 {
        let k = match self.form {
            OgdenForm::Seed => 2.0,
            OgdenForm::Original => alpha,
        };
        k * mu * lam.powf(alpha - 1.0)
    }
}

/// The power q of a mode's traction-free stretch λ3 = λ1^(−q): uniaxial ½,
/// equibiaxial 2, planar 1 (incompressibility, [`Mode::kinematics`]).
fn lateral_power(mode: Mode) -> f64 {
    match mode {
        Mode::Uniaxial => 0.5,
        Mode::Equibiaxial => 2.0,
        Mode::Planar => 1.0,
    }
}

impl StrainEnergy for Ogden {
    fn name(&self) -> String {
        format!("ogden{}", self.n)
    }
    fn params(&self) -> &[ParamInfo] {
        &self.params
    }
    fn nominal_stress(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        let Some(terms) = self.terms(p) else {
            return f64::NAN;
        };
        let a = lam.ln();
        terms
            .map(|t| t[0] * self.basis(t[1], a, mode).0)
            .sum::<f64>()
            / lam
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
                OgdenForm::Seed if alpha.abs() < 1e-6 => return None,
                OgdenForm::Seed => 2.0 / alpha,
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
        let (Some(terms), true) = (self.terms(p), out.len() == p.len()) else {
            out.fill(f64::NAN);
            return;
        };
        let a = lam.ln();
        for (t, o) in terms.zip(out.chunks_exact_mut(2)) {
            let (v, dv) = self.basis(t[1], a, mode);
            o[0] = v / lam;
            o[1] = t[0] * dv / lam;
        }
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
                OgdenForm::Seed => t[0],
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
