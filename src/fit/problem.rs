//! The hyperelastic least-squares problem: scaled residuals r_i = s_i·(P(λ_i; p) − y_i)
//! and their Jacobian, plus the variable-projection form that solves the linear
//! coefficients exactly inside the search over the nonlinear ones.

use super::linear::{self, RowQr};
use super::lm::LeastSquares;
use crate::data::{Dataset, Sample};
use crate::material::hyperelastic::{Mode, Points, StrainEnergy};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How residuals are measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Residual {
    /// Absolute stress error in Pa (default): load-cell noise is absolute, and
    /// relative errors blow up rounding noise at the near-zero stresses by λ = 1.
    #[default]
    Abs,
    /// Error relative to the measured stress, with a floor of 1 % of the mode's
    /// largest |stress| so that points at λ = 1 (P = 0) stay finite.
    Rel,
}

/// Residual floor of relative residuals, as a fraction of the mode's largest |stress|.
pub const REL_FLOOR: f64 = 0.01;

/// Data of a fit, flattened for fast evaluation.
pub struct HyperProblem<'a> {
    /// The model.
    pub model: &'a dyn StrainEnergy,
    /// Mode of each point.
    pub modes: Vec<Mode>,
    /// Stretch of each point (read-only after construction: `ln_stretch` is taken
    /// from it once).
    pub stretch: Vec<f64>,
    /// ln λ of each point, fixed data taken once ([`Points`]); NaN where the model
    /// reads no logarithm ([`StrainEnergy::reads_ln_stretch`]).
    ln_stretch: Vec<f64>,
    /// Measured nominal stress (Pa).
    pub stress: Vec<f64>,
    /// Residual multiplier s_i (√(weight / largest weight) / scale).
    pub scale: Vec<f64>,
    /// Evaluation count.
    pub evaluations: usize,
    /// Number of the model's parameters.
    k: usize,
    /// Row-major n × k Jacobian rows of an evaluation, reused.
    rows: Vec<f64>,
}

/// Problems with at least this many points evaluate their residuals and Jacobian in
/// parallel, in blocks of [`BLOCK_ROWS`] points (the model evaluates a block at a
/// time, [`StrainEnergy::nominal_stresses`], each point on its own, so the values
/// are those of the serial loop, bit for bit); the tensile reader reads the rows of
/// such a file, and the fit predicts its stresses, in parallel in the same way.
pub const PARALLEL_ROWS: usize = 16_384;
/// Points per parallel block.
const BLOCK_ROWS: usize = 2048;

impl<'a> HyperProblem<'a> {
    /// Build from a dataset.
    pub fn new(model: &'a dyn StrainEnergy, data: &Dataset, residual: Residual) -> Self {
        let s = &data.samples;
        // Each mode's largest |stress| (the floor of relative residuals), in one pass.
        let mut max_abs = [0.0f64; 3];
        let slot = Mode::index;
        if residual == Residual::Rel {
            for x in s {
                let a = &mut max_abs[slot(x.mode)];
                *a = a.max(x.stress.abs());
            }
        }
        // Weights are relative: divided by the largest, every multiplier is ≤ 1 and
        // no weight (1e300, say) can overflow the cost.
        let w_max = s.iter().map(|x| x.weight).fold(0.0, f64::max);
        let scale_of = |x: &Sample| {
            let w = (x.weight / w_max).sqrt();
            match residual {
                Residual::Abs => w,
                Residual::Rel => {
                    let floor = (REL_FLOOR * max_abs[slot(x.mode)]).max(f64::MIN_POSITIVE);
                    w / x.stress.abs().max(floor)
                }
            }
        };
        // Each column in a pass over the samples (a large dataset's in parallel); the
        // logarithms only for a model that reads them (NaN otherwise: never read).
        let logs = model.reads_ln_stretch();
        let (modes, stretch, ln_stretch, stress, scale) = if s.len() < PARALLEL_ROWS {
            (
                s.iter().map(|x| x.mode).collect(),
                s.iter().map(|x| x.stretch).collect(),
                if logs {
                    s.iter().map(|x| x.stretch.ln()).collect()
                } else {
                    vec![f64::NAN; s.len()]
                },
                s.iter().map(|x| x.stress).collect(),
                s.iter().map(scale_of).collect(),
            )
        } else {
            (
                s.par_iter().map(|x| x.mode).collect(),
                s.par_iter().map(|x| x.stretch).collect(),
                if logs {
                    s.par_iter().map(|x| x.stretch.ln()).collect()
                } else {
                    vec![f64::NAN; s.len()]
                },
                s.par_iter().map(|x| x.stress).collect(),
                s.par_iter().map(scale_of).collect(),
            )
        };
        HyperProblem {
            model,
            modes,
            stretch,
            ln_stretch,
            stress,
            scale,
            evaluations: 0,
            k: model.params().len(),
            rows: Vec::new(),
        }
    }

    /// The same problem with repeated (mode, stretch) points merged into one row:
    /// Σ s_i²(P − y_i)² = S²(P − ȳ)² + Σ s_i²(y_i − ȳ)² with S² = Σ s_i² and ȳ the
    /// s²-weighted mean, so the minimiser is unchanged and an evaluation costs one row
    /// per distinct point (10⁶ repeats of three stretches: three rows). The constant
    /// is left out: merged problems are for the search, not for residual statistics.
    /// `None` when no point repeats (the problem is its own merge).
    ///
    /// Repeats are found by sorting the points by (mode, stretch), which costs almost
    /// nothing on the usual monotone loading curves (a hash map per point was 30 % of
    /// fitting 10⁶ points); merged rows keep the order of their first occurrence.
    pub fn merge_repeats(&self) -> Option<Self> {
        let n = self.len();
        let key = |i: usize| (self.modes[i], self.stretch[i].to_bits());
        let mut order: Vec<usize> = (0..n).collect();
        // Stable: each run of equal keys starts at the point's first occurrence.
        order.sort_by_key(|&i| key(i));
        if order.windows(2).all(|w| key(w[0]) != key(w[1])) {
            return None;
        }
        // first[i]: the first occurrence of point i's (mode, stretch).
        let mut first = vec![0; n];
        for run in order.chunk_by(|&i, &j| key(i) == key(j)) {
            for &i in run {
                first[i] = run[0];
            }
        }
        let mut row = vec![usize::MAX; n];
        let (mut modes, mut stretch, mut ln_stretch) = (vec![], vec![], vec![]);
        let (mut s2, mut s2y) = (vec![], vec![]);
        for i in 0..n {
            let f = first[i];
            if row[f] == usize::MAX {
                row[f] = modes.len();
                modes.push(self.modes[i]);
                stretch.push(self.stretch[i]);
                ln_stretch.push(self.ln_stretch[i]);
                s2.push(0.0);
                s2y.push(0.0);
            }
            let j = row[f];
            let w = self.scale[i] * self.scale[i];
            s2[j] += w;
            s2y[j] += w * self.stress[i];
        }
        Some(HyperProblem {
            model: self.model,
            stress: s2
                .iter()
                .zip(&s2y)
                .map(|(w, wy)| if *w > 0.0 { wy / w } else { 0.0 })
                .collect(),
            scale: s2.iter().map(|w| w.sqrt()).collect(),
            modes,
            stretch,
            ln_stretch,
            evaluations: 0,
            k: self.k,
            rows: Vec::new(),
        })
    }

    /// At most `per_mode` points of each mode, spread evenly over its stretches (the
    /// mode's points sorted by stretch, every ((m − 1)/(per_mode − 1))-th taken, both
    /// ends kept), in their original order and with their multipliers; `None` when no
    /// mode has more than `per_mode` points (the problem is its own subsample).
    /// A smooth loading curve keeps its shape, so a multi-start search on the
    /// subsample finds the basin of the optimum at a cost independent of n.
    pub fn subsample(&self, per_mode: usize) -> Option<HyperProblem<'a>> {
        let per_mode = per_mode.max(2);
        let mut keep = Vec::new();
        let mut thinned = false;
        for mode in Mode::ALL {
            let mut idx: Vec<usize> = (0..self.len()).filter(|&i| self.modes[i] == mode).collect();
            let m = idx.len();
            if m <= per_mode {
                keep.extend(idx);
                continue;
            }
            thinned = true;
            idx.sort_by(|&i, &j| self.stretch[i].total_cmp(&self.stretch[j]));
            keep.extend(
                (0..per_mode).map(|q| idx[(q * (m - 1) + (per_mode - 1) / 2) / (per_mode - 1)]),
            );
        }
        if !thinned {
            return None;
        }
        keep.sort_unstable();
        keep.dedup();
        Some(HyperProblem {
            model: self.model,
            modes: keep.iter().map(|&i| self.modes[i]).collect(),
            stretch: keep.iter().map(|&i| self.stretch[i]).collect(),
            ln_stretch: keep.iter().map(|&i| self.ln_stretch[i]).collect(),
            stress: keep.iter().map(|&i| self.stress[i]).collect(),
            scale: keep.iter().map(|&i| self.scale[i]).collect(),
            evaluations: 0,
            k: self.k,
            rows: Vec::new(),
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.stretch.len()
    }

    /// True if there are no points.
    pub fn is_empty(&self) -> bool {
        self.stretch.is_empty()
    }

    /// Largest I1 − 3 over the data (the Gent limit must exceed it).
    pub fn max_i1_minus_3(&self) -> f64 {
        self.modes
            .iter()
            .zip(&self.stretch)
            .map(|(m, &l)| m.kinematics(l).invariants().0 - 3.0)
            .fold(0.0, f64::max)
    }

    /// The points `rows` for the model's block evaluators.
    fn points(&self, rows: std::ops::Range<usize>) -> Points<'_> {
        Points::new(
            &self.modes[rows.clone()],
            &self.stretch[rows.clone()],
            &self.ln_stretch[rows],
        )
        .expect("the problem's columns have one length")
    }

    /// The scaled Jacobian rows s_i·∂P/∂p of the points `rows` into `out` (row-major,
    /// k values a point), by the model's block evaluator.
    fn scaled_rows(&self, p: &[f64], rows: std::ops::Range<usize>, out: &mut [f64]) {
        let k = self.k.max(1);
        let at = rows.start;
        self.model.stress_jacobians(p, self.points(rows), out);
        for (i, row) in out.chunks_exact_mut(k).enumerate() {
            let s = self.scale[at + i];
            row.iter_mut().for_each(|v| *v *= s);
        }
    }

    /// Scaled Jacobian ∂r/∂p into `jac` (n × k): the model's rows in blocks of
    /// [`BLOCK_ROWS`] points ([`StrainEnergy::stress_jacobians`]), in parallel from
    /// [`PARALLEL_ROWS`] points on, then scaled column by column into `jac`.
    pub fn jacobian(&mut self, p: &[f64], jac: &mut DMatrix<f64>) {
        let (n, k) = (self.len(), self.k);
        if n == 0 || k == 0 {
            return;
        }
        let mut rows = std::mem::take(&mut self.rows);
        rows.resize(n * k, 0.0);
        let fill = |(b, block): (usize, &mut [f64])| {
            let at = b * BLOCK_ROWS;
            let pts = self.points(at..at + block.len() / k);
            self.model.stress_jacobians(p, pts, block);
        };
        if n < PARALLEL_ROWS {
            rows.chunks_mut(BLOCK_ROWS * k).enumerate().for_each(fill);
        } else {
            rows.par_chunks_mut(BLOCK_ROWS * k)
                .enumerate()
                .for_each(fill);
        }
        for (j, col) in jac.as_mut_slice().chunks_exact_mut(n).enumerate() {
            for ((c, s), row) in col.iter_mut().zip(&self.scale).zip(rows.chunks_exact(k)) {
                *c = s * row[j];
            }
        }
        self.rows = rows;
    }

    /// The triangular factor of [J | s·y] (J the scaled Jacobian ∂r/∂p at `p`, s·y the
    /// scaled targets), built row by row without storing J ([`RowQr`]): for a model
    /// linear in its parameters, the whole least-squares problem. A problem of
    /// [`PARALLEL_ROWS`] points or more is factored in blocks of [`BLOCK_ROWS`] in
    /// parallel and the blocks' factors appended in order ([`RowQr::append`]): the
    /// same blocks on any number of threads, so the same factor bit for bit.
    pub fn factor(&self, p: &[f64]) -> RowQr {
        let (n, k) = (self.len(), self.k);
        if n < PARALLEL_ROWS {
            return self.factor_rows(p, 0..n, RowQr::with_rows(k, n));
        }
        let blocks: Vec<RowQr> = (0..n.div_ceil(BLOCK_ROWS))
            .into_par_iter()
            .map(|b| {
                let rows = b * BLOCK_ROWS..n.min((b + 1) * BLOCK_ROWS);
                self.factor_rows(p, rows, RowQr::new(k))
            })
            .collect();
        let mut qr = RowQr::new(k);
        blocks.iter().for_each(|b| qr.append(b));
        qr
    }

    /// `qr` with the scaled rows [J | s·y] of the points `rows` pushed, evaluated
    /// [`BLOCK_ROWS`] at a time ([`HyperProblem::scaled_rows`]).
    fn factor_rows(&self, p: &[f64], rows: std::ops::Range<usize>, mut qr: RowQr) -> RowQr {
        let k = self.k.max(1);
        let mut block = vec![0.0; rows.len().min(BLOCK_ROWS) * k];
        for at in rows.clone().step_by(BLOCK_ROWS) {
            let end = rows.end.min(at + BLOCK_ROWS);
            let out = &mut block[..(end - at) * k];
            self.scaled_rows(p, at..end, out);
            for (i, row) in (at..end).zip(out.chunks_exact(k)) {
                qr.push(row, self.scale[i] * self.stress[i]);
            }
        }
        qr
    }

    /// Scaled residuals s_i·(P_i − y_i), the stresses P_i by the model's block
    /// evaluator ([`StrainEnergy::nominal_stresses`]) [`BLOCK_ROWS`] points at a time,
    /// in parallel from [`PARALLEL_ROWS`] points on; false if any is not finite.
    pub fn residuals(&self, p: &[f64], r: &mut DVector<f64>) -> bool {
        let block = |(b, out): (usize, &mut [f64])| {
            let at = b * BLOCK_ROWS;
            self.model
                .nominal_stresses(p, self.points(at..at + out.len()), out);
            let mut ok = true;
            for (i, v) in (at..).zip(out.iter_mut()) {
                *v = self.scale[i] * (*v - self.stress[i]);
                ok &= v.is_finite();
            }
            ok
        };
        let r = &mut r.as_mut_slice()[..self.len()];
        if self.len() < PARALLEL_ROWS {
            // Every block evaluated (no short circuit: all of r is written).
            let mut ok = true;
            for b in r.chunks_mut(BLOCK_ROWS).enumerate() {
                ok &= block(b);
            }
            return ok;
        }
        r.par_chunks_mut(BLOCK_ROWS)
            .enumerate()
            .map(block)
            .reduce(|| true, |a, b| a && b)
    }

    /// Scaled measured stresses s_i·y_i.
    pub fn scaled_targets(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.len(),
            self.stress.iter().zip(&self.scale).map(|(y, s)| y * s),
        )
    }
}

impl LeastSquares for HyperProblem<'_> {
    fn dims(&self) -> (usize, usize) {
        (self.len(), self.model.params().len())
    }
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        self.evaluations += 1;
        if !self.residuals(p, r) {
            return false;
        }
        if let Some(j) = jac {
            self.jacobian(p, j);
            return j.iter().all(|v| v.is_finite());
        }
        true
    }
}

/// Solve min ‖A·c − b‖ by SVD with a relative rank tolerance; returns (c, U_r) where
/// U_r spans the range of A (for the orthogonal projector), or `None` if A is empty
/// of rank or A or b hold a value that is not finite (see [`linear::svd`]).
pub fn svd_solve(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<(DVector<f64>, DMatrix<f64>)> {
    if !b.iter().all(|v| v.is_finite()) {
        return None;
    }
    let svd = linear::svd(a.clone(), true, true)?;
    let smax = svd.singular_values.max();
    if smax <= 0.0 {
        return None;
    }
    let tol = smax * 1e-13 * (a.nrows().max(a.ncols()) as f64);
    let u = svd.u.as_ref()?;
    let vt = svd.v_t.as_ref()?;
    let rank = svd.singular_values.iter().filter(|&&s| s > tol).count();
    let mut c = DVector::zeros(a.ncols());
    for k in 0..rank {
        let coef = u.column(k).dot(b) / svd.singular_values[k];
        c += vt.row(k).transpose() * coef;
    }
    Some((c, u.columns(0, rank).into_owned()))
}

/// [`svd_solve`] by the row-by-row QR of [A | b] ([`RowQr`]) and an SVD of its small
/// R: the same c (the same rank tolerance) and U_r = A·V_r·Σ_r⁻¹, which spans the
/// same range, in a pass over the rows and without an SVD of the tall A (on 10⁵
/// rows the tall SVD was a quarter of `hyperelastic --model auto`). None as
/// [`svd_solve`].
pub fn range_solve(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<(DVector<f64>, DMatrix<f64>)> {
    if !b.iter().all(|v| v.is_finite()) {
        return None;
    }
    let k = a.ncols();
    let mut qr = RowQr::with_rows(k, a.nrows());
    let mut row = vec![0.0; k];
    for (i, &bi) in b.iter().enumerate() {
        for (j, d) in row.iter_mut().enumerate() {
            *d = a[(i, j)];
        }
        qr.push(&row, bi);
    }
    let (c, w) = qr.solve_with_range()?;
    Some((c, a * w))
}

/// Variable projection (Golub-Pereyra with Kaufman's Jacobian): the search runs over
/// the nonlinear parameters θ only; for each θ the linear coefficients c are the exact
/// least-squares solution, r(θ) = A(θ)c(θ) − b, and ∂r/∂θ ≈ P⊥·(∂A/∂θ)c.
pub struct VarPro<'p, 'a> {
    /// The full problem.
    pub inner: &'p mut HyperProblem<'a>,
    lin: Vec<usize>,
    nonlin: Vec<usize>,
    /// Full parameter vector of the last evaluation.
    pub full: Vec<f64>,
    jfull: DMatrix<f64>,
    b: DVector<f64>,
    /// For each nonlinear parameter, the position in `lin` of the coefficient that
    /// scales its column ([`StrainEnergy::coefficient_of`]), when every one has
    /// such a coefficient: then one model evaluation at unit coefficients gives
    /// both A(θ) and ∂A/∂θ.
    coefficient: Option<Vec<usize>>,
    /// The projection at the last θ evaluated. The search evaluates each accepted
    /// point twice (the residuals to accept it, then the Jacobian there); the second
    /// evaluation reuses the first one's solve.
    last: Option<Projection>,
}

/// The linear solve of variable projection at one θ.
struct Projection {
    theta: Vec<f64>,
    /// The linear columns A(θ).
    a: DMatrix<f64>,
    /// The coefficients c.
    c: DVector<f64>,
    /// U_r, spanning the range of A ([`range_solve`]).
    u: DMatrix<f64>,
    /// The nonlinear columns at unit coefficients (with `coefficient` only).
    unit: Option<DMatrix<f64>>,
}

impl<'p, 'a> VarPro<'p, 'a> {
    /// Wrap a problem; `start` supplies values for all parameters (linear ones are
    /// overwritten by the projection).
    pub fn new(inner: &'p mut HyperProblem<'a>, start: &[f64]) -> Self {
        let params = inner.model.params();
        let lin: Vec<usize> = (0..params.len()).filter(|&k| params[k].linear).collect();
        let nonlin: Vec<usize> = (0..params.len()).filter(|&k| !params[k].linear).collect();
        let jfull = DMatrix::zeros(inner.len(), params.len());
        let b = inner.scaled_targets();
        let coefficient = nonlin
            .iter()
            .map(|&j| {
                let l = inner.model.coefficient_of(j)?;
                lin.iter().position(|&k| k == l)
            })
            .collect();
        VarPro {
            inner,
            lin,
            nonlin,
            coefficient,
            full: start.to_vec(),
            jfull,
            b,
            last: None,
        }
    }

    /// Indices of the nonlinear parameters.
    pub fn nonlinear(&self) -> &[usize] {
        &self.nonlin
    }
}

impl LeastSquares for VarPro<'_, '_> {
    fn dims(&self) -> (usize, usize) {
        (self.inner.len(), self.nonlin.len())
    }
    fn eval(
        &mut self,
        theta: &[f64],
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> bool {
        self.inner.evaluations += 1;
        let (a, c, u, unit) = match self.last.take() {
            Some(p) if p.theta == theta => (p.a, p.c, p.u, p.unit),
            _ => {
                for (&k, &t) in self.nonlin.iter().zip(theta) {
                    self.full[k] = t;
                }
                if self.coefficient.is_some() {
                    self.lin.iter().for_each(|&k| self.full[k] = 1.0);
                }
                self.inner.jacobian(&self.full, &mut self.jfull);
                let a = self.jfull.select_columns(&self.lin);
                if !a.iter().all(|v| v.is_finite()) {
                    return false;
                }
                let Some((c, u)) = range_solve(&a, &self.b) else {
                    return false;
                };
                let unit = self
                    .coefficient
                    .is_some()
                    .then(|| self.jfull.select_columns(&self.nonlin));
                (a, c, u, unit)
            }
        };
        for (&k, &t) in self.nonlin.iter().zip(theta) {
            self.full[k] = t;
        }
        for (&k, &v) in self.lin.iter().zip(c.iter()) {
            self.full[k] = v;
        }
        let fit = &a * &c;
        for i in 0..r.len() {
            r[i] = fit[i] - self.b[i];
        }
        if !r.iter().all(|v| v.is_finite()) {
            return false;
        }
        if let Some(j) = jac {
            let n = match (unit, &self.coefficient) {
                // ∂P/∂θ_q = c_l·(∂P/∂θ_q at unit coefficients), l = coefficient[q].
                (Some(mut n), Some(coefficient)) => {
                    for (q, &l) in coefficient.iter().enumerate() {
                        n.column_mut(q).scale_mut(c[l]);
                    }
                    n
                }
                _ => {
                    self.inner.jacobian(&self.full, &mut self.jfull);
                    self.jfull.select_columns(&self.nonlin)
                }
            };
            let proj = &n - &u * (u.transpose() * &n);
            j.copy_from(&proj);
            return j.iter().all(|v| v.is_finite());
        }
        self.last = Some(Projection {
            theta: theta.to_vec(),
            a,
            c,
            u,
            unit,
        });
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model that says it reads no logarithm gives the same stresses and Jacobian
    /// rows, bit for bit, with the ln λ column NaN (what the problem then holds) as
    /// with the logarithms; Ogden reads them (it is wrong without them), so its
    /// problem takes them. Every model, the three modes, compression to tension.
    #[test]
    fn models_that_read_no_logarithm_do_without() {
        use crate::material::hyperelastic::{ModelSpec, OgdenForm, MODEL_NAMES};
        let modes: Vec<Mode> = (0..12).map(|i| Mode::ALL[i % 3]).collect();
        let stretch: Vec<f64> = (0..12).map(|i| 0.4 + 0.3 * i as f64).collect();
        let logs: Vec<f64> = stretch.iter().map(|l| l.ln()).collect();
        let nan = vec![f64::NAN; 12];
        for name in MODEL_NAMES {
            let m = ModelSpec::new(name, OgdenForm::Abaqus).build().unwrap();
            let k = m.params().len();
            // Linear coefficients of mixed sign; exponents and Gent limits of 40.
            let p: Vec<f64> = (0..k)
                .map(|j| match (m.params()[j].linear, j % 2) {
                    (true, 0) => 1e5,
                    (true, _) => -2e3,
                    (false, _) => 40.0,
                })
                .collect();
            let eval = |ln: &[f64]| {
                let pts = Points::new(&modes, &stretch, ln).unwrap();
                let (mut s, mut j) = (vec![0.0; 12], vec![0.0; 12 * k]);
                m.nominal_stresses(&p, pts, &mut s);
                m.stress_jacobians(&p, pts, &mut j);
                let bits = |v: Vec<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                (bits(s), bits(j))
            };
            assert_eq!(eval(&logs) == eval(&nan), !m.reads_ln_stretch(), "{name}");
        }
    }

    /// The row-QR projection ([`range_solve`]) gives the tall SVD's ([`svd_solve`])
    /// objective, coefficients, projector and rank on a well-conditioned, a graded
    /// (columns 10⁰…10¹⁰, condition ≈ 10¹²) and a rank-deficient Ogden-like basis.
    /// The residual norm is never larger than the SVD's by more than 1e-12 relative
    /// (on one of these bases it is 2.5e-9 smaller: the tall SVD loses digits); c
    /// and U·Uᵀ agree to
    /// 1e-9 where the basis is well conditioned, and to 1e-3 and 1e-4 on the graded
    /// one, whose c and projector are determined only to about ε times its
    /// condition (10⁻⁴) by either method.
    #[test]
    fn range_solve_projects_as_the_tall_svd() {
        let n = 200;
        let t = |i: usize| 1.0 + 6.0 * i as f64 / (n - 1) as f64;
        let b = DVector::from_fn(n, |i, _| (t(i) * 1.3).sin() + 0.1 * t(i));
        let cases = [
            (
                DMatrix::from_fn(n, 3, |i, j| t(i).powf([-2.0, 1.5, 4.0][j])),
                1e-9,
            ),
            (
                DMatrix::from_fn(n, 3, |i, j| {
                    t(i).powi(j as i32 + 1) * 10f64.powi(5 * j as i32)
                }),
                1e-3,
            ),
            (
                DMatrix::from_fn(n, 3, |i, j| t(i).powf([2.0, 2.0, 0.5][j])),
                1e-9,
            ),
        ];
        for (a, tol) in cases {
            let (want_c, want_u) = svd_solve(&a, &b).unwrap();
            let (got_c, got_u) = range_solve(&a, &b).unwrap();
            assert_eq!(got_u.ncols(), want_u.ncols(), "rank");
            let (rw, rg) = ((&a * &want_c - &b).norm(), (&a * &got_c - &b).norm());
            assert!(rg <= rw * (1.0 + 1e-12), "residual {rg} vs {rw}");
            assert!(
                (&got_c - &want_c).norm() <= tol * want_c.norm(),
                "{got_c} vs {want_c}"
            );
            let (pw, pg) = (&want_u * want_u.transpose(), &got_u * got_u.transpose());
            let off = (&pg - &pw).amax();
            assert!(off <= tol.min(1e-4), "projector off by {off}");
        }
        let mut bad = b.clone();
        bad[3] = f64::NAN;
        assert!(range_solve(&DMatrix::from_element(n, 2, 1.0), &bad).is_none());
    }

    /// The projected Jacobian from one evaluation at unit coefficients, each
    /// nonlinear column scaled by its coefficient, equals the one from a second
    /// evaluation at the solved coefficients (Ogden-3, Gent; residuals bit for bit,
    /// Jacobian to 1e-13 of its largest entry: the products are rounded in another
    /// order), at a fresh θ and at the θ just evaluated.
    /// `n` points cycling through the three modes, at stretch `stretch(i)` and weight
    /// `weight(i)`, with a nearly linear stress (1 % of sinusoidal scatter).
    fn three_modes(
        n: usize,
        stretch: impl Fn(usize) -> f64,
        weight: impl Fn(usize) -> f64,
    ) -> Dataset {
        let samples = (0..n)
            .map(|i| Sample {
                mode: Mode::ALL[i % 3],
                stretch: stretch(i),
                stress: 1e5 * (stretch(i) - 1.0) * (1.0 + 0.01 * (i as f64).sin()),
                weight: weight(i),
                source: 0,
                line: i + 1,
            })
            .collect();
        Dataset {
            samples,
            sources: Vec::new(),
        }
    }

    /// A problem of [`PARALLEL_ROWS`] points or more is factored in blocks: the same
    /// factor bit for bit on one thread and on three, and the serial factor's
    /// solution to 1e-13 relative (Yeoh at 3·[`PARALLEL_ROWS`] + 5 points of three
    /// modes; round-off of the two orders of reduction is a few ε times the
    /// condition of the basis, ≈ 10²).
    #[test]
    fn a_large_factor_in_blocks_is_the_factor_of_every_row() {
        use crate::material::hyperelastic::ModelSpec;
        let n = 3 * PARALLEL_ROWS + 5;
        let data = three_modes(
            n,
            |i| 1.0 + 2.0 * i as f64 / n as f64,
            |i| 1.0 + (i % 7) as f64,
        );
        let model = ModelSpec::new("yeoh", Default::default()).build().unwrap();
        let prob = HyperProblem::new(model.as_ref(), &data, Residual::Abs);
        let p = [0.0; 3];
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| prob.factor(&p))
        };
        let (one, three) = (on(1), on(3));
        assert_eq!(one.r(), three.r());
        assert_eq!(one.solve(), three.solve());
        assert_eq!(one.rows(), n);
        let serial = prob.factor_rows(&p, 0..n, RowQr::with_rows(3, n));
        let (got, want) = (one.solve().unwrap(), serial.solve().unwrap());
        assert!(
            (&got - &want).norm() <= 1e-13 * want.norm(),
            "{got} vs {want}"
        );
    }

    /// The problem's residuals, Jacobian and factor are the model's per-point values
    /// scaled, bit for bit, with the model's block evaluators
    /// ([`StrainEnergy::nominal_stresses`]) and the logarithms taken once: serial
    /// (37 points, and a problem's subsample and merge of repeats, which carry
    /// their points' logarithms) and in parallel blocks ([`PARALLEL_ROWS`] + 13),
    /// Ogden-3 (its own block evaluator) and Yeoh (the per-point default).
    #[test]
    fn evaluations_are_the_models_points_bit_for_bit() {
        use crate::material::hyperelastic::ModelSpec;
        let check = |prob: &mut HyperProblem, p: &[f64]| {
            let (n, k) = (prob.len(), p.len());
            let (mut r, mut jac) = (DVector::zeros(n), DMatrix::zeros(n, k));
            assert!(prob.residuals(p, &mut r));
            prob.jacobian(p, &mut jac);
            let mut row = vec![0.0; k];
            for i in 0..n {
                let (mode, lam, s) = (prob.modes[i], prob.stretch[i], prob.scale[i]);
                let want = s * (prob.model.nominal_stress(p, mode, lam) - prob.stress[i]);
                assert_eq!(r[i].to_bits(), want.to_bits(), "point {i} of {n}");
                prob.model.stress_jacobian(p, mode, lam, &mut row);
                for j in 0..k {
                    assert_eq!(jac[(i, j)].to_bits(), (s * row[j]).to_bits(), "({i}, {j})");
                }
            }
            let mut qr = RowQr::with_rows(k, n);
            for i in 0..n {
                let r = jac.row(i).iter().copied().collect::<Vec<_>>();
                qr.push(&r, prob.scale[i] * prob.stress[i]);
            }
            if n < PARALLEL_ROWS {
                assert_eq!(prob.factor(p).r(), qr.r());
            }
        };
        for (name, p) in [
            ("ogden3", vec![3.4e5, 1.92, 3.1, 8.62, 7.3e3, -2.16]),
            ("yeoh", vec![6.9e4, -888.0, 16.7]),
        ] {
            let model = ModelSpec::new(name, Default::default()).build().unwrap();
            for n in [37, PARALLEL_ROWS + 13] {
                // Every stretch twice: the merge of repeats has rows to merge.
                let data = three_modes(
                    n,
                    |i| 0.6 + 4.0 * (i / 6) as f64 / n as f64,
                    |i| 1.0 + (i % 5) as f64,
                );
                let mut prob = HyperProblem::new(model.as_ref(), &data, Residual::Abs);
                check(&mut prob, &p);
                if n < PARALLEL_ROWS {
                    check(&mut prob.subsample(4).unwrap(), &p);
                    check(&mut prob.merge_repeats().unwrap(), &p);
                }
            }
        }
    }

    #[test]
    fn projection_jacobian_from_unit_coefficients() {
        use crate::material::hyperelastic::ModelSpec;
        let data = three_modes(60, |i| 1.05 + 0.05 * i as f64, |_| 1.0);
        for (name, theta) in [("ogden3", vec![-2.0, 1.9, 8.0]), ("gent", vec![40.0])] {
            let model = ModelSpec::new(name, Default::default()).build().unwrap();
            let hidden = crate::material::hyperelastic::WithoutCoefficients(
                ModelSpec::new(name, Default::default()).build().unwrap(),
            );
            assert!(hidden.coefficient_of(1).is_none() && model.coefficient_of(1) == Some(0));
            let k = model.params().len();
            let (mut one, mut two) = (
                HyperProblem::new(model.as_ref(), &data, Residual::Abs),
                HyperProblem::new(&hidden, &data, Residual::Abs),
            );
            let (mut a, mut b) = (
                VarPro::new(&mut one, &vec![1.0; k]),
                VarPro::new(&mut two, &vec![1.0; k]),
            );
            let (n, m) = (data.samples.len(), theta.len());
            for first in [false, true] {
                let (mut ra, mut rb) = (DVector::zeros(n), DVector::zeros(n));
                let (mut ja, mut jb) = (DMatrix::zeros(n, m), DMatrix::zeros(n, m));
                if first {
                    // The residuals first, then the Jacobian at the same θ.
                    assert!(a.eval(&theta, &mut ra, None) && b.eval(&theta, &mut rb, None));
                }
                assert!(a.eval(&theta, &mut ra, Some(&mut ja)));
                assert!(b.eval(&theta, &mut rb, Some(&mut jb)));
                assert_eq!(ra, rb, "{name}");
                let off = (&ja - &jb).amax();
                assert!(off <= 1e-13 * jb.amax(), "{name}: {off} of {}", jb.amax());
            }
        }
    }
}
