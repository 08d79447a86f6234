//! Noise per channel: given by the user, or estimated.
//!
//! **From the data** (the start of the search, before any model): the residual of
//! linear interpolation between each row's neighbours, e_i = y_i − (w·y_{i−1} +
//! (1 − w)·y_{i+1}) with w = (t_{i+1} − t_i)/(t_{i+1} − t_{i−1}), has variance
//! σ²·(1 + w² + (1 − w)²) for white noise on a signal that is locally linear; its
//! median absolute deviation, scaled by 1.4826, is robust to the few rows at corners
//! and steps. This works on irregular sample times.
//!
//! **From the residuals** (after the search): σ_c² = Σ r_ci² / (n_c − p·n_c/N), the
//! channel's share of the degrees of freedom, so the channels' χ² each come out at
//! their degrees of freedom.

/// A channel's noise as the user gives it (`--sigma contraction=0.5um`,
/// `--sigma capacitance=0.2%`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sigma {
    /// Standard deviation (SI).
    Absolute(f64),
    /// Fraction of the channel's RMS measured value.
    Relative(f64),
}

/// Where a channel's σ came from (reported).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SigmaSource {
    /// Given with `--sigma`.
    Given,
    /// Estimated from the residuals at the optimum.
    Residuals,
}

impl Sigma {
    /// σ (SI) of a channel with these values.
    pub fn resolve(self, values: &[f64]) -> f64 {
        match self {
            Sigma::Absolute(s) => s,
            Sigma::Relative(f) => f * rms(values),
        }
    }
}

/// Root mean square of the finite values.
pub fn rms(values: &[f64]) -> f64 {
    let (s, n) = values
        .iter()
        .filter(|v| v.is_finite())
        .fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    (s / n.max(1) as f64).sqrt()
}

/// Noise σ estimated from the data alone (module documentation); the rows with a
/// value and their times. A floor of 10⁻⁹ of the RMS value keeps a noiseless
/// channel's σ positive.
pub fn from_data(times: &[f64], values: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> = times
        .iter()
        .zip(values)
        .filter(|(_, v)| v.is_finite())
        .map(|(&t, &v)| (t, v))
        .collect();
    let mut e: Vec<f64> = pts
        .windows(3)
        .filter_map(|w| {
            let ((t0, y0), (t1, y1), (t2, y2)) = (w[0], w[1], w[2]);
            let span = t2 - t0;
            (span > 0.0).then(|| {
                let a = (t2 - t1) / span;
                (y1 - (a * y0 + (1.0 - a) * y2)) / (1.0 + a * a + (1.0 - a) * (1.0 - a)).sqrt()
            })
        })
        .collect();
    let floor = 1e-9 * rms(values).max(f64::MIN_POSITIVE);
    if e.is_empty() {
        return floor;
    }
    let med = median(&mut e);
    let mut dev: Vec<f64> = e.iter().map(|x| (x - med).abs()).collect();
    (1.4826 * median(&mut dev)).max(floor)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n % 2 {
        1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// White noise of σ = 0.01 on a smooth signal sampled irregularly: the estimate is
    /// within 10 % (the MAD of 2000 normal values has a relative spread of about
    /// 1.7 %; the curvature of the signal adds less than 1 %).
    #[test]
    fn estimates_white_noise_on_irregular_times() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let n = Normal::new(0.0, 0.01).unwrap();
        let mut t: f64 = 0.0;
        let (mut ts, mut ys) = (Vec::new(), Vec::new());
        for i in 0..2000 {
            t += if i % 7 == 0 { 0.01 } else { 0.001 };
            ts.push(t);
            ys.push((2.0 * t).sin() + n.sample(&mut rng));
        }
        let s = from_data(&ts, &ys);
        assert!((s / 0.01 - 1.0).abs() < 0.1, "σ estimate {s}");
    }
}
