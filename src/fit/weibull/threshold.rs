//! The three-parameter (threshold) Weibull, F(E) = 1 − exp[−((E − γ)/α)^β] for
//! E > γ, by maximising the profile likelihood over γ ∈ [0, lowest breakdown).
//!
//! Its known instability (Rinne 2009, *The Weibull Distribution: A Handbook*,
//! §11.3.2.3): for β < 1 the
//! density is unbounded at γ, so the likelihood grows without bound as γ approaches
//! the lowest breakdown; and the maximum often sits at γ = 0 (no evidence of a
//! threshold). Both are detected and said; the fit is only made when asked for.

use super::likelihood::{Data, Hold, Point};
use super::{Estimate, Model, Specimen, Z_975};
use crate::fit::Status;

/// The normalised data shifted by γ (in V/m): x_i = ln((E_i − γ)/E_ref); survivors
/// at or below γ carry no information (their survival probability is one) and are
/// left out.
fn shifted(model: &Model, gamma: f64) -> Data {
    let d = &model.data;
    let mut out = Data {
        x: Vec::with_capacity(d.len()),
        fail: Vec::with_capacity(d.len()),
        lnw: Vec::with_capacity(d.len()),
        z: Vec::with_capacity(d.len()),
        loc: d.loc,
        r: d.r,
    };
    for i in 0..d.len() {
        let e = model.scale * d.x[i].exp() - gamma;
        if e > 0.0 {
            out.x.push((e / model.scale).ln());
            out.fail.push(d.fail[i]);
            out.lnw.push(d.lnw[i]);
            out.z.push(d.z[i]);
        }
    }
    out
}

/// ℓ (normalised units) of the threshold model at γ and a point.
pub(super) fn loglik(model: &Model, gamma: f64, p: &Point) -> f64 {
    shifted(model, gamma).loglik(p, 0.0)
}

/// Fit γ by the profile likelihood: a grid of γ/E_min over [0, 1) (uniform, then
/// geometric towards E_min), refined by golden section around the best grid point.
pub(super) fn fit(
    model: &mut Model,
    specimens: &[Specimen],
    warnings: &mut Vec<String>,
    status: &mut Status,
) {
    let e_min = specimens
        .iter()
        .filter(|s| !s.survived)
        .map(|s| s.field)
        .fold(f64::INFINITY, f64::min);
    let start = model.point;
    let profile = |g: f64| -> Option<(f64, Point)> {
        let m = shifted(model, g).maximize(start, Hold::Nothing, 0.0).ok()?;
        Some((m.loglik, m.point))
    };
    let mut grid: Vec<f64> = (0..20).map(|j| j as f64 / 20.0).collect();
    grid.extend([1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0].map(|m: f64| 1.0 - 10f64.powf(-m)));
    let values: Vec<Option<(f64, Point)>> = grid.iter().map(|&t| profile(t * e_min)).collect();
    let Some(best) = (0..grid.len())
        .filter(|&j| values[j].is_some())
        .max_by(|&a, &b| values[a].unwrap().0.total_cmp(&values[b].unwrap().0))
    else {
        warnings.push(
            "threshold fit: no γ with a converged profile; the two-parameter fit is reported"
                .into(),
        );
        *status = Status::NotConverged;
        return;
    };
    warnings.push(
        "three-parameter (threshold) fit: its likelihood is unbounded as β < 1 and γ → the lowest breakdown, and γ often sits at a boundary (Rinne 2009 §11.3.2.3); read γ with care".into(),
    );
    let last = grid.len() - 1;
    let (g, point) = if best == last {
        let (_, p) = values[best].unwrap();
        warnings.push(format!(
            "threshold fit: the likelihood still grows as γ approaches the lowest breakdown ({e_min:.4e} V/m; β = {:.3}): no finite maximum, γ is not estimable",
            p.beta
        ));
        *status = Status::IllPosed;
        (grid[best] * e_min, p)
    } else {
        // Golden section on [grid[best−1], grid[best+1]].
        let mut a = grid[best.saturating_sub(1)];
        let mut b = grid[best + 1];
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        let f = |t: f64| profile(t * e_min).map_or(f64::NEG_INFINITY, |v| v.0);
        let mut c = b - phi * (b - a);
        let mut d = a + phi * (b - a);
        let (mut fc, mut fd) = (f(c), f(d));
        for _ in 0..80 {
            if (b - a) < 1e-12 {
                break;
            }
            if fc > fd {
                b = d;
                d = c;
                fd = fc;
                c = b - phi * (b - a);
                fc = f(c);
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + phi * (b - a);
                fd = f(d);
            }
        }
        let mut t = 0.5 * (a + b);
        // The boundary γ = 0 itself when the profile falls from it.
        if best == 0 && f(0.0) >= f(t) {
            t = 0.0;
        }
        match profile(t * e_min) {
            Some((_, p)) => (t * e_min, p),
            None => (grid[best] * e_min, values[best].unwrap().1),
        }
    };
    if g == 0.0 {
        warnings.push(
            "threshold fit: γ is at its lower bound 0: the data give no evidence of a threshold, the two-parameter fit applies".into(),
        );
    }
    model.point = point;
    model.gamma = Some(g);
}

/// Observed information of (u, β, γ) (analytic; docs/breakdown.md): with
/// x_i = ln((E_i − γ)/E_ref), t_i = 1/(E_i − γ), d_i = x_i − u, H_i = w_i e^{β d_i}:
/// −ℓ_uu = β²ΣH, −ℓ_uβ = Σ(δ − H) − βΣHd, −ℓ_ββ = r/β² + ΣHd²,
/// −ℓ_γγ = (β − 1)Σδt² + β(β − 1)ΣHt², −ℓ_γu = β²ΣHt, −ℓ_γβ = Σδt − ΣHt − βΣHdt.
pub(super) fn information(model: &Model, gamma: f64) -> Vec<Vec<f64>> {
    let data = shifted(model, gamma);
    let p = model.point;
    let b = p.beta;
    let mut info = data.information(&p);
    for row in info.iter_mut() {
        row.push(0.0);
    }
    info.push(vec![0.0; 3]);
    let (mut gg, mut gu, mut gb) = (0.0, 0.0, 0.0);
    for i in 0..data.len() {
        let t = 1.0 / (model.scale * data.x[i].exp());
        let d = data.x[i] - p.c[0];
        let s = (data.lnw[i] + b * d).exp();
        let f = data.fail[i];
        gg += (b - 1.0) * f * t * t + b * (b - 1.0) * s * t * t;
        gu += b * b * s * t;
        gb += f * t - s * t - b * s * d * t;
    }
    info[2][2] = gg;
    info[2][0] = gu;
    info[0][2] = gu;
    info[2][1] = gb;
    info[1][2] = gb;
    info
}

/// E_p = γ + α·e^{K/β} with σ by the delta method (∂E/∂u = α e^{K/β},
/// ∂E/∂β = −α e^{K/β} K/β², ∂E/∂γ = 1) and Fisher bounds on the log scale; no
/// likelihood-ratio bounds for a threshold fit.
pub(super) fn percentile(model: &Model, gamma: f64, k: f64) -> Estimate {
    let b = model.point.beta;
    let part = model.scale * (model.point.c[0] + k / b).exp();
    let value = gamma + part;
    let se = model.var(&[part, -part * k / (b * b), 1.0]).map(f64::sqrt);
    Estimate {
        value,
        std_error: se,
        fisher95: se.map(|s| {
            let r = Z_975 * s / value;
            (value * (-r).exp(), value * r.exp())
        }),
        lr95: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::weibull::{fit as fit_series, Settings};

    /// The analytic 3×3 information of (u, β, γ) equals the negative central
    /// difference Hessian of ℓ (steps 1e-5 in u and β, 1e-5·E_min in γ; checked
    /// to 1e-4 relative), censored data included, away from the maximum in γ.
    #[test]
    fn information_is_the_negative_hessian() {
        let fields = [21.0, 23.5, 24.0, 26.2, 27.0, 28.4, 29.9, 31.0, 33.0, 33.0];
        let mut specimens: Vec<Specimen> = fields
            .iter()
            .map(|&e| Specimen::new(e * 1e6, false))
            .collect();
        specimens[8].survived = true;
        let f = fit_series(
            &specimens,
            &Settings {
                threshold: true,
                ..Settings::default()
            },
        )
        .expect("fits");
        let m = &f.model;
        let g0 = 10e6;
        let info = information(m, g0);
        let h = [1e-5, 1e-5, 1e-5 * 21e6];
        let at = |d: [f64; 3]| {
            let p = Point {
                c: [m.point.c[0] + d[0], 0.0, 0.0],
                beta: m.point.beta + d[1],
            };
            loglik(m, g0 + d[2], &p)
        };
        for j in 0..3 {
            for l in 0..3 {
                let mut e = [[0.0; 3]; 4];
                for (k, (sj, sl)) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
                    .iter()
                    .enumerate()
                {
                    e[k][j] += sj * h[j];
                    e[k][l] += sl * h[l];
                }
                let d2 = (at(e[0]) - at(e[1]) - at(e[2]) + at(e[3])) / (4.0 * h[j] * h[l]);
                let scale = info[j][l].abs().max(d2.abs());
                assert!(
                    (info[j][l] + d2).abs() <= 1e-4 * scale,
                    "{j},{l}: {} vs {}",
                    info[j][l],
                    -d2
                );
            }
        }
    }
}
