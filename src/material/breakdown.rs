//! Breakdown strength as a statistical property: the two-parameter Weibull law of
//! the field at which a film fails, and the weakest-link law that carries a
//! coupon's strength to an actuator's electrode area.
//!
//! * F(E) = 1 − exp[−(E/α)^β]: α the characteristic field (63.2 % of specimens
//!   have failed below it), β the shape (IEEE Std 930-2004, IEC 62539:2007).
//! * Weakest link: a film of area A fails where any of its A/A0 coupon-sized parts
//!   fails, so 1 − F_A(E) = [1 − F_A0(E)]^(A/A0), which for the Weibull law is the
//!   same β with α_A = α_A0·(A0/A)^(1/β) (IEEE Std 930-2004 §6.2; Dissado & Fothergill
//!   1992, *Electrical Degradation and Breakdown in Polymers*, §15.3).
//!
//! The estimators are in `fit::weibull`; the fit file in [`super::file`].

/// A two-parameter Weibull breakdown law (α in V/m, β dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weibull {
    /// Characteristic (scale) field α (V/m): F(α) = 1 − 1/e.
    pub alpha: f64,
    /// Shape β (> 0): larger is less scatter.
    pub beta: f64,
}

impl Weibull {
    /// Probability of breakdown at or below field `e` (V/m):
    /// F(E) = 1 − exp[−(E/α)^β] (0 for E ≤ 0).
    pub fn cdf(&self, e: f64) -> f64 {
        match e > 0.0 {
            true => -(-(e / self.alpha).powf(self.beta)).exp_m1(),
            false => 0.0,
        }
    }

    /// The field below which a share `p` (0 < p < 1) of specimens fails:
    /// E_p = α·[−ln(1 − p)]^(1/β).
    pub fn percentile(&self, p: f64) -> f64 {
        self.alpha * (-(-p).ln_1p()).powf(1.0 / self.beta)
    }

    /// The law of an electrode of area `to` (m²) from that of area `from` (m²): the
    /// same β, α·(from/to)^(1/β) ([`area_factor`]).
    pub fn scaled(&self, from: f64, to: f64) -> Weibull {
        Weibull {
            alpha: self.alpha * area_factor(from, to, self.beta),
            beta: self.beta,
        }
    }
}

/// The weakest-link factor on α from electrode area `from` to area `to` (m²) at
/// shape β: (from/to)^(1/β). A 100× larger electrode at β = 10 gives 0.631.
pub fn area_factor(from: f64, to: f64, beta: f64) -> f64 {
    (from / to).powf(1.0 / beta)
}

/// Where a breakdown strength comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrengthOrigin {
    /// Typed into a scene or a manifest (with or without ±).
    Stated,
    /// From a breakdown fit file (`dea-fit breakdown`).
    Fitted,
}

/// A breakdown strength as a scene or a ranking uses it: the field (V/m) at which
/// the actuator's film is taken to fail, its first-order standard error, where it
/// comes from and what was done to it (area, thickness and prestretch scaling).
#[derive(Debug, Clone, PartialEq)]
pub struct Strength {
    /// Breakdown field (V/m): α at the actuator's electrode area.
    pub field: f64,
    /// Standard error (V/m); None: none stated (an exact stated value).
    pub std_error: Option<f64>,
    /// Stated or fitted.
    pub origin: StrengthOrigin,
    /// The file (with key or line) it comes from.
    pub source: String,
    /// The Weibull law at the actuator's area (fitted strengths only): the
    /// probability of breakdown at a field is `law.cdf(E)`.
    pub law: Option<Weibull>,
    /// What was scaled and what could not be, in words (e.g. "α × 0.631 from the
    /// coupon's 1 cm² to the actuator's 100 cm² (β = 10)").
    pub notes: Vec<String>,
}

impl Strength {
    /// A stated strength (`25 V/um` or `25 ± 2 V/um`) from `source`.
    pub fn stated(field: f64, std_error: Option<f64>, source: impl Into<String>) -> Strength {
        Strength {
            field,
            std_error,
            origin: StrengthOrigin::Stated,
            source: source.into(),
            law: None,
            notes: Vec::new(),
        }
    }

    /// Probability of breakdown at field `e` (V/m), where the law is known.
    pub fn probability(&self, e: f64) -> Option<f64> {
        self.law.map(|w| w.cdf(e))
    }

    /// Margin of field `e` (V/m) to breakdown, as a share of the breakdown field:
    /// 1 − E/Eb (negative beyond breakdown).
    pub fn margin(&self, e: f64) -> f64 {
        1.0 - e / self.field
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_area_law_is_the_weakest_link() {
        // The number: 100× the area at β = 10 is ×0.631 (to 3 digits).
        assert!((area_factor(1.0, 100.0, 10.0) - 0.630_957).abs() < 1e-6);
        // 1 − F_A(E) = (1 − F_A0(E))^(A/A0) at every field, compared as
        // −ln(1 − F) = (E/α)^β (1 − F itself underflows to 0 at 40× the area):
        // relative 1e-12, a few roundings of one pow.
        let w = Weibull {
            alpha: 30e6,
            beta: 8.0,
        };
        let big = w.scaled(1e-4, 4e-3);
        for e in [5e6, 15e6, 25e6, 30e6, 40e6] {
            let lhs = (e / big.alpha).powf(big.beta);
            let rhs = 40.0 * (e / w.alpha).powf(w.beta);
            assert!((lhs / rhs - 1.0).abs() <= 1e-12, "{e}: {lhs} {rhs}");
        }
        assert!(big.cdf(20e6) > w.cdf(20e6));
    }

    #[test]
    fn percentile_inverts_the_law() {
        let w = Weibull {
            alpha: 25e6,
            beta: 12.0,
        };
        for p in [1e-6, 0.01, 0.1, 0.5, 1.0 - (-1.0f64).exp(), 0.99] {
            // Relative 1e-12: one log, one power and one exp of rounding.
            assert!(
                (w.cdf(w.percentile(p)) - p).abs() <= 1e-12 * p.max(1e-3),
                "{p}"
            );
        }
        // α is the 63.2 % percentile (1e-12: 1 − (1 − 1/e) rounds).
        assert!((w.percentile(1.0 - (-1.0f64).exp()) / w.alpha - 1.0).abs() < 1e-12);
        assert_eq!(w.cdf(0.0), 0.0);
    }
}
