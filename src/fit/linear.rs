//! Exact solvers for models linear in their parameters: weighted linear least squares
//! (SVD), and the same problem under linear inequality constraints as a convex QP
//! solved by Clarabel (used to keep a fit Drucker-stable). [`svd`] is the one SVD of
//! the estimators: guarded against input on which nalgebra's iteration never ends.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use nalgebra::{DMatrix, DVector, Dyn, SVD};

/// The SVD of `m` (singular values in descending order), or None when `m` is empty,
/// holds a value that is not finite, or the iteration does not converge within
/// LAPACK's limit (`dbdsqr`: 6 sweeps per singular value and dimension, 6·d²; at
/// least 60). nalgebra's plain `svd` iterates without a limit and never returns on
/// a matrix holding NaN or ∞ (seen with stretches of 1e200 and stresses of 1e150).
pub fn svd(m: DMatrix<f64>, compute_u: bool, compute_v: bool) -> Option<SVD<f64, Dyn, Dyn>> {
    if m.is_empty() || !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let d = m.nrows().min(m.ncols());
    let max_iterations = (6 * d * d).max(60);
    let mut svd = m.try_svd_unordered(compute_u, compute_v, 5.0 * f64::EPSILON, max_iterations)?;
    if !svd.singular_values.iter().all(|v| v.is_finite()) {
        return None;
    }
    // Safe now: the sort panics only on a NaN singular value.
    svd.sort_by_singular_values();
    Some(svd)
}

/// Dense → CSC; with `upper` only the upper triangle is kept (Clarabel's P).
fn csc(m: &DMatrix<f64>, upper: bool) -> CscMatrix<f64> {
    let mut colptr = vec![0];
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if (!upper || i <= j) && m[(i, j)] != 0.0 {
                rowval.push(i);
                nzval.push(m[(i, j)]);
            }
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(m.nrows(), m.ncols(), colptr, rowval, nzval)
}

/// Solution of a constrained least-squares problem.
#[derive(Debug, Clone)]
pub struct QpSolution {
    /// Minimiser.
    pub x: DVector<f64>,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Number of constraints active at the solution (slack below 1e-7 of scale).
    pub active: usize,
}

/// Solve min ‖A·x − b‖² subject to G·x ≥ 0 (row-wise). Columns of A and rows of G
/// are scaled to unit norm first so that moduli in Pa and dimensionless rows meet
/// an O(1) problem.
pub fn constrained_least_squares(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    g: &DMatrix<f64>,
) -> Result<QpSolution, String> {
    let finite = |m: &DMatrix<f64>| m.iter().all(|v| v.is_finite());
    if !(finite(a) && finite(g) && b.iter().all(|v| v.is_finite())) {
        return Err("the problem holds a value that is not finite".into());
    }
    let n = a.ncols();
    let d: Vec<f64> = (0..n)
        .map(|j| {
            let s = a.column(j).norm();
            if s > 0.0 {
                1.0 / s
            } else {
                1.0
            }
        })
        .collect();
    let beta = b.norm().max(f64::MIN_POSITIVE);
    let mut ad = a.clone();
    for j in 0..n {
        ad.column_mut(j).scale_mut(d[j]);
    }
    let p = ad.transpose() * &ad;
    let q: Vec<f64> = (-(ad.transpose() * b) / beta).iter().copied().collect();
    let mut gd = g.clone();
    for j in 0..n {
        gd.column_mut(j).scale_mut(d[j]);
    }
    for i in 0..gd.nrows() {
        let s = gd.row(i).norm();
        if s > 0.0 {
            gd.row_mut(i).scale_mut(-1.0 / s);
        }
    }
    let m = gd.nrows();
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .map_err(|e| e.to_string())?;
    let cones = [NonnegativeConeT(m)];
    let mut solver = DefaultSolver::new(
        &csc(&p, true),
        &q,
        &csc(&gd, false),
        &vec![0.0; m],
        &cones,
        settings,
    )
    .map_err(|e| e.to_string())?;
    solver.solve();
    let why = match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => None,
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            Some("the constraints admit no solution (primal infeasible)")
        }
        SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
            Some("the objective is unbounded (dual infeasible)")
        }
        SolverStatus::MaxIterations => Some("its iteration limit was reached"),
        SolverStatus::MaxTime => Some("its time limit was reached"),
        SolverStatus::NumericalError => Some("a numerical error"),
        SolverStatus::InsufficientProgress => Some("it made insufficient progress"),
        SolverStatus::Unsolved | SolverStatus::CallbackTerminated => {
            Some("it did not run to the end")
        }
    };
    if let Some(why) = why {
        return Err(format!(
            "the QP solver (Clarabel) stopped without a solution: {why}"
        ));
    }
    let z = &solver.solution.x;
    let x = DVector::from_iterator(n, (0..n).map(|j| z[j] * d[j] * beta));
    let active = solver
        .solution
        .s
        .iter()
        .filter(|&&s| s.abs() < 1e-7)
        .count();
    Ok(QpSolution {
        x,
        iterations: solver.solution.iterations,
        active,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constraint_binds_only_when_needed() {
        // min (x−1)² + (y+1)² s.t. y ≥ 0 → (1, 0).
        let a = DMatrix::identity(2, 2);
        let b = DVector::from_vec(vec![1.0, -1.0]);
        let g = DMatrix::from_row_slice(1, 2, &[0.0, 1.0]);
        let s = constrained_least_squares(&a, &b, &g).unwrap();
        assert!(
            (s.x[0] - 1.0).abs() < 1e-7 && s.x[1].abs() < 1e-7,
            "{:?}",
            s.x
        );
        assert_eq!(s.active, 1);
        // Inactive constraint: unconstrained optimum returned.
        let b = DVector::from_vec(vec![1.0, 2.0]);
        let s = constrained_least_squares(&a, &b, &g).unwrap();
        assert!((s.x[1] - 2.0).abs() < 1e-7);
    }

    /// A matrix holding ∞ or NaN (nalgebra's `svd` never returns on it) or too
    /// large to square gives None or a finite decomposition, at once.
    #[test]
    fn svd_refuses_what_it_cannot_decompose() {
        let mut m = DMatrix::from_element(5, 3, 1.0);
        m[(2, 1)] = f64::INFINITY;
        assert!(svd(m.clone(), true, true).is_none());
        m[(2, 1)] = f64::NAN;
        assert!(svd(m, true, true).is_none());
        assert!(svd(DMatrix::zeros(0, 3), true, true).is_none());
        let big = DMatrix::from_fn(6, 3, |i, j| 1e300 * ((i + 1) as f64).powi(j as i32));
        let s = svd(big, true, true).expect("finite entries decompose");
        assert!(s.singular_values.iter().all(|v| v.is_finite()));
        // Descending order, as the callers' rank tests assume.
        assert!(s.singular_values[0] >= s.singular_values[2]);
    }
}
