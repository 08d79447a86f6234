//! Uncertainty the trace does not contain: the tolerances of the scene's geometry in
//! the identified constants' intervals.
//!
//! The simulator runs the scene's nominal geometry, so the constants are identified
//! *given* it: εr from a stack's capacitance C = εr·ε0·π·r0²·nd/zd0 is known to the
//! trace's ±0.003 % only if r0 and zd0 are exact, and a 1 % error in zd0 is a 1 % error
//! in εr (and the Maxwell pressure εr·ε0·(V/zd0)² moves the moduli too). A scene can
//! state a length's tolerance, one standard deviation (`layer_thickness = "500 ± 5
//! um"`, [`crate::sim::scene::Tolerance`]).
//!
//! **The move of the optimum.** At the optimum x̂ (search coordinates) the gradient
//! Jᵀr vanishes; when a length g moves, the optimum moves so that it still does. By
//! the implicit-function theorem, with the Gauss–Newton approximation of the Hessian
//! (JᵀJ, the one the covariance uses: Bates & Watts, *Nonlinear Regression Analysis*,
//! 1988, §2.1),
//!
//! ```text
//! dx̂/d ln g = −(JᵀJ)⁻¹ Jᵀ ∂r/∂ln g
//! ```
//!
//! J over the free constants that have an interval (one at a bound of its search is
//! held there, as in the assessment), solved by [`RowQr`] as in
//! [`super::integration_shift`]; ∂r/∂ln g is a forward difference of the scaled
//! residuals with ln g moved by [`STEP`] (one simulator run per
//! length and experiment, and one at the nominal geometry, so that both sides of the
//! difference are the same kind of run). The experiments are of one actuator: a
//! length moves by the same fraction in each.
//!
//! **Into the intervals.** The tolerances are independent, so to first order (GUM,
//! JCGM 100:2008, Eq. 10) each constant's geometry σ in its search coordinate is
//! σ_geo,x² = Σ_g (dx̂/d ln g · σ_g/g)², and in the constant's unit |dθ/dx|·σ_geo,x.
//! The reported σ is sqrt(σ_trace² + σ_geo²), and the 95 % interval is widened in the
//! search coordinate (ln θ for a positive constant, so it stays positive): each half
//! width w of the trace's interval becomes sqrt(w² + (z·σ_geo,x)²), z = 1.96 (the
//! stated σ is a normal one). A constant whose combined σ breaks the one rule
//! ([`crate::fit::identifiability`]) is not identifiable: the geometry, not the
//! trace, leaves it loose. Without tolerances nothing is widened, and the output
//! says that the intervals exclude the geometry and how far a 1 % error of each
//! length would move each constant.

use super::assessment::Estimate;
use super::problem::Problem;
use crate::fit::identifiability;
use crate::fit::linear::RowQr;
use crate::fit::lm::LeastSquares;
use crate::fit::weibull::Z_975;
use crate::report::format::{si, sig};
use crate::sim::scene::Length;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Relative step of a length for ∂r/∂ln g: the forward difference's truncation
/// error is about STEP/2 of the derivative for a law as curved as C ∝ 1/zd0 (5·10⁻⁴),
/// and the integration error of the two runs (≈ rtol = 10⁻⁶ of the signal) is
/// 10⁻³ of the change the step makes: both near 0.1 % of the move.
pub const STEP: f64 = 1e-3;

/// A stated tolerance that went into the intervals.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stated {
    /// The length.
    pub length: Length,
    /// Its nominal value (m).
    pub value_m: f64,
    /// Its standard deviation (m).
    pub sigma_m: f64,
}

/// How far a 1 % error of a length moves a constant.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Move {
    /// The length.
    pub length: Length,
    /// The constant's move (SI) when the length is 1 % larger than the scene says.
    pub shift: f64,
    /// The same in % of the constant (None when the constant is 0).
    pub percent: Option<f64>,
}

/// One free constant's two parts of the uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Term {
    /// The constant.
    pub name: String,
    /// Its SI unit.
    pub unit: String,
    /// σ from the trace alone (SI).
    pub sigma_trace: Option<f64>,
    /// The 95 % interval from the trace alone (SI).
    pub ci95_trace: Option<[f64; 2]>,
    /// σ from the stated tolerances (SI); None when none went in.
    pub sigma_geometry: Option<f64>,
    /// The move per 1 % of each length of the geometry.
    pub per_percent: Vec<Move>,
}

/// What the geometry adds to the intervals (`--json` `geometry`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Geometry {
    /// Whether the reported σ and intervals include the stated tolerances.
    pub included: bool,
    /// The tolerances that went in.
    pub tolerances: Vec<Stated>,
    /// The lengths without a tolerance: taken as exact.
    pub exact: Vec<Length>,
    /// Per free constant with an interval.
    pub constants: Vec<Term>,
    /// Why the geometry's effect could not be computed (a run with a moved length
    /// failed); the intervals then exclude it, and a warning says so.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failed: Option<String>,
    /// What the intervals include, and what a 1 % error of each length does, in
    /// words (a note, not a warning).
    pub note: String,
    /// A tolerance as the scene would state it (its thickness at 1 %), for the note.
    #[serde(skip)]
    example: String,
}

impl Geometry {
    /// The warning of stated tolerances that could not be included.
    pub fn warning(&self) -> Option<String> {
        let why = self.failed.as_ref()?;
        (!self.tolerances.is_empty()).then(|| {
            format!(
                "the geometry's tolerances are not in the intervals: {why}; the intervals hold the trace's uncertainty only"
            )
        })
    }
}

/// The geometry's part of the uncertainty at the optimum `x` (Jacobian `jac` of the
/// scaled residuals over the free constants), and, when the scene states
/// tolerances, `estimates` widened by it (σ and interval; identifiability by the
/// one rule on the combined σ). See the module's documentation.
pub fn include(
    problem: &Problem,
    x: &[f64],
    jac: &DMatrix<f64>,
    estimates: &mut [Estimate],
) -> Geometry {
    let scene = &problem.experiments[0].scene;
    let lengths: Vec<(Length, f64)> = scene
        .actuator
        .lengths()
        .into_iter()
        .filter_map(|l| scene.actuator.length(l).map(|v| (l, v)))
        .filter(|&(_, v)| v > 0.0)
        .collect();
    let tolerances: Vec<Stated> = scene
        .tolerances
        .iter()
        .filter_map(|t| {
            let v = scene.actuator.length(t.length)?;
            Some(Stated {
                length: t.length,
                value_m: v,
                sigma_m: t.sigma_m,
            })
        })
        .collect();
    let exact = lengths
        .iter()
        .map(|l| l.0)
        .filter(|l| !tolerances.iter().any(|t| t.length == *l))
        .collect();
    let cols: Vec<usize> = (0..estimates.len())
        .filter(|&j| estimates[j].std_error.is_some())
        .collect();
    let thickness = match scene.actuator {
        crate::sim::scene::Actuator::Stack(s) => (Length::LayerThickness, s.layer_m),
        crate::sim::scene::Actuator::Helix(h) => (Length::Thickness, h.thickness_m),
    };
    let mut g = Geometry {
        included: false,
        tolerances,
        exact,
        constants: Vec::new(),
        failed: None,
        note: String::new(),
        example: format!(
            "{} = \"{} ± {} um\"",
            thickness.0,
            sig(thickness.1 * 1e6, 3),
            sig(thickness.1 * 1e4, 3)
        ),
    };
    if cols.is_empty() {
        // no constant has an interval to widen or a move to report
        g.included = !g.tolerances.is_empty();
        g.note = g.statement();
        return g;
    }
    let moves = match moves(problem, x, jac, &cols, &lengths) {
        Ok(m) => m,
        Err(why) => {
            g.failed = Some(why);
            g.note = g.words();
            return g;
        }
    };
    g.included = !g.tolerances.is_empty();
    for (&j, dx) in cols.iter().zip(&moves) {
        let c = &problem.free[j];
        let e = &mut estimates[j];
        let dtheta = c.space.dtheta_dx(x[j]);
        let per_percent = lengths
            .iter()
            .zip(dx)
            .map(|(&(l, _), &d)| {
                let shift = 0.01 * dtheta * d;
                Move {
                    length: l,
                    shift,
                    percent: (e.value != 0.0).then(|| 100.0 * shift / e.value.abs()),
                }
            })
            .collect();
        // σ_geo,x² = Σ (dx/d ln g · σ_g/g)² over the stated tolerances
        let sx = g
            .tolerances
            .iter()
            .map(|t| {
                let k = lengths.iter().position(|l| l.0 == t.length);
                k.map_or(0.0, |k| dx[k] * t.sigma_m / t.value_m)
            })
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
        let term = Term {
            name: e.name.clone(),
            unit: e.unit.clone(),
            sigma_trace: e.std_error,
            ci95_trace: e.ci95,
            sigma_geometry: g.included.then(|| (dtheta * sx).abs()),
            per_percent,
        };
        if g.included {
            widen(c, x[j], sx, e);
        }
        g.constants.push(term);
    }
    g.note = g.words();
    g
}

/// dx̂/d ln g of the constants `cols` for each length (rows: lengths), or why a run
/// gave no residuals.
fn moves(
    problem: &Problem,
    x: &[f64],
    jac: &DMatrix<f64>,
    cols: &[usize],
    lengths: &[(Length, f64)],
) -> Result<Vec<Vec<f64>>, String> {
    let n = jac.nrows();
    let residuals = |moved: Option<Length>| -> Result<DVector<f64>, String> {
        let mut p = problem.clone();
        if let Some(l) = moved {
            for e in &mut p.experiments {
                let a = &mut e.scene.actuator;
                let v = a.length(l).ok_or("a length of another kind of actuator")?;
                // ln g moves by exactly STEP
                *a = a.with_length(l, v * STEP.exp()).expect("its own length");
            }
        }
        let mut r = DVector::zeros(n);
        match p.eval(x, &mut r, None) {
            true => Ok(r),
            false => Err(match moved {
                None => "the run at the nominal geometry".to_string(),
                Some(l) => format!("the run with {l} {:.1} % larger", 100.0 * STEP),
            } + &format!(
                " failed ({})",
                p.failure().unwrap_or_else(|| "no reason given".into())
            )),
        }
    };
    let r0 = residuals(None)?;
    // one run per length; each solve is −(JᵀJ)⁻¹Jᵀ(∂r/∂ln g) over `cols`
    let per_length = lengths
        .iter()
        .map(|&(l, _)| {
            let d = (residuals(Some(l))? - &r0) / STEP;
            let mut qr = RowQr::with_rows(cols.len(), n);
            let mut row = vec![0.0; cols.len()];
            for (i, &di) in d.iter().enumerate() {
                for (v, &c) in row.iter_mut().zip(cols) {
                    *v = jac[(i, c)];
                }
                qr.push(&row, -di);
            }
            let step = qr
                .solve()
                .ok_or("no Gauss-Newton step (a rank-0 or non-finite Jacobian)")?;
            match step.iter().all(|v| v.is_finite()) {
                true => Ok(step.iter().copied().collect::<Vec<f64>>()),
                false => Err(format!("a non-finite move of the optimum with {l}")),
            }
        })
        .collect::<Result<Vec<_>, String>>()?;
    // per constant: its move per length
    Ok((0..cols.len())
        .map(|a| per_length.iter().map(|m| m[a]).collect())
        .collect())
}

/// `e` (at search coordinate `x`) with its geometry σ `sx` (search coordinates) added:
/// σ² = σ_trace² + σ_geo², each half width of the interval in x widened to
/// sqrt(w² + (z·sx)²), and not identifiable when the combined σ breaks the rule.
fn widen(c: &super::params::Constant, x: f64, sx: f64, e: &mut Estimate) {
    let sd_geo = (c.space.dtheta_dx(x) * sx).abs();
    e.std_error = e.std_error.map(|s| s.hypot(sd_geo));
    e.ci95 = e.ci95.map(|[lo, hi]| {
        let (a, b) = (c.space.x(lo), c.space.x(hi));
        let (a, b) = (a.min(b), a.max(b));
        let out = |w: f64| w.hypot(Z_975 * sx);
        let (lo, hi) = (c.space.theta(x - out(x - a)), c.space.theta(x + out(b - x)));
        [lo.min(hi), lo.max(hi)]
    });
    if !e.identifiable {
        return;
    }
    let sign_free = matches!(c.space, super::params::Space::Linear { .. });
    let limit = identifiability::limit(sign_free, Z_975);
    let rel = identifiability::rel_sigma(e.value, e.std_error);
    if let Some(w) = identifiability::judge(rel, limit, std::iter::empty()) {
        e.identifiable = false;
        e.reason = Some(format!(
            "with the geometry's tolerances {w}: the stated tolerances of the scene's lengths, not the trace, leave it loose; measure the geometry more precisely"
        ));
    }
}

impl Geometry {
    /// The note in words: [`Geometry::statement`], and per length what a 1 % error
    /// moves.
    fn words(&self) -> String {
        let mut out = self.statement();
        let lengths: Vec<Length> = self
            .constants
            .first()
            .map(|t| t.per_percent.iter().map(|m| m.length).collect())
            .unwrap_or_default();
        for (k, l) in lengths.iter().enumerate() {
            let moved: Vec<String> = self
                .constants
                .iter()
                .map(|t| format!("{} by {}", t.name, t.per_percent[k].words(&t.unit)))
                .collect();
            out += &format!("; a 1 % error in {l} moves {}", moved.join(", "));
        }
        out
    }

    /// What the intervals include, in words (a sentence).
    pub fn statement(&self) -> String {
        match (self.included, self.tolerances.is_empty()) {
            (true, _) => {
                let stated: Vec<String> = self
                    .tolerances
                    .iter()
                    .map(|t| {
                        format!(
                            "{} {} ± {} ({} %)",
                            t.length,
                            si(t.value_m, "m"),
                            si(t.sigma_m, "m"),
                            sig(100.0 * t.sigma_m / t.value_m, 2)
                        )
                    })
                    .collect();
                let exact: Vec<String> = self.exact.iter().map(|l| l.to_string()).collect();
                format!(
                    "The σ and 95 % intervals include the geometry's stated tolerances ({}), σ² = σ_trace² + σ_geometry²{}",
                    stated.join(", "),
                    match exact.is_empty() {
                        true => String::new(),
                        false => format!("; {} given without a tolerance, taken as exact", exact.join(", ")),
                    }
                )
            }
            (false, true) => format!("The intervals exclude the geometry: the scene states no tolerance of its lengths (e.g. {}, one standard deviation), so they hold only if the geometry is exact", self.example),
            (false, false) => "The intervals exclude the geometry's stated tolerances (their effect could not be computed)".to_string(),
        }
    }
}

impl Move {
    /// The move in words: a percentage of the constant, or its unit for a constant
    /// at 0.
    pub fn words(&self, unit: &str) -> String {
        match self.percent {
            // a move below the last digit printed is 0, not "−0.00 %"
            Some(p) if p.abs() < 0.005 => "0.00 %".into(),
            Some(p) => format!("{p:+.2} %"),
            None => si(self.shift, unit),
        }
    }
}
