//! Drucker stability: the sign of dP/dλ in each mode over [`DRUCKER_RANGE`].
//!
//! The result is stated on a log-spaced grid of [`GRID`] stretches (400 per decade
//! pair): a stretch is stable when dP/dλ there is finite and positive, and the
//! reported intervals run from grid stretch to grid stretch (so a bound is known to
//! one grid step, 1.2 % in stretch).
//!
//! [`drucker`] decides the sign at every grid stretch without evaluating most of
//! them. Where the model writes its tangent as a sum of powers
//! ([`StrainEnergy::tangent_powers`]), T(s) = P(s) − N(s) in s = ln λ with P and N
//! sums of positive exponentials, both convex. On a cell [sa, sb] of the grid:
//!
//! * P ≥ the larger of its tangent lines at sa and sb, N ≤ its chord, so T is at least
//!   a convex piecewise-linear function whose minimum is at sa, sb or the tangent
//!   lines' crossing; if that minimum exceeds [`MARGIN`]·(P + N)max, T > 0 on the
//!   whole cell (every stretch in it, not only the grid's);
//! * symmetrically T ≤ (chord of P) − (tangent lines of N); if its maximum is below
//!   −[`MARGIN`]·(P + N)max, T < 0 on the whole cell;
//! * otherwise the cell is halved, down to single grid steps, whose two ends are
//!   evaluated by [`StrainEnergy::tangent`], as the dense sweep does.
//!
//! The bounds are applied to T·e^{−m·(s − sa)}, m the mean exponent of the terms at the
//! cell's ends (same sign; see `bound`): the parts' curvature, and so the bounds'
//! slack, is then the spread of the exponents about m, and cells where terms of near
//! exponents cancel are decided wider (the fitted VHB 4910 Yeoh: 32.9 k → 22.6 k
//! instructions a check, callgrind).
//!
//! Before any of that, Descartes' rule of signs (which holds for sums of real
//! powers) bounds the zeros of the sum in λ > 0 by the sign changes of its
//! coefficients in order of exponent. With at most one change T has at most one
//! simple zero, so the grid holds one sign up to it and the other after: the two
//! ends and a bisection for the crossing (some ten evaluations) decide the mode.
//! That is the common case of a fitted model.
//!
//! The margin (10⁻⁹ of the terms' magnitude, some 10⁶ times the rounding of either
//! way of evaluating T) keeps a decided cell decided whichever way T is computed, so
//! the result equals [`drucker_dense`]'s (the previous method, kept as the baseline
//! and for models without a power form) at every grid stretch; the property test in
//! `tests/models.rs` checks it on random parameters of every model. A bounded model
//! (Gent: finite only up to its extensibility limit) first has the ends of its
//! finite interval found by bisection on the grid.

use crate::material::hyperelastic::powers::Parts;
use crate::material::hyperelastic::{AtParams, Mode, StrainEnergy};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// Stretch range over which Drucker stability is checked.
pub const DRUCKER_RANGE: (f64, f64) = (0.1, 10.0);

/// Stretches of the grid on which the result is stated.
pub const GRID: usize = 801;

/// Relative margin by which a bound must clear zero to decide a cell.
pub const MARGIN: f64 = 1e-9;

/// Drucker stability of one mode over [`DRUCKER_RANGE`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DruckerCheck {
    /// Mode.
    pub mode: Mode,
    /// True if dP/dλ > 0 over the whole checked range.
    pub stable: bool,
    /// Lower end of the stable interval that contains λ = 1.
    pub stretch_min: f64,
    /// Upper end of the stable interval that contains λ = 1.
    pub stretch_max: f64,
    /// Intervals [a, b] of the checked range where dP/dλ ≤ 0 or is undefined.
    pub unstable: Vec<[f64; 2]>,
}

/// The grid: (ln λ, λ) at [`GRID`] log-spaced stretches over [`DRUCKER_RANGE`].
fn grid() -> &'static [(f64, f64)] {
    static GRID_POINTS: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    GRID_POINTS.get_or_init(|| {
        let (a, b) = (DRUCKER_RANGE.0.ln(), DRUCKER_RANGE.1.ln());
        (0..GRID)
            .map(|i| {
                let s = a + (b - a) * i as f64 / (GRID - 1) as f64;
                (s, s.exp())
            })
            .collect()
    })
}

/// Drucker stability of every mode, decided by bounds on cells of the grid (see the
/// module notes); the same result as [`drucker_dense`].
pub fn drucker(model: &dyn StrainEnergy, p: &[f64]) -> Vec<DruckerCheck> {
    Mode::ALL
        .iter()
        .map(|&mode| summarize(mode, &signs(model, p, mode)))
        .collect()
}

/// Drucker stability of every mode by evaluating dP/dλ at every grid stretch: the
/// baseline [`drucker`] is measured and tested against.
pub fn drucker_dense(model: &dyn StrainEnergy, p: &[f64]) -> Vec<DruckerCheck> {
    Mode::ALL
        .iter()
        .map(|&mode| {
            let mut runs = Runs::default();
            dense(&Tangent::new(model, p, mode), 0, GRID - 1, &mut runs);
            summarize(mode, &runs)
        })
        .collect()
}

/// The sign of dP/dλ over the grid as runs (first index, last index, positive),
/// in order, adjacent runs of opposite sign.
#[derive(Debug, Default)]
struct Runs(Vec<(usize, usize, bool)>);

impl Runs {
    /// Grid stretches `i..=j` have sign `ok` (a point already decided keeps its sign).
    fn push(&mut self, i: usize, j: usize, ok: bool) {
        let from = match self.0.last_mut() {
            Some(last) if last.1 >= j => return,
            Some(last) if last.2 == ok => {
                last.1 = j;
                return;
            }
            Some(last) => i.max(last.1 + 1),
            None => i,
        };
        self.0.push((from, j, ok));
    }
}

/// dP/dλ of one mode at fixed parameters on the grid ([`AtParams::tangent`]).
struct Tangent<'a> {
    model: &'a dyn StrainEnergy,
    p: &'a [f64],
    at: AtParams,
}

impl<'a> Tangent<'a> {
    fn new(model: &'a dyn StrainEnergy, p: &'a [f64], mode: Mode) -> Self {
        Tangent {
            model,
            p,
            at: AtParams::new(model, p, mode),
        }
    }

    /// dP/dλ at grid stretch `i`.
    #[inline]
    fn at(&self, i: usize) -> f64 {
        self.at.tangent(self.model, self.p, grid()[i].1)
    }

    /// Whether dP/dλ at grid stretch `i` is finite and positive.
    #[inline]
    fn positive(&self, i: usize) -> bool {
        let t = self.at(i);
        t.is_finite() && t > 0.0
    }
}

/// The sign at every grid stretch from `lo` to `hi` by direct evaluation.
fn dense(t: &Tangent, lo: usize, hi: usize, runs: &mut Runs) {
    for i in lo..=hi {
        runs.push(i, i, t.positive(i));
    }
}

/// What the bounds say about T on a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cell {
    Positive,
    Negative,
    Undecided,
}

/// The parts of e^{−m·t}·S at a point t = s − sa from those of S there (`f` =
/// e^{−m·t}): each term's exponent e becomes e − m, so P̃ = f·P, P̃′ = f·(P′ − m·P),
/// and the same for N.
fn shifted(x: Parts, m: f64, f: f64) -> Parts {
    Parts {
        p: f * x.p,
        dp: f * (x.dp - m * x.p),
        n: f * x.n,
        dn: f * (x.dn - m * x.n),
    }
}

/// The sign of T = P − N on [sa, sb] from the parts at its ends (module notes).
///
/// T is first divided by the positive e^{m·(s − sa)}, which keeps its sign and turns
/// every exponent e into e − m; m is the mean exponent of the terms at the two ends
/// (weighted by their size, (P′ + N′)/(P + N)). The bounds' slack grows with the
/// parts' curvature, Σ|a|·(e − m)²·e^{(e−m)s}: about m it is the spread of the
/// exponents rather than their distance from 0, so where terms of near exponents
/// cancel (T ≪ P + N) a cell is decided several times wider. The margin scales with
/// the same factor, so a decided cell still has T > [`MARGIN`]·(P + N) throughout.
/// The rounding of P′ − m·P (≈ ε·|e|max·P, times the cell width in the tangent
/// lines) stays some 10⁴ below the margin.
fn bound(sa: f64, a: Parts, sb: f64, b: Parts) -> Cell {
    let h = sb - sa;
    let mean = |x: Parts| (x.dp + x.dn) / (x.p + x.n);
    let m = 0.5 * (mean(a) + mean(b));
    let m = if m.is_finite() { m } else { 0.0 };
    let (a, b) = (shifted(a, m, 1.0), shifted(b, m, (-m * h).exp()));
    let tol = MARGIN * (a.p + a.n).max(b.p + b.n);
    let (ta, tb) = (a.p - a.n, b.p - b.n);
    if !(tol.is_finite() && ta.is_finite() && tb.is_finite()) {
        return Cell::Undecided;
    }
    // The crossing of the tangent lines of a convex function g at the ends, and the
    // value there of (tangent lines of g) − (chord of the other part h).
    let crossing = |ga: f64, dga: f64, gb: f64, dgb: f64, ha: f64, hb: f64| {
        if dgb <= dga {
            return None;
        }
        let t = (gb - ga - dgb * h) / (dga - dgb);
        (t > 0.0 && t < h).then(|| ga + dga * t - (ha + (hb - ha) * t / h))
    };
    if ta > tol && tb > tol {
        let low = crossing(a.p, a.dp, b.p, b.dp, a.n, b.n).unwrap_or(f64::INFINITY);
        if low > tol {
            return Cell::Positive;
        }
    }
    if ta < -tol && tb < -tol {
        // N − P ≥ (tangent lines of N) − (chord of P).
        let low = crossing(a.n, a.dn, b.n, b.dn, a.p, b.p).unwrap_or(f64::INFINITY);
        if low > tol {
            return Cell::Negative;
        }
    }
    Cell::Undecided
}

/// The last index of `lo..=hi` whose sign is that of `lo`, given that the sign
/// changes once (bisection on direct evaluations).
fn last_like_first(t: &Tangent, lo: usize, hi: usize, first: bool) -> usize {
    let (mut a, mut b) = (lo, hi);
    while b - a > 1 {
        let m = (a + b) / 2;
        if t.positive(m) == first {
            a = m
        } else {
            b = m
        }
    }
    a
}

/// The sign of dP/dλ at every grid stretch of `mode`.
fn signs(model: &dyn StrainEnergy, p: &[f64], mode: Mode) -> Runs {
    let mut runs = Runs::default();
    let t = Tangent::new(model, p, mode);
    let Some(tp) = model.tangent_powers(p, mode) else {
        dense(&t, 0, GRID - 1, &mut runs);
        return runs;
    };
    let g = grid();
    let (mut lo, mut hi) = (0, GRID - 1);
    if tp.bounded {
        // Finite on an interval of grid stretches around λ = 1: find its ends.
        let one = grid_one();
        let finite = |i: usize| t.at(i).is_finite();
        if !finite(one) {
            dense(&t, 0, GRID - 1, &mut runs);
            return runs;
        }
        let find = |from: usize, to: usize| {
            // The last finite index going from `from` (finite) towards `to`.
            let (mut good, mut bad) = (from, to);
            while good.abs_diff(bad) > 1 {
                let m = (good + bad) / 2;
                if finite(m) {
                    good = m
                } else {
                    bad = m
                }
            }
            good
        };
        if !finite(0) {
            lo = find(one, 0);
            runs.push(0, lo - 1, false);
        }
        if !finite(GRID - 1) {
            hi = find(one, GRID - 1);
        }
    }
    if tp.sum.sign_changes() <= 1 {
        // At most one simple zero in λ > 0 (Descartes): one sign on either side of it.
        let (a, b) = (t.positive(lo), t.positive(hi));
        if a == b {
            runs.push(lo, hi, a);
        } else {
            let m = last_like_first(&t, lo, hi, a);
            runs.push(lo, m, a);
            runs.push(m + 1, hi, b);
        }
    } else {
        let split = tp.sum.split();
        let parts = |i: usize| split.parts(g[i].0, g[i].1);
        // Depth-first over cells, left to right, each carrying the parts at its ends.
        let mut stack = Vec::with_capacity(32);
        stack.push((lo, parts(lo), hi, parts(hi)));
        while let Some((i, pi, j, pj)) = stack.pop() {
            match bound(g[i].0, pi, g[j].0, pj) {
                Cell::Positive => runs.push(i, j, true),
                Cell::Negative => runs.push(i, j, false),
                Cell::Undecided if j - i <= 1 => {
                    runs.push(i, i, t.positive(i));
                    runs.push(j, j, t.positive(j));
                }
                Cell::Undecided => {
                    let m = (i + j) / 2;
                    let pm = parts(m);
                    stack.push((m, pm, j, pj));
                    stack.push((i, pi, m, pm));
                }
            }
        }
    }
    if hi < GRID - 1 {
        runs.push(hi + 1, GRID - 1, false);
    }
    runs
}

/// The first grid index at or above λ = 1.
fn grid_one() -> usize {
    static ONE: OnceLock<usize> = OnceLock::new();
    *ONE.get_or_init(|| {
        grid()
            .iter()
            .position(|&(_, l)| l >= 1.0)
            .unwrap_or(GRID / 2)
    })
}

/// The check of one mode from the sign runs over the grid.
fn summarize(mode: Mode, runs: &Runs) -> DruckerCheck {
    let g = grid();
    let one = grid_one();
    let unstable: Vec<[f64; 2]> = runs
        .0
        .iter()
        .filter(|r| !r.2)
        .map(|r| [g[r.0].1, g[r.1].1])
        .collect();
    let (stretch_min, stretch_max) = match runs.0.iter().find(|r| r.0 <= one && one <= r.1) {
        Some(&(a, b, true)) => (g[a].1, g[b].1),
        _ => (1.0, 1.0),
    };
    DruckerCheck {
        mode,
        stable: unstable.is_empty(),
        stretch_min,
        stretch_max,
        unstable,
    }
}

/// The grid of (mode, stretch) points at which `--stable` constrains dP/dλ ≥ 0.
pub fn drucker_grid() -> Vec<(Mode, f64)> {
    const N: usize = 121;
    let (a, b) = (DRUCKER_RANGE.0.ln(), DRUCKER_RANGE.1.ln());
    Mode::ALL
        .iter()
        .flat_map(|&m| (0..N).map(move |i| (m, (a + (b - a) * i as f64 / (N - 1) as f64).exp())))
        .collect()
}
