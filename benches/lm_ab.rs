//! TEMPORARY: hand loop vs argmin Executor on the estimators' problems.
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use dea_fit::bench::{shipped_datasets, TRELOAR_ALL, VHB_UNIAXIAL};
use dea_fit::fit::hyperelastic::{fit, Search, Settings};
use dea_fit::fit::lm::{self, LeastSquares, LmSettings, DIRECT};
use dea_fit::fit::problem::HyperProblem;
use dea_fit::fit::relaxation::{self, Loading};
use dea_fit::io::relaxation::{from_table, log_times, RelaxationOptions, Synthetic};
use dea_fit::io::table::Table;
use dea_fit::material::hyperelastic::ModelSpec;
use dea_fit::material::viscoelastic::preset;
use nalgebra::{DMatrix, DVector};
use std::hint::black_box;
use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::Duration;

struct Tiny;
impl LeastSquares for Tiny {
    fn dims(&self) -> (usize, usize) {
        (2, 2)
    }
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        r[0] = 10.0 * (p[1] - p[0] * p[0]);
        r[1] = 1.0 - p[0];
        if let Some(j) = jac {
            j[(0, 0)] = -20.0 * p[0];
            j[(0, 1)] = 10.0;
            j[(1, 0)] = -1.0;
            j[(1, 1)] = 0.0;
        }
        true
    }
}

fn ab(c: &mut Criterion) {
    let sets = shipped_datasets(&Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets")).unwrap();
    let vhb = &sets.iter().find(|d| d.name == VHB_UNIAXIAL).unwrap().data;
    let treloar = &sets.iter().find(|d| d.name == TRELOAR_ALL).unwrap().data;
    let base = Settings::default();
    let yeoh = ModelSpec::new("yeoh", base.ogden_form).build().unwrap();
    let ybounds = yeoh.bounds(0.0);
    let o3 = ModelSpec::new("ogden3", base.ogden_form);
    let full = Settings {
        method: Search::Full,
        ..base.clone()
    };
    let syn = Synthetic {
        prony: preset("seed-table-3.3").unwrap().prony,
        strain: 0.5,
        ramp_time: None,
        times: log_times(0.01, 1000.0, 200, false),
        noise: 0.01,
        seed: 4910,
        record_strain: false,
    };
    let csv = syn.csv(&["bench"]).unwrap();
    let rdata = from_table(
        &Table::parse(Path::new("bench.csv"), csv.as_bytes()).unwrap(),
        &RelaxationOptions::default(),
    )
    .unwrap();
    let loading = Loading {
        strain: Some(0.5),
        ramp_time: None,
    };
    let rset = relaxation::Settings {
        terms: Some(4),
        ..relaxation::Settings::default()
    };
    let mut g = c.benchmark_group("ab");
    g.sampling_mode(SamplingMode::Flat);
    for round in 0..2 {
        for (mode, direct) in [("loop", true), ("argmin", false)] {
            DIRECT.store(direct, Ordering::Relaxed);
            g.bench_function(format!("tiny2/{mode}/{round}"), |b| {
                b.iter(|| {
                    lm::minimize(
                        &mut Tiny,
                        black_box(&[-1.2, 1.0]),
                        &[(f64::NEG_INFINITY, f64::INFINITY); 2],
                        &LmSettings::default(),
                    )
                })
            });
            g.bench_function(format!("yeoh-lm/{mode}/{round}"), |b| {
                b.iter(|| {
                    let mut p = HyperProblem::new(yeoh.as_ref(), black_box(vhb), base.residual);
                    lm::minimize(&mut p, &[1e5, 0.0, 0.0], &ybounds, &LmSettings::default())
                })
            });
            g.bench_function(format!("ogden3-varpro/{mode}/{round}"), |b| {
                b.iter(|| fit(black_box(treloar), &o3, &base).unwrap())
            });
            g.bench_function(format!("ogden3-full/{mode}/{round}"), |b| {
                b.iter(|| fit(black_box(treloar), &o3, &full).unwrap())
            });
            g.bench_function(format!("prony4/{mode}/{round}"), |b| {
                b.iter(|| relaxation::fit(black_box(&rdata), &loading, None, &rset).unwrap())
            });
        }
    }
    g.finish();
}
criterion_group! { name = benches; config = Criterion::default().sample_size(20).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(2)); targets = ab }
criterion_main!(benches);
