//! Weibull bench: the maximum-likelihood fit of a 10⁴-specimen breakdown series
//! (docs/breakdown.md, "Performance": ≤ 5 ms in-process), complete and with 20 %
//! survivors at the rig's limit; everything `fit` computes (estimates,
//! information, Fisher bounds — likelihood-ratio bounds only below 100 breakdowns,
//! where the table shows them —, plot positions, goodness of fit) and the E_1 %
//! percentile with its bounds; and a 20-specimen series, likelihood-ratio bounds
//! included, as the command fits it.

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::fit::weibull::{fit, Settings, Specimen};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

fn series(n: usize, censored: bool) -> Vec<Specimen> {
    let (alpha, beta) = (30e6, 8.0);
    let limit = alpha * (-(0.2f64).ln()).powf(1.0 / beta);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    (0..n)
        .map(|_| {
            let e = alpha * (-(1.0 - rng.gen::<f64>()).ln()).powf(1.0 / beta);
            match censored && e > limit {
                true => Specimen::new(limit, true),
                false => Specimen::new(e, false),
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let settings = Settings::default();
    for (name, censored) in [("complete", false), ("censored", true)] {
        let s = series(10_000, censored);
        c.bench_function(&format!("weibull mle 10^4 specimens, {name}"), |b| {
            b.iter(|| {
                let f = fit(black_box(&s), &settings).expect("fits");
                f.percentile(0.01, None).expect("percentile")
            })
        });
    }
    let small = series(20, true);
    c.bench_function("weibull mle 20 specimens, censored, LR bounds", |b| {
        b.iter(|| {
            let f = fit(black_box(&small), &settings).expect("fits");
            f.percentile(0.01, None).expect("percentile")
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
