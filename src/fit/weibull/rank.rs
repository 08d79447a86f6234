//! Plotting positions (median-rank estimates of F at each breakdown, survivors by
//! Johnson's adjusted ranks) and rank regression on the Weibull plot.

use super::Positions;

/// The plotting position of every breakdown, in the order of `order` (specimen
/// indices sorted by field, breakdowns before survivors at a tie: a survivor at a
/// field has outlasted a breakdown at the same field).
///
/// Adjusted ranks (Johnson 1964, *The Statistical Treatment of Fatigue
/// Experiments*, Elsevier, §2; Abernethy, *The New Weibull Handbook*, 5th ed.,
/// 2006, §5.3): for the k-th specimen in order (k = 1..n), if it broke down,
/// O_k = O_prev + (n + 1 − O_prev)/(n − k + 2), with O_prev the adjusted rank of the
/// previous breakdown (0 at the start). Without survivors O_k = k. Each adjusted
/// rank gives F by the chosen position ([`Positions::position`]). Ties get
/// consecutive ranks, as every reference does.
///
/// Returns (specimen index, F) for each breakdown, in field order.
pub(crate) fn positions(
    order: &[usize],
    failed: &[bool],
    positions: Positions,
) -> Vec<(usize, f64)> {
    let n = order.len() as f64;
    let mut prev = 0.0;
    let mut out = Vec::with_capacity(order.len());
    for (k0, &i) in order.iter().enumerate() {
        if !failed[i] {
            continue;
        }
        let k = (k0 + 1) as f64;
        let rank = prev + (n + 1.0 - prev) / (n - k + 2.0);
        prev = rank;
        out.push((i, positions.position(rank, n)));
    }
    out
}

/// Rank-regression estimates in log units: (u = ln α, β) from the points
/// (x = ln E, y = ln(−ln(1 − F))) of the Weibull plot, on which the model is the
/// line y = β(x − u).
///
/// `on_x` false (rry): least squares of y on x, β = S_xy/S_xx, u = x̄ − ȳ/β.
/// `on_x` true (rrx): least squares of x on y, 1/β = S_xy/S_yy, u = x̄ − ȳ/β
/// (Abernethy 2006, §5.3.1: rank regression on X is the handbook's recommendation,
/// since the scatter is in the field, not in the rank). None when the fitted
/// slope is not positive and finite (all breakdowns at one field, or a plot
/// falling with the field).
pub(crate) fn regression(points: &[(f64, f64)], on_x: bool) -> Option<(f64, f64)> {
    let m = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x / m, b + y / m));
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for &(x, y) in points {
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
        sxy += (x - mx) * (y - my);
    }
    let beta = if on_x { syy / sxy } else { sxy / sxx };
    (beta.is_finite() && beta > 0.0).then(|| (mx - my / beta, beta))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without survivors the adjusted rank is the rank: Bernard's F = (i − 0.3)/(n + 0.4).
    #[test]
    fn complete_data_ranks_are_the_ranks() {
        let order = [0, 1, 2, 3];
        let p = positions(&order, &[true; 4], Positions::Bernard);
        for (k, &(_, f)) in p.iter().enumerate() {
            let want = (k as f64 + 1.0 - 0.3) / 4.4;
            assert!((f - want).abs() < 1e-15);
        }
    }

    /// Johnson's adjusted ranks on Abernethy's worked form: n = 5, order
    /// F S F F S: ranks 1, then 1 + (6 − 1)/(5 − 3 + 2) = 2.25, then
    /// 2.25 + (6 − 2.25)/(5 − 4 + 2) = 3.5 (exact fractions, so 1e-14).
    #[test]
    fn adjusted_ranks_with_survivors() {
        let order = [0, 1, 2, 3, 4];
        let failed = [true, false, true, true, false];
        let p = positions(&order, &failed, Positions::Bernard);
        let ranks: Vec<f64> = p.iter().map(|&(_, f)| f * 5.4 + 0.3).collect();
        for (r, want) in ranks.iter().zip([1.0, 2.25, 3.5]) {
            assert!((r - want).abs() < 1e-14, "{r} vs {want}");
        }
    }
}
