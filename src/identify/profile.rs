//! Profile likelihoods (`--profiles NAME,...`): for a free constant held at each of
//! a grid of values around its estimate, the others re-fitted, the rise of χ² above
//! its minimum. Where Δχ² stays below 3.84 (the 95 % point of χ²₁) the traces cannot
//! exclude the value; the profile interval is where it crosses 3.84. Unlike the
//! linearised interval it follows a curved or one-sided valley, and a flat profile
//! shows a constant the traces do not pin down.

use super::problem::Problem;
use crate::fit::lm::{self, LmSettings};
use serde::Serialize;

/// Δχ² of the 95 % profile interval (χ²₁ quantile).
pub const DELTA_CHI2_95: f64 = 3.841_458_820_694_124;

/// Grid points per profile.
pub const POINTS: usize = 11;

/// One constant's profile.
#[derive(Debug, Clone, Serialize)]
pub struct Profile {
    /// Constant.
    pub name: String,
    /// SI unit.
    pub unit: String,
    /// Held values (SI).
    pub values: Vec<f64>,
    /// χ²(value) − χ²min (∞ where the others could not be re-fitted).
    pub delta_chi2: Vec<f64>,
    /// Where Δχ² crosses 3.84 on each side (None: not within the grid).
    pub interval: [Option<f64>; 2],
}

/// The profile of free constant `j` of `problem` about the optimum `x` with ½χ² =
/// `cost`, over ±3 linearised σ (`sigma_x` in search coordinates; ±2.3 in x, a
/// factor 10 for a log constant, without one).
pub fn profile(
    problem: &Problem,
    x: &[f64],
    cost: f64,
    j: usize,
    sigma_x: Option<f64>,
    settings: &LmSettings,
) -> Profile {
    let c = problem.free[j].clone();
    let half = sigma_x
        .map(|s| 3.0 * s)
        .filter(|h| h.is_finite() && *h > 0.0)
        .unwrap_or(2.3);
    let (lo, hi) = problem.x_bounds()[j];
    let grid: Vec<f64> = (0..POINTS)
        .map(|i| x[j] - half + 2.0 * half * i as f64 / (POINTS - 1) as f64)
        .map(|v| lm::project(v, (lo, hi)))
        .collect();
    let mut reduced = problem.clone();
    reduced.free.remove(j);
    let mut x0: Vec<f64> = x.to_vec();
    x0.remove(j);
    let bounds = reduced.x_bounds();
    let mut delta = Vec::with_capacity(POINTS);
    for &xv in &grid {
        let mut p = reduced.clone();
        p.theta[c.index] = c.space.theta(xv);
        let r = lm::minimize(&mut p, &x0, &bounds, settings);
        delta.push(if r.cost.is_finite() {
            (2.0 * (r.cost - cost)).max(0.0)
        } else {
            f64::INFINITY
        });
    }
    let values: Vec<f64> = grid.iter().map(|&v| c.space.theta(v)).collect();
    let mid = POINTS / 2;
    let cross = |range: Vec<usize>| {
        range.windows(2).find_map(|w| {
            let (a, b) = (w[0], w[1]);
            (delta[a] < DELTA_CHI2_95 && delta[b] >= DELTA_CHI2_95 && delta[b].is_finite()).then(
                || {
                    let f = (DELTA_CHI2_95 - delta[a]) / (delta[b] - delta[a]);
                    values[a] + f * (values[b] - values[a])
                },
            )
        })
    };
    let interval = [
        cross((0..=mid).rev().collect()),
        cross((mid..POINTS).collect()),
    ];
    Profile {
        name: c.name.clone(),
        unit: c.unit.to_string(),
        values,
        delta_chi2: delta,
        interval,
    }
}
