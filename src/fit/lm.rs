//! Bounded Levenberg-Marquardt (Marquardt scaling, Nielsen's damping update,
//! active-set handling of box bounds).
//!
//! Written here rather than taken from a crate because the estimators need box
//! bounds, analytic Jacobians supplied in place, variable projection on top, and
//! exact counts for the solver report; none of the Rust LM crates offers all four.

use nalgebra::{DMatrix, DVector};

/// A nonlinear least-squares problem: minimise ½‖r(p)‖².
pub trait LeastSquares {
    /// (number of residuals, number of parameters).
    fn dims(&self) -> (usize, usize);
    /// Residuals into `r` and, if asked, the Jacobian ∂r/∂p into `jac`.
    /// Returns false when `p` is outside the model's domain or a value is not finite.
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool;
}

/// Stopping rules.
#[derive(Debug, Clone, Copy)]
pub struct LmSettings {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Relative cost decrease below which the search stops.
    pub ftol: f64,
    /// Relative step below which the search stops.
    pub xtol: f64,
    /// Projected-gradient infinity norm (relative to the cost) below which it stops.
    pub gtol: f64,
}

impl Default for LmSettings {
    fn default() -> Self {
        LmSettings {
            max_iterations: 200,
            ftol: 1e-12,
            xtol: 1e-10,
            gtol: 1e-12,
        }
    }
}

/// Why a search stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum Termination {
    /// A convergence test passed (which one).
    Converged(&'static str),
    /// The iteration limit was reached.
    MaxIterations,
    /// The start was outside the domain or the problem produced non-finite values.
    Failed(String),
}

/// Result of one search.
#[derive(Debug, Clone)]
pub struct LmResult {
    /// Final parameters.
    pub x: Vec<f64>,
    /// ½‖r‖² at `x`.
    pub cost: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// Residual evaluations (each with or without Jacobian).
    pub evaluations: usize,
    /// Why it stopped.
    pub termination: Termination,
}

/// `v` moved into `[lo, hi]`. Unlike `f64::clamp` it never panics (NaN or inverted
/// bounds); [`minimize`] refuses such bounds before it projects anything.
pub fn project(v: f64, (lo, hi): (f64, f64)) -> f64 {
    v.max(lo).min(hi)
}

/// Why `x0` and `bounds` cannot start a search, if they cannot: one start value and
/// one (lo, hi) pair per parameter, a finite start, bounds not NaN with lo ≤ hi.
fn invalid_start(n: usize, x0: &[f64], bounds: &[(f64, f64)]) -> Option<String> {
    if x0.len() != n || bounds.len() != n {
        return Some(format!(
            "{} start values and {} bounds for {n} parameters",
            x0.len(),
            bounds.len()
        ));
    }
    if let Some(i) = (0..n).find(|&i| !x0[i].is_finite()) {
        return Some(format!("start value {i} is {}", x0[i]));
    }
    if let Some(&(lo, hi)) = bounds
        .iter()
        .find(|(lo, hi)| lo.is_nan() || hi.is_nan() || lo > hi)
    {
        return Some(format!("empty bounds [{lo}, {hi}]"));
    }
    None
}

/// Minimise ½‖r(p)‖² from `x0` within `bounds`. A start or bounds that cannot be
/// used (see [`invalid_start`]) end the search at once as [`Termination::Failed`].
pub fn minimize<P: LeastSquares + ?Sized>(
    problem: &mut P,
    x0: &[f64],
    bounds: &[(f64, f64)],
    settings: &LmSettings,
) -> LmResult {
    let (m, n) = problem.dims();
    if let Some(why) = invalid_start(n, x0, bounds) {
        return LmResult {
            x: x0.to_vec(),
            cost: f64::INFINITY,
            iterations: 0,
            evaluations: 0,
            termination: Termination::Failed(why),
        };
    }
    let mut x: Vec<f64> = x0
        .iter()
        .zip(bounds)
        .map(|(&v, &b)| project(v, b))
        .collect();
    let mut r = DVector::zeros(m);
    let mut jac = DMatrix::zeros(m, n);
    let mut r_new = DVector::zeros(m);
    let mut x_new = vec![0.0; n];
    let mut evaluations = 1;
    if !problem.eval(&x, &mut r, Some(&mut jac)) {
        return LmResult {
            cost: f64::INFINITY,
            x,
            iterations: 0,
            evaluations,
            termination: Termination::Failed("not finite at the start".into()),
        };
    }
    let mut cost = 0.5 * r.norm_squared();
    // Damping is relative to diag(JᵀJ) (Marquardt scaling), so it is dimensionless.
    let mut mu = 1e-3;
    let mut nu = 2.0;
    let mut a = DMatrix::zeros(n, n);
    let mut g = DVector::zeros(n);
    for it in 0..settings.max_iterations {
        jac.tr_mul_to(&jac, &mut a);
        jac.tr_mul_to(&r, &mut g);
        if !(a.iter().all(|v| v.is_finite()) && g.iter().all(|v| v.is_finite())) {
            return done(
                x,
                cost,
                it,
                evaluations,
                Termination::Failed("the normal equations overflowed".into()),
            );
        }
        // Active set: variables at a bound whose gradient pushes outward stay put.
        let mut free = vec![true; n];
        for i in 0..n {
            let (lo, hi) = bounds[i];
            if (x[i] <= lo && g[i] > 0.0) || (x[i] >= hi && g[i] < 0.0) {
                free[i] = false;
            }
        }
        let gnorm = (0..n)
            .filter(|&i| free[i])
            .map(|i| g[i].abs())
            .fold(0.0, f64::max);
        if gnorm <= settings.gtol * (1.0 + cost) {
            return done(x, cost, it, evaluations, Termination::Converged("gradient"));
        }
        loop {
            let mut sys = a.clone();
            let mut rhs = -&g;
            for i in 0..n {
                if free[i] {
                    sys[(i, i)] += mu * a[(i, i)].max(1e-12 * (1.0 + a[(i, i)]));
                } else {
                    for j in 0..n {
                        sys[(i, j)] = 0.0;
                        sys[(j, i)] = 0.0;
                    }
                    sys[(i, i)] = 1.0;
                    rhs[i] = 0.0;
                }
            }
            let Some(step) = sys.cholesky().map(|c| c.solve(&rhs)) else {
                mu *= nu;
                nu *= 2.0;
                if !mu.is_finite() || mu > 1e300 {
                    return done(
                        x,
                        cost,
                        it,
                        evaluations,
                        Termination::Failed("singular system".into()),
                    );
                }
                continue;
            };
            for i in 0..n {
                x_new[i] = project(x[i] + step[i], bounds[i]);
            }
            let dx: Vec<f64> = (0..n).map(|i| x_new[i] - x[i]).collect();
            let dx_norm = dx.iter().map(|d| d * d).sum::<f64>().sqrt();
            let x_norm = x.iter().map(|d| d * d).sum::<f64>().sqrt();
            if dx_norm <= settings.xtol * (x_norm + settings.xtol) {
                return done(x, cost, it, evaluations, Termination::Converged("step"));
            }
            evaluations += 1;
            let ok = problem.eval(&x_new, &mut r_new, None);
            let cost_new = if ok {
                0.5 * r_new.norm_squared()
            } else {
                f64::INFINITY
            };
            // Predicted decrease of the linear model for the (projected) step.
            let dxv = DVector::from_column_slice(&dx);
            let pred = -(g.dot(&dxv)) - 0.5 * (&a * &dxv).dot(&dxv);
            let rho = if pred > 0.0 {
                (cost - cost_new) / pred
            } else {
                -1.0
            };
            if ok && cost_new < cost && rho > 0.0 {
                let rel = (cost - cost_new) / cost.max(f64::MIN_POSITIVE);
                x.copy_from_slice(&x_new);
                evaluations += 1;
                problem.eval(&x, &mut r, Some(&mut jac));
                cost = cost_new;
                mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                nu = 2.0;
                if rel <= settings.ftol {
                    return done(x, cost, it + 1, evaluations, Termination::Converged("cost"));
                }
                break;
            }
            mu *= nu;
            nu *= 2.0;
            if !mu.is_finite() || mu > 1e300 {
                return done(
                    x,
                    cost,
                    it,
                    evaluations,
                    Termination::Converged("no further decrease"),
                );
            }
        }
    }
    done(
        x,
        cost,
        settings.max_iterations,
        evaluations,
        Termination::MaxIterations,
    )
}

fn done(
    x: Vec<f64>,
    cost: f64,
    iterations: usize,
    evaluations: usize,
    termination: Termination,
) -> LmResult {
    LmResult {
        x,
        cost,
        iterations,
        evaluations,
        termination,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares: r = (10(y − x²), 1 − x).
    struct Rosen;
    impl LeastSquares for Rosen {
        fn dims(&self) -> (usize, usize) {
            (2, 2)
        }
        fn eval(
            &mut self,
            p: &[f64],
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> bool {
            r[0] = 10.0 * (p[1] - p[0] * p[0]);
            r[1] = 1.0 - p[0];
            if let Some(j) = jac {
                j[(0, 0)] = -20.0 * p[0];
                j[(0, 1)] = 10.0;
                j[(1, 0)] = -1.0;
                j[(1, 1)] = 0.0;
            }
            true
        }
    }

    #[test]
    fn solves_rosenbrock_and_respects_bounds() {
        let inf = f64::INFINITY;
        let res = minimize(
            &mut Rosen,
            &[-1.2, 1.0],
            &[(-inf, inf); 2],
            &LmSettings::default(),
        );
        assert!(
            (res.x[0] - 1.0).abs() < 1e-8 && (res.x[1] - 1.0).abs() < 1e-8,
            "{res:?}"
        );
        // With x ≤ 0.5 the constrained optimum is on the bound, y = x².
        let res = minimize(
            &mut Rosen,
            &[-1.2, 1.0],
            &[(-inf, 0.5), (-inf, inf)],
            &LmSettings::default(),
        );
        assert!(
            (res.x[0] - 0.5).abs() < 1e-12 && (res.x[1] - 0.25).abs() < 1e-6,
            "{res:?}"
        );
    }

    /// Bounds that `f64::clamp` panics on (the Gent limit's lower end above its upper
    /// end, NaN) and a non-finite start end the search as failed, never in a panic.
    #[test]
    fn unusable_bounds_or_start_fail_without_panic() {
        let inf = f64::INFINITY;
        for (x0, bounds) in [
            ([-1.2, 1.0], [(2.0, 1.0), (-inf, inf)]),
            ([-1.2, 1.0], [(f64::NAN, 1.0), (-inf, inf)]),
            ([f64::NAN, 1.0], [(-inf, inf), (-inf, inf)]),
            ([inf, 1.0], [(-inf, inf), (-inf, inf)]),
        ] {
            let res = minimize(&mut Rosen, &x0, &bounds, &LmSettings::default());
            assert!(
                matches!(res.termination, Termination::Failed(_)),
                "{x0:?} {bounds:?}: {res:?}"
            );
        }
        let res = minimize(&mut Rosen, &[0.0], &[(-inf, inf)], &LmSettings::default());
        assert!(matches!(res.termination, Termination::Failed(_)), "{res:?}");
    }

    #[test]
    fn project_never_panics() {
        assert_eq!(project(5.0, (0.0, 1.0)), 1.0);
        assert_eq!(project(-5.0, (0.0, 1.0)), 0.0);
        // Inverted or NaN bounds give some value instead of a panic.
        assert!(!project(0.5, (2.0, 1.0)).is_nan());
        assert_eq!(project(0.5, (f64::NAN, 1.0)), 0.5);
    }
}
