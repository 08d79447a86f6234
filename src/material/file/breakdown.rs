//! A breakdown fit (`dea-fit breakdown --out`, schema [`BREAKDOWN_SCHEMA`]): the
//! Weibull α and β of a series of specimens, with their standard errors and
//! correlation, the electrode area α holds at, and (with `--covariates`) the
//! exponents of α = α_ref·(h/h_ref)^a·(λ/λ_ref)^b. A scene or a ranking reads it
//! with [`read_breakdown`] and takes [`BreakdownFit::strength`]: α carried to the
//! actuator's electrode area by the weakest-link law (`material::breakdown`), to
//! its thickness and prestretch when the fit has those exponents, with the
//! first-order standard error of the result (GUM, JCGM 100:2008 eq. 13).

use super::{err, read_text, typed, Spread, BREAKDOWN_SCHEMA};
use crate::error::Result;
use crate::material::breakdown::{area_factor, Strength, StrengthOrigin, Weibull};
use crate::material::check::fmt_g;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One parameter of a breakdown fit: `alpha` (V/m), `beta` (1), and where fitted
/// `threshold` (V/m, three-parameter Weibull), `thickness_exponent` (1),
/// `prestretch_exponent` (1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BreakdownParameter {
    /// Name.
    pub name: String,
    /// SI unit (`V/m` or `1`).
    pub unit: String,
    /// Value (SI).
    pub value: f64,
    /// Standard error (SI), None where the fit gives none.
    #[serde(default)]
    pub std_error: Option<f64>,
    /// 95 % bounds (the kind the file's `bounds` names).
    #[serde(default)]
    pub ci95: Option<[f64; 2]>,
}

/// One percentile E_p of a breakdown fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BreakdownPercentile {
    /// Share of specimens failed (0 < p < 1).
    pub p: f64,
    /// E_p (V/m).
    pub value: f64,
    /// Standard error (V/m), where the fit gives one.
    #[serde(default)]
    pub std_error: Option<f64>,
    /// 95 % bounds (V/m).
    #[serde(default)]
    pub ci95: Option<[f64; 2]>,
}

/// A breakdown fit file. The command writes it (and may write more fields, which a
/// reader ignores); scenes and the ranking read it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BreakdownFit {
    /// Schema tag, [`BREAKDOWN_SCHEMA`].
    pub schema: String,
    /// dea-fit version that wrote it.
    pub tool_version: String,
    /// Status of the fit (`ok`, `warning`, …); only `ok` and `warning` are used.
    pub status: String,
    /// Estimator: `mle`, `rry` or `rrx`.
    pub method: String,
    /// Plotting position of a rank regression (`bernard`, `exact`, `ieee930`).
    #[serde(default)]
    pub positions: Option<String>,
    /// Specimens.
    pub n: usize,
    /// Specimens that broke down.
    pub failures: usize,
    /// Specimens that survived to their field (right-censored).
    pub survived: usize,
    /// Parameters, SI.
    pub parameters: Vec<BreakdownParameter>,
    /// Correlation of the parameters, in their order (None where undefined).
    #[serde(default)]
    pub correlation: Vec<Vec<Option<f64>>>,
    /// β times the small-sample unbiasing factor.
    #[serde(default)]
    pub beta_unbiased: Option<f64>,
    /// Log-likelihood at the estimate.
    pub log_likelihood: f64,
    /// E_1 %, E_10 %, α, … with bounds.
    #[serde(default)]
    pub percentiles: Vec<BreakdownPercentile>,
    /// Electrode area α holds at (m²); None: not stated when fitted.
    #[serde(rename = "reference_area_m2", default)]
    pub reference_area: Option<f64>,
    /// Thickness α holds at (m), with a thickness exponent.
    #[serde(rename = "reference_thickness_m", default)]
    pub reference_thickness: Option<f64>,
    /// Prestretch α holds at, with a prestretch exponent.
    #[serde(default)]
    pub reference_prestretch: Option<f64>,
    /// Thickness range of the specimens (m), with a thickness exponent.
    #[serde(rename = "thickness_range_m", default)]
    pub thickness_range: Option<[f64; 2]>,
    /// Prestretch range of the specimens, with a prestretch exponent.
    #[serde(default)]
    pub prestretch_range: Option<[f64; 2]>,
    /// Kind of the 95 % bounds (`likelihood-ratio` or `fisher`).
    #[serde(default)]
    pub bounds: String,
    /// Warnings of the fit.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Input files and settings.
    #[serde(default)]
    pub provenance: serde_json::Value,
}

/// Parameter names and units a breakdown fit may hold; the first two it must.
const NAMES: [(&str, &str); 5] = [
    ("alpha", "V/m"),
    ("beta", "1"),
    ("threshold", "V/m"),
    ("thickness_exponent", "1"),
    ("prestretch_exponent", "1"),
];

/// Read and check a breakdown fit: its schema tag, a status of `ok` or `warning`,
/// every parameter by name with its unit, finite, α and β positive, each
/// exponent with its reference value, the reference area positive.
pub fn read_breakdown(path: &Path) -> Result<BreakdownFit> {
    let (text, _) = read_text(path, &[BREAKDOWN_SCHEMA], "breakdown")?;
    let fit: BreakdownFit = typed(path, &text)?;
    if !matches!(fit.status.as_str(), "ok" | "warning") {
        return Err(err(
            path,
            "status",
            format!("the fit's status is '{}': not usable", fit.status),
        )
        .with_hint("only a breakdown fit with status ok or warning is used; read its warnings and fit again"));
    }
    let mut seen = [false; NAMES.len()];
    for (i, p) in fit.parameters.iter().enumerate() {
        let at = format!("parameters[{i}]");
        let Some(j) = NAMES.iter().position(|(n, _)| *n == p.name) else {
            let all: Vec<&str> = NAMES.iter().map(|n| n.0).collect();
            return Err(err(
                path,
                &format!("{at}.name"),
                format!("'{}' is not a breakdown parameter", p.name),
            )
            .with_hint(format!("a breakdown fit holds {}", all.join(", "))));
        };
        if std::mem::replace(&mut seen[j], true) {
            return Err(err(
                path,
                &format!("{at}.name"),
                format!("'{}' is given twice", p.name),
            ));
        }
        if p.unit != NAMES[j].1 {
            return Err(err(
                path,
                &format!("{at}.unit"),
                format!("{} is in '{}', found '{}'", p.name, NAMES[j].1, p.unit),
            )
            .with_hint("fit files hold SI values: write them with dea-fit breakdown"));
        }
        let positive = j < 2;
        if !p.value.is_finite() || (positive && p.value <= 0.0) {
            let want = if positive {
                "a finite positive number"
            } else {
                "a finite number"
            };
            return Err(err(
                path,
                &format!("{at}.value"),
                format!("{} needs {want}, found {}", p.name, p.value),
            ));
        }
        if p.std_error.is_some_and(|s| !(s.is_finite() && s >= 0.0)) {
            return Err(err(
                path,
                &format!("{at}.std_error"),
                "needs a finite number ≥ 0 or null",
            ));
        }
    }
    for (k, (name, _)) in NAMES.iter().enumerate().take(2) {
        if !seen[k] {
            return Err(err(path, "parameters", format!("{name} is missing"))
                .with_hint("write breakdown fits with dea-fit breakdown --out"));
        }
    }
    let positive = |key: &str, v: Option<f64>| match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(err(
            path,
            key,
            format!("needs a finite positive number, found {x}"),
        )),
        _ => Ok(()),
    };
    positive("reference_area_m2", fit.reference_area)?;
    positive("reference_thickness_m", fit.reference_thickness)?;
    positive("reference_prestretch", fit.reference_prestretch)?;
    for (exponent, reference, key) in [
        (
            "thickness_exponent",
            fit.reference_thickness,
            "reference_thickness_m",
        ),
        (
            "prestretch_exponent",
            fit.reference_prestretch,
            "reference_prestretch",
        ),
    ] {
        if fit.parameter(exponent).is_some() && reference.is_none() {
            return Err(err(
                path,
                key,
                format!("missing: {exponent} needs the value α holds at"),
            ));
        }
    }
    let n = fit.parameters.len();
    if !fit.correlation.is_empty()
        && (fit.correlation.len() != n || fit.correlation.iter().any(|r| r.len() != n))
    {
        return Err(err(
            path,
            "correlation",
            format!("needs {n} rows of {n}, one per parameter"),
        ));
    }
    Ok(fit)
}

/// A number with its unit for notes: `1.5e-4 m²`.
fn with_unit(v: f64, unit: &str) -> String {
    format!("{} {unit}", fmt_g(v))
}

impl BreakdownFit {
    /// The parameter `name`, if the fit has it.
    pub fn parameter(&self, name: &str) -> Option<&BreakdownParameter> {
        self.parameters.iter().find(|p| p.name == name)
    }

    /// The Weibull law at the reference area (and reference covariates).
    pub fn law(&self) -> Weibull {
        let v = |n: &str| self.parameter(n).map_or(f64::NAN, |p| p.value);
        Weibull {
            alpha: v("alpha"),
            beta: v("beta"),
        }
    }

    /// The breakdown strength of an actuator whose film has electrode area `area`
    /// (m², all of it under field), thickness `thickness` (m) and prestretch
    /// `prestretch`, each where known: Eb = γ + α·(A0/A)^(1/β)·(h/h_ref)^a·(λ/λ_ref)^b
    /// (γ the threshold of a three-parameter fit, else 0; a factor whose inputs are
    /// missing is 1, and a note says what was not scaled), with its first-order
    /// standard error from the file's standard errors and correlation. `source`
    /// names the reference in messages (e.g. the scene file and key).
    pub fn strength(
        &self,
        area: Option<f64>,
        thickness: Option<f64>,
        prestretch: Option<f64>,
        source: &str,
    ) -> Strength {
        let Weibull { alpha, beta } = self.law();
        let mut notes = Vec::new();
        // ln of each factor, and the gradient of Eb in the parameters' order.
        let mut ln_area = 0.0;
        match (self.reference_area, area) {
            (Some(a0), Some(a)) => {
                ln_area = (a0 / a).ln();
                notes.push(format!(
                    "α × {:.3} from the specimens' {} to the actuator's {} (weakest link, β = {})",
                    area_factor(a0, a, beta),
                    with_unit(a0, "m²"),
                    with_unit(a, "m²"),
                    fmt_g(beta)
                ));
            }
            (None, Some(_)) => notes.push(
                "not scaled to the actuator's electrode area: the fit states no specimen area (fit with --specimen-area or an area_mm2 column)"
                    .to_string(),
            ),
            _ => {}
        }
        let mut covariate = |name: &str,
                             reference: Option<f64>,
                             value: Option<f64>,
                             range: Option<[f64; 2]>,
                             unit: &str|
         -> f64 {
            let (Some(p), Some(r)) = (self.parameter(name), reference) else {
                return 0.0;
            };
            let Some(x) = value else {
                notes.push(format!(
                    "{name} not applied: taken at the fit's reference {}",
                    with_unit(r, unit)
                ));
                return 0.0;
            };
            if let Some([lo, hi]) = range {
                if x < lo || x > hi {
                    notes.push(format!(
                        "extrapolated: {} is outside the specimens' {}–{}",
                        with_unit(x, unit),
                        fmt_g(lo),
                        with_unit(hi, unit)
                    ));
                }
            }
            notes.push(format!(
                "α × {:.3} for {} against the fit's {} ({name} {})",
                (x / r).powf(p.value),
                with_unit(x, unit),
                with_unit(r, unit),
                fmt_g(p.value)
            ));
            (x / r).ln()
        };
        let ln_h = covariate(
            "thickness_exponent",
            self.reference_thickness,
            thickness,
            self.thickness_range,
            "m",
        );
        let ln_l = covariate(
            "prestretch_exponent",
            self.reference_prestretch,
            prestretch,
            self.prestretch_range,
            "",
        );
        let exp_of = |n: &str| self.parameter(n).map_or(0.0, |p| p.value);
        let factor = (ln_area / beta
            + exp_of("thickness_exponent") * ln_h
            + exp_of("prestretch_exponent") * ln_l)
            .exp();
        let gamma = self.parameter("threshold").map_or(0.0, |p| p.value);
        let scaled = alpha * factor;
        let grad: Vec<f64> = self
            .parameters
            .iter()
            .map(|p| match p.name.as_str() {
                "alpha" => factor,
                "beta" => -scaled * ln_area / (beta * beta),
                "threshold" => 1.0,
                "thickness_exponent" => scaled * ln_h,
                "prestretch_exponent" => scaled * ln_l,
                _ => 0.0,
            })
            .collect();
        let spread = Spread {
            std_error: self.parameters.iter().map(|p| p.std_error).collect(),
            correlation: self.correlation.clone(),
        };
        let law = match self.parameter("threshold") {
            None => Some(Weibull {
                alpha: scaled,
                beta,
            }),
            Some(_) => {
                notes
                    .push("three-parameter fit: Eb is the threshold plus the scaled α".to_string());
                None
            }
        };
        Strength {
            field: gamma + scaled,
            std_error: spread.propagate(&grad),
            origin: StrengthOrigin::Fitted,
            source: source.to_string(),
            law,
            notes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fit(params: Vec<BreakdownParameter>, correlation: Vec<Vec<Option<f64>>>) -> BreakdownFit {
        BreakdownFit {
            schema: BREAKDOWN_SCHEMA.into(),
            tool_version: "test".into(),
            status: "ok".into(),
            method: "mle".into(),
            positions: None,
            n: 15,
            failures: 15,
            survived: 0,
            parameters: params,
            correlation,
            beta_unbiased: None,
            log_likelihood: 0.0,
            percentiles: Vec::new(),
            reference_area: Some(1e-4),
            reference_thickness: None,
            reference_prestretch: None,
            thickness_range: None,
            prestretch_range: None,
            bounds: "fisher".into(),
            warnings: Vec::new(),
            provenance: serde_json::Value::Null,
        }
    }

    fn p(name: &str, unit: &str, value: f64, s: f64) -> BreakdownParameter {
        BreakdownParameter {
            name: name.into(),
            unit: unit.into(),
            value,
            std_error: Some(s),
            ci95: None,
        }
    }

    #[test]
    fn strength_scales_by_area_with_the_delta_method_sigma() {
        let rho = -0.3;
        let f = fit(
            vec![p("alpha", "V/m", 30e6, 0.6e6), p("beta", "1", 10.0, 1.5)],
            vec![vec![Some(1.0), Some(rho)], vec![Some(rho), Some(1.0)]],
        );
        let s = f.strength(Some(1e-2), None, None, "x");
        // 100× the area at β = 10: ×0.631 (1e-9: one pow).
        assert!((s.field / (30e6 * 100f64.powf(-0.1)) - 1.0).abs() < 1e-9);
        // σ against a finite-difference propagation of ln Eb = ln α − ln(100)/β,
        // at a step of 1e-6 relative (central differences: error ≈ 1e-12).
        let eb = |a: f64, b: f64| a * (1e-4f64 / 1e-2).powf(1.0 / b);
        let (ga, gb) = (
            (eb(30e6 * (1.0 + 1e-6), 10.0) - eb(30e6 * (1.0 - 1e-6), 10.0)) / (2.0 * 30.0),
            (eb(30e6, 10.0 + 1e-5) - eb(30e6, 10.0 - 1e-5)) / 2e-5,
        );
        let var = (ga * 0.6e6).powi(2) + (gb * 1.5).powi(2) + 2.0 * rho * ga * 0.6e6 * gb * 1.5;
        assert!((s.std_error.unwrap() / var.sqrt() - 1.0).abs() < 1e-6);
        assert_eq!(s.law.unwrap().beta, 10.0);
        assert!(s.notes[0].contains("× 0.631"), "{:?}", s.notes);
        // Without the actuator's area nothing is scaled and σ is α's.
        let same = f.strength(None, None, None, "x");
        assert_eq!(same.field, 30e6);
        assert!((same.std_error.unwrap() - 0.6e6).abs() < 1e-3);
    }

    #[test]
    fn a_fit_without_specimen_area_says_it_was_not_scaled() {
        let mut f = fit(
            vec![p("alpha", "V/m", 30e6, 0.6e6), p("beta", "1", 10.0, 1.5)],
            Vec::new(),
        );
        f.reference_area = None;
        let s = f.strength(Some(1e-2), None, None, "x");
        assert_eq!(s.field, 30e6);
        assert!(s.notes[0].contains("not scaled"), "{:?}", s.notes);
        // No correlation stated: σ of α alone still propagates (β's gradient is 0).
        assert!((s.std_error.unwrap() - 0.6e6).abs() < 1e-3);
    }

    #[test]
    fn covariates_scale_and_say_when_they_extrapolate() {
        let mut f = fit(
            vec![
                p("alpha", "V/m", 30e6, 0.6e6),
                p("beta", "1", 10.0, 1.5),
                p("thickness_exponent", "1", -0.4, 0.05),
            ],
            Vec::new(),
        );
        f.reference_thickness = Some(100e-6);
        f.thickness_range = Some([50e-6, 200e-6]);
        let s = f.strength(None, Some(400e-6), None, "x");
        // (4)^−0.4 = 0.5743 (1e-9: one pow).
        assert!((s.field / (30e6 * 4f64.powf(-0.4)) - 1.0).abs() < 1e-9);
        assert!(
            s.notes.iter().any(|n| n.contains("extrapolated")),
            "{:?}",
            s.notes
        );
        // No correlation stated between α and the exponent, both moved: no σ.
        assert_eq!(s.std_error, None);
        let at_ref = f.strength(None, None, None, "x");
        assert_eq!(at_ref.field, 30e6);
        assert!(at_ref.notes[0].contains("not applied"));
    }
}
