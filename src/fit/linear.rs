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

    /// The factor of the matrix `a` (right-hand side zero): its rows pushed in
    /// order ([`RowQr::push`]), a block's columns copied into the stack at once
    /// (the same stack, so the same factor bit for bit).
    pub fn of(a: &DMatrix<f64>) -> RowQr {
        let (n, k) = a.shape();
        let mut qr = RowQr::with_rows(k, n);
        let (m, h) = (k + 1, k + 1 + qr.block);
        for lo in (0..n).step_by(qr.block) {
            let rows = (n - lo).min(qr.block);
            for (j, col) in a.as_slice().chunks_exact(n).enumerate() {
                qr.stack[j * h + m..j * h + m + rows].copy_from_slice(&col[lo..lo + rows]);
            }
            qr.stack[k * h + m..k * h + m + rows].fill(0.0);
            qr.rows += rows;
            qr.pending = rows;
            if rows == qr.block {
                reduce(&mut qr.stack, m, h, m + rows);
                qr.pending = 0;
            }
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

    /// Add the rows of `other` (a factor of the same k): the rows of its R̃ pushed
    /// as rows. [A₁; A₂] and [R̃₁; R̃₂] have the same normal equations and residual
    /// norm, so the result is a factor of the stacked problem (the tall-skinny QR of
    /// Demmel, Grigori, Hoemmen & Langou, SIAM J. Sci. Comput. 34 (2012) A206–A239);
    /// the row count is the two problems' rows.
    pub fn append(&mut self, other: &RowQr) {
        let (k, m, rows) = (self.k, self.k + 1, self.rows);
        let r = other.reduced();
        for row in r.chunks_exact(m) {
            self.push(&row[..k], row[k]);
        }
        self.rows = rows + other.rows;
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

    /// Unknowns k.
    pub fn unknowns(&self) -> usize {
        self.k
    }

    /// The k × k factor R (AᵀA = RᵀR).
    pub fn r(&self) -> DMatrix<f64> {
        DMatrix::from_column_slice(self.k, self.k, &self.r_columns())
    }

    /// R column-major (k²), without a matrix type: what [`SmallSvd::of`] takes.
    pub fn r_columns(&self) -> Vec<f64> {
        r_columns_of(&self.reduced(), self.k)
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
        let (k, m) = (self.k, self.k + 1);
        let r = self.reduced();
        let qtb: Vec<f64> = (0..k).map(|i| r[i * m + k]).collect();
        if !qtb.iter().all(|v| v.is_finite()) {
            return None;
        }
        let svd = SmallSvd::of(&r_columns_of(&r, k), k)?;
        let smax = svd.sigma[0];
        if smax <= 0.0 {
            return None;
        }
        let tol = smax * 1e-13 * (self.rows.max(k) as f64);
        let rank = svd.sigma.iter().take_while(|&&s| s > tol).count();
        let mut c = DVector::zeros(k);
        for q in 0..rank {
            let coef = (0..k).map(|i| svd.u(i, q) * qtb[i]).sum::<f64>() / svd.sigma[q];
            for j in 0..k {
                c[j] += svd.v(j, q) * coef;
            }
        }
        let w = DMatrix::from_fn(k, rank, |j, q| svd.v(j, q) / svd.sigma[q]);
        Some((c, w))
    }
}

/// The leading k × k block of the row-major (k + 1)² R̃, column-major.
fn r_columns_of(r: &[f64], k: usize) -> Vec<f64> {
    let m = k + 1;
    let mut out = vec![0.0; k * k];
    for j in 0..k {
        for i in 0..=j {
            out[j * k + i] = r[i * m + j];
        }
    }
    out
}

/// The SVD A = U·Σ·Vᵀ of a small square matrix (a [`RowQr`] factor R, k × k) by
/// one-sided Jacobi rotations (Hestenes 1958; Demmel & Veselić, SIAM J. Matrix Anal.
/// Appl. 13, 1992, Alg. 4.1): plane rotations V_pq applied to the columns of A until
/// every pair is orthogonal to the working precision, |a_pᵀa_q| ≤ ε·‖a_p‖·‖a_q‖;
/// then A·V = U·Σ with σ_j = ‖(A·V)_j‖. Each small singular value is found to a
/// relative accuracy (the QR iteration of a bidiagonal form only to ε·σ_max), in
/// one buffer of 2k² + k numbers: no allocation per step, unlike a general SVD of a
/// dynamic matrix (two of those were ~15 % of a whole Yeoh fit call).
#[derive(Debug, Clone)]
pub struct SmallSvd {
    k: usize,
    /// Singular values in descending order.
    pub sigma: Vec<f64>,
    /// A·V = U·Σ, column-major.
    us: Vec<f64>,
    /// V, column-major.
    v: Vec<f64>,
}

/// Sweeps of [`SmallSvd::of`] before it gives up (LAPACK's `dgesvj` stops at 30;
/// a k ≤ 10 matrix converges in ≲ 10).
const JACOBI_SWEEPS: usize = 30;

impl SmallSvd {
    /// The SVD of the column-major k × k matrix `a`, or None if `a` is empty, holds a
    /// value that is not finite, or the rotations do not converge in
    /// [`JACOBI_SWEEPS`] sweeps. The matrix is scaled by its largest entry first, so
    /// that no column norm over- or underflows for entries up to 10³⁰⁸.
    pub fn of(a: &[f64], k: usize) -> Option<SmallSvd> {
        if k == 0 || a.len() != k * k || !a.iter().all(|v| v.is_finite()) {
            return None;
        }
        let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut us: Vec<f64> = if scale > 0.0 {
            a.iter().map(|v| v / scale).collect()
        } else {
            a.to_vec()
        };
        let mut v = vec![0.0; k * k];
        (0..k).for_each(|j| v[j * k + j] = 1.0);
        let mut converged = false;
        for _ in 0..JACOBI_SWEEPS {
            let mut rotated = false;
            for p in 0..k {
                for q in p + 1..k {
                    rotated |= rotate(&mut us, &mut v, k, p, q);
                }
            }
            if !rotated {
                converged = true;
                break;
            }
        }
        if !converged {
            return None;
        }
        let mut sigma: Vec<f64> = (0..k)
            .map(|j| {
                us[j * k..(j + 1) * k]
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        // Descending order (selection sort: k is small).
        for j in 0..k {
            let top = (j..k).fold(j, |b, i| if sigma[i] > sigma[b] { i } else { b });
            if top != j {
                sigma.swap(j, top);
                for i in 0..k {
                    us.swap(j * k + i, top * k + i);
                    v.swap(j * k + i, top * k + i);
                }
            }
        }
        if scale > 0.0 {
            us.iter_mut().for_each(|x| *x *= scale);
            sigma.iter_mut().for_each(|s| *s *= scale);
        }
        sigma
            .iter()
            .all(|s| s.is_finite())
            .then_some(SmallSvd { k, sigma, us, v })
    }

    /// U_iq (zero in a column whose σ_q is zero).
    pub fn u(&self, i: usize, q: usize) -> f64 {
        let s = self.sigma[q];
        if s > 0.0 {
            self.us[q * self.k + i] / s
        } else {
            0.0
        }
    }

    /// V_jq.
    pub fn v(&self, j: usize, q: usize) -> f64 {
        self.v[q * self.k + j]
    }
}

/// One Jacobi rotation of columns p < q of `us` (and of `v`) that makes them
/// orthogonal: with α = ‖a_p‖², β = ‖a_q‖², γ = a_pᵀa_q, ζ = (β − α)/(2γ),
/// t = sign(ζ)/(|ζ| + √(1 + ζ²)) (t = 1/(2ζ) where ζ² would overflow),
/// c = 1/√(1 + t²), s = c·t (Golub & Van Loan, 4th ed., §8.6.3). False when the
/// pair is orthogonal already.
fn rotate(us: &mut [f64], v: &mut [f64], k: usize, p: usize, q: usize) -> bool {
    let (alpha, beta, gamma) = us[p * k..(p + 1) * k]
        .iter()
        .zip(&us[q * k..(q + 1) * k])
        .fold((0.0, 0.0, 0.0), |(a, b, g), (x, y)| {
            (a + x * x, b + y * y, g + x * y)
        });
    if gamma.abs() <= f64::EPSILON * (alpha.sqrt() * beta.sqrt()) {
        return false;
    }
    let zeta = (beta - alpha) / (2.0 * gamma);
    let t = if zeta.abs() < 1e150 {
        zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt())
    } else {
        0.5 / zeta
    };
    let c = 1.0 / (1.0 + t * t).sqrt();
    let s = c * t;
    for m in [us, v] {
        let (head, tail) = m.split_at_mut(q * k);
        for (x, y) in head[p * k..(p + 1) * k].iter_mut().zip(&mut tail[..k]) {
            let (a, b) = (*x, *y);
            *x = c * a - s * b;
            *y = s * a + c * b;
        }
    }
    true
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

    /// [`RowQr::of`] (a block's columns copied at once) is the factor of the rows
    /// pushed one by one with a zero right-hand side, bit for bit: the whole stack,
    /// rows reduced and pending, for row counts around the block size.
    #[test]
    fn of_is_the_rows_pushed_one_by_one() {
        for n in [0, 1, 5, BLOCK - 1, BLOCK, BLOCK + 1, 2 * BLOCK, 300] {
            for k in [1, 3, 4] {
                let a = DMatrix::from_fn(n, k, |i, j| {
                    ((i * 7 + j * 13) as f64 * 0.37).sin() + j as f64
                });
                let mut pushed = RowQr::with_rows(k, n);
                for i in 0..n {
                    let row: Vec<f64> = (0..k).map(|j| a[(i, j)]).collect();
                    pushed.push(&row, 0.0);
                }
                let of = RowQr::of(&a);
                assert_eq!(
                    (of.rows, of.pending),
                    (pushed.rows, pushed.pending),
                    "{n} × {k}"
                );
                let bits = |q: &RowQr| q.stack.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&of), bits(&pushed), "{n} × {k}");
            }
        }
    }

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
            // Blocks factored apart and appended: a factor of the whole problem (the
            // same normal equations to round-off, the same solution as the SVD).
            let mut appended = RowQr::new(3);
            for rows in [0..17, 17..37, 37..n] {
                let mut block = RowQr::with_rows(3, rows.len());
                for i in rows {
                    let row: Vec<f64> = a.row(i).iter().copied().collect();
                    block.push(&row, b[i]);
                }
                appended.append(&block);
            }
            assert_eq!(appended.rows(), n);
            let rtr = appended.r().transpose() * appended.r();
            assert!((&rtr - &ata).norm() <= 1e-12 * ata.norm());
            let got = appended.solve().unwrap();
            assert!((&got - &want).norm() <= 1e-9 * scale, "{got} vs {want}");
        }
        // Not finite: no solution; empty of rank: none either.
        let mut qr = RowQr::new(2);
        qr.push(&[1.0, f64::NAN], 1.0);
        assert!(qr.solve().is_none());
        let mut qr = RowQr::new(2);
        qr.push(&[0.0, 0.0], 1.0);
        assert!(qr.solve().is_none());
    }

    /// The Jacobi SVD of small square matrices agrees with nalgebra's: singular
    /// values to 1e-13 of σ_max, U·Σ·Vᵀ = A to 1e-14 of ‖A‖, VᵀV = I to 1e-14, on
    /// random, graded (rows and columns 10⁰…10¹²), rank-deficient and huge (10³⁰⁰)
    /// matrices of order 1–6 (round-off of either method is ~k·ε·σ_max); a value
    /// that is not finite gives None.
    #[test]
    fn small_svd_agrees_with_the_general_svd() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for k in 1..=6 {
            for case in 0..4 {
                let a = DMatrix::from_fn(k, k, |i, j| {
                    let v = uniform();
                    match case {
                        1 => v * 10f64.powi((3 * (i + j)) as i32 % 13),
                        2 if j == k - 1 && k > 1 => 0.0,
                        3 => v * 1e300,
                        _ => v,
                    }
                });
                let a = if case == 2 && k > 1 {
                    // The last column a combination of the first: rank k − 1.
                    let mut a = a;
                    let c0 = a.column(0).clone_owned();
                    a.column_mut(k - 1).copy_from(&(c0 * 2.0));
                    a
                } else {
                    a
                };
                let s = SmallSvd::of(a.as_slice(), k).expect("finite");
                let want = svd(a.clone(), false, false).unwrap().singular_values;
                let smax = want[0];
                for q in 0..k {
                    assert!(
                        (s.sigma[q] - want[q]).abs() <= 1e-13 * smax,
                        "k {k} case {case}"
                    );
                }
                let v = DMatrix::from_fn(k, k, |i, j| s.v(i, j));
                let us = DMatrix::from_fn(k, k, |i, j| s.u(i, j) * s.sigma[j]);
                let anorm = a.norm();
                assert!((&us * v.transpose() - &a).norm() <= 1e-14 * anorm * k as f64);
                assert!((v.transpose() * &v - DMatrix::identity(k, k)).norm() <= 1e-14 * k as f64);
            }
        }
        assert!(SmallSvd::of(&[1.0, f64::NAN, 0.0, 1.0], 2).is_none());
        assert!(SmallSvd::of(&[1.0, f64::INFINITY, 0.0, 1.0], 2).is_none());
        assert!(SmallSvd::of(&[], 0).is_none());
        let zero = SmallSvd::of(&[0.0; 4], 2).expect("zero matrix");
        assert_eq!(zero.sigma, vec![0.0, 0.0]);
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
