//! Breakdown wherever a scene applies a field: the true field in a layer, the film
//! a breakdown strength is scaled to, and the check of the largest field of a
//! static curve or a run against the scene's `material.breakdown`.
//!
//! * True field in a layer: E = V/h(λ), with the electrode gap h the layer's current
//!   thickness, zd0·λ for a stack layer (seed Eq. 3.2: zd = zd0·λ) and z0·λ·sin α for
//!   a helix element (seed Eq. 4.3). The nominal field V/zd0 understates it by λ.
//! * The breakdown voltage at a stretch is V_b(λ) = Eb·h(λ).
//! * The weakest-link population is the whole film under field as built: every
//!   active layer of a stack, nd·π·r0², and every element of a helix, Np·Ne·A_e
//!   (seed Eq. 4.12 at λ = 1); its thickness is the gap as built, h(1).

use super::scene::Actuator;
use crate::material::breakdown::{Strength, StrengthOrigin};
use serde::Serialize;

impl Actuator {
    /// The electrode gap (m) at thickness stretch λ: zd0·λ for a stack layer (seed
    /// Eq. 3.2), z0·λ·sin α(λ) for a helix element (seed Eq. 4.3).
    pub fn gap(&self, lam: f64) -> f64 {
        match self {
            Actuator::Stack(s) => s.layer_m * lam,
            Actuator::Helix(h) => h.thickness_m * lam * h.alpha(lam).sin(),
        }
    }

    /// The true field (V/m) in a layer at voltage `v` and stretch λ: E = V/h(λ).
    pub fn field(&self, v: f64, lam: f64) -> f64 {
        v / self.gap(lam)
    }

    /// The area (m²) of film under field as built, the weakest-link population a
    /// breakdown strength is scaled to: nd·π·r0² for a stack (all its active
    /// layers), Np·Ne·A_e(1) for a helix (seed Eq. 4.12).
    pub fn film_area(&self) -> f64 {
        match self {
            Actuator::Stack(s) => s.layers as f64 * s.area0(),
            Actuator::Helix(h) => (h.periods * h.per_period) as f64 * h.electrode_area(1.0),
        }
    }
}

/// The largest true field of a curve or a run, and where it was.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FieldPeak {
    /// Field E = V/h(λ) (V/m).
    #[serde(rename = "field_V_per_m")]
    pub field: f64,
    /// Terminal voltage there (V).
    #[serde(rename = "voltage_V")]
    pub voltage_v: f64,
    /// Thickness stretch there.
    pub stretch: f64,
    /// Time (s) of a run; None for a static state.
    #[serde(rename = "time_s", skip_serializing_if = "Option::is_none")]
    pub time_s: Option<f64>,
}

impl FieldPeak {
    /// No field yet (E = 0 at rest).
    pub const NONE: FieldPeak = FieldPeak {
        field: 0.0,
        voltage_v: 0.0,
        stretch: f64::NAN,
        time_s: None,
    };

    /// Keep the larger of this peak and the field at (t, V, λ) of `a`.
    pub fn widen(&mut self, a: &Actuator, t: Option<f64>, v: f64, lam: f64) {
        let e = a.field(v, lam).abs();
        if e > self.field {
            *self = FieldPeak {
                field: e,
                voltage_v: v,
                stretch: lam,
                time_s: t,
            };
        }
    }
}

/// The largest field against the breakdown strength: what `static` and
/// `simulate` print and put in their JSON (`breakdown`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// Whether a breakdown strength was stated (else nothing was checked).
    pub checked: bool,
    /// The largest true field and where it was.
    pub peak: FieldPeak,
    /// Breakdown field Eb (V/m) at the actuator's film.
    #[serde(rename = "breakdown_V_per_m")]
    pub breakdown: Option<f64>,
    /// Its standard error (V/m), where known.
    #[serde(rename = "breakdown_std_error_V_per_m")]
    pub std_error: Option<f64>,
    /// `stated` or `fitted`.
    pub origin: Option<&'static str>,
    /// Where Eb comes from (the scene's key or the fit file).
    pub source: Option<String>,
    /// What was scaled (area, thickness, prestretch) and what was not.
    pub notes: Vec<String>,
    /// 1 − E/Eb (negative beyond breakdown).
    pub margin: Option<f64>,
    /// Probability of breakdown at the largest field (fitted strengths: the Weibull
    /// law at the actuator's film area).
    pub probability: Option<f64>,
    /// The largest field reaches Eb.
    pub exceeded: bool,
    /// One line for people.
    pub message: String,
}

/// A field in V/µm for people.
pub fn v_per_um(e: f64) -> String {
    format!("{:.2} V/µm", e * 1e-6)
}

/// What [`Check::message`] says when a scene states no breakdown strength.
pub const NOT_CHECKED: &str = "breakdown not checked: the scene states none";

/// Check `peak` (what it is in words: `what`) against `strength`.
pub fn check(strength: Option<&Strength>, peak: FieldPeak, what: &str) -> Check {
    let Some(s) = strength else {
        return Check {
            checked: false,
            peak,
            breakdown: None,
            std_error: None,
            origin: None,
            source: None,
            notes: Vec::new(),
            margin: None,
            probability: None,
            exceeded: false,
            message: format!("{NOT_CHECKED} ({what} is {})", v_per_um(peak.field)),
        };
    };
    let margin = s.margin(peak.field);
    let exceeded = peak.field >= s.field;
    let origin = match s.origin {
        StrengthOrigin::Stated => "stated",
        StrengthOrigin::Fitted => "fitted",
    };
    let sigma = s
        .std_error
        .map_or(String::new(), |e| format!(" ± {:.2}", e * 1e-6));
    let eb = format!("{:.2}{sigma} V/µm ({origin})", s.field * 1e-6);
    let probability = s.probability(peak.field);
    let p = probability.map_or(String::new(), |p| {
        format!(", probability of breakdown {:.3e}", p)
    });
    let message = match exceeded {
        true => format!(
            "beyond breakdown: {what} is {}, at or above the breakdown field {eb} (margin {:.1} %{p})",
            v_per_um(peak.field),
            100.0 * margin
        ),
        false => format!(
            "{what} is {}, against the breakdown field {eb}: margin {:.1} %{p}",
            v_per_um(peak.field),
            100.0 * margin
        ),
    };
    Check {
        checked: true,
        peak,
        breakdown: Some(s.field),
        std_error: s.std_error,
        origin: Some(origin),
        source: Some(s.source.clone()),
        notes: s.notes.clone(),
        margin: Some(margin),
        probability,
        exceeded,
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::scene::{HelixGeometry, Lateral, StackGeometry};

    #[test]
    fn the_field_is_the_voltage_over_the_current_gap() {
        let s = Actuator::Stack(StackGeometry {
            radius_m: 2e-3,
            layer_m: 500e-6,
            electrode_m: 0.0,
            layers: 10,
            electrodes: 11,
        });
        // 10 kV over 500 µm·0.8: 25 V/µm (1e-12: two roundings).
        assert!((s.field(10e3, 0.8) / 25e6 - 1.0).abs() < 1e-12);
        assert!((s.film_area() / (10.0 * std::f64::consts::PI * 4e-6) - 1.0).abs() < 1e-12);
        let h = HelixGeometry {
            outer_m: 30e-3,
            inner_m: 10e-3,
            thickness_m: 1e-3,
            periods: 50,
            per_period: 2,
            lateral: Lateral::Planar,
        };
        let a = Actuator::Helix(h);
        // The gap is z·sin α (seed Eq. 4.3): below z, so the field above V/z.
        let g = a.gap(0.9);
        assert!((g / (0.9e-3 * h.alpha(0.9).sin()) - 1.0).abs() < 1e-12);
        assert!(g < 0.9e-3);
        assert!((a.film_area() / (100.0 * h.electrode_area(1.0)) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_check_says_the_margin_and_when_nothing_was_checked() {
        let mut peak = FieldPeak::NONE;
        let s = Actuator::Stack(StackGeometry {
            radius_m: 2e-3,
            layer_m: 100e-6,
            electrode_m: 0.0,
            layers: 1,
            electrodes: 0,
        });
        peak.widen(&s, Some(1.0), 2e3, 1.0);
        peak.widen(&s, Some(2.0), 1e3, 1.0);
        assert_eq!(peak.time_s, Some(1.0));
        let strength = Strength::stated(25e6, None, "x");
        let c = check(Some(&strength), peak, "the largest field");
        // 20 V/µm against 25: margin 0.2 (1e-12: one division).
        assert!((c.margin.unwrap() - 0.2).abs() < 1e-12);
        assert!(
            !c.exceeded && c.message.contains("margin 20.0 %"),
            "{}",
            c.message
        );
        peak.widen(&s, Some(3.0), 3e3, 1.0);
        let c = check(Some(&strength), peak, "the largest field");
        assert!(c.exceeded && c.message.starts_with("beyond breakdown"));
        let none = check(None, peak, "the largest field");
        assert!(!none.checked && none.message.starts_with(NOT_CHECKED));
    }
}
