//! Variable projection of the Prony problem: the search over ln τ alone, the
//! moduli by non-negative least squares at each τ.

use super::problem::{Need, Problem, BLOCK_ROWS};
use super::Kernels;
use crate::fit::lm::LeastSquares;
use crate::fit::nnls::{dot, NnlsWork};
use nalgebra::{DMatrix, DVector};

/// Variable projection of a [`Problem`] (Golub & Pereyra 1973, with Kaufman's 1975
/// Jacobian): the search runs over θ = ln τ only. At each θ the moduli c = (e∞, eᵢ)
/// are the non-negative least-squares solution of A(θ)·c ≈ b ([`NnlsWork`], started
/// from the last solution's positive set), with A = [w·S·x, w·S·h(τ₁), …] and b = w·y,
/// so r(θ) = A·c − b are the residuals of [`Problem`] at the best moduli for these τ.
/// Kaufman's Jacobian is ∂r/∂θᵢ ≈ Jᵢ = cᵢ·P⊥·∂aᵢ/∂θᵢ, with P⊥ the projector off the
/// columns whose modulus is positive (a term at zero modulus moves nothing); its
/// gradient Jᵀr is the exact gradient of ½‖r(θ)‖², since r ⟂ those columns.
/// The amplitudes no longer lie in the search, so neither does the long valley
/// between a modulus and its τ that a joint search walks along.
///
/// The search only uses the Jacobian's normal equations, and those follow from the
/// Gram products of the columns ([`Projected::gram`], [`Projected::residuals`]):
/// (JᵀJ)ᵢⱼ = cᵢ·cⱼ·(dᵢ·dⱼ − (A_Pᵀdᵢ)ᵀ(A_PᵀA_P)⁻¹(A_Pᵀdⱼ)) with dᵢ = ∂aᵢ/∂θᵢ and A_P
/// the positive columns, and (Jᵀr)ᵢ = cᵢ·dᵢ·r ([`LeastSquares::forms_normal_equations`]),
/// so no m × N Jacobian is formed or projected.
pub struct Projected<'p, K: Kernels> {
    prob: &'p mut Problem<K>,
    /// Number of terms N.
    n: usize,
    /// The Gram products of the columns [A | b | ∂A] of the last evaluation (the ∂A
    /// rows and columns only when it was asked for a Jacobian).
    gram: DMatrix<f64>,
    /// The moduli's normal equations AᵀA and Aᵀb of the last evaluation (copied from
    /// `gram` for [`NnlsWork::solve`]).
    ata: DMatrix<f64>,
    atb: DVector<f64>,
    /// The moduli of the last evaluation.
    pub(crate) c: DVector<f64>,
    /// Which of them are positive: the next solve's start.
    pub(crate) positive: Vec<bool>,
    /// The moduli's NNLS work space (no allocation a solve).
    work: NnlsWork,
    /// x·x and b·x of the fixed first column x = w·S·x and b = w·y, summed over
    /// the blocks of [`Projected::gram`] as it sums them: the same at every θ.
    fixed: [f64; 2],
    /// θ of the last evaluation, whose Gram products of [A | b] `gram` holds.
    theta: Vec<f64>,
    /// A block of [`BLOCK_ROWS`] rows of the columns ([`Problem::design_block`]):
    /// no column of the data's length is formed.
    block: Vec<f64>,
    /// θ, JᵀJ and Jᵀr of the last evaluation asked for a Jacobian.
    normal: super::NormalCache,
}

/// The row blocks `lo..hi` of [`BLOCK_ROWS`] rows of a curve of `m` points.
fn blocks(m: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..m)
        .step_by(BLOCK_ROWS)
        .map(move |lo| (lo, (lo + BLOCK_ROWS).min(m)))
}

impl<'p, K: Kernels> Projected<'p, K> {
    /// The projection of `prob` (its term count set).
    pub fn new(prob: &'p mut Problem<K>) -> Projected<'p, K> {
        let (m, n) = (prob.len(), prob.n_terms);
        // x·x and b·x block by block, as [`Projected::gram`] adds its products
        let mut block = Vec::new();
        let mut fixed = [0.0; 2];
        for (lo, hi) in blocks(m) {
            let len = hi - lo;
            // the kernels' columns are not read: only x (column 0) and b (n + 1)
            block.resize((2 + n) * len, 0.0);
            prob.input_column_block(lo, hi, &mut block[..len]);
            prob.targets_block(lo, hi, &mut block[(n + 1) * len..(n + 2) * len]);
            let (x, b) = (&block[..len], &block[(n + 1) * len..(n + 2) * len]);
            fixed[0] += dot(x, x);
            fixed[1] += dot(b, x);
        }
        Projected {
            prob,
            n,
            gram: DMatrix::zeros(2 + 2 * n, 2 + 2 * n),
            ata: DMatrix::zeros(1 + n, 1 + n),
            atb: DVector::zeros(1 + n),
            c: DVector::zeros(1 + n),
            positive: vec![false; 1 + n],
            work: NnlsWork::new(1 + n),
            fixed,
            theta: Vec::with_capacity(n),
            block,
            normal: super::NormalCache::default(),
        }
    }

    /// The moduli at θ into `c` (a failed solve leaves them as they were), as
    /// [`LeastSquares::eval`] without a Jacobian would set them, counted as an
    /// evaluation: from the Gram products of the last evaluation when it was at θ
    /// (the same products, so the same bits), else from a pass at θ, which a problem
    /// that keeps its kernels makes with their derivatives for the joint problem's
    /// first evaluation at the same τ ([`Need::ValuesThenDerivatives`]).
    pub fn moduli_at(&mut self, theta: &[f64]) {
        self.prob.evaluations += 1;
        if self.theta != theta {
            let taus: Vec<f64> = theta.iter().map(|t| t.exp()).collect();
            self.gram(&taus, Need::ValuesThenDerivatives);
            self.theta.clear();
            self.theta.extend_from_slice(theta);
        }
        self.solve_moduli();
    }

    /// The moduli's NNLS on the Gram products of the last evaluation, started from
    /// the positive set of the one before, into `c` and `positive`; false (both
    /// unchanged) when it fails.
    fn solve_moduli(&mut self) -> bool {
        let n = self.n;
        for j in 0..=n {
            for i in 0..=n {
                self.ata[(i, j)] = self.gram[(i, j)];
            }
            self.atb[j] = self.gram[(j, 1 + n)];
        }
        let solved = self.work.solve(
            self.ata.as_slice(),
            self.atb.as_slice(),
            Some(&self.positive),
        );
        if solved.is_err() {
            return false;
        }
        self.c.copy_from_slice(self.work.x());
        for (f, &v) in self.positive.iter_mut().zip(self.c.iter()) {
            *f = v > 0.0;
        }
        true
    }

    /// The parameters of [`Problem`] at θ: [e∞, eᵢ…, ln τᵢ…], the moduli those of the
    /// last evaluation (which must have been at θ).
    pub fn joint(&self, theta: &[f64]) -> Vec<f64> {
        self.c.iter().chain(theta).copied().collect()
    }

    /// The Gram products kᵢ·kⱼ of the columns [A | b] (b·b, which nothing uses,
    /// left at 0) into the leading block of `gram`, in one pass over the rows at
    /// `taus` ([`Problem::pass`]): blocks of [`BLOCK_ROWS`] rows formed from the
    /// kernels ([`Problem::design_block`]), every product of a block while its
    /// columns are in the cache (column by column, each product of a 10⁵-point
    /// curve would read two 0.8 MB columns from memory). The two products of the
    /// fixed columns alone are `fixed`'s. The rows and columns of ∂A are
    /// [`Projected::residuals`]'s.
    fn gram(&mut self, taus: &[f64], need: Need) {
        let n = self.n;
        let size = 2 + 2 * n;
        let g = self.gram.as_mut_slice();
        g.fill(0.0);
        let block = &mut self.block;
        self.prob.pass(taus, need, |prob, b| {
            prob.design_block(b, false, block);
            products(block, b.rows.len(), n, 0..n + 2, g);
        });
        g[0] = self.fixed[0];
        g[(n + 1) * size] = self.fixed[1];
        symmetric(g, size, 0..n + 2);
    }

    /// The residuals r = A·c − b at the moduli `c` into `r` (as nalgebra's gemv
    /// forms them: a₀c₀ − b, then + aⱼcⱼ column by column, so the same bits) in a
    /// second pass over the row blocks at `taus` (the kernels of [`Projected::gram`]'s,
    /// where the problem keeps them: [`Problem::pass`]), and, when `derivatives`, dᵢ·r for
    /// each term (blocked as [`Projected::gram`] sums) into `dr` and the Gram
    /// products of the columns ∂A with [A | ∂A] into `gram`; then `gram` made
    /// symmetric.
    fn residuals(&mut self, taus: &[f64], r: &mut [f64], derivatives: bool, dr: &mut [f64]) {
        let n = self.n;
        let size = 2 + 2 * n;
        dr.fill(0.0);
        let (block, c, g) = (&mut self.block, &self.c, self.gram.as_mut_slice());
        let need = match derivatives {
            true => Need::Derivatives,
            false => Need::Values,
        };
        self.prob.pass(taus, need, |prob, b| {
            let (rows, len) = (b.rows.clone(), b.rows.len());
            prob.design_block(b, derivatives, block);
            let col = |i: usize| &block[i * len..(i + 1) * len];
            let rb = &mut r[rows];
            let c0 = c[0];
            for ((r, a), b) in rb.iter_mut().zip(col(0)).zip(col(n + 1)) {
                *r = a * c0 + -b;
            }
            for j in 1..=n {
                let cj = c[j];
                // a·c + r as gemv adds it (addition commutes bit for bit)
                for (r, a) in rb.iter_mut().zip(col(j)) {
                    *r += a * cj;
                }
            }
            if derivatives {
                for (i, d) in dr.iter_mut().enumerate() {
                    *d += dot(col(n + 2 + i), rb);
                }
                products(block, len, n, n + 2..2 * n + 2, g);
            }
        });
        if derivatives {
            symmetric(g, size, n + 2..size);
        }
    }

    /// Kaufman's JᵀJ and Jᵀr (type notes) from the Gram products, moduli and
    /// residuals of the last evaluation; None where the positive columns' Gram
    /// matrix is singular.
    fn normal_from_gram(&self, dr: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
        let n = self.n;
        let gram = &self.gram;
        let pos: Vec<usize> = (0..=n).filter(|&j| self.c[j] > 0.0).collect();
        // (A_PᵀA_P)⁻¹ through the Cholesky factor of the unit-diagonal scaling
        // (as the NNLS solve factors it), u = L⁻¹·A_Pᵀ∂A scaled alike.
        let s: Vec<f64> = pos.iter().map(|&j| 1.0 / gram[(j, j)].sqrt()).collect();
        let gp = DMatrix::from_fn(pos.len(), pos.len(), |p, q| {
            gram[(pos[p], pos[q])] * s[p] * s[q]
        });
        let mut u = DMatrix::from_fn(pos.len(), n, |p, i| gram[(pos[p], n + 2 + i)] * s[p]);
        if !pos.is_empty() && !gp.cholesky()?.l_dirty().solve_lower_triangular_mut(&mut u) {
            return None;
        }
        let jtj = DMatrix::from_fn(n, n, |i, j| {
            let dd = gram[(n + 2 + i, n + 2 + j)];
            self.c[1 + i] * self.c[1 + j] * (dd - u.column(i).dot(&u.column(j)))
        });
        let jtr = DVector::from_fn(n, |i, _| self.c[1 + i] * dr[i]);
        Some((jtj, jtr))
    }
}

/// The Gram products of a block of `len` rows of the columns [x | A | b | ∂A]
/// ([`Problem::design_block`], N = `n` terms) of the columns `cols` with those
/// before them, each added to its entry of the column-major `g` (of side 2N + 2,
/// the upper triangle: row ≤ column): b·b and b·∂A, which nothing uses, are not
/// formed (Jᵀr is taken from the residuals), nor x·x and b·x (`fixed`).
fn products(block: &[f64], len: usize, n: usize, cols: std::ops::Range<usize>, g: &mut [f64]) {
    let size = 2 + 2 * n;
    let col = |i: usize| &block[i * len..(i + 1) * len];
    for j in cols {
        let cj = col(j);
        let fixed = |i: usize| i == 0 && (j == 0 || j == n + 1);
        for i in (0..=j).filter(|&i| i != n + 1 && !fixed(i)) {
            g[j * size + i] += dot(col(i), cj);
        }
    }
}

/// The columns `cols` of the column-major `g` (of side `size`) above the diagonal
/// copied to their rows below it.
fn symmetric(g: &mut [f64], size: usize, cols: std::ops::Range<usize>) {
    for j in cols {
        for i in 0..j {
            g[i * size + j] = g[j * size + i];
        }
    }
}

impl<K: Kernels> LeastSquares for Projected<'_, K> {
    fn dims(&self) -> (usize, usize) {
        (self.prob.len(), self.prob.n_terms)
    }
    /// Asked for a Jacobian (any matrix: see [`LeastSquares::forms_normal_equations`]),
    /// it forms the normal equations instead.
    fn eval(
        &mut self,
        theta: &[f64],
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> bool {
        self.prob.evaluations += 1;
        let derivatives = jac.is_some();
        let taus: Vec<f64> = theta.iter().map(|t| t.exp()).collect();
        let need = match derivatives {
            true => Need::ValuesThenDerivatives,
            false => Need::Values,
        };
        self.gram(&taus, need);
        self.theta.clear();
        self.theta.extend_from_slice(theta);
        if !self.solve_moduli() {
            return false;
        }
        let mut dr = vec![0.0; self.n];
        self.residuals(&taus, r.as_mut_slice(), derivatives, &mut dr);
        if !r.as_slice().iter().all(|v| v.is_finite()) {
            return false;
        }
        if !derivatives {
            return true;
        }
        match self.normal_from_gram(&dr) {
            Some((jtj, jtr)) if jtj.iter().chain(jtr.iter()).all(|v| v.is_finite()) => {
                self.normal.keep(theta, jtj, jtr);
                true
            }
            _ => false,
        }
    }
    fn jacobian_with_trial(&self) -> bool {
        true
    }
    fn forms_normal_equations(&self) -> bool {
        true
    }
    fn normal_equations(&self, p: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
        self.normal.at(p)
    }
}
