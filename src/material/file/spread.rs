//! The standard errors and correlation a fit file states for its parameters, and
//! the first-order standard error of a function of them (GUM propagation).

use super::FileParam;
use serde_json::Value;

/// Standard errors and correlation of parameters, in the order a caller named them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Spread {
    /// Standard error of each parameter (None: not stated, held fixed, or not a
    /// standard error: negative or not finite).
    pub std_error: Vec<Option<f64>>,
    /// Correlation between them (None where not stated or not in [−1, 1]).
    pub correlation: Vec<Vec<Option<f64>>>,
}

impl Spread {
    /// The spread of the parameters `names` as a file lists them: `params` by name
    /// (a file may list them in any order), `correlation` in the file's order (the
    /// top-level `correlation` of a hyperelastic fit, a rule's of a composite fit).
    pub(super) fn by_name(params: &[FileParam], names: &[String], correlation: &Value) -> Spread {
        let at: Vec<Option<usize>> = names
            .iter()
            .map(|n| params.iter().position(|p| &p.name == n))
            .collect();
        let rho = |a: usize, b: usize| -> Option<f64> {
            let r = correlation.get(a)?.get(b)?.as_f64()?;
            (r.abs() <= 1.0 + 1e-9).then_some(r.clamp(-1.0, 1.0))
        };
        Spread {
            std_error: at
                .iter()
                .map(|i| {
                    let s = params[(*i)?].std_error?;
                    (s.is_finite() && s >= 0.0).then_some(s)
                })
                .collect(),
            correlation: at
                .iter()
                .map(|a| at.iter().map(|b| rho((*a)?, (*b)?)).collect())
                .collect(),
        }
    }

    /// The standard error of f(θ) with gradient `grad` = ∂f/∂θ, to first order:
    /// u(f) = √(gᵀ·D·R·D·g) with D = diag(σ) and R the correlation (JCGM 100:2008,
    /// the GUM, eq. 13). Only the parameters f depends on (gᵢ ≠ 0) need a σ, and
    /// only pairs of them a correlation: None where one is not stated.
    pub fn propagate(&self, grad: &[f64]) -> Option<f64> {
        let used: Vec<usize> = (0..grad.len()).filter(|&i| grad[i] != 0.0).collect();
        let mut var = 0.0;
        for &a in &used {
            for &b in &used {
                let sa = self.std_error.get(a).copied().flatten()?;
                let sb = self.std_error.get(b).copied().flatten()?;
                let r = match a == b {
                    true => 1.0,
                    false => self.correlation.get(a)?.get(b).copied().flatten()?,
                };
                var += grad[a] * sa * r * sb * grad[b];
            }
        }
        (var.is_finite() && var >= 0.0).then(|| var.sqrt())
    }
}

/// The gradient of `f` at `theta` by central differences (step 10⁻⁶ of each value,
/// or 10⁻⁶ at zero; truncation ≈ 10⁻¹² relative for smooth f and rounding ≈
/// 10⁻¹⁰ of f's size, far below any standard error it is multiplied with).
pub fn gradient(theta: &[f64], f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    let mut x = theta.to_vec();
    (0..theta.len())
        .map(|i| {
            let h = match theta[i] {
                0.0 => 1e-6,
                v => 1e-6 * v.abs(),
            };
            x[i] = theta[i] + h;
            let up = f(&x);
            x[i] = theta[i] - h;
            let down = f(&x);
            x[i] = theta[i];
            (up - down) / (2.0 * h)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spread(se: &[Option<f64>], r: f64) -> Spread {
        Spread {
            std_error: se.to_vec(),
            correlation: vec![vec![Some(1.0), Some(r)], vec![Some(r), Some(1.0)]],
        }
    }

    /// u(a + b) = √(σa² + σb² + 2ρσaσb): 5 for σ = (3, 4) uncorrelated, 7 fully
    /// correlated, 1 anticorrelated (exact in floating point to rounding).
    #[test]
    fn a_sum_adds_variances_with_the_correlation() {
        for (r, want) in [(0.0, 5.0), (1.0, 7.0), (-1.0, 1.0)] {
            let u = spread(&[Some(3.0), Some(4.0)], r).propagate(&[1.0, 1.0]);
            assert!((u.unwrap() - want).abs() < 1e-12, "{r}: {u:?}");
        }
    }

    /// A function of one parameter needs neither the other's σ nor a correlation.
    #[test]
    fn only_what_the_function_depends_on_is_needed() {
        let s = Spread {
            std_error: vec![Some(2.0), None],
            correlation: Vec::new(),
        };
        assert_eq!(s.propagate(&[3.0, 0.0]), Some(6.0));
        assert_eq!(s.propagate(&[3.0, 1.0]), None);
    }

    #[test]
    fn central_differences_of_a_quadratic_are_exact_to_rounding() {
        let g = gradient(&[2.0, 0.0], |x| x[0] * x[0] + 3.0 * x[1]);
        assert!(
            (g[0] - 4.0).abs() < 1e-8 && (g[1] - 3.0).abs() < 1e-8,
            "{g:?}"
        );
    }
}
