//! Gent (1996): W = −(μ·Jm/2)·ln(1 − (I1 − 3)/Jm), with the limiting chain
//! extensibility Jm > I1 − 3. μ0 = μ; Neo-Hookean is the limit Jm → ∞.
//! Linear in μ for fixed Jm.

use super::loadcase::{InvariantDerivs, Mode};
use super::powers::{Laurent, LaurentKinematics, PowerSum, TangentPowers};
use super::{ParamInfo, StrainEnergy};

/// The largest Jm the model takes (its parameter bound): the neo-Hookean limit in
/// practice, since W = −μJm/2·ln(1 − (I1 − 3)/Jm), expanded in (I1 − 3)/Jm,
/// departs from the neo-Hookean μ(I1 − 3)/2 by (I1 − 3)/(2Jm) relative: 10⁻⁶ at
/// a stretch of 2. The model reduction of identification drops a Jm the
/// trace cannot see to this value (`identify::reduce`).
pub const JM_MAX: f64 = 1e6;

/// The Gent model, parameters `mu` (Pa) and `Jm` (dimensionless).
#[derive(Debug, Clone)]
pub struct Gent {
    params: Vec<ParamInfo>,
}

impl Default for Gent {
    fn default() -> Self {
        Self::new()
    }
}

impl Gent {
    /// A Gent model.
    pub fn new() -> Self {
        Gent {
            params: vec![
                ParamInfo::modulus("mu"),
                ParamInfo {
                    name: "Jm".into(),
                    unit: "1",
                    lower: 1e-3,
                    upper: JM_MAX,
                    linear: false,
                },
            ],
        }
    }

    /// Derivatives at I1; NaN beyond the extensibility limit (no finite stress there)
    /// and for a parameter vector that is not (μ, Jm).
    #[inline]
    fn derivs(p: &[f64], i1: f64) -> InvariantDerivs {
        let &[mu, jm] = p else {
            return InvariantDerivs::NAN;
        };
        let gap = jm - (i1 - 3.0);
        if gap.is_nan() || gap <= 0.0 {
            return InvariantDerivs::NAN;
        }
        InvariantDerivs {
            w1: 0.5 * mu * jm / gap,
            w11: 0.5 * mu * jm / (gap * gap),
            ..Default::default()
        }
    }
}

impl StrainEnergy for Gent {
    fn name(&self) -> String {
        "gent".into()
    }
    fn params(&self) -> &[ParamInfo] {
        &self.params
    }
    fn nominal_stress(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        let k = mode.kinematics(lam);
        let d = Self::derivs(p, k.invariants().0);
        k.invariant_stress(d.w1, 0.0)
    }
    fn tangent(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        let k = mode.kinematics(lam);
        k.invariant_tangent(&Self::derivs(p, k.invariants().0))
    }
    fn reads_ln_stretch(&self) -> bool {
        false
    }
    fn tangent_powers(&self, p: &[f64], mode: Mode) -> Option<TangentPowers> {
        // P = f·W1 with W1 = μ·Jm/(2·gap), gap = Jm − x: T = μ·Jm/(2·gap²)·Q with
        // Q = f′·gap + f·x′, finite only where gap > 0 (an interval around λ = 1,
        // since x = I1 − 3 falls to 0 at λ = 1 and rises on either side).
        let &[mu, jm] = p else {
            return None;
        };
        let k = LaurentKinematics::of(mode);
        let gap = Laurent::monomial(jm, 0)?.add_scaled(-1.0, &k.x);
        let q =
            k.f.derivative()?
                .mul(&gap)?
                .add_scaled(1.0, &k.f.mul(&k.x.derivative()?)?);
        Some(TangentPowers {
            sum: PowerSum::Integer(Laurent::ZERO.add_scaled(0.5 * mu * jm, &q)),
            bounded: true,
        })
    }
    fn stress_jacobian(&self, p: &[f64], mode: Mode, lam: f64, out: &mut [f64]) {
        if p.len() != 2 || out.len() != 2 {
            out.fill(f64::NAN);
            return;
        }
        let (mu, jm) = (p[0], p[1]);
        let k = mode.kinematics(lam);
        let x = k.invariants().0 - 3.0;
        let gap = jm - x;
        let f = k.invariant_factor();
        // ∂W1/∂μ = Jm/(2·gap); ∂W1/∂Jm = −μ·x/(2·gap²).
        out[0] = f * 0.5 * jm / gap;
        out[1] = -f * 0.5 * mu * x / (gap * gap);
    }
    /// Jm (index 1) enters μ's term alone: ∂P/∂Jm = μ·∂A/∂Jm.
    fn coefficient_of(&self, j: usize) -> Option<usize> {
        (j == 1).then_some(0)
    }
    fn initial_shear_modulus(&self, p: &[f64]) -> f64 {
        match p {
            &[mu, _] => mu,
            _ => f64::NAN,
        }
    }
    fn nonlinear_starts(&self, max_x: f64) -> Vec<Vec<f64>> {
        let lo = self.bounds(max_x)[1].0;
        [1.05 * lo, 1.5 * lo, 3.0 * lo, 10.0 * lo, 100.0 * lo]
            .into_iter()
            .map(|j| vec![j])
            .collect()
    }
    fn bounds(&self, max_x: f64) -> Vec<(f64, f64)> {
        // The limit must lie beyond every data point: Jm > max(I1 − 3). Data beyond
        // the upper bound (I1 − 3 > 1e6, a stretch above 1000, which the tensile
        // domain refuses) leave the box a point rather than an inverted interval; a
        // NaN max_x is ignored by f64::max.
        let lo = (max_x * (1.0 + 1e-6)).max(self.params[1].lower);
        vec![
            (f64::NEG_INFINITY, f64::INFINITY),
            (lo, self.params[1].upper.max(lo)),
        ]
    }
}
