//! Goodness of fit of a straight Weibull plot.
//!
//! Complete data: the Anderson–Darling statistic of the probability-integral
//! transforms U_i = F̂_i(E_i) = 1 − exp(−Ĥ_i) under the maximum-likelihood fit,
//! A² = −n − (1/n) Σ (2i − 1)[ln U_(i) + ln(1 − U_(n+1−i))], with Stephens'
//! modification for both parameters estimated, A* = A²(1 + 0.2/√n), against the 5 %
//! critical value 0.757 (D'Agostino & Stephens 1986, *Goodness-of-Fit Techniques*,
//! Table 4.17, extreme-value/Weibull case 3; Stephens 1977, Biometrika 64:583).

use super::likelihood::{Data, Point};
use super::Goodness;

/// The 5 % critical value of the modified A* (D'Agostino & Stephens 1986, Table 4.17).
pub const AD_CRITICAL_5: f64 = 0.757;

/// Anderson–Darling test of complete data (None with survivors: see docs/breakdown.md).
pub(super) fn test(data: &Data, mle: &Point) -> Option<Goodness> {
    if data.fail.contains(&0.0) {
        return None;
    }
    let n = data.len();
    // Cumulative hazards Ĥ_i, sorted: U is increasing in H.
    let mut h: Vec<f64> = (0..n)
        .map(|i| {
            let eta: f64 = (0..data.loc).map(|j| mle.c[j] * data.z[i][j]).sum();
            (data.lnw[i] + mle.beta * (data.x[i] - eta)).exp()
        })
        .collect();
    h.sort_by(f64::total_cmp);
    let nf = n as f64;
    let mut sum = 0.0;
    for i in 0..n {
        let ln_u = (-(-h[i]).exp_m1()).ln();
        let ln_1mu = -h[n - 1 - i];
        sum += (2.0 * i as f64 + 1.0) * (ln_u + ln_1mu);
    }
    let a2 = -nf - sum / nf;
    let statistic = a2 * (1.0 + 0.2 / nf.sqrt());
    Some(Goodness {
        test: "Anderson-Darling A* (Stephens' modification, D'Agostino & Stephens 1986 Table 4.17)"
            .into(),
        statistic,
        critical5: AD_CRITICAL_5,
        p_value: None,
        straight: statistic <= AD_CRITICAL_5,
    })
}
