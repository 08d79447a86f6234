//! Exact solvers for models linear in their parameters: weighted linear least squares
//! (a triangular factor built row by row, [`RowQr`], then the SVD of that small
//! factor), and the same problem under linear inequality constraints as a convex QP
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

/// The triangular factor of a tall least-squares problem, built from blocks of rows:
/// [A | b] = Q·R̃ with R̃ upper triangular of order k + 1. Each block of [`BLOCK`]
/// rows is stacked under the current R̃ and the stack reduced by Householder
/// reflections (Golub & Van Loan, *Matrix Computations*, 4th ed., §5.2.2 and the
/// row-updating of §6.5.4), so the column sums run over independent rows rather than
/// a chain of rotations. The leading k × k block R has AᵀA = RᵀR, so the singular
/// values and right singular vectors of A are those of R; its last column holds
/// (Qᵀb)₁..ₖ. Nothing of size n is stored: a 10⁶-row fit costs one pass over the rows
/// and (k + 1)·(k + 1 + [`BLOCK`]) numbers.
#[derive(Debug, Clone)]
pub struct RowQr {
    k: usize,
    rows: usize,
    /// Rows reduced together: [`BLOCK`], or fewer when the problem has fewer rows.
    block: usize,
    /// The stack, column-major, (k + 1 + block) × (k + 1): R̃ on top (upper
    /// triangular), then `pending` rows not yet reduced.
    stack: Vec<f64>,
    pending: usize,
}

/// Rows reduced together (a stack of R̃ and this many rows per Householder pass).
pub const BLOCK: usize = 128;

impl RowQr {
    /// An empty factor of a problem with `k` unknowns.
    pub fn new(k: usize) -> RowQr {
        RowQr::with_rows(k, BLOCK)
    }

    /// An empty factor of a problem with `k` unknowns and `n` rows: a problem of
    /// fewer than [`BLOCK`] rows gets a stack of its own size, reduced once, when
    /// its last row arrives (the same reflections as a full-size stack reduced at
    /// the end, so the same factor bit for bit, without zeroing and copying a
    /// stack ten times the data).
    pub fn with_rows(k: usize, n: usize) -> RowQr {
        let block = n.clamp(1, BLOCK);
        RowQr {
            k,
            rows: 0,
            block,
            stack: vec![0.0; (k + 1 + block) * (k + 1)],
            pending: 0,
        }
    }

    /// The factor of the matrix `a` (right-hand side zero).
    pub fn of(a: &DMatrix<f64>) -> RowQr {
        let mut qr = RowQr::with_rows(a.ncols(), a.nrows());
        let mut row = vec![0.0; a.ncols()];
        for i in 0..a.nrows() {
            row.iter_mut()
                .zip(a.row(i).iter())
                .for_each(|(r, v)| *r = *v);
            qr.push(&row, 0.0);
        }
        qr
    }

    /// Add the row `a` with right-hand side `b` (a value that is not finite makes
    /// the factor not finite, and [`svd`] of it then refuses).
    pub fn push(&mut self, a: &[f64], b: f64) {
        let (m, h) = (self.k + 1, self.k + 1 + self.block);
        let i = m + self.pending;
        for (j, &v) in a.iter().enumerate() {
            self.stack[j * h + i] = v;
        }
        self.stack[self.k * h + i] = b;
        self.pending += 1;
        self.rows += 1;
        if self.pending == self.block {
            reduce(&mut self.stack, m, h, m + self.pending);
            self.pending = 0;
        }
    }

    /// R̃ (row-major, (k + 1)²) with every row reduced (rows still pending are
    /// reduced in a copy of the stack).
    fn reduced(&self) -> Vec<f64> {
        let (m, h) = (self.k + 1, self.k + 1 + self.block);
        let copy;
        let stack = if self.pending > 0 {
            let mut s = self.stack.clone();
            reduce(&mut s, m, h, m + self.pending);
            copy = s;
            &copy
        } else {
            &self.stack
        };
        let mut r = vec![0.0; m * m];
        for i in 0..m {
            for j in i..m {
                r[i * m + j] = stack[j * h + i];
            }
        }
        r
    }

    /// Rows added so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The k × k factor R (AᵀA = RᵀR).
    pub fn r(&self) -> DMatrix<f64> {
        let m = self.k + 1;
        let r = self.reduced();
        DMatrix::from_fn(self.k, self.k, |i, j| r[i * m + j])
    }

    /// min ‖A·c − b‖ with the minimum norm: c = Σ v_i (u_iᵀ Qᵀb) / σ_i over the
    /// singular values of R above the relative rank tolerance 10⁻¹³·max(n, k)·σ_max
    /// (those of A: the same solution as an SVD of A itself); None if every singular
    /// value is zero or the factor is not finite.
    pub fn solve(&self) -> Option<DVector<f64>> {
        self.solve_with_range().map(|(c, _)| c)
    }

    /// [`RowQr::solve`]'s c and W = V_r·Σ_r⁻¹ (k × rank) over the same singular values
    /// of R (R = U_R·Σ·Vᵀ, A = Q·R): A·W = Q·U_R,r is an orthonormal basis of the range
    /// of A, formed in one pass over A's rows without an SVD of the tall A.
    pub fn solve_with_range(&self) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let m = self.k + 1;
        let r = self.reduced();
        let svd = svd(
            DMatrix::from_fn(self.k, self.k, |i, j| r[i * m + j]),
            true,
            true,
        )?;
        let smax = svd.singular_values.max();
        if smax <= 0.0 {
            return None;
        }
        let tol = smax * 1e-13 * (self.rows.max(self.k) as f64);
        let (u, vt) = (svd.u.as_ref()?, svd.v_t.as_ref()?);
        let qtb = DVector::from_fn(self.k, |i, _| r[i * m + self.k]);
        if !qtb.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut c = DVector::zeros(self.k);
        let mut kept = Vec::with_capacity(self.k);
        for (i, &s) in svd.singular_values.iter().enumerate() {
            if s > tol {
                c += vt.row(i).transpose() * (u.column(i).dot(&qtb) / s);
                kept.push(i);
            }
        }
        let w = DMatrix::from_fn(self.k, kept.len(), |j, q| {
            vt[(kept[q], j)] / svd.singular_values[kept[q]]
        });
        Some((c, w))
    }
}

/// Householder QR in place of the first `rows` rows of the column-major `stack`
/// (leading dimension `h`, `m` columns), whose top m × m block is upper triangular:
/// afterwards that block is the R of the whole stack and the rows below are zero.
fn reduce(stack: &mut [f64], m: usize, h: usize, rows: usize) {
    for j in 0..m {
        let (head, tail) = stack.split_at_mut((j + 1) * h);
        let col = &mut head[j * h..];
        // The reflector zeroes column j below the diagonal: rows j + 1..m of the
        // triangle are zero already, so only the pending rows count.
        let below = &col[m..rows];
        let ss: f64 = below.iter().map(|v| v * v).sum();
        if ss == 0.0 {
            continue;
        }
        let d = col[j];
        let mut norm = (ss + d * d).sqrt();
        if !(norm.is_finite() && ss >= f64::MIN_POSITIVE) {
            // Squares that over- or underflow: work in units of the largest entry.
            let scale = below.iter().fold(d.abs(), |a, v| a.max(v.abs()));
            let sum: f64 = below.iter().map(|v| (v / scale).powi(2)).sum();
            norm = scale * (sum + (d / scale).powi(2)).sqrt();
        }
        let alpha = if d >= 0.0 { -norm } else { norm };
        // v = (d − α, below…); vᵀv = 2·α·(α − d), the reflector I − 2vvᵀ/vᵀv.
        let v0 = d - alpha;
        let beta = alpha * (alpha - d);
        if !(beta.is_finite() && beta != 0.0) {
            continue;
        }
        col[j] = alpha;
        for l in 0..m - j - 1 {
            let other = &mut tail[l * h..(l + 1) * h];
            let dot = v0 * other[j]
                + col[m..rows]
                    .iter()
                    .zip(&other[m..rows])
                    .map(|(v, o)| v * o)
                    .sum::<f64>();
            let f = dot / beta;
            other[j] -= f * v0;
            for (o, v) in other[m..rows].iter_mut().zip(&col[m..rows]) {
                *o -= f * v;
            }
        }
        col[m..rows].iter_mut().for_each(|v| *v = 0.0);
    }
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

    /// The row-by-row factor solves as the SVD of the whole matrix does (the solver
    /// it replaces, [`crate::fit::problem::svd_solve`]), on a well-conditioned, a
    /// graded (columns 10⁰…10¹⁰) and a rank-deficient problem, and has AᵀA = RᵀR.
    #[test]
    fn row_qr_solves_as_the_svd_of_the_whole_matrix() {
        let n = 50;
        let t = |i: usize| 1.0 + 3.0 * i as f64 / (n - 1) as f64;
        let cases = [
            DMatrix::from_fn(n, 3, |i, j| t(i).powi(j as i32 + 1)),
            DMatrix::from_fn(n, 3, |i, j| {
                t(i).powi(j as i32 + 1) * 10f64.powi(5 * j as i32)
            }),
            DMatrix::from_fn(n, 3, |i, j| {
                if j == 2 {
                    2.0 * t(i)
                } else {
                    t(i).powi(j as i32 + 1)
                }
            }),
        ];
        for a in cases {
            let b = DVector::from_fn(n, |i, _| (t(i) * 1.3).sin() + 0.1 * t(i));
            let mut qr = RowQr::new(3);
            // Sized to the rows: reduced once, at the last row, to the same bits.
            let mut sized = RowQr::with_rows(3, n);
            for i in 0..n {
                let row: Vec<f64> = a.row(i).iter().copied().collect();
                qr.push(&row, b[i]);
                sized.push(&row, b[i]);
            }
            assert_eq!(sized.r(), qr.r());
            assert_eq!(sized.solve(), qr.solve());
            let (want, _) = crate::fit::problem::svd_solve(&a, &b).unwrap();
            let got = qr.solve().unwrap();
            let scale = want.norm();
            assert!((&got - &want).norm() <= 1e-9 * scale, "{got} vs {want}");
            let ata = a.transpose() * &a;
            let rtr = qr.r().transpose() * qr.r();
            assert!((&rtr - &ata).norm() <= 1e-12 * ata.norm());
            assert_eq!(qr.rows(), n);
        }
        // Not finite: no solution; empty of rank: none either.
        let mut qr = RowQr::new(2);
        qr.push(&[1.0, f64::NAN], 1.0);
        assert!(qr.solve().is_none());
        let mut qr = RowQr::new(2);
        qr.push(&[0.0, 0.0], 1.0);
        assert!(qr.solve().is_none());
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
