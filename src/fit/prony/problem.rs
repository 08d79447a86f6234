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
///
/// Every product over the data is taken a block of [`BLOCK_ROWS`] rows at a time
/// ([`Problem::pass`]). A problem whose kernels and derivatives fit
/// [`KEPT_KERNEL_BYTES`] keeps every block's between passes, so a second pass at
/// the same τ computes none; a larger one computes each block's, uses them and
/// overwrites them with the next block's, so an evaluation holds N·[`BLOCK_ROWS`]
/// kernels (and as many derivatives) whatever the number of rows, not N per row (at
/// 10⁶ points and six terms the kernels and their derivatives were 96 MB a term
/// count).
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
    /// The scale S of the moduli: every column of the design (and of the Jacobian)
    /// has the factor wₖ·S, formed where it is used (the same product every time).
    pub scale: f64,
    /// Number of Prony terms N.
    pub n_terms: usize,
    /// The rows of the curve whose subsample the problem is (its own where it is
    /// none): what its kept kernels are reckoned on ([`Problem::keeps_kernels`]).
    curve_rows: usize,
    /// The kernels of the last pass: every block's, in order, where they fit
    /// [`KEPT_KERNEL_BYTES`], else the last block's.
    kernels: Vec<KernelBlock>,
    /// p, JᵀJ and Jᵀr of the last evaluation asked for its normal equations
    /// ([`LeastSquares::forms_normal_equations`]).
    normal: super::NormalCache,
    /// A block of [`BLOCK_ROWS`] rows of the Jacobian ([`Problem::jacobian_block`]).
    block: Vec<f64>,
    /// Evaluations so far (counted for the solver report).
    pub evaluations: usize,
}

/// Rows of a block of the products over the data ([`Problem`]'s kernels, residuals
/// and normal equations, [`super::projection::Projected`]'s Gram products): the
/// kernels and columns of a block (at most 2·40 + 2 of 4 kB) stay in the level-2
/// cache while all their products are taken, and no column of the data's length is
/// formed.
pub(crate) const BLOCK_ROWS: usize = 512;

/// The most a problem spends on keeping its kernels hᵢ and τ-derivatives between
/// passes ([`Problem::pass`]): it keeps every block's when 2·N·m·8 B (N terms, m
/// rows) is at most this ([`Problem::keeps_kernels`]). A pass at the kernels' τ
/// (the projection's residuals after its Gram products, the joint polish's first
/// evaluation after the projection's moduli, the assessment's Jacobian after its
/// residuals) then computes none: at 10⁵ points recomputing them made
/// `relaxation --terms auto` 18 % longer. 12 MiB keeps a curve of 10⁵ points up to
/// 7 terms (N·1.6 MB; the default `--max-terms` is 6) and no curve of 10⁶ points
/// (one term alone is 16 MB), whose kernels would multiply its memory. The term
/// counts are searched in parallel (rayon, each on its own clone of the problem),
/// so the searches hold at most this a thread; a finished search drops them
/// ([`Problem::release_kernels`]), but an assessed count keeps its assessment's
/// until the choice: Σ_N 2·N·m·8 B, 34 MB for the counts 1–6 at 10⁵ points.
pub(crate) const KEPT_KERNEL_BYTES: usize = 12 << 20;

/// The terms' kernels at one block of rows ([`Problem::pass`]): hᵢ(τᵢ) of the rows
/// `rows`, one column of `rows.len()` values a term end to end, and their
/// τ-derivatives in `dh` where they were asked for.
#[derive(Debug, Clone, Default)]
pub(crate) struct KernelBlock {
    /// The τᵢ.
    pub(crate) taus: Vec<f64>,
    /// The rows.
    pub(crate) rows: std::ops::Range<usize>,
    /// Whether `dh` holds the derivatives.
    derivatives: bool,
    pub(crate) h: Vec<f64>,
    pub(crate) dh: Vec<f64>,
}

impl KernelBlock {
    /// The kernels of `kern` at `taus` on `rows` (and their derivatives when
    /// `derivatives`), the pass standing at `carry` before them and left after them
    /// ([`Kernels::kernel_rows`]), in place of this block's (no allocation when it
    /// held as many).
    fn compute<K: Kernels>(
        &mut self,
        kern: &K,
        taus: &[f64],
        rows: std::ops::Range<usize>,
        derivatives: bool,
        carry: &mut K::Carry,
    ) {
        let len = taus.len() * rows.len();
        self.h.resize(len, 0.0);
        self.dh.resize(if derivatives { len } else { 0 }, 0.0);
        let dh = derivatives.then_some(&mut self.dh[..]);
        kern.kernel_rows(taus, rows.clone(), carry, &mut self.h, dh);
        self.taus.clear();
        self.taus.extend_from_slice(taus);
        self.rows = rows;
        self.derivatives = derivatives;
    }
}

/// What a pass over the rows needs of the kernels ([`Problem::pass`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Need {
    /// The kernels.
    Values,
    /// The kernels and their τ-derivatives.
    Derivatives,
    /// The kernels, and the derivatives at the same τ in the pass after: a problem
    /// that keeps its kernels ([`KEPT_KERNEL_BYTES`]) computes both at once.
    ValuesThenDerivatives,
}

impl<K: Kernels> Problem<K> {
    /// The problem of the rows `kern` with data `y`, weights `w` and scale S, no
    /// terms yet.
    pub fn new(kern: K, y: Vec<f64>, w: Vec<f64>, scale: f64) -> Problem<K> {
        let m = y.len();
        Problem {
            kern: Arc::new(kern),
            y: y.into(),
            w: w.into(),
            scale,
            n_terms: 0,
            curve_rows: m,
            kernels: Vec::new(),
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
        sub.curve_rows = self.curve_rows;
        Some(sub)
    }

    /// How many kernels and τ-derivatives the problem holds (those of the last
    /// pass: [`Problem::pass`]).
    #[cfg(test)]
    pub(crate) fn kernel_values(&self) -> (usize, usize) {
        let sum = |f: fn(&KernelBlock) -> usize| self.kernels.iter().map(f).sum();
        (sum(|b| b.h.len()), sum(|b| b.dh.len()))
    }

    /// Drops the kernels the problem keeps ([`Problem::pass`]): a finished fit
    /// waits for the others before its assessment, whose passes are at other τ
    /// (the terms sorted), and the kept kernels of every count at 10⁵ points were
    /// 34 MB.
    pub(crate) fn release_kernels(&mut self) {
        self.kernels = Vec::new();
    }

    /// Whether the problem keeps the kernels and derivatives of `terms` terms at
    /// every row between passes: where they are one block, or where those of the
    /// whole curve (`curve_rows`, m) would fit [`KEPT_KERNEL_BYTES`] (2·N·m·8 B).
    /// A subsample of a longer curve (the searches of [`super::refine::Levels`])
    /// keeps them as that curve would: its searches run before the whole curve's,
    /// where the fit's memory peaks, and kept kernels freed by then stay in the
    /// allocator's pages (10⁶ points on one thread: 133–135 → 138–140 MB).
    fn keeps_kernels(&self, terms: usize) -> bool {
        let bytes = 2 * terms * self.curve_rows * std::mem::size_of::<f64>();
        self.len() <= BLOCK_ROWS || bytes <= KEPT_KERNEL_BYTES
    }

    /// The τᵢ = e^(ln τᵢ) of the terms of `p`.
    pub(crate) fn taus(&self, p: &[f64]) -> Vec<f64> {
        let n = self.n_terms;
        p[1 + n..1 + 2 * n].iter().map(|lt| lt.exp()).collect()
    }

    /// One pass over the rows with the terms' kernels at `taus`: `f(self, block)`
    /// for each block of [`BLOCK_ROWS`] rows in order, with its kernels (and
    /// τ-derivatives, as `need` says). Where the problem holds every block's at
    /// `taus` (with derivatives if needed) from the pass before, the pass takes them
    /// (the same bits: each τ's kernel depends on that τ alone); otherwise each
    /// block's are computed from where the block before left the pass
    /// ([`Kernels::kernel_rows`]), and kept for the next pass, every block's where
    /// they fit [`KEPT_KERNEL_BYTES`], else only the last one's.
    pub(crate) fn pass(
        &mut self,
        taus: &[f64],
        need: Need,
        mut f: impl FnMut(&Self, &KernelBlock),
    ) {
        let m = self.len();
        let keep = self.keeps_kernels(taus.len());
        let derivatives = match need {
            Need::Values => false,
            Need::Derivatives => true,
            Need::ValuesThenDerivatives => keep,
        };
        let mut kept = std::mem::take(&mut self.kernels);
        let blocks = m.div_ceil(BLOCK_ROWS);
        let held = kept.len() == blocks
            && kept
                .iter()
                .all(|b| b.taus == taus && (b.derivatives || !derivatives));
        if held {
            kept.iter().for_each(|b| f(self, b));
        } else {
            kept.resize_with(if keep { blocks } else { blocks.min(1) }, Default::default);
            let mut carry = K::Carry::default();
            for (i, lo) in (0..m).step_by(BLOCK_ROWS).enumerate() {
                let b = &mut kept[if keep { i } else { 0 }];
                let rows = lo..(lo + BLOCK_ROWS).min(m);
                b.compute(&*self.kern, taus, rows, derivatives, &mut carry);
                f(self, b);
            }
        }
        self.kernels = kept;
    }

    /// e∞·x + Σ eᵢ·hᵢ at the rows of `b` into `out` (the model over S).
    fn combine(&self, p: &[f64], b: &KernelBlock, out: &mut [f64]) {
        let len = b.rows.len();
        for (o, x) in out.iter_mut().zip(&self.kern.input()[b.rows.clone()]) {
            *o = p[0] * x;
        }
        for (e, h) in p[1..=self.n_terms].iter().zip(b.h.chunks_exact(len)) {
            for (o, h) in out.iter_mut().zip(h) {
                *o += e * h;
            }
        }
    }

    /// One pass at `p`: the residuals wₖ·(S·(e∞·xₖ + Σ eᵢ·hᵢₖ) − yₖ) into `r`, and for
    /// each block `then(self, block, model over S, residuals)` of its rows.
    fn residual_pass(
        &mut self,
        p: &[f64],
        need: Need,
        r: &mut [f64],
        mut then: impl FnMut(&Self, &KernelBlock, &[f64], &[f64]),
    ) {
        let taus = self.taus(p);
        let s = self.scale;
        let mut model = vec![0.0; BLOCK_ROWS.min(self.len())];
        self.pass(&taus, need, |prob, b| {
            let rows = b.rows.clone();
            let c = &mut model[..rows.len()];
            prob.combine(p, b, c);
            let rb = &mut r[rows.clone()];
            for (((rk, c), w), y) in rb
                .iter_mut()
                .zip(&*c)
                .zip(&prob.w[rows.clone()])
                .zip(&prob.y[rows])
            {
                *rk = w * (s * c - y);
            }
            then(prob, b, c, rb);
        });
    }

    /// Each term's reach: the largest weighted change it makes to any row,
    /// maxₖ wₖ·|Eᵢ·hₖ(τᵢ)| (a relative change where the weights are relative).
    pub fn reach(&mut self, p: &[f64]) -> Vec<f64> {
        let mut reach = vec![0.0; self.n_terms];
        let taus = self.taus(p);
        self.pass(&taus, Need::Values, |prob, b| {
            prob.reach_block(p, b, &mut reach)
        });
        reach
    }

    /// [`Problem::reach`] over the rows of `b`, each term's into `reach` where larger.
    fn reach_block(&self, p: &[f64], b: &KernelBlock, reach: &mut [f64]) {
        let (len, s) = (b.rows.len(), self.scale);
        let w = &self.w[b.rows.clone()];
        for ((e, h), reach) in p[1..=self.n_terms]
            .iter()
            .zip(b.h.chunks_exact(len))
            .zip(reach)
        {
            *reach = h
                .iter()
                .zip(w)
                .map(|(h, w)| (w * s * e * h).abs())
                .fold(*reach, f64::max);
        }
    }

    /// What the assessment takes of a fit at `p`, in one pass over the rows: the
    /// residuals into `r` (those of [`LeastSquares::eval`]), the model observations
    /// (stress, modulus) into `model`, and each term's reach ([`Problem::reach`]),
    /// returned; the kernels' derivatives at p follow (a problem that keeps its
    /// kernels keeps them for the Jacobian: [`Need::ValuesThenDerivatives`]).
    pub(crate) fn residuals_model_reach(
        &mut self,
        p: &[f64],
        r: &mut [f64],
        model: &mut [f64],
    ) -> Vec<f64> {
        self.evaluations += 1;
        let s = self.scale;
        let mut reach = vec![0.0; self.n_terms];
        self.residual_pass(p, Need::ValuesThenDerivatives, r, |prob, b, c, _| {
            for (m, c) in model[b.rows.clone()].iter_mut().zip(c) {
                *m = c * s;
            }
            prob.reach_block(p, b, &mut reach);
        });
        reach
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
        let (x, s) = (&self.kern.input()[lo..hi], self.scale);
        for ((o, x), w) in out.iter_mut().zip(x).zip(&self.w[lo..hi]) {
            *o = x * (w * s);
        }
    }

    /// The rows of `b` of the columns [w·S·x | w·S·h(τᵢ)… | w·y | w·S·τᵢ·∂h/∂τ(τᵢ)…]
    /// (the last N only when `derivatives`, which `b` must hold then) end to end
    /// into `out`: the columns of [`super::projection::Projected`]'s Gram products a
    /// block at a time, each value the product [`Problem::kernel_columns`] forms
    /// (h·wS, ∂h/∂τ·(wS·τ)), so the same bits.
    pub(crate) fn design_block(&self, b: &KernelBlock, derivatives: bool, out: &mut Vec<f64>) {
        let (lo, hi) = (b.rows.start, b.rows.end);
        let (n, len, s) = (self.n_terms, hi - lo, self.scale);
        let cols = 2 + n + if derivatives { n } else { 0 };
        out.resize(cols * len, 0.0);
        let w = &self.w[lo..hi];
        let (x, rest) = out.split_at_mut(len);
        self.input_column_block(lo, hi, x);
        let (a, rest) = rest.split_at_mut(n * len);
        for (a, h) in a.chunks_exact_mut(len).zip(b.h.chunks_exact(len)) {
            for ((a, w), h) in a.iter_mut().zip(w).zip(h) {
                *a = h * (w * s);
            }
        }
        let (t, d) = rest.split_at_mut(len);
        self.targets_block(lo, hi, t);
        if derivatives {
            let dh = b.dh.chunks_exact(len);
            for ((a, tau), dh) in d.chunks_exact_mut(len).zip(&b.taus).zip(dh) {
                for ((a, w), dh) in a.iter_mut().zip(w).zip(dh) {
                    *a = dh * (w * s * tau);
                }
            }
        }
    }

    /// The rows of `b` (which must hold the kernels' derivatives at `p`) of the
    /// Jacobian at `p` end to end into `out`: the columns w·S·x, w·S·hᵢ and
    /// w·S·eᵢ·τᵢ·∂hᵢ/∂τ of [`LeastSquares::eval`].
    pub(crate) fn jacobian_block(&self, p: &[f64], b: &KernelBlock, out: &mut [f64]) {
        let (lo, hi) = (b.rows.start, b.rows.end);
        let (n, len, s) = (self.n_terms, hi - lo, self.scale);
        let w = &self.w[lo..hi];
        let (j0, terms) = out.split_at_mut(len);
        self.input_column_block(lo, hi, j0);
        let (je, jt) = terms.split_at_mut(n * len);
        for i in 0..n {
            let (e, tau) = (p[1 + i], b.taus[i]);
            let (h, dh) = (&b.h[i * len..(i + 1) * len], &b.dh[i * len..(i + 1) * len]);
            for ((j, w), h) in je[i * len..(i + 1) * len].iter_mut().zip(w).zip(h) {
                *j = w * s * h;
            }
            for ((j, w), dh) in jt[i * len..(i + 1) * len].iter_mut().zip(w).zip(dh) {
                *j = w * s * e * tau * dh;
            }
        }
    }

    /// The design's columns of the terms at `taus`, w·S·h(τᵢ), end to end into `out`
    /// (one pass over the data, [`Kernels::kernels`]), and their derivatives
    /// w·S·τᵢ·∂h/∂τ(τᵢ) = ∂aᵢ/∂ln τᵢ into `dout` if given: the whole m × N matrix, for
    /// the grid NNLS of at most [`super::refine::START_POINTS`] rows.
    pub(crate) fn kernel_columns(
        &self,
        taus: &[f64],
        out: &mut [f64],
        mut dout: Option<&mut [f64]>,
    ) {
        let (m, s) = (self.len(), self.scale);
        self.kern.kernels(taus, out, dout.as_deref_mut());
        for (i, &tau) in taus.iter().enumerate() {
            for (a, w) in out[i * m..(i + 1) * m].iter_mut().zip(self.w.iter()) {
                *a *= w * s;
            }
            if let Some(d) = dout.as_deref_mut() {
                for (a, w) in d[i * m..(i + 1) * m].iter_mut().zip(self.w.iter()) {
                    *a *= w * s * tau;
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
    /// Jacobian, its normal equations JᵀJ and Jᵀr summed a block of rows at a time
    /// (no m × (2N + 1) Jacobian formed: at 10⁶ points 104 MB for six terms), kept
    /// for [`LeastSquares::normal_equations`]: all in one pass over the rows.
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        self.evaluations += 1;
        let (m, k) = (self.len(), 1 + 2 * self.n_terms);
        let finite = |v: &[f64]| v.iter().all(|v| v.is_finite());
        let r = r.as_mut_slice();
        let Some(jac) = jac else {
            self.residual_pass(p, Need::Values, r, |_, _, _, _| {});
            return finite(r);
        };
        let normal = jac.nrows() == 0;
        if !normal {
            debug_assert_eq!(jac.shape(), (m, k));
        }
        let (mut jtj, mut jtr) = (DMatrix::<f64>::zeros(k, k), DVector::<f64>::zeros(k));
        let mut block = std::mem::take(&mut self.block);
        let jac = jac.as_mut_slice();
        self.residual_pass(p, Need::Derivatives, r, |prob, b, _, rb| {
            let len = b.rows.len();
            block.resize(k * len, 0.0);
            prob.jacobian_block(p, b, &mut block);
            let col = |i: usize| &block[i * len..(i + 1) * len];
            if !normal {
                for c in 0..k {
                    jac[c * m + b.rows.start..c * m + b.rows.end].copy_from_slice(col(c));
                }
                return;
            }
            for j in 0..k {
                for i in 0..=j {
                    jtj[(i, j)] += dot(col(i), col(j));
                }
                jtr[j] += dot(col(j), rb);
            }
        });
        self.block = block;
        if !normal {
            return finite(r) && finite(jac);
        }
        for j in 0..k {
            for i in 0..j {
                jtj[(j, i)] = jtj[(i, j)];
            }
        }
        let formed = finite(r) && finite(jtj.as_slice()) && finite(jtr.as_slice());
        match formed {
            true => self.normal.keep(p, jtj, jtr),
            false => self.normal.clear(),
        }
        formed
    }
    /// A trial's Jacobian costs the kernels' derivatives and the columns over the
    /// residuals alone, where evaluating again after an accepted trial costs the
    /// kernels twice.
    fn jacobian_with_trial(&self) -> bool {
        true
    }
    /// The search takes the normal equations a block of rows at a time.
    fn forms_normal_equations(&self) -> bool {
        true
    }
    fn normal_equations(&self, p: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
        self.normal.at(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::prony::projection::Projected;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Time between rows of [`Decays`].
    const STEP: f64 = 0.01;

    /// Rows k = 0, 1, … with x = 1 and hₖ(τ) = e^(−k·STEP/τ), each row's from the
    /// row before (hₖ₊₁ = hₖ·e^(−STEP/τ): a recursion, as the time domain's), and
    /// ∂h/∂τ = k·STEP/τ²·hₖ; `computed` counts the kernels computed.
    #[derive(Debug, Clone)]
    struct Decays {
        x: Vec<f64>,
        computed: Arc<AtomicUsize>,
    }

    /// Where a pass of [`Decays`] stands: its next row and each τ's kernel there.
    #[derive(Debug, Clone, Default)]
    struct Stand {
        row: usize,
        h: Vec<f64>,
    }

    impl Kernels for Decays {
        const WINDOW: &'static str = "the rows";
        type Carry = Stand;
        fn len(&self) -> usize {
            self.x.len()
        }
        fn input(&self) -> &[f64] {
            &self.x
        }
        fn kernel_rows(
            &self,
            taus: &[f64],
            rows: std::ops::Range<usize>,
            carry: &mut Stand,
            h: &mut [f64],
            mut dh: Option<&mut [f64]>,
        ) {
            assert_eq!(carry.row, rows.start, "a pass resumes where it stood");
            if rows.start == 0 {
                carry.h = vec![1.0; taus.len()];
            }
            let len = rows.len();
            for (i, &tau) in taus.iter().enumerate() {
                let (a, mut s) = ((-STEP / tau).exp(), carry.h[i]);
                for (q, k) in rows.clone().enumerate() {
                    h[i * len + q] = s;
                    if let Some(dh) = dh.as_deref_mut() {
                        dh[i * len + q] = k as f64 * STEP / (tau * tau) * s;
                    }
                    s *= a;
                }
                carry.h[i] = s;
            }
            carry.row = rows.end;
            self.computed.fetch_add(taus.len() * len, Ordering::Relaxed);
        }
        /// The rows `idx`, numbered anew from 0.
        fn subsample(&self, idx: &[usize]) -> Option<Decays> {
            Some(Decays {
                x: idx.iter().map(|&i| self.x[i]).collect(),
                computed: self.computed.clone(),
            })
        }
        fn outside_window(name: &str, _: bool, _: (f64, f64)) -> String {
            name.to_string()
        }
    }

    /// A problem of `m` rows of [`Decays`] with `n` terms: the data those of
    /// E∞ = 1 and Eᵢ = 1 at τ = 0.1, 1, 10, … (s), unit weights and scale.
    fn decays(m: usize, n: usize) -> (Problem<Decays>, Arc<AtomicUsize>) {
        let computed = Arc::new(AtomicUsize::new(0));
        let kern = Decays {
            x: vec![1.0; m],
            computed: computed.clone(),
        };
        let taus: Vec<f64> = (0..n).map(|i| 0.1 * 10f64.powi(i as i32)).collect();
        let mut h = vec![0.0; n * m];
        kern.kernels(&taus, &mut h, None);
        let y = (0..m)
            .map(|k| 1.0 + (0..n).map(|i| h[i * m + k]).sum::<f64>())
            .collect();
        let mut prob = Problem::new(kern, y, vec![1.0; m], 1.0);
        prob.n_terms = n;
        computed.store(0, Ordering::Relaxed);
        (prob, computed)
    }

    /// The kernels and derivatives a pass at `taus` hands its blocks, gathered as
    /// [`Kernels::kernels`] lays them out (a column of m values a τ), as bits.
    fn passed(prob: &mut Problem<Decays>, taus: &[f64], need: Need) -> (Vec<u64>, Vec<u64>) {
        let (m, n) = (prob.len(), taus.len());
        let (mut h, mut dh) = (vec![0u64; n * m], vec![0u64; n * m]);
        prob.pass(taus, need, |_, b| {
            let len = b.rows.len();
            for i in 0..n {
                for (q, k) in b.rows.clone().enumerate() {
                    h[i * m + k] = b.h[i * len + q].to_bits();
                    dh[i * m + k] = b.dh.get(i * len + q).map_or(0, |v| v.to_bits());
                }
            }
        });
        (h, dh)
    }

    /// [`Kernels::kernels`] at `taus` over all the rows in one pass (not counted
    /// in the problem's `computed`), as bits.
    fn one_pass(prob: &Problem<Decays>, taus: &[f64]) -> (Vec<u64>, Vec<u64>) {
        let size = taus.len() * prob.len();
        let (mut h, mut dh) = (vec![0.0; size], vec![0.0; size]);
        let kern = Decays {
            x: prob.kern.x.clone(),
            computed: Arc::default(),
        };
        kern.kernels(taus, &mut h, Some(&mut dh));
        let bits = |v: Vec<f64>| v.into_iter().map(f64::to_bits).collect();
        (bits(h), bits(dh))
    }

    /// A problem of several blocks whose kernels and derivatives fit
    /// [`KEPT_KERNEL_BYTES`] (exactly) computes them once a τ: a pass at the τ of
    /// the pass before takes them, with derivatives when they were computed with
    /// them ([`Need::ValuesThenDerivatives`]), and recomputes them for the
    /// derivatives otherwise; each pass hands the bits of a pass over all rows at
    /// once. A variable-projection evaluation (the Gram products and the
    /// residuals: two passes) and the joint problem's evaluation at its τ after it
    /// compute N·m kernels (they were 3·N·m: the time domain's 18 % at 10⁵ points).
    #[test]
    fn kernels_within_the_budget_are_computed_once_a_tau() {
        let n = 4;
        let m = KEPT_KERNEL_BYTES / (2 * n * std::mem::size_of::<f64>());
        let (mut prob, computed) = decays(m, n);
        assert!(m > 2 * BLOCK_ROWS && prob.keeps_kernels(n));
        let count = || computed.swap(0, Ordering::Relaxed);
        let (a, b) = (vec![0.2, 3.0, 40.0, 500.0], vec![0.3, 3.0, 40.0, 500.0]);
        let (ha, dha) = one_pass(&prob, &a);
        let both = passed(&mut prob, &a, Need::ValuesThenDerivatives);
        assert_eq!(both, (ha.clone(), dha.clone()));
        assert_eq!(count(), n * m);
        assert_eq!(passed(&mut prob, &a, Need::Derivatives), (ha.clone(), dha));
        assert_eq!(count(), 0, "the second pass at the same τ");
        assert_eq!(prob.kernel_values(), (n * m, n * m));
        let (hb, dhb) = one_pass(&prob, &b);
        let none = vec![0; n * m];
        assert_eq!(
            passed(&mut prob, &b, Need::Values),
            (hb.clone(), none.clone())
        );
        assert_eq!(passed(&mut prob, &b, Need::Values), (hb.clone(), none));
        assert_eq!(count(), n * m);
        assert_eq!(passed(&mut prob, &b, Need::Derivatives), (hb, dhb));
        assert_eq!(count(), n * m, "values kept without their derivatives");
        assert_eq!(passed(&mut prob, &a, Need::Values).0, ha);
        assert_eq!(count(), n * m);

        let theta: Vec<f64> = b.iter().map(|t| t.ln()).collect();
        let mut r = DVector::zeros(m);
        let mut vp = Projected::new(&mut prob);
        assert!(vp.eval(&theta, &mut r, Some(&mut DMatrix::zeros(0, n))));
        let joint = vp.joint(&theta);
        assert!(prob.eval(&joint, &mut r, Some(&mut DMatrix::zeros(0, 2 * n + 1))));
        assert_eq!(count(), n * m);
        prob.release_kernels();
        assert_eq!(prob.kernel_values(), (0, 0));
    }

    /// A problem whose kernels and derivatives exceed [`KEPT_KERNEL_BYTES`] (by one
    /// row's) holds those of one block of rows, not of every row, and computes them
    /// again each pass, the same bits as a pass over all rows at once. Its
    /// subsamples keep their kernels as it does, except in one block; those of a
    /// problem within the budget keep them.
    #[test]
    fn kernels_beyond_the_budget_are_held_a_block_at_a_time() {
        let n = 4;
        let m = KEPT_KERNEL_BYTES / (2 * n * std::mem::size_of::<f64>()) + 1;
        let (mut prob, computed) = decays(m, n);
        assert!(!prob.keeps_kernels(n));
        let taus = [0.2, 3.0, 40.0, 500.0];
        let (h, dh) = one_pass(&prob, &taus);
        for need in [Need::ValuesThenDerivatives, Need::Values] {
            assert_eq!(passed(&mut prob, &taus, need).0, h);
            assert_eq!(computed.swap(0, Ordering::Relaxed), n * m);
        }
        assert_eq!(passed(&mut prob, &taus, Need::Derivatives), (h, dh));
        assert_eq!(computed.swap(0, Ordering::Relaxed), n * m);
        let (h, dh) = prob.kernel_values();
        assert!(h <= n * BLOCK_ROWS && dh <= n * BLOCK_ROWS, "{h}, {dh}");
        let keeps = |prob: &Problem<Decays>, rows| prob.subsample(rows).unwrap().keeps_kernels(n);
        assert!(!keeps(&prob, 4 * BLOCK_ROWS) && keeps(&prob, BLOCK_ROWS));
        let (within, _) = decays(m - 1, n);
        assert!(keeps(&within, 4 * BLOCK_ROWS));
    }
}
