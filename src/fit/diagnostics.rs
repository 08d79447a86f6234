//! Fit diagnostics: covariance and standard errors from the Jacobian, confidence
//! intervals, correlation and condition number, information criteria, the seed's
//! %RMSE (Eq. 3.28). Drucker stability is [`super::drucker`].

use super::identifiability::{self, Weakness, MAX_CORRELATION, WARN_CORRELATION};
use super::linear::{RowQr, SmallSvd};
use nalgebra::DMatrix;
use statrs::distribution::{ContinuousCDF, StudentsT};
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// The two-sided 95 % Student-t quantile t₀.₉₇₅(ν) (1.96 if statrs refuses ν).
/// Inverting the t distribution's CDF takes microseconds, as long as the rest of a
/// small linear fit; each ν is computed once per process and then looked up.
pub fn t_quantile_975(dof: usize) -> f64 {
    static CACHE: OnceLock<Mutex<HashMap<usize, f64>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(&t) = cache.lock().ok().as_ref().and_then(|c| c.get(&dof)) {
        return t;
    }
    let t = StudentsT::new(0.0, 1.0, dof as f64)
        .map(|t| t.inverse_cdf(0.975))
        .unwrap_or(1.96);
    if let Ok(mut c) = cache.lock() {
        // Bounded: a long run over many sizes keeps at most a few thousand values.
        if c.len() >= 4096 {
            c.clear();
        }
        c.insert(dof, t);
    }
    t
}

/// Parameter uncertainty from the linearised model.
#[derive(Debug, Clone)]
pub struct Uncertainty {
    /// Covariance s²·(JᵀJ)⁻¹ (NaN where not identifiable).
    pub covariance: DMatrix<f64>,
    /// Standard errors (None where not identifiable).
    pub std_error: Vec<Option<f64>>,
    /// Correlation matrix (None where undefined).
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Condition number of the column-normalised Jacobian (∞ if rank deficient).
    pub condition: f64,
    /// Two-sided 95 % Student-t quantile used for the intervals (None if no dof).
    pub t95: Option<f64>,
}

/// Covariance of least-squares estimates: cov = s²·(JᵀJ)⁻¹, s² = RSS/(n − k), with
/// J the Jacobian of the scaled residuals at the optimum (pseudo-inverse by SVD). A
/// Jacobian that cannot be decomposed (a value not finite) leaves every parameter
/// unidentified, with condition number ∞. See [`factor_uncertainty`].
pub fn uncertainty(jac: &DMatrix<f64>, rss: f64) -> Uncertainty {
    factor_uncertainty(&RowQr::of(jac), rss)
}

/// [`uncertainty`] from the triangular factor R of the Jacobian (JᵀJ = RᵀR, see
/// [`RowQr`]): the column-normalised J = Q·R·D⁻¹ has the singular values and right
/// singular vectors of R·D⁻¹ (D the column norms, those of R), so only a k × k SVD
/// ([`SmallSvd`]) is needed however many points there are.
pub fn factor_uncertainty(qr: &RowQr, rss: f64) -> Uncertainty {
    let (n, k) = (qr.rows(), qr.unknowns());
    let mut norm = qr.r_columns();
    let dof = n.saturating_sub(k);
    let mut col = vec![1.0; k];
    for (j, c) in norm.chunks_exact_mut(k.max(1)).enumerate() {
        let s = c.iter().map(|v| v * v).sum::<f64>().sqrt();
        if s > 0.0 {
            col[j] = s;
            c.iter_mut().for_each(|v| *v *= 1.0 / s);
        }
    }
    let t95 = (dof > 0).then(|| t_quantile_975(dof));
    let Some(svd) = SmallSvd::of(&norm, k) else {
        // A Jacobian holding ∞ or NaN (or an empty one) determines nothing.
        return Uncertainty {
            covariance: DMatrix::from_element(k, k, f64::NAN),
            std_error: vec![None; k],
            correlation: vec![vec![None; k]; k],
            condition: f64::INFINITY,
            t95,
        };
    };
    let sv = &svd.sigma;
    let (smax, smin) = (sv[0], sv[k - 1]);
    let condition = if smin > 0.0 {
        smax / smin
    } else {
        f64::INFINITY
    };
    let identifiable = smin > 1e-12 * smax && dof > 0;
    let s2 = if dof > 0 { rss / dof as f64 } else { f64::NAN };
    let mut cov = DMatrix::from_element(k, k, f64::NAN);
    if identifiable {
        for a in 0..k {
            for b in 0..k {
                let mut acc = 0.0;
                for i in 0..k {
                    acc += svd.v(a, i) * svd.v(b, i) / (sv[i] * sv[i]);
                }
                cov[(a, b)] = s2 * acc / (col[a] * col[b]);
            }
        }
    }
    let mut unc = Uncertainty {
        covariance: DMatrix::zeros(0, 0),
        std_error: Vec::new(),
        correlation: Vec::new(),
        condition,
        t95,
    };
    unc.set_covariance(cov);
    unc
}

impl Uncertainty {
    /// Take `cov` as the covariance, with the standard errors (None where a
    /// variance is not finite) and correlations that follow from it.
    pub fn set_covariance(&mut self, cov: DMatrix<f64>) {
        let k = cov.nrows();
        self.std_error = (0..k)
            .map(|i| Some(cov[(i, i)].sqrt()).filter(|v| v.is_finite()))
            .collect();
        let se = &self.std_error;
        self.correlation = (0..k)
            .map(|a| {
                (0..k)
                    .map(|b| match (se[a], se[b]) {
                        (Some(sa), Some(sb)) if sa > 0.0 && sb > 0.0 => {
                            Some(cov[(a, b)] / (sa * sb))
                        }
                        _ => None,
                    })
                    .collect()
            })
            .collect();
        self.covariance = cov;
    }
}

/// The covariance Σ_ab = ρ_ab·σ_a·σ_b of the estimates a fit reports (standard errors
/// σ and correlation matrix ρ), or None when any of them is undefined (a parameter
/// not identifiable: no band can be drawn).
pub fn covariance(
    std_error: &[Option<f64>],
    correlation: &[Vec<Option<f64>>],
) -> Option<DMatrix<f64>> {
    let k = std_error.len();
    if correlation.len() != k {
        return None;
    }
    let mut cov = DMatrix::zeros(k, k);
    for a in 0..k {
        for b in 0..k {
            let rho = match a == b {
                true => 1.0,
                false => correlation[a].get(b).copied().flatten()?,
            };
            cov[(a, b)] = rho * std_error[a]? * std_error[b]?;
        }
    }
    Some(cov)
}

/// The first-order (delta-method) standard deviation of each output of a model
/// y(θ) at the estimate θ̂ with covariance Σ: σᵢ = √(gᵢᵀ Σ gᵢ), gᵢ = ∂yᵢ/∂θ.
///
/// With Σ = Σ_c λ_c v_c v_cᵀ (its eigen-decomposition), gᵢᵀ Σ gᵢ = Σ_c (gᵢ · d_c)²
/// along the one-σ directions d_c = √λ_c v_c, and gᵢ · d_c is the derivative of yᵢ
/// along d_c: a central difference with steps ±10⁻³ d_c (a step far below the
/// uncertainty gives the local slope where the model is smooth; truncation error
/// O(10⁻⁶) relative). So the model is evaluated twice per direction, and only σ² is
/// accumulated: memory three outputs, not one per parameter (10⁶ outputs × 9
/// parameters held 72 MB). A direction with λ ≤ 0 (a fixed parameter, or rounding
/// in a covariance read back from a file) carries no variance. None when the model
/// has no value at a step, or Σ is not finite.
pub fn propagated_std(
    model: impl Fn(&[f64]) -> Option<Vec<f64>>,
    theta: &[f64],
    cov: &DMatrix<f64>,
) -> Option<Vec<f64>> {
    const STEP: f64 = 1e-3;
    if cov.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let eig = nalgebra::SymmetricEigen::new(cov.clone());
    let mut var: Option<Vec<f64>> = None;
    let mut t = theta.to_vec();
    for (c, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda <= 0.0 {
            continue;
        }
        let d = eig.eigenvectors.column(c) * (STEP * lambda.sqrt());
        let at = |t: &mut Vec<f64>, sign: f64| {
            for (j, v) in t.iter_mut().enumerate() {
                *v = theta[j] + sign * d[j];
            }
            model(t)
        };
        let up = at(&mut t, 1.0)?;
        let down = at(&mut t, -1.0)?;
        let var = var.get_or_insert_with(|| vec![0.0; up.len()]);
        for ((s, u), w) in var.iter_mut().zip(&up).zip(&down) {
            *s += ((u - w) / (2.0 * STEP)).powi(2);
        }
    }
    let std: Vec<f64> = match var {
        Some(var) => var.into_iter().map(f64::sqrt).collect(),
        // no direction carries variance: the model at θ̂, exactly
        None => vec![0.0; model(theta)?.len()],
    };
    std.iter().all(|v| v.is_finite()).then_some(std)
}

/// The first-order standard deviation σᵢ = √(gᵢᵀ Σ gᵢ) of each output i of a model
/// with gradients `grads[a][i]` = ∂yᵢ/∂θₐ and parameter covariance Σ (the delta
/// method); None when any is not finite.
pub fn gradient_std(grads: &[Vec<f64>], cov: &DMatrix<f64>) -> Option<Vec<f64>> {
    let k = grads.len();
    let n = grads.first().map_or(0, Vec::len);
    let std = (0..n)
        .map(|i| {
            let mut var = 0.0;
            for a in 0..k {
                for b in 0..k {
                    var += grads[a][i] * cov[(a, b)] * grads[b][i];
                }
            }
            var.max(0.0).sqrt()
        })
        .collect::<Vec<f64>>();
    std.iter().all(|v| v.is_finite()).then_some(std)
}

/// Corrected Akaike and Bayesian information criteria for a least-squares fit with
/// Gaussian errors: AIC = n·ln(RSS/n) + 2k, AICc = AIC + 2k(k+1)/(n−k−1),
/// BIC = n·ln(RSS/n) + k·ln n. AICc is None when n ≤ k + 1.
pub fn information_criteria(rss: f64, n: usize, k: usize) -> (Option<f64>, f64) {
    let nf = n as f64;
    let kf = k as f64;
    let base = nf * (rss.max(f64::MIN_POSITIVE) / nf).ln();
    let aic = base + 2.0 * kf;
    let aicc = (n > k + 1).then(|| aic + 2.0 * kf * (kf + 1.0) / (nf - kf - 1.0));
    (aicc, base + kf * nf.ln())
}

/// The one rule for "identifiable" ([`identifiability::judge`]) applied to every
/// parameter of a least-squares fit, with its findings in words.
#[derive(Debug, Clone, PartialEq)]
pub struct Judgement {
    /// Per parameter: why it is not identifiable (None: it is).
    pub weakness: Vec<Option<Weakness>>,
    /// One sentence per parameter that is not identifiable for its σ/value or its
    /// correlation: its name, σ/value against the limit (and whether its interval
    /// reaches 0) or |ρ| and the partner. A singular information matrix is the
    /// caller's to say once for the fit (no parameter has a σ then).
    pub findings: Vec<String>,
    /// One sentence per pair of identifiable parameters correlated above
    /// [`WARN_CORRELATION`] (and at most [`MAX_CORRELATION`]): each is determined,
    /// their marginal intervals are wide.
    pub warnings: Vec<String>,
}

impl Judgement {
    /// Whether parameter `j` is identifiable by the rule.
    pub fn identifiable(&self, j: usize) -> bool {
        self.weakness.get(j).is_some_and(Option::is_none)
    }
}

/// [`identifiability::judge`] for each parameter `names[j]` = `values[j]` of a fit
/// with uncertainty `unc` (its σ, correlations and Student-t quantile t; 1.96 where
/// it has none). `sign_free[j]`: the law lets the parameter take either sign (a
/// Mooney-Rivlin C01, a Yeoh C20, an Ogden μᵢ or αᵢ), so its 95 % interval θ ± t·σ
/// must also exclude 0 ([`identifiability::limit`]: σ/|θ| ≤ min(0.5, 1/t)).
/// `floor[j]`: the parameter sits at a physical bound its law allows (a modulus at
/// 0 from non-negative least squares), where σ/value is undefined and not a finding:
/// only its correlations are judged. A bound of a search box is the caller's to
/// report (the rule's last point).
pub fn judge(
    names: &[String],
    values: &[f64],
    unc: &Uncertainty,
    sign_free: &[bool],
    floor: &[bool],
) -> Judgement {
    let k = values.len();
    let t = unc.t95.unwrap_or(1.96);
    let rho = |a: usize, b: usize| {
        unc.correlation
            .get(a)
            .and_then(|r| r.get(b).copied().flatten())
    };
    let mut findings = Vec::new();
    let weakness: Vec<Option<Weakness>> = (0..k)
        .map(|j| {
            let sd = unc.std_error[j];
            let rel = match (floor[j], sd) {
                (true, Some(_)) => Some(0.0),
                _ => identifiability::rel_sigma(values[j], sd),
            };
            let limit = identifiability::limit(sign_free[j], t);
            let partners = (0..k).filter(|&b| b != j).filter_map(|b| rho(j, b).map(|c| (b, c)));
            let w = identifiability::judge(rel, limit, partners);
            match w {
                Some(Weakness::Loose(_)) if values[j] == 0.0 => findings.push(format!(
                    "{} is not identifiable from these data: its estimate is 0, which no standard error tells apart from 0",
                    names[j]
                )),
                Some(Weakness::Loose(r)) => findings.push(format!(
                    "{} is not identifiable from these data: σ/value = {r:.2}, above {limit:.2}{}",
                    names[j],
                    if sign_free[j] && r * t >= 1.0 {
                        " (its 95 % interval includes 0)"
                    } else {
                        ""
                    }
                )),
                Some(Weakness::Traded(b, c)) => findings.push(format!(
                    "{} is not identifiable from these data: |ρ| = {:.4} with {} (above {MAX_CORRELATION}): the data pin down their combination, not each",
                    names[j],
                    c.abs(),
                    names[b]
                )),
                Some(Weakness::Singular) | None => {}
            }
            w
        })
        .collect();
    let mut warnings = Vec::new();
    // (a pair with a parameter already found not identifiable is said with it)
    for a in 0..k {
        for b in a + 1..k {
            if weakness[a].is_some() || weakness[b].is_some() {
                continue;
            }
            if let Some(c) =
                rho(a, b).filter(|c| c.abs() > WARN_CORRELATION && c.abs() <= MAX_CORRELATION)
            {
                warnings.push(format!(
                    "{} and {} are correlated ({c:+.4}, |ρ| above {WARN_CORRELATION}): each is determined, but their intervals are wide beside what either would have alone",
                    names[a], names[b]
                ));
            }
        }
    }
    Judgement {
        weakness,
        findings,
        warnings,
    }
}

/// Seed Eq. 3.28: %RMSE = RMSE / (max ŷ − min ŷ)·100, normalised by the reference range.
pub fn rmse_percent(rmse: f64, reference: &[f64]) -> Option<f64> {
    let (lo, hi) = reference
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    (hi > lo).then(|| 100.0 * rmse / (hi - lo))
}

/// The warning for a fit that explains less of the data's variation than their mean
/// (R² < 0, R² = 1 − RSS/Σ(y − ȳ)²): a constant would do better, so no constant of
/// the model can be trusted. Both estimators make it `ill_posed`; `None` when R² ≥ 0.
pub fn worse_than_mean(r2: f64) -> Option<String> {
    (r2 < 0.0).then(|| {
        format!(
            "R² = {r2:.3} < 0: the fit explains less of the stress than its mean value would; the model cannot describe these data (check the columns, their units and signs, and outliers)"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For a linear model y = Aθ the band is exactly √diag(A Σ Aᵀ) (central
    /// differences are exact for it: rounding only, so 1e-9 relative), with a
    /// correlated Σ and with a parameter of zero variance (a fixed one: its direction
    /// carries nothing, the others still do).
    #[test]
    fn propagated_std_of_a_linear_model_is_its_closed_form() {
        let a = DMatrix::from_row_slice(
            4,
            3,
            &[
                1.0, 0.5, -2.0, 0.0, 3.0, 1.0, 2.5, -1.0, 0.25, 1e3, 0.0, 1.0,
            ],
        );
        let theta = [0.3, -1.2, 4.0];
        let model = |t: &[f64]| {
            Some(
                (&a * nalgebra::DVector::from_column_slice(t))
                    .as_slice()
                    .to_vec(),
            )
        };
        let correlated = DMatrix::from_row_slice(
            3,
            3,
            &[0.04, 0.01, -0.02, 0.01, 0.09, 0.0, -0.02, 0.0, 0.25],
        );
        let mut fixed = correlated.clone();
        for k in 0..3 {
            fixed[(1, k)] = 0.0;
            fixed[(k, 1)] = 0.0;
        }
        for cov in [correlated, fixed] {
            let std = propagated_std(model, &theta, &cov).expect("a band");
            let exact = (&a * &cov * a.transpose()).diagonal().map(f64::sqrt);
            for (s, e) in std.iter().zip(exact.iter()) {
                assert!((s - e).abs() <= 1e-9 * e, "{s} against {e}");
            }
        }
        // a covariance that is not finite gives no band
        let nan = DMatrix::from_element(3, 3, f64::NAN);
        assert!(propagated_std(model, &theta, &nan).is_none());
    }
}
