//! Static voltage–stretch curve and its peak (pull-in, electromechanical instability).
//!
//! Fully relaxed equilibrium (arms carry no stress) of the Lagrange equation:
//! Vol·P(λ) − F_load·L0 = ½V²·dC/dλ, so V(λ) = sqrt(2(Vol·P(λ) − F_load·L0)/(dC/dλ)).
//! For a free Neo-Hookean stack layer this is V = H·sqrt(μ/ε)·sqrt(λ − λ⁴), with the
//! peak at λ = 4^(-1/3), V = 0.687·H·sqrt(μ/ε) (Zhao & Suo 2007). Past the peak no
//! stable equilibrium exists.

use super::plant::Plant;
use crate::units::CountRange;
use serde::Serialize;

/// A point of the curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Point {
    /// Thickness stretch λ.
    pub stretch: f64,
    /// Voltage (V).
    #[serde(rename = "voltage_V")]
    pub voltage_v: f64,
    /// Capacitance C(λ) (F).
    #[serde(rename = "capacitance_F")]
    pub capacitance_f: f64,
}

/// What the peak search found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Search {
    /// A peak inside the examined range: the pull-in.
    PullIn,
    /// V(λ) still rises at the smallest stretch examined: no pull-in down to it.
    Rising,
    /// Too few points with a real voltage, or the largest voltage at the rest state:
    /// the search could not look, and claims nothing.
    Undetermined,
}

/// The static curve and its peak.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticCurve {
    /// Points from the loaded rest state (0 V) towards thinner layers.
    pub curve: Vec<Point>,
    /// What the search found.
    pub search: Search,
    /// The peak (pull-in), if `search` is `pull_in`.
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

/// Fewest curve points a search may use: the peak must be bracketed by grid points.
pub const MIN_POINTS: usize = 10;

/// The curve points a user may ask for: at least [`MIN_POINTS`], at most 10⁵ (a
/// step of 1e-5 in λ over the widest range, far finer than a chart shows; the peak
/// is refined by golden section whatever the grid).
pub const POINTS: CountRange = CountRange::new(
    MIN_POINTS,
    100_000,
    "points of the static curve; the peak is refined to 1e-10 in λ whatever the grid",
);

/// Where `f` is largest on [a, b], by golden-section search to within `tol` (or
/// to the resolution of the numbers there, whichever is coarser): exact for an `f`
/// with one maximum there (Kiefer 1953; the bracket shrinks by (√5 − 1)/2 per
/// evaluation).
pub fn golden_max(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64, tol: f64) -> f64 {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let tol = tol.max(4.0 * f64::EPSILON * a.abs().max(b.abs()));
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    while (b - a).abs() > tol {
        if f(c) > f(d) {
            b = d;
        } else {
            a = c;
        }
        c = b - g * (b - a);
        d = a + g * (b - a);
    }
    0.5 * (a + b)
}

/// The curve on `n` (at least [`MIN_POINTS`]) points from the rest stretch down to
/// `stretch_min`, and the peak refined by golden-section search to 1e-10 in λ. The
/// curve is unimodal for every shipped model; a grid maximum at the thinnest point
/// is a pull-in only if V already falls there (checked on a step of 1e-7 in λ),
/// otherwise V still rises and there is no pull-in down to `stretch_min`.
pub fn static_curve(p: &Plant, n: usize, stretch_min: f64) -> StaticCurve {
    let lam0 = p.lam0;
    let n = n.max(MIN_POINTS);
    let grid: Vec<f64> = (0..n)
        .map(|i| lam0 + (stretch_min - lam0) * i as f64 / (n - 1) as f64)
        .collect();
    // The rest state is the equilibrium at 0 V by definition (the formula's
    // rounding there can fall just below zero and drop it).
    let curve: Vec<Point> = grid
        .iter()
        .enumerate()
        .filter_map(|(i, &l)| {
            let v = if i == 0 { Some(0.0) } else { voltage_at(p, l) };
            v.map(|v| Point {
                stretch: l,
                voltage_v: v,
                capacitance_f: p.capacitance(l).0,
            })
        })
        .collect();
    let f = |l: f64| voltage_at(p, l).unwrap_or(0.0);
    let imax = (0..curve.len()).max_by(|&a, &b| curve[a].voltage_v.total_cmp(&curve[b].voltage_v));
    let last = curve.len().saturating_sub(1);
    let bracket = match imax {
        _ if curve.len() < 3 => None,
        Some(i) if i > 0 && i < last => Some((curve[i + 1].stretch, curve[i - 1].stretch)),
        Some(i) if i == last => {
            let l = curve[i].stretch;
            if f(l) >= f(l + 1e-7) {
                return StaticCurve {
                    curve,
                    search: Search::Rising,
                    pull_in: None,
                    stretch_min,
                };
            }
            Some((l, curve[i - 1].stretch))
        }
        _ => None,
    };
    let pull_in = bracket.map(|(a, b)| {
        let l = golden_max(&f, a, b, 1e-10);
        Point {
            stretch: l,
            voltage_v: f(l),
            capacitance_f: p.capacitance(l).0,
        }
    });
    StaticCurve {
        curve,
        search: match pull_in {
            Some(_) => Search::PullIn,
            None => Search::Undetermined,
        },
        pull_in,
        stretch_min,
    }
}

/// The point of the stable branch (from the rest state, where the field is zero,
/// down to the pull-in, or to the smallest stretch examined without one) where
/// the true field E = V(λ)/h(λ) (`Actuator::field`) reaches `eb`: there the static
/// voltage meets the breakdown voltage V_b(λ) = Eb·h(λ). The first curve point at or
/// above it, refined by bisection to 1e-12 in λ (the field rises along the branch:
/// V rises and h falls). None: the field stays below `eb` on the whole branch.
pub fn breakdown_point(p: &Plant, c: &StaticCurve, eb: f64) -> Option<Point> {
    let bottom = c.pull_in.map_or(c.stretch_min, |q| q.stretch);
    let field = |l: f64| voltage_at(p, l).map_or(0.0, |v| p.actuator.field(v, l));
    let lams: Vec<f64> = c
        .curve
        .iter()
        .map(|q| q.stretch)
        .filter(|&l| l > bottom)
        .chain([bottom])
        .collect();
    let i = lams.iter().position(|&l| field(l) >= eb)?;
    let l = match i {
        0 => lams[0],
        _ => {
            let (mut hi, mut lo) = (lams[i - 1], lams[i]);
            for _ in 0..60 {
                if hi - lo <= 1e-12 {
                    break;
                }
                let mid = 0.5 * (hi + lo);
                match field(mid) >= eb {
                    true => lo = mid,
                    false => hi = mid,
                }
            }
            lo
        }
    };
    Some(Point {
        stretch: l,
        voltage_v: voltage_at(p, l).unwrap_or(0.0),
        capacitance_f: p.capacitance(l).0,
    })
}
