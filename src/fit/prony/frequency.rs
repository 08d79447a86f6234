//! The frequency domain: a Prony series from storage and loss moduli (a DMA sweep or
//! a time–temperature master curve).
//!
//! Model: the generalized Maxwell body (Ferry, *Viscoelastic Properties of Polymers*,
//! 3rd ed., 1980, eq. 3-44 and 3-45; Park & Schapery, Int. J. Solids Struct. 36,
//! 1653–1675, 1999, eq. 8 for its use in interconversion):
//!
//! E′(ω) = E∞ + Σ Eᵢ·ω²τᵢ²/(1 + ω²τᵢ²),  E″(ω) = Σ Eᵢ·ωτᵢ/(1 + ω²τᵢ²),
//!
//! the rows of the Prony core ([`Kernels`]): a storage row has input 1 (the E∞
//! column) and kernel ω²τ²/(1 + ω²τ²), a loss row input 0 and kernel ωτ/(1 + ω²τ²).
//! The estimation is the time domain's ([`super`]): grid NNLS (6 τ a decade by
//! default over the data's 1/ω range widened ×3 at each end), variable projection,
//! joint polish, `terms: N | auto` by AICc among counts whose terms are all
//! identifiable ([`crate::fit::identifiability`]), E∞ ≥ 0 fitted (never forced to 0).
//!
//! **Weighting: E′ leads.** A storage row's residual is relative,
//! (E′_model − E′)/E′, with no floor: E′ > 0 is required, and a master curve's E′
//! spans three to five decades from the rubbery plateau to the glass (a floor at
//! 1 % of the largest E′, as the time domain has for values that cross zero, left
//! the plateau of the shipped curve all but unweighted and its E∞ 50 % high); a loss
//! row's is relative to
//! the complex modulus and scaled by w < 1 (default [`LOSS_WEIGHT`]):
//! w·(E″_model − E″)/|E*|, |E*| = √(E′² + E″²). Where the loss is small against the
//! storage (the glassy and rubbery plateaus, tan δ ≪ 1, where a measured E″ is the
//! least accurate and most often inconsistent with E′ by Kramers–Kronig) a loss row
//! weighs little; in the transition (tan δ ≈ 1), where E″ pins the relaxation
//! times, it counts as a relative error times w/√2. With w = ½ and equal relative
//! noise on both, a loss point weighs at most ⅛ of a storage point in χ²: it informs
//! the τ without pulling E′ off.
//!
//! **Kramers–Kronig check.** A Prony series is causal, so its E′ and E″ are
//! Kramers–Kronig consistent by construction. The check fits E′ alone (the same
//! search, at the term count of the joint fit, started from the joint fit's τ: E′
//! leads the joint fit, so its τ lie in or next to the valley E′ alone has),
//! predicts E″ from that series, and lists the frequency ranges where the measured E″
//! differs from the prediction by more than [`KK_TOLERANCE`] plus three times the
//! storage fit's relative RMS residual (the noise): there the two measured moduli
//! cannot both belong to one linear viscoelastic material (a temperature drift, a
//! compliance correction, a shifted isotherm…).

use super::assess::{self, Assessed};
use super::grid::{self, Grid};
use super::problem::Problem;
use super::select::{self, Selection};
use super::{fmt_s, refine, Kernels, Search, Setup, ShiftCovariance};
use crate::error::{Error, Result};
use crate::fit::{Parameter, SolverReport, Status};
use crate::material::viscoelastic::Prony;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Default weight w of the loss rows (module docs, "Weighting").
pub const LOSS_WEIGHT: f64 = 0.5;

/// Largest relative disagreement of a measured E″ with the E″ that E′ implies that
/// the Kramers–Kronig check lets pass besides the noise: the E″ of a series fitted
/// to E′ alone is the log-derivative of a smoothed curve (E″ ≈ (π/2)·dE′/d ln ω,
/// Booij & Thoone, Rheol. Acta 21, 15–24, 1982), uncertain by a few % at 1 %
/// noise (`tests/prony_frequency.rs` measures ≤ 5 % on consistent data over 7
/// decades); 10 % leaves that margin twice.
pub const KK_TOLERANCE: f64 = 0.1;

/// Most terms a frequency fit may have: a master curve spans 10–25 decades, and a
/// fixed grid of two terms a decade over 15 of them is 30 terms (pyvisco's
/// discretisation, one a decade, is coarser).
pub const MAX_TERMS: usize = 40;

/// The measured complex modulus: E′ and E″ at each angular frequency (SI). Points
/// need not be sorted and a frequency may repeat (overlapping isotherms of a master
/// curve).
#[derive(Debug, Clone, Copy)]
pub struct ComplexModulus<'a> {
    /// Angular frequency ω (rad/s), > 0.
    pub omega_rad_s: &'a [f64],
    /// Storage modulus E′ (Pa), > 0.
    pub storage_pa: &'a [f64],
    /// Loss modulus E″ (Pa), ≥ 0.
    pub loss_pa: &'a [f64],
    /// The uncertainty of the shifts that made a master curve of these points
    /// (`group`: each point's isotherm, in the points' order), carried into the σ
    /// of every parameter; None where ω and the moduli are as measured.
    pub shifts: Option<&'a ShiftCovariance>,
}

/// Settings of a frequency-domain fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrequencySettings {
    /// The Prony search (term count or auto, criterion, grid density, LM limits);
    /// at most [`MAX_TERMS`] terms.
    pub search: Search,
    /// Weight w of the loss rows, in [0, 1] (default [`LOSS_WEIGHT`]); 0 fits E′
    /// alone.
    pub loss_weight: f64,
    /// Run the Kramers–Kronig check (default true).
    pub kramers_kronig: bool,
}

impl Default for FrequencySettings {
    fn default() -> Self {
        FrequencySettings {
            search: Search::default(),
            loss_weight: LOSS_WEIGHT,
            kramers_kronig: true,
        }
    }
}

impl FrequencySettings {
    /// Reject settings that cannot work.
    pub fn check(&self) -> Result<()> {
        self.search.check_terms(MAX_TERMS)?;
        if !(0.0..=1.0).contains(&self.loss_weight) {
            return Err(Error::settings(format!(
                "the loss modulus weight must be in [0, 1], found {}",
                self.loss_weight
            ))
            .with_hint("E′ leads the fit: E″ is weighted by w ≤ 1 (default 0.5)"));
        }
        Ok(())
    }
}

/// One Prony term of a frequency fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrequencyTerm {
    /// Relaxation time τ (s).
    pub tau_s: f64,
    /// Modulus Eᵢ (Pa).
    #[serde(rename = "modulus_Pa")]
    pub modulus_pa: f64,
    /// Standard error of τ (s).
    pub tau_std_s: Option<f64>,
    /// Standard error of Eᵢ (Pa).
    #[serde(rename = "modulus_std_Pa")]
    pub modulus_std_pa: Option<f64>,
    /// Whether the data pin τ and Eᵢ down (the one rule, fit::identifiability).
    pub identifiable: bool,
    /// Whether τ lies in the range the data support, [1/ω_max, 1/ω_min].
    pub supported: bool,
}

/// A frequency range where the measured E″ disagrees with the E″ that the measured
/// E′ implies (Kramers–Kronig).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KkDisagreement {
    /// Lowest and highest angular frequency of the range (rad/s).
    pub omega_rad_s: [f64; 2],
    /// Points of the range.
    pub points: usize,
    /// Measured E″ over the E″ implied by E′ at the point of largest disagreement.
    pub worst_ratio: f64,
}

/// A frequency-domain Prony fit. The σ of every parameter takes the storage and
/// the loss rows each with its own residual variance ([`Kernels::noise_groups`],
/// the sandwich covariance of `assess`): the loss rows' weighted noise is smaller
/// than the storage rows' (module docs, "Weighting"), and one pooled variance left
/// the σ of a parameter set by E′ alone (E∞ at the lowest frequencies) low by a
/// factor 1.35 on the shipped master curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrequencyFit {
    /// Overall status.
    pub status: Status,
    /// E∞ (Pa), ≥ 0.
    #[serde(rename = "long_term_modulus_Pa")]
    pub e_inf_pa: f64,
    /// Its standard error (Pa).
    #[serde(rename = "long_term_modulus_std_Pa")]
    pub e_inf_std_pa: Option<f64>,
    /// Terms, sorted by τ.
    pub terms: Vec<FrequencyTerm>,
    /// Parameters in SI (E_inf, E1…, tau1…) with σ and 95 % intervals.
    pub parameters: Vec<Parameter>,
    /// The range of τ the data support, [1/ω_max, 1/ω_min] (s).
    pub supported_tau_s: [f64; 2],
    /// Weight w of the loss rows.
    pub loss_weight: f64,
    /// RMS relative residual of E′ ((model − E′)/E′).
    pub rel_rmse_storage: f64,
    /// RMS residual of E″ relative to |E*| (unweighted by w).
    pub rel_rmse_loss: f64,
    /// AICc of the weighted objective (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC of the weighted objective.
    pub bic: f64,
    /// Number of (ω, E′, E″) points.
    pub points: usize,
    /// Parameter correlation matrix.
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Condition number of the column-normalised Jacobian.
    pub condition_number: Option<f64>,
    /// Kramers–Kronig disagreements (empty when consistent or not checked).
    pub kramers_kronig: Vec<KkDisagreement>,
    /// Everything the user should know.
    pub warnings: Vec<String>,
    /// How the term count was chosen (auto only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selection: Option<Selection>,
    /// Solver report.
    pub solver: SolverReport,
}

impl FrequencyFit {
    /// The fitted Prony series (Pa, s).
    pub fn prony(&self) -> Result<Prony> {
        let terms: Vec<(f64, f64)> = self.terms.iter().map(|t| (t.tau_s, t.modulus_pa)).collect();
        Prony::new(self.e_inf_pa, &terms)
    }
}

/// The rows of a complex-modulus fit: a storage row (input 1, kernel
/// ω²τ²/(1 + ω²τ²)) or a loss row (input 0, kernel ωτ/(1 + ω²τ²)) at each ω.
#[derive(Debug, Clone)]
pub struct FrequencyKernels {
    omega: Vec<f64>,
    /// Whether each row is a loss row.
    loss: Vec<bool>,
    input: Vec<f64>,
    /// The shifts' uncertainty, by row.
    shifts: Option<ShiftCovariance>,
}

impl FrequencyKernels {
    /// Rows at `omega` (rad/s), loss rows where `loss`, with the shifts' uncertainty
    /// by row.
    fn new(omega: Vec<f64>, loss: Vec<bool>, shifts: Option<ShiftCovariance>) -> FrequencyKernels {
        let input = loss.iter().map(|&l| if l { 0.0 } else { 1.0 }).collect();
        FrequencyKernels {
            omega,
            loss,
            input,
            shifts,
        }
    }
}

impl Kernels for FrequencyKernels {
    const WINDOW: &'static str = "the τ range the data support (1/ω_max … 1/ω_min)";

    fn len(&self) -> usize {
        self.omega.len()
    }
    fn input(&self) -> &[f64] {
        &self.input
    }
    /// Each row alone (nothing carried): with u = ωτ and d = 1 + u², storage
    /// h = u²/d, ∂h/∂τ = 2ωu/d²; loss h = u/d, ∂h/∂τ = ω(1 − u²)/d².
    type Carry = ();

    fn kernel_rows(
        &self,
        taus: &[f64],
        rows: std::ops::Range<usize>,
        _: &mut (),
        h: &mut [f64],
        mut dh: Option<&mut [f64]>,
    ) {
        let len = rows.len();
        let (omega, loss) = (&self.omega[rows.clone()], &self.loss[rows]);
        for (i, &tau) in taus.iter().enumerate() {
            for (k, (&w, &loss)) in omega.iter().zip(loss).enumerate() {
                let u = w * tau;
                let d = 1.0 + u * u;
                let (v, dv) = match loss {
                    true => (u / d, w * (1.0 - u * u) / (d * d)),
                    false => (u * u / d, 2.0 * w * u / (d * d)),
                };
                h[i * len + k] = v;
                if let Some(dh) = dh.as_deref_mut() {
                    dh[i * len + k] = dv;
                }
            }
        }
    }
    /// Storage rows 0, loss rows 1: the loss rows' weighted noise is w·E″/|E*| of
    /// the storage rows' (module docs, "Weighting").
    fn noise_groups(&self) -> Option<Vec<usize>> {
        Some(self.loss.iter().map(|&l| usize::from(l)).collect())
    }
    fn shift_covariance(&self) -> Option<&ShiftCovariance> {
        self.shifts.as_ref()
    }
    fn subsample(&self, idx: &[usize]) -> Option<FrequencyKernels> {
        Some(FrequencyKernels::new(
            idx.iter().map(|&i| self.omega[i]).collect(),
            idx.iter().map(|&i| self.loss[i]).collect(),
            self.shifts.as_ref().map(|s| s.rows(idx)),
        ))
    }
    fn outside_window(name: &str, short: bool, window: (f64, f64)) -> String {
        match short {
            true => format!(
                "{name} is shorter than 1/ω_max ({}): at every measured frequency this term has relaxed, so its τ and modulus are not determined separately",
                fmt_s(window.0)
            ),
            false => format!(
                "{name} is longer than 1/ω_min ({}): at every measured frequency this term has not begun to relax, so its τ, its modulus and E∞ are not determined separately",
                fmt_s(window.1)
            ),
        }
    }
}

/// Check the data: equal lengths, at least 3 points, ω > 0, E′ > 0, E″ ≥ 0, all
/// finite.
fn check(data: &ComplexModulus) -> Result<()> {
    let m = data.omega_rad_s.len();
    if data.storage_pa.len() != m || data.loss_pa.len() != m {
        return Err(Error::settings(format!(
            "{m} frequencies but {} storage and {} loss moduli",
            data.storage_pa.len(),
            data.loss_pa.len()
        )));
    }
    if m < 3 {
        return Err(Error::settings(format!(
            "{m} points cannot determine even a long-term modulus with an uncertainty"
        )));
    }
    let bad = |what: &str, k: usize, v: f64, want: &str| {
        Err(Error::settings(format!(
            "point {}: {what} = {v} must be {want}",
            k + 1
        )))
    };
    if let Some(sh) = data.shifts {
        let g = sh.horizontal.nrows();
        let square = |c: &nalgebra::DMatrix<f64>| c.is_square() && c.nrows() == g;
        if sh.group.len() != m
            || sh.group.iter().any(|&i| i >= g)
            || !square(&sh.horizontal)
            || sh.vertical.as_ref().is_some_and(|v| !square(v))
            || sh.joint().iter().any(|v| !v.is_finite())
        {
            return Err(Error::settings(format!(
                "the shifts' uncertainty must give each of the {m} points one of {g} groups and finite {g} × {g} covariances"
            )));
        }
    }
    for k in 0..m {
        let (w, s, l) = (data.omega_rad_s[k], data.storage_pa[k], data.loss_pa[k]);
        if !(w.is_finite() && w > 0.0) {
            return bad("ω", k, w, "finite and > 0 rad/s");
        }
        if !(s.is_finite() && s > 0.0) {
            return bad("E′", k, s, "finite and > 0 Pa");
        }
        if !(l.is_finite() && l >= 0.0) {
            return bad("E″", k, l, "finite and ≥ 0 Pa");
        }
    }
    Ok(())
}

/// The problem of the data sorted by ω: storage rows (weights 1/E′), then, when
/// w > 0, loss rows (weights w/|E*|); scale the largest E′; window
/// [1/ω_max, 1/ω_min].
fn setup(data: &ComplexModulus, loss_weight: f64) -> Setup<FrequencyKernels> {
    let mut order: Vec<usize> = (0..data.omega_rad_s.len()).collect();
    order.sort_by(|&a, &b| data.omega_rad_s[a].total_cmp(&data.omega_rad_s[b]));
    let omega: Vec<f64> = order.iter().map(|&k| data.omega_rad_s[k]).collect();
    let storage: Vec<f64> = order.iter().map(|&k| data.storage_pa[k]).collect();
    let modulus: Vec<f64> = order
        .iter()
        .map(|&k| data.storage_pa[k].hypot(data.loss_pa[k]))
        .collect();
    let smax = storage.iter().copied().fold(0.0, f64::max);
    let mut rows = omega.clone();
    let mut loss = vec![false; omega.len()];
    let mut y = storage.clone();
    let mut w: Vec<f64> = storage.iter().map(|s| 1.0 / s).collect();
    if loss_weight > 0.0 {
        rows.extend(&omega);
        loss.extend(omega.iter().map(|_| true));
        y.extend(order.iter().map(|&k| data.loss_pa[k]));
        w.extend(modulus.iter().map(|e| loss_weight / e));
    }
    let window = (1.0 / omega[omega.len() - 1], 1.0 / omega[0]);
    let shifts = data.shifts.map(|s| {
        let idx: Vec<usize> = order
            .iter()
            .chain(&order)
            .take(rows.len())
            .copied()
            .collect();
        s.rows(&idx)
    });
    let kern = FrequencyKernels::new(rows, loss, shifts);
    Setup::new(Problem::new(kern, y, w, smax), window, 1.0)
}

/// What the Prony core gives for one setup: the chosen count's assessment, the
/// grid, the selection (auto only) and the notes of the choice.
struct Estimate {
    chosen: Assessed<FrequencyKernels>,
    grid: Grid,
    selection: Option<Selection>,
    notes: Vec<String>,
}

/// The Prony core on a setup: grid, every count, assessment, choice.
fn estimate(setup: &mut Setup<FrequencyKernels>, search: &Search) -> Result<Estimate> {
    let m = setup.prob.len();
    let counts = select::term_counts(search, m)?;
    let grid = grid::grid_stage(setup, search.grid_per_decade)?;
    let fits = refine::fit_counts(setup, &grid, &counts, search)?;
    let mut assessed = assess::assess_all(setup, fits);
    let mut notes = Vec::new();
    let choice = select::choose(&assessed, search, &mut notes);
    Ok(Estimate {
        chosen: assessed.swap_remove(choice.index),
        grid,
        selection: choice.selection,
        notes,
    })
}

/// Fit a Prony series to the complex modulus `data` (module docs: model,
/// weighting, Kramers–Kronig check).
pub fn fit(data: &ComplexModulus, settings: &FrequencySettings) -> Result<FrequencyFit> {
    settings.check()?;
    check(data)?;
    let t0 = Instant::now();
    let mut setup = setup(data, settings.loss_weight);
    let Estimate {
        chosen: a,
        grid,
        selection,
        notes,
    } = estimate(&mut setup, &settings.search)?;
    let kk = match settings.kramers_kronig && settings.loss_weight > 0.0 {
        true => kramers_kronig(data, &settings.search, &a)?,
        false => Vec::new(),
    };
    let seconds = t0.elapsed().as_secs_f64();
    Ok(record(
        &setup, a, &grid, selection, notes, kk, settings, seconds,
    ))
}

/// The fit record of the chosen count `a`.
#[allow(clippy::too_many_arguments)]
fn record(
    setup: &Setup<FrequencyKernels>,
    a: Assessed<FrequencyKernels>,
    grid: &Grid,
    selection: Option<Selection>,
    notes: Vec<String>,
    kk: Vec<KkDisagreement>,
    settings: &FrequencySettings,
    seconds: f64,
) -> FrequencyFit {
    let n = a.tf.n_terms;
    let (si, se) = (&a.si, &a.unc.std_error);
    let parameters = a.parameters();
    let window = setup.window;
    let terms = (0..n)
        .map(|i| FrequencyTerm {
            tau_s: si[1 + n + i],
            modulus_pa: si[1 + i],
            tau_std_s: se[1 + n + i],
            modulus_std_pa: se[1 + i],
            identifiable: a.identifiable[1 + i] && a.identifiable[1 + n + i],
            supported: (window.0..=window.1).contains(&si[1 + n + i]),
        })
        .collect();
    let (status, warnings) = verdict(&a, notes, &kk);
    let (storage, loss) = residuals(setup, &a, settings.loss_weight);
    FrequencyFit {
        status,
        e_inf_pa: si[0],
        e_inf_std_pa: se[0],
        terms,
        parameters,
        supported_tau_s: [window.0, window.1],
        loss_weight: settings.loss_weight,
        rel_rmse_storage: storage,
        rel_rmse_loss: loss,
        aicc: a.aicc,
        bic: a.bic,
        points: setup.prob.kern.loss.iter().filter(|&&l| !l).count(),
        correlation: a.unc.correlation.clone(),
        condition_number: a.unc.condition.is_finite().then_some(a.unc.condition),
        kramers_kronig: kk,
        warnings,
        selection,
        solver: SolverReport {
            method: format!(
                "grid NNLS ({} τ, {}/decade, Lawson–Hanson) + merge/prune + variable projection (bounded Levenberg-Marquardt over ln τᵢ, E∞ and Eᵢ by NNLS), multi-start, then LM over (E∞, Eᵢ, ln τᵢ); E′ relative, E″ relative to |E*| × {}",
                grid.0.len(),
                settings.search.grid_per_decade,
                settings.loss_weight
            ),
            starts: a.tf.starts,
            starts_at_best: a.tf.at_best,
            iterations: a.tf.iterations + grid.2,
            evaluations: a.tf.evaluations,
            seconds,
            termination: a.tf.termination.to_string(),
        },
    }
}

/// RMS relative residual of the storage rows and of the loss rows (relative to
/// |E*|, without the weight w) of the chosen count.
fn residuals(
    setup: &Setup<FrequencyKernels>,
    a: &Assessed<FrequencyKernels>,
    loss_weight: f64,
) -> (f64, f64) {
    let Ok(prony) = Prony::new(
        a.si[0],
        &(0..a.tf.n_terms)
            .map(|i| (a.si[1 + a.tf.n_terms + i], a.si[1 + i]))
            .collect::<Vec<_>>(),
    ) else {
        return (f64::NAN, f64::NAN);
    };
    let (prob, kern) = (&setup.prob, &setup.prob.kern);
    let (mut ss, mut sl, mut ns, mut nl) = (0.0, 0.0, 0, 0);
    for k in 0..prob.len() {
        let (e1, e2) = prony.storage_loss(kern.omega[k]);
        let r = match kern.loss[k] {
            true => prob.w[k] / loss_weight * (e2 - prob.y[k]),
            false => prob.w[k] * (e1 - prob.y[k]),
        };
        match kern.loss[k] {
            true => (sl, nl) = (sl + r * r, nl + 1),
            false => (ss, ns) = (ss + r * r, ns + 1),
        }
    }
    (
        (ss / ns.max(1) as f64).sqrt(),
        (sl / nl.max(1) as f64).sqrt(),
    )
}

/// Status and warnings of the chosen count: the choice's notes, its problems and
/// warnings, the Kramers–Kronig disagreements.
fn verdict(
    a: &Assessed<FrequencyKernels>,
    notes: Vec<String>,
    kk: &[KkDisagreement],
) -> (Status, Vec<String>) {
    let mut status = Status::Ok;
    let mut warnings = Vec::new();
    for w in notes {
        status.escalate(Status::Warning);
        warnings.push(w);
    }
    for (s, w) in a.problems.iter().chain(&a.warnings) {
        status.escalate(*s);
        warnings.push(w.clone());
    }
    for d in kk {
        status.escalate(Status::Warning);
        warnings.push(format!(
            "Kramers–Kronig: over ω = {:.4e}…{:.4e} rad/s ({} points) the measured E″ is up to {:.2} × the E″ that the measured E′ implies; E′ and E″ there are not of one linear viscoelastic material (temperature drift, compliance correction, a misplaced isotherm): the fit follows E′",
            d.omega_rad_s[0], d.omega_rad_s[1], d.points, d.worst_ratio
        ));
    }
    (status, warnings)
}

/// The Kramers–Kronig check (module docs): E″ of a series fitted to E′ alone
/// (the count of the joint fit `joint`, searched from its τ) against the measured
/// E″, sorted by ω; ranges of two or more consecutive points beyond
/// [`KK_TOLERANCE`] + 3 × the storage fit's relative RMS residual.
fn kramers_kronig(
    data: &ComplexModulus,
    search: &Search,
    joint: &Assessed<FrequencyKernels>,
) -> Result<Vec<KkDisagreement>> {
    let storage_only = setup(data, 0.0);
    let n = joint.tf.n_terms;
    let start = joint.tf.p[1 + n..].to_vec();
    let levels = refine::Levels::new(&storage_only.prob);
    let tf = refine::fit_from(&storage_only, &levels, n, &[start], search);
    let a = assess::assess(&storage_only, tf);

    let n = a.tf.n_terms;
    let terms: Vec<(f64, f64)> = (0..n).map(|i| (a.si[1 + n + i], a.si[1 + i])).collect();
    let prony = Prony::new(a.si[0], &terms)?;
    let limit = KK_TOLERANCE + 3.0 * a.rel_rmse;
    let mut order: Vec<usize> = (0..data.omega_rad_s.len()).collect();
    order.sort_by(|&p, &q| data.omega_rad_s[p].total_cmp(&data.omega_rad_s[q]));
    let mut out = Vec::new();
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut close = |run: &mut Vec<(f64, f64)>| {
        if run.len() >= 2 {
            let worst = run
                .iter()
                .map(|r| r.1)
                .max_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()))
                .expect("two points");
            out.push(KkDisagreement {
                omega_rad_s: [run[0].0, run[run.len() - 1].0],
                points: run.len(),
                worst_ratio: worst,
            });
        }
        run.clear();
    };
    for &k in &order {
        let w = data.omega_rad_s[k];
        let implied = prony.storage_loss(w).1;
        let ratio = data.loss_pa[k] / implied;

        match implied > 0.0 && (ratio - 1.0).abs() > limit {
            true => run.push((w, ratio)),
            false => close(&mut run),
        }
    }
    close(&mut run);
    Ok(out)
}
