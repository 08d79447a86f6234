//! A candidate material: one series of the design at one loading, with each
//! property's value and provenance, and the constants the simulator runs with.
//!
//! At loading x (fraction on the series' basis; φ the filler volume fraction from the
//! phase densities, `material::dielectric::volume_fraction`):
//!
//! * **εr**: a measured value at x; else the series' model — a stated mixing rule
//!   with the matrix's and the filler's εr (predicted) or a composite fit's rule
//!   (fitted) — times a correction that passes through the measured values of the
//!   series: r = measured/model at each measured loading, r = 1 at x = 0, linear in x
//!   between, held beyond the last. Without measured εr the model stands alone.
//! * **Hyperelastic constants**: a measured (fitted) part at x; else the matrix's
//!   with every stress coefficient (unit Pa) multiplied by the stiffening factor
//!   X(φ) of the named rule ([`Stiffening`]) and by a correction through the
//!   measured parts (their μ0 over the matrix's μ0·X(φ), interpolated as for εr).
//!   Y = 3μ0 of the result. The viscous part (Nv, arm moduli and viscosities; the
//!   relaxation times unchanged) is scaled by the same factor μ0/μ0,matrix: a rigid
//!   filler amplifies the strain of the matrix, whose whole stress grows with it.
//! * **tan δ, breakdown field**: a value at x (stated, or for Eb from a breakdown
//!   fit scaled to the actuator's film, `manifest::Film`); else interpolated linearly
//!   in x between the measured loadings (the matrix counts as measured at x = 0);
//!   beyond the last measured loading held at its value, and with no measured
//!   composite held at the matrix's value — both with a warning.
//! * **Density**: φρf + (1 − φ)ρm.
//!
//! Standard errors (carried to the figures by [`Candidate::shifts`]) come from the fit files and from
//! values written in the manifest as `value ± σ` (a value written without ± is
//! taken as exact), to first order (GUM, JCGM 100:2008):
//! * εr of a composite fit's rule from its εm, εf (and n) with their correlation;
//!   of a stated rule from the σ of the matrix's and the filler's εr (independent);
//!   either times the correction, combined in quadrature with the relative σ of
//!   the measured εr it passes through (interpolated in x as the correction is);
//! * Y of a fitted part from the σ of its μ0, of a part written in the manifest
//!   from its parameters' σ (independent); a predicted Y carries the relative σ of
//!   the parts it is corrected through, interpolated in x as the correction is
//!   (the matrix's at x = 0);
//! * tan δ and the breakdown field as their values: measured, interpolated
//!   (independent knots) or held.

use super::manifest::{Design, MeasuredPoint, PermittivityModel, Series, Stated, Uncertain};
use super::short;
use super::{Figure, Provenance};
use crate::fit::composite::Basis;
use crate::material::dielectric::volume_fraction;
use crate::material::file::{self, Arm, HyperelasticPart, Viscous};
use crate::Result;

/// Stiffening of an elastomer by rigid spherical filler: the modulus of the
/// composite is X(φ) times the matrix's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stiffening {
    /// Guth & Gold (1938), Guth (1945), J. Appl. Phys. 16, 20: X = 1 + 2.5φ + 14.1φ²
    /// (Einstein's term plus pair interactions), for φ up to about 0.3.
    GuthGold,
    /// Einstein (1906, 1911; Smallwood 1944 for elastomers): X = 1 + 2.5φ, dilute
    /// (φ up to about 0.1).
    Einstein,
    /// No stiffening: X = 1 (a soft or compliant filler, or to isolate εr).
    None,
}

impl Stiffening {
    /// Names as written in the manifest.
    pub const NAMES: [&'static str; 3] = ["guth-gold", "einstein", "none"];

    /// Parse a name.
    pub fn parse(s: &str) -> Option<Stiffening> {
        match s.trim() {
            "guth-gold" => Some(Stiffening::GuthGold),
            "einstein" => Some(Stiffening::Einstein),
            "none" => Some(Stiffening::None),
            _ => None,
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Stiffening::GuthGold => "guth-gold",
            Stiffening::Einstein => "einstein",
            Stiffening::None => "none",
        }
    }

    /// The factor X(φ) on the matrix modulus.
    pub fn factor(self, phi: f64) -> f64 {
        match self {
            Stiffening::GuthGold => 1.0 + 2.5 * phi + 14.1 * phi * phi,
            Stiffening::Einstein => 1.0 + 2.5 * phi,
            Stiffening::None => 1.0,
        }
    }

    /// The largest φ for which the rule is a fair description.
    pub fn valid_to(self) -> f64 {
        match self {
            Stiffening::GuthGold => 0.3,
            Stiffening::Einstein => 0.1,
            Stiffening::None => 1.0,
        }
    }

    /// The rule in words.
    pub fn formula(self) -> &'static str {
        match self {
            Stiffening::GuthGold => "X = 1 + 2.5φ + 14.1φ²",
            Stiffening::Einstein => "X = 1 + 2.5φ",
            Stiffening::None => "X = 1",
        }
    }
}

/// A candidate: its identity, its catalogue properties with provenance, and the
/// constants the simulator runs with.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Name (series and loading).
    pub name: String,
    /// Series name.
    pub series: String,
    /// Matrix name.
    pub matrix: String,
    /// Filler name (None: the matrix alone).
    pub filler: Option<String>,
    /// Loading on the basis.
    pub loading: f64,
    /// Basis of the loading.
    pub basis: Basis,
    /// Filler volume fraction φ.
    pub volume_fraction: f64,
    /// Relative permittivity.
    pub eps_r: Figure,
    /// Small-strain Young's modulus Y = 3μ0 (Pa).
    pub youngs_modulus: Figure,
    /// Loss tangent at the drive frequency.
    pub tan_delta: Figure,
    /// Breakdown field (V/m).
    pub breakdown: Figure,
    /// Density (kg/m³).
    pub density: f64,
    /// Hyperelastic constants.
    pub hyperelastic: HyperelasticPart,
    /// Viscous constants.
    pub viscous: Viscous,
    /// The εr model and the stiffening rule of the series, in words.
    pub rules: String,
    /// What was held or extrapolated, in words.
    pub warnings: Vec<String>,
}

/// A property of a candidate moved by ±1σ ([`Candidate::shifts`]).
#[derive(Debug, Clone)]
pub struct Shift {
    /// The property: `Y` or `εr` (`Eb` too, which enters the state, the limits
    /// and, under `breakdown_fraction`, the drive).
    pub what: &'static str,
    /// The candidate with the property 1σ higher.
    pub up: Candidate,
    /// The candidate with the property 1σ lower; None where that is not
    /// positive (σ ≥ the value: no first-order propagation holds).
    pub down: Option<Candidate>,
}

impl Candidate {
    /// The candidate with each property that has a standard error and reaches the
    /// simulator moved by ±1σ, one at a time, named: `Y` (the hyperelastic and
    /// viscous parts scaled together, the direction the stiffening rule moves
    /// them), `εr` and `Eb`. The figures' first-order standard errors follow from
    /// these by central differences ([`super::figures::Evaluation::spread`]).
    /// tan δ is not moved: it enters only the loss per cycle, linearly, whose
    /// derivative is exact (and β, Fm are closed forms: [`super::figures::catalogue`]).
    pub fn shifts(&self) -> Vec<Shift> {
        let step = |f: &Figure| match (f.value, f.std_error) {
            (Some(v), Some(s)) if s > 0.0 && v.is_finite() => Some((v, s)),
            _ => None,
        };
        let mut out = Vec::new();
        if let Some((y, s)) = step(&self.youngs_modulus) {
            let moved = |sign: f64| {
                let x = 1.0 + sign * s / y;
                let mut c = self.clone();
                c.hyperelastic = HyperelasticPart {
                    ranges: self.hyperelastic.ranges.clone(),
                    ..scaled(&self.hyperelastic, x)
                };
                c.viscous = scaled_viscous(&self.viscous, x);
                c.youngs_modulus.value = Some(y + sign * s);
                c
            };
            out.push(Shift {
                what: "Y",
                up: moved(1.0),
                down: (s < y).then(|| moved(-1.0)),
            });
        }
        type Field = fn(&mut Candidate) -> &mut Figure;
        let figures: [(&'static str, &Figure, Field); 2] = [
            ("εr", &self.eps_r, |c| &mut c.eps_r),
            ("Eb", &self.breakdown, |c| &mut c.breakdown),
        ];
        for (what, figure, field) in figures {
            if let Some((v, s)) = step(figure) {
                let moved = |x: f64| {
                    let mut c = self.clone();
                    field(&mut c).value = Some(x);
                    c
                };
                out.push(Shift {
                    what,
                    up: moved(v + s),
                    down: (s < v).then(|| moved(v - s)),
                });
            }
        }
        out
    }
}

/// Where x lies among the knots of a piecewise-linear table.
enum Place {
    /// On knot i.
    At(usize),
    /// Between knots i and i + 1 (weight of i + 1).
    Between(usize, f64),
    /// Beyond the last knot.
    Beyond,
}

/// Whether two loadings are the same (to 1e-9: a swept loading computed as
/// 0.6·2/6 is the measured 0.2).
pub fn same_loading(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9
}

/// Locate `x` among sorted knots (the first knot is 0 and x ≥ 0).
fn place(knots: &[f64], x: f64) -> Place {
    if let Some(i) = knots.iter().position(|&k| same_loading(k, x)) {
        return Place::At(i);
    }
    match knots.iter().position(|&k| k > x) {
        Some(j) => Place::Between(j - 1, (x - knots[j - 1]) / (knots[j] - knots[j - 1])),
        None => Place::Beyond,
    }
}

/// A loading for names and messages: "20 wt%", "10 vol%".
pub fn loading_label(x: f64, basis: Basis) -> String {
    let unit = match basis {
        Basis::Weight => "wt%",
        Basis::Volume => "vol%",
    };
    format!("{} {unit}", short(100.0 * x))
}

/// The candidate of series `si` at `loading`.
pub fn build(d: &Design, si: usize, loading: f64) -> Result<Candidate> {
    let s = &d.series[si];
    let m = &d.matrices[s.matrix];
    let Some(fi) = s.filler else {
        return Ok(Candidate {
            name: s.name.clone(),
            series: s.name.clone(),
            matrix: m.name.clone(),
            filler: None,
            loading: 0.0,
            basis: s.basis,
            volume_fraction: 0.0,
            eps_r: stated(&m.eps_r, "1"),
            youngs_modulus: youngs(&m.hyperelastic)?,
            tan_delta: stated(&m.tan_delta, "1"),
            breakdown: stated(&m.breakdown, "V/m"),
            density: m.density,
            hyperelastic: m.hyperelastic.value.clone(),
            viscous: m.viscous.value.clone(),
            rules: "matrix alone".into(),
            warnings: m.breakdown.warnings.clone(),
        });
    };
    let f = &d.fillers[fi];
    let phi_of = |x: f64| match s.basis {
        Basis::Volume => x,
        Basis::Weight => volume_fraction(x, f.density, m.density),
    };
    let phi = phi_of(loading);
    let label = loading_label(loading, s.basis);
    let mut warnings = Vec::new();

    // εr: measured, else the model corrected through the measured values.
    let model = |x: f64| eps_model(d, s, phi_of(x), x);
    let model_value = |x: f64| model(x).0;
    let knots: Vec<(f64, f64, &str)> = std::iter::once((0.0, 1.0, ""))
        .chain(s.measured.iter().filter_map(|p| {
            p.eps_r.map(|e| {
                (
                    p.loading,
                    e.value / model_value(p.loading),
                    p.source.as_str(),
                )
            })
        }))
        .collect();
    // relative σ of the measured εr the correction passes through (0 at x = 0,
    // where the model is the matrix's value)
    let eknots: Vec<(f64, f64)> = std::iter::once((0.0, 0.0))
        .chain(s.measured.iter().filter_map(|p| {
            p.eps_r
                .map(|e| (p.loading, e.std_error.unwrap_or(0.0) / e.value))
        }))
        .collect();
    let eps_r = match measured_at(&s.measured, loading, |p| p.eps_r) {
        Some((u, src)) => {
            Figure::new(u.value, "1", Provenance::Stated, src).with_std_error(u.std_error)
        }
        None => {
            let (v, prov, src, sigma) = model(loading);
            let (r, how) = correction(&knots, loading);
            let from_measured = v * r * linear(&eknots, loading);
            let sigma = match (sigma, from_measured > 0.0) {
                (None, false) => None,
                (s, _) => Some((s.unwrap_or(0.0) * r).hypot(from_measured)),
            };
            Figure::new(v * r, "1", prov, format!("{src}{how}")).with_std_error(sigma)
        }
    };

    // Hyperelastic constants: fitted, else the matrix stiffened by the rule and
    // corrected through the fitted composites.
    let mu_m = mu0(&m.hyperelastic.value)?;
    let rule = s.stiffening;
    let hknots = std::iter::once(Ok((0.0, 1.0, "")))
        .chain(s.measured.iter().filter_map(|p| {
            p.hyperelastic.as_ref().map(|h| {
                mu0(&h.value).map(|mu| {
                    (
                        p.loading,
                        mu / (mu_m * rule.factor(phi_of(p.loading))),
                        h.source.as_str(),
                    )
                })
            })
        }))
        .collect::<Result<Vec<_>>>()?;
    // relative σ of μ0 at the knots of the correction (the matrix's at 0)
    let sknots = std::iter::once(Ok((0.0, rel_std_error(&m.hyperelastic)?)))
        .chain(s.measured.iter().filter_map(|p| {
            p.hyperelastic
                .as_ref()
                .map(|h| rel_std_error(h).map(|r| (p.loading, r)))
        }))
        .collect::<Result<Vec<_>>>()?;
    let fitted = s
        .measured
        .iter()
        .find(|p| same_loading(p.loading, loading))
        .and_then(|p| p.hyperelastic.as_ref());
    let (hyperelastic, youngs_modulus) = match fitted {
        Some(h) => (h.value.clone(), youngs(h)?),
        None if loading == 0.0 => (m.hyperelastic.value.clone(), youngs(&m.hyperelastic)?),
        None => {
            let (c, how) = correction(&hknots, loading);
            let scale = rule.factor(phi) * c;
            let part = scaled(&m.hyperelastic.value, scale);
            let y = 3.0 * mu0(&part)?;
            let src = format!(
                "{} {} at φ = {} on the matrix ({}){how}",
                rule.name(),
                rule.formula(),
                short(phi),
                m.hyperelastic.source
            );
            let rel = linear(&sknots, loading);
            let y = Figure::new(y, "Pa", Provenance::Predicted, src)
                .with_std_error((rel > 0.0).then_some(rel * y));
            (part, y)
        }
    };
    if phi > rule.valid_to() {
        warnings.push(format!(
            "{}: {} stiffening used beyond φ = {} (its range)",
            s.name,
            rule.name(),
            rule.valid_to()
        ));
    }
    let viscous = scaled_viscous(&m.viscous.value, mu0(&hyperelastic)? / mu_m);

    // Loss and breakdown: measured, interpolated, or held.
    let tan_delta = interpolated(
        s,
        &m.tan_delta,
        loading,
        "tan δ",
        "1",
        |p| p.tan_delta.map(|u| typed(p, u)),
        &mut warnings,
    );
    let breakdown = interpolated(
        s,
        &m.breakdown,
        loading,
        "breakdown field",
        "V/m",
        |p| p.breakdown.clone(),
        &mut warnings,
    );
    Ok(Candidate {
        name: format!("{} {label}", s.name),
        series: s.name.clone(),
        matrix: m.name.clone(),
        filler: Some(f.name.clone()),
        loading,
        basis: s.basis,
        volume_fraction: phi,
        eps_r,
        youngs_modulus,
        tan_delta,
        breakdown,
        density: phi * f.density + (1.0 - phi) * m.density,
        hyperelastic,
        viscous,
        rules: format!("εr {}, stiffening {}", eps_rule(s), rule.name()),
        warnings,
    })
}

/// The series' εr model in words: the rule, stated or from a composite fit.
fn eps_rule(s: &Series) -> String {
    match &s.permittivity {
        Some(PermittivityModel::Rule { rule, .. }) => format!("{} (stated)", rule.name()),
        Some(PermittivityModel::Composite { mixture, .. }) => {
            format!("{} (composite fit)", mixture.rule.name())
        }
        None => "of the matrix".into(),
    }
}

/// A manifest value as a figure.
fn stated(s: &Stated<f64>, unit: &str) -> Figure {
    Figure::new(s.value, unit, s.provenance, s.source.clone()).with_std_error(s.std_error)
}

/// μ0 of a hyperelastic part.
fn mu0(h: &HyperelasticPart) -> Result<f64> {
    Ok(h.evaluator()?.initial_shear_modulus(&h.params))
}

/// Y = 3μ0 of a stated part.
fn youngs(h: &Stated<HyperelasticPart>) -> Result<Figure> {
    Ok(
        Figure::new(3.0 * mu0(&h.value)?, "Pa", h.provenance, h.source.clone())
            .with_std_error(h.std_error.map(|s| 3.0 * s)),
    )
}

/// The relative standard error of μ0 of a stated part (0 where none is stated).
fn rel_std_error(h: &Stated<HyperelasticPart>) -> Result<f64> {
    h.std_error
        .map_or(Ok(0.0), |s| mu0(&h.value).map(|m| s / m))
}

/// The viscous part with Nv and every arm's modulus and viscosity times `x` (the
/// relaxation times unchanged).
fn scaled_viscous(v: &Viscous, x: f64) -> Viscous {
    Viscous {
        nv_pa_s: v.nv_pa_s * x,
        arms: v
            .arms
            .iter()
            .map(|a| Arm {
                k_pa: a.k_pa * x,
                eta_pa_s: a.eta_pa_s * x,
            })
            .collect(),
    }
}

/// The part with every stress coefficient (unit Pa) times `x`.
fn scaled(h: &HyperelasticPart, x: f64) -> HyperelasticPart {
    let model = h.spec.build().expect("a checked model builds");
    let params = model
        .params()
        .iter()
        .zip(&h.params)
        .map(|(info, &v)| if info.unit == "Pa" { v * x } else { v })
        .collect();
    HyperelasticPart {
        spec: h.spec.clone(),
        params,
        ranges: None,
    }
}

/// The series' εr model at volume fraction φ (loading x): value, provenance, source
/// and, for a composite fit, the standard error its εm, εf (and n) give the value.
fn eps_model(d: &Design, s: &Series, phi: f64, x: f64) -> (f64, Provenance, String, Option<f64>) {
    let m = &d.matrices[s.matrix];
    let f = &d.fillers[s.filler.expect("a filler")];
    match s
        .permittivity
        .as_ref()
        .expect("a filler has a permittivity model")
    {
        PermittivityModel::Rule { .. } if x == 0.0 => (
            m.eps_r.value,
            m.eps_r.provenance,
            m.eps_r.source.clone(),
            m.eps_r.std_error,
        ),
        PermittivityModel::Rule { rule, shape } => (
            rule.eval(m.eps_r.value, f.eps_r.value, phi, *shape),
            Provenance::Predicted,
            format!(
                "{} at φ = {} with εm {} ({}) and εf {} ({})",
                rule.name(),
                short(phi),
                short(m.eps_r.value),
                m.eps_r.source,
                short(f.eps_r.value),
                f.eps_r.source
            ),
            // σ of εm and εf written in the manifest, independent (GUM eq. 10)
            match (m.eps_r.std_error, f.eps_r.std_error) {
                (None, None) => None,
                (sm, sf) => {
                    let g = file::gradient(&[m.eps_r.value, f.eps_r.value], |p| {
                        rule.eval(p[0], p[1], phi, *shape)
                    });
                    Some((g[0] * sm.unwrap_or(0.0)).hypot(g[1] * sf.unwrap_or(0.0)))
                }
            },
        ),
        PermittivityModel::Composite {
            mixture,
            freq_hz,
            file,
            spread,
        } => (
            match s.basis {
                Basis::Weight => mixture.eps_r(x),
                Basis::Volume => {
                    mixture
                        .rule
                        .eval(mixture.eps_matrix, mixture.eps_filler, phi, mixture.shape_n)
                }
            },
            Provenance::Fitted,
            format!(
                "{} fitted at {} Hz in {file} (εm {}, εf {}) at φ = {}",
                mixture.rule.name(),
                short(*freq_hz),
                short(mixture.eps_matrix),
                short(mixture.eps_filler),
                short(phi)
            ),
            {
                let k = if mixture.rule.has_shape() { 3 } else { 2 };
                let theta = [mixture.eps_matrix, mixture.eps_filler, mixture.shape_n];
                let grad = file::gradient(&theta[..k], |p| {
                    let n = p.get(2).copied().unwrap_or(mixture.shape_n);
                    mixture.rule.eval(p[0], p[1], phi, n)
                });
                spread.propagate(&grad)
            },
        ),
    }
}

/// A value typed at a measured point, with the point's line.
fn typed(p: &MeasuredPoint, u: Uncertain) -> Stated<f64> {
    Stated {
        value: u.value,
        std_error: u.std_error,
        provenance: Provenance::Stated,
        source: p.source.clone(),
        warnings: Vec::new(),
    }
}

/// The value of a measured point exactly at `x`, with its source.
fn measured_at(
    points: &[MeasuredPoint],
    x: f64,
    get: impl Fn(&MeasuredPoint) -> Option<Uncertain>,
) -> Option<(Uncertain, String)> {
    points
        .iter()
        .find(|p| same_loading(p.loading, x))
        .and_then(|p| get(p).map(|v| (v, p.source.clone())))
}

/// The piecewise-linear function through (x, y) knots (sorted, the first at 0) at
/// x ≥ 0, held at the last value beyond the last knot.
fn linear(knots: &[(f64, f64)], x: f64) -> f64 {
    let xs: Vec<f64> = knots.iter().map(|k| k.0).collect();
    match place(&xs, x) {
        Place::At(i) => knots[i].1,
        Place::Between(i, w) => knots[i].1 + w * (knots[i + 1].1 - knots[i].1),
        Place::Beyond => knots[knots.len() - 1].1,
    }
}

/// The correction factor at x through knots (loading, factor, source) starting at
/// (0, 1): linear between knots, held beyond the last; with the words for the source.
fn correction(knots: &[(f64, f64, &str)], x: f64) -> (f64, String) {
    if knots.len() < 2 {
        return (1.0, String::new());
    }
    let names = || {
        knots[1..]
            .iter()
            .map(|k| k.2)
            .collect::<Vec<_>>()
            .join("; ")
    };
    let pairs: Vec<(f64, f64)> = knots.iter().map(|k| (k.0, k.1)).collect();
    let r = linear(&pairs, x);
    (
        r,
        format!(
            ", × {} (corrected through the measured {})",
            short(r),
            names()
        ),
    )
}

/// tan δ or the breakdown field at x: measured, interpolated between the measured
/// loadings (the matrix at 0), or held with a warning. A standard uncertainty is
/// carried as the value is: interpolated with weights 1 − w and w of two
/// independent measurements, u = √((1 − w)²u₁² + w²u₂²), or held. The warnings
/// of the values used (a breakdown fit not scaled to the actuator) are the
/// candidate's.
fn interpolated(
    s: &Series,
    matrix: &Stated<f64>,
    x: f64,
    what: &str,
    unit: &str,
    get: impl Fn(&MeasuredPoint) -> Option<Stated<f64>>,
    warnings: &mut Vec<String>,
) -> Figure {
    let knots: Vec<(f64, Stated<f64>)> = std::iter::once((0.0, matrix.clone()))
        .chain(
            s.measured
                .iter()
                .filter_map(|p| get(p).map(|v| (p.loading, v))),
        )
        .collect();
    let xs: Vec<f64> = knots.iter().map(|k| k.0).collect();
    let mut used = |k: &Stated<f64>| {
        for w in &k.warnings {
            if !warnings.contains(w) {
                warnings.push(w.clone());
            }
        }
    };
    match place(&xs, x) {
        Place::At(i) => {
            let k = &knots[i].1;
            used(k);
            Figure::new(k.value, unit, k.provenance, k.source.clone()).with_std_error(k.std_error)
        }
        Place::Between(i, w) => {
            let ((xa, a), (xb, b)) = (&knots[i], &knots[i + 1]);
            used(a);
            used(b);
            let sigma = match (a.std_error, b.std_error) {
                (None, None) => None,
                (sa, sb) => Some(((1.0 - w) * sa.unwrap_or(0.0)).hypot(w * sb.unwrap_or(0.0))),
            };
            Figure::new(
                a.value + w * (b.value - a.value),
                unit,
                Provenance::Predicted,
                format!(
                    "linear in loading between {} at {} ({}) and {} at {} ({})",
                    short(a.value),
                    loading_label(*xa, s.basis),
                    a.source,
                    short(b.value),
                    loading_label(*xb, s.basis),
                    b.source
                ),
            )
            .with_std_error(sigma)
        }
        Place::Beyond => {
            let (xl, last) = &knots[knots.len() - 1];
            used(last);
            let why = match knots.len() {
                1 => format!(
                    "{}: no measured {what} of a composite: held at the matrix's value",
                    s.name
                ),
                _ => format!(
                    "{}: {what} beyond the measured loadings held at its value at {}",
                    s.name,
                    loading_label(*xl, s.basis)
                ),
            };
            warnings.push(why.clone());
            Figure::new(
                last.value,
                unit,
                Provenance::Predicted,
                format!("held: {}", last.source),
            )
            .with_std_error(last.std_error)
            .noted(why)
        }
    }
}
