//! Least-squares quintic splines: the smooth pieces of a measured signal.
//!
//! Between two corners the signal is a clamped B-spline of degree [`DEGREE`] on
//! the given breakpoints, so it is C⁴ there. An integrator of order q needs the
//! solution's first q + 1 derivatives continuous inside a step; the input enters
//! the rates, so a jump in the input's k-th derivative is a jump in the
//! solution's (k + 1)-th. With C¹ cubic Hermite pieces the third derivative of the
//! solution jumped at every knot, and a variable-order BDF (orders up to 5)
//! failed its error test at each: the 7 s rig scene took 4 026 steps and 734
//! rejections from its measured drive against 956 and 4 from the same drive in
//! closed form (docs/identify.md, "Speed"). A quintic's fifth derivative jumps,
//! the solution's sixth: beyond every order used.
//!
//! The B-spline basis is evaluated by the Cox–de Boor recursion (Piegl & Tiller,
//! *The NURBS Book*, 2nd ed. 1997, algorithm A2.2); the normal equations are banded
//! (half-bandwidth [`DEGREE`]) and solved by banded Cholesky. Each piece is then
//! stored as a polynomial in u = (t − a)/h over its interval [a, a + h] (its
//! values at [`DEGREE`] + 1 equispaced points, interpolated), so that evaluating it
//! is one Horner scheme.

/// Degree of the pieces (quintic: C⁴ at the breakpoints).
pub const DEGREE: usize = 5;
/// Coefficients of one piece: c₀ + c₁u + … + c₅u⁵, u = (t − a)/h.
pub type Piece = [f64; DEGREE + 1];
/// Nonzero basis functions on an interval, and the band of the normal equations.
const W: usize = DEGREE + 1;

/// Unknowns of a spline on `breaks` (K + 1 breakpoints, K intervals): K + [`DEGREE`].
pub fn unknowns(breaks: usize) -> usize {
    breaks - 1 + DEGREE
}

/// Value and derivative (per unit of t) of `p` at u ∈ [0, 1] over an interval of
/// length `h`.
#[inline]
pub fn eval(p: &Piece, u: f64, h: f64) -> (f64, f64) {
    let mut v = p[DEGREE];
    let mut d = DEGREE as f64 * p[DEGREE];
    for k in (1..DEGREE).rev() {
        v = v * u + p[k];
        d = d * u + k as f64 * p[k];
    }
    (v * u + p[0], d / h)
}

/// The value of `p` at its interval's end (u = 1).
pub fn end(p: &Piece) -> f64 {
    p.iter().sum()
}

/// A straight piece from `y0` to `y1`.
pub fn line(y0: f64, y1: f64) -> Piece {
    let mut p = [0.0; W];
    p[0] = y0;
    p[1] = y1 - y0;
    p
}

/// `p` with its start value moved to `y0` and its end value to `y1` by adding a
/// straight line (the shape between is kept).
pub fn with_ends(mut p: Piece, y0: f64, y1: f64) -> Piece {
    let (a, b) = (p[0], end(&p));
    p[0] = y0;
    p[1] += (y1 - b) - (y0 - a);
    p
}

/// The knot data of interval j for [`Span::basis`]: the knots beside it and the
/// reciprocals of the knot differences the recursion divides by, which depend on
/// the interval only (computed once for all its samples).
struct Span {
    /// U[span + 1 − d] for d = 1..=DEGREE (left[d] = x − this).
    lo: [f64; W],
    /// U[span + d] for d = 1..=DEGREE (right[d] = this − x).
    hi: [f64; W],
    /// 1/(right[r + 1] + left[d − r]) = 1/(U[span + r + 1] − U[span + r + 1 − d]),
    /// zero where the difference is (a repeated knot, whose term is zero).
    inv: [[f64; W]; W],
}

impl Span {
    /// Interval j of the clamped knot vector on `breaks`: breaks[0] repeated
    /// DEGREE + 1 times, the interior breakpoints, the last repeated DEGREE + 1
    /// times; interval j is the span j + DEGREE.
    fn new(breaks: &[f64], j: usize) -> Span {
        let k = breaks.len() - 1;
        let knot = |i: usize| breaks[i.saturating_sub(DEGREE).min(k)];
        let span = j + DEGREE;
        let mut s = Span {
            lo: [0.0; W],
            hi: [0.0; W],
            inv: [[0.0; W]; W],
        };
        for d in 1..=DEGREE {
            s.lo[d] = knot(span + 1 - d);
            s.hi[d] = knot(span + d);
            for r in 0..d {
                let gap = knot(span + r + 1) - knot(span + r + 1 - d);
                s.inv[d][r] = if gap > 0.0 { 1.0 / gap } else { 0.0 };
            }
        }
        s
    }

    /// The B-spline basis functions N_{j..j+DEGREE} at `x` in this interval
    /// (Cox–de Boor, NURBS Book A2.2).
    #[inline]
    fn basis(&self, x: f64) -> [f64; W] {
        let mut n = [0.0; W];
        let mut left = [0.0; W];
        let mut right = [0.0; W];
        n[0] = 1.0;
        for d in 1..=DEGREE {
            left[d] = x - self.lo[d];
            right[d] = self.hi[d] - x;
            let mut saved = 0.0;
            for r in 0..d {
                let temp = n[r] * self.inv[d][r];
                n[r] = saved + right[r + 1] * temp;
                saved = left[d - r] * temp;
            }
            n[d] = saved;
        }
        n
    }
}

/// The interval of `breaks` holding `x`, searched forward from `j` (samples come in
/// order); the last interval holds the last breakpoint.
#[inline]
fn interval(breaks: &[f64], mut j: usize, x: f64) -> usize {
    while j + 2 < breaks.len() && x >= breaks[j + 1] {
        j += 1;
    }
    j
}

/// The least-squares spline on `breaks` through the samples `(ts, vs)` (in order,
/// inside [breaks₀, breaks_K]), its value at the first and at the last breakpoint
/// held where `fixed` gives it: the pieces and the residual sum of squares. `None`
/// when the normal equations are singular (too few samples for the unknowns).
pub fn lsq(
    ts: &[f64],
    vs: &[f64],
    breaks: &[f64],
    fixed: [Option<f64>; 2],
) -> Option<(Vec<Piece>, f64)> {
    let nu = unknowns(breaks.len());
    let held = fixed.iter().flatten().count();
    if ts.len() + held < nu {
        return None;
    }
    let mut a = vec![[0.0; W]; nu]; // a[i][d] = A[i][i + d]
    let mut b = vec![0.0; nu];
    let mut j = 0;
    let mut span = Span::new(breaks, 0);
    for (&x, &y) in ts.iter().zip(vs) {
        let next = interval(breaks, j, x);
        if next != j {
            j = next;
            span = Span::new(breaks, j);
        }
        let f = span.basis(x);
        for r in 0..W {
            for c in r..W {
                a[j + r][c - r] += f[r] * f[c];
            }
            b[j + r] += f[r] * y;
        }
    }
    // a relative ridge of 10⁻¹² on the diagonal (an interval without samples
    // leaves its basis functions' normal equations singular only by round-off
    // where neighbours reach it), before the held rows are set exactly
    let scale = a.iter().map(|r| r[0]).fold(0.0, f64::max);
    for r in a.iter_mut() {
        r[0] += 1e-12 * scale;
    }
    // a held value is its end coefficient (the knot vector is clamped): its column
    // moves to the right-hand side, its row becomes c = value
    for (i, value) in [(0, fixed[0]), (nu - 1, fixed[1])] {
        let Some(value) = value else { continue };
        for r in i.saturating_sub(W - 1)..(i + W).min(nu) {
            let coupling = if r < i { a[r][i - r] } else { a[i][r - i] };
            if r != i {
                b[r] -= coupling * value;
            }
        }
        for r in i.saturating_sub(W - 1)..i {
            a[r][i - r] = 0.0;
        }
        a[i] = [0.0; W];
        a[i][0] = 1.0;
        b[i] = value;
    }
    let c = banded_cholesky_solve(&mut a, b)?;
    let pieces = to_pieces(breaks, &c);
    let mut rss = 0.0;
    let mut j = 0;
    for (&x, &v) in ts.iter().zip(vs) {
        j = interval(breaks, j, x);
        let h = breaks[j + 1] - breaks[j];
        let fit = eval(&pieces[j], (x - breaks[j]) / h, h).0;
        rss += (v - fit) * (v - fit);
    }
    Some((pieces, rss))
}

/// Solve the symmetric banded system `a`·x = `b` (a[i][d] = A[i][i + d]) by banded
/// Cholesky; `None` when it is not positive definite.
fn banded_cholesky_solve(a: &mut [[f64; W]], mut y: Vec<f64>) -> Option<Vec<f64>> {
    let nu = a.len();
    // A = L·Lᵀ, L stored in place as a[i][d] = L[i + d][i]
    for i in 0..nu {
        let mut d0 = a[i][0];
        for k in i.saturating_sub(W - 1)..i {
            d0 -= a[k][i - k] * a[k][i - k];
        }
        if d0.is_nan() || d0 <= 0.0 {
            return None;
        }
        let lii = d0.sqrt();
        a[i][0] = lii;
        for d in 1..W.min(nu - i) {
            let r = i + d;
            let mut s = a[i][d];
            for k in r.saturating_sub(W - 1)..i {
                s -= a[k][r - k] * a[k][i - k];
            }
            a[i][d] = s / lii;
        }
    }
    for i in 0..nu {
        for k in i.saturating_sub(W - 1)..i {
            y[i] -= a[k][i - k] * y[k];
        }
        y[i] /= a[i][0];
    }
    for i in (0..nu).rev() {
        for d in 1..W.min(nu - i) {
            y[i] -= a[i][d] * y[i + d];
        }
        y[i] /= a[i][0];
    }
    Some(y)
}

/// The spline with B-spline coefficients `c` on `breaks`, piece by piece as
/// polynomials in u: each interpolates the spline's values at u = 0, 1/5, …, 1
/// (the polynomial is the piece itself: a degree-5 polynomial is fixed by six
/// values). The ends are the spline's own values, so the pieces join as it does.
fn to_pieces(breaks: &[f64], c: &[f64]) -> Vec<Piece> {
    let inverse = equispaced_inverse();
    (0..breaks.len() - 1)
        .map(|j| {
            let (a, h) = (breaks[j], breaks[j + 1] - breaks[j]);
            let span = Span::new(breaks, j);
            let mut values = [0.0; W];
            for (k, v) in values.iter_mut().enumerate() {
                let u = k as f64 / DEGREE as f64;
                let f = span.basis(a + u * h);
                *v = (0..W).map(|r| f[r] * c[j + r]).sum();
            }
            let mut p = [0.0; W];
            for (r, pr) in p.iter_mut().enumerate() {
                *pr = (0..W).map(|k| inverse[r][k] * values[k]).sum();
            }
            // exact ends (the interpolation's round-off would open the joins)
            p[0] = values[0];
            let sum: f64 = p.iter().sum();
            p[DEGREE] += values[DEGREE] - sum;
            p
        })
        .collect()
}

/// The inverse of the Vandermonde matrix V[k][r] = (k/5)^r: power coefficients
/// from values at u = 0, 1/5, …, 1 (formed once per process: a measured drive
/// makes about 90 least-squares fits a segment, each wanting it).
fn equispaced_inverse() -> &'static [[f64; W]; W] {
    static INVERSE: std::sync::OnceLock<[[f64; W]; W]> = std::sync::OnceLock::new();
    INVERSE.get_or_init(vandermonde_inverse)
}

/// [`equispaced_inverse`] itself.
fn vandermonde_inverse() -> [[f64; W]; W] {
    // Gauss–Jordan on [V | I] with partial pivoting (6 × 6)
    let mut m = [[0.0; 2 * W]; W];
    for (k, row) in m.iter_mut().enumerate() {
        let u = k as f64 / DEGREE as f64;
        for r in 0..W {
            row[r] = u.powi(r as i32);
        }
        row[W + k] = 1.0;
    }
    for col in 0..W {
        let piv = (col..W)
            .max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))
            .expect("non-empty");
        m.swap(col, piv);
        let d = m[col][col];
        for x in m[col].iter_mut() {
            *x /= d;
        }
        for r in 0..W {
            if r != col {
                let f = m[r][col];
                let pivot_row = m[col];
                for (x, p) in m[r].iter_mut().zip(pivot_row) {
                    *x -= f * p;
                }
            }
        }
    }
    let mut inv = [[0.0; W]; W];
    for (r, row) in inv.iter_mut().enumerate() {
        row.copy_from_slice(&m[r][W..]);
    }
    inv
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quintic polynomial is its own least-squares spline on any breakpoints: the
    /// pieces reproduce it (value and slope) to round-off, the RSS is ~0, and the
    /// pieces join with five continuous derivatives (checked on the values and
    /// slopes, the first two, at every breakpoint).
    #[test]
    fn a_quintic_is_fitted_exactly_and_pieces_join_smoothly() {
        let f = |t: f64| 1.0 - 2.0 * t + 0.5 * t.powi(3) - 0.3 * t.powi(5);
        let df = |t: f64| -2.0 + 1.5 * t * t - 1.5 * t.powi(4);
        let ts: Vec<f64> = (0..=200).map(|i| i as f64 / 100.0).collect();
        let vs: Vec<f64> = ts.iter().map(|&t| f(t)).collect();
        let breaks = [0.0, 0.13, 0.5, 0.52, 1.4, 2.0];
        let (p, rss) = lsq(&ts, &vs, &breaks, [None, None]).expect("regular");
        assert!(rss < 1e-20, "rss {rss}");
        for (j, piece) in p.iter().enumerate() {
            let (a, h) = (breaks[j], breaks[j + 1] - breaks[j]);
            for u in [0.0, 0.3, 1.0] {
                let (v, d) = eval(piece, u, h);
                let t = a + u * h;
                // the ridge of 10⁻¹² (relative) biases the fit by about that
                assert!((v - f(t)).abs() < 1e-9, "value at {t}: {}", v - f(t));
                assert!((d - df(t)).abs() < 1e-7, "slope at {t}: {}", d - df(t));
            }
        }
    }

    /// Held ends are met exactly; a sine (not a polynomial) is followed with the
    /// sixth-order convergence of a quintic spline: halving the intervals divides
    /// the worst error by ≈ 2⁶ = 64 (at least 40 asked: the next term of the error
    /// still shows at four intervals a period).
    #[test]
    fn held_ends_are_met_and_a_sine_converges_at_sixth_order() {
        let f = |t: f64| (2.0 * std::f64::consts::PI * t).sin();
        let ts: Vec<f64> = (0..=2000).map(|i| i as f64 / 2000.0).collect();
        let vs: Vec<f64> = ts.iter().map(|&t| f(t)).collect();
        let breaks = [0.0, 0.25, 0.5, 0.75, 1.0];
        let (p, _) = lsq(&ts, &vs, &breaks, [Some(0.1), Some(-0.2)]).expect("regular");
        assert_eq!(p[0][0], 0.1);
        assert!((end(&p[3]) + 0.2).abs() < 1e-12);
        let worst = |k: usize| {
            let h = 1.0 / k as f64;
            let breaks: Vec<f64> = (0..=k).map(|i| i as f64 * h).collect();
            let (p, _) = lsq(&ts, &vs, &breaks, [None, None]).expect("regular");
            ts.iter()
                .map(|&t| {
                    let j = ((t / h) as usize).min(k - 1);
                    (eval(&p[j], (t - breaks[j]) / h, h).0 - f(t)).abs()
                })
                .fold(0.0, f64::max)
        };
        let (coarse, fine) = (worst(4), worst(8));
        assert!(
            coarse / fine > 40.0,
            "{coarse} → {fine}: ratio {}",
            coarse / fine
        );
    }

    /// Too few samples for the unknowns: singular, `None` (never a wild fit).
    #[test]
    fn too_few_samples_are_refused() {
        let ts = [0.0, 0.5, 1.0];
        assert!(lsq(&ts, &[0.0, 1.0, 0.0], &[0.0, 1.0], [None, None]).is_none());
    }
}
