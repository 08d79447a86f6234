//! A measured voltage as one smooth input with real corners.
//!
//! A logged drive voltage is noisy and has thousands of samples; a piecewise-linear
//! input through every sample would restart the integrator at each of them (every
//! sample is a kink, and scenes cap the kinks, `sim::budget::MAX_KINKS`). Instead,
//! [`Measured::fit`] finds the real corners (steps, ramp ends, triangle peaks) with a
//! noise-aware test and represents the signal between two corners by one C¹ cubic
//! Hermite spline fitted by least squares, so that [`Measured::corners`] lists only
//! the corners and [`Measured::eval`] gives the value and its time derivative by a
//! binary search (O(log n), no allocation).
//!
//! 1. **Noise.** σ̂ = 1.4826·median|rᵢ|/√(1 + wᵢ² + (1 − wᵢ)²), with rᵢ the distance
//!    of sample i from the chord of its neighbours and wᵢ = (tᵢ − tᵢ₋₁)/(tᵢ₊₁ − tᵢ₋₁)
//!    (the normalised second difference of white noise has standard deviation σ;
//!    1.4826·MAD is its robust estimate, unaffected by the few samples at corners).
//!    The test uses σ = max(σ̂, [`NOISE_FLOOR`] × range), so a noiseless record is
//!    not split at the rounding of its digits.
//! 2. **Steps.** Interval i departs from the local slope (median of the
//!    [`STEP_NEIGHBOURS`] neighbouring intervals on each side) when its increment
//!    differs from it by more than [`STEP_SIGMAS`]·√2·σ; consecutive departures of
//!    one sign form a rise, less its first and last intervals that go on as the
//!    slope before (after) it does (so a slope corner, whose neighbours straddle
//!    two slopes, is no rise). Where one or two intervals of a rise change by more
//!    than [`STEP_DOMINANCE`] times the intervals beside them, the sampling did not
//!    resolve that jump: it is a step, a pair of corners at its first and last
//!    sample joined by a straight line ([`Measured::steps`]). A rise resolved over
//!    more intervals (a supply's first-order rise sampled at a few points per time
//!    constant) is a fast but smooth change: its first and last samples are
//!    corners, kept only if they pay (below), and the pieces follow its shape.
//! 3. **Corners.** At each remaining sample c, a cubic plus a hinge (t − t_c)₊ is
//!    fitted over up to w samples on each side, w in [`WINDOWS`] (never across a
//!    corner found already); the hinge coefficient's t-ratio against σ measures a
//!    slope jump that no smooth signal explains. A window whose residual sum of
//!    squares exceeds its noise expectation (dof + 4·√(2·dof))·σ² holds more than a
//!    cubic and a corner and is not used. The largest ratio above [`CORNER_SIGMAS`] becomes a
//!    corner, located by [`refine`] within [`REFINE_SAMPLES`] sample intervals, and
//!    the test is repeated on the split segments until no ratio exceeds the
//!    threshold (greedy, so two close corners are found as two).
//!    A corner stays only where splitting its segment there lowers the BIC of
//!    the pieces (step 4) on the two sides, by more than [`CORNER_RSS`]·σ²
//!    in RSS, against one piece over both (also with the two sides' knots): a smooth
//!    peak that a hinge imitates over a long window is one spline with a few more
//!    knots. The least useful corner is removed until every one pays. Each
//!    corner that stays is located again between its final neighbours: the two
//!    straight lines (or parabolas, where the signal curves) on either side that
//!    meet at the corner time of least squares, over the longest windows the
//!    noise test admits (the corner time's standard error is about
//!    σ/(Δs·√w) for a slope jump Δs per interval and w samples a side: long
//!    windows place a weak corner within a sample interval, where a cubic and a
//!    hinge over a short one could not).
//! 4. **Pieces.** Between two corners, a cubic Hermite spline (C¹) with knots at
//!    sample quantiles is fitted by least squares; its number of intervals K (1, 2,
//!    …, growing by an eighth) minimises BIC with the known σ, RSS/σ² + 2(K + 1)·ln m (m samples). At a
//!    corner the two sides' values are averaged (the input is continuous; only its
//!    slope jumps).
//!
//! Before the first sample and after the last the value is held.

use std::cell::Cell;
use std::time::Instant;

mod spline;
use spline::Piece;

/// Noise floor as a fraction of the record's range (0.1 %): below any real drive's
/// noise; it keeps a noiseless synthetic record from being split at its rounding.
pub const NOISE_FLOOR: f64 = 1e-3;
/// Threshold of the hinge t-ratio for a corner (a 6σ slope jump: the chance that
/// noise alone reaches it anywhere in a 10⁴-sample record is below 10⁻⁵).
pub const CORNER_SIGMAS: f64 = 6.0;
/// The RSS (in σ²) a corner must save against one spline over both its sides
/// ([`corner_gain`]): the split has five unknowns more (a second value and the
/// first four derivatives at the corner; the pieces are quintics, C⁴ between
/// corners), so the saving of noise alone is χ² with 5 degrees of freedom, and
/// this is its quantile at the tail of a [`CORNER_SIGMAS`] normal deviation
/// (2·Φ(−6) = 1.97·10⁻⁹): the hinge test's false-alarm rate.
pub const CORNER_RSS: f64 = 49.25;
/// Threshold of a one-interval jump for a step, in standard deviations of a
/// difference of two noisy samples.
pub const STEP_SIGMAS: f64 = 8.0;
/// Samples on each side of a candidate corner in its test windows: a slope jump
/// shows best over a long window, a smooth signal fits a cubic only over a short
/// one; a window whose residual exceeds the noise is not used.
pub const WINDOWS: [usize; 4] = [20, 40, 80, 160];
/// Intervals on each side whose median slope is the local slope of the step test.
pub const STEP_NEIGHBOURS: usize = 6;
/// A rise is a step (a jump the sampling did not resolve) where one or two of its
/// intervals change by more than this multiple of the intervals beside them: a
/// first-order rise sampled at 1.4 time constants or coarser. A rise resolved over
/// more intervals is a fast but smooth change between two corners.
pub const STEP_DOMINANCE: f64 = 2.0;
/// Fewest samples on each side of a candidate corner (the hinge needs both sides).
const MIN_SIDE: usize = 4;

/// The work of a [`Measured::fit_with`] and the deadline it must end by. The unit
/// of work is a sample visited by a least-squares fit (a hinge window of the
/// corner test, a spline of the pieces or of a corner's worth): the fit is
/// linear in the record's length when this count is. Once the deadline has
/// passed every further fit is skipped and the fit ends in an error that says so
/// (never a partial signal taken as whole).
#[derive(Debug, Default)]
pub struct Work {
    deadline: Option<Instant>,
    samples: Cell<u64>,
    exceeded: Cell<bool>,
}

impl Work {
    /// No work done yet, to end by `deadline` (None: no limit).
    pub fn until(deadline: Option<Instant>) -> Work {
        Work {
            deadline,
            ..Work::default()
        }
    }

    /// Samples visited by the fits so far.
    pub fn samples(&self) -> u64 {
        self.samples.get()
    }

    /// Count a fit over `n` samples: false (the fit is to be skipped) once the
    /// deadline has passed.
    fn spend(&self, n: usize) -> bool {
        if self.exceeded.get() || self.deadline.is_some_and(|d| Instant::now() > d) {
            self.exceeded.set(true);
            return false;
        }
        self.samples.set(self.samples.get() + n as u64);
        true
    }
}

/// A measured signal: smooth quintic pieces between corners.
#[derive(Debug, Clone, PartialEq)]
pub struct Measured {
    /// Knot times (s), increasing; piece i spans `knots[i]..knots[i + 1]`.
    knots: Vec<f64>,
    /// Per piece: its polynomial in u = (t − a)/h over [a, a + h] ([`spline::Piece`]).
    pieces: Vec<Piece>,
    /// Corner times (s), increasing, including the first and last sample.
    corners: Vec<f64>,
    /// Steps (s): start and end of each jump the sampling did not resolve.
    steps: Vec<(f64, f64)>,
    /// The noise σ used by the tests (V).
    noise: f64,
    /// Where to look for a time's piece ([`lookup_table`]).
    lookup: Lookup,
}

/// An index over the knots for [`Measured::eval`], which the integrator calls at
/// every right-hand side (a binary search over the 3500 knots of a rig trace's
/// input was 9.6 % of an identification's time): the knot span [t₀, t_end] cut
/// into as many equal buckets as there are knots, and for each bucket edge
/// e_b = t₀ + b·w the number of knots ≤ e_b. A time in bucket b has its piece
/// between `first[b]` and `first[b + 1]`, a search over about one knot.
#[derive(Debug, Clone, PartialEq)]
struct Lookup {
    /// t₀.
    start: f64,
    /// 1/w (0 for a single knot).
    inverse_width: f64,
    /// Knots ≤ e_b, for b = 0 … buckets.
    first: Vec<usize>,
}

/// The [`Lookup`] of increasing `knots`.
fn lookup_table(knots: &[f64]) -> Lookup {
    let n = knots.len();
    let (start, end) = (knots[0], knots[n - 1]);
    let width = (end - start) / n as f64;
    Lookup {
        start,
        inverse_width: if width > 0.0 { 1.0 / width } else { 0.0 },
        first: (0..=n)
            .map(|b| knots.partition_point(|&x| x <= start + b as f64 * width))
            .collect(),
    }
}

/// A segment between two corners, in sample indices (inclusive) and times.
#[derive(Debug, Clone, Copy)]
struct Segment {
    t0: f64,
    t1: f64,
    /// A step: a straight line between its neighbours' end values.
    step: bool,
}

impl Measured {
    /// Fit samples `(times, values)`: times finite and strictly increasing, values
    /// finite, at least two. The error says what is wrong (the caller locates it).
    pub fn fit(times: &[f64], values: &[f64]) -> Result<Measured, String> {
        Measured::fit_with(times, values, &Work::default())
    }

    /// [`Measured::fit`] counting its `work` and ending by its deadline: past it,
    /// an error says how far the fit came.
    pub fn fit_with(times: &[f64], values: &[f64], work: &Work) -> Result<Measured, String> {
        let n = times.len();
        if n < 2 || values.len() != n {
            return Err(format!(
                "a measured signal needs at least 2 samples and one value per time ({n} times, {} values)",
                values.len()
            ));
        }
        if let Some(i) = (0..n).find(|&i| !times[i].is_finite() || !values[i].is_finite()) {
            return Err(format!("sample {}: time and value must be finite", i + 1));
        }
        if let Some(i) = (1..n).find(|&i| times[i] <= times[i - 1]) {
            return Err(format!(
                "sample {}: time {} s is not after the previous {} s",
                i + 1,
                times[i],
                times[i - 1]
            ));
        }
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let noise = noise_sigma(times, values).max(NOISE_FLOOR * (hi - lo));
        let mut segs = if noise > 0.0 {
            find_corners(times, values, noise, work)
        } else {
            // a constant record: one piece
            vec![(0, n - 1, times[0], false)]
        };
        segs.sort_by(|a, b| a.2.total_cmp(&b.2));
        let m = build(times, values, noise, &segs, work);
        if work.exceeded.get() {
            return Err(format!(
                "the time budget ran out while the measured signal ({n} samples) was fitted, \
                 after {} samples of least-squares work",
                work.samples()
            ));
        }
        Ok(m)
    }

    /// Value and time derivative at `t` (right-continuous at corners; held outside
    /// the samples).
    #[inline]
    pub fn eval(&self, t: f64) -> (f64, f64) {
        let k = &self.knots;
        if t < k[0] {
            return (self.pieces[0][0], 0.0);
        }
        let i = self.piece_end(t);
        if i >= k.len() {
            return (spline::end(&self.pieces[self.pieces.len() - 1]), 0.0);
        }
        let (a, h) = (k[i - 1], k[i] - k[i - 1]);
        spline::eval(&self.pieces[i - 1], (t - a) / h, h)
    }

    /// The number of knots ≤ t (t ≥ the first knot): `knots.partition_point(|x| x
    /// ≤ t)`, searched between the [`Lookup`]'s bounds of t's bucket, and over every
    /// knot when rounding of the bucket edges put t outside them (the result is
    /// the same either way: the bounds are checked, not trusted).
    #[inline]
    fn piece_end(&self, t: f64) -> usize {
        let (k, l) = (&self.knots, &self.lookup);
        let last = l.first.len() - 2;
        let b = (((t - l.start) * l.inverse_width) as usize).min(last);
        let (a, c) = (l.first[b], l.first[b + 1]);
        let inside = (a == 0 || k[a - 1] <= t) && (c == k.len() || k[c] > t);
        match inside {
            true => a + k[a..c].partition_point(|&x| x <= t),
            false => k.partition_point(|&x| x <= t),
        }
    }

    /// Corner times (s): where the slope jumps, the first and last sample included
    /// (the held value outside has zero slope).
    pub fn corners(&self) -> &[f64] {
        &self.corners
    }

    /// Start and end (s) of each step: a jump within one or two sample intervals,
    /// whose shape between the samples was not recorded (a straight line here).
    pub fn steps(&self) -> &[(f64, f64)] {
        &self.steps
    }

    /// The noise standard deviation the corner test used (units of the values).
    pub fn noise(&self) -> f64 {
        self.noise
    }

    /// First and last sample time (s).
    pub fn span(&self) -> (f64, f64) {
        (self.knots[0], self.knots[self.knots.len() - 1])
    }

    /// Shortest interval between two corners (s).
    pub fn shortest_piece(&self) -> f64 {
        self.corners
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min)
    }

    /// Values at the knots (for range checks).
    pub fn knot_values(&self) -> impl Iterator<Item = f64> + '_ {
        self.pieces.iter().flat_map(|p| [p[0], spline::end(p)])
    }
}

/// Robust noise σ from normalised second differences (module doc, step 1).
fn noise_sigma(t: &[f64], v: &[f64]) -> f64 {
    if t.len() < 3 {
        return 0.0;
    }
    let mut r: Vec<f64> = (1..t.len() - 1)
        .map(|i| {
            let w = (t[i] - t[i - 1]) / (t[i + 1] - t[i - 1]);
            let chord = (1.0 - w) * v[i - 1] + w * v[i + 1];
            (v[i] - chord).abs() / (1.0 + w * w + (1.0 - w) * (1.0 - w)).sqrt()
        })
        .collect();
    1.4826 * median(&mut r)
}

fn median(x: &mut [f64]) -> f64 {
    x.sort_by(f64::total_cmp);
    let n = x.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => x[n / 2],
        _ => 0.5 * (x[n / 2 - 1] + x[n / 2]),
    }
}

/// Rises found by the step test (step 2), as sample indices (first, last).
#[derive(Debug, Default)]
struct Rises {
    /// Unresolved jumps (one or two intervals): a pair of corners each.
    steps: Vec<(usize, usize)>,
    /// Fast but resolved changes: their ends are corner candidates.
    resolved: Vec<(usize, usize)>,
}

/// The rises of the step test (step 2): runs of intervals that jump against the
/// local slope, each split into a step (one or two intervals that dominate their
/// neighbours) or kept as a resolved change.
fn find_rises(t: &[f64], v: &[f64], sigma: f64) -> Rises {
    let n = t.len();
    let slope = |j: usize| (v[j + 1] - v[j]) / (t[j + 1] - t[j]);
    // each interval's departure from the local slope
    let mut buf = Vec::with_capacity(2 * STEP_NEIGHBOURS);
    let e: Vec<f64> = (0..n - 1)
        .map(|i| {
            buf.clear();
            let lo = i.saturating_sub(STEP_NEIGHBOURS);
            let hi = (i + STEP_NEIGHBOURS).min(n - 2);
            buf.extend((lo..=hi).filter(|&j| j != i).map(slope));
            let local = if buf.is_empty() {
                0.0
            } else {
                median(&mut buf)
            };
            (v[i + 1] - v[i]) - local * (t[i + 1] - t[i])
        })
        .collect();
    let threshold = STEP_SIGMAS * std::f64::consts::SQRT_2 * sigma;
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for i in 0..n - 1 {
        if e[i].abs() <= threshold {
            continue;
        }
        match runs.last_mut() {
            Some(r) if r.1 + 1 == i && e[i].signum() == e[r.1].signum() => r.1 = i,
            _ => runs.push((i, i)),
        }
    }
    let size = |i: Option<usize>| i.and_then(|i| e.get(i)).map_or(0.0, |x| x.abs());
    // the median slope of the intervals in lo..hi (clipped), if any
    let side = |lo: usize, hi: usize, buf: &mut Vec<f64>| {
        buf.clear();
        buf.extend((lo..hi.min(n - 1)).map(slope));
        (!buf.is_empty()).then(|| median(buf))
    };
    // an interval that goes on as the slope before the run (or after it) does is
    // no part of the rise: the median of both sides makes a run at a slope corner
    let agrees = |i: usize, s: Option<f64>| {
        s.is_some_and(|s| ((v[i + 1] - v[i]) - s * (t[i + 1] - t[i])).abs() <= threshold)
    };
    let mut rises = Rises::default();
    for (a, b) in runs {
        let before = side(a.saturating_sub(STEP_NEIGHBOURS), a, &mut buf);
        let after = side(b + 1, b + 1 + STEP_NEIGHBOURS, &mut buf);
        let (mut a, mut b) = (a, b);
        while a <= b && agrees(a, before) {
            a += 1;
        }
        while b > a && agrees(b, after) {
            b -= 1;
        }
        if a > b || (a == b && agrees(a, after)) {
            continue;
        }
        // the block of one or two intervals that dominates the intervals beside it
        let block = (a..=b)
            .flat_map(|k| [(k, k), (k, k + 1)])
            .filter(|&(_, m)| m <= b)
            .map(|(k, m)| {
                let inside = size(Some(k)).min(size(Some(m)));
                let beside = size(k.checked_sub(1)).max(size(Some(m + 1)));
                (k, m, inside, beside)
            })
            .filter(|x| x.2 > STEP_DOMINANCE * x.3)
            .max_by(|x, y| x.2.total_cmp(&y.2));
        match block {
            Some((k, m, ..)) => rises.steps.push((k, m + 1)),
            None => rises.resolved.push((a, b + 1)),
        }
    }
    rises
}

/// Least squares on a cubic plus a hinge at t_c over samples `lo..=hi` (x scaled
/// about t_c): the hinge coefficient's t-ratio against `sigma` and the RSS.
fn hinge_fit(t: &[f64], v: &[f64], lo: usize, hi: usize, tc: f64, sigma: f64) -> (f64, f64) {
    let h = (t[hi] - tc).abs().max((tc - t[lo]).abs());
    let mut a = [[0.0; 5]; 5];
    let mut b = [0.0; 5];
    let mut yy = 0.0;
    for i in lo..=hi {
        let x = (t[i] - tc) / h;
        let f = [1.0, x, x * x, x * x * x, x.max(0.0)];
        for r in 0..5 {
            for c in 0..5 {
                a[r][c] += f[r] * f[c];
            }
            b[r] += f[r] * v[i];
        }
        yy += v[i] * v[i];
    }
    let Some(l) = cholesky5(&a) else {
        return (0.0, f64::INFINITY);
    };
    let beta = solve5(&l, &b);
    let rss = (yy - (0..5).map(|r| beta[r] * b[r]).sum::<f64>()).max(0.0);
    // (AᵀA)⁻¹₄₄ = ‖L⁻¹e₄‖² … with A = L·Lᵀ it is 1/L₄₄²
    let var44 = 1.0 / (l[4][4] * l[4][4]);
    (beta[4] / (sigma * var44.sqrt()), rss)
}

fn cholesky5(a: &[[f64; 5]; 5]) -> Option<[[f64; 5]; 5]> {
    let mut l = [[0.0; 5]; 5];
    let scale = (0..5).map(|i| a[i][i]).fold(0.0, f64::max);
    for i in 0..5 {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if s <= 1e-13 * scale {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(l)
}

fn solve5(l: &[[f64; 5]; 5], b: &[f64; 5]) -> [f64; 5] {
    let mut y = [0.0; 5];
    for i in 0..5 {
        y[i] = (b[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    let mut x = [0.0; 5];
    for i in (0..5).rev() {
        x[i] = (y[i] - (i + 1..5).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
    }
    x
}

/// The segments between corners (steps 2 and 3): (first sample, last sample, start
/// time, is a step), unsorted.
fn find_corners(t: &[f64], v: &[f64], sigma: f64, work: &Work) -> Vec<(usize, usize, f64, bool)> {
    let n = t.len();
    // boundaries: sample index and corner time; a step's two corners are samples
    let mut bounds: Vec<(usize, f64)> = vec![(0, t[0]), (n - 1, t[n - 1])];
    let rises = find_rises(t, v, sigma);
    let steps: Vec<usize> = rises.steps.iter().map(|s| s.0).collect();
    let step_ends: Vec<usize> = rises.steps.iter().map(|s| s.1).collect();
    for &(a, b) in rises.steps.iter().chain(&rises.resolved) {
        bounds.push((a, t[a]));
        bounds.push((b, t[b]));
    }
    bounds.sort_by_key(|b| b.0);
    bounds.dedup_by_key(|b| b.0);
    // the rises are found in the order of their samples: both lists are sorted
    let is_step = |b: usize| steps.binary_search(&b).is_ok();
    let is_step_end = |b: usize| step_ends.binary_search(&b).is_ok();
    // the largest hinge t-ratio at c over the window scales, and its window
    let ratio = |bounds: &[(usize, f64)], c: usize| -> (f64, usize, usize) {
        let none = (0.0, 0, 0);
        let k = bounds.partition_point(|b| b.0 <= c);
        if k == 0 || k >= bounds.len() || bounds[k - 1].0 == c || is_step(bounds[k - 1].0) {
            return none;
        }
        let (lo, hi) = (bounds[k - 1].0, bounds[k].0);
        let mut best = none;
        for w in WINDOWS {
            let (a, b) = (lo.max(c.saturating_sub(w)), hi.min(c + w));
            if c - a < MIN_SIDE || b - c < MIN_SIDE || !work.spend(b - a + 1) {
                continue;
            }
            let (r, rss) = hinge_fit(t, v, a, b, t[c], sigma);
            // a window whose residual exceeds the noise holds more than a cubic and
            // a corner: its ratio means nothing
            let dof = (b - a + 1 - 5) as f64;
            if rss > sigma * sigma * (dof + 4.0 * (2.0 * dof).sqrt()) {
                continue;
            }
            if r.abs() > best.0 {
                best = (r.abs(), a, b);
            }
        }
        best
    };
    let mut r: Vec<(f64, usize, usize)> = (0..n).map(|c| ratio(&bounds, c)).collect();
    let reach = WINDOWS[WINDOWS.len() - 1];
    // The largest ratio first, the last sample of equal ones (the order of a scan
    // of `r` for its maximum, kept in a heap so that each corner costs log n, not
    // n). A ratio is ≥ 0 (or NaN, largest as in `total_cmp`), so its bits order as
    // it does; an entry whose ratio has since changed is stale and skipped.
    let threshold = CORNER_SIGMAS.to_bits();
    let mut heap: std::collections::BinaryHeap<(u64, usize)> = r
        .iter()
        .enumerate()
        .map(|(c, x)| (x.0.to_bits(), c))
        .filter(|e| e.0 > threshold)
        .collect();
    while let Some((key, c)) = heap.pop() {
        let (best, a, b) = r[c];
        if best.to_bits() != key {
            continue;
        }
        let k = bounds.partition_point(|x| x.0 <= c);
        let between = (bounds[k - 1].1, bounds[k].1);
        let Some(tc) = [refine(t, v, a, b, c, sigma), t[c]]
            .into_iter()
            .find(|&x| x > between.0 && x < between.1)
        else {
            // no time for it between its neighbours' (refined) times
            r[c].0 = 0.0;
            continue;
        };
        bounds.insert(k, (c, tc));
        for j in c.saturating_sub(reach)..=(c + reach).min(n - 1) {
            r[j] = ratio(&bounds, j);
            if r[j].0.to_bits() > threshold {
                heap.push((r[j].0.to_bits(), j));
            }
        }
    }
    // a hinge corner stays only where splitting its segment lowers the BIC of the
    // smooth fits: a smooth peak that a hinge imitates over a long window is one
    // spline with a few more knots. Each corner's gain depends on its neighbours
    // only: after a removal the two beside it are computed again, the others kept.
    let gain = |bounds: &[(usize, f64)], i: usize| -> Option<f64> {
        if i == 0 || i + 1 >= bounds.len() {
            return None;
        }
        let (p, c, q) = (bounds[i - 1], bounds[i], bounds[i + 1]);
        if is_step(c.0) || is_step(p.0) || is_step_end(c.0) {
            return None;
        }
        // its neighbours' segments, each side clipped to GAIN_REACH samples
        let (lo, hi) = (
            p.0.max(c.0.saturating_sub(GAIN_REACH)),
            q.0.min(c.0 + GAIN_REACH),
        );
        let a = if lo == p.0 { p.1 } else { t[lo] };
        let b = if hi == q.0 { q.1 } else { t[hi] };
        let m = (hi - lo + 1) as f64;
        Some(corner_gain(t, v, (a, c.1, b), sigma, m, work))
    };
    let mut gains: Vec<Option<f64>> = (0..bounds.len()).map(|i| gain(&bounds, i)).collect();
    loop {
        let mut worst: Option<(usize, f64)> = None;
        for (i, g) in gains.iter().enumerate() {
            if let Some(g) = *g {
                if worst.is_none_or(|w| g < w.1) {
                    worst = Some((i, g));
                }
            }
        }
        match worst {
            Some((i, g)) if g < 0.0 => {
                bounds.remove(i);
                gains.remove(i);
                for j in [i - 1, i] {
                    gains[j] = gain(&bounds, j);
                }
            }
            _ => break,
        }
    }
    // every slope corner located on the final segments: its sides reach to the
    // neighbouring corners (less a margin for their own uncertainty)
    for i in 1..bounds.len().saturating_sub(1) {
        let c = bounds[i].0;
        if is_step(c) || is_step_end(c) {
            continue;
        }
        let (lo, hi) = (
            (bounds[i - 1].0 + NEIGHBOUR_MARGIN).min(c),
            bounds[i + 1].0.saturating_sub(NEIGHBOUR_MARGIN).max(c),
        );
        let tc = refine(t, v, lo, hi, c, sigma);
        if tc > bounds[i - 1].1 && tc < bounds[i + 1].1 {
            bounds[i].1 = tc;
        }
    }
    bounds
        .windows(2)
        .map(|w| (w[0].0, w[1].0, w[0].1, is_step(w[0].0)))
        .collect()
}

/// Samples on each side of a corner over which its BIC gain ([`corner_gain`]) is
/// measured, at most (its neighbouring corners' segments, clipped): a corner is a
/// local feature, and without the clip every corner removed makes its
/// neighbours' segments longer, so that removing most of a long record's
/// candidates refitted splines over ever longer spans (work of the record's
/// length times the candidates' count). A record of at most 4097 samples is never
/// clipped (every one shipped: datasets/identify, ≤ 2501 rows), so that those are
/// fitted as before.
const GAIN_REACH: usize = 4096;

/// Samples kept clear of a neighbouring corner when a corner's sides are fitted.
const NEIGHBOUR_MARGIN: usize = 2;

/// The corner time of least squares near sample c (step 3, module doc): a smooth
/// polynomial of degree d (1, 2 or 3) plus a hinge b·(t − t_h)₊, over up to w
/// samples on each side (w in [`REFINE_WINDOWS`], inside `lo..=hi`); for d = 1 the
/// two straight lines that meet at t_h. The corner time t_h minimises the RSS
/// within [`REFINE_SAMPLES`] sample intervals of c. Of the (d, w) whose RSS is
/// consistent with the noise, the one that places t_h best ([`join_spread`]) is
/// used; c's own time when none is.
fn refine(t: &[f64], v: &[f64], lo: usize, hi: usize, c: usize, sigma: f64) -> f64 {
    let widest = REFINE_WINDOWS[REFINE_WINDOWS.len() - 1];
    let sums = JoinSums::new(
        t,
        v,
        (lo.max(c.saturating_sub(widest)), hi.min(c + widest)),
        c,
    );
    let mut best: Option<(f64, f64)> = None; // (spread, time)
    let mut tried: Vec<(usize, usize, usize)> = Vec::new();
    for degree in 1..=3 {
        for w in REFINE_WINDOWS {
            let (a, b) = (lo.max(c.saturating_sub(w)), hi.min(c + w));
            if c < a + MIN_SIDE + degree
                || b < c + MIN_SIDE + degree
                || tried.contains(&(a, b, degree))
            {
                continue;
            }
            tried.push((a, b, degree));
            let Some((th, rss)) = best_join(&sums, (a, b), c, degree) else {
                continue;
            };
            let dof = (b - a + 1 - degree - 2) as f64;
            if rss > sigma * sigma * (dof + 2.0 * (2.0 * dof).sqrt()) {
                continue;
            }
            let Some(se) = join_spread(t, (a, b), th, degree) else {
                continue;
            };
            if best.is_none_or(|x| se < x.0) {
                best = Some((se, th));
            }
        }
    }
    best.map_or(t[c], |x| x.1)
}

/// How far (in sample intervals) a corner's time is refined from the sample of the
/// largest t-ratio (a weak corner's ratio peaks up to several intervals off).
const REFINE_SAMPLES: usize = 16;

/// Samples on each side of a corner over which the join is fitted when its time
/// is refined: a long window locates a weak corner best, a short one holds only a
/// polynomial and a hinge where the signal curves (shorter ones give unstable
/// standard errors).
const REFINE_WINDOWS: [usize; 6] = [20, 40, 80, 160, 320, 640];

/// The join time t_h of least RSS in the search range around c (see [`refine`]):
/// the RSS at every sample, then a golden-section search between the neighbours
/// of the best. `None` if no fit is possible.
fn best_join(s: &JoinSums, (a, b): (usize, usize), c: usize, degree: usize) -> Option<(f64, f64)> {
    let t = s.t;
    let rss = |th: f64| s.rss((a, b), th, degree).unwrap_or(f64::INFINITY);
    let (i0, i1) = (
        c.saturating_sub(REFINE_SAMPLES).max(a + 1),
        (c + REFINE_SAMPLES).min(b - 1),
    );
    let k = (i0..=i1).min_by(|&x, &y| rss(t[x]).total_cmp(&rss(t[y])))?;
    let fk = rss(t[k]);
    if !fk.is_finite() {
        return None;
    }
    // golden section between the neighbours of the best sample
    let (mut x0, mut x1) = (t[k.saturating_sub(1).max(i0)], t[(k + 1).min(i1)]);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut p, mut q) = (x1 - g * (x1 - x0), x0 + g * (x1 - x0));
    let (mut fp, mut fq) = (rss(p), rss(q));
    for _ in 0..40 {
        if fp <= fq {
            x1 = q;
            (q, fq) = (p, fp);
            p = x1 - g * (x1 - x0);
            fp = rss(p);
        } else {
            x0 = p;
            (p, fp) = (q, fq);
            q = x0 + g * (x1 - x0);
            fq = rss(q);
        }
    }
    let th = 0.5 * (x0 + x1);
    let f = rss(th);
    Some(if f <= fk { (th, f) } else { (t[k], fk) })
}

/// Highest power of u in the prefix sums: x^d·x^d for d ≤ 3.
const MOMENTS: usize = 7;

/// Prefix sums for the least squares of a join over any window inside `a0..=b0`
/// and any join time: with u = (t − t_c)/h and y = v − v_c, `pu[j][i]` = Σ u^j
/// (j < [`MOMENTS`]) and `py[j][i]` = Σ u^j·y (j ≤ 3) over the first i samples
/// from a0, and `yy[i]` = Σ y²; a window's moments about any u_h then follow
/// binomially in O(1).
struct JoinSums<'a> {
    t: &'a [f64],
    a0: usize,
    tc: f64,
    h: f64,
    pu: [Vec<f64>; MOMENTS],
    py: [Vec<f64>; 4],
    yy: Vec<f64>,
}

impl<'a> JoinSums<'a> {
    fn new(t: &'a [f64], v: &'a [f64], (a0, b0): (usize, usize), c: usize) -> JoinSums<'a> {
        let (tc, vc) = (t[c], v[c]);
        let h = (t[b0] - tc).max(tc - t[a0]).max(f64::MIN_POSITIVE);
        let m = b0 - a0 + 2;
        let mut pu: [Vec<f64>; MOMENTS] = std::array::from_fn(|_| Vec::with_capacity(m));
        let mut py: [Vec<f64>; 4] = std::array::from_fn(|_| Vec::with_capacity(m));
        let mut yy = Vec::with_capacity(m);
        let (mut su, mut sy, mut s2) = ([0.0; MOMENTS], [0.0; 4], 0.0);
        for i in a0..=b0 + 1 {
            pu.iter_mut().zip(&su).for_each(|(p, s)| p.push(*s));
            py.iter_mut().zip(&sy).for_each(|(p, s)| p.push(*s));
            yy.push(s2);
            if i > b0 {
                break;
            }
            let (u, y) = ((t[i] - tc) / h, v[i] - vc);
            let mut uj = 1.0;
            for j in 0..MOMENTS {
                su[j] += uj;
                if j < 4 {
                    sy[j] += uj * y;
                }
                uj *= u;
            }
            s2 += y * y;
        }
        JoinSums {
            t,
            a0,
            tc,
            h,
            pu,
            py,
            yy,
        }
    }

    /// Σ x^k (k < [`MOMENTS`]) and Σ x^k·y (k ≤ 3) over samples lo..hi
    /// (exclusive), x = u − uh: Σ (u − uh)^k = Σ_j C(k, j)·(−uh)^(k−j)·Σ u^j.
    fn moments(&self, lo: usize, hi: usize, uh: f64) -> ([f64; MOMENTS], [f64; 4]) {
        let (lo, hi) = (lo - self.a0, hi - self.a0);
        let su: [f64; MOMENTS] = std::array::from_fn(|j| self.pu[j][hi] - self.pu[j][lo]);
        let sy: [f64; 4] = std::array::from_fn(|j| self.py[j][hi] - self.py[j][lo]);
        let mut pw = [1.0; MOMENTS];
        for k in 1..MOMENTS {
            pw[k] = pw[k - 1] * -uh;
        }
        let shift = |k: usize, s: &[f64]| -> f64 {
            let mut binom = 1.0;
            let mut sum = 0.0;
            for j in 0..=k {
                sum += binom * pw[k - j] * s[j];
                binom *= (k - j) as f64 / (j + 1) as f64;
            }
            sum
        };
        (
            std::array::from_fn(|k| shift(k, &su)),
            std::array::from_fn(|k| shift(k, &sy)),
        )
    }

    /// The RSS of the least squares on samples `a..=b` of 1, x, …, x^d and the
    /// hinge x₊ in x = (t − th)/h.
    fn rss(&self, (a, b): (usize, usize), th: f64, degree: usize) -> Option<f64> {
        let m = degree + 2;
        let uh = (th - self.tc) / self.h;
        let split = a + self.t[a..=b].partition_point(|&x| x <= th);
        let (full, full_y) = self.moments(a, b + 1, uh);
        let (right, right_y) = self.moments(split, b + 1, uh);
        // column r < m − 1 is x^r; the last is the hinge x₊ (x^r·x₊ = x₊^(r+1))
        let power = |r: usize| if r + 1 == m { 1 } else { r };
        let hinge = |r: usize| r + 1 == m;
        let mut ata = nalgebra::SMatrix::<f64, 5, 5>::identity();
        let mut atb = nalgebra::SVector::<f64, 5>::zeros();
        for r in 0..m {
            for q in 0..m {
                let k = power(r) + power(q);
                ata[(r, q)] = if hinge(r) || hinge(q) {
                    right[k]
                } else {
                    full[k]
                };
            }
            atb[r] = if hinge(r) { right_y[1] } else { full_y[r] };
        }
        let beta = ata.cholesky()?.solve(&atb);
        let yy = self.yy[b + 1 - self.a0] - self.yy[a - self.a0];
        Some((yy - (0..m).map(|r| beta[r] * atb[r]).sum::<f64>()).max(0.0))
    }
}

/// How poorly the samples `a..=b` place a join at th: σ_h²·b²/σ², the variance of
/// the join time in units of s² per (slope jump/noise)² — [(JᵀJ)⁻¹] of the join
/// time's column, the samples after th (∂fit/∂t_h = −b·[t > t_h]; the polynomial's
/// own shift lies in its columns), after the polynomial of `degree` and the hinge.
/// It does not depend on the data, so windows and degrees compare by it without
/// the noise of a fitted slope jump; `None` if singular.
fn join_spread(t: &[f64], (a, b): (usize, usize), th: f64, degree: usize) -> Option<f64> {
    let m = degree + 2;
    let h = (t[b] - t[a]).max(f64::MIN_POSITIVE);
    let mut jtj = nalgebra::SMatrix::<f64, 6, 6>::identity();
    for r in 0..=m {
        jtj[(r, r)] = 0.0;
    }
    let mut row = [0.0; 6];
    for &ti in &t[a..=b] {
        let x = (ti - th) / h;
        let mut xk = 1.0;
        for r in row.iter_mut().take(degree + 1) {
            *r = xk;
            xk *= x;
        }
        row[m - 1] = x.max(0.0);
        row[m] = if x > 0.0 { 1.0 } else { 0.0 };
        for r in 0..=m {
            for q in 0..=m {
                jtj[(r, q)] += row[r] * row[q];
            }
        }
    }
    let var = jtj.try_inverse()?[(m, m)];
    (var.is_finite() && var > 0.0).then_some(var)
}

/// Hermite pieces on each segment, joined at the corners (step 4).
fn build(
    t: &[f64],
    v: &[f64],
    noise: f64,
    segs: &[(usize, usize, f64, bool)],
    work: &Work,
) -> Measured {
    let n = t.len();
    let mut knots: Vec<f64> = Vec::new();
    let mut pieces: Vec<Piece> = Vec::new();
    // first piece index of each segment
    let mut first = Vec::with_capacity(segs.len() + 1);
    for (k, &(_, _, t0, step)) in segs.iter().enumerate() {
        let t1 = segs.get(k + 1).map_or(t[n - 1], |s| s.2);
        let seg = Segment { t0, t1, step };
        first.push(pieces.len());
        let (ks, ps) = fit_segment(t, v, &seg, noise, work);
        if knots.is_empty() {
            knots.push(ks[0]);
        }
        knots.extend_from_slice(&ks[1..]);
        pieces.extend(ps);
    }
    first.push(pieces.len());
    // two smooth sides of a corner meet halfway between their fitted values, and
    // each side is fitted again through that value (the whole side adapts, not
    // only its last piece)
    let mut ends: Vec<[Option<f64>; 2]> = vec![[None, None]; segs.len()];
    for k in 1..segs.len() {
        if !segs[k - 1].3 && !segs[k].3 {
            let m = 0.5 * (spline::end(&pieces[first[k] - 1]) + pieces[first[k]][0]);
            ends[k - 1][1] = Some(m);
            ends[k][0] = Some(m);
        }
    }
    for (k, fixed) in ends.iter().enumerate() {
        if *fixed == [None, None] {
            continue;
        }
        let (a, b) = (first[k], first[k + 1]);
        let ks = &knots[a..=b];
        let lo = t.partition_point(|&x| x < ks[0]);
        let hi = t.partition_point(|&x| x <= ks[ks.len() - 1]);
        match spline_lsq(&t[lo..hi], &v[lo..hi], ks, *fixed, work) {
            Some((u, _)) => pieces[a..b].copy_from_slice(&u),
            // too few samples to fit again: the end pieces moved onto the held
            // values by a straight line each (the shape between is kept)
            None => {
                let y0 = fixed[0].unwrap_or(pieces[a][0]);
                let y1 = fixed[1].unwrap_or(spline::end(&pieces[b - 1]));
                if b - a == 1 {
                    pieces[a] = spline::with_ends(pieces[a], y0, y1);
                } else {
                    pieces[a] = spline::with_ends(pieces[a], y0, spline::end(&pieces[a]));
                    pieces[b - 1] = spline::with_ends(pieces[b - 1], pieces[b - 1][0], y1);
                }
            }
        }
    }
    // a step takes its neighbours' values
    for k in 0..segs.len() {
        let (a, b) = (first[k], first[k + 1] - 1);
        if segs[k].3 {
            let y0 = if k > 0 {
                spline::end(&pieces[a - 1])
            } else {
                pieces[a][0]
            };
            let y1 = if k + 1 < segs.len() && !segs[k + 1].3 {
                pieces[b + 1][0]
            } else {
                spline::end(&pieces[b])
            };
            pieces[a] = spline::line(y0, y1);
        }
    }
    let mut corners: Vec<f64> = segs.iter().map(|s| s.2).collect();
    corners.push(t[n - 1]);
    let steps = segs
        .iter()
        .enumerate()
        .filter(|(_, s)| s.3)
        .map(|(k, s)| (s.2, corners[k + 1]))
        .collect();
    Measured {
        pieces,
        corners,
        steps,
        noise,
        lookup: lookup_table(&knots),
        knots,
    }
}

/// Knots and quintic pieces of one segment. A step is one straight piece (its
/// values are set from its neighbours afterwards).
fn fit_segment(
    t: &[f64],
    v: &[f64],
    s: &Segment,
    sigma: f64,
    work: &Work,
) -> (Vec<f64>, Vec<Piece>) {
    let lo = t.partition_point(|&x| x < s.t0);
    let hi = t.partition_point(|&x| x <= s.t1);
    let (ts, vs) = (&t[lo..hi], &v[lo..hi]);
    let m = ts.len();
    let fitted = (!s.step)
        .then(|| segment_fit(t, v, (s.t0, s.t1), sigma, m as f64, true, work))
        .flatten();
    match fitted {
        Some((_, knots, pieces)) => (knots, pieces),
        // a step, or too few samples for a curve: the straight line of least squares
        None => {
            let (y0, y1) = line_fit(ts, vs, s.t0, s.t1);
            (vec![s.t0, s.t1], vec![spline::line(y0, y1)])
        }
    }
}

/// What a corner at c saves in BIC on [a, b] (`m` samples): the best spline over
/// both sides, or the two sides' knots as one spline (the split without its
/// jumps, so the comparison is nested), against the two sides' splines: the
/// RSS the split saves must exceed [`CORNER_RSS`]·σ² (the hinge test's
/// false-alarm rate).
fn corner_gain(
    t: &[f64],
    v: &[f64],
    (a, c, b): (f64, f64, f64),
    sigma: f64,
    m: f64,
    work: &Work,
) -> f64 {
    let (Some(l), Some(r)) = (
        segment_fit(t, v, (a, c), sigma, m, false, work),
        segment_fit(t, v, (c, b), sigma, m, false, work),
    ) else {
        return f64::INFINITY;
    };
    let lo = t.partition_point(|&x| x < a);
    let hi = t.partition_point(|&x| x <= b);
    let mut knots = l.1.clone();
    knots.extend_from_slice(&r.1[1..]);
    let joined = spline_lsq(&t[lo..hi], &v[lo..hi], &knots, [None, None], work)
        .map_or(f64::INFINITY, |(_, rss)| {
            rss / (sigma * sigma) + spline::unknowns(knots.len()) as f64 * m.ln()
        });
    let merged = segment_fit(t, v, (a, b), sigma, m, false, work).map_or(f64::INFINITY, |f| f.0);
    // the split has more unknowns than the joined spline (a second value and
    // derivatives at c): refund their BIC and ask the saving of a χ² at the
    // hinge test's false-alarm rate instead
    let extra =
        spline::unknowns(l.1.len()) + spline::unknowns(r.1.len()) - spline::unknowns(knots.len());
    merged.min(joined) - l.0 - r.0 + extra as f64 * m.ln() - CORNER_RSS
}

/// The spline of least BIC on the samples in [t0, t1]: (score, knots, unknowns),
/// score = RSS/σ² + p·ln `m` with p = K + 5 unknowns for K intervals (BIC with
/// a known σ; `m` is the sample count the penalty is counted on); with `graded`,
/// each K also with its first interval graded ([`graded_knots`]). The corner test
/// ([`corner_gain`]) compares even knots only: graded knots right after a corner
/// would let a spline turn within two samples, as sharply as the corner it
/// tests. `None` with fewer samples than a single quintic's six unknowns.
fn segment_fit(
    t: &[f64],
    v: &[f64],
    (t0, t1): (f64, f64),
    sigma: f64,
    m: f64,
    graded: bool,
    work: &Work,
) -> Option<(f64, Vec<f64>, Vec<Piece>)> {
    let lo = t.partition_point(|&x| x < t0);
    let hi = t.partition_point(|&x| x <= t1);
    let (ts, vs) = (&t[lo..hi], &v[lo..hi]);
    let n = ts.len();
    if n < spline::unknowns(2) {
        return None;
    }
    let mut best: Option<(f64, Vec<f64>, Vec<Piece>)> = None;
    let mut k = 1usize;
    while k == 1 || 4 * k <= n {
        let even = quantile_knots(ts, t0, t1, k);
        let graded = graded.then(|| graded_knots(ts, &even)).flatten();
        for knots in [Some(even), graded].into_iter().flatten() {
            // the score is at least its penalty: a spline whose penalty alone
            // reaches the best score cannot beat it (not fitted)
            let penalty = spline::unknowns(knots.len()) as f64 * m.ln();
            if best.as_ref().is_some_and(|b| penalty >= b.0) {
                continue;
            }
            if let Some((u, rss)) = spline_lsq(ts, vs, &knots, [None, None], work) {
                let score = rss / (sigma * sigma) + penalty;
                if best.as_ref().is_none_or(|b| score < b.0) {
                    best = Some((score, knots, u));
                }
            }
        }
        k += 1 + k / 8;
    }
    best
}

/// `knots` with the first interval graded: more knots at the samples 2, 2√2, 4, …
/// (a ratio of √2) after its start, so that a transient that starts at a corner (a supply's rise,
/// decaying over a few samples) is followed without spending knots on the rest
/// of the segment. `None` when the first interval has no room for them.
fn graded_knots(ts: &[f64], knots: &[f64]) -> Option<Vec<f64>> {
    let mut out = vec![knots[0]];
    let mut x = 2.0_f64;
    while (x as usize) < ts.len() && ts[x as usize] < knots[1] {
        let knot = ts[x as usize];
        if knot > *out.last().expect("non-empty") {
            out.push(knot);
        }
        x *= std::f64::consts::SQRT_2;
    }
    if out.len() == 1 {
        return None;
    }
    out.extend_from_slice(&knots[1..]);
    Some(out)
}

/// Values at t0 and t1 of the least-squares line through the samples (the mean
/// when fewer than two, the chord of the ends when none).
fn line_fit(ts: &[f64], vs: &[f64], t0: f64, t1: f64) -> (f64, f64) {
    let m = ts.len() as f64;
    match ts.len() {
        0 => (0.0, 0.0),
        1 => (vs[0], vs[0]),
        _ => {
            let tm = ts.iter().sum::<f64>() / m;
            let vm = vs.iter().sum::<f64>() / m;
            let sxx: f64 = ts.iter().map(|t| (t - tm) * (t - tm)).sum();
            let sxy: f64 = ts.iter().zip(vs).map(|(t, v)| (t - tm) * (v - vm)).sum();
            let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
            (vm + b * (t0 - tm), vm + b * (t1 - tm))
        }
    }
}

/// k intervals over [t0, t1] with interior knots at sample quantiles.
fn quantile_knots(ts: &[f64], t0: f64, t1: f64, k: usize) -> Vec<f64> {
    let m = ts.len();
    let mut knots = vec![t0];
    for j in 1..k {
        let x = ts[j * m / k];
        if x > *knots.last().expect("non-empty") && x < t1 {
            knots.push(x);
        }
    }
    knots.push(t1);
    knots
}

/// [`spline::lsq`] on `knots`, counted against the budget of `work`: `None` when
/// singular, or past its deadline.
fn spline_lsq(
    ts: &[f64],
    vs: &[f64],
    knots: &[f64],
    fixed: [Option<f64>; 2],
    work: &Work,
) -> Option<(Vec<Piece>, f64)> {
    if !work.spend(ts.len()) {
        return None;
    }
    spline::lsq(ts, vs, knots, fixed)
}

#[cfg(test)]
mod tests {
    use super::{lookup_table, spline, Measured, CORNER_RSS, CORNER_SIGMAS};

    /// [`CORNER_RSS`] is the χ² quantile it says: 5 degrees of freedom (the
    /// unknowns a split adds to one spline), at the two-sided normal tail of
    /// [`CORNER_SIGMAS`] (to the 0.01 it is written with).
    #[test]
    fn the_corner_threshold_is_its_chi_square_quantile() {
        use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};
        let tail = 2.0 * Normal::standard().cdf(-CORNER_SIGMAS);
        let extra = 2 * spline::unknowns(2) - spline::unknowns(3);
        assert_eq!(extra, 5);
        let q = ChiSquared::new(extra as f64)
            .expect("dof > 0")
            .inverse_cdf(1.0 - tail);
        assert!((q - CORNER_RSS).abs() < 0.01, "quantile {q}");
    }

    /// The bucketed search ([`Measured::piece_end`]) gives what a binary search
    /// over every knot gives, at every knot, halfway between two, a hair below
    /// each, and past the last, for knots spaced very unevenly (quadratically
    /// spreading, then a tight cluster: many buckets empty, some holding dozens).
    #[test]
    fn the_lookup_finds_the_piece_of_a_binary_search() {
        let mut knots: Vec<f64> = (0..300).map(|i| 1e-4 * (i * i) as f64).collect();
        let end = knots[knots.len() - 1];
        knots.extend((1..100).map(|i| end + 1e-6 * i as f64));
        let m = Measured {
            pieces: vec![[0.0; 6]; knots.len() - 1],
            corners: vec![knots[0], knots[knots.len() - 1]],
            steps: Vec::new(),
            noise: 0.0,
            lookup: lookup_table(&knots),
            knots,
        };
        let k = &m.knots;
        let mut ts = vec![k[0], k[k.len() - 1] + 1.0];
        for w in k.windows(2) {
            ts.extend([w[1], 0.5 * (w[0] + w[1]), w[1] - 1e-12 * (w[1] - w[0])]);
        }
        for t in ts {
            assert_eq!(m.piece_end(t), k.partition_point(|&x| x <= t), "t = {t}");
        }
    }
}
