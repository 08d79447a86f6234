//! The joint Prony problem: p = [e∞, e₁…e_N, ln τ₁…ln τ_N] in scaled units
//! (observation = S·(e∞·x + Σ eᵢ·hᵢ)), residuals rₖ = wₖ·(model − yₖ), on any
//! domain's rows ([`Kernels`]).

use super::Kernels;
use crate::fit::lm::LeastSquares;
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
    /// Evaluations so far (counted for the solver report).
    pub evaluations: usize,
}

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
        self.kernel_taus.clear();
        self.kernel_derivatives = false;
    }

    /// The weighted data w·y: the right-hand side of the moduli's least squares.
    pub(crate) fn targets(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.len(),
            self.y.iter().zip(self.w.iter()).map(|(y, w)| y * w),
        )
    }

    /// The design's first column, w·S·x (the E∞ term), into `out`.
    pub(crate) fn input_column(&self, out: &mut [f64]) {
        for ((o, x), ws) in out.iter_mut().zip(self.kern.input()).zip(self.ws.iter()) {
            *o = x * ws;
        }
    }

    /// The design's columns of the terms at the τᵢ of the last evaluation,
    /// [`Problem::kernel_columns`] from its kernels `h` (and `dh`, which must hold
    /// their derivatives when `dout` is given): the same products, so the same bits.
    pub(crate) fn design_columns(&self, out: &mut [f64], dout: Option<&mut [f64]>) {
        let m = self.len();
        for (i, a) in out.chunks_exact_mut(m).enumerate() {
            for ((a, ws), h) in a.iter_mut().zip(self.ws.iter()).zip(&self.h[i * m..]) {
                *a = h * ws;
            }
        }
        if let Some(d) = dout {
            for ((i, a), tau) in d.chunks_exact_mut(m).enumerate().zip(&self.taus) {
                for ((a, ws), dh) in a.iter_mut().zip(self.ws.iter()).zip(&self.dh[i * m..]) {
                    *a = dh * (ws * tau);
                }
            }
        }
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
    /// w·S·hᵢ and w·S·eᵢ·τᵢ·∂hᵢ/∂τ (∂/∂ln τᵢ).
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
        let (j0, terms) = jac.as_mut_slice().split_at_mut(m);
        self.input_column(j0);
        let (je, jt) = terms.split_at_mut(n * m);
        for i in 0..n {
            let (e, tau) = (p[1 + i], self.taus[i]);
            let (h, dh) = (&self.h[i * m..(i + 1) * m], &self.dh[i * m..(i + 1) * m]);
            for ((j, ws), h) in je[i * m..(i + 1) * m].iter_mut().zip(self.ws.iter()).zip(h) {
                *j = ws * h;
            }
            for ((j, ws), dh) in jt[i * m..(i + 1) * m]
                .iter_mut()
                .zip(self.ws.iter())
                .zip(dh)
            {
                *j = ws * e * tau * dh;
            }
        }
        finite(r) && finite(jac.as_slice())
    }
    /// A trial's Jacobian costs the kernels' derivatives and the columns over the
    /// residuals alone, where evaluating again after an accepted trial costs the
    /// kernels twice.
    fn jacobian_with_trial(&self) -> bool {
        true
    }
}
