//! Static voltage–stretch curve and its peak (pull-in, electromechanical instability).
//!
//! Fully relaxed equilibrium (arms carry no stress) of the Lagrange equation:
//! Vol·P(λ) − F_load·L0 = ½V²·dC/dλ, so V(λ) = sqrt(2(Vol·P(λ) − F_load·L0)/(dC/dλ)).
//! For a free Neo-Hookean stack layer this is V = H·sqrt(μ/ε)·sqrt(λ − λ⁴), with the
//! peak at λ = 4^(-1/3), V = 0.687·H·sqrt(μ/ε) (Zhao & Suo 2007). Past the peak no
//! stable equilibrium exists.

use super::plant::Plant;
use serde::Serialize;

/// A point of the curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Point {
    /// Thickness stretch λ.
    pub stretch: f64,
    /// Voltage (V).
    #[serde(rename = "voltage_V")]
    pub voltage_v: f64,
}

/// The static curve and its peak.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticCurve {
    /// Points from the loaded rest state towards thinner layers.
    pub curve: Vec<Point>,
    /// The peak (pull-in), or None if V(λ) rises monotonically down to `stretch_min`.
    pub pull_in: Option<Point>,
    /// Smallest stretch examined.
    pub stretch_min: f64,
}

/// Voltage holding the plant in static equilibrium at λ (None where no real voltage does).
pub fn voltage_at(p: &Plant, lam: f64) -> Option<f64> {
    let (_, dc, _) = p.capacitance(lam);
    let v2 = 2.0 * (p.vol * p.stress(lam) - p.f_load * p.l0) / dc;
    (v2 >= 0.0 && v2.is_finite()).then(|| v2.sqrt())
}

/// The curve on `n` points from the rest stretch down to `stretch_min`, and the peak
/// refined by golden-section search to 1e-10 in λ.
pub fn static_curve(p: &Plant, n: usize, stretch_min: f64) -> StaticCurve {
    let lam0 = p.lam0;
    let n = n.max(3);
    let grid: Vec<f64> = (0..n)
        .map(|i| lam0 + (stretch_min - lam0) * i as f64 / (n - 1) as f64)
        .collect();
    let curve: Vec<Point> = grid
        .iter()
        .filter_map(|&l| {
            voltage_at(p, l).map(|v| Point {
                stretch: l,
                voltage_v: v,
            })
        })
        .collect();
    let imax = (0..curve.len()).max_by(|&a, &b| curve[a].voltage_v.total_cmp(&curve[b].voltage_v));
    let pull_in = imax.and_then(|i| {
        if i == 0 || i + 1 >= curve.len() {
            return None;
        }
        let f = |l: f64| voltage_at(p, l).unwrap_or(0.0);
        let (mut a, mut b) = (curve[i + 1].stretch, curve[i - 1].stretch);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let mut c = b - g * (b - a);
        let mut d = a + g * (b - a);
        while (b - a).abs() > 1e-10 {
            if f(c) > f(d) {
                b = d;
            } else {
                a = c;
            }
            c = b - g * (b - a);
            d = a + g * (b - a);
        }
        let l = 0.5 * (a + b);
        Some(Point {
            stretch: l,
            voltage_v: f(l),
        })
    });
    StaticCurve {
        curve,
        pull_in,
        stretch_min,
    }
}
