//! Stage 1: non-negative least squares over a log-spaced τ grid (Lawson–Hanson,
//! [`nnls`]): where the relaxation spectrum lives.

use super::problem::Problem;
use super::refine::START_POINTS;
use super::{Kernels, Setup};
use crate::error::{Error, Result};
use crate::fit::nnls::nnls;
use nalgebra::DMatrix;

/// A grid spectrum: (grid τ, scaled coefficients [e∞, e_grid…], active-set
/// iterations).
pub type Grid = (Vec<f64>, Vec<f64>, usize);

/// Stage 1 on the points the starts are searched on ([`START_POINTS`]): the grid
/// spectrum only places the starts of the term counts, and on a longer curve those
/// are searched on its even subsample ([`Problem::subsample`]), so the grid NNLS
/// runs there too instead of on every point (at 10⁵ points that was 37 kernels of
/// 10⁵ points and 703 column products for a spectrum no finer than the subsample's).
/// A curve of at most [`START_POINTS`] points (every shipped one) uses all of it.
pub fn grid_stage<K: Kernels>(setup: &mut Setup<K>, per_decade: usize) -> Result<Grid> {
    match setup.prob.subsample(START_POINTS) {
        Some(mut sub) => grid_nnls(&mut sub, setup.window, per_decade),
        None => grid_nnls(&mut setup.prob, setup.window, per_decade),
    }
}

/// NNLS over the τ grid: `per_decade` τ a decade over the window widened ×3 at
/// each end.
pub fn grid_nnls<K: Kernels>(
    prob: &mut Problem<K>,
    window: (f64, f64),
    per_decade: usize,
) -> Result<Grid> {
    let (a, b) = ((window.0 / 3.0).log10(), (window.1 * 3.0).log10());
    let count = ((b - a) * per_decade as f64).ceil() as usize + 1;
    let taus: Vec<f64> = (0..count)
        .map(|i| 10f64.powf(a + (b - a) * i as f64 / (count - 1) as f64))
        .collect();
    let (c, it, _) = nnls_at(prob, &taus)?;
    Ok((taus, c, it))
}

/// Non-negative least squares for E∞ and moduli at fixed τ (scaled units), by
/// Lawson–Hanson ([`nnls`]). Returns the coefficients, the active-set iterations
/// and the cost ½‖A·c − b‖² there (∞ where not finite).
pub fn nnls_at<K: Kernels>(prob: &mut Problem<K>, taus: &[f64]) -> Result<(Vec<f64>, usize, f64)> {
    let n = prob.len();
    let mut a = DMatrix::zeros(n, taus.len() + 1);
    let (input, terms) = a.as_mut_slice().split_at_mut(n);
    prob.input_column(input);
    prob.kernel_columns(taus, terms, None);
    let b = prob.targets();
    let sol = nnls(&a, &b, None).map_err(|e| {
        Error::settings(format!("the non-negative least-squares stage failed: {e}"))
    })?;
    prob.evaluations += 1;
    let cost = 0.5 * (&a * &sol.x - b).norm_squared();
    let cost = if cost.is_finite() {
        cost
    } else {
        f64::INFINITY
    };
    Ok((sol.x.iter().copied().collect(), sol.iterations, cost))
}
