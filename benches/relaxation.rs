//! Criterion benches of the relaxation estimator on the seed's Table 3.3 curve
//! (200 log-spaced points over 0.01–1000 s, step to strain 0.5, 1 % noise, seed 4910):
//! a 4-term fit (refined and grid-only), the automatic term count, and the exact
//! hereditary recursion against the naive closed form per point; the grid NNLS stage
//! (200 points × 37 columns: E∞ and 36 τ at 6 per decade) by Lawson–Hanson against
//! the Clarabel QP it replaced, in the same run. And the frequency-domain Prony fit
//! (`fit::prony::frequency`) of a DMA master curve the size of issue 36's "Speed"
//! target: 21 isotherms × 10 points (0.01–100 Hz each, shifted a decade apart:
//! 210 points over 24 decades) of a 12-term series with E∞ > 0, 1 % noise; a
//! 30-term fit on the grid (NNLS at 30 τ from the grid spectrum) and the automatic
//! choice (up to 12 terms, refined).

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::fit::linear::constrained_least_squares;
use dea_fit::fit::nnls::nnls;
use dea_fit::fit::relaxation::{self, Loading, Method, Settings};
use dea_fit::io::relaxation::{from_table, log_times, RelaxationOptions, Synthetic};
use dea_fit::io::table::Table;
use dea_fit::material::viscoelastic::{preset, History, Schedule};
use nalgebra::{DMatrix, DVector};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let syn = Synthetic {
        prony: preset("elatrache2021-table-3.3").unwrap().prony,
        strain: 0.5,
        ramp_time: None,
        times: log_times(0.01, 1000.0, 200, false),
        noise: 0.01,
        seed: 4910,
        record_strain: false,
    };
    let csv = syn.csv(&["bench"]).unwrap();
    let data = from_table(
        &Table::parse(Path::new("bench.csv"), csv.as_bytes()).unwrap(),
        &RelaxationOptions::default(),
    )
    .unwrap();
    let loading = Loading {
        strain: Some(0.5),
        ramp_time: None,
    };
    let mut g = c.benchmark_group("relaxation");
    g.sample_size(30)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    for (name, settings) in [
        (
            "fit_200pts_4terms_refined",
            Settings {
                terms: Some(4),
                ..Settings::default()
            },
        ),
        (
            "fit_200pts_4terms_refined_1start",
            Settings {
                terms: Some(4),
                max_starts: 1,
                ..Settings::default()
            },
        ),
        (
            "fit_200pts_4terms_grid_only",
            Settings {
                terms: Some(4),
                method: Method::Grid,
                ..Settings::default()
            },
        ),
        ("fit_200pts_auto_0to6", Settings::default()),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| relaxation::fit(black_box(&data), &loading, None, &settings).unwrap())
        });
    }
    let times = log_times(0.01, 1000.0, 200, false);
    let sched = Schedule::new(&History::step(0.5), &times).unwrap();
    let mut h = vec![0.0; times.len()];
    let mut dh = vec![0.0; times.len()];
    g.bench_function("kernel_recursion_200pts_with_derivative", |b| {
        b.iter(|| sched.kernel(black_box(0.464), &mut h, Some(&mut dh)))
    });
    g.bench_function("kernel_naive_closed_form_200pts_with_derivative", |b| {
        b.iter(|| {
            let tau = black_box(0.464);
            for (k, &t) in times.iter().enumerate() {
                let e = (-t / tau).exp();
                h[k] = 0.5 * e;
                dh[k] = 0.5 * e * t / (tau * tau);
            }
        })
    });
    // The grid stage's problem: relaxation kernels at 36 log-spaced τ over the data's
    // window widened ×3 (0.0033–3000 s) and the constant E∞ column, the data's stress.
    let taus: Vec<f64> = (0..36)
        .map(|j| 10f64.powf((1.0 / 300.0f64).log10() + 6.0 * j as f64 / 35.0))
        .collect();
    let a = DMatrix::from_fn(times.len(), 37, |i, j| {
        if j == 0 {
            0.5
        } else {
            0.5 * (-times[i] / taus[j - 1]).exp()
        }
    });
    let b = DVector::from_iterator(times.len(), data.stress.iter().copied());
    let lh = nnls(&a, &b, None).unwrap();
    let qp = constrained_least_squares(&a, &b, &DMatrix::identity(37, 37)).unwrap();
    let cost = |x: &DVector<f64>| (&a * x - &b).norm_squared();
    assert!(cost(&lh.x) <= cost(&qp.x.map(|v| v.max(0.0))) * (1.0 + 1e-9));
    g.bench_function("nnls_200x37_lawson_hanson", |bch| {
        bch.iter(|| nnls(black_box(&a), &b, None).unwrap())
    });
    g.bench_function("nnls_200x37_clarabel", |bch| {
        bch.iter(|| {
            constrained_least_squares(black_box(&a), &b, &DMatrix::identity(37, 37)).unwrap()
        })
    });
    g.finish();
}

fn frequency(c: &mut Criterion) {
    use dea_fit::fit::prony::frequency::{fit, ComplexModulus, FrequencySettings};
    use dea_fit::fit::prony::{Method as PronyMethod, Search};
    use dea_fit::material::viscoelastic::Prony;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let terms: Vec<(f64, f64)> = (0..12)
        .map(|i| (1e-12 * 100f64.powi(i), 1e6 * 0.7f64.powi(i)))
        .collect();
    let truth = Prony::new(1e5, &terms).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(36);
    let noise = Normal::new(0.0, 0.01).unwrap();
    let (mut omega, mut storage, mut loss) = (Vec::new(), Vec::new(), Vec::new());
    for iso in 0..21 {
        for k in 0..10 {
            let hz = 0.01 * 10f64.powf(4.0 * k as f64 / 9.0) * 10f64.powi(iso - 10);
            let w = 2.0 * std::f64::consts::PI * hz;
            let (e1, e2) = truth.storage_loss(w);
            omega.push(w);
            storage.push(e1 * (1.0 + noise.sample(&mut rng)));
            loss.push(e2 * (1.0 + noise.sample(&mut rng)));
        }
    }
    let data = ComplexModulus {
        omega_rad_s: &omega,
        storage_pa: &storage,
        loss_pa: &loss,
        shifts: None,
    };
    let grid30 = FrequencySettings {
        search: Search {
            terms: Some(30),
            method: PronyMethod::Grid,
            ..Search::default()
        },
        ..FrequencySettings::default()
    };
    let auto = FrequencySettings {
        search: Search {
            max_terms: 12,
            ..Search::default()
        },
        ..FrequencySettings::default()
    };
    let mut g = c.benchmark_group("prony_frequency");
    g.measurement_time(Duration::from_secs(3));
    g.sample_size(10);
    g.bench_function("master_210_points_30_terms_grid", |b| {
        b.iter(|| fit(black_box(&data), &grid30).unwrap())
    });
    g.bench_function("master_210_points_auto_12", |b| {
        b.iter(|| fit(black_box(&data), &auto).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench, frequency);
criterion_main!(benches);
