//! The joint Prony problem: p = [e∞, e₁…e_N, ln τ₁…ln τ_N] in scaled units
//! (observation = S·(e∞·x + Σ eᵢ·hᵢ)), residuals rₖ = wₖ·(model − yₖ), on any
//! domain's rows ([`Kernels`]).

use super::Kernels;
use crate::fit::lm::LeastSquares;
use crate::fit::nnls::dot;
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

/// The fitting problem: p = [e∞, e₁…e_N, ln τ₁…ln τ_N] in scaled units (observation =
/// S·(e∞·x + Σ eᵢ·hᵢ)), residuals rₖ = wₖ·(model − yₖ).
#[derive(Debug, Clone)]
pub struct Problem<K: Kernels> {
    /// The domain's rows: inputs and kernels. The rows, data and weights are
    /// shared (not copied) by the clones that fit each term count: at 10⁶ points
    /// they are tens of MB a copy.
    pub kern: Arc<K>,
    /// The data yₖ.
    pub y: Arc<[f64]>,
    /// The residual weights wₖ.
    pub w: Arc<[f64]>,
    /// The scale S of the moduli.
    pub scale: f64,
    /// wₖ·S: the factor of every column of the design (and of the Jacobian).
    ws: Arc<[f64]>,
    /// Number of Prony terms N.
    pub n_terms: usize,
    /// The terms' kernels and their τ-derivatives of the last evaluation, one block
    /// of [`Problem::len`] values a term ([`Kernels::kernels`]), and their τᵢ.
    h: Vec<f64>,
    dh: Vec<f64>,
    taus: Vec<f64>,
    /// The τᵢ whose kernels `h` holds, and whether `dh` holds their derivatives: an
    /// evaluation at the same τ (the polish's start at the projection's optimum,
    /// the assessment at the polish's) takes them instead of a pass over the data.
    pub(crate) kernel_taus: Vec<f64>,
    kernel_derivatives: bool,
    /// p, JᵀJ and Jᵀr of the last evaluation asked for its normal equations
    /// ([`LeastSquares::forms_normal_equations`]).
    normal: super::NormalCache,
    /// A block of [`BLOCK_ROWS`] rows of columns ([`Problem::jacobian_block`]).
    block: Vec<f64>,
    /// Evaluations so far (counted for the solver report).
    pub evaluations: usize,
}

/// Rows of a block of the products over the data ([`Problem`]'s normal equations,
/// [`super::projection::Projected`]'s Gram products): the columns of a block (at
/// most 2·40 + 2 of 4 kB) stay in the level-2 cache while all their products are
/// taken, and no column of the data's length is formed; a curve of at most this
/// many points (every shipped one, and the starts' subsample) takes each product
/// in one piece.
pub(crate) const BLOCK_ROWS: usize = 512;

impl<K: Kernels> Problem<K> {
    /// The problem of the rows `kern` with data `y`, weights `w` and scale S, no
    /// terms yet.
    pub fn new(kern: K, y: Vec<f64>, w: Vec<f64>, scale: f64) -> Problem<K> {
        let ws = w.iter().map(|w| w * scale).collect();
        Problem {
            kern: Arc::new(kern),
            y: y.into(),
            w: w.into(),
            scale,
            ws,
            n_terms: 0,
            h: Vec::new(),
            dh: Vec::new(),
            taus: Vec::new(),
            kernel_taus: Vec::new(),
            kernel_derivatives: false,
            normal: super::NormalCache::default(),
            block: Vec::new(),
            evaluations: 0,
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.y.len()
    }

    /// True if there are no rows.
    pub fn is_empty(&self) -> bool {
        self.y.is_empty()
    }

    /// The same objective on `count` of the points, spread evenly over their order
    /// (both ends kept; a log-spaced curve stays log-spaced), with their weights and
    /// the same scale; `None` when there are no more points than that.
    pub fn subsample(&self, count: usize) -> Option<Problem<K>> {
        let (m, count) = (self.len(), count.max(2));
        if m <= count {
            return None;
        }
        let idx: Vec<usize> = (0..count)
            .map(|q| (q * (m - 1) + (count - 1) / 2) / (count - 1))
            .collect();
        let mut sub = Problem::new(
            self.kern.subsample(&idx)?,
            idx.iter().map(|&i| self.y[i]).collect(),
            idx.iter().map(|&i| self.w[i]).collect(),
            self.scale,
        );
        sub.n_terms = self.n_terms;
        Some(sub)
    }

    /// Model observation (stress, modulus) at every point into `m`, from the kernels of the last evaluation
    /// (which must have been at `p`).
    pub fn model(&self, p: &[f64], m: &mut [f64]) {
        self.combine(p, m);
        for mk in m.iter_mut() {
            *mk *= self.scale;
        }
    }

    /// Each term's reach: the largest weighted change it makes to any row,
    /// maxₖ wₖ·|Eᵢ·hₖ(τᵢ)| (a relative change where the weights are relative), from
    /// the kernels of the last evaluation (which must have been at `p`).
    pub fn reach(&self, p: &[f64]) -> Vec<f64> {
        let m = self.len();
        p[1..=self.n_terms]
            .iter()
            .zip(self.h.chunks_exact(m))
            .map(|(e, h)| {
                h.iter()
                    .zip(self.ws.iter())
                    .map(|(h, ws)| (ws * e * h).abs())
                    .fold(0.0, f64::max)
            })
            .collect()
    }

    /// e∞·x + Σ eᵢ·hᵢ at every point into `out` (the model over S), from the
    /// kernels of the last evaluation.
    fn combine(&self, p: &[f64], out: &mut [f64]) {
        let m = self.len();
        for (o, x) in out.iter_mut().zip(self.kern.input()) {
            *o = p[0] * x;
        }
        for (e, h) in p[1..=self.n_terms].iter().zip(self.h.chunks_exact(m)) {
            for (o, h) in out.iter_mut().zip(h) {
                *o += e * h;
            }
        }
    }

    /// Every term's kernel at the τᵢ = e^(ln τᵢ) of `p` into `h` (and their
    /// τ-derivatives into `dh` when `derivatives`), in one pass over the data.
    fn kernels_at(&mut self, p: &[f64], derivatives: bool) {
        let n = self.n_terms;
        self.kernels_at_log_taus(&p[1 + n..1 + 2 * n], derivatives);
    }

    /// [`Problem::kernels_at`] of the terms' ln τᵢ alone; nothing to compute when
    /// `h` (and `dh` if asked for) hold the kernels of these τ already, bit for bit
    /// the values a pass would give (each τ's kernel depends on that τ alone).
    pub(crate) fn kernels_at_log_taus(&mut self, ln_taus: &[f64], derivatives: bool) {
        let m = self.len();
        let n = ln_taus.len();
        self.taus.clear();
        self.taus.extend(ln_taus.iter().map(|lt| lt.exp()));
        if self.kernel_taus == self.taus && (self.kernel_derivatives || !derivatives) {
            return;
        }
        self.h.resize(n * m, 0.0);
        if derivatives {
            self.dh.resize(n * m, 0.0);
        }
        self.kern.kernels(
            &self.taus,
            &mut self.h,
            derivatives.then_some(&mut self.dh[..]),
        );
        self.kernel_taus.clone_from(&self.taus);
        self.kernel_derivatives = derivatives;
    }

    /// Free the kept kernels (n·m values, and as many derivatives): a term fit
    /// waiting for its assessment keeps nothing of the data's size; the
    /// assessment computes them again, the same bits ([`Problem::kernels_at_log_taus`]).
    pub(crate) fn release_kernels(&mut self) {
        self.h = Vec::new();
        self.dh = Vec::new();
        self.block = Vec::new();
        self.normal.clear();
        self.kernel_taus.clear();
        self.kernel_derivatives = false;
    }

    /// The weighted data w·y: the right-hand side of the moduli's least squares.
    pub(crate) fn targets(&self) -> DVector<f64> {
        let mut b = DVector::zeros(self.len());
        self.targets_block(0, self.len(), b.as_mut_slice());
        b
    }

    /// The rows `lo..hi` of [`Problem::targets`] into `out`.
    pub(crate) fn targets_block(&self, lo: usize, hi: usize, out: &mut [f64]) {
        for ((b, y), w) in out.iter_mut().zip(&self.y[lo..hi]).zip(&self.w[lo..hi]) {
            *b = y * w;
        }
    }

    /// The design's first column, w·S·x (the E∞ term), into `out`.
    pub(crate) fn input_column(&self, out: &mut [f64]) {
        self.input_column_block(0, self.len(), out);
    }

    /// The rows `lo..hi` of [`Problem::input_column`] into `out`.
    pub(crate) fn input_column_block(&self, lo: usize, hi: usize, out: &mut [f64]) {
        let x = &self.kern.input()[lo..hi];
        for ((o, x), ws) in out.iter_mut().zip(x).zip(&self.ws[lo..hi]) {
            *o = x * ws;
        }
    }

    /// The rows `lo..hi` of the columns [w·S·x | w·S·h(τᵢ)… | w·y | w·S·τᵢ·∂h/∂τ(τᵢ)…]
    /// (the last N only when `derivatives`; the kernels of the last evaluation,
    /// which must hold their derivatives then) end to end into `out`: the columns of
    /// [`super::projection::Projected`]'s Gram products a block at a time, each
    /// value the product [`Problem::kernel_columns`] forms (h·wS, ∂h/∂τ·(wS·τ)), so
    /// the same bits.
    pub(crate) fn design_block(&self, lo: usize, hi: usize, derivatives: bool, out: &mut Vec<f64>) {
        let (m, n, len) = (self.len(), self.n_terms, hi - lo);
        let cols = 2 + n + if derivatives { n } else { 0 };
        out.resize(cols * len, 0.0);
        let ws = &self.ws[lo..hi];
        let (x, rest) = out.split_at_mut(len);
        self.input_column_block(lo, hi, x);
        let (a, rest) = rest.split_at_mut(n * len);
        for (i, a) in a.chunks_exact_mut(len).enumerate() {
            for ((a, ws), h) in a.iter_mut().zip(ws).zip(&self.h[i * m + lo..]) {
                *a = h * ws;
            }
        }
        let (b, d) = rest.split_at_mut(len);
        self.targets_block(lo, hi, b);
        if derivatives {
            for ((i, a), tau) in d.chunks_exact_mut(len).enumerate().zip(&self.taus) {
                for ((a, ws), dh) in a.iter_mut().zip(ws).zip(&self.dh[i * m + lo..]) {
                    *a = dh * (ws * tau);
                }
            }
        }
    }

    /// The rows `lo..hi` of the Jacobian at `p` (which the kernels of the last
    /// evaluation, with derivatives, must be at) end to end into `out`: the columns
    /// w·S·x, w·S·hᵢ and w·S·eᵢ·τᵢ·∂hᵢ/∂τ of [`LeastSquares::eval`], the same bits.
    pub(crate) fn jacobian_block(&self, p: &[f64], lo: usize, hi: usize, out: &mut [f64]) {
        let (m, n, len) = (self.len(), self.n_terms, hi - lo);
        let ws = &self.ws[lo..hi];
        let (j0, terms) = out.split_at_mut(len);
        self.input_column_block(lo, hi, j0);
        let (je, jt) = terms.split_at_mut(n * len);
        for i in 0..n {
            let (e, tau) = (p[1 + i], self.taus[i]);
            let (h, dh) = (
                &self.h[i * m + lo..i * m + hi],
                &self.dh[i * m + lo..i * m + hi],
            );
            for ((j, ws), h) in je[i * len..(i + 1) * len].iter_mut().zip(ws).zip(h) {
                *j = ws * h;
            }
            for ((j, ws), dh) in jt[i * len..(i + 1) * len].iter_mut().zip(ws).zip(dh) {
                *j = ws * e * tau * dh;
            }
        }
    }

    /// JᵀJ and Jᵀr at `p` from the residuals `r` there, a block of [`BLOCK_ROWS`]
    /// rows of the Jacobian at a time ([`Problem::jacobian_block`]): no m × (2N + 1)
    /// Jacobian is formed (at 10⁶ points 104 MB for six terms, and as many for a
    /// trial's). Kept for [`LeastSquares::normal_equations`]; false where not finite.
    fn form_normal_equations(&mut self, p: &[f64], r: &[f64]) -> bool {
        let (m, k) = (self.len(), 1 + 2 * self.n_terms);
        let mut jtj = DMatrix::<f64>::zeros(k, k);
        let mut jtr = DVector::<f64>::zeros(k);
        let mut block = std::mem::take(&mut self.block);
        for lo in (0..m).step_by(BLOCK_ROWS) {
            let hi = (lo + BLOCK_ROWS).min(m);
            let len = hi - lo;
            block.resize(k * len, 0.0);
            self.jacobian_block(p, lo, hi, &mut block);
            let col = |i: usize| &block[i * len..(i + 1) * len];
            for j in 0..k {
                for i in 0..=j {
                    jtj[(i, j)] += dot(col(i), col(j));
                }
                jtr[j] += dot(col(j), &r[lo..hi]);
            }
        }
        self.block = block;
        for j in 0..k {
            for i in 0..j {
                jtj[(j, i)] = jtj[(i, j)];
            }
        }
        let finite = jtj.iter().chain(jtr.iter()).all(|v| v.is_finite());
        match finite {
            true => self.normal.keep(p, jtj, jtr),
            false => self.normal.clear(),
        }
        finite
    }

    /// The design's columns of the terms at `taus`, w·S·h(τᵢ), end to end into `out`
    /// (one pass over the data, [`Kernels::kernels`]), and their derivatives
    /// w·S·τᵢ·∂h/∂τ(τᵢ) = ∂aᵢ/∂ln τᵢ into `dout` if given.
    pub(crate) fn kernel_columns(
        &self,
        taus: &[f64],
        out: &mut [f64],
        mut dout: Option<&mut [f64]>,
    ) {
        let m = self.len();
        self.kern.kernels(taus, out, dout.as_deref_mut());
        for (i, &tau) in taus.iter().enumerate() {
            for (a, ws) in out[i * m..(i + 1) * m].iter_mut().zip(self.ws.iter()) {
                *a *= ws;
            }
            if let Some(d) = dout.as_deref_mut() {
                for (a, ws) in d[i * m..(i + 1) * m].iter_mut().zip(self.ws.iter()) {
                    *a *= ws * tau;
                }
            }
        }
    }
}

impl<K: Kernels> LeastSquares for Problem<K> {
    fn dims(&self) -> (usize, usize) {
        (self.len(), 1 + 2 * self.n_terms)
    }
    /// Residuals wₖ·(S·(e∞·xₖ + Σ eᵢ·hᵢₖ) − yₖ); the Jacobian's columns w·S·x,
    /// w·S·hᵢ and w·S·eᵢ·τᵢ·∂hᵢ/∂τ (∂/∂ln τᵢ), or, asked with an empty (0-row)
    /// Jacobian, its normal equations ([`Problem::form_normal_equations`]).
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        self.evaluations += 1;
        let (n, m, s) = (self.n_terms, self.len(), self.scale);
        self.kernels_at(p, jac.is_some());
        let r = r.as_mut_slice();
        self.combine(p, r);
        for ((rk, w), y) in r.iter_mut().zip(self.w.iter()).zip(self.y.iter()) {
            *rk = w * (s * *rk - y);
        }
        let finite = |v: &[f64]| v.iter().all(|v| v.is_finite());
        let Some(jac) = jac else {
            return finite(r);
        };
        if jac.nrows() == 0 {
            return finite(r) && self.form_normal_equations(p, r);
        }
        debug_assert_eq!(jac.shape(), (m, 1 + 2 * n));
        self.jacobian_block(p, 0, m, jac.as_mut_slice());
        finite(r) && finite(jac.as_slice())
    }
    /// A trial's Jacobian costs the kernels' derivatives and the columns over the
    /// residuals alone, where evaluating again after an accepted trial costs the
    /// kernels twice.
    fn jacobian_with_trial(&self) -> bool {
        true
    }
    /// The search takes the normal equations a block of rows at a time
    /// ([`Problem::form_normal_equations`]).
    fn forms_normal_equations(&self) -> bool {
        true
    }
    fn normal_equations(&self, p: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
        self.normal.at(p)
    }
}
