//! The censored Weibull log-likelihood, its maximisation (whole and profiled) and
//! its observed information.
//!
//! Specimen i fails at, or survives up to, the field E_i (δ_i = 1 or 0), with the
//! exposure w_i = A_i/A₀ (electrode area over the reference area) and covariate logs
//! z_i = (1, ln(h_i/h_ref), ln(λ_i/λ_ref)). With x_i = ln(E_i/E_ref) (E_ref a fixed
//! scale, so that every number stays near one) and the characteristic field
//! ln(α_i/E_ref) = η_i = c·z_i (c = (u, a, b), u = ln(α/E_ref) at the references),
//! the cumulative hazard is H_i = w_i·exp(β(x_i − η_i)) (weakest link: the hazard
//! adds over area) and
//!
//!   ℓ = r·ln β + Σ δ_i (ln w_i − x_i) + Σ δ_i β(x_i − η_i) − Σ H_i
//!
//! (r = Σ δ_i; the density term ln f = ln β + ln w + (β − 1)·x − β·η in the
//! normalised units). In the variables θ = −β·c and β it is concave — r·ln β is,
//! the δ-terms are linear and −Σ exp(β x_i + θ·z_i + ln w_i) is the negative of a
//! convex function (Pratt 1981, "Concavity of the log likelihood", JASA 76:103, for
//! log-concave error laws, censored or not) — so Newton's method with a
//! backtracking line search on ℓ converges from any start to the one maximum, and
//! so does every profile (some coordinates held, the others free: the held ones
//! enter linearly).
//!
//! A percentile is handled by the same code: with ln(E_p/E_ref) = q = u + K/β
//! (K = ln(−ln(1 − p)) + ln(A₀/A)), substituting u = q − K/β gives exactly ℓ with
//! u → q and w → w·e^K, so the profile likelihood of a percentile is the profile
//! of u with an offset K.

/// Largest number of location coefficients: u and two covariate exponents.
pub(crate) const LOC: usize = 3;
/// Variables of a Newton step: the location coefficients and β.
const DIM: usize = LOC + 1;

/// The data of a likelihood fit in normalised units (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Data {
    /// x_i = ln(E_i/E_ref), or ln((E_i − γ)/E_ref) for a threshold fit.
    pub x: Vec<f64>,
    /// δ_i: 1 for a breakdown, 0 for a survivor.
    pub fail: Vec<f64>,
    /// ln w_i = ln(A_i/A₀).
    pub lnw: Vec<f64>,
    /// z_i = (1, covariate logs...), unused entries 0.
    pub z: Vec<[f64; LOC]>,
    /// Location coefficients in use: 1 + number of covariates.
    pub loc: usize,
    /// Number of breakdowns r.
    pub r: f64,
}

/// A point of the parameter space: location coefficients c (u and exponents) and β.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Point {
    pub c: [f64; LOC],
    pub beta: f64,
}

/// Which coordinate a profile holds fixed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Hold {
    /// None: the full maximum.
    Nothing,
    /// Location coefficient j (0 = u).
    Loc(usize),
    /// The shape β.
    Beta,
}

/// The maximisation did not converge (iterations or no ascent).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NotConverged {
    pub iterations: usize,
}

/// A maximum: the point, ℓ there, ∂ℓ/∂(held coordinate) there (the slope of the
/// profile likelihood, by the envelope theorem) and the Newton iterations taken.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Maximum {
    pub point: Point,
    pub loglik: f64,
    pub held_slope: f64,
    pub iterations: usize,
}

/// ℓ, its gradient and Hessian in the concave variables of a profile, and the
/// derivative of ℓ in the held natural coordinate.
struct Local {
    loglik: f64,
    grad: [f64; DIM],
    hess: [[f64; DIM]; DIM],
    held: f64,
}

/// Newton iterations before a maximisation is declared not converged.
const MAX_ITER: usize = 200;
/// Converged when half the Newton decrement, gᵀ(−H)⁻¹g/2 (≈ the gain of ℓ still
/// available, in units of ℓ whatever n), is below this: a remaining step of
/// ≈ 1.4·10⁻⁶ standard errors.
const DECREMENT: f64 = 1e-12;

impl Data {
    /// Number of specimens.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// ℓ at a point, with the log-exposure offset `k` (0 for the parameters
    /// themselves, K for a percentile profile).
    pub fn loglik(&self, p: &Point, k: f64) -> f64 {
        let mut sum = self.r * p.beta.ln();
        for i in 0..self.len() {
            let d = self.x[i] - dot(&p.c, &self.z[i], self.loc);
            let lw = self.lnw[i] + k;
            sum += self.fail[i] * (lw - self.x[i] + p.beta * d) - (lw + p.beta * d).exp();
        }
        sum
    }

    /// ℓ with gradient and Hessian in the concave variables of `hold`: θ_j = −β·c_j
    /// for each free location coefficient, then β if free. One pass over the data,
    /// no allocation.
    fn local(&self, p: &Point, hold: Hold, k: f64) -> Local {
        let free = free_list(hold, self.loc);
        let beta_free = hold != Hold::Beta;
        let mut loglik = self.r * p.beta.ln();
        let mut grad = [0.0; DIM];
        let mut hess = [[0.0; DIM]; DIM];
        let m = free.len;
        let mut held = 0.0;
        for i in 0..self.len() {
            let z = &self.z[i];
            let d = self.x[i] - dot(&p.c, z, self.loc);
            let lw = self.lnw[i] + k;
            let s = (lw + p.beta * d).exp();
            let f = self.fail[i];
            loglik += f * (lw - self.x[i] + p.beta * d) - s;
            held += match hold {
                Hold::Loc(j) => (s - f) * z[j],
                Hold::Beta => (f - s) * d,
                Hold::Nothing => 0.0,
            };
            // a_i = x_i − (held part of η_i) = d_i + (free part of η_i).
            let mut a = d;
            for (jj, &j) in free.idx[..m].iter().enumerate() {
                a += p.c[j] * z[j];
                grad[jj] += (f - s) * z[j];
                for (ll, &l) in free.idx[..=jj].iter().enumerate() {
                    hess[jj][ll] -= s * z[j] * z[l];
                }
            }
            if beta_free {
                grad[m] += (f - s) * a;
                for (jj, &j) in free.idx[..m].iter().enumerate() {
                    hess[m][jj] -= s * a * z[j];
                }
                hess[m][m] -= s * a * a;
            }
        }
        if beta_free {
            grad[m] += self.r / p.beta;
            hess[m][m] -= self.r / (p.beta * p.beta);
        }
        held = match hold {
            Hold::Loc(_) => p.beta * held,
            Hold::Beta => held + self.r / p.beta,
            Hold::Nothing => 0.0,
        };
        let dim = m + usize::from(beta_free);
        for j in 0..dim {
            for l in 0..j {
                hess[l][j] = hess[j][l];
            }
        }
        Local {
            loglik,
            grad,
            hess,
            held,
        }
    }

    /// Maximise ℓ over the coordinates `hold` leaves free, from `start` (whose held
    /// coordinate is kept), with the offset `k`: Newton in the concave variables
    /// with a backtracking (Armijo) line search that also keeps β > 0.
    pub fn maximize(&self, start: Point, hold: Hold, k: f64) -> Result<Maximum, NotConverged> {
        let free = free_list(hold, self.loc);
        let beta_free = hold != Hold::Beta;
        let m = free.len;
        let dim = m + usize::from(beta_free);
        let mut p = start;
        let mut here = self.local(&p, hold, k);
        for it in 0..MAX_ITER {
            let Some((step, slope)) = newton(&here, dim) else {
                return Err(NotConverged { iterations: it });
            };
            if slope / 2.0 < DECREMENT {
                return Ok(Maximum {
                    point: p,
                    loglik: here.loglik,
                    held_slope: here.held,
                    iterations: it,
                });
            }
            // Current concave variables.
            let theta: [f64; LOC] = std::array::from_fn(|j| -p.beta * p.c[j]);
            let mut t = 1.0;
            let mut accepted = None;
            for _ in 0..60 {
                let beta = if beta_free {
                    p.beta + t * step[m]
                } else {
                    p.beta
                };
                if beta > 0.0 && beta.is_finite() {
                    let mut q = Point { c: p.c, beta };
                    for (jj, &j) in free.idx[..m].iter().enumerate() {
                        q.c[j] = -(theta[j] + t * step[jj]) / beta;
                    }
                    let there = self.local(&q, hold, k);
                    // Armijo on ℓ; or, where the gain is within the rounding of
                    // ℓ (a sum of n terms), a decrement that falls fourfold: for
                    // a concave ℓ that is progress towards the one maximum.
                    let ascent = there.loglik >= here.loglik + 1e-4 * t * slope;
                    let closer = || newton(&there, dim).is_some_and(|(_, s)| s < 0.25 * slope);
                    if there.loglik.is_finite() && (ascent || closer()) {
                        accepted = Some((q, there));
                        break;
                    }
                }
                t *= 0.5;
            }
            match accepted {
                Some((q, there)) => {
                    p = q;
                    here = there;
                }
                None => return Err(NotConverged { iterations: it }),
            }
        }
        Err(NotConverged {
            iterations: MAX_ITER,
        })
    }

    /// ∂ℓ/∂(held coordinate) in natural units at a point (the derivative of a
    /// profile likelihood by the envelope theorem, when the free coordinates are at
    /// their maximum): ∂ℓ/∂c_j = β·Σ (H_i − δ_i) z_ij, ∂ℓ/∂β = r/β + Σ (δ_i − H_i) d_i.
    pub fn held_derivative(&self, p: &Point, hold: Hold, k: f64) -> f64 {
        self.local(p, hold, k).held
    }

    /// The observed information −∂²ℓ in the natural coordinates (c_0..c_{loc−1}, β),
    /// analytic (module docs; d_i = x_i − η_i, H_i the cumulative hazard):
    /// −∂²ℓ/∂c_j∂c_l = β² Σ H z_j z_l, −∂²ℓ/∂c_j∂β = Σ (δ − H) z_j − β Σ H d z_j,
    /// −∂²ℓ/∂β² = r/β² + Σ H d².
    pub fn information(&self, p: &Point) -> Vec<Vec<f64>> {
        let n = self.loc + 1;
        let mut info = vec![vec![0.0; n]; n];
        let b = p.beta;
        for i in 0..self.len() {
            let z = &self.z[i];
            let d = self.x[i] - dot(&p.c, z, self.loc);
            let s = (self.lnw[i] + b * d).exp();
            let f = self.fail[i];
            for j in 0..self.loc {
                for l in 0..self.loc {
                    info[j][l] += b * b * s * z[j] * z[l];
                }
                info[j][self.loc] += (f - s) * z[j] - b * s * d * z[j];
            }
            info[self.loc][self.loc] += s * d * d;
        }
        info[self.loc][self.loc] += self.r / (b * b);
        for j in 0..self.loc {
            info[self.loc][j] = info[j][self.loc];
        }
        info
    }
}

/// The Newton step of a local model, −H⁻¹g, and its decrement gᵀ(−H)⁻¹g; None
/// when −H is not positive definite or the decrement is not finite.
fn newton(here: &Local, dim: usize) -> Option<([f64; DIM], f64)> {
    let mut neg = [[0.0; DIM]; DIM];
    for j in 0..dim {
        for l in 0..dim {
            neg[j][l] = -here.hess[j][l];
        }
    }
    let step = solve_spd(&neg, &here.grad, dim)?;
    let slope: f64 = (0..dim).map(|j| here.grad[j] * step[j]).sum();
    slope.is_finite().then_some((step, slope))
}

/// The free location coefficients of a profile.
struct Free {
    idx: [usize; LOC],
    len: usize,
}

fn free_list(hold: Hold, loc: usize) -> Free {
    let mut idx = [0; LOC];
    let mut len = 0;
    for j in 0..loc {
        if hold != Hold::Loc(j) {
            idx[len] = j;
            len += 1;
        }
    }
    Free { idx, len }
}

#[inline(always)]
fn dot(c: &[f64; LOC], z: &[f64; LOC], loc: usize) -> f64 {
    let mut s = 0.0;
    for j in 0..loc {
        s += c[j] * z[j];
    }
    s
}

/// Solve A·x = b for a symmetric positive definite A of size `n` ≤ DIM by Cholesky;
/// None when A is not positive definite (to rounding).
pub(crate) fn solve_spd(a: &[[f64; DIM]; DIM], b: &[f64; DIM], n: usize) -> Option<[f64; DIM]> {
    let mut l = [[0.0; DIM]; DIM];
    for j in 0..n {
        let mut s = a[j][j];
        for k in 0..j {
            s -= l[j][k] * l[j][k];
        }
        if s <= 0.0 || !s.is_finite() {
            return None;
        }
        l[j][j] = s.sqrt();
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            l[i][j] = s / l[j][j];
        }
    }
    let mut y = [0.0; DIM];
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    let mut x = [0.0; DIM];
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Data {
        // A censored series in normalised units with one covariate.
        let x = [-0.3, -0.1, 0.0, 0.05, 0.12, 0.2, 0.25, 0.3];
        let fail = [1.0, 1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
        let zc = [0.1, -0.2, 0.05, 0.3, -0.1, 0.2, -0.3, 0.0];
        Data {
            x: x.to_vec(),
            fail: fail.to_vec(),
            lnw: vec![0.0; 8],
            z: zc.iter().map(|&v| [1.0, v, 0.0]).collect(),
            loc: 2,
            r: fail.iter().sum(),
        }
    }

    /// The analytic information equals the negative of a central-difference
    /// Hessian of ℓ (step 1e-4: truncation ~1e-8, rounding ~1e-8 relative; checked
    /// to 1e-5 relative).
    #[test]
    fn information_is_the_negative_hessian() {
        let data = sample();
        let p = Point {
            c: [0.1, 0.3, 0.0],
            beta: 6.0,
        };
        let info = data.information(&p);
        let h = 1e-4;
        let coord = |p: &Point, j: usize, dv: f64| {
            let mut q = *p;
            if j < data.loc {
                q.c[j] += dv;
            } else {
                q.beta += dv;
            }
            q
        };
        let n = data.loc + 1;
        for j in 0..n {
            for l in 0..n {
                let f = |dj: f64, dl: f64| data.loglik(&coord(&coord(&p, j, dj), l, dl), 0.0);
                let d2 = (f(h, h) - f(h, -h) - f(-h, h) + f(-h, -h)) / (4.0 * h * h);
                assert!(
                    (info[j][l] + d2).abs() <= 1e-5 * info[j][l].abs().max(1.0),
                    "{j},{l}: {} vs {}",
                    info[j][l],
                    -d2
                );
            }
        }
    }

    /// The profile maximum has a zero derivative in every free natural coordinate
    /// (checked by central differences of ℓ, to 1e-6 of the scale of ℓ's curvature).
    #[test]
    fn profiles_reach_the_maximum() {
        let data = sample();
        let start = Point {
            c: [0.0, 0.0, 0.0],
            beta: 1.0,
        };
        for hold in [Hold::Nothing, Hold::Beta, Hold::Loc(0), Hold::Loc(1)] {
            let m = data.maximize(start, hold, 0.3).expect("converges");
            let h = 1e-6;
            for j in 0..=data.loc {
                let held = match hold {
                    Hold::Beta => j == data.loc,
                    Hold::Loc(l) => l == j,
                    Hold::Nothing => false,
                };
                if held {
                    continue;
                }
                let mut a = m.point;
                let mut b = m.point;
                if j < data.loc {
                    a.c[j] += h;
                    b.c[j] -= h;
                } else {
                    a.beta += h;
                    b.beta -= h;
                }
                let g = (data.loglik(&a, 0.3) - data.loglik(&b, 0.3)) / (2.0 * h);
                assert!(g.abs() < 1e-5, "{hold:?} coordinate {j}: {g}");
            }
        }
    }
}
