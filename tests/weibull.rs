//! The Weibull estimators of `dea-fit breakdown` (src/fit/weibull): published
//! worked examples, an independent implementation (the `reliability` package,
//! datasets/breakdown/reference/), and properties of the estimators on synthetic
//! series (recovery, coverage of the bounds, censoring, area scaling, ties).

use dea_fit::fit::weibull::{
    fit, BoundKind, Covariate, Method, Positions, Settings, Specimen, WeibullError, CHI2_1_95,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn complete(fields: &[f64]) -> Vec<Specimen> {
    fields.iter().map(|&e| Specimen::new(e, false)).collect()
}

fn mle() -> Settings {
    Settings::default()
}

/// Within half a unit of the last printed digit.
fn printed(value: f64, want: f64, digits: i32) {
    within_units(value, want, digits, 0.5);
}

/// Within `units` of the last printed digit.
fn within_units(value: f64, want: f64, digits: i32, units: f64) {
    let tol = units * 10f64.powi(-digits);
    assert!(
        (value - want).abs() <= tol,
        "{value} is not {want} to {units} units of the {digits}th decimal"
    );
}

/// Altair Compose `wblfit` reference example (2021.help.altair.com, OML
/// "wblfit"; MATLAB's wblfit gives the same): 20 complete values, a = 10.411,
/// b = 1.7397, 95 % bounds a 7.974..13.594, b 1.2667..2.3893 — maximum
/// likelihood with Fisher bounds on the log scale. Checked to the printed digits.
#[test]
fn published_complete_example_wblfit() {
    let x = [
        13.22, 9.41, 8.58, 7.98, 4.12, 16.1, 5.62, 2.28, 9.69, 28.2, 13.84, 5.62, 5.26, 6.91, 8.92,
        9.07, 9.83, 1.86, 12.66, 5.44,
    ];
    let f = fit(&complete(&x), &mle()).expect("fits");
    printed(f.alpha.value, 10.411, 3);
    printed(f.beta.value, 1.7397, 4);
    let (lo, hi) = f.alpha.fisher95.unwrap();
    printed(lo, 7.974, 3);
    printed(hi, 13.594, 3);
    let (lo, hi) = f.beta.fisher95.unwrap();
    printed(lo, 1.2667, 4);
    printed(hi, 2.3893, 4);
}

/// NAG Library g07bef/g07bec example (support.nag.com, "nag_univar_estim_weibull
/// example program results"): 20 complete values, in NAG's form
/// f = λγx^(γ−1)exp(−λx^γ): γ (our β) = 2.7870 ± 0.4273, ln λ = −β ln α = −2.1073
/// ± 0.4627 (standard errors from the observed information). To the printed digits.
#[test]
fn published_example_nag_with_standard_errors() {
    let x = [
        1.1, 1.4, 1.3, 1.7, 1.9, 1.8, 1.6, 2.2, 1.7, 2.7, 4.1, 1.8, 1.5, 1.2, 1.4, 3.0, 1.7, 2.3,
        1.6, 2.0,
    ];
    let f = fit(&complete(&x), &mle()).expect("fits");
    let b = f.beta.value;
    let u = f.alpha.value.ln();
    printed(b, 2.7870, 4);
    printed(f.beta.std_error.unwrap(), 0.4273, 4);
    printed(-b * u, -2.1073, 4);
    // σ of ln λ = −βu by the delta method from σ_u = σ_α/α, σ_β and their correlation.
    let su = f.alpha.std_error.unwrap() / f.alpha.value;
    let sb = f.beta.std_error.unwrap();
    let rho = f.correlation.as_ref().unwrap()[0][1];
    let var = b * b * su * su + u * u * sb * sb + 2.0 * b * u * rho * su * sb;
    printed(var.sqrt(), 0.4627, 4);
}

/// A right-censored published example (MATLAB `wblfit(data, 0.05, censoring)`,
/// blog.csdn.net/weixin_30134145/article/details/115929233): ten specimens on test
/// for 70 h, six failures at 10, 20, 35, 52, 56, 63 and four survivors at 70:
/// a = 74.6426, b = 1.6194, bounds a 44.5897..124.9509, b 0.7795..3.3645 (Fisher,
/// log scale). To the printed digits, except α's bounds to two units of the last
/// digit: MATLAB prints 44.5897 and 124.9509 where the converged values are
/// 44.589643 and 124.951057 (the `reliability` package agrees with us to 1e-8), a
/// difference of ≤ 1.3·10⁻⁶ relative — the stopping tolerance of MATLAB's iteration.
#[test]
fn published_censored_example() {
    let mut s = complete(&[10.0, 20.0, 35.0, 52.0, 56.0, 63.0]);
    s.extend((0..4).map(|_| Specimen::new(70.0, true)));
    let f = fit(&s, &mle()).expect("fits");
    assert_eq!((f.n, f.failures, f.survived), (10, 6, 4));
    printed(f.alpha.value, 74.6426, 4);
    printed(f.beta.value, 1.6194, 4);
    let (lo, hi) = f.alpha.fisher95.unwrap();
    within_units(lo, 44.5897, 4, 2.0);
    within_units(hi, 124.9509, 4, 2.0);
    let (lo, hi) = f.beta.fisher95.unwrap();
    printed(lo, 0.7795, 4);
    printed(hi, 3.3645, 4);
    // Censored: Ross's factor with r = 6 breakdowns, and it says so.
    let bu = f.beta_unbiased.unwrap();
    assert!((bu - f.beta.value * 4.0 / 5.32).abs() < 1e-12);
    assert!(f.beta_unbiased_method.contains("r the breakdowns"));
}

/// Weibull sample: E = α(−ln U)^(1/β).
fn sample(rng: &mut ChaCha8Rng, alpha: f64, beta: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|_| alpha * (-(1.0 - rng.gen::<f64>()).ln()).powf(1.0 / beta))
        .collect()
}

/// The likelihood-ratio bounds of β are where the profile likelihood is χ²₁/2
/// below its maximum: checked with an independent profile (for fixed β the
/// maximising α has the closed form α^β = Σ E_i^β / r, complete data), to 1e-7.
#[test]
fn lr_bounds_of_beta_are_at_the_chi_square_level() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let x = sample(&mut rng, 30e6, 8.0, 12);
    let f = fit(&complete(&x), &mle()).expect("fits");
    let ll = |b: f64| {
        let n = x.len() as f64;
        let ab = x.iter().map(|e| e.powf(b)).sum::<f64>() / n;
        let a = ab.powf(1.0 / b);
        x.iter()
            .map(|e| b.ln() - a.ln() + (b - 1.0) * (e / a).ln() - (e / a).powf(b))
            .sum::<f64>()
    };
    let top = ll(f.beta.value);
    assert!((top - f.log_likelihood).abs() < 1e-7 * top.abs());
    let (lo, hi) = f.beta.lr95.expect("LR bounds");
    for b in [lo, hi] {
        assert!((top - ll(b) - CHI2_1_95 / 2.0).abs() < 1e-7, "{b}");
    }
    // Small series: the table shows the LR bounds, and says so.
    assert_eq!(f.bounds, BoundKind::LikelihoodRatio);
}

/// The three plotting positions give different rank-regression β (Bernard and the
/// exact median rank agree to ≈ 10⁻³ relative, as Bernard's approximation is
/// meant to; ieee930 moves β by more than 1 %, the "second digit"), and
/// rrx differs from rry.
#[test]
fn plotting_positions_move_beta() {
    let x = [
        22.1e6, 24.0e6, 25.3e6, 26.0e6, 27.2e6, 27.9e6, 28.8e6, 29.5e6, 30.7e6, 32.0e6,
    ];
    let mut betas = Vec::new();
    for method in [Method::Rry, Method::Rrx] {
        for positions in Positions::ALL {
            let s = Settings {
                method,
                positions: *positions,
                ..Settings::default()
            };
            let f = fit(&complete(&x), &s).expect("fits");
            assert_eq!(f.positions, Some(*positions));
            assert!(f.alpha.fisher95.is_some() && f.alpha.lr95.is_none());
            betas.push(f.beta.value);
        }
    }
    for i in 0..betas.len() {
        for j in 0..i {
            let rel = (betas[i] - betas[j]).abs() / betas[j];
            assert!(rel > 2e-4, "β {} and {} agree", betas[i], betas[j]);
        }
    }
    // Bernard against ieee930 under rry: different in the second significant digit.
    assert!((betas[0] - betas[2]).abs() > 0.01 * betas[0]);
}

/// Refusals: too few breakdowns, all survived, non-positive and non-finite fields,
/// one field for every breakdown, a constant covariate — errors, never panics.
#[test]
fn bad_series_are_refused() {
    let s = Settings::default();
    let one = vec![Specimen::new(20e6, false), Specimen::new(25e6, true)];
    assert_eq!(
        fit(&one, &s).unwrap_err(),
        WeibullError::TooFewBreakdowns { failures: 1 }
    );
    let none = vec![Specimen::new(20e6, true); 3];
    assert_eq!(
        fit(&none, &s).unwrap_err(),
        WeibullError::AllSurvived { n: 3 }
    );
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut v = complete(&[20e6, 21e6, 22e6]);
        v[1].field = bad;
        let e = fit(&v, &s).unwrap_err();
        assert_eq!(e.specimen(), Some(1), "{e}");
    }
    let tied = complete(&[20e6, 20e6, 20e6]);
    let e = fit(&tied, &s).unwrap_err();
    assert!(
        matches!(e, WeibullError::Degenerate { failures: 3, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("degenerate"));
    let mut v = complete(&[20e6, 21e6, 22e6, 23e6]);
    for x in v.iter_mut() {
        x.thickness = Some(100e-6);
    }
    let cov = Settings {
        covariates: vec![Covariate::Thickness],
        ..Settings::default()
    };
    assert!(matches!(
        fit(&v, &cov).unwrap_err(),
        WeibullError::ConstantCovariate {
            covariate: Covariate::Thickness,
            ..
        }
    ));
    // The crate error carries a hint.
    let err: dea_fit::Error = WeibullError::AllSurvived { n: 3 }.into();
    assert!(err.to_string().contains("hint"));
}

/// The reference series and the `reliability` package's fits of them
/// (.ci/weibull-reference.sh writes datasets/breakdown/reference/reliability.json).
fn reference_series(name: &str) -> Vec<Specimen> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/breakdown/reference");
    let text = std::fs::read_to_string(dir.join(name)).expect("reference series");
    text.lines()
        .skip(1)
        .map(|l| {
            let (e, s) = l.split_once(',').expect("two columns");
            Specimen::new(e.parse::<f64>().expect("field") * 1e6, s.trim() == "1")
        })
        .collect()
}

/// dea-fit against the independent implementation, like with like (conventions in
/// .ci/weibull_reference.py): MLE, RRX and RRY (Bernard positions, Johnson's
/// adjusted ranks for the survivors) on a complete, a censored (survivors at the
/// rig's limit and one mid-series) and a small series; α, β, their standard
/// errors, Fisher bounds and ℓ.
/// Tolerances: rank regression is closed form, so its α and β agree to 1e-8
/// (the JSON keeps ten digits), and its σ and bounds (reliability's autograd
/// Hessian at the same point) to 2e-5. The MLE to 1e-4 relative, its σ and bounds
/// to 5e-4: reliability's optimizer (L-BFGS-B) stops early — on complete-20 its
/// β = 8.267244 where the root of the profile score is 8.266896 (scipy's brentq
/// to 1e-14 agrees with ours to 1e-13), ℓ 3·10⁻⁸ below the maximum; σ moves with
/// the estimate at first order. ℓ to 1e-7 relative.
#[test]
fn agrees_with_the_reliability_package() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/breakdown/reference");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("reliability.json")).unwrap())
            .unwrap();
    let series = json["series"].as_object().expect("series");
    assert!(series.len() >= 3);
    let mut compared = 0;
    for (name, refs) in series {
        let specimens = reference_series(name);
        assert_eq!(specimens.len() as u64, refs["n"].as_u64().unwrap());
        for (method, key) in [
            (Method::Mle, "mle"),
            (Method::Rrx, "rrx"),
            (Method::Rry, "rry"),
        ] {
            let r = &refs[key];
            let s = Settings {
                method,
                ..Settings::default()
            };
            let f = fit(&specimens, &s).expect("fits");
            let (tol_est, tol_se) = if method == Method::Mle {
                (1e-4, 5e-4)
            } else {
                (1e-8, 2e-5)
            };
            let close = |ours: f64, theirs: &serde_json::Value, tol: f64, what: &str| {
                let theirs = theirs.as_f64().unwrap();
                assert!(
                    (ours - theirs).abs() <= tol * theirs.abs(),
                    "{name} {key} {what}: {ours} vs reliability {theirs}"
                );
            };
            close(f.alpha.value / 1e6, &r["alpha"], tol_est, "alpha");
            close(f.beta.value, &r["beta"], tol_est, "beta");
            close(
                f.alpha.std_error.unwrap() / 1e6,
                &r["alpha_se"],
                tol_se,
                "alpha σ",
            );
            close(f.beta.std_error.unwrap(), &r["beta_se"], tol_se, "beta σ");
            let (lo, hi) = f.alpha.fisher95.unwrap();
            close(lo / 1e6, &r["alpha_ci95"][0], tol_se, "alpha lower");
            close(hi / 1e6, &r["alpha_ci95"][1], tol_se, "alpha upper");
            let (lo, hi) = f.beta.fisher95.unwrap();
            close(lo, &r["beta_ci95"][0], tol_se, "beta lower");
            close(hi, &r["beta_ci95"][1], tol_se, "beta upper");
            // ℓ of the fields in V/µm = ℓ in V/m + r·ln 10⁶.
            let ll = f.log_likelihood + f.failures as f64 * 1e6f64.ln();
            close(ll, &r["log_likelihood"], 1e-7, "log-likelihood");
            compared += 1;
        }
    }
    assert_eq!(compared, 3 * series.len());
}

/// Coverage of the 95 % bounds over 400 replicates of 15 specimens (α = 30 V/µm,
/// β = 8), complete and Type-I censored at 33 V/µm (≈ 12 % survivors): the
/// likelihood-ratio bounds of α and β cover the truth in 91.2–98.8 % of the
/// replicates (95 % ± 3.5 binomial standard deviations, √(0.95·0.05/400) = 1.09 %);
/// Fisher's, known to be too narrow at this size, at least 85 %. The mean of
/// Ross's unbiased β is within 4 standard errors of the mean of 8 for complete
/// data (the plain MLE is 10 % high at n = 15, so this fails without the factor).
#[test]
fn bounds_cover_the_truth() {
    let (alpha, beta, n, reps) = (30e6, 8.0, 15, 400);
    for limit in [None, Some(33e6)] {
        let mut rng = ChaCha8Rng::seed_from_u64(33);
        let mut cover = [0usize; 4];
        let mut unbiased = Vec::new();
        for _ in 0..reps {
            let specimens: Vec<Specimen> = sample(&mut rng, alpha, beta, n)
                .into_iter()
                .map(|e| match limit {
                    Some(l) if e > l => Specimen::new(l, true),
                    _ => Specimen::new(e, false),
                })
                .collect();
            let Ok(f) = fit(&specimens, &mle()) else {
                continue;
            };
            let inside =
                |b: Option<(f64, f64)>, v: f64| b.is_some_and(|(lo, hi)| lo <= v && v <= hi);
            cover[0] += usize::from(inside(f.alpha.lr95, alpha));
            cover[1] += usize::from(inside(f.beta.lr95, beta));
            cover[2] += usize::from(inside(f.alpha.fisher95, alpha));
            cover[3] += usize::from(inside(f.beta.fisher95, beta));
            unbiased.push(f.beta_unbiased.unwrap());
        }
        let rate = cover.map(|c| c as f64 / reps as f64);
        for (what, r) in [("α LR", rate[0]), ("β LR", rate[1])] {
            assert!(
                (0.912..=0.988).contains(&r),
                "{limit:?} {what} coverage {r}"
            );
        }
        for (what, r) in [("α Fisher", rate[2]), ("β Fisher", rate[3])] {
            assert!(r >= 0.85, "{limit:?} {what} coverage {r}");
        }
        if limit.is_none() {
            let m = unbiased.iter().sum::<f64>() / unbiased.len() as f64;
            let sd = (unbiased.iter().map(|b| (b - m).powi(2)).sum::<f64>()
                / (unbiased.len() - 1) as f64)
                .sqrt();
            let se = sd / (unbiased.len() as f64).sqrt();
            assert!((m - beta).abs() < 4.0 * se, "mean unbiased β {m} ± {se}");
        }
    }
}

/// A large censored series recovers α and β within 4 of its own standard errors,
/// and the percentile E_1 % with them (synthetic, 3000 specimens, 20 % survivors
/// at the rig's limit).
#[test]
fn large_censored_series_recovers_the_law() {
    let (alpha, beta) = (40e6, 12.0);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let limit = alpha * (-(0.2f64).ln()).powf(1.0 / beta); // F(limit) = 0.8
    let specimens: Vec<Specimen> = sample(&mut rng, alpha, beta, 3000)
        .into_iter()
        .map(|e| Specimen::new(e.min(limit), e > limit))
        .collect();
    let all = Settings {
        all_lr_bounds: true,
        ..mle()
    };
    let f = fit(&specimens, &all).expect("fits");
    assert!((f.survived as f64 / 3000.0 - 0.2).abs() < 0.03);
    // Without asking, LR bounds are not computed where the table shows Fisher's.
    assert_eq!(fit(&specimens, &mle()).expect("fits").beta.lr95, None);
    let within = |est: &dea_fit::fit::weibull::Estimate, truth: f64| {
        let s = est.std_error.unwrap();
        assert!(
            (est.value - truth).abs() < 4.0 * s,
            "{} vs {truth} (σ {s})",
            est.value
        );
    };
    within(&f.alpha, alpha);
    within(&f.beta, beta);
    let e1 = f.percentile(0.01, None).unwrap();
    within(&e1.estimate, alpha * (-(0.99f64).ln()).powf(1.0 / beta));
    // Large n: the table shows Fisher bounds, and they agree with LR's to 2 % of the width.
    assert_eq!(f.bounds, BoundKind::Fisher);
    let (fl, fh) = f.beta.fisher95.unwrap();
    let (ll, lh) = f.beta.lr95.unwrap();
    assert!((fl - ll).abs() < 0.02 * (fh - fl) && (fh - lh).abs() < 0.02 * (fh - fl));
}

/// Area scaling (weakest link): the percentile at an electrode area A equals the
/// core's law scaled from A₀ to A, α·(A₀/A)^(1/β)·(−ln(1 − p))^(1/β); α at A is
/// the 63.2 % percentile there; and fitting the same series with another reference
/// area A₀' gives α' = α·(A₀/A₀')^(1/β) and the same β (1e-9).
#[test]
fn area_scaling_is_the_weakest_link_law() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let a0 = 1e-4; // 1 cm²
    let specimens: Vec<Specimen> = sample(&mut rng, 30e6, 9.0, 20)
        .into_iter()
        .map(|e| Specimen {
            area: Some(a0),
            ..Specimen::new(e, false)
        })
        .collect();
    let f = fit(&specimens, &mle()).expect("fits");
    assert_eq!(f.reference_area, Some(a0));
    let big = 40e-4;
    for p in [0.01, 0.1, 0.632] {
        let at = f.percentile(p, Some(big)).unwrap();
        let core = f.law().scaled(a0, big).percentile(p);
        assert!((at.estimate.value - core).abs() < 1e-9 * core, "{p}");
        assert_eq!(at.area, Some(big));
        let (lo, hi) = at.estimate.lr95.unwrap();
        assert!(lo < core && core < hi);
    }
    let alpha_big = f.alpha_at(big).unwrap().estimate.value;
    let want = f.alpha.value * (a0 / big).powf(1.0 / f.beta.value);
    assert!((alpha_big - want).abs() < 1e-9 * want);
    let g = fit(
        &specimens,
        &Settings {
            reference_area: Some(big),
            ..Settings::default()
        },
    )
    .expect("fits");
    assert!((g.beta.value - f.beta.value).abs() < 1e-9 * f.beta.value);
    assert!((g.alpha.value - want).abs() < 1e-9 * want);
    // The bounds of α at A₀' are those of the 63.2 % percentile at A₀' of the
    // first fit (not α's scaled by a fixed factor: β is uncertain), to 1e-7.
    let (lo, hi) = f.alpha_at(big).unwrap().estimate.lr95.unwrap();
    let (glo, ghi) = g.alpha.lr95.unwrap();
    assert!((glo - lo).abs() < 1e-7 * glo && (ghi - hi).abs() < 1e-7 * ghi);
    // Without areas in the series, another area is refused (not guessed).
    let bare = fit(&complete(&[20e6, 22e6, 25e6]), &mle()).unwrap();
    assert!(bare.percentile(0.1, Some(1e-3)).is_err());
}

/// Specimens of two electrode areas (1 and 10 cm²) drawn from one law by the
/// weakest link: the exposure-weighted MLE recovers α at the stated reference area
/// and β within 4σ (600 specimens).
#[test]
fn mixed_areas_enter_as_exposure() {
    let (alpha, beta, a0): (f64, f64, f64) = (30e6, 10.0, 1e-4);
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut specimens = Vec::new();
    for area in [a0, 10.0 * a0] {
        let alpha_a = alpha * (a0 / area).powf(1.0 / beta);
        for e in sample(&mut rng, alpha_a, beta, 300) {
            specimens.push(Specimen {
                area: Some(area),
                ..Specimen::new(e, false)
            });
        }
    }
    let s = Settings {
        reference_area: Some(a0),
        ..Settings::default()
    };
    let f = fit(&specimens, &s).expect("fits");
    for (est, truth) in [(f.alpha, alpha), (f.beta, beta)] {
        assert!(
            (est.value - truth).abs() < 4.0 * est.std_error.unwrap(),
            "{} vs {truth}",
            est.value
        );
    }
    // Rank regression pools ranks: mixed areas are refused for it.
    let rr = Settings {
        method: Method::Rrx,
        ..s.clone()
    };
    assert!(matches!(
        fit(&specimens, &rr),
        Err(WeibullError::Unsupported(_))
    ));
    // Without a reference area the median area is used, and said.
    let g = fit(&specimens, &mle()).expect("fits");
    assert!(g.warnings.iter().any(|w| w.contains("median area")));
}

/// Ties (a stepped ramp): the fit does not depend on the order of the rows; tied
/// breakdowns take consecutive ranks; a survivor at a breakdown's field ranks after
/// it (it outlasted the breakdown).
#[test]
fn ties_are_normal() {
    let fields = [20e6, 22e6, 22e6, 22e6, 24e6, 24e6, 26e6, 28e6, 28e6, 30e6];
    let mut s = complete(&fields);
    s.push(Specimen::new(24e6, true));
    let f = fit(&s, &mle()).expect("fits");
    let mut r = s.clone();
    r.reverse();
    let g = fit(&r, &mle()).expect("fits");
    assert!((f.alpha.value - g.alpha.value).abs() < 1e-12 * f.alpha.value);
    assert!((f.beta.value - g.beta.value).abs() < 1e-9 * f.beta.value);
    let probs: Vec<Option<f64>> = f.plot.iter().map(|p| p.probability).collect();
    // Order: 20, 22×3, 24×2 then the survivor at 24, 26, 28×2, 30.
    assert!(probs[6].is_none() && f.plot[6].survived);
    let ranks: Vec<f64> = probs.iter().flatten().map(|p| p * 11.4 + 0.3).collect();
    for k in 0..6 {
        assert!((ranks[k] - (k as f64 + 1.0)).abs() < 1e-12);
    }
    // After the survivor: 6 + (12 − 6)/(11 − 8 + 2) = 7.2.
    assert!((ranks[6] - 7.2).abs() < 1e-12, "{}", ranks[6]);
}

/// The threshold fit recovers γ of a shifted series within 4σ and says what it
/// did; on a series with β < 1 and no threshold the likelihood has no finite
/// maximum in γ, which is reported as ill-posed, never silently used.
#[test]
fn threshold_fit_and_its_instability() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let gamma = 15e6;
    let x: Vec<f64> = sample(&mut rng, 10e6, 2.5, 400)
        .iter()
        .map(|e| e + gamma)
        .collect();
    let s = Settings {
        threshold: true,
        ..Settings::default()
    };
    let f = fit(&complete(&x), &s).expect("fits");
    let g = f.threshold.expect("a threshold");
    assert!(
        (g.value - gamma).abs() < 4.0 * g.std_error.unwrap(),
        "γ {} ± {:?}",
        g.value,
        g.std_error
    );
    assert!((f.beta.value - 2.5).abs() < 4.0 * f.beta.std_error.unwrap());
    assert!(f.warnings.iter().any(|w| w.contains("three-parameter")));
    assert!(f.beta.lr95.is_none() && f.bounds == BoundKind::Fisher);
    let p = f.percentile(0.5, None).unwrap().estimate.value;
    assert!((f.cdf(p) - 0.5).abs() < 1e-9);
    let y = sample(&mut rng, 30e6, 0.7, 40);
    let f = fit(&complete(&y), &s).expect("fits");
    assert_eq!(f.status, dea_fit::fit::Status::IllPosed, "{:?}", f.warnings);
    assert!(f.warnings.iter().any(|w| w.contains("not estimable")));
    // Not for rank regression.
    let rr = Settings {
        method: Method::Rry,
        ..s
    };
    assert!(fit(&complete(&x), &rr).is_err());
}

/// Covariates: α = C·h^a·λ^b with a common β, from 3 thicknesses × 2 prestretches
/// (a = −0.4, b = 1.0, 600 specimens): both exponents within 4σ, α at the
/// reference (geometric-mean) thickness and prestretch within 4σ of the law's
/// value there; LR bounds of each exponent contain it.
#[test]
fn covariates_recover_the_exponents() {
    let (c, a, b, beta) = (30e6, -0.4, 1.0, 9.0);
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mut specimens = Vec::new();
    for h in [50e-6, 100e-6, 200e-6] {
        for l in [1.0, 3.0] {
            let alpha = c * (h / 100e-6f64).powf(a) * f64::powf(l, b);
            for e in sample(&mut rng, alpha, beta, 100) {
                specimens.push(Specimen {
                    thickness: Some(h),
                    prestretch: Some(l),
                    ..Specimen::new(e, false)
                });
            }
        }
    }
    let s = Settings {
        covariates: vec![Covariate::Thickness, Covariate::Prestretch],
        all_lr_bounds: true,
        ..Settings::default()
    };
    let f = fit(&specimens, &s).expect("fits");
    assert_eq!(f.exponents.len(), 2);
    assert_eq!(
        f.parameter_names,
        ["alpha", "beta", "thickness", "prestretch"]
    );
    for (x, truth) in f.exponents.iter().zip([a, b]) {
        let e = x.estimate;
        assert!(
            (e.value - truth).abs() < 4.0 * e.std_error.unwrap(),
            "{:?}: {}",
            x.covariate,
            e.value
        );
        let (lo, hi) = e.lr95.expect("LR bounds");
        assert!(lo < e.value && e.value < hi);
    }
    let h_ref = f.exponents[0].reference;
    let l_ref = f.exponents[1].reference;
    assert!((h_ref - 100e-6).abs() < 1e-12, "{h_ref}");
    let alpha_ref = c * (h_ref / 100e-6).powf(a) * l_ref.powf(b);
    assert!((f.alpha.value - alpha_ref).abs() < 4.0 * f.alpha.std_error.unwrap());
    // A covariate missing on a row is named by its row.
    let mut m = specimens.clone();
    m[5].prestretch = None;
    assert_eq!(fit(&m, &s).unwrap_err().specimen(), Some(5));
}

/// Goodness of fit: the Anderson–Darling test rejects a bent plot (two
/// populations, α 20 and 40 V/µm) with a warning; its size at the 5 % critical
/// value is 5 % over 400 Weibull replicates of 20 (within 1.5–8.5 %: ± 3.2
/// binomial standard deviations), which checks the table's constant with
/// Stephens' modification.
#[test]
fn goodness_of_fit_flags_a_bent_plot() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let mut x = sample(&mut rng, 20e6, 10.0, 20);
    x.extend(sample(&mut rng, 40e6, 10.0, 20));
    let f = fit(&complete(&x), &mle()).expect("fits");
    let g = f.goodness.as_ref().expect("a test");
    assert!(!g.straight, "A* = {}", g.statistic);
    assert!(f.warnings.iter().any(|w| w.contains("not straight")));
    assert_eq!(f.status, dea_fit::fit::Status::Warning);
    let mut rejected = 0;
    for _ in 0..400 {
        let y = sample(&mut rng, 30e6, 8.0, 20);
        let f = fit(&complete(&y), &mle()).expect("fits");
        rejected += usize::from(!f.goodness.unwrap().straight);
    }
    let size = rejected as f64 / 400.0;
    assert!((0.015..=0.085).contains(&size), "size {size}");
}

/// Fewer than ten specimens: a warning with the width of β's interval.
#[test]
fn small_series_warn_with_the_width_of_beta() {
    let f = fit(&complete(&[22e6, 24e6, 25e6, 27e6, 28e6, 30e6]), &mle()).expect("fits");
    let w = f
        .warnings
        .iter()
        .find(|w| w.contains("only 6 specimens"))
        .expect("warned");
    assert!(
        w.contains("β's 95 % interval") && w.contains("likelihood-ratio"),
        "{w}"
    );
}

/// A censored series counts its breakdowns: 15 specimens of which 10 survived at
/// the rig's limit carry the information of 5 breakdowns, and are warned so
/// (status warning), while 15 with 12 breakdowns are not.
#[test]
fn heavily_censored_series_warn_by_their_breakdowns() {
    let fields = [22e6, 24e6, 25e6, 27e6, 28e6];
    let mut specimens = complete(&fields);
    specimens.extend((0..10).map(|_| Specimen::new(29e6, true)));
    let f = fit(&specimens, &mle()).expect("fits");
    assert!(
        f.warnings
            .iter()
            .any(|w| w.contains("only 5 breakdowns (15 specimens, 10 survived")),
        "{:?}",
        f.warnings
    );
    assert_eq!(f.status, dea_fit::fit::Status::Warning);
    let mut many = complete(&[
        20e6, 21e6, 22e6, 23e6, 24e6, 25e6, 26e6, 26.5e6, 27e6, 27.5e6, 28e6, 28.5e6,
    ]);
    many.extend((0..3).map(|_| Specimen::new(29e6, true)));
    let g = fit(&many, &mle()).expect("fits");
    assert!(
        !g.warnings.iter().any(|w| w.contains("only")),
        "{:?}",
        g.warnings
    );
}
