//! Permittivity benches: reading and analysing one 201-point export (the new
//! reader) against a naive baseline (str::parse of a plain CSV, no checks), and
//! fitting all mixing rules at one frequency.

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::fit::composite::{fit_frequency, FractionPoint};
use dea_fit::fit::permittivity::{analyse, Geometry, Settings};
use dea_fit::io::lcr::{self, LcrOptions};
use dea_fit::material::dielectric::{MixingRule, Pair};
use dea_fit::units::Quantity;
use nalgebra::Complex;
use std::f64::consts::PI;
use std::hint::black_box;
use std::path::Path;

fn sweep_points() -> Vec<(f64, Complex<f64>)> {
    (0..201)
        .map(|i| {
            let f = 20.0 * 10f64.powf(i as f64 / 50.0);
            let w = 2.0 * PI * f;
            (f, Complex::new(w * 15.75e-12 * 1e-3, w * 15.75e-12))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let geom = Geometry::new(
        Some(Quantity {
            value: 1.439e-3,
            tolerance: Some(1e-6),
        }),
        None,
        Some(Quantity {
            value: 2.2e-3,
            tolerance: Some(5e-5),
        }),
    )
    .expect("valid");
    let e4990a = lcr::write_e4990a(Pair::ZTheta, &sweep_points()).unwrap();
    let plain = lcr::write_csv(Pair::CpD, &sweep_points()).unwrap();
    let path = Path::new("bench.csv");
    c.bench_function("read+analyse E4990A 201 points", |b| {
        b.iter(|| {
            let s = lcr::parse(path, black_box(e4990a.as_bytes()), &LcrOptions::default())
                .expect("parses");
            analyse(&s, "b", &geom, &Settings::default(), "bench").expect("capacitor")
        })
    });
    c.bench_function("baseline: naive split+parse of a Cp-D CSV", |b| {
        b.iter(|| {
            black_box(&plain)
                .lines()
                .skip(1)
                .map(|l| {
                    let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(0.0)).collect();
                    v[1] * 2.2e-3 / (8.854e-12 * 1.439e-3)
                })
                .sum::<f64>()
        })
    });
    let data: Vec<FractionPoint> = [0.0, 0.02, 0.04, 0.07, 0.1, 0.15, 0.2]
        .iter()
        .map(|&p| FractionPoint {
            volume_fraction: p,
            eps_r: MixingRule::Bruggeman.eval(2.72, 150.0, p, 3.0),
            eps_r_std: None,
        })
        .collect();
    c.bench_function("fit 6 mixing rules at one frequency (7 samples)", |b| {
        b.iter(|| fit_frequency(1e3, black_box(data.clone())))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
