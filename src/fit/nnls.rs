//! Non-negative least squares, min ‖A·x − b‖² subject to x ≥ 0, by the active-set
//! method of Lawson & Hanson (1974, *Solving Least Squares Problems*, ch. 23) on the
//! normal equations G = AᵀA, h = Aᵀb (columns scaled to unit norm first).
//!
//! The passive set P holds the free coefficients. Each outer step moves into P the
//! coefficient with the largest gradient w = h − G·x (the most negative
//! multiplier), then solves G_PP·z = h_P (Cholesky); while some z ≤ 0 it steps from
//! x towards z until the first coefficient reaches zero and drops it. It ends when
//! every coefficient outside P has w ≤ tol: the KKT conditions x ≥ 0, w ≤ 0 off P,
//! w = 0 on P hold. A start (warm start) seeds P with the coefficients a previous,
//! similar problem left positive.
//!
//! No crate of the Rust ecosystem offers a maintained NNLS (the search found only
//! R, Python and JavaScript packages); Clarabel solves the same problem as a QP and
//! is the reference in the tests and the baseline of `benches/relaxation.rs`.

use nalgebra::{DMatrix, DVector};

/// Result of [`nnls`].
#[derive(Debug, Clone)]
pub struct NnlsSolution {
    /// Minimiser (every entry ≥ 0).
    pub x: DVector<f64>,
    /// Outer (add-a-coefficient) iterations.
    pub iterations: usize,
}

/// Solve min ‖A·x − b‖², x ≥ 0. `start`: coefficients that are expected to be
/// positive (a warm start; any subset is valid). Err when a value is not finite or
/// the iteration limit (3·k) is reached.
pub fn nnls(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    start: Option<&[bool]>,
) -> Result<NnlsSolution, String> {
    let k = a.ncols();
    if !(a.iter().all(|v| v.is_finite()) && b.iter().all(|v| v.is_finite())) {
        return Err("the problem holds a value that is not finite".into());
    }
    let col = |j: usize| &a.as_slice()[j * a.nrows()..(j + 1) * a.nrows()];
    // AᵀA from the upper triangle (contiguous column dot products), Aᵀb.
    let mut g = DMatrix::zeros(k, k);
    for j in 0..k {
        for i in 0..=j {
            let v = dot(col(i), col(j));
            g[(i, j)] = v;
            g[(j, i)] = v;
        }
    }
    let h = DVector::from_fn(k, |i, _| dot(col(i), b.as_slice()));
    nnls_normal(&g, &h, start)
}

/// [`nnls`] from the normal equations G = AᵀA and h = Aᵀb (formed by the caller,
/// e.g. in one pass over the rows with other products it needs): the same solution
/// as [`nnls`] of the A and b they came from, bit for bit when they hold the same
/// dot products. The columns are scaled to unit norm through G's diagonal
/// (G_ij/(√G_ii·√G_jj)); a zero diagonal leaves that coefficient at 0.
pub fn nnls_normal(
    g: &DMatrix<f64>,
    h: &DVector<f64>,
    start: Option<&[bool]>,
) -> Result<NnlsSolution, String> {
    let k = h.len();
    if !(g.iter().all(|v| v.is_finite()) && h.iter().all(|v| v.is_finite())) {
        return Err("the problem holds a value that is not finite".into());
    }
    let d: Vec<f64> = (0..k).map(|j| unit_scale(g[(j, j)])).collect();
    let gs = DMatrix::from_fn(k, k, |i, j| g[(i, j)] * d[i] * d[j]);
    let hs = DVector::from_fn(k, |i, _| h[i] * d[i]);
    let x = solve_normal(&gs, &hs, start.unwrap_or(&vec![false; k]), &d)?;
    Ok(NnlsSolution {
        x: DVector::from_iterator(k, x.0.iter().zip(&d).map(|(v, s)| v * s)),
        iterations: x.1,
    })
}

/// 1/‖a‖ of a column whose squared norm is `square` (0 for a zero column).
fn unit_scale(square: f64) -> f64 {
    let s = square.sqrt();
    if s > 0.0 {
        1.0 / s
    } else {
        0.0
    }
}

/// Σ aₖ·bₖ in [`LANES`] interleaved partial sums (k mod [`LANES`]) added at the end:
/// independent sums the compiler keeps in vector registers, where a single running
/// sum is a chain of dependent additions, one element per add latency (4× to 8×
/// slower on a long column). Its rounding differs from the running sum's in the
/// last bits. Compiled for AVX2 (four f64 a register) where the processor has it,
/// else for the baseline (two): the same arithmetic, so the same bits either way.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (detected on the line above).
        return unsafe { dot_avx2(a, b) };
    }
    dot_lanes(a, b)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn dot_avx2(a: &[f64], b: &[f64]) -> f64 {
    dot_lanes(a, b)
}

/// The arithmetic of [`dot`].
#[inline(always)]
fn dot_lanes(a: &[f64], b: &[f64]) -> f64 {
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut acc = [0.0; LANES];
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            acc[l] += x[l] * y[l];
        }
    }
    acc.iter().sum::<f64>() + tail
}

/// Partial sums of [`dot`]: two AVX registers of four.
const LANES: usize = 8;

/// Lawson–Hanson on the scaled normal equations (module notes). Returns the scaled
/// solution and the outer iterations.
fn solve_normal(
    g: &DMatrix<f64>,
    h: &DVector<f64>,
    start: &[bool],
    d: &[f64],
) -> Result<(Vec<f64>, usize), String> {
    let k = h.len();
    // Gradient tolerance: rounding of the normal equations, relative to ‖h‖∞.
    let tol = 1e-10 * h.amax().max(f64::MIN_POSITIVE);
    let usable = |j: usize| d[j] > 0.0;
    let mut passive: Vec<bool> = (0..k)
        .map(|j| start.get(j) == Some(&true) && usable(j))
        .collect();
    let mut x = DVector::zeros(k);
    let mut z = vec![0.0; k];
    let mut w = DVector::zeros(k);
    let mut iterations = 0;
    // A warm start is made feasible by the inner loop before the first addition.
    let mut add_next = !passive.iter().any(|&p| p);
    loop {
        if add_next {
            // w = h − G·x, over the coefficients outside P.
            w.copy_from(h);
            w.gemv(-1.0, g, &x, 1.0);
            let best = (0..k)
                .filter(|&j| !passive[j] && usable(j))
                .map(|j| (j, w[j]))
                .filter(|&(_, w)| w > tol)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let Some((t, _)) = best else {
                return Ok((x.iter().copied().collect(), iterations));
            };
            iterations += 1;
            if iterations > 3 * k.max(1) {
                return Err(format!("no convergence in {} iterations", 3 * k));
            }
            passive[t] = true;
        }
        add_next = true;
        // Inner loop: keep the solution on P feasible.
        loop {
            if !solve_passive(g, h, &passive, &mut z) {
                return Err("the normal equations on the free set are singular".into());
            }
            if (0..k).all(|j| !passive[j] || z[j] > 0.0) {
                x.copy_from_slice(&z);
                break;
            }
            let alpha = (0..k)
                .filter(|&j| passive[j] && z[j] <= 0.0)
                .map(|j| x[j] / (x[j] - z[j]))
                .fold(1.0, f64::min);
            for j in 0..k {
                x[j] += alpha * (z[j] - x[j]);
                if passive[j] && (x[j] <= 0.0 || (z[j] <= 0.0 && x[j] <= 1e-15)) {
                    passive[j] = false;
                    x[j] = 0.0;
                }
            }
            if !passive.iter().any(|&p| p) {
                break;
            }
        }
    }
}

/// z_P = G_PP⁻¹·h_P (Cholesky), z = 0 off P. False if G_PP is not positive definite.
fn solve_passive(g: &DMatrix<f64>, h: &DVector<f64>, passive: &[bool], z: &mut [f64]) -> bool {
    let idx: Vec<usize> = (0..passive.len()).filter(|&j| passive[j]).collect();
    let m = idx.len();
    let gp = DMatrix::from_fn(m, m, |r, c| g[(idx[r], idx[c])]);
    let hp = DVector::from_fn(m, |r, _| h[idx[r]]);
    let Some(ch) = gp.cholesky() else {
        return false;
    };
    let sol = ch.solve(&hp);
    z.fill(0.0);
    for (r, &j) in idx.iter().enumerate() {
        z[j] = sol[r];
    }
    sol.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::linear::constrained_least_squares;

    /// KKT residual of x for min ½‖Ax − b‖², x ≥ 0, relative to ‖Aᵀb‖∞: the
    /// gradient w = Aᵀ(b − Ax) must vanish where x > 0 and be ≤ 0 where x = 0.
    fn kkt(a: &DMatrix<f64>, b: &DVector<f64>, x: &DVector<f64>) -> f64 {
        assert!(x.iter().all(|&v| v >= 0.0));
        let w = a.tr_mul(&(b - a * x));
        let scale = a.tr_mul(b).amax().max(f64::MIN_POSITIVE);
        (0..x.len())
            .map(|j| if x[j] > 0.0 { w[j].abs() } else { w[j].max(0.0) } / scale)
            .fold(0.0, f64::max)
    }

    /// A Prony-like grid: decaying exponentials at log-spaced τ, data from three.
    fn prony(n: usize, k: usize) -> (DMatrix<f64>, DVector<f64>) {
        let t: Vec<f64> = (0..n)
            .map(|i| 10f64.powf(-1.0 + 4.0 * i as f64 / n as f64))
            .collect();
        let taus: Vec<f64> = (0..k - 1)
            .map(|j| 10f64.powf(-1.5 + 5.0 * j as f64 / (k - 2) as f64))
            .collect();
        let a = DMatrix::from_fn(n, k, |i, j| {
            if j == 0 {
                1.0
            } else {
                (-t[i] / taus[j - 1]).exp()
            }
        });
        let b = DVector::from_fn(n, |i, _| {
            1.0 + 2.0 * (-t[i] / 0.7).exp()
                + 0.5 * (-t[i] / 40.0).exp()
                + 1e-3 * (i as f64 * 0.37).sin()
        });
        (a, b)
    }

    #[test]
    fn matches_clarabel_on_a_prony_grid() {
        let (a, b) = prony(200, 37);
        let ours = nnls(&a, &b, None).unwrap();
        let qp = constrained_least_squares(&a, &b, &DMatrix::identity(37, 37)).unwrap();
        let qx = qp.x.map(|v| v.max(0.0));
        let cost = |x: &DVector<f64>| (&a * x - &b).norm_squared();
        // Same optimum: the active-set solution is at least as good as the interior
        // point's (which stops at a duality-gap tolerance) and satisfies KKT.
        assert!(
            cost(&ours.x) <= cost(&qx) * (1.0 + 1e-9),
            "{} vs {}",
            cost(&ours.x),
            cost(&qx)
        );
        assert!(kkt(&a, &b, &ours.x) < 1e-8, "KKT {}", kkt(&a, &b, &ours.x));
        assert!(ours.x.iter().all(|&v| v >= 0.0));
        // A warm start from the answer ends at once, at the same point.
        let start: Vec<bool> = ours.x.iter().map(|&v| v > 0.0).collect();
        let warm = nnls(&a, &b, Some(&start)).unwrap();
        assert_eq!(warm.iterations, 0);
        assert!((&warm.x - &ours.x).amax() <= 1e-9 * ours.x.amax());
    }

    #[test]
    fn random_problems_meet_kkt_and_clarabel() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for case in 0..200 {
            let (n, k) = (rng.gen_range(12..30), rng.gen_range(1..12));
            let a = DMatrix::from_fn(n, k, |_, _| rng.gen_range(-1.0..1.0));
            let b = DVector::from_fn(n, |_, _| rng.gen_range(-1.0..1.0));
            let ours = nnls(&a, &b, None).expect("full column rank");
            let qp = constrained_least_squares(&a, &b, &DMatrix::identity(k, k)).unwrap();
            let cost = |x: &DVector<f64>| (&a * x - &b).norm_squared();
            let qx = qp.x.map(|v| v.max(0.0));
            assert!(
                cost(&ours.x) <= cost(&qx) + 1e-9 * b.norm_squared(),
                "case {case}"
            );
            assert!(
                kkt(&a, &b, &ours.x) < 1e-8,
                "case {case}: KKT {}",
                kkt(&a, &b, &ours.x)
            );
        }
    }

    /// The lane-split dot product is the running sum's to rounding (10⁻¹⁴ of Σ|aₖbₖ|)
    /// at every length around the lane count, remainders included.
    #[test]
    fn dot_is_the_sum_of_products() {
        for n in 0..40 {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
            let b: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 1.3).cos()).collect();
            let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let scale: f64 = a.iter().zip(&b).map(|(x, y)| (x * y).abs()).sum();
            assert!((dot(&a, &b) - naive).abs() <= 1e-14 * scale, "n = {n}");
        }
    }

    /// [`dot`] compiled for AVX2 and for the baseline gives the same bits at every
    /// length around the lane count, where the processor has AVX2 to compare.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn vector_and_baseline_dot_agree_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        for n in 0..600 {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() * 1e3).collect();
            let b: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 1.3).cos() / 7.0).collect();
            // SAFETY: AVX2 detected above.
            let v = unsafe { dot_avx2(&a, &b) };
            assert_eq!(v.to_bits(), dot_lanes(&a, &b).to_bits(), "n = {n}");
        }
    }

    #[test]
    fn refuses_what_is_not_finite() {
        let a = DMatrix::from_element(3, 2, f64::NAN);
        assert!(nnls(&a, &DVector::zeros(3), None).is_err());
    }
}
