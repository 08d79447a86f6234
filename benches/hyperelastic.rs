//! Criterion benches of the hyperelastic estimator (`cargo bench --bench hyperelastic`).
//!
//! * `fit/vhb4910-uniaxial/<model>`: a whole `fit` call (search and diagnostics) of
//!   every model on the shipped VHB 4910 uniaxial data.
//! * `fit/treloar-3modes/ogden3-{varpro,full}`: the classic hard case, Ogden-3 on
//!   Treloar's three modes, by variable projection and by the plain full-parameter
//!   LM baseline from the same starts.
//! * `search/vhb4910-uniaxial/yeoh-{qr,svd,lm}`: the search alone for Yeoh, the exact
//!   linear least-squares solve (row-block QR and the SVD of R, as `fit` runs it; the
//!   SVD of the whole design matrix it replaced) against the naive baseline of an
//!   iterative LM.
//! * `varpro/ogden3-100k/{row-qr,tall-svd}`: the linear solve inside one
//!   variable-projection evaluation of Ogden-3 at 10⁵ points (Treloar's fitted
//!   exponents, the stretch ranges of its three modes): the row-by-row QR and the
//!   SVD of its small R (`range_solve`, what the search runs) against the SVD of the
//!   tall basis it replaced (`svd_solve`), in the same run.
//! * `ogden3-100k/jacobian/{block,per-point}`: Ogden-3's Jacobian on 10⁵ points (as
//!   above) by the block evaluator (`StrainEnergy::stress_jacobians`: vector lanes,
//!   the logarithms given, what the fit problem runs) against the per-point method
//!   at every point, the same bits (asserted), in the same run.
//! * `varpro/treloar-ogden3/{one-evaluation,two-evaluations}`: one variable-projection
//!   search of Ogden-3 on Treloar's three modes from one start, with ∂A/∂θ taken
//!   from the model evaluation that gives A(θ) (`StrainEnergy::coefficient_of`, what
//!   the search runs) against a second model evaluation at every accepted point (the
//!   model's `coefficient_of` hidden), in the same run.
//! * `drucker/<model>/{bounded,dense}`: the Drucker check of the fitted Yeoh
//!   (VHB 4910 uniaxial), of an unstable Yeoh and of the Ogden-3 Treloar fit, by
//!   bounds on grid cells (what `fit` runs) against the dense 3 × 801 sweep
//!   (the previous method) in the same run.
//! * `search/rosenbrock-2/lm`: the LM on a 2-parameter problem (some twenty
//!   iterations of microseconds), where the fixed cost of argmin's `Executor`
//!   around `Lm::step` shows (docs/architecture.md, "argmin: what it bought, what
//!   it cost").
//!
//! Sample settings are modest (10 flat samples, 1 s) so the whole run takes a
//! couple of minutes on a shared 2-core machine.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use dea_fit::bench::{shipped_datasets, NamedData, TRELOAR_ALL, VHB_UNIAXIAL};
use dea_fit::fit::drucker::{drucker, drucker_dense};
use dea_fit::fit::hyperelastic::{fit, Search, Settings};
use dea_fit::fit::lm::{self, LeastSquares, LmSettings};
use dea_fit::fit::problem::{range_solve, svd_solve, HyperProblem, Residual, VarPro};
use dea_fit::material::hyperelastic::{
    Mode, ModelSpec, Points, StrainEnergy, WithoutCoefficients, MODEL_NAMES,
};
use nalgebra::{DMatrix, DVector};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn data() -> Vec<NamedData> {
    shipped_datasets(&Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets"))
        .expect("the shipped datasets are readable")
}

fn get<'a>(sets: &'a [NamedData], name: &str) -> &'a NamedData {
    sets.iter().find(|d| d.name == name).expect("shipped set")
}

fn fits(c: &mut Criterion) {
    let sets = data();
    let vhb = &get(&sets, VHB_UNIAXIAL).data;
    let treloar = &get(&sets, TRELOAR_ALL).data;
    let base = Settings::default();
    let mut g = c.benchmark_group(format!("fit/{VHB_UNIAXIAL}"));
    g.sampling_mode(SamplingMode::Flat);
    for m in MODEL_NAMES {
        let spec = ModelSpec::new(m, base.ogden_form);
        g.bench_function(m, |b| {
            b.iter(|| fit(black_box(vhb), &spec, &base).expect("fit"))
        });
    }
    g.finish();

    let mut g = c.benchmark_group(format!("fit/{TRELOAR_ALL}"));
    g.sampling_mode(SamplingMode::Flat);
    let spec = ModelSpec::new("ogden3", base.ogden_form);
    for (label, method) in [
        ("ogden3-varpro", Search::VarPro),
        ("ogden3-full", Search::Full),
    ] {
        let s = Settings {
            method,
            ..base.clone()
        };
        g.bench_function(label, |b| {
            b.iter(|| fit(black_box(treloar), &spec, &s).expect("fit"))
        });
    }
    g.finish();
}

fn yeoh_search(c: &mut Criterion) {
    let sets = data();
    let vhb = &get(&sets, VHB_UNIAXIAL).data;
    let base = Settings::default();
    let model = ModelSpec::new("yeoh", base.ogden_form)
        .build()
        .expect("yeoh");
    let mut g = c.benchmark_group(format!("search/{VHB_UNIAXIAL}"));
    // Exact: the stress is linear in (C10, C20, C30): the factor of [A | b] built row
    // by row and the SVD of its 3 × 3 R (what the estimator does), against the SVD of
    // the whole design matrix (what it did), in the same run.
    g.bench_function("yeoh-qr", |b| {
        b.iter(|| {
            let prob = HyperProblem::new(model.as_ref(), black_box(vhb), base.residual);
            let k = prob.dims().1;
            prob.factor(&vec![0.0; k]).solve().expect("solvable")
        })
    });
    g.bench_function("yeoh-svd", |b| {
        b.iter(|| {
            let mut prob = HyperProblem::new(model.as_ref(), black_box(vhb), base.residual);
            let (n, k) = prob.dims();
            let mut a = DMatrix::zeros(n, k);
            prob.jacobian(&vec![0.0; k], &mut a);
            svd_solve(&a, &prob.scaled_targets()).expect("solvable")
        })
    });
    // Naive: bounded LM over the same three coefficients from a neo-Hookean-sized start.
    let bounds = model.bounds(0.0);
    let settings = LmSettings::default();
    // The baseline must reach the exact optimum, or the comparison means nothing.
    let mut prob = HyperProblem::new(model.as_ref(), vhb, base.residual);
    let naive = lm::minimize(&mut prob, &[1e5, 0.0, 0.0], &bounds, &settings);
    let (n, k) = prob.dims();
    let mut a = DMatrix::zeros(n, k);
    prob.jacobian(&vec![0.0; k], &mut a);
    let (c, _) = svd_solve(&a, &prob.scaled_targets()).expect("solvable");
    let exact = 0.5 * (&a * &c - prob.scaled_targets()).norm_squared();
    assert!(
        (naive.cost - exact).abs() <= 1e-8 * exact,
        "LM {} vs exact {exact}",
        naive.cost
    );
    g.bench_function("yeoh-lm", |b| {
        b.iter(|| {
            let mut prob = HyperProblem::new(model.as_ref(), black_box(vhb), base.residual);
            lm::minimize(&mut prob, &[1e5, 0.0, 0.0], &bounds, &settings)
        })
    });
    g.finish();
}

/// Ogden-3 at Treloar's fitted parameters (seed form) and 10⁵ points spread over
/// its three modes' stretch ranges: the model, p, and each point's mode and λ.
fn ogden3_100k() -> (Box<dyn StrainEnergy>, [f64; 6], Vec<Mode>, Vec<f64>) {
    let model = ModelSpec::new("ogden3", Default::default())
        .build()
        .expect("ogden3");
    let p = [7.33e3, -2.157, 3.382e5, 1.918, 3.139, 8.619];
    let ranges = [
        (Mode::Uniaxial, 7.61),
        (Mode::Equibiaxial, 4.44),
        (Mode::Planar, 4.96),
    ];
    let (n, per) = (100_002, 33_334);
    let modes = (0..n).map(|i| ranges[i / per].0).collect();
    let stretch = (0..n)
        .map(|i| 1.0 + (ranges[i / per].1 - 1.0) * (i % per) as f64 / (per - 1) as f64)
        .collect();
    (model, p, modes, stretch)
}

fn varpro_projection(c: &mut Criterion) {
    // Ogden-3's linear columns (the basis of μ1..μ3) at Treloar's fitted exponents,
    // 10⁵ points over its modes' stretch ranges.
    let (model, p, modes, stretch) = ogden3_100k();
    let n = modes.len();
    let mut row = [0.0; 6];
    let mut a = DMatrix::zeros(n, 3);
    let mut b = DVector::zeros(n);
    for i in 0..n {
        let (mode, lam) = (modes[i], stretch[i]);
        model.stress_jacobian(&p, mode, lam, &mut row);
        for j in 0..3 {
            a[(i, j)] = row[2 * j];
        }
        b[i] = model.nominal_stress(&p, mode, lam) * (1.0 + 0.01 * (i as f64).sin());
    }
    let mut g = c.benchmark_group("varpro/ogden3-100k");
    g.sampling_mode(SamplingMode::Flat);
    g.bench_function("row-qr", |bch| {
        bch.iter(|| range_solve(black_box(&a), &b).expect("solvable"))
    });
    g.bench_function("tall-svd", |bch| {
        bch.iter(|| svd_solve(black_box(&a), &b).expect("solvable"))
    });
    g.finish();
}

fn ogden_blocks(c: &mut Criterion) {
    // Ogden-3's Jacobian at Treloar's fitted parameters on 10⁵ points over its
    // modes' stretch ranges: the block evaluator (vector lanes, ln λ given) against
    // the per-point method (ln λ and the lane arithmetic one point at a time), the
    // same bits (asserted), in the same run.
    let (model, p, modes, stretch) = ogden3_100k();
    let n = modes.len();
    let ln: Vec<f64> = stretch.iter().map(|l| l.ln()).collect();
    let pts = Points::new(&modes, &stretch, &ln).expect("one length");
    let (mut block, mut single) = (vec![0.0; 6 * n], vec![0.0; 6 * n]);
    let per_point = |out: &mut [f64]| {
        for (i, row) in out.chunks_exact_mut(6).enumerate() {
            model.stress_jacobian(&p, modes[i], stretch[i], row);
        }
    };
    model.stress_jacobians(&p, pts, &mut block);
    per_point(&mut single);
    assert!(block
        .iter()
        .zip(&single)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    let mut g = c.benchmark_group("ogden3-100k/jacobian");
    g.sampling_mode(SamplingMode::Flat);
    g.bench_function("block", |bch| {
        bch.iter(|| model.stress_jacobians(black_box(&p), pts, &mut block))
    });
    g.bench_function("per-point", |bch| bch.iter(|| per_point(&mut single)));
    g.finish();
}

fn varpro_search(c: &mut Criterion) {
    let sets = data();
    let treloar = &get(&sets, TRELOAR_ALL).data;
    let build = || {
        ModelSpec::new("ogden3", Default::default())
            .build()
            .expect("ogden3")
    };
    let one = build();
    let two = WithoutCoefficients(build());
    let start = [1.0, 1.5, 1.0, 5.0, 1.0, -2.0];
    let settings = LmSettings::default();
    let search = |model: &dyn StrainEnergy| {
        let mut prob = HyperProblem::new(model, treloar, Residual::Abs);
        let bounds = model.bounds(prob.max_i1_minus_3());
        let mut vp = VarPro::new(&mut prob, &start);
        let nonlin = vp.nonlinear().to_vec();
        let theta: Vec<f64> = nonlin.iter().map(|&j| start[j]).collect();
        let b: Vec<(f64, f64)> = nonlin.iter().map(|&j| bounds[j]).collect();
        lm::minimize(&mut vp, &theta, &b, &settings)
    };
    let (a, b) = (search(one.as_ref()), search(&two));
    assert!(
        (a.cost - b.cost).abs() <= 1e-9 * b.cost,
        "{} vs {}",
        a.cost,
        b.cost
    );
    let mut g = c.benchmark_group("varpro/treloar-ogden3");
    g.sampling_mode(SamplingMode::Flat);
    g.bench_function("one-evaluation", |bch| {
        bch.iter(|| search(black_box(one.as_ref())))
    });
    g.bench_function("two-evaluations", |bch| {
        bch.iter(|| search(black_box(&two)))
    });
    g.finish();
}

fn drucker_checks(c: &mut Criterion) {
    let sets = data();
    let base = Settings::default();
    let fitted = |set: &str, m: &str| {
        let spec = ModelSpec::new(m, base.ogden_form);
        let f = fit(&get(&sets, set).data, &spec, &base).expect("fit");
        (
            format!("{m}-{set}"),
            spec.build().expect("model"),
            f.values(),
        )
    };
    let yeoh = ModelSpec::new("yeoh", base.ogden_form)
        .build()
        .expect("yeoh");
    let cases = [
        fitted(VHB_UNIAXIAL, "yeoh"),
        ("yeoh-unstable".to_string(), yeoh, vec![1e5, -5e3, 50.0]),
        fitted(TRELOAR_ALL, "ogden3"),
    ];
    for (name, model, p) in &cases {
        assert_eq!(drucker(model.as_ref(), p), drucker_dense(model.as_ref(), p));
        let mut g = c.benchmark_group(format!("drucker/{name}"));
        g.bench_function("bounded", |b| {
            b.iter(|| drucker(model.as_ref(), black_box(p)))
        });
        g.bench_function("dense", |b| {
            b.iter(|| drucker_dense(model.as_ref(), black_box(p)))
        });
        g.finish();
    }
}

/// Rosenbrock as least squares: r = (10(y − x²), 1 − x), from (−1.2, 1).
struct Rosenbrock;

impl LeastSquares for Rosenbrock {
    fn dims(&self) -> (usize, usize) {
        (2, 2)
    }
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        r[0] = 10.0 * (p[1] - p[0] * p[0]);
        r[1] = 1.0 - p[0];
        if let Some(j) = jac {
            j.copy_from_slice(&[-20.0 * p[0], -1.0, 10.0, 0.0]);
        }
        true
    }
}

fn tiny_search(c: &mut Criterion) {
    let free = [(f64::NEG_INFINITY, f64::INFINITY); 2];
    let settings = LmSettings::default();
    let res = lm::minimize(&mut Rosenbrock, &[-1.2, 1.0], &free, &settings);
    assert!(res.cost < 1e-20, "{res:?}");
    c.bench_function("search/rosenbrock-2/lm", |b| {
        b.iter(|| lm::minimize(&mut Rosenbrock, black_box(&[-1.2, 1.0]), &free, &settings))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = fits, yeoh_search, varpro_projection, ogden_blocks, varpro_search, drucker_checks, tiny_search
}
criterion_main!(benches);
