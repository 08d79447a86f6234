//! Free time–temperature shifts of adjacent isotherms, each with its standard error,
//! accumulated to the reference temperature.
//!
//! Two isotherms, the colder at T₁ and the warmer at T₂, overlap once the colder is
//! moved by d = log10 a(T₁) − log10 a(T₂) decades along log ω (and, with a vertical
//! shift, by v = log10 b(T₁) − log10 b(T₂) along log E). d (and v) minimise the mean
//! squared mismatch in log–log space over the overlap, taken both ways: each point of
//! one isotherm against the other's curve, linearly interpolated in log ω, where it
//! reaches (a symmetric form: the interpolation's bias on a curved isotherm cancels
//! to first order between the two ways). The minimum is found on a grid of
//! [`GRID_STEP`] decades, then refined by golden-section search. The standard error
//! is the Gauss–Newton one at the minimum, s²(JᵀJ)⁻¹ with J the slopes of the
//! interpolated curves, s² the residual variance, and n counted as half the residuals
//! (each point enters once as a point and once in an interpolant: the two ways are
//! not independent); docs/dma.md and tests/dma.rs check it holds the truth ≈ 95 % of
//! the time at ± 1.96 σ.

use super::Isotherm;
use crate::error::{Error, Location, Result};
use nalgebra::DMatrix;

/// What the shifts are computed on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShiftOn {
    /// log E′ (default: the storage modulus is the best-determined, monotonic in ω).
    Storage,
    /// log E″.
    Loss,
    /// log tan δ (independent of a vertical shift).
    TanDelta,
    /// log E′ and log E″ together.
    Both,
}

impl ShiftOn {
    /// The name the command line and the JSON use.
    pub fn name(self) -> &'static str {
        match self {
            ShiftOn::Storage => "storage",
            ShiftOn::Loss => "loss",
            ShiftOn::TanDelta => "tan-delta",
            ShiftOn::Both => "both",
        }
    }
}

/// Grid step of the search for a pair's shift (decades).
pub const GRID_STEP: f64 = 0.01;

/// The fewest points of each isotherm that must lie in the other's range for a
/// shift: fewer leave the residual scatter (and so σ) undetermined.
pub const MIN_OVERLAP: usize = 3;

/// The shift of one adjacent pair of isotherms.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairShift {
    /// The colder isotherm's temperature (K).
    pub cold_k: f64,
    /// The warmer isotherm's temperature (K).
    pub warm_k: f64,
    /// d = log10 a(cold) − log10 a(warm) (decades; > 0 for a thermorheologically
    /// simple material).
    pub log_shift: f64,
    /// Its standard error (decades).
    pub std_error: f64,
    /// v = log10 b(cold) − log10 b(warm), with a vertical shift.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub log_vertical: Option<f64>,
    /// Its standard error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertical_std_error: Option<f64>,
    /// Points in the overlap at the minimum, both ways counted.
    pub overlap_points: usize,
    /// RMS of the log mismatch there (decades).
    pub rms_mismatch: f64,
    /// How many decades the shifted quantity changes across the overlap.
    pub overlap_span_decades: f64,
    /// The minimum lies where the overlap holds the fewest points allowed.
    pub at_edge: bool,
}

/// One isotherm's curves in log–log space: log ω, and per channel the log values
/// and whether a vertical shift moves them (moduli do, tan δ does not).
struct Curves {
    x: Vec<f64>,
    y: Vec<Vec<f64>>,
    /// PCHIP slopes of each channel at the points.
    m: Vec<Vec<f64>>,
    moves: Vec<bool>,
}

fn curves(iso: &Isotherm, on: ShiftOn) -> Curves {
    let l = |v: &[f64]| v.iter().map(|x| x.log10()).collect::<Vec<f64>>();
    let tan: Vec<f64> = iso
        .loss
        .iter()
        .zip(&iso.storage)
        .map(|(a, b)| (a / b).log10())
        .collect();
    let (y, moves) = match on {
        ShiftOn::Storage => (vec![l(&iso.storage)], vec![true]),
        ShiftOn::Loss => (vec![l(&iso.loss)], vec![true]),
        ShiftOn::TanDelta => (vec![tan], vec![false]),
        ShiftOn::Both => (vec![l(&iso.storage), l(&iso.loss)], vec![true, true]),
    };
    let x = iso.log_omega();
    let m = y.iter().map(|c| pchip_slopes(&x, c)).collect();
    Curves { x, y, m, moves }
}

/// The slopes of the monotone piecewise-cubic Hermite interpolant (PCHIP) of
/// (xs, ys) at its nodes: the weighted harmonic mean of the neighbouring secants, 0
/// where they differ in sign (Fritsch & Carlson, SIAM J. Numer. Anal. 17, 238, 1980;
/// the weights of Fritsch & Butland 1984), the secant at the ends.
fn pchip_slopes(xs: &[f64], ys: &[f64]) -> Vec<f64> {
    let n = xs.len();
    let h: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
    let d: Vec<f64> = (0..n - 1).map(|k| (ys[k + 1] - ys[k]) / h[k]).collect();
    (0..n)
        .map(|k| {
            if k == 0 {
                d[0]
            } else if k == n - 1 {
                d[n - 2]
            } else if d[k - 1] * d[k] <= 0.0 {
                0.0
            } else {
                let (w1, w2) = (2.0 * h[k] + h[k - 1], h[k] + 2.0 * h[k - 1]);
                (w1 + w2) / (w1 / d[k - 1] + w2 / d[k])
            }
        })
        .collect()
}

/// The PCHIP interpolant of (xs, ys) with node slopes `m` at x within [xs₀, xsₙ]:
/// value and slope. A log–log isotherm is curved between points 0.4 decades apart;
/// a straight line between them would put its curvature into the residual scatter
/// and so into σ.
fn interp(xs: &[f64], ys: &[f64], m: &[f64], x: f64) -> (f64, f64) {
    let k = xs.partition_point(|&v| v <= x).clamp(1, xs.len() - 1);
    let (x0, x1) = (xs[k - 1], xs[k]);
    let h = x1 - x0;
    let t = (x - x0) / h;
    let (y0, y1, m0, m1) = (ys[k - 1], ys[k], m[k - 1] * h, m[k] * h);
    let (t2, t3) = (t * t, t * t * t);
    let y = (2.0 * t3 - 3.0 * t2 + 1.0) * y0
        + (t3 - 2.0 * t2 + t) * m0
        + (-2.0 * t3 + 3.0 * t2) * y1
        + (t3 - t2) * m1;
    let dy = (6.0 * t2 - 6.0 * t) * y0
        + (3.0 * t2 - 4.0 * t + 1.0) * m0
        + (-6.0 * t2 + 6.0 * t) * y1
        + (3.0 * t2 - 2.0 * t) * m1;
    (y, dy / h)
}

/// The residuals at relative shift d (vertical v), with their derivatives by d and
/// by v, and the counts of points in the overlap each way.
struct Mismatch {
    r: Vec<f64>,
    dd: Vec<f64>,
    dv: Vec<f64>,
    counts: (usize, usize),
    span: f64,
}

fn mismatch(c: &Curves, w: &Curves, d: f64, v: f64) -> Mismatch {
    let mut m = Mismatch {
        r: Vec::new(),
        dd: Vec::new(),
        dv: Vec::new(),
        counts: (0, 0),
        span: 0.0,
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let inside = |xs: &[f64], x: f64| x >= xs[0] && x <= xs[xs.len() - 1];
    for (i, &x) in c.x.iter().enumerate() {
        if !inside(&w.x, x + d) {
            continue;
        }
        m.counts.0 += 1;
        for (ch, &moves) in c.moves.iter().enumerate() {
            let (wy, slope) = interp(&w.x, &w.y[ch], &w.m[ch], x + d);
            let s = if moves { -1.0 } else { 0.0 };
            m.r.push(c.y[ch][i] + s * v - wy);
            m.dd.push(-slope);
            m.dv.push(s);
            if ch == 0 {
                lo = lo.min(wy);
                hi = hi.max(wy);
            }
        }
    }
    for (i, &x) in w.x.iter().enumerate() {
        if !inside(&c.x, x - d) {
            continue;
        }
        m.counts.1 += 1;
        for (ch, &moves) in w.moves.iter().enumerate() {
            let (cy, slope) = interp(&c.x, &c.y[ch], &c.m[ch], x - d);
            let s = if moves { 1.0 } else { 0.0 };
            m.r.push(w.y[ch][i] - (cy - if moves { v } else { 0.0 }));
            m.dd.push(slope);
            m.dv.push(s);
            if ch == 0 {
                lo = lo.min(w.y[ch][i]);
                hi = hi.max(w.y[ch][i]);
            }
        }
    }
    m.span = (hi - lo).max(0.0);
    m
}

/// The vertical shift that minimises the mismatch at d (0 without one), and the
/// mean squared mismatch; None where the overlap is too small.
fn score(c: &Curves, w: &Curves, d: f64, vertical: bool) -> Option<(f64, f64)> {
    let m = mismatch(c, w, d, 0.0);
    if m.counts.0 < MIN_OVERLAP || m.counts.1 < MIN_OVERLAP {
        return None;
    }
    // r(v) = r(0) + dv·v: least squares in v
    let v = if vertical {
        let den: f64 = m.dv.iter().map(|s| s * s).sum();
        -m.r.iter().zip(&m.dv).map(|(r, s)| r * s).sum::<f64>() / den
    } else {
        0.0
    };
    let ms =
        m.r.iter()
            .zip(&m.dv)
            .map(|(r, s)| (r + s * v).powi(2))
            .sum::<f64>()
            / m.r.len() as f64;
    Some((v, ms))
}

/// The shift of the colder isotherm `cold` onto the warmer `warm`.
pub fn pair(cold: &Isotherm, warm: &Isotherm, on: ShiftOn, vertical: bool) -> Result<PairShift> {
    let (c, w) = (curves(cold, on), curves(warm, on));
    let (tc, tw) = (
        cold.temperature_k.unwrap_or(f64::NAN),
        warm.temperature_k.unwrap_or(f64::NAN),
    );
    let lo = w.x[0] - c.x[c.x.len() - 1];
    let hi = w.x[w.x.len() - 1] - c.x[0];
    let steps = ((hi - lo) / GRID_STEP).ceil() as usize;
    let grid: Vec<(f64, f64)> = (0..=steps)
        .filter_map(|k| {
            let d = lo + k as f64 * GRID_STEP;
            score(&c, &w, d, vertical).map(|(_, ms)| (d, ms))
        })
        .collect();
    let no_overlap = || {
        Error::input(
            Location::line(&warm.file, warm.line[0]),
            format!(
                "the isotherms at {} and {} cannot be overlapped by {MIN_OVERLAP} points each",
                super::temperature::celsius(tc),
                super::temperature::celsius(tw)
            ),
        )
        .with_hint("each isotherm needs at least 3 frequencies inside its neighbour's range once shifted: measure more frequencies per sweep, or temperatures closer together")
    };
    let best = grid
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .ok_or_else(no_overlap)?
        .0;
    let (first, last) = (grid[0].0, grid[grid.len() - 1].0);
    let f = |d: f64| score(&c, &w, d, vertical).map_or(f64::INFINITY, |s| s.1);
    let a = (grid[best].0 - GRID_STEP).max(first);
    let b = (grid[best].0 + GRID_STEP).min(last);
    let d = crate::sim::static_curve::golden_max(&|d| -f(d), a, b, 1e-6);
    let d = if f(d) <= grid[best].1 {
        d
    } else {
        grid[best].0
    };
    let (v, _) = score(&c, &w, d, vertical).ok_or_else(no_overlap)?;
    let m = mismatch(&c, &w, d, v);
    let n = m.r.len();
    let k = if vertical { 2 } else { 1 };
    let ss: f64 = m.r.iter().map(|r| r * r).sum();
    let s2 = ss / (n.saturating_sub(k).max(1)) as f64;
    // JᵀJ over half the residuals' count (see the module docs)
    let half = 0.5;
    let a11: f64 = half * m.dd.iter().map(|x| x * x).sum::<f64>();
    let (var_d, var_v) = if vertical {
        let a12: f64 = half * m.dd.iter().zip(&m.dv).map(|(a, b)| a * b).sum::<f64>();
        let a22: f64 = half * m.dv.iter().map(|x| x * x).sum::<f64>();
        let det = a11 * a22 - a12 * a12;
        (s2 * a22 / det, Some(s2 * a11 / det))
    } else {
        (s2 / a11, None)
    };
    let edge = (d - first).abs() < 2.0 * GRID_STEP || (last - d).abs() < 2.0 * GRID_STEP;
    Ok(PairShift {
        cold_k: tc,
        warm_k: tw,
        log_shift: d,
        std_error: var_d.sqrt(),
        log_vertical: vertical.then_some(v),
        vertical_std_error: var_v.map(f64::sqrt),
        overlap_points: m.counts.0 + m.counts.1,
        rms_mismatch: (ss / n as f64).sqrt(),
        overlap_span_decades: m.span,
        at_edge: edge,
    })
}

/// Shifts of every isotherm relative to the reference temperature.
#[derive(Debug, Clone, PartialEq)]
pub struct Accumulated {
    /// log10 aT per isotherm (coldest first).
    pub log_at: Vec<f64>,
    /// Standard errors (decades).
    pub std_error: Vec<f64>,
    /// The covariance of the log10 aT of every two isotherms (decades²): they share
    /// the pair shifts of their chains, so they are not independent.
    pub covariance: DMatrix<f64>,
    /// log10 bT per isotherm, with a vertical shift.
    pub log_bt: Option<Vec<f64>>,
    /// Standard errors of log10 bT.
    pub bt_std_error: Option<Vec<f64>>,
    /// The covariance of the log10 bT, with a vertical shift.
    pub bt_covariance: Option<DMatrix<f64>>,
    /// The reference temperature lies outside the isotherms' (extrapolated).
    pub extrapolated: bool,
}

/// How the shift (d, v) of a pair moves with each log value of its two isotherms,
/// by the implicit function theorem at the minimum: δθ = −(JᵀJ)⁻¹Jᵀ ∂r/∂y δy, J
/// the mismatch's derivatives by d (and v), ∂r/∂y by a central difference of the
/// mismatch with one log value moved (its PCHIP slopes recomputed). The colder
/// isotherm's values first, then the warmer's, channel by channel; each entry
/// (∂d/∂y, ∂v/∂y).
fn sensitivities(c: &Curves, w: &Curves, p: &PairShift) -> [Vec<[f64; 2]>; 2] {
    let (d, v) = (p.log_shift, p.log_vertical.unwrap_or(0.0));
    let vertical = p.log_vertical.is_some();
    let m = mismatch(c, w, d, v);
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (a11, a12, a22) = (dot(&m.dd, &m.dd), dot(&m.dd, &m.dv), dot(&m.dv, &m.dv));
    let det = a11 * a22 - a12 * a12;
    let solve = |g1: f64, g2: f64| match vertical {
        true => [-(a22 * g1 - a12 * g2) / det, -(a11 * g2 - a12 * g1) / det],
        false => [-g1 / a11, 0.0],
    };
    let h = 1e-6;
    let moved = |k: &Curves, ch: usize, j: usize, by: f64| {
        let mut y = k.y.clone();
        y[ch][j] += by;
        let mut s = k.m.clone();
        s[ch] = pchip_slopes(&k.x, &y[ch]);
        Curves {
            x: k.x.clone(),
            y,
            m: s,
            moves: k.moves.clone(),
        }
    };
    let of = |cold: bool| -> Vec<[f64; 2]> {
        let k = if cold { c } else { w };
        let mut out = Vec::new();
        for ch in 0..k.y.len() {
            for j in 0..k.x.len() {
                let (up, down) = (moved(k, ch, j, h), moved(k, ch, j, -h));
                let (ru, rd) = match cold {
                    true => (mismatch(&up, w, d, v).r, mismatch(&down, w, d, v).r),
                    false => (mismatch(c, &up, d, v).r, mismatch(c, &down, d, v).r),
                };
                let dr: Vec<f64> = ru
                    .iter()
                    .zip(&rd)
                    .map(|(a, b)| (a - b) / (2.0 * h))
                    .collect();
                out.push(solve(dot(&m.dd, &dr), dot(&m.dv, &dr)));
            }
        }
        out
    };
    [of(true), of(false)]
}

/// The correlation of the shifts of adjacent pairs i and i + 1, which share
/// isotherm i + 1 (the warmer of pair i, the colder of pair i + 1): noise that
/// moves it one way widens one pair's shift and narrows the next's, so their errors
/// are anticorrelated and largely cancel in the sum that refers an isotherm to Tr.
/// From the [`sensitivities`] s of each pair's shift to every log value y, taken
/// with one common variance σ_y²: ρᵢ = Σ_{y ∈ i+1} sᵢ(y)·sᵢ₊₁(y) /
/// √(Σ_y sᵢ² · Σ_y sᵢ₊₁²) (the first-order covariance of two functions of the same
/// data, σ_y² cancelling). Horizontal (d) and, with a vertical shift, vertical (v)
/// correlations; one fewer than the pairs.
pub fn adjacent_correlations(
    isotherms: &[Isotherm],
    pairs: &[PairShift],
    on: ShiftOn,
) -> (Vec<f64>, Vec<f64>) {
    let curves: Vec<Curves> = isotherms.iter().map(|i| curves(i, on)).collect();
    let s: Vec<[Vec<[f64; 2]>; 2]> = pairs
        .iter()
        .enumerate()
        .map(|(i, p)| sensitivities(&curves[i], &curves[i + 1], p))
        .collect();
    let rho = |q: usize| -> Vec<f64> {
        let sq = |v: &[[f64; 2]]| v.iter().map(|e| e[q] * e[q]).sum::<f64>();
        s.windows(2)
            .map(|w| {
                let cov: f64 = w[0][1].iter().zip(&w[1][0]).map(|(a, b)| a[q] * b[q]).sum();
                let var = (sq(&w[0][0]) + sq(&w[0][1])) * (sq(&w[1][0]) + sq(&w[1][1]));
                if var > 0.0 {
                    (cov / var.sqrt()).clamp(-1.0, 1.0)
                } else {
                    0.0
                }
            })
            .collect()
    };
    (rho(0), rho(1))
}

/// The chain of pair shifts `pairs` (between `temps[i]` and `temps[i + 1]`) summed to
/// each isotherm and referred to `tr` (K): linearly interpolated in T between the two
/// isotherms around it (extrapolated from the nearest two outside). The shifts are
/// L = W·d, W the weight of each pair in each isotherm's sum, so their covariance is
/// W Σ Wᵀ, Σ the pairs' covariance: σᵢ² on the diagonal, ρᵢσᵢσᵢ₊₁ between adjacent
/// pairs (`rho`, from [`adjacent_correlations`]: `.0` horizontal, `.1` vertical), 0
/// beyond (pairs two apart share no isotherm). Taken as independent (ρ = 0), the
/// shifts far from Tr came out 2–3× too uncertain (tests/dma.rs).
pub fn accumulate(
    temps: &[f64],
    pairs: &[PairShift],
    rho: &(Vec<f64>, Vec<f64>),
    tr: f64,
) -> Accumulated {
    let n = temps.len();
    let m = temps.partition_point(|&t| t <= tr).clamp(1, n - 1) - 1;
    let w = (tr - temps[m]) / (temps[m + 1] - temps[m]);
    // weight of pair i in L_j − L(Tr), with L_j = Σ_{i ≥ j} d_i
    let weights = DMatrix::from_fn(n, pairs.len(), |j, i| {
        let e = |k: usize| if i >= k { 1.0 } else { 0.0 };
        e(j) - (1.0 - w) * e(m) - w * e(m + 1)
    });
    let combine = |val: &dyn Fn(&PairShift) -> f64, sd: &dyn Fn(&PairShift) -> f64, rho: &[f64]| {
        let d = DMatrix::from_iterator(pairs.len(), 1, pairs.iter().map(val));
        let p = pairs.len();
        let sigma = DMatrix::from_fn(p, p, |a, b| match a.abs_diff(b) {
            0 => sd(&pairs[a]).powi(2),
            1 => rho[a.min(b)] * sd(&pairs[a]) * sd(&pairs[b]),
            _ => 0.0,
        });
        let cov = &weights * sigma * weights.transpose();
        let vals = (&weights * d).iter().copied().collect();
        let ses = (0..n).map(|j| cov[(j, j)].max(0.0).sqrt()).collect();
        (vals, ses, cov)
    };
    let (log_at, std_error, covariance) = combine(&|p| p.log_shift, &|p| p.std_error, &rho.0);
    let vertical = pairs.first().is_some_and(|p| p.log_vertical.is_some());
    let (log_bt, bt_std_error, bt_covariance) = if vertical {
        let (a, b, c) = combine(
            &|p| p.log_vertical.unwrap_or(0.0),
            &|p| p.vertical_std_error.unwrap_or(0.0),
            &rho.1,
        );
        (Some(a), Some(b), Some(c))
    } else {
        (None, None, None)
    };
    Accumulated {
        log_at,
        std_error,
        covariance,
        log_bt,
        bt_std_error,
        bt_covariance,
        extrapolated: tr < temps[0] || tr > temps[n - 1],
    }
}
