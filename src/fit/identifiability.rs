//! One rule for "identifiable", written once and applied by every estimator
//! (`hyperelastic`, `relaxation`, `identify`): whether the data pin a parameter down
//! on its own.
//!
//! A parameter is **not identifiable** when any of these holds:
//! - the information matrix is singular (no standard error);
//! - its relative standard error exceeds [`MAX_REL_SIGMA`] (a 95 % interval wider
//!   than a factor ≈ 2.7 either way), or, for a parameter that may take either
//!   sign, exceeds 1/t as well (its interval θ ± t·σ reaches 0) ([`limit`]);
//! - its correlation with another free parameter exceeds [`MAX_CORRELATION`] in
//!   magnitude (the data fix only their combination);
//! - its 95 % interval is one-sided (the likelihood does not rise on one side: the
//!   data cannot exclude 0 or ∞ for it);
//! - it ended at a bound of a search box (the box holds it, not the data).
//!
//! For an interval that is not the linearised one (a profile interval, asymmetric),
//! the relative standard error is the one of the equivalent symmetric interval
//! ([`equivalent_rel_sigma`]): ln(hi/lo)/(2t) for a positive parameter searched in
//! log space, (hi − lo)/(2t·|value|) for one that may take either sign. The same
//! threshold then means the same width, whichever way the interval was found.
//!
//! A correlation above [`WARN_CORRELATION`] (and not above [`MAX_CORRELATION`]) is
//! a warning naming the pair: each is still determined, but the pair's marginal
//! intervals are wide compared with what either would be alone.

/// Largest relative standard error of an identifiable parameter (a 95 % interval
/// within about a factor 2.7 either way; an interval of a sign-free parameter that
/// excludes 0).
pub const MAX_REL_SIGMA: f64 = 0.5;

/// Largest |correlation| between two identifiable parameters: beyond it the data fix
/// only their combination.
pub const MAX_CORRELATION: f64 = 0.999;

/// |correlation| above which a warning names the pair.
pub const WARN_CORRELATION: f64 = 0.99;

/// The rule in one sentence, for outputs and documentation.
pub const RULE: &str = "a parameter is identifiable when its information is not singular, its relative standard error is at most 0.5 (for an asymmetric interval, that of the equivalent symmetric one), its |correlation| with every other free parameter is at most 0.999, its 95 % interval is two-sided, and it did not end at a bound of a search box";

/// Why a parameter is not identifiable, of what its σ and correlations show.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Weakness {
    /// The information matrix is singular: no standard error.
    Singular,
    /// Its relative standard error (NaN when its value is 0).
    Loose(f64),
    /// Correlated with the free parameter of this index, with this ρ.
    Traded(usize, f64),
}

impl std::fmt::Display for Weakness {
    /// The finding in words, without the parameter's or partner's name.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Weakness::Singular => f.write_str("its information is singular"),
            Weakness::Loose(r) => write!(f, "σ/value = {r:.2}"),
            Weakness::Traded(_, rho) => write!(f, "|ρ| = {:.4} (> {MAX_CORRELATION})", rho.abs()),
        }
    }
}

/// The largest relative standard error the rule allows: [`MAX_REL_SIGMA`], and for a
/// parameter that may take either sign (`sign_free`) also 1/t, so that its 95 %
/// interval θ ± t·σ (t the interval's quantile) excludes 0.
pub fn limit(sign_free: bool, t: f64) -> f64 {
    match sign_free && t > 0.0 {
        true => MAX_REL_SIGMA.min(1.0 / t),
        false => MAX_REL_SIGMA,
    }
}

/// The rule: the weakness of a parameter with relative standard error `rel_sigma`
/// (None: singular information) against the `limit` ([`limit`]), correlated with
/// the other free parameters `partners` (index, ρ), or None when it is
/// identifiable. The strongest
/// correlation is the one reported. A bound of a search box and a one-sided
/// interval are the caller's to report (the last two points of the rule), since
/// only it knows its boxes and its interval's kind.
pub fn judge(
    rel_sigma: Option<f64>,
    limit: f64,
    partners: impl Iterator<Item = (usize, f64)>,
) -> Option<Weakness> {
    let partner = partners
        .filter(|p| p.1.is_finite())
        .max_by(|p, q| p.1.abs().total_cmp(&q.1.abs()));
    match (rel_sigma, partner) {
        (None, _) => Some(Weakness::Singular),
        (Some(r), _) if r.is_nan() || r > limit => Some(Weakness::Loose(r)),
        (_, Some((k, rho))) if rho.abs() > MAX_CORRELATION => Some(Weakness::Traded(k, rho)),
        _ => None,
    }
}

/// The relative standard error of a parameter with standard error `sd` at `value`
/// (NaN at value 0, which the rule treats as not identifiable: a parameter whose
/// estimate is 0 to the last digit is not told apart from 0 by any σ).
pub fn rel_sigma(value: f64, sd: Option<f64>) -> Option<f64> {
    sd.map(|s| s / value.abs())
}

/// The relative standard error of the symmetric interval equivalent to the 95 %
/// interval [lo, hi] about `value` at the quantile `t`: ln(hi/lo)/(2t) when `log`
/// (a positive parameter, 0 < lo ≤ hi), (hi − lo)/(2t·|value|) otherwise. NaN when
/// the interval is not ordered or a log interval is not positive.
pub fn equivalent_rel_sigma(value: f64, lo: f64, hi: f64, t: f64, log: bool) -> f64 {
    if !(lo <= hi && t > 0.0) {
        return f64::NAN;
    }
    match log {
        true if lo > 0.0 => (hi / lo).ln() / (2.0 * t),
        true => f64::NAN,
        false => (hi - lo) / (2.0 * t * value.abs()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_takes_the_strongest_correlation_and_the_width_first() {
        assert_eq!(
            judge(Some(0.1), MAX_REL_SIGMA, [(1, 0.5), (2, -0.99)].into_iter()),
            None
        );
        assert_eq!(
            judge(
                Some(0.1),
                MAX_REL_SIGMA,
                [(1, 0.5), (2, -0.9996), (3, 0.9991)].into_iter()
            ),
            Some(Weakness::Traded(2, -0.9996))
        );
        assert_eq!(
            judge(None, MAX_REL_SIGMA, std::iter::empty()),
            Some(Weakness::Singular)
        );
        assert_eq!(
            judge(Some(0.6), MAX_REL_SIGMA, [(1, 0.99999)].into_iter()),
            Some(Weakness::Loose(0.6))
        );
        assert!(matches!(
            judge(rel_sigma(0.0, Some(1.0)), MAX_REL_SIGMA, std::iter::empty()),
            Some(Weakness::Loose(r)) if r.is_infinite()
        ));
        assert!(matches!(
            judge(Some(f64::NAN), MAX_REL_SIGMA, std::iter::empty()),
            Some(Weakness::Loose(_))
        ));
    }

    /// A symmetric Wald interval gives back its own σ (linear: θ ± tσ; log:
    /// θ·exp(±tσ_x)), to rounding.
    #[test]
    fn an_equivalent_sigma_of_a_wald_interval_is_its_sigma() {
        let (v, s, t) = (3.0, 0.45, 1.97);
        let r = equivalent_rel_sigma(v, v - t * s, v + t * s, t, false);
        assert!((r - s / v).abs() < 1e-15);
        let sx = 0.3;
        let r = equivalent_rel_sigma(v, v * (-t * sx).exp(), v * (t * sx).exp(), t, true);
        assert!((r - sx).abs() < 1e-15);
        assert!(equivalent_rel_sigma(v, 2.0, 1.0, t, false).is_nan());
        assert!(equivalent_rel_sigma(v, -1.0, 1.0, t, true).is_nan());
    }

    /// A sign-free parameter whose interval θ ± t·σ reaches 0 is not identifiable,
    /// at any number of degrees of freedom (t = 2.78 at ν = 4: 1/t = 0.36 < 0.5);
    /// a positive one is held to 0.5 alone.
    #[test]
    fn an_interval_through_zero_is_loose() {
        for t in [1.96, 2.0, 2.78, 12.7] {
            let s = 1.0001 / t;
            let l = limit(true, t);
            assert!(judge(rel_sigma(1.0, Some(s)), l, std::iter::empty()).is_some());
            assert!(judge(rel_sigma(1.0, Some(0.999 * l)), l, std::iter::empty()).is_none());
            assert_eq!(limit(false, t), MAX_REL_SIGMA);
        }
    }
}
