//! What the trace pins down: standard errors, intervals and correlations from the
//! Jacobian at the optimum, and, for every constant it does not pin down, the reason
//! in words.
//!
//! Covariance in search coordinates: cov_x = s²·(JᵀJ)⁻¹ with s² = 2·cost/(N − p)
//! ([`crate::fit::diagnostics::uncertainty`]). For a log-searched constant the
//! relative standard error is σ_x and the 95 % interval θ·exp(±t·σ_x) (asymmetric,
//! always positive); for a linear one σ_θ = s·σ_x and θ ± t·σ_θ.
//!
//! **Not identifiable** when σ_θ/|θ| > [`MAX_REL_SIGMA`], or |ρ| > [`MAX_CORRELATION`]
//! with another free constant, or the information matrix is singular. The weakest
//! direction of the column-normalised Jacobian (its smallest singular vector) names
//! the constants that trade off against each other; the known cases get their own
//! explanation (small strains and higher polynomial terms, εr against the moduli
//! without capacitance, an arm slower than the trace, unresolved damping).

use super::params::{Constant, Role, Space};
use crate::fit::diagnostics::uncertainty;
use crate::report::format::si;
use nalgebra::DMatrix;
use serde::Serialize;

/// Largest relative standard error of an identified constant (a 95 % interval
/// within about a factor 2.7 either way).
pub const MAX_REL_SIGMA: f64 = 0.5;

/// Largest |correlation| between two identified constants: beyond it the trace fixes
/// only their combination.
pub const MAX_CORRELATION: f64 = 0.999;

/// Correlation above which a warning names the pair.
pub const WARN_CORRELATION: f64 = 0.99;

/// One identified constant, as printed and written (`--json` `parameters`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// Name.
    pub name: String,
    /// Value (SI).
    pub value: f64,
    /// SI unit.
    pub unit: String,
    /// Standard error (SI), None when the information matrix is singular.
    pub std_error: Option<f64>,
    /// 95 % interval (SI).
    pub ci95: Option<[f64; 2]>,
    /// Whether the trace pins it down.
    pub identifiable: bool,
    /// Why not, in words (None when identifiable).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The start value (the scene's).
    pub start: f64,
    /// At a bound of the search.
    pub at_bound: bool,
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
    /// Correlation matrix of the free constants (None where undefined).
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Condition number of the column-normalised Jacobian.
    pub condition: f64,
    /// Constants with the largest weight in the weakest direction, and that
    /// direction's singular value relative to the largest.
    pub weakest: (Vec<String>, f64),
}

/// Assess the optimum `x` (search coordinates) with Jacobian `jac` of the scaled
/// residuals and 2·cost = `rss`.
pub fn assess(
    free: &[Constant],
    x: &[f64],
    jac: &DMatrix<f64>,
    rss: f64,
    ctx: &Context,
) -> Assessment {
    let u = uncertainty(jac, rss);
    let weakest = weakest_direction(free, jac);
    let t = u.t95.unwrap_or(1.96);
    let mut estimates: Vec<Estimate> = free
        .iter()
        .zip(x)
        .enumerate()
        .map(|(j, (c, &xj))| {
            let value = c.space.theta(xj);
            let (sd, ci) = match u.std_error[j] {
                Some(sx) => match c.space {
                    Space::Log => (
                        Some(value * sx),
                        Some([value * (-t * sx).exp(), value * (t * sx).exp()]),
                    ),
                    Space::Linear { scale } => {
                        let s = scale * sx;
                        (Some(s), Some([value - t * s, value + t * s]))
                    }
                },
                None => (None, None),
            };
            let tol = 1e-6 * (c.bounds.1 - c.bounds.0).abs().max(f64::MIN_POSITIVE);
            Estimate {
                name: c.name.clone(),
                value,
                unit: c.unit.to_string(),
                std_error: sd,
                ci95: ci,
                identifiable: true,
                reason: None,
                start: c.start,
                at_bound: (value - c.bounds.0).abs() <= tol || (value - c.bounds.1).abs() <= tol,
            }
        })
        .collect();
    for j in 0..free.len() {
        let partner = (0..free.len())
            .filter(|&k| k != j)
            .filter_map(|k| u.correlation[j][k].map(|r| (k, r)))
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
        let e = &estimates[j];
        let rel = e.std_error.map(|s| s / e.value.abs());
        let why = match (rel, partner) {
            (None, _) => Some(Weakness::Singular),
            (Some(r), _) if r.is_nan() || r > MAX_REL_SIGMA => Some(Weakness::Loose(r)),
            (_, Some((k, rho))) if rho.abs() > MAX_CORRELATION => Some(Weakness::Traded(k, rho)),
            _ => None,
        };
        if let Some(w) = why {
            let reason = explain(free, j, w, &weakest.0, ctx);
            estimates[j].identifiable = false;
            estimates[j].reason = Some(reason);
        }
    }
    let names: Vec<String> = weakest.0.iter().map(|&k| free[k].name.clone()).collect();
    Assessment {
        estimates,
        correlation: u.correlation,
        condition: u.condition,
        weakest: (names, weakest.1),
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
}

/// The free constants (indices) with |component| > 0.3 in the smallest singular
/// vector of the column-normalised Jacobian, and that singular value relative to
/// the largest.
fn weakest_direction(free: &[Constant], jac: &DMatrix<f64>) -> (Vec<usize>, f64) {
    let mut norm = jac.clone();
    for j in 0..norm.ncols() {
        let s = norm.column(j).norm();
        if s > 0.0 {
            norm.column_mut(j).scale_mut(1.0 / s);
        }
    }
    let Some(svd) = crate::fit::linear::svd(norm, false, true) else {
        return ((0..free.len()).collect(), 0.0);
    };
    let sv = &svd.singular_values;
    let last = sv.len() - 1;
    let vt = svd.v_t.expect("requested");
    let members = (0..free.len())
        .filter(|&k| vt[(last, k)].abs() > 0.3)
        .collect();
    (members, sv[last] / sv[0].max(f64::MIN_POSITIVE))
}

/// The reason in words for constant j.
fn explain(free: &[Constant], j: usize, w: Weakness, weakest: &[usize], ctx: &Context) -> String {
    let c = &free[j];
    let partners: Vec<&Constant> = match w {
        Weakness::Traded(k, _) => vec![&free[k]],
        _ if weakest.contains(&j) => weakest
            .iter()
            .filter(|&&k| k != j)
            .map(|&k| &free[k])
            .collect(),
        _ => Vec::new(),
    };
    let how = match w {
        Weakness::Singular => "the trace's information about it is singular".to_string(),
        Weakness::Loose(r) => format!("σ/value = {r:.2}"),
        Weakness::Traded(k, rho) => format!("correlated with {} (ρ = {rho:.4})", free[k].name),
    };
    let has = |pred: &dyn Fn(Role) -> bool| pred(c.role) || partners.iter().any(|p| pred(p.role));
    let modulus = |r: Role| matches!(r, Role::LeadingModulus | Role::HigherOrder | Role::ArmK(_));
    let dielectric = std::iter::once(c)
        .chain(partners.iter().copied())
        .find(|k| k.role.is_dielectric());
    let why = if let Some(d) = dielectric.filter(|_| !ctx.capacitance && has(&modulus)) {
        format!(
            "contraction alone cannot separate εr{} from the moduli: the Maxwell pressure scales with εr and the elastic stress with the moduli, so only their ratio is seen; measure the capacitance too (C ∝ εr) or fix {}",
            match d.role {
                Role::MassFraction => " (here the filler mass fraction)",
                _ => "",
            },
            d.name
        )
    } else if c.role == Role::HigherOrder {
        format!(
            "the traces reach a strain of only {:.2} %, where the terms beyond the leading modulus are below the noise; fix {} or add a trace with larger strain",
            100.0 * ctx.max_strain,
            c.name
        )
    } else if let Some(tau) = slow_arm(c, &partners, ctx) {
        format!(
            "an arm with τ = {} is slower than the {} trace: within it the arm acts as extra stiffness, traded against the leading modulus; use a longer trace or fix the arm",
            si(tau, "s"),
            si(ctx.span, "s")
        )
    } else if c.role == Role::Nv {
        "the damping is unresolved: the traces have no motion fast enough for the dashpot nv to show above the noise (fix nv, e.g. --fix nv=0, or add a fast step)".to_string()
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
