//! Non-negative least squares, min ‖A·x − b‖² subject to x ≥ 0, by the active-set
//! method of Lawson & Hanson (1974, *Solving Least Squares Problems*, ch. 23) on the
//! normal equations G = AᵀA, h = Aᵀb (columns scaled to unit norm first).
//!
//! The passive set P holds the free coefficients. Each outer step moves into P the
//! coefficient with the largest gradient w = h − G·x (the most negative
//! multiplier), then solves G_PP·z = h_P (a Cholesky factor of G_PP kept across the
//! steps: a row appended when a coefficient enters, Givens rotations when one
//! leaves); while some z ≤ 0 it steps from x towards z until the first coefficient
//! reaches zero and drops it. It ends when every coefficient outside P has
//! w ≤ tol: the KKT conditions x ≥ 0, w ≤ 0 off P, w = 0 on P hold. A start (warm
//! start) seeds P with the coefficients a previous, similar problem left positive,
//! less those whose solution on it is not positive.
//!
//! No crate of the Rust ecosystem offers a maintained NNLS (the search found only
//! R, Python and JavaScript packages); Clarabel solves the same problem as a QP and
//! is the reference in the tests and the baseline of `benches/relaxation.rs`.

use nalgebra::{DMatrix, DVector};

/// Result of [`nnls`].
#[derive(Debug, Clone)]
pub struct NnlsSolution {
    /// Minimiser (every entry ≥ 0).
    pub x: DVector<f64>,
    /// Outer (add-a-coefficient) iterations.
    pub iterations: usize,
}

/// Solve min ‖A·x − b‖², x ≥ 0. `start`: coefficients that are expected to be
/// positive (a warm start; any subset is valid). Err when a value is not finite or
/// the iteration limit (3·k) is reached.
pub fn nnls(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    start: Option<&[bool]>,
) -> Result<NnlsSolution, String> {
    let k = a.ncols();
    // A value of A that is not finite makes its column's squared norm G_jj infinite
    // or NaN (squares cannot cancel), which [`nnls_normal`] refuses: only b is
    // checked here.
    if !b.iter().all(|v| v.is_finite()) {
        return Err("the problem holds a value that is not finite".into());
    }
    let col = |j: usize| &a.as_slice()[j * a.nrows()..(j + 1) * a.nrows()];
    let g = gram(a);
    let h = DVector::from_fn(k, |i, _| dot(col(i), b.as_slice()));
    nnls_normal(&g, &h, start)
}

/// [`nnls`] from the normal equations G = AᵀA and h = Aᵀb (formed by the caller,
/// e.g. in one pass over the rows with other products it needs): the same solution
/// as [`nnls`] of the A and b they came from, bit for bit when they hold the same
/// dot products. The columns are scaled to unit norm through G's diagonal
/// (G_ij/(√G_ii·√G_jj)); a zero diagonal leaves that coefficient at 0.
/// [`NnlsWork::solve`] without its kept work space.
pub fn nnls_normal(
    g: &DMatrix<f64>,
    h: &DVector<f64>,
    start: Option<&[bool]>,
) -> Result<NnlsSolution, String> {
    let mut work = NnlsWork::new(h.len());
    let iterations = work.solve(g.as_slice(), h.as_slice(), start)?;
    Ok(NnlsSolution {
        x: DVector::from_column_slice(work.x()),
        iterations,
    })
}

/// The work space of [`nnls_normal`] for problems of k coefficients, kept by a
/// caller that solves many (the variable projection, one an evaluation): no
/// allocation a solve.
#[derive(Debug, Clone)]
pub struct NnlsWork {
    k: usize,
    /// 1/√G_jj (0 for a zero column).
    d: Vec<f64>,
    /// The scaled normal equations.
    gs: Vec<f64>,
    hs: Vec<f64>,
    /// The scaled solution, then the solution.
    x: Vec<f64>,
    z: Vec<f64>,
    w: Vec<f64>,
    leaving: Vec<bool>,
    /// The empty start.
    cold: Vec<bool>,
    f: PassiveFactor,
}

impl NnlsWork {
    /// The work space of problems of `k` coefficients.
    pub fn new(k: usize) -> NnlsWork {
        NnlsWork {
            k,
            d: vec![0.0; k],
            gs: Vec::with_capacity(k * k),
            hs: vec![0.0; k],
            x: vec![0.0; k],
            z: vec![0.0; k],
            w: vec![0.0; k],
            leaving: vec![false; k],
            cold: vec![false; k],
            f: PassiveFactor::new(k),
        }
    }

    /// [`nnls_normal`] of G (column-major k × k) and h: the solution into
    /// [`NnlsWork::x`], the outer iterations returned. Err as [`nnls`] (a value
    /// not finite, no convergence, a singular free set), or when G and h are not
    /// of this work space's k.
    pub fn solve(&mut self, g: &[f64], h: &[f64], start: Option<&[bool]>) -> Result<usize, String> {
        let k = self.k;
        if g.len() != k * k || h.len() != k {
            return Err(format!(
                "normal equations of {} coefficients for a work space of {k}",
                h.len()
            ));
        }
        let finite = |v: &[f64]| v.iter().all(|v| v.is_finite());
        if !(finite(g) && finite(h)) {
            return Err("the problem holds a value that is not finite".into());
        }
        for (j, dj) in self.d.iter_mut().enumerate() {
            *dj = unit_scale(g[j * k + j]);
        }
        let d = &self.d;
        self.gs.clear();
        self.gs.extend_from_slice(g);
        for (gj, dj) in self.gs.chunks_exact_mut(k.max(1)).zip(d) {
            for (v, di) in gj.iter_mut().zip(d) {
                *v = *v * di * dj;
            }
        }
        for ((hs, h), di) in self.hs.iter_mut().zip(h).zip(d) {
            *hs = h * di;
        }
        let start = start.unwrap_or(&self.cold);
        let iterations = solve_normal(
            &self.gs,
            &self.hs,
            start,
            d,
            &mut self.f,
            [&mut self.x, &mut self.z, &mut self.w],
            &mut self.leaving,
        )?;
        for (x, s) in self.x.iter_mut().zip(d) {
            *x *= s;
        }
        Ok(iterations)
    }

    /// The solution of the last [`NnlsWork::solve`] that succeeded.
    pub fn x(&self) -> &[f64] {
        &self.x
    }
}

/// 1/‖a‖ of a column whose squared norm is `square` (0 for a zero column).
fn unit_scale(square: f64) -> f64 {
    let s = square.sqrt();
    if s > 0.0 {
        1.0 / s
    } else {
        0.0
    }
}

/// Σ aₖ·bₖ in [`LANES`] interleaved partial sums (k mod [`LANES`]) added at the end:
/// independent sums the compiler keeps in vector registers, where a single running
/// sum is a chain of dependent additions, one element per add latency (4× to 8×
/// slower on a long column). Its rounding differs from the running sum's in the
/// last bits. Compiled for AVX2 (four f64 a register) where the processor has it,
/// else for the baseline (two): the same arithmetic, so the same bits either way.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (detected on the line above).
        return unsafe { dot_avx2(a, b) };
    }
    dot_lanes(a, b)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn dot_avx2(a: &[f64], b: &[f64]) -> f64 {
    dot_lanes(a, b)
}

/// The arithmetic of [`dot`].
#[inline(always)]
fn dot_lanes(a: &[f64], b: &[f64]) -> f64 {
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ta, tb) = (ca.remainder(), cb.remainder());
    let mut acc = [0.0; LANES];
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            acc[l] += x[l] * y[l];
        }
    }
    total(&acc, ta, tb)
}

/// The end of [`dot`]: the partial sums `acc` added in order, plus the products of
/// the remainders `a`, `b` (the elements past the last whole chunk of [`LANES`]).
/// Never inlined: the partial sums of [`dot_2x2`]'s four products then stay in
/// registers of their own, lane by lane (inlined, the compiler packed the four
/// products' partial sums into shared registers, for this ordered sum, with a
/// shuffle for every operand of the loop).
#[inline(never)]
fn total(acc: &[f64; LANES], a: &[f64], b: &[f64]) -> f64 {
    let tail: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    acc.iter().sum::<f64>() + tail
}

/// Partial sums of [`dot`]: two AVX registers of four.
const LANES: usize = 8;

/// AᵀA, each entry [`dot`] of its two columns bit for bit, taken a 2 × 2 block of
/// columns at a time ([`dot_2x2`]: four products from one read of four columns,
/// where four [`dot`]s read eight); the last column of an odd count by [`dot`].
/// Compiled for AVX2 where the processor has it, as [`dot`] is.
fn gram(a: &DMatrix<f64>) -> DMatrix<f64> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (detected on the line above).
        return unsafe { gram_avx2(a) };
    }
    gram_lanes(a)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gram_avx2(a: &DMatrix<f64>) -> DMatrix<f64> {
    gram_lanes(a)
}

/// The arithmetic of [`gram`].
#[inline(always)]
fn gram_lanes(a: &DMatrix<f64>) -> DMatrix<f64> {
    let (m, k) = a.shape();
    let col = |j: usize| &a.as_slice()[j * m..(j + 1) * m];
    let mut g = DMatrix::zeros(k, k);
    let mut set = |i: usize, j: usize, v: f64| {
        g[(i, j)] = v;
        g[(j, i)] = v;
    };
    for j in (0..k - k % 2).step_by(2) {
        for i in (0..=j).step_by(2) {
            let v = dot_2x2([col(i), col(i + 1)], [col(j), col(j + 1)]);
            set(i, j, v[0]);
            set(i, j + 1, v[1]);
            set(i + 1, j, v[2]);
            set(i + 1, j + 1, v[3]);
        }
    }
    if k % 2 == 1 {
        for i in 0..k {
            set(i, k - 1, dot_lanes(col(i), col(k - 1)));
        }
    }
    g
}

/// [a₀·b₀, a₀·b₁, a₁·b₀, a₁·b₁], each by [`dot`]'s arithmetic (the same partial
/// sums in the same order, so the same bits) in one pass over the four columns.
#[inline(always)]
fn dot_2x2(a: [&[f64]; 2], b: [&[f64]; 2]) -> [f64; 4] {
    fn chunks(c: &[f64]) -> std::slice::ChunksExact<'_, f64> {
        c.chunks_exact(LANES)
    }
    let pairs = [(a[0], b[0]), (a[0], b[1]), (a[1], b[0]), (a[1], b[1])];
    let mut acc = [[0.0; LANES]; 4];
    for (((x0, x1), y0), y1) in chunks(a[0])
        .zip(chunks(a[1]))
        .zip(chunks(b[0]))
        .zip(chunks(b[1]))
    {
        for l in 0..LANES {
            acc[0][l] += x0[l] * y0[l];
            acc[1][l] += x0[l] * y1[l];
            acc[2][l] += x1[l] * y0[l];
            acc[3][l] += x1[l] * y1[l];
        }
    }
    std::array::from_fn(|p| {
        let (x, y) = pairs[p];
        total(&acc[p], chunks(x).remainder(), chunks(y).remainder())
    })
}

/// Lawson–Hanson on the scaled normal equations (module notes): the scaled
/// solution into `x`, the outer iterations returned. The work space is the
/// caller's ([`NnlsWork`]; `x`, `z`, `w` of k entries, every mark of `leaving`
/// clear): the factor of G_PP is kept across the steps ([`PassiveFactor`]), and
/// w = h − G·x takes only P's columns of G (x is zero off P).
fn solve_normal(
    g: &[f64],
    h: &[f64],
    start: &[bool],
    d: &[f64],
    f: &mut PassiveFactor,
    [x, z, w]: [&mut Vec<f64>; 3],
    leaving: &mut [bool],
) -> Result<usize, String> {
    let k = h.len();
    // Gradient tolerance: rounding of the normal equations, relative to ‖h‖∞.
    let tol = 1e-10
        * h.iter()
            .fold(0.0, |m: f64, v| m.max(v.abs()))
            .max(f64::MIN_POSITIVE);
    let usable = |j: usize| d[j] > 0.0;
    f.clear();
    x.fill(0.0);
    z.fill(0.0);
    leaving.fill(false);
    warm_start(f, g, h, start, &usable, z, leaving);
    for &j in &f.order {
        x[j] = z[j];
    }
    let mut iterations = 0;
    loop {
        // w = h − G·x: the columns of P only.
        w.copy_from_slice(h);
        for &j in &f.order {
            let xj = x[j];
            for (wi, gi) in w.iter_mut().zip(&g[j * k..(j + 1) * k]) {
                *wi -= gi * xj;
            }
        }
        let best = (0..k)
            .filter(|&j| !f.passive[j] && usable(j))
            .map(|j| (j, w[j]))
            .filter(|&(_, w)| w > tol)
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((t, _)) = best else {
            return Ok(iterations);
        };
        iterations += 1;
        if iterations > 3 * k.max(1) {
            return Err(format!("no convergence in {} iterations", 3 * k));
        }
        if !f.push(g, h, t) {
            return Err("the normal equations on the free set are singular".into());
        }
        // Inner loop: keep the solution on P feasible.
        loop {
            if !f.solve(z) {
                return Err("the normal equations on the free set are singular".into());
            }
            if f.order.iter().all(|&j| z[j] > 0.0) {
                for &j in &f.order {
                    x[j] = z[j];
                }
                break;
            }
            let alpha = f
                .order
                .iter()
                .filter(|&&j| z[j] <= 0.0)
                .map(|&j| x[j] / (x[j] - z[j]))
                .fold(1.0, f64::min);
            for &j in &f.order {
                x[j] += alpha * (z[j] - x[j]);
                if x[j] <= 0.0 || (z[j] <= 0.0 && x[j] <= 1e-15) {
                    leaving[j] = true;
                    x[j] = 0.0;
                }
            }
            f.remove(leaving);
            if f.order.is_empty() {
                break;
            }
        }
    }
}

/// Seed P with the start's usable coefficients (a coefficient that would make G_PP
/// singular is left out: the start is only a hint), then drop every coefficient
/// whose solution on P is not positive and solve again, until it is: a feasible
/// point (the least-squares solution on P, in `z`) from which the steps go on as
/// from the cold start x = 0. Leaves P empty if nothing of the start survives.
fn warm_start(
    f: &mut PassiveFactor,
    g: &[f64],
    h: &[f64],
    start: &[bool],
    usable: &dyn Fn(usize) -> bool,
    z: &mut [f64],
    leaving: &mut [bool],
) {
    for j in (0..start.len().min(h.len())).filter(|&j| start[j] && usable(j)) {
        f.push(g, h, j);
    }
    while !f.order.is_empty() {
        if !f.solve(z) {
            f.clear();
            return;
        }
        let mut any = false;
        for &j in &f.order {
            if z[j] <= 0.0 {
                leaving[j] = true;
                any = true;
            }
        }
        if !any {
            return;
        }
        f.remove(leaving);
    }
}

/// The Cholesky factor L·Lᵀ = G_PP of the passive set P, kept across the active
/// set's steps (Lawson & Hanson update their QR factors the same way; here the
/// factor of the normal equations). A coefficient entering P appends a row to L
/// (forward substitution against the rows before it, O(|P|²) instead of a fresh
/// O(|P|³) factorisation: the row is the one a fresh factorisation with P in entry
/// order would compute, bit for bit); a coefficient leaving P deletes its row and
/// rotates the factor back to triangular form ([`PassiveFactor::delete`]). No
/// allocation after [`PassiveFactor::new`]. y = L⁻¹·h_P is kept alongside, so a
/// solve is one back substitution.
#[derive(Debug, Clone)]
struct PassiveFactor {
    k: usize,
    /// P in entry order: row r of L belongs to `order[r]`.
    order: Vec<usize>,
    passive: Vec<bool>,
    /// L by rows, packed: row r in `l[r(r+1)/2 ..][..r + 1]`.
    l: Vec<f64>,
    y: Vec<f64>,
    /// Work: the solution on P.
    s: Vec<f64>,
}

/// Start of row r of a packed lower triangle.
fn row_start(r: usize) -> usize {
    r * (r + 1) / 2
}

/// Σ aᵢ·bᵢ in order, for the factor's short rows (at most |P| entries; [`dot`]'s
/// lanes and dispatch cost more than they save there).
fn short_dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl PassiveFactor {
    fn new(k: usize) -> PassiveFactor {
        PassiveFactor {
            k,
            order: Vec::with_capacity(k),
            passive: vec![false; k],
            l: Vec::with_capacity(row_start(k)),
            y: Vec::with_capacity(k),
            s: vec![0.0; k],
        }
    }

    fn clear(&mut self) {
        for &j in &self.order {
            self.passive[j] = false;
        }
        self.order.clear();
        self.y.clear();
        self.l.clear();
    }

    /// Append coefficient t to P (G column-major k × k): the new row
    /// ℓ = L⁻¹·G_P,t, pivot √(G_tt − ℓ·ℓ), and y_t = (h_t − ℓ·y)/pivot. False (and P
    /// unchanged) when the pivot is not positive: G_PP with t is not positive
    /// definite in rounding (t's column depends on P's).
    fn push(&mut self, g: &[f64], h: &[f64], t: usize) -> bool {
        let (k, r) = (self.k, self.order.len());
        let gt = &g[t * k..(t + 1) * k];
        for c in 0..r {
            let (rows, row) = self.l.split_at(row_start(r));
            let lc = &rows[row_start(c)..row_start(c + 1)];
            let v = (gt[self.order[c]] - short_dot(&row[..c], &lc[..c])) / lc[c];
            self.l.push(v);
        }
        let row = &self.l[row_start(r)..];
        let pivot = gt[t] - short_dot(row, row);
        if !(pivot > 0.0 && pivot.is_finite()) {
            self.l.truncate(row_start(r));
            return false;
        }
        let d = pivot.sqrt();
        self.y.push((h[t] - short_dot(row, &self.y)) / d);
        self.l.push(d);
        self.order.push(t);
        self.passive[t] = true;
        true
    }

    /// Take the coefficients marked in `leaving` out of P (and clear the marks),
    /// each by [`PassiveFactor::delete`].
    fn remove(&mut self, leaving: &mut [bool]) {
        let mut r = 0;
        while r < self.order.len() {
            let j = self.order[r];
            if leaving[j] {
                leaving[j] = false;
                self.delete(r);
            } else {
                r += 1;
            }
        }
    }

    /// Take row and column r out of G_PP's factor: L without row r is lower
    /// triangular but for one entry right of the diagonal in each later row; Givens
    /// rotations of the column pairs (c, c + 1), c = r … |P| − 2, fold each into its
    /// diagonal (the rotation that zeroes row c + 1's entry in column c + 1), which
    /// leaves the last column zero (Golub & Van Loan, *Matrix Computations*, 4th
    /// ed., §6.5, deleting a column of a QR factorisation: Lᵀ is that R). The
    /// product L·Lᵀ keeps its value since the rotations are orthogonal; L·y = h_P
    /// keeps holding with y rotated alike. O((|P| − r)²) instead of a factorisation.
    fn delete(&mut self, r: usize) {
        let m = self.order.len();
        for c in r..m - 1 {
            let d = row_start(c + 1);
            let (a, b) = (self.l[d + c], self.l[d + c + 1]);
            let rho = a.hypot(b);
            let (cs, sn) = (a / rho, b / rho);
            self.l[d + c] = rho;
            self.l[d + c + 1] = 0.0;
            for q in c + 2..m {
                let e = row_start(q) + c;
                let (u, v) = (self.l[e], self.l[e + 1]);
                self.l[e] = cs * u + sn * v;
                self.l[e + 1] = cs * v - sn * u;
            }
            let (u, v) = (self.y[c], self.y[c + 1]);
            self.y[c] = cs * u + sn * v;
            self.y[c + 1] = cs * v - sn * u;
        }
        // Row q > r moves up to q − 1, without its last (now zero) entry.
        for q in r + 1..m {
            let from = row_start(q);
            self.l.copy_within(from..from + q, row_start(q - 1));
        }
        self.l.truncate(row_start(m - 1));
        self.y.truncate(m - 1);
        self.passive[self.order.remove(r)] = false;
    }

    /// z_P = L⁻ᵀ·y (back substitution) into z's entries on P (the others are not
    /// written). False if z_P is not finite.
    fn solve(&mut self, z: &mut [f64]) -> bool {
        let m = self.order.len();
        let s = &mut self.s[..m];
        for r in (0..m).rev() {
            let below: f64 = (r + 1..m).map(|q| self.l[row_start(q) + r] * s[q]).sum();
            s[r] = (self.y[r] - below) / self.l[row_start(r) + r];
        }
        for (&j, &v) in self.order.iter().zip(s.iter()) {
            z[j] = v;
        }
        s.iter().all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::linear::constrained_least_squares;

    /// KKT residual of x for min ½‖Ax − b‖², x ≥ 0, relative to ‖Aᵀb‖∞: the
    /// gradient w = Aᵀ(b − Ax) must vanish where x > 0 and be ≤ 0 where x = 0.
    fn kkt(a: &DMatrix<f64>, b: &DVector<f64>, x: &DVector<f64>) -> f64 {
        assert!(x.iter().all(|&v| v >= 0.0));
        let w = a.tr_mul(&(b - a * x));
        let scale = a.tr_mul(b).amax().max(f64::MIN_POSITIVE);
        (0..x.len())
            .map(|j| if x[j] > 0.0 { w[j].abs() } else { w[j].max(0.0) } / scale)
            .fold(0.0, f64::max)
    }

    /// A Prony-like grid: decaying exponentials at log-spaced τ, data from three.
    fn prony(n: usize, k: usize) -> (DMatrix<f64>, DVector<f64>) {
        let t: Vec<f64> = (0..n)
            .map(|i| 10f64.powf(-1.0 + 4.0 * i as f64 / n as f64))
            .collect();
        let taus: Vec<f64> = (0..k - 1)
            .map(|j| 10f64.powf(-1.5 + 5.0 * j as f64 / (k - 2) as f64))
            .collect();
        let a = DMatrix::from_fn(n, k, |i, j| {
            if j == 0 {
                1.0
            } else {
                (-t[i] / taus[j - 1]).exp()
            }
        });
        let b = DVector::from_fn(n, |i, _| {
            1.0 + 2.0 * (-t[i] / 0.7).exp()
                + 0.5 * (-t[i] / 40.0).exp()
                + 1e-3 * (i as f64 * 0.37).sin()
        });
        (a, b)
    }

    #[test]
    fn matches_clarabel_on_a_prony_grid() {
        let (a, b) = prony(200, 37);
        let ours = nnls(&a, &b, None).unwrap();
        let qp = constrained_least_squares(&a, &b, &DMatrix::identity(37, 37)).unwrap();
        let qx = qp.x.map(|v| v.max(0.0));
        let cost = |x: &DVector<f64>| (&a * x - &b).norm_squared();
        // Same optimum: the active-set solution is at least as good as the interior
        // point's (which stops at a duality-gap tolerance) and satisfies KKT.
        assert!(
            cost(&ours.x) <= cost(&qx) * (1.0 + 1e-9),
            "{} vs {}",
            cost(&ours.x),
            cost(&qx)
        );
        assert!(kkt(&a, &b, &ours.x) < 1e-8, "KKT {}", kkt(&a, &b, &ours.x));
        assert!(ours.x.iter().all(|&v| v >= 0.0));
        // A warm start from the answer ends at once, at the same point.
        let start: Vec<bool> = ours.x.iter().map(|&v| v > 0.0).collect();
        let warm = nnls(&a, &b, Some(&start)).unwrap();
        assert_eq!(warm.iterations, 0);
        assert!((&warm.x - &ours.x).amax() <= 1e-9 * ours.x.amax());
    }

    #[test]
    fn random_problems_meet_kkt_and_clarabel() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for case in 0..200 {
            let (n, k) = (rng.gen_range(12..30), rng.gen_range(1..12));
            let a = DMatrix::from_fn(n, k, |_, _| rng.gen_range(-1.0..1.0));
            let b = DVector::from_fn(n, |_, _| rng.gen_range(-1.0..1.0));
            let ours = nnls(&a, &b, None).expect("full column rank");
            let qp = constrained_least_squares(&a, &b, &DMatrix::identity(k, k)).unwrap();
            let cost = |x: &DVector<f64>| (&a * x - &b).norm_squared();
            let qx = qp.x.map(|v| v.max(0.0));
            assert!(
                cost(&ours.x) <= cost(&qx) + 1e-9 * b.norm_squared(),
                "case {case}"
            );
            assert!(
                kkt(&a, &b, &ours.x) < 1e-8,
                "case {case}: KKT {}",
                kkt(&a, &b, &ours.x)
            );
        }
    }

    /// The lane-split dot product is the running sum's to rounding (10⁻¹⁴ of Σ|aₖbₖ|)
    /// at every length around the lane count, remainders included.
    #[test]
    fn dot_is_the_sum_of_products() {
        for n in 0..40 {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
            let b: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 1.3).cos()).collect();
            let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let scale: f64 = a.iter().zip(&b).map(|(x, y)| (x * y).abs()).sum();
            assert!((dot(&a, &b) - naive).abs() <= 1e-14 * scale, "n = {n}");
        }
    }

    /// [`dot`] compiled for AVX2 and for the baseline gives the same bits at every
    /// length around the lane count, where the processor has AVX2 to compare.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn vector_and_baseline_dot_agree_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        for n in 0..600 {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() * 1e3).collect();
            let b: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 1.3).cos() / 7.0).collect();
            // SAFETY: AVX2 detected above.
            let v = unsafe { dot_avx2(&a, &b) };
            assert_eq!(v.to_bits(), dot_lanes(&a, &b).to_bits(), "n = {n}");
        }
    }

    /// [`gram`]'s 2 × 2 blocks give every entry [`dot`]'s bits, at lengths around
    /// the lane count, even and odd column counts; its AVX2 and baseline builds
    /// agree bit for bit.
    #[test]
    fn gram_is_dot_bit_for_bit() {
        for m in (0..20).chain(198..203) {
            for k in 0..6 {
                let a = DMatrix::from_fn(m, k, |i, j| ((i * 7 + j * 3) as f64 * 0.37).sin());
                let g = gram(&a);
                for i in 0..k {
                    for j in 0..k {
                        let want = dot(a.column(i).as_slice(), a.column(j).as_slice());
                        assert_eq!(g[(i, j)].to_bits(), want.to_bits(), "m {m} k {k} ({i},{j})");
                    }
                }
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: AVX2 detected above.
                    let v = unsafe { gram_avx2(&a) };
                    assert_eq!(v, gram_lanes(&a), "m {m} k {k}");
                }
            }
        }
    }

    #[test]
    fn refuses_what_is_not_finite() {
        let a = DMatrix::from_element(3, 2, f64::NAN);
        assert!(nnls(&a, &DVector::zeros(3), None).is_err());
        // One infinite or NaN entry anywhere, in A or in b.
        let (a, b) = prony(20, 5);
        for (i, j, v) in [
            (3, 2, f64::INFINITY),
            (0, 0, f64::NEG_INFINITY),
            (7, 4, f64::NAN),
        ] {
            let mut bad = a.clone();
            bad[(i, j)] = v;
            assert!(nnls(&bad, &b, None).is_err(), "A[{i},{j}] = {v}");
            let mut bad = b.clone();
            bad[i] = v;
            assert!(nnls(&a, &bad, None).is_err(), "b[{i}] = {v}");
        }
    }

    /// A random problem of n rows and k columns, scaled normal equations.
    fn random_normal(
        rng: &mut rand_chacha::ChaCha8Rng,
        n: usize,
        k: usize,
    ) -> (DMatrix<f64>, DVector<f64>, DMatrix<f64>, DVector<f64>) {
        use rand::Rng;
        let a = DMatrix::from_fn(n, k, |_, _| rng.gen_range(-1.0..1.0));
        let b = DVector::from_fn(n, |_, _| rng.gen_range(-1.0..1.0));
        let (g, h) = (a.tr_mul(&a), a.tr_mul(&b));
        (a, b, g, h)
    }

    /// The kept factor after appends and removals (one or several at a time, at
    /// any position) is the fresh one: nalgebra's Cholesky factor of G_PP with P in
    /// entry order to 10⁻¹² of G_PP's largest entry, and its solution of
    /// G_PP·z = h_P to 10⁻¹⁰ (random G of 30 rows and at most 12 columns, condition
    /// numbers ≲ 10²: the rounding of a 12 × 12 factorisation and of up to 12 × 4
    /// deletions' rotations is ≲ 10⁻¹⁴).
    #[test]
    fn kept_factor_is_the_fresh_factor() {
        use rand::seq::SliceRandom;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for case in 0..100 {
            let k = rng.gen_range(1..13);
            let (_, _, g, h) = random_normal(&mut rng, 30, k);
            let (gs, hs) = (g.as_slice(), h.as_slice());
            let mut kept = PassiveFactor::new(k);
            let mut leaving = vec![false; k];
            let mut entry: Vec<usize> = (0..k).collect();
            for _ in 0..4 {
                entry.shuffle(&mut rng);
                for &j in &entry {
                    if !kept.passive[j] && rng.gen_bool(0.7) {
                        assert!(kept.push(gs, hs, j), "case {case}");
                    }
                }
                for &j in &kept.order {
                    leaving[j] = rng.gen_bool(0.3);
                }
                kept.remove(&mut leaving);
                assert!(leaving.iter().all(|&l| !l));
                let m = kept.order.len();
                assert_eq!((kept.l.len(), kept.y.len()), (row_start(m), m));
                assert_eq!(kept.passive.iter().filter(|&&p| p).count(), m);
                let p = kept.order.clone();
                let gp = DMatrix::from_fn(m, m, |r, c| g[(p[r], p[c])]);
                let Some(ch) = gp.clone().cholesky() else {
                    panic!("case {case}: random G_PP not positive definite");
                };
                for r in 0..m {
                    for c in 0..=r {
                        let e = (kept.l[row_start(r) + c] - ch.l()[(r, c)]).abs();
                        assert!(e <= 1e-12 * gp.amax(), "case {case}: L[{r},{c}] off by {e}");
                    }
                }
                let mut z = vec![0.0; k];
                assert!(kept.solve(&mut z));
                let want = ch.solve(&DVector::from_fn(m, |r, _| h[p[r]]));
                for (r, &j) in p.iter().enumerate() {
                    assert!((z[j] - want[r]).abs() <= 1e-10 * want.amax().max(1.0));
                }
            }
        }
    }

    /// Degenerate columns: a repeated column, a zero column and a column that is the
    /// sum of two others. The factor refuses a column that depends on P's (pivot not
    /// positive) and leaves P as it was; the solve ends at a point that meets KKT to
    /// 10⁻⁸, the zero column's coefficient at 0, and as low as Clarabel's cost.
    #[test]
    fn degenerate_columns() {
        let (a0, b) = prony(60, 5);
        let mut a = DMatrix::zeros(60, 8);
        for j in 0..5 {
            a.set_column(j, &a0.column(j));
        }
        a.set_column(5, &a0.column(2)); // a repeat of column 2
        a.set_column(7, &(a0.column(1) + a0.column(3))); // column 6 stays zero
        let x = nnls(&a, &b, None).unwrap().x;
        assert!(kkt(&a, &b, &x) < 1e-8, "KKT {}", kkt(&a, &b, &x));
        assert_eq!(x[6], 0.0);
        let qp = constrained_least_squares(&a, &b, &DMatrix::identity(8, 8)).unwrap();
        let cost = |x: &DVector<f64>| (&a * x - &b).norm_squared();
        assert!(cost(&x) <= cost(&qp.x.map(|v| v.max(0.0))) * (1.0 + 1e-9));
        // The factor: 2 then its repeat 5, and 1, 3 then their sum 7.
        let g = a.tr_mul(&a);
        let h = a.tr_mul(&b);
        let mut f = PassiveFactor::new(8);
        assert!(f.push(g.as_slice(), h.as_slice(), 2));
        assert!(!f.push(g.as_slice(), h.as_slice(), 5));
        assert_eq!((f.order.clone(), f.passive[5]), (vec![2], false));
        // An exact dependence up to rounding: the pivot is 0 or a rounding residue
        // of the column's squared norm, never a number the solve can use.
        let mut f = PassiveFactor::new(8);
        for j in [1, 3] {
            assert!(f.push(g.as_slice(), h.as_slice(), j));
        }
        if f.push(g.as_slice(), h.as_slice(), 7) {
            let pivot = f.l[row_start(2) + 2].powi(2);
            assert!(pivot <= 1e-12 * g[(7, 7)], "pivot {pivot}");
        }
    }

    /// One [`NnlsWork`] kept across 300 problems of one size (cold and warm
    /// starts, the last solution's positive set among them, and refused problems
    /// between them: a value not finite, a repeated column) gives each the
    /// solution and iterations of a fresh work space, bit for bit: nothing of one
    /// solve leaks into the next.
    #[test]
    fn kept_work_space_is_a_fresh_one() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let k = 9;
        let mut work = NnlsWork::new(k);
        let mut last = vec![false; k];
        for case in 0..300 {
            let n = rng.gen_range(12..30);
            let (_, _, mut g, h) = random_normal(&mut rng, n, k);
            if case % 37 == 5 {
                g[(2, 3)] = f64::NAN;
            }
            if case % 41 == 7 {
                // Column 4 a copy of column 1: G_PP singular with both in P.
                for i in 0..k {
                    g[(i, 4)] = g[(i, 1)];
                    g[(4, i)] = g[(1, i)];
                }
                g[(4, 4)] = g[(1, 1)];
            }
            let random: Vec<bool> = (0..k).map(|_| rng.gen_bool(0.5)).collect();
            let start = match case % 3 {
                0 => None,
                1 => Some(&random[..]),
                _ => Some(&last[..]),
            };
            let fresh = nnls_normal(&g, &h, start);
            let kept = work.solve(g.as_slice(), h.as_slice(), start);
            match (fresh, kept) {
                (Ok(f), Ok(it)) => {
                    assert_eq!(it, f.iterations, "case {case}");
                    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(work.x()), bits(f.x.as_slice()), "case {case}");
                    last = f.x.iter().map(|&v| v > 0.0).collect();
                }
                (Err(f), Err(w)) => assert_eq!(f, w, "case {case}"),
                (f, w) => panic!("case {case}: fresh {f:?}, kept {w:?}"),
            }
        }
        assert!(
            work.solve(&[1.0], &[1.0], None).is_err(),
            "the wrong size is refused"
        );
    }

    /// A warm start from any subset, right or wrong, ends at the cold start's
    /// solution (the problem is strictly convex: one minimiser) to 10⁻⁹ of its
    /// largest entry, with the same positive set, and a start from the answer takes
    /// no step.
    #[test]
    fn warm_start_is_cold_start() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for case in 0..300 {
            let (n, k) = (rng.gen_range(15..40), rng.gen_range(1..14));
            let (a, b, _, _) = random_normal(&mut rng, n, k);
            let cold = nnls(&a, &b, None).unwrap();
            let start: Vec<bool> = (0..k).map(|_| rng.gen_bool(0.5)).collect();
            let warm = nnls(&a, &b, Some(&start)).unwrap();
            let scale = cold.x.amax().max(f64::MIN_POSITIVE);
            assert!(
                (&warm.x - &cold.x).amax() <= 1e-9 * scale,
                "case {case}: {} vs {}",
                warm.x,
                cold.x
            );
            let positive = |x: &DVector<f64>| x.iter().map(|&v| v > 0.0).collect::<Vec<_>>();
            assert_eq!(positive(&warm.x), positive(&cold.x), "case {case}");
            let exact = nnls(&a, &b, Some(&positive(&cold.x))).unwrap();
            assert_eq!(exact.iterations, 0, "case {case}");
        }
    }
}
