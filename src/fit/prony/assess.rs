//! Stage 4: what a term fit is worth: statistics, information criteria, the σ of
//! every SI parameter, and the problems that keep `auto` from taking it.

use super::problem::{Need, Problem};
use super::refine::TermFit;
use super::{fmt_s, param_names, Kernels, Setup, ShiftCovariance};
use crate::fit::linear::RowQr;
use crate::fit::{diagnostics, Parameter, Status};
use nalgebra::{DMatrix, DVector};

/// Diagnostics of one term fit: statistics, uncertainty in SI, problems found.
pub struct Assessed<K: Kernels> {
    /// The term fit.
    pub tf: TermFit<K>,
    /// SI parameters: [E∞, E₁…, τ₁…].
    pub si: Vec<f64>,
    /// Their uncertainty.
    pub unc: diagnostics::Uncertainty,
    /// RMSE of the unweighted residuals (Pa).
    pub rmse: f64,
    /// RMS of the weighted (scaled) residuals.
    pub rel_rmse: f64,
    /// Fraction of the data explained, 1 − ‖r‖²/‖w·y‖², against zero stress.
    pub explained: f64,
    /// Lag-1 autocorrelation of the scaled residuals in time order: ≈ 0 (±1/√n) for
    /// noise, near 1 for a misfit the model leaves systematically.
    pub lag1: f64,
    /// R² of the unweighted residuals.
    pub r2: f64,
    /// AICc (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC.
    pub bic: f64,
    /// Problems that make the count ineligible for auto (and raise the status).
    pub problems: Vec<(Status, String)>,
    /// Softer warnings.
    pub warnings: Vec<(Status, String)>,
    /// Per parameter ([E∞, E₁…, τ₁…]): whether the data pin it down by the one rule
    /// (fit::identifiability) and it is not at a bound of the τ search.
    pub identifiable: Vec<bool>,
}

impl<K: Kernels> Assessed<K> {
    /// The SI parameters (E_inf, E1…, tau1…) with σ, 95 % interval and whether
    /// each is identifiable. Every parameter is ≥ 0 by its law: an interval reaching
    /// below 0 is clipped there (it loses no value the parameter can take).
    pub fn parameters(&self) -> Vec<Parameter> {
        param_names(self.tf.n_terms)
            .into_iter()
            .zip(&self.si)
            .zip(&self.unc.std_error)
            .zip(&self.identifiable)
            .map(|((((name, unit), &v), se), &identifiable)| Parameter {
                name,
                value: v,
                unit: unit.to_string(),
                std_error: *se,
                ci95: se
                    .zip(self.unc.t95)
                    .map(|(s, t)| [(v - t * s).max(0.0), v + t * s]),
                identifiable: Some(identifiable),
            })
            .collect()
    }
}

/// Stage 4 for one term count: residual statistics, information criteria and the
/// uncertainty of the SI parameters, and the [`problems`] found.
pub fn assess<K: Kernels>(setup: &Setup<K>, mut tf: TermFit<K>) -> Assessed<K> {
    let prob = &mut tf.problem;
    let n = tf.n_terms;
    let m = prob.len();
    let k = 1 + 2 * n;
    let mut r = DVector::zeros(m);
    let mut pred = vec![0.0; m];
    let reach = prob.residuals_model_reach(&tf.p, r.as_mut_slice(), &mut pred);
    let finite = r.iter().all(|v| v.is_finite());
    let rss = r.norm_squared();
    let s = prob.scale * setup.unit;
    let mut si = vec![tf.p[0] * s];
    si.extend((0..n).map(|i| tf.p[1 + i] * s));
    si.extend((0..n).map(|i| tf.p[1 + n + i].exp()));
    // Jacobian with respect to the SI parameters: column factors
    let columns: Vec<f64> = (0..k)
        .map(|c| match c <= n {
            true => 1.0 / s,
            false => 1.0 / si[c],
        })
        .collect();
    let groups = prob
        .kern
        .noise_groups()
        .and_then(|g| group_scales(&r, &g, k).map(|s| (g, s)));
    let kern = prob.kern.clone();
    let shifts = kern.shift_covariance();
    let (mut unc, bread, jac_finite) = match groups {
        Some((g, scales)) => group_sandwich(prob, &tf.p, &columns, g, &scales),
        None => {
            let (qr, finite) = factor(prob, &tf.p, &columns, None);
            let dof = m.saturating_sub(k) as f64;
            let bread = shifts.map(|_| diagnostics::factor_uncertainty(&qr, dof).covariance);
            (diagnostics::factor_uncertainty(&qr, rss), bread, finite)
        }
    };
    let mut finite = finite && jac_finite;
    if let (Some(sh), Some(bread)) = (shifts, bread) {
        let (added, shift_finite) = with_shifts(prob, &tf.p, &columns, &bread, sh);
        unc.set_covariance(&unc.covariance + added);
        finite &= shift_finite;
    }
    // the count waits for the others' assessments before the choice: its kept
    // kernels are of no further use (10⁵ points, counts 1–6: ≈ 10 MB less at the peak)
    prob.release_kernels();
    let y: &[f64] = &prob.y;
    let nf = m as f64;
    let mean = y.iter().sum::<f64>() / nf;
    let ss_res: f64 = pred.iter().zip(y).map(|(p, y)| (p - y).powi(2)).sum();
    let ss_tot: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    // Against zero stress (all moduli 0, which every series contains), in the fit's
    // own weighting.
    let null: f64 = y
        .iter()
        .zip(prob.w.iter())
        .map(|(y, w)| (y * w).powi(2))
        .sum();
    let lag1 = if rss > 0.0 {
        r.iter()
            .zip(r.iter().skip(1))
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / rss
    } else {
        0.0
    };
    let (aicc, bic) = diagnostics::information_criteria(rss, m, k);

    let (problems, warnings, identifiable) = problems(setup, &tf, &si, &reach, &unc, finite, m);
    Assessed {
        tf,
        si,
        unc,
        rmse: (ss_res / nf).sqrt(),
        rel_rmse: (rss / nf).sqrt(),
        explained: 1.0 - rss / null,
        lag1,
        r2: if ss_tot > 0.0 {
            1.0 - ss_res / ss_tot
        } else {
            f64::NAN
        },
        aicc,
        bic,
        problems,
        warnings,
        identifiable,
    }
}

/// The Jacobian at `p` a block of rows at a time ([`Problem::pass`],
/// [`Problem::jacobian_block`]): `f(first row, rows, block)` with the block's
/// columns end to end. Whether every value was finite.
fn jacobian_pass<K: Kernels>(
    prob: &mut Problem<K>,
    p: &[f64],
    mut f: impl FnMut(usize, usize, &[f64]),
) -> bool {
    let k = 1 + 2 * prob.n_terms;
    let mut block = Vec::new();
    let mut finite = true;
    let taus = prob.taus(p);
    prob.pass(&taus, Need::Derivatives, |prob, b| {
        let len = b.rows.len();
        block.resize(k * len, 0.0);
        prob.jacobian_block(p, b, &mut block);
        finite &= block.iter().all(|v| v.is_finite());
        f(b.rows.start, len, &block);
    });
    finite
}

/// The factor R of the Jacobian at `p` with respect to the SI parameters (column
/// c times `columns[c]`) and, with noise groups (`groups`: each row's group and a
/// scale per group), each row divided by its group's scale, its rows pushed a block
/// at a time in one pass over the rows ([`Problem::jacobian_block`],
/// [`RowQr::push`]): the factor [`diagnostics::uncertainty`] takes of the whole
/// m × (2N + 1) matrix, the same bits, without forming it (at 10⁶ points 104 MB for
/// six terms). Whether every value was finite.
fn factor<K: Kernels>(
    prob: &mut Problem<K>,
    p: &[f64],
    columns: &[f64],
    groups: Option<&(Vec<usize>, Vec<f64>)>,
) -> (RowQr, bool) {
    let (m, k) = (prob.len(), columns.len());
    let mut qr = RowQr::with_rows(k, m);
    let mut row = vec![0.0; k];
    let finite = jacobian_pass(prob, p, |start, len, block| {
        for q in 0..len {
            for (c, v) in row.iter_mut().enumerate() {
                *v = block[c * len + q] * columns[c];
            }
            if let Some((g, scales)) = groups {
                let f = 1.0 / scales[g[start + q]];
                row.iter_mut().for_each(|v| *v *= f);
            }
            qr.push(&row, 0.0);
        }
    });
    (qr, finite)
}

/// The residual scale of each noise group, s_g² = RSS_g/(m_g − k·m_g/m) (the
/// degrees of freedom shared in proportion to the rows), [`group_sandwich`]'s
/// variances. None (one pooled variance) where a group has no degrees of freedom
/// or no residual.
fn group_scales(r: &DVector<f64>, groups: &[usize], k: usize) -> Option<Vec<f64>> {
    let m = r.len();
    let count = groups.iter().copied().max().map_or(0, |g| g + 1);
    let mut sum = vec![0.0; count];
    let mut rows = vec![0usize; count];
    for (g, v) in groups.iter().zip(r.iter()) {
        sum[*g] += v * v;
        rows[*g] += 1;
    }
    let s: Vec<f64> = (0..count)
        .map(|g| {
            let dof = rows[g] as f64 * (1.0 - k as f64 / m as f64);
            (sum[g] / dof).sqrt()
        })
        .collect();
    s.iter().all(|s| s.is_finite() && *s > 0.0).then_some(s)
}

/// The uncertainty of a fit whose rows fall in noise groups of their own variances
/// s_g² ([`group_scales`]) while the fit weighs every row alike: the least-squares
/// estimate's covariance is then the sandwich
///
/// C = A⁻¹ B A⁻¹,  A = JᵀJ,  B = Σ_g s_g² J_gᵀJ_g
///
/// (Huber, Proc. 5th Berkeley Symp. 1, 221–233, 1967; White, Econometrica 48,
/// 817–838, 1980, with the variance modelled per group instead of per row; Seber &
/// Wild, *Nonlinear Regression*, 1989, §2.1.4 for (Σ_g J_gᵀJ_g/s_g²)⁻¹, the
/// covariance of the estimate that would weigh each group by 1/s_g², which the fit
/// is not: that one was 1.5–1.7× too small for a DMA fit's terms, whose loss rows
/// the fit weighs by w < 1 though their noise is smaller, tests/dma.rs). A and its
/// rank test, condition number and t quantile are [`diagnostics::factor_uncertainty`]'s
/// (s² = 1); B is the factor of the rows times s_g ([`factor`] divides by the scales
/// it is given: 1/s_g). Whether every value of J was finite.
fn group_sandwich<K: Kernels>(
    prob: &mut Problem<K>,
    p: &[f64],
    columns: &[f64],
    groups: Vec<usize>,
    scales: &[f64],
) -> (diagnostics::Uncertainty, Option<DMatrix<f64>>, bool) {
    let k = columns.len();
    let (qa, finite_a) = factor(prob, p, columns, None);
    let inverse = (groups, scales.iter().map(|s| 1.0 / s).collect());
    let (qb, finite_b) = factor(prob, p, columns, Some(&inverse));
    let dof = qa.rows().saturating_sub(k);
    let mut unc = diagnostics::factor_uncertainty(&qa, dof as f64);
    let rb = qb.r();
    let bread = unc.covariance.clone();
    let cov = &bread * (rb.transpose() * &rb) * &bread;
    unc.set_covariance(cov);
    (unc, Some(bread), finite_a && finite_b)
}

/// What the uncertain shifts `sh` of the rows' groups add to the covariance of the
/// estimate ([`Kernels::shift_covariance`]): at the optimum
/// of ½‖r(p; s)‖² the estimate moves with the shifts s as ∂p/∂s = −A⁻¹JᵀD (the
/// implicit function theorem, A = JᵀJ the unscaled `bread`, J the Jacobian in SI
/// `columns`, D = ∂r/∂s), so it gains G Σ_s Gᵀ, G = A⁻¹JᵀD and Σ_s the shifts'
/// covariance (the delta method; the shifts' errors taken as independent of the
/// residuals' noise, which is what the fit leaves of the data, not what the
/// overlaps that made the shifts hold). A row of group g with abscissa ω has
/// kernels of ω·a_g·τ, so ∂r/∂log10 a_g = ln 10 · Σᵢ ∂r/∂ln τᵢ; its value divided
/// by b_g makes its weighted residual w·model/b_g − w·y/b_g with w ∝ b_g (a relative
/// weight), so ∂r/∂log10 b_g = ln 10 · w·model. Over the rows a block at a time
/// ([`Problem::pass`]). Whether every value was finite.
fn with_shifts<K: Kernels>(
    prob: &mut Problem<K>,
    p: &[f64],
    columns: &[f64],
    bread: &DMatrix<f64>,
    sh: &ShiftCovariance,
) -> (DMatrix<f64>, bool) {
    let (k, n) = (columns.len(), prob.n_terms);
    let gh = sh.horizontal.nrows();
    let gv = sh.vertical.as_ref().map_or(0, |v| v.nrows());
    let mut jtd = DMatrix::zeros(k, gh + gv);
    let ln10 = std::f64::consts::LN_10;
    let finite = jacobian_pass(prob, p, |start, len, block| {
        for q in 0..len {
            let g = sh.group[start + q];
            let dh = ln10 * (0..n).map(|i| block[(1 + n + i) * len + q]).sum::<f64>();
            let dv = ln10 * (0..=n).map(|c| block[c * len + q] * p[c]).sum::<f64>();
            for c in 0..k {
                let j = block[c * len + q] * columns[c];
                jtd[(c, g)] += j * dh;
                if gv > 0 {
                    jtd[(c, gh + g)] += j * dv;
                }
            }
        }
    });
    let gain = bread * jtd;
    (&gain * sh.joint() * gain.transpose(), finite)
}

/// Findings about a fit, each with the status it raises.
type Findings = Vec<(Status, String)>;

/// Largest weighted change a term may make to every row and still be negligible:
/// 0.1 % where the residuals are relative.
pub const NEGLIGIBLE_REACH: f64 = 1e-3;

/// The terms' problems into `problems`: negligible (a `reach`
/// ([`crate::fit::prony::problem::Problem::reach`]) of at most
/// [`NEGLIGIBLE_REACH`]: judged row by row, not against E0, since a master curve's
/// modulus spans decades and a term of 0.02 % of the glassy E0 may carry the whole
/// rubbery plateau's relaxation), at a bound of the τ search (`at_bound`), outside
/// the window the data support, within a factor 1.25 of the next.
fn term_problems<K: Kernels>(
    setup: &Setup<K>,
    si: &[f64],
    reach: &[f64],
    at_bound: &[bool],
    problems: &mut Findings,
) {
    let n = reach.len();
    for i in 0..n {
        let tau = si[1 + n + i];
        let name = format!("τ{} = {}", i + 1, fmt_s(tau));
        if reach[i] <= NEGLIGIBLE_REACH {
            problems.push((
                Status::IllPosed,
                format!("term {} ({name}) is negligible (it changes the fitted curve by at most 0.1 % anywhere in the data): a term too many for these data", i + 1),
            ));
        } else if at_bound[i] {
            problems.push((
                Status::IllPosed,
                format!("{name} ran to its bound: the data do not determine it"),
            ));
        } else if tau < setup.window.0 || tau > setup.window.1 {
            problems.push((
                Status::IllPosed,
                K::outside_window(&name, tau < setup.window.0, setup.window),
            ));
        }
    }
    for i in 1..n {
        let ratio = si[1 + n + i] / si[n + i];
        if ratio < 1.25 {
            problems.push((
                Status::IllPosed,
                format!(
                    "τ{} and τ{} are within a factor {ratio:.2}: two terms describe one relaxation",
                    i,
                    i + 1
                ),
            ));
        }
    }
}

/// What makes a term fit ineligible for `auto` (and raises its status), and softer
/// warnings: a search that did not converge, a model not finite at the data, terms
/// that are negligible, at a bound, outside the sampled window or within a factor
/// 1.25 of each other, too few points, a parameter that is not identifiable by the
/// one rule (fit::identifiability; E∞ at its physical bound 0, or with an interval
/// reaching it, is judged by its
/// correlations only, and said as a one-sided interval); and per parameter whether
/// it is identifiable. `reach`: each term's ([`Problem::reach`]).
fn problems<K: Kernels>(
    setup: &Setup<K>,
    tf: &TermFit<K>,
    si: &[f64],
    reach: &[f64],
    unc: &diagnostics::Uncertainty,
    finite: bool,
    m: usize,
) -> (Findings, Findings, Vec<bool>) {
    let n = tf.n_terms;
    let k = 1 + 2 * n;
    let mut problems = Vec::new();
    let mut warnings = Vec::new();
    if let Some(w) = tf.termination.shortfall() {
        problems.push((Status::NotConverged, w));
    }
    if !finite {
        problems.push((
            Status::NotConverged,
            "the model is not finite at some data points".into(),
        ));
    }
    // E∞ at the bound 0 its law allows, or with a 95 % interval that reaches it (the
    // non-negative least squares hold it at or next to 0): judged by its
    // correlations only, its interval one-sided
    let t = unc.t95.unwrap_or(1.96);
    let at_floor = unc.std_error[0].is_some_and(|sd| si[0] - t * sd <= 0.0);
    let (lo, hi) = (setup.bounds.0.exp(), setup.bounds.1.exp());
    let at_bound: Vec<bool> = (0..n)
        .map(|i| si[1 + n + i] <= lo * 1.0001 || si[1 + n + i] >= hi / 1.0001)
        .collect();
    term_problems(setup, si, reach, &at_bound, &mut problems);
    if m <= k + 1 {
        problems.push((
            Status::IllPosed,
            format!("{m} points for {k} parameters: no degrees of freedom left"),
        ));
    } else if unc.std_error.iter().any(Option::is_none) {
        problems.push((
            Status::IllPosed,
            format!(
                "parameters not identifiable from these data (condition number {:.2e})",
                unc.condition
            ),
        ));
    } else {
        if unc.condition > 1e8 {
            warnings.push((
                Status::Warning,
                format!(
                    "ill-conditioned: condition number {:.2e}; the parameters are poorly determined individually",
                    unc.condition
                ),
            ));
        }
        if at_floor {
            warnings.push((
                Status::Warning,
                format!(
                    "E∞ = {} is at its physical bound 0 within its 95 % interval (the data show no equilibrium modulus); its interval is one-sided, [0, {}]",
                    crate::report::format::si(si[0], "Pa"),
                    crate::report::format::si(si[0] + t * unc.std_error[0].unwrap_or(f64::NAN), "Pa")
                ),
            ));
        }
    }
    // The one rule for "identifiable" (fit::identifiability) for every parameter
    // (E∞, Eᵢ, τᵢ: none may change sign); E∞ at or next to the bound 0 its law allows
    // and is judged by its correlations only.
    let names: Vec<String> = param_names(n).into_iter().map(|(name, _)| name).collect();
    let mut floor = vec![false; k];
    floor[0] = at_floor;
    let judgement = diagnostics::judge(&names, si, unc, &vec![false; k], &floor);
    if unc.std_error.iter().all(Option::is_some) && m > k + 1 {
        problems.extend(
            judgement
                .findings
                .iter()
                .map(|w| (Status::IllPosed, w.clone())),
        );
        warnings.extend(
            judgement
                .warnings
                .iter()
                .map(|w| (Status::Warning, w.clone())),
        );
    }
    let identifiable = (0..k)
        .map(|j| judgement.identifiable(j) && !(j > n && at_bound[j - 1 - n]))
        .collect();
    (problems, warnings, identifiable)
}

/// [`assess`] of every term fit, in parallel.
pub fn assess_all<K: Kernels>(setup: &Setup<K>, fits: Vec<TermFit<K>>) -> Vec<Assessed<K>> {
    use rayon::prelude::*;
    fits.into_par_iter().map(|f| assess(setup, f)).collect()
}
