//! What the trace pins down: standard errors, intervals and correlations from the
//! Jacobian at the optimum, and, for every constant it does not pin down, the reason
//! in words.
//!
//! Covariance in search coordinates: cov_x = s²·(JᵀJ)⁻¹ with s² = 2·cost/(N − p)
//! ([`crate::fit::diagnostics::uncertainty`]). For a log-searched constant the
//! relative standard error is σ_x and the 95 % interval θ·exp(±t·σ_x) (asymmetric,
//! always positive); for a linear one σ_θ = s·σ_x and θ ± t·σ_θ.
//!
//! The covariance is that of every free constant free: the constants the trace does
//! not pin down (flagged loose or traded) and, as a local linearisation, those that
//! ended at a bound of their search stay in it, so no interval is silently
//! conditional on a value the trace did not fix. Only where that information is
//! singular for a constant inside its bounds is its σ taken from the problem with the
//! bounded constants held, and its estimate then names them (`conditional_on`).
//! Where the linearisation fails the interval is the profile likelihood's
//! ([`super::profile`]); the estimate says which kind it holds (`interval`).
//!
//! **Not identifiable** ([`identifiability`], the one rule) when σ_θ/|θ| >
//! [`MAX_REL_SIGMA`] (of the equivalent symmetric interval for a profile interval),
//! or |ρ| > [`MAX_CORRELATION`] with another free constant, or the information matrix
//! is singular, or its profile interval is one-sided, or the constant ended at a
//! bound of its search (the bound holds it, not the trace: it gets no σ or
//! interval, and is reported as held by the bound, not as fixed there). The weakest
//! direction of the column-normalised Jacobian (its smallest singular vector) names
//! the constants that trade off against each other; the known cases get their own
//! explanation (small strains and higher polynomial terms, εr against the moduli
//! without capacitance, an arm slower than the trace, unresolved damping).

use super::params::{Constant, Role, Space};
use crate::fit::diagnostics::uncertainty;
use crate::fit::identifiability::{self, rel_sigma};
use crate::report::format::si;
use nalgebra::DMatrix;
use serde::Serialize;

pub use crate::fit::identifiability::{MAX_CORRELATION, MAX_REL_SIGMA, WARN_CORRELATION};

/// One identified constant, as printed and written (`--json` `parameters`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// Name.
    pub name: String,
    /// Value (SI).
    pub value: f64,
    /// SI unit.
    pub unit: String,
    /// Standard error (SI): the linearised one for a Wald interval, that of the
    /// equivalent symmetric interval ([`identifiability::equivalent_rel_sigma`]) for
    /// a profile interval; None when the information matrix is singular, the
    /// constant is held by a bound, or its interval is one-sided.
    pub std_error: Option<f64>,
    /// 95 % interval (SI); for an interval open on one side ([`Estimate::open`]) the
    /// bound of the search at that end.
    pub ci95: Option<[f64; 2]>,
    /// Whether the trace pins it down.
    pub identifiable: bool,
    /// Why not, in words (None when identifiable).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The start value (the scene's).
    pub start: f64,
    /// At a bound of the search (held there by the bound: no σ, no interval).
    pub at_bound: bool,
    /// How the 95 % interval was found (None: no interval).
    pub interval: Option<Kind>,
    /// The side on which the profile does not reach the 95 % level before the
    /// bound of the search (None: two-sided, or no interval). A one-sided constant
    /// is not identifiable.
    pub open: Option<Open>,
    /// The constants whose values the interval is conditional on: for a Wald
    /// interval the constants held at a bound of their search when the full
    /// information is singular, for a profile interval those a bound held in the
    /// re-fits at its ends (the search box; for a constant that ended at a bound,
    /// the box released by its width, [`super::profile`]); empty when every other
    /// free constant was free.
    pub conditional_on: Vec<String>,
}

/// How an interval was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Linearised (Wald): θ ± t·σ, or θ·exp(±t·σ_x) for a log-searched constant,
    /// from the covariance; kept where the profile at ±2σ agrees with the
    /// quadratic model ([`super::profile::WALD_TOLERANCE`]).
    Wald,
    /// Profile likelihood: where χ² with the others re-fitted rises by t²·s².
    Profile,
}

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Kind::Wald => "Wald",
            Kind::Profile => "profile",
        })
    }
}

/// The open side of a one-sided interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Open {
    /// The trace does not exclude smaller values down to the search's lower bound.
    Below,
    /// The trace does not exclude larger values up to the search's upper bound.
    Above,
    /// Neither (a flat profile).
    Both,
}

impl std::fmt::Display for Open {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Open::Below => "below",
            Open::Above => "above",
            Open::Both => "both ways",
        })
    }
}

/// What the traces show, for the explanations.
#[derive(Debug, Clone, PartialEq)]
pub struct Context {
    /// A capacitance channel is measured in some experiment.
    pub capacitance: bool,
    /// Largest |λ − λ_rest|/λ_rest over the simulated traces.
    pub max_strain: f64,
    /// Longest trace (s).
    pub span: f64,
    /// Shortest sample interval (s).
    pub min_dt: f64,
    /// τ of each arm at the optimum (s).
    pub arm_tau: Vec<f64>,
}

/// The assessment at the optimum.
#[derive(Debug, Clone, Serialize)]
pub struct Assessment {
    /// Per free constant.
    pub estimates: Vec<Estimate>,
    /// Correlation matrix of the free constants, every one free (None where
    /// undefined).
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Condition number of the column-normalised Jacobian.
    pub condition: f64,
    /// Constants with the largest weight in the weakest direction, and that
    /// direction's singular value relative to the largest.
    pub weakest: (Vec<String>, f64),
    /// What the profiles found that the caller must warn of (a χ² below the
    /// optimum's: the search missed the optimum) ([`super::profile`]).
    #[serde(skip)]
    pub warnings: Vec<String>,
}

/// The linearised assessment and what the profile stage needs of it.
#[derive(Debug, Clone)]
pub(super) struct Linear {
    /// The assessment, every interval Wald.
    pub assessment: Assessment,
    /// σ in search coordinates behind each estimate's Wald interval (None: none).
    pub sigma_x: Vec<Option<f64>>,
    /// Covariance of every free constant free, in search coordinates (NaN when
    /// singular).
    pub covariance: DMatrix<f64>,
    /// The Student quantile of the 95 % intervals (ν = N − p).
    pub t: f64,
    /// The weakest direction's members (indices), for the reasons.
    weakest: Vec<usize>,
}

/// Assess the optimum `x` (search coordinates) with Jacobian `jac` of the scaled
/// residuals and 2·cost = `rss`, linearised: Wald intervals from the covariance
/// with every free constant free ([`linear`]); [`super::profile::assess`] checks
/// them against the profile likelihood.
pub fn assess(
    free: &[Constant],
    x: &[f64],
    jac: &DMatrix<f64>,
    rss: f64,
    ctx: &Context,
) -> Assessment {
    linear(free, x, jac, rss, ctx).assessment
}

/// The linearised assessment ([`assess`]).
///
/// σ comes from s²(JᵀJ)⁻¹ with every free constant free, also those the trace
/// does not pin down and those at a bound of their search (to first order, as if
/// the bound were not there): a σ conditional on a value the trace did not fix
/// would be too small (the rig trace: C10 ±1.0 % with C30 held at its bound, ±3.2 %
/// with it free, and the truth 2.2 % off). A constant that ended at a bound is held
/// there by the bound, not by the trace (otherwise the search would have moved it
/// inside): it gets no σ and no interval and is not identifiable. Only where the
/// full information is singular for a constant inside its bounds is its σ the one
/// with the bounded constants held (their columns left out), and the estimate
/// names them in `conditional_on`. Whether a bounded constant drifted there along a
/// direction the trace does not pin down, or the trace pushed it, its weakness with
/// every constant free says (in the reason).
pub(super) fn linear(
    free: &[Constant],
    x: &[f64],
    jac: &DMatrix<f64>,
    rss: f64,
    ctx: &Context,
) -> Linear {
    let values: Vec<f64> = free
        .iter()
        .zip(x)
        .map(|(c, &xj)| c.space.theta(xj))
        .collect();
    let bound: Vec<Option<Side>> = free
        .iter()
        .zip(&values)
        .map(|(c, &v)| at_bound(c, v))
        .collect();
    // every constant free: what the trace pins down, and the weakest direction
    let full = uncertainty(jac, rss);
    let t = full.t95.unwrap_or(1.96);
    let weakest = weakest_direction(jac);
    // the constants inside their bounds, and each one's column in the held problem
    // (only consulted where the full information is singular)
    let inside: Vec<usize> = (0..free.len()).filter(|&j| bound[j].is_none()).collect();
    let column = |j: usize| inside.iter().position(|&k| k == j);
    let held = uncertainty(&jac.select_columns(inside.iter()), rss);
    let held_names: Vec<String> = (0..free.len())
        .filter(|&j| bound[j].is_some())
        .map(|j| free[j].name.clone())
        .collect();
    let conditional: Vec<bool> = (0..free.len())
        .map(|j| {
            bound[j].is_none()
                && full.std_error[j].is_none()
                && column(j).is_some_and(|a| held.std_error[a].is_some())
        })
        .collect();
    let sigma_x: Vec<Option<f64>> = (0..free.len())
        .map(|j| match (bound[j], conditional[j]) {
            (Some(_), _) => None,
            (None, true) => column(j).and_then(|a| held.std_error[a]),
            (None, false) => full.std_error[j],
        })
        .collect();
    let correlation: Vec<Vec<Option<f64>>> = (0..free.len())
        .map(|j| {
            (0..free.len())
                .map(
                    |l| match (conditional[j] || conditional[l], column(j), column(l)) {
                        (true, Some(a), Some(b)) => held.correlation[a][b],
                        (true, _, _) => None,
                        (false, _, _) => full.correlation[j][l],
                    },
                )
                .collect()
        })
        .collect();
    let mut estimates: Vec<Estimate> = free
        .iter()
        .enumerate()
        .map(|(j, c)| {
            let (sd, ci) = in_theta(c, values[j], sigma_x[j], t);
            Estimate {
                name: c.name.clone(),
                value: values[j],
                unit: c.unit.to_string(),
                std_error: sd,
                ci95: ci,
                identifiable: true,
                reason: None,
                start: c.start,
                at_bound: bound[j].is_some(),
                interval: ci.map(|_| Kind::Wald),
                open: None,
                conditional_on: match conditional[j] {
                    true => held_names.clone(),
                    false => Vec::new(),
                },
            }
        })
        .collect();
    let mut lin = Linear {
        assessment: Assessment {
            estimates: Vec::new(),
            correlation,
            condition: full.condition,
            weakest: (
                weakest.0.iter().map(|&k| free[k].name.clone()).collect(),
                weakest.1,
            ),
            warnings: Vec::new(),
        },
        sigma_x,
        covariance: full.covariance,
        t,
        weakest: weakest.0,
    };
    for (j, e) in estimates.iter_mut().enumerate() {
        let why = match bound[j] {
            // with every constant free: why it went there
            Some(side) => {
                let free_sd = in_theta(&free[j], values[j], full.std_error[j], t).0;
                let partners = lin.partners(j);
                Some((
                    Weakness::AtBound(side),
                    weakness(&free[j], rel_sigma(values[j], free_sd), t, partners),
                ))
            }
            None => weakness(
                &free[j],
                rel_sigma(values[j], e.std_error),
                t,
                lin.partners(j),
            )
            .map(|w| (w, None)),
        };
        if let Some((w, cause)) = why {
            e.identifiable = false;
            e.reason = Some(explain(free, j, w, cause, &lin.weakest, ctx));
        }
    }
    lin.assessment.estimates = estimates;
    lin
}

impl Linear {
    /// The other free constants' correlations with constant j (index, ρ).
    fn partners(&self, j: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.assessment.correlation[j]
            .iter()
            .enumerate()
            .filter(move |&(k, _)| k != j)
            .filter_map(|(k, r)| r.map(|r| (k, r)))
    }

    /// Constant j's interval becomes its profile interval [lo, hi] (θ), open on
    /// side `open` (the bound of the search at that end), conditional on `given`,
    /// judged by the one rule ([`identifiability`]): its width through the
    /// equivalent symmetric interval ([`identifiability::equivalent_rel_sigma`],
    /// the same threshold whatever the interval's kind), and a one-sided interval
    /// not identifiable.
    pub(super) fn with_profile(
        &mut self,
        free: &[Constant],
        j: usize,
        [lo, hi]: [f64; 2],
        open: Option<Open>,
        given: Vec<String>,
        ctx: &Context,
    ) {
        let c = &free[j];
        let value = self.assessment.estimates[j].value;
        let log = matches!(c.space, Space::Log);
        let rel = identifiability::equivalent_rel_sigma(value, lo, hi, self.t, log);
        let why = match open {
            Some(side) => Some(Weakness::OneSided(side)),
            None => weakness(c, Some(rel), self.t, self.partners(j)),
        };
        let reason = why.map(|w| explain(free, j, w, None, &self.weakest, ctx));
        let e = &mut self.assessment.estimates[j];
        e.ci95 = Some([lo, hi]);
        e.interval = Some(Kind::Profile);
        e.open = open;
        e.conditional_on = given;
        e.std_error = (open.is_none() && rel.is_finite()).then(|| rel * value.abs());
        e.identifiable = reason.is_none();
        e.reason = reason;
    }
}

/// σ and 95 % interval in θ of a constant at `value` with σ_x (search coordinates):
/// θ·σ_x and θ·exp(±t·σ_x) in log space, s·σ_x and θ ± t·s·σ_x in linear.
fn in_theta(c: &Constant, value: f64, sx: Option<f64>, t: f64) -> (Option<f64>, Option<[f64; 2]>) {
    match (sx, c.space) {
        (None, _) => (None, None),
        (Some(sx), Space::Log) => (
            Some(value * sx),
            Some([value * (-t * sx).exp(), value * (t * sx).exp()]),
        ),
        (Some(sx), Space::Linear { scale }) => {
            let s = scale * sx;
            (Some(s), Some([value - t * s, value + t * s]))
        }
    }
}

/// Why a constant with relative standard error `rel` (None: singular), correlated
/// with the free constants `partners` (index, ρ), is not pinned down, if it is not:
/// the one rule ([`identifiability::judge`]), a sign-free constant (searched
/// linearly) also held to an interval that excludes 0.
fn weakness(
    c: &Constant,
    rel: Option<f64>,
    t: f64,
    partners: impl Iterator<Item = (usize, f64)>,
) -> Option<Weakness> {
    let sign_free = matches!(c.space, Space::Linear { .. });
    let limit = identifiability::limit(sign_free, t);
    identifiability::judge(rel, limit, partners).map(|w| match w {
        identifiability::Weakness::Singular => Weakness::Singular,
        identifiability::Weakness::Loose(r) => Weakness::Loose(r),
        identifiability::Weakness::Traded(k, rho) => Weakness::Traded(k, rho),
    })
}

/// Which bound of its search a constant ended at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Lower,
    Upper,
}

/// The bound `value` lies at (within 10⁻⁶ of the searched range, in the constant's
/// search coordinate), if any.
fn at_bound(c: &Constant, value: f64) -> Option<Side> {
    let (lo, hi) = c.bounds;
    let near = |a: f64, b: f64| match c.space {
        Space::Log if a > 0.0 && b > 0.0 && lo > 0.0 => {
            (a / b).ln().abs() <= 1e-6 * (hi / lo).ln().abs()
        }
        _ => (a - b).abs() <= 1e-6 * (hi - lo).abs().max(f64::MIN_POSITIVE),
    };
    if near(value, lo) {
        Some(Side::Lower)
    } else if near(value, hi) {
        Some(Side::Upper)
    } else {
        None
    }
}

/// Why a constant is not pinned down.
#[derive(Debug, Clone, Copy)]
enum Weakness {
    /// The information matrix is singular.
    Singular,
    /// Its relative standard error.
    Loose(f64),
    /// Correlated with free constant k.
    Traded(usize, f64),
    /// Held at a bound of the search.
    AtBound(Side),
    /// Its profile interval is open on this side.
    OneSided(Open),
}

/// The free constants (indices) with |component| > 0.3 in the smallest singular
/// vector of the column-normalised Jacobian, and that singular value relative to
/// the largest.
fn weakest_direction(jac: &DMatrix<f64>) -> (Vec<usize>, f64) {
    let mut norm = jac.clone();
    for j in 0..norm.ncols() {
        let s = norm.column(j).norm();
        if s > 0.0 {
            norm.column_mut(j).scale_mut(1.0 / s);
        }
    }
    let Some(svd) = crate::fit::linear::svd(norm, false, true) else {
        return ((0..jac.ncols()).collect(), 0.0);
    };
    let sv = &svd.singular_values;
    let last = sv.len() - 1;
    let vt = svd.v_t.expect("requested");
    let members = (0..jac.ncols())
        .filter(|&k| vt[(last, k)].abs() > 0.3)
        .collect();
    (members, sv[last] / sv[0].max(f64::MIN_POSITIVE))
}

/// The reason in words for constant j; for one at a bound, `cause` is its weakness
/// with every constant free (it drifted there along it), None if it has none (the
/// trace pushed it there).
fn explain(
    free: &[Constant],
    j: usize,
    w: Weakness,
    cause: Option<Weakness>,
    weakest: &[usize],
    ctx: &Context,
) -> String {
    let c = &free[j];
    let how = match w {
        Weakness::Singular => "the trace's information about it is singular".to_string(),
        Weakness::Loose(r) => format!("σ/value = {r:.2}"),
        Weakness::Traded(k, rho) => format!("correlated with {} (ρ = {rho:.4})", free[k].name),
        Weakness::AtBound(side) => {
            let (word, b) = match side {
                Side::Lower => ("lower", c.bounds.0),
                Side::Upper => ("upper", c.bounds.1),
            };
            format!(
                "at the {word} bound of its search ({}): the bound, not the trace, holds it there, so it has no σ or interval",
                si(b, c.unit)
            )
        }
        Weakness::OneSided(side) => {
            let (word, bound) = match side {
                Open::Below => (
                    "below",
                    format!("the lower bound of its search ({})", si(c.bounds.0, c.unit)),
                ),
                Open::Above => (
                    "above",
                    format!("the upper bound of its search ({})", si(c.bounds.1, c.unit)),
                ),
                Open::Both => ("both ways", "either bound of its search".to_string()),
            };
            format!(
                "its 95 % profile interval is open {word}: the trace excludes no value between the estimate and {bound}"
            )
        }
    };
    if let Weakness::AtBound(_) = w {
        return match cause {
            Some(cause) => format!(
                "{how}; it drifted there: with every constant free, {}",
                explain(free, j, cause, None, weakest, ctx)
            ),
            None => format!(
                "{how}: the value the trace wants lies outside the range searched ({} to {}, set around the scene's {}); start the scene nearer it (holding it at the scene's value would contradict the trace)",
                si(c.bounds.0, c.unit),
                si(c.bounds.1, c.unit),
                si(c.start, c.unit),
            ),
        };
    }
    let partners: Vec<&Constant> = match w {
        Weakness::Traded(k, _) => vec![&free[k]],
        _ if weakest.contains(&j) => weakest
            .iter()
            .filter(|&&k| k != j)
            .map(|&k| &free[k])
            .collect(),
        _ => Vec::new(),
    };
    let has = |pred: &dyn Fn(Role) -> bool| pred(c.role) || partners.iter().any(|p| pred(p.role));
    let modulus = |r: Role| matches!(r, Role::LeadingModulus | Role::HigherOrder | Role::ArmK(_));
    let dielectric = std::iter::once(c)
        .chain(partners.iter().copied())
        .find(|k| k.role.is_dielectric());
    let why = if let Some(d) = dielectric.filter(|_| !ctx.capacitance && has(&modulus)) {
        format!(
            "contraction alone cannot separate εr{} from the moduli: the Maxwell pressure scales with εr and the elastic stress with the moduli, so only their ratio is seen; measure the capacitance too (C ∝ εr) or fix {} at the scene's value (as the default run does; every other interval is then conditional on it)",
            match d.role {
                Role::MassFraction => " (here the filler mass fraction)",
                _ => "",
            },
            d.name
        )
    } else if c.role == Role::HigherOrder {
        format!(
            "the traces reach a strain of only {:.2} %, where the terms beyond the leading modulus are below the noise; {} or add a trace with larger strain",
            100.0 * ctx.max_strain,
            match super::reduce::drop_advice(free, c) {
                Some(fix) => format!("drop it (--fix {fix}, as the default run does)"),
                None => format!("fix {}", c.name),
            }
        )
    } else if let Some(tau) = slow_arm(c, &partners, ctx) {
        format!(
            "an arm with τ = {} is slower than the {} trace: within it the arm acts as extra stiffness, traded against the leading modulus; use a trace at least 3τ long ({}), which resolves the arm. Holding a constant here does not help: the arm stays in the actuator, and an interval conditional on a held value misses wherever that value is off (the default run keeps the arm free, so every other interval accounts for it)",
            si(tau, "s"),
            si(ctx.span, "s"),
            si(3.0 * tau, "s")
        )
    } else if c.role == Role::Nv {
        "the damping is unresolved: the traces have no motion fast enough for the dashpot nv to show above the noise; add a fast step, or state a damping measured elsewhere with --fix. Holding it at a guess (0, or the scene's value) biases the arms wherever the guess is off, so the default run keeps it free and every other interval accounts for it".to_string()
    } else if partners.is_empty() {
        "the trace does not pin it down".to_string()
    } else {
        let names: Vec<&str> = partners.iter().map(|p| p.name.as_str()).collect();
        format!(
            "the trace fixes only a combination of it with {}",
            names.join(", ")
        )
    };
    format!("{how}: {why}")
}

/// τ of an arm (this constant's or a partner's) slower than half the longest trace.
fn slow_arm(c: &Constant, partners: &[&Constant], ctx: &Context) -> Option<f64> {
    let arm = |k: &Constant| match k.role {
        Role::ArmK(a) | Role::ArmTau(a) => Some(a),
        _ => None,
    };
    let a = arm(c).or_else(|| partners.iter().find_map(|p| arm(p)))?;
    ctx.arm_tau
        .get(a)
        .copied()
        .filter(|&tau| tau > 0.5 * ctx.span)
}
