//! Composite series: εr of each sample (see [`super::permittivity`]), weight →
//! volume fractions, mixing rules fitted to εr(φ) at each frequency and ranked by
//! AICc, the effective filler permittivity each rule implies, and the check of a
//! claimed increase ("which rule and which fraction basis can explain it").
//!
//! Each rule is fitted in log space: parameters ln εm, ln εf (and ln n for Yamada),
//! residuals ln ε_rule(φi) − ln εi (relative errors, since εr spans decades), by the
//! bounded Levenberg–Marquardt of [`super::lm`] from several starts.

use super::diagnostics::{information_criteria, uncertainty};
use super::lm::{self, LeastSquares, LmSettings};
use super::permittivity::{self, same_freq, worst, Input, SamplePermittivity};
use super::{Parameter, Status};
use crate::error::{Error, Result};
use crate::io::lcr;
use crate::io::manifest::Manifest;
use crate::material::check::{fmt_g, PERMITTIVITY};
use crate::material::dielectric::{volume_fraction, weight_fraction, MixingRule, Pair};
use crate::rank::manifest::TAN_DELTA;
use crate::units::{count_product, MAX_POINTS};
use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::Normal;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Schema tag of composite fit files.
pub const SCHEMA: &str = crate::material::file::COMPOSITE_SCHEMA;

/// Upper bound of the fitted filler permittivity: a rule that needs more saturates.
pub const EPS_FILLER_MAX: f64 = 1e7;

/// Basis of a filler fraction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// Mass of filler over mass of composite.
    Weight,
    /// Volume of filler over volume of composite (what mixing rules need).
    Volume,
}

impl std::fmt::Display for Basis {
    /// The name the JSON uses (`weight`, `volume`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Basis::Weight => "weight",
            Basis::Volume => "volume",
        })
    }
}

/// A phase of the composite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Phase {
    /// Name.
    pub name: String,
    /// Density (kg/m³), when given.
    #[serde(rename = "density_kg_per_m3")]
    pub density: Option<f64>,
    /// Nominal relative permittivity, when given.
    pub eps_r: Option<f64>,
}

/// The fraction of one sample on both bases.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FractionRow {
    /// Sample name.
    pub name: String,
    /// Fraction as given.
    pub fraction: f64,
    /// Basis as given.
    pub basis: Basis,
    /// Filler volume fraction φ used by the mixing rules.
    pub volume_fraction: f64,
    /// Filler weight fraction (None without densities).
    pub weight_fraction: Option<f64>,
}

/// One mixing rule fitted at one frequency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RuleFit {
    /// The rule.
    pub rule: MixingRule,
    /// εm, εf (and Yamada's n), with standard errors and 95 % intervals.
    pub parameters: Vec<Parameter>,
    /// Correlation of the parameters' estimates (of their logarithms, which the
    /// search fits: to first order the same as of the values); None where undefined.
    #[serde(default)]
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Effective filler permittivity the rule implies.
    pub eps_filler_eff: f64,
    /// RMS relative error (%).
    pub rms_rel_pct: f64,
    /// AICc (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC.
    pub bic: f64,
    /// AICc (BIC where undefined) minus the best at this frequency.
    pub delta: f64,
    /// Status of this fit.
    pub status: Status,
    /// Warnings of this fit.
    pub warnings: Vec<String>,
    /// LM iterations over all starts.
    pub iterations: usize,
    /// Why the best search stopped.
    pub termination: String,
}

/// One data point of a frequency fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FractionPoint {
    /// Filler volume fraction.
    pub volume_fraction: f64,
    /// Measured εr.
    pub eps_r: f64,
    /// Its standard uncertainty (None, null: no tolerance stated, unknown).
    pub eps_r_std: Option<f64>,
}

/// The rules fitted at one frequency, best first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrequencyFit {
    /// Frequency (Hz).
    #[serde(rename = "freq_Hz")]
    pub freq_hz: f64,
    /// Data at this frequency.
    pub data: Vec<FractionPoint>,
    /// Fits ranked by AICc (BIC where AICc is undefined).
    pub rules: Vec<RuleFit>,
}

/// How a rule did over all frequencies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RuleSummary {
    /// The rule.
    pub rule: MixingRule,
    /// Frequencies at which it ranked first with a usable (not blocking) fit.
    pub best_at: usize,
    /// Median ΔAICc over the frequencies.
    pub median_delta: f64,
    /// Range of the effective filler permittivity over the frequencies.
    pub eps_filler_eff_range: [f64; 2],
    /// Frequencies at which its fit was not usable (blocking status).
    pub unusable_at: usize,
}

/// What one rule predicts for a claim on one basis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RuleReading {
    /// The rule.
    pub rule: MixingRule,
    /// Increase (%) the rule predicts with the nominal filler permittivity.
    pub predicted_increase_pct: f64,
    /// Filler permittivity the rule needs to give exactly the claim (None: no
    /// εf ≤ 1e9 reaches it).
    pub eps_filler_needed: Option<f64>,
    /// The claim is reached with εf at or below the nominal value.
    pub explains: bool,
}

/// A claim read on one basis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BasisReading {
    /// Basis.
    pub basis: Basis,
    /// Filler volume fraction on this reading.
    pub volume_fraction: f64,
    /// Each rule's prediction.
    pub rules: Vec<RuleReading>,
}

/// A claimed increase of εr at a filler fraction, checked against the rules.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClaimCheck {
    /// Fraction as claimed.
    pub fraction: f64,
    /// Claimed increase over the matrix (%).
    pub increase_pct: f64,
    /// Basis the claim states (None: not stated, both are read).
    pub basis_stated: Option<Basis>,
    /// Matrix εr used.
    pub eps_matrix: f64,
    /// Nominal (bulk) filler εr used.
    pub eps_filler_nominal: f64,
    /// The readings.
    pub readings: Vec<BasisReading>,
    /// The answer in words.
    pub verdict: String,
}

/// Inputs and settings of a composite fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompositeProvenance {
    /// Manifest path.
    pub manifest: String,
    /// Its SHA-256.
    pub sha256: String,
    /// Permittivity settings.
    pub settings: permittivity::Settings,
}

/// A composite series: what `dea-fit composite --json` prints and the fit file holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompositeFit {
    /// Schema tag.
    pub schema: String,
    /// dea-fit version.
    pub tool_version: String,
    /// Series name.
    pub name: String,
    /// Matrix.
    pub matrix: Phase,
    /// Filler.
    pub filler: Phase,
    /// Fractions of each sample.
    pub fractions: Vec<FractionRow>,
    /// Each sample's permittivity.
    pub samples: Vec<SamplePermittivity>,
    /// Mixing-rule fits per common frequency.
    pub fits: Vec<FrequencyFit>,
    /// Rules over all frequencies, best first.
    pub summary: Vec<RuleSummary>,
    /// Claims checked.
    pub claims: Vec<ClaimCheck>,
    /// Worst status.
    pub status: Status,
    /// What the user should know.
    pub warnings: Vec<String>,
    /// Inputs and settings.
    pub provenance: CompositeProvenance,
}

struct RuleProblem<'a> {
    rule: MixingRule,
    phi: &'a [f64],
    ln_eps: Vec<f64>,
}

impl RuleProblem<'_> {
    fn k(&self) -> usize {
        if self.rule.has_shape() {
            3
        } else {
            2
        }
    }

    fn residuals(&self, p: &[f64], r: &mut DVector<f64>) -> bool {
        let (em, ef) = (p[0].exp(), p[1].exp());
        let n = p.get(2).map(|v| v.exp()).unwrap_or(3.0);
        for (i, (&phi, &le)) in self.phi.iter().zip(&self.ln_eps).enumerate() {
            let e = self.rule.eval(em, ef, phi, n);
            if !(e > 0.0 && e.is_finite()) {
                return false;
            }
            r[i] = e.ln() - le;
        }
        true
    }
}

impl LeastSquares for RuleProblem<'_> {
    fn dims(&self) -> (usize, usize) {
        (self.phi.len(), self.k())
    }

    /// Residuals; the Jacobian by central differences in the log parameters
    /// (step 1e-6: the rules are smooth, truncation error ~1e-12).
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        if !self.residuals(p, r) {
            return false;
        }
        if let Some(j) = jac {
            let n = self.phi.len();
            let (mut rp, mut rm) = (DVector::zeros(n), DVector::zeros(n));
            let mut q = p.to_vec();
            for c in 0..p.len() {
                let h = 1e-6;
                q[c] = p[c] + h;
                let okp = self.residuals(&q, &mut rp);
                q[c] = p[c] - h;
                let okm = self.residuals(&q, &mut rm);
                q[c] = p[c];
                if !(okp && okm) {
                    return false;
                }
                for i in 0..n {
                    j[(i, c)] = (rp[i] - rm[i]) / (2.0 * h);
                }
            }
        }
        true
    }
}

/// Fit one rule to εr(φ) (all εr > 0). `None` when there are too few points
/// (n ≤ k).
pub fn fit_rule(rule: MixingRule, phi: &[f64], eps: &[f64]) -> Option<RuleFit> {
    let mut prob = RuleProblem {
        rule,
        phi,
        ln_eps: eps.iter().map(|e| e.ln()).collect(),
    };
    let (n, k) = prob.dims();
    if n <= k {
        return None;
    }
    let i0 = (0..n)
        .min_by(|&a, &b| phi[a].total_cmp(&phi[b]))
        .expect("n > k ≥ 2");
    let em0 = eps[i0].clamp(1.0, 1e4).ln();
    let bounds: Vec<(f64, f64)> = [
        (0.0, 1e4f64.ln()),
        (0.0, EPS_FILLER_MAX.ln()),
        (0.1f64.ln(), 1e4f64.ln()),
    ][..k]
        .to_vec();
    let settings = LmSettings {
        max_iterations: 300,
        ..LmSettings::default()
    };
    let mut best: Option<lm::LmResult> = None;
    let mut iterations = 0;
    for ef in [10.0f64, 100.0, 1e3, 1e4] {
        for shape in if k == 3 {
            vec![1.0f64, 3.0, 10.0]
        } else {
            vec![3.0]
        } {
            let x0 = [em0, ef.ln(), shape.ln()];
            let res = lm::minimize(&mut prob, &x0[..k], &bounds, &settings);
            iterations += res.iterations;
            if res.cost.is_finite() && best.as_ref().is_none_or(|b| res.cost < b.cost) {
                best = Some(res);
            }
        }
    }
    let best = best?;
    let p = &best.x;
    let mut r = DVector::zeros(n);
    let mut jac = DMatrix::zeros(n, k);
    prob.eval(p, &mut r, Some(&mut jac));
    let rss = r.norm_squared();
    let unc = uncertainty(&jac, rss);
    let (aicc, bic) = information_criteria(rss, n, k);
    let names = [("eps_matrix", "1"), ("eps_filler", "1"), ("shape_n", "1")];
    let parameters: Vec<Parameter> = (0..k)
        .map(|j| {
            let v = p[j].exp();
            let se = unc.std_error[j];
            Parameter {
                name: names[j].0.into(),
                value: v,
                unit: names[j].1.into(),
                std_error: se.map(|s| v * s),
                ci95: se
                    .zip(unc.t95)
                    .map(|(s, t)| [(p[j] - t * s).exp(), (p[j] + t * s).exp()]),
                identifiable: None,
            }
        })
        .collect();
    let mut warnings = Vec::new();
    let mut status = Status::Ok;
    if let Some(w) = best.termination.shortfall() {
        status = Status::NotConverged;
        warnings.push(w);
    }
    for (j, &(lo, hi)) in bounds.iter().enumerate() {
        if j == 0 {
            continue;
        }
        let span = hi - lo;
        if (p[j] - lo).abs() < 1e-6 * span || (hi - p[j]).abs() < 1e-6 * span {
            status = worst(status, Status::IllPosed);
            warnings.push(if j == 1 && (hi - p[j]).abs() < 1e-6 * span {
                format!(
                    "εf ran to its bound {EPS_FILLER_MAX:.0e}: the rule saturates below the measured increase and cannot explain it"
                )
            } else {
                format!(
                    "{} ran to its bound ({:.4}): not determined by these data",
                    names[j].0,
                    p[j].exp()
                )
            });
        }
    }
    if status == Status::Ok && unc.std_error.iter().any(Option::is_none) {
        status = Status::IllPosed;
        warnings.push(format!(
            "parameters not identifiable (condition number {:.2e})",
            unc.condition
        ));
    }
    Some(RuleFit {
        rule,
        eps_filler_eff: p[1].exp(),
        parameters,
        correlation: unc.correlation,
        rms_rel_pct: 100.0 * (rss / n as f64).sqrt(),
        aicc,
        bic,
        delta: 0.0,
        status,
        warnings,
        iterations,
        termination: best.termination.to_string(),
    })
}

/// Fit every rule at one frequency and rank them (AICc, or BIC where undefined;
/// fits with a blocking status go last).
pub fn fit_frequency(freq_hz: f64, data: Vec<FractionPoint>) -> FrequencyFit {
    let phi: Vec<f64> = data.iter().map(|d| d.volume_fraction).collect();
    let eps: Vec<f64> = data.iter().map(|d| d.eps_r).collect();
    let mut rules: Vec<RuleFit> = MixingRule::ALL
        .iter()
        .filter_map(|&r| fit_rule(r, &phi, &eps))
        .collect();
    let score = |f: &RuleFit| f.aicc.unwrap_or(f.bic);
    rules.sort_by(|a, b| {
        a.status
            .is_blocking()
            .cmp(&b.status.is_blocking())
            .then(score(a).total_cmp(&score(b)))
    });
    // Δ against the best usable rule; where none is usable, against the best of all
    // (the ranking stays readable, and every row says `ill_posed`).
    let best_of = |usable: bool| {
        rules
            .iter()
            .filter(|f| !usable || !f.status.is_blocking())
            .map(score)
            .fold(f64::INFINITY, f64::min)
    };
    let best = match best_of(true) {
        b if b.is_finite() => b,
        _ => best_of(false),
    };
    for f in &mut rules {
        f.delta = score(f) - best;
    }
    FrequencyFit {
        freq_hz,
        data,
        rules,
    }
}

/// Rules over all frequencies, most often best first.
pub fn summarise(fits: &[FrequencyFit]) -> Vec<RuleSummary> {
    let mut out: Vec<RuleSummary> = MixingRule::ALL
        .iter()
        .filter_map(|&rule| {
            let of: Vec<&RuleFit> = fits
                .iter()
                .filter_map(|f| f.rules.iter().find(|r| r.rule == rule))
                .collect();
            if of.is_empty() {
                return None;
            }
            let mut d: Vec<f64> = of.iter().map(|r| r.delta).collect();
            d.sort_by(f64::total_cmp);
            let ef = of.iter().map(|r| r.eps_filler_eff);
            Some(RuleSummary {
                rule,
                best_at: fits
                    .iter()
                    .filter(|f| {
                        f.rules
                            .first()
                            .is_some_and(|r| r.rule == rule && !r.status.is_blocking())
                    })
                    .count(),
                median_delta: d[d.len() / 2],
                eps_filler_eff_range: [
                    ef.clone().fold(f64::INFINITY, f64::min),
                    ef.fold(f64::NEG_INFINITY, f64::max),
                ],
                unusable_at: of.iter().filter(|r| r.status.is_blocking()).count(),
            })
        })
        .collect();
    out.sort_by(|a, b| {
        b.best_at
            .cmp(&a.best_at)
            .then(a.median_delta.total_cmp(&b.median_delta))
    });
    out
}

/// The rules a claim is checked against: every rule without a free shape (Yamada's
/// n can be tuned to any increase, so it tests nothing).
pub const CLAIM_RULES: [MixingRule; 5] = [
    MixingRule::MaxwellGarnett,
    MixingRule::Bruggeman,
    MixingRule::Lichtenecker,
    MixingRule::Looyenga,
    MixingRule::JayasundereSmith,
];

/// Check a claimed increase of εr over the matrix at a filler fraction: for each
/// basis (the stated one, or both when unstated; weight needs both densities) and
/// each rule of [`CLAIM_RULES`], the increase the rule predicts with the nominal
/// filler εr and the filler εr it would need.
pub fn check_claim(
    fraction: f64,
    increase_pct: f64,
    basis: Option<Basis>,
    matrix: &Phase,
    filler: &Phase,
) -> Result<ClaimCheck> {
    let (Some(em), Some(ef)) = (matrix.eps_r, filler.eps_r) else {
        return Err(
            Error::settings("checking a claim needs the nominal εr of matrix and filler")
                .with_hint("set eps_r under [matrix] and [filler] in the manifest"),
        );
    };
    if !(0.0..1.0).contains(&fraction) || increase_pct <= -100.0 {
        return Err(Error::settings(format!(
            "a claim needs a fraction in [0, 1) and an increase above -100 %, found {fraction} and {increase_pct} %"
        )));
    }
    let target = em * (1.0 + increase_pct / 100.0);
    let mut readings = Vec::new();
    let mut skipped = None;
    for b in [Basis::Weight, Basis::Volume] {
        if basis.is_some_and(|s| s != b) {
            continue;
        }
        let phi = match b {
            Basis::Volume => fraction,
            Basis::Weight => match (filler.density, matrix.density) {
                (Some(rf), Some(rm)) => volume_fraction(fraction, rf, rm),
                _ => {
                    skipped = Some("the weight reading needs both densities");
                    continue;
                }
            },
        };
        let rules = CLAIM_RULES
            .iter()
            .map(|&rule| {
                let needed = rule.filler_for(em, phi, 3.0, target);
                RuleReading {
                    rule,
                    predicted_increase_pct: 100.0 * (rule.eval(em, ef, phi, 3.0) / em - 1.0),
                    eps_filler_needed: needed,
                    explains: needed.is_some_and(|n| n <= ef),
                }
            })
            .collect();
        readings.push(BasisReading {
            basis: b,
            volume_fraction: phi,
            rules,
        });
    }
    if readings.is_empty() {
        return Err(Error::settings(format!(
            "the claim cannot be read: {}",
            skipped.unwrap_or("no basis")
        ))
        .with_hint("give density under [matrix] and [filler]"));
    }
    let mut parts = Vec::new();
    for r in &readings {
        let yes: Vec<String> = r
            .rules
            .iter()
            .filter(|x| x.explains)
            .map(|x| {
                format!(
                    "{} (needs εf ≈ {:.0})",
                    x.rule.name(),
                    x.eps_filler_needed.unwrap_or(f64::NAN)
                )
            })
            .collect();
        let nearest = r.rules.iter().filter(|x| !x.explains).max_by(|a, b| {
            a.predicted_increase_pct
                .total_cmp(&b.predicted_increase_pct)
        });
        let b = match r.basis {
            Basis::Weight => "weight",
            Basis::Volume => "volume",
        };
        let mut s = format!(
            "as {b} fraction (φ = {:.4}): {}",
            r.volume_fraction,
            if yes.is_empty() {
                "no standard rule explains it".to_string()
            } else {
                format!("explained by {}", yes.join(", "))
            }
        );
        if let Some(n) = nearest {
            s.push_str(&format!(
                "; closest other: {} +{:.0} %{}",
                n.rule.name(),
                n.predicted_increase_pct,
                n.eps_filler_needed
                    .map(|e| format!(" (would need εf ≈ {e:.0})"))
                    .unwrap_or_else(|| " (unreachable at any εf)".into())
            ));
        }
        parts.push(s);
    }
    Ok(ClaimCheck {
        fraction,
        increase_pct,
        basis_stated: basis,
        eps_matrix: em,
        eps_filler_nominal: ef,
        readings,
        verdict: format!(
            "+{increase_pct} % at {fraction} with εm = {em}, εf = {ef}: {}",
            parts.join("; ")
        ),
    })
}

/// Fit a whole series: read and analyse every sample (in parallel; `on_done` per
/// file), build the fractions, fit the rules at every frequency common to all
/// samples, and check the manifest's claims.
pub fn fit_series(m: &Manifest, on_done: &(dyn Fn() + Sync)) -> Result<CompositeFit> {
    m.settings.check()?;
    let inputs: Vec<Input> = m
        .samples
        .iter()
        .map(|s| Input {
            path: s.file.clone(),
            name: s.name.clone(),
            geometry: Ok(s.geometry),
            geometry_from: format!("manifest {}", m.path.display()),
        })
        .collect();
    let run = permittivity::analyse_batch(&inputs, &m.lcr, &m.settings, on_done)?;
    if let Some(f) = run.failed.first() {
        return Err(Error::settings(format!(
            "sample file {} could not be used: {}",
            f.file, f.error
        ))
        .with_hint("fix or remove that sample in the manifest"));
    }
    let mut warnings = run.warnings.clone();
    let mut status = run.status;
    let fractions: Vec<FractionRow> = m
        .samples
        .iter()
        .map(|s| FractionRow {
            name: s.name.clone(),
            fraction: s.fraction,
            basis: s.basis,
            volume_fraction: s.volume_fraction,
            weight_fraction: match s.basis {
                Basis::Weight => Some(s.fraction),
                Basis::Volume => m
                    .filler
                    .density
                    .zip(m.matrix.density)
                    .map(|(rf, rm)| weight_fraction(s.fraction, rf, rm)),
            },
        })
        .collect();
    // Frequencies present in every sample.
    let samples = run.samples;
    let common: Vec<f64> = samples
        .first()
        .map(|s0| {
            s0.points
                .iter()
                .map(|p| p.freq_hz)
                .filter(|&f| {
                    samples
                        .iter()
                        .all(|s| s.points.iter().any(|p| same_freq(p.freq_hz, f)))
                })
                .collect()
        })
        .unwrap_or_default();
    let fits: Vec<FrequencyFit> = if samples.len() < 3 {
        if !samples.is_empty() {
            warnings.push(format!(
                "{} sample(s): at least 3 fractions are needed to fit a mixing rule",
                samples.len()
            ));
            status = worst(status, Status::Warning);
        }
        Vec::new()
    } else {
        if common.is_empty() {
            return Err(Error::settings(
                "the samples share no frequency: mixing rules are fitted per frequency",
            )
            .with_hint("measure every sample on the same frequency list"));
        }
        common
            .par_iter()
            .map(|&f| {
                let data = samples
                    .iter()
                    .zip(&fractions)
                    .map(|(s, fr)| {
                        let p = s
                            .points
                            .iter()
                            .find(|p| same_freq(p.freq_hz, f))
                            .expect("common frequency");
                        FractionPoint {
                            volume_fraction: fr.volume_fraction,
                            eps_r: p.eps_r.max(f64::MIN_POSITIVE),
                            eps_r_std: p.eps_r_std,
                        }
                    })
                    .collect();
                fit_frequency(f, data)
            })
            .collect()
    };
    let summary = summarise(&fits);
    // The series is only as good as its usable fits: ill-posed when no rule is usable
    // at any frequency, a warning when some frequencies have none.
    let unusable = fits
        .iter()
        .filter(|f| f.rules.iter().all(|r| r.status.is_blocking()))
        .count();
    if !fits.is_empty() && unusable == fits.len() {
        status = worst(status, Status::IllPosed);
        warnings.push(format!(
            "no mixing rule is usable at any of the {} frequencies (every fit is ill_posed or not_converged): the series does not determine the rules' constants",
            fits.len()
        ));
    } else if unusable > 0 {
        status = worst(status, Status::Warning);
        warnings.push(format!(
            "no mixing rule is usable at {unusable} of {} frequencies",
            fits.len()
        ));
    }
    let claims = m
        .claims
        .iter()
        .map(|c| check_claim(c.fraction, c.increase_pct, c.basis, &m.matrix, &m.filler))
        .collect::<Result<Vec<_>>>()?;
    Ok(CompositeFit {
        schema: SCHEMA.into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        name: m.name.clone(),
        matrix: m.matrix.clone(),
        filler: m.filler.clone(),
        fractions,
        samples,
        fits,
        summary,
        claims,
        status,
        warnings,
        provenance: CompositeProvenance {
            manifest: m.path.display().to_string(),
            sha256: m.sha256.clone(),
            settings: m.settings,
        },
    })
}

/// Parameters of a synthetic series (the `[synthetic]` table of a manifest).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Synthetic {
    /// Mixing rule that generates εr(φ).
    pub rule: MixingRule,
    /// Matrix εr at 100 Hz.
    pub eps_matrix: f64,
    /// Change of the matrix εr per decade of frequency (absolute).
    pub eps_matrix_per_decade: f64,
    /// Effective filler εr at 100 Hz.
    pub eps_filler: f64,
    /// Relative change of the filler εr per decade (e.g. -0.05).
    pub eps_filler_per_decade: f64,
    /// Yamada's n (only for `rule = "yamada"`).
    #[serde(default = "three")]
    pub shape: f64,
    /// Matrix loss tangent.
    pub tan_delta_matrix: f64,
    /// Loss tangent of pure filler (tan δ is interpolated linearly in φ).
    pub tan_delta_filler: f64,
    /// Relative noise (1 σ, %) on Cp and on D.
    pub noise_pct: f64,
    /// Random seed (ChaCha8; sample i uses seed + i).
    pub seed: u64,
    /// Lowest frequency (Hz).
    pub freq_min: f64,
    /// Highest frequency (Hz).
    pub freq_max: f64,
    /// Points per decade.
    pub points_per_decade: usize,
    /// Stray capacitance added to every reading (pF).
    pub stray_pf: f64,
}

fn three() -> f64 {
    3.0
}

/// Most rows `composite --generate` makes in all (samples × frequencies): as many
/// as one file of `synth` ([`MAX_POINTS`]), since the exports are held in memory
/// until every one is made (about 40 bytes a row); a measured series has a few
/// hundred.
pub const GENERATED_ROWS: usize = MAX_POINTS;

/// The largest noise_pct of a synthetic series: at a relative σ of 20 % a negative
/// capacitance is a 5σ event, already one in 3·10⁶ rows.
pub const MAX_NOISE_PCT: f64 = 20.0;

impl Synthetic {
    /// The series at frequency `f` (Hz) and filler volume fraction `phi`: (εm, εf,
    /// ε′ of the rule, tan δ) with εm(f) = εm + s_m·log10(f/100 Hz),
    /// εf(f) = εf·(1 + s_f·log10(f/100 Hz)) and tan δ linear in φ.
    pub fn at(&self, f: f64, phi: f64) -> (f64, f64, f64, f64) {
        let dec = (f / 100.0).log10();
        let em = self.eps_matrix + self.eps_matrix_per_decade * dec;
        let ef = self.eps_filler * (1.0 + self.eps_filler_per_decade * dec);
        let tan = self.tan_delta_matrix + (self.tan_delta_filler - self.tan_delta_matrix) * phi;
        (em, ef, self.rule.eval(em, ef, phi, self.shape), tan)
    }

    /// Check the table and the series it GENERATES for `samples` (name, φ): every
    /// number finite, the noise in [0, [`MAX_NOISE_PCT`]] %, the stray ≥ 0, the
    /// sweep's count in range ([`lcr::log_sweep_points`]) and samples × points
    /// within [`GENERATED_ROWS`], and at every sample and frequency εm, εf and the
    /// rule's ε′ plausible relative permittivities ([`PERMITTIVITY`]) and tan δ a
    /// plausible loss tangent: finite inputs can still make a negative or infinite
    /// εr (eps_filler_per_decade = −0.3 turns εf negative above 2 MHz). Returns the
    /// sweep's point count, or the key to blame and why.
    pub fn check(
        &self,
        samples: &[(&str, f64)],
    ) -> std::result::Result<usize, (&'static str, String)> {
        let numbers = [
            ("eps_matrix", self.eps_matrix),
            ("eps_matrix_per_decade", self.eps_matrix_per_decade),
            ("eps_filler", self.eps_filler),
            ("eps_filler_per_decade", self.eps_filler_per_decade),
            ("shape", self.shape),
            ("tan_delta_matrix", self.tan_delta_matrix),
            ("tan_delta_filler", self.tan_delta_filler),
            ("noise_pct", self.noise_pct),
            ("freq_min", self.freq_min),
            ("freq_max", self.freq_max),
            ("stray_pf", self.stray_pf),
        ];
        if let Some((k, v)) = numbers.iter().find(|(_, v)| !v.is_finite()) {
            return Err((k, format!("{k} must be a finite number, found {v}")));
        }
        if !(0.0..=MAX_NOISE_PCT).contains(&self.noise_pct) {
            return Err((
                "noise_pct",
                format!(
                    "noise_pct must be in [0, {MAX_NOISE_PCT}] %, found {} (a larger relative σ makes negative capacitances)",
                    fmt_g(self.noise_pct)
                ),
            ));
        }
        if self.stray_pf < 0.0 {
            return Err((
                "stray_pf",
                format!("stray_pf must be ≥ 0, found {}", fmt_g(self.stray_pf)),
            ));
        }
        let n = lcr::log_sweep_points(self.freq_min, self.freq_max, self.points_per_decade)
            .map_err(|e| ("points_per_decade", format!("points_per_decade: {e}")))?;
        count_product(
            &[("samples", samples.len()), ("frequencies", n)],
            GENERATED_ROWS,
            "rows of all the exports, held in memory until every one is made",
        )
        .map_err(|e| ("points_per_decade", format!("points_per_decade: {e}")))?;
        let freqs = lcr::log_frequencies(self.freq_min, self.freq_max, self.points_per_decade)
            .map_err(|e| ("points_per_decade", e.to_string()))?;
        for &(name, phi) in samples {
            for &f in &freqs {
                let (em, ef, eps, tan) = self.at(f, phi);
                let bad = [
                    ("eps_matrix", "the matrix εr", em, &PERMITTIVITY),
                    ("eps_filler", "the filler εr", ef, &PERMITTIVITY),
                    ("rule", "the mixture's εr", eps, &PERMITTIVITY),
                    ("tan_delta_filler", "tan δ", tan, &TAN_DELTA),
                ]
                .into_iter()
                .find_map(|(key, what, v, dom)| dom.check(what, v).err().map(|e| (key, e)));
                if let Some((key, e)) = bad {
                    return Err((
                        key,
                        format!(
                            "the generated series is not physical at sample '{name}' (φ = {phi:.4}), {f} Hz: {}; {}",
                            e.msg, e.hint
                        ),
                    ));
                }
            }
        }
        Ok(n)
    }
}

/// Export format of a synthetic sample file.
pub const SYNTH_FORMATS: [&str; 5] = [
    "csv-cp-d",
    "csv-cs-rs",
    "csv-cp-rp",
    "e4990a-z-theta",
    "hioki",
];

/// Generate the export files of a manifest's synthetic series: (path, contents) for
/// every sample. ε′ from the rule with εm(f) = εm + s_m·log10(f/100 Hz) and
/// εf(f) = εf·(1 + s_f·log10(f/100 Hz)); tan δ linear in φ; Cp = ε′·ε0·A/d + stray,
/// each with Gaussian relative noise.
pub fn synthesize(m: &Manifest) -> Result<Vec<(std::path::PathBuf, String)>> {
    let Some(s) = &m.synthetic else {
        return Err(Error::settings("the manifest has no [synthetic] table")
            .with_hint("add [synthetic] with rule, eps_matrix, eps_filler, noise_pct, seed, ..."));
    };
    let phis: Vec<(&str, f64)> = m
        .samples
        .iter()
        .map(|x| (x.name.as_str(), x.volume_fraction))
        .collect();
    s.check(&phis).map_err(|(key, e)| {
        Error::settings(format!("[synthetic] {key}: {e}"))
            .with_hint("set [synthetic] so that every generated value is physical")
    })?;
    let freqs = lcr::log_frequencies(s.freq_min, s.freq_max, s.points_per_decade)?;
    let noise = Normal::new(0.0, s.noise_pct / 100.0)
        .map_err(|e| Error::settings(format!("noise_pct: {e}")))?;
    let mut out = Vec::new();
    for (i, sample) in m.samples.iter().enumerate() {
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed + i as u64);
        let phi = sample.volume_fraction;
        let pts = lcr::synthetic_points(
            &freqs,
            sample.geometry.empty_capacitance(),
            s.stray_pf * 1e-12,
            &noise,
            &mut rng,
            |f| {
                let (_, _, eps, tan) = s.at(f, phi);
                (eps, tan)
            },
        );
        let text = match sample.format.as_deref().unwrap_or("csv-cp-d") {
            "csv-cp-d" => lcr::write_csv(Pair::CpD, &pts)?,
            "csv-cs-rs" => lcr::write_csv(Pair::CsRs, &pts)?,
            "csv-cp-rp" => lcr::write_csv(Pair::CpRp, &pts)?,
            "e4990a-z-theta" => lcr::write_e4990a(Pair::ZTheta, &pts)?,
            "hioki" => lcr::write_hioki(&pts)?,
            other => {
                return Err(Error::settings(format!(
                    "sample '{}': unknown synthetic format '{other}'",
                    sample.name
                ))
                .with_hint(format!("use one of {}", SYNTH_FORMATS.join(", "))))
            }
        };
        out.push((sample.file.clone(), text));
    }
    Ok(out)
}
