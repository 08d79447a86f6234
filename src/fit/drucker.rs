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
//! A model whose tangent is linear in its parameters, T = Σ p_k·B_k(λ) (the
//! polynomial models: [`StrainEnergy::tangent_basis`]), goes another way before all
//! of that: it is certified on fixed cells of the grid, halved four times (1, 2, 4,
//! 8, 16 cells of 800/2^l grid steps; `Certificate`). With T = λ^lo·Q(μ), μ = λ^g
//! (g the exponents' common step), the Bernstein coefficients of each basis' Q on
//! every cell are computed once per model and mode, so a cell's coefficients are a
//! product of that small table with p. If every coefficient exceeds 2·[`MARGIN`]
//! times Σ|p_k|·ρ_k, ρ_k the largest Bernstein coefficient on the cell of B_k's
//! magnitudes' polynomial Σ_e |b_ke|·λ^e (so the bound is ≥ 2·[`MARGIN`]·(P + N)
//! anywhere in the cell), T > [`MARGIN`]·(P + N) on the whole cell (a Bernstein
//! polynomial lies within the hull of its coefficients: Farin, *Curves and Surfaces
//! for CAGD*, 5th ed., §5.7), and symmetrically for T < 0. A cell that is neither
//! is halved; one of the last level goes to the convex bounds above (without the
//! Descartes shortcut). The fitted VHB 4910 Yeoh is certified in 5 to 9 cells a
//! mode of some forty products each, where the bounds needed some 20 evaluations of
//! the parts and a dozen bounds a mode.
//!
//! The margin (10⁻⁹ of the terms' magnitude, some 10⁶ times the rounding of either
//! way of evaluating T) keeps a decided cell decided whichever way T is computed, so
//! the result equals [`drucker_dense`]'s (the previous method, kept as the baseline
//! and for models without a power form) at every grid stretch; the property test in
//! `tests/models.rs` checks it on random parameters of every model. A bounded model
//! (Gent: finite only up to its extensibility limit) first has the ends of its
//! finite interval found by bisection on the grid.

use crate::material::hyperelastic::powers::{Laurent, Parts, Split, TangentPowers};
use crate::material::hyperelastic::{AtParams, Mode, StrainEnergy};
use serde::{Deserialize, Serialize};
use std::sync::{Mutex, OnceLock, PoisonError};

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
    mode: Mode,
    at: AtParams,
}

impl<'a> Tangent<'a> {
    fn new(model: &'a dyn StrainEnergy, p: &'a [f64], mode: Mode) -> Self {
        Tangent {
            model,
            p,
            mode,
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
    if let Some(cert) = model
        .tangent_basis(mode)
        .and_then(certificate)
        .filter(|c| c.k == p.len())
    {
        let mut lanes = Lanes::default();
        for ((v, a), &x) in lanes.p.iter_mut().zip(&mut lanes.abs).zip(p) {
            (*v, *a) = (x, x.abs());
        }
        let mut fallback = Fallback {
            t: &t,
            powers: None,
        };
        certify(cert, 0, 0, &lanes, &mut fallback, &mut runs);
        return runs;
    }
    let Some(tp) = model.tangent_powers(p, mode) else {
        dense(&t, 0, GRID - 1, &mut runs);
        return runs;
    };
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
        bounded(&t, &tp.sum.split(), lo, hi, &mut runs);
    }
    if hi < GRID - 1 {
        runs.push(hi + 1, GRID - 1, false);
    }
    runs
}

/// The sign at every grid stretch from `lo` to `hi` by the convex bounds on cells
/// (module notes), halved down to single grid steps whose ends are evaluated.
fn bounded(t: &Tangent, split: &Split, lo: usize, hi: usize, runs: &mut Runs) {
    let g = grid();
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

/// Levels of the certificate's cells: level l has 2^l cells of (GRID − 1)/2^l grid
/// steps (the last, 16 cells of 50 steps).
const LEVELS: usize = 5;

/// The most bases (parameters) a certificate takes: the lanes of a row.
const MAX_BASES: usize = 4;

/// One coefficient of each basis (zero after the last), or the parameters.
type Row = [f64; MAX_BASES];

/// Σ a_k·b_k over a row.
#[inline(always)]
fn dot(a: &Row, b: &Row) -> f64 {
    (a[0] * b[0] + a[1] * b[1]) + (a[2] * b[2] + a[3] * b[3])
}

/// The parameters and their magnitudes as rows (zero after the last).
#[derive(Debug, Default)]
struct Lanes {
    p: Row,
    abs: Row,
}

/// The most Bernstein coefficients a cell (a degree below the exponents a
/// [`Laurent`] polynomial holds).
const MAX_LEN: usize = 32;

/// Relative widening of a certificate cell in μ, beyond the rounding of λ^g at its
/// ends, so that the cell holds the grid stretches at its ends.
const WIDEN: f64 = 1e-12;

/// The Bernstein coefficients of a linear tangent's bases on the certificate's
/// cells, in one mode (module notes): T = Σ p_k·B_k, B_k = λ^lo·Q_k(λ^g).
#[derive(Debug)]
struct Certificate {
    /// Bases (parameters).
    k: usize,
    /// Bernstein coefficients a cell: the degree of Q in μ, plus one.
    len: usize,
    /// Per cell (the cells in heap order: cell c of level l is number 2^l − 1 + c,
    /// its halves 2n + 1 and 2n + 2), `len` rows of the bases' coefficients β_jk,
    /// then a row of their largest coefficients ρ_k = max_j ρ_jk of the bases'
    /// magnitudes' polynomials Σ_e |b_ke|·μ^e.
    coef: Vec<Row>,
}

/// Pascal's triangle to n = [`MAX_LEN`] − 1 (exact in f64).
fn pascal() -> [[f64; MAX_LEN]; MAX_LEN] {
    let mut c = [[0.0; MAX_LEN]; MAX_LEN];
    for n in 0..MAX_LEN {
        c[n][0] = 1.0;
        for i in 1..=n {
            c[n][i] = c[n - 1][i - 1] + c[n - 1][i];
        }
    }
    c
}

/// The Bernstein coefficients on [a, b] (0 < a < b) of Q(μ) = Σ_m q_m·μ^m (at most
/// [`MAX_LEN`] of them; `c` from [`pascal`]): with μ = a + h·t, Q = Σ_i τ_i·t^i,
/// τ_i = Σ_{m ≥ i} q_m·C(m, i)·a^(m−i)·h^i, and β_j = Σ_{i ≤ j} C(j, i)/C(d, i)·τ_i
/// (Farin, §5.7). Every weight is ≥ 0, so the rounding of β_j is a few tens of
/// units of the last place of the same sum over |q_m|.
fn bernstein(q: &[f64], a: f64, b: f64, c: &[[f64; MAX_LEN]; MAX_LEN]) -> Vec<f64> {
    let d = q.len() - 1;
    let h = b - a;
    // a^n and h^n by repeated products (n ≤ 31: relative error ≤ 31 units).
    let (mut pa, mut ph) = ([1.0; MAX_LEN], [1.0; MAX_LEN]);
    for n in 1..=d {
        (pa[n], ph[n]) = (pa[n - 1] * a, ph[n - 1] * h);
    }
    let tau: Vec<f64> = (0..=d)
        .map(|i| (i..=d).map(|m| q[m] * c[m][i] * pa[m - i]).sum::<f64>() * ph[i])
        .collect();
    (0..=d)
        .map(|j| (0..=j).map(|i| c[j][i] / c[d][i] * tau[i]).sum())
        .collect()
}

/// Greatest common divisor.
fn gcd(a: i32, b: i32) -> i32 {
    if b == 0 {
        a.abs()
    } else {
        gcd(b, a % b)
    }
}

impl Certificate {
    /// The table of `basis` (None for no basis, too many, or a zero one).
    fn new(basis: &[Laurent]) -> Option<Certificate> {
        let k = basis.len();
        if k == 0 || k > MAX_BASES {
            return None;
        }
        let terms = || {
            basis
                .iter()
                .flat_map(|b| b.terms().filter(|&(_, c)| c != 0.0))
        };
        let lo = terms().map(|(e, _)| e).min()?;
        let step = terms().fold(0, |g, (e, _)| gcd(g, e - lo)).max(1);
        let len = terms().map(|(e, _)| (e - lo) / step).max()? as usize + 1;
        if len > MAX_LEN {
            return None;
        }
        // Q_k's coefficients in μ = λ^step, and those of its magnitudes.
        let q: Vec<[Vec<f64>; 2]> = basis
            .iter()
            .map(|b| {
                let mut q = vec![0.0; len];
                for (e, c) in b.terms().filter(|&(_, c)| c != 0.0) {
                    q[((e - lo) / step) as usize] = c;
                }
                let magnitudes = q.iter().map(|v| v.abs()).collect();
                [q, magnitudes]
            })
            .collect();
        let (g, c) = (grid(), pascal());
        let mut coef = Vec::with_capacity(((1 << LEVELS) - 1) * (len + 1));
        for level in 0..LEVELS {
            let steps = (GRID - 1) >> level;
            for cell in 0..1 << level {
                let a = g[cell * steps].1.powi(step) * (1.0 - WIDEN);
                let b = g[(cell + 1) * steps].1.powi(step) * (1.0 + WIDEN);
                let cell = coef.len();
                coef.resize(cell + len + 1, [0.0; MAX_BASES]);
                for (kk, [qk, magnitudes]) in q.iter().enumerate() {
                    for (row, beta) in coef[cell..].iter_mut().zip(bernstein(qk, a, b, &c)) {
                        row[kk] = beta;
                    }
                    let rho = bernstein(magnitudes, a, b, &c);
                    coef[cell + len][kk] = rho.iter().fold(0.0, |m: f64, &r| m.max(r));
                }
            }
        }
        Some(Certificate { k, len, coef })
    }

    /// What the coefficients of cell `n` say at parameters `p`.
    ///
    /// Positive (negative) when every β_j(p) = Σ_k p_k·β_jk exceeds (is below minus)
    /// 2·[`MARGIN`]·Σ_k |p_k|·ρ_k, which is at least 2·[`MARGIN`] times the largest
    /// coefficient of the magnitudes' polynomial on the cell, so at least
    /// [`MARGIN`]·(P + N) anywhere in it; the rounding of β_j(p) is some 10⁻¹⁴ of
    /// that bound.
    fn cell(&self, n: usize, p: &Lanes) -> Cell {
        let rows = &self.coef[n * (self.len + 1)..(n + 1) * (self.len + 1)];
        let (beta, rho) = rows.split_at(self.len);
        let tol = 2.0 * MARGIN * dot(&rho[0], &p.abs);
        let first = dot(&beta[0], &p.p);
        let (sign, cell) = if first > tol {
            (1.0, Cell::Positive)
        } else if first < -tol {
            (-1.0, Cell::Negative)
        } else {
            return Cell::Undecided;
        };
        if beta[1..].iter().all(|row| sign * dot(row, &p.p) > tol) {
            cell
        } else {
            Cell::Undecided
        }
    }
}

/// The certificate of a linear tangent's basis, built at its first use and kept:
/// the bases are static (one per model and mode), so their address names them.
fn certificate(basis: &'static [Laurent]) -> Option<&'static Certificate> {
    type Known = Vec<((usize, usize), Option<&'static Certificate>)>;
    static KNOWN: Mutex<Known> = Mutex::new(Vec::new());
    let key = (basis.as_ptr() as usize, basis.len());
    let mut known = KNOWN.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(&(_, c)) = known.iter().find(|(k, _)| *k == key) {
        return c;
    }
    let c = Certificate::new(basis).map(|c| &*Box::leak(Box::new(c)));
    known.push((key, c));
    c
}

/// What a cell the certificate leaves undecided falls back to: the convex bounds
/// on the tangent's power sum, built at the first need.
struct Fallback<'a> {
    t: &'a Tangent<'a>,
    powers: Option<Option<TangentPowers>>,
}

impl Fallback<'_> {
    /// The sign at grid stretches `lo..=hi` by the convex bounds (by direct
    /// evaluation if the model gives no unbounded power form).
    fn decide(&mut self, lo: usize, hi: usize, runs: &mut Runs) {
        let t = self.t;
        let tp = self
            .powers
            .get_or_insert_with(|| t.model.tangent_powers(t.p, t.mode));
        match tp {
            Some(tp) if !tp.bounded => bounded(t, &tp.sum.split(), lo, hi, runs),
            _ => dense(t, lo, hi, runs),
        }
    }
}

/// The sign at every grid stretch of certificate cell `n` (level `level`): from
/// its coefficients if they decide it, else from its halves, else (last level)
/// from the convex bounds.
fn certify(
    cert: &Certificate,
    n: usize,
    level: usize,
    p: &Lanes,
    fallback: &mut Fallback,
    runs: &mut Runs,
) {
    let steps = (GRID - 1) >> level;
    let c = n + 1 - (1 << level);
    let (i, j) = (c * steps, (c + 1) * steps);
    match cert.cell(n, p) {
        Cell::Positive => runs.push(i, j, true),
        Cell::Negative => runs.push(i, j, false),
        Cell::Undecided if level + 1 < LEVELS => {
            certify(cert, 2 * n + 1, level + 1, p, fallback, runs);
            certify(cert, 2 * n + 2, level + 1, p, fallback, runs);
        }
        Cell::Undecided => fallback.decide(i, j, runs),
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::hyperelastic::{ModelSpec, OgdenForm};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Bernstein coefficients are the polynomial: Σ β_j·C(d, j)·t^j·(1 − t)^(d−j) equals
    /// Q(a + (b − a)·t) to 10⁻¹³ of the magnitudes' polynomial at the same point (the
    /// rounding of two sums of some ten non-negative-weight terms is ~10⁻¹⁵ of it),
    /// the end coefficients are Q(a) and Q(b), and every coefficient of a polynomial
    /// with non-negative coefficients is non-negative.
    #[test]
    fn bernstein_coefficients_are_the_polynomial() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        for _ in 0..200 {
            let d = rng.gen_range(0..12);
            let q: Vec<f64> = (0..=d).map(|_| rng.gen_range(-1e3..1e3)).collect();
            let a = 10f64.powf(rng.gen_range(-2.0..1.5));
            let b = a * (1.0 + 10f64.powf(rng.gen_range(-3.0..0.5)));
            let c = pascal();
            let beta = bernstein(&q, a, b, &c);
            let mags: Vec<f64> = q.iter().map(|v| v.abs()).collect();
            assert!(bernstein(&mags, a, b, &c).iter().all(|&r| r >= 0.0));
            let poly = |q: &[f64], x: f64| q.iter().rev().fold(0.0, |acc, c| acc * x + c);
            for t in [0.0, 0.1, 0.37, 0.5, 0.81, 1.0] {
                let x = a + (b - a) * t;
                let bern: f64 = (0..=d)
                    .map(|j| beta[j] * c[d][j] * t.powi(j as i32) * (1.0 - t).powi((d - j) as i32))
                    .sum();
                let tol = 1e-13 * poly(&mags, x);
                assert!((bern - poly(&q, x)).abs() <= tol, "d {d} t {t}");
            }
            let tol = 1e-13 * poly(&mags, b);
            assert!((beta[0] - poly(&q, a)).abs() <= tol);
            assert!((beta[d] - poly(&q, b)).abs() <= tol);
        }
    }

    fn model(name: &str) -> Box<dyn StrainEnergy> {
        ModelSpec::new(name, OgdenForm::Abaqus).build().unwrap()
    }

    /// The certificate decides the fitted VHB 4910 Yeoh in every mode without the
    /// convex bounds' fallback, and so does a certified cell by itself: each of its
    /// grid stretches has a positive tangent by direct evaluation.
    #[test]
    fn certificate_decides_the_fitted_yeoh() {
        let m = model("yeoh");
        let p = [69337.65358693252, -904.1759940890297, 17.328065272581014];
        for mode in Mode::ALL {
            let cert = certificate(m.tangent_basis(mode).unwrap()).unwrap();
            let lanes = Lanes {
                p: [p[0], p[1], p[2], 0.0],
                abs: [p[0].abs(), p[1].abs(), p[2].abs(), 0.0],
            };
            let t = Tangent::new(m.as_ref(), &p, mode);
            // The cells the certificate decides, walked as `certify` walks them.
            let (mut decided, mut visited) = (Vec::new(), 0);
            let mut todo = vec![(0usize, 0usize)];
            while let Some((n, level)) = todo.pop() {
                visited += 1;
                let steps = (GRID - 1) >> level;
                let c = n + 1 - (1 << level);
                match cert.cell(n, &lanes) {
                    Cell::Positive => decided.push((c * steps, (c + 1) * steps)),
                    Cell::Negative => panic!("{mode}: a negative cell"),
                    Cell::Undecided => {
                        assert!(level + 1 < LEVELS, "{mode}: a cell left to the bounds");
                        todo.push((2 * n + 2, level + 1));
                        todo.push((2 * n + 1, level + 1));
                    }
                }
            }
            eprintln!("{mode}: {visited} cells visited, {} decided", decided.len());
            for (i, j) in decided {
                assert!((i..=j).all(|i| t.positive(i)), "{mode}");
            }
        }
    }
}
