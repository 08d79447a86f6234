//! `dea-fit rank` speed: one candidate evaluation (static curve, pull-in, breakdown
//! and the damped step of the shipped design's stack) and a 212-point sweep on the
//! machine's threads (rayon). `dea-fit bench rank` measures the sweep size.

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::rank::figures::{evaluate, step_scene};
use dea_fit::rank::{candidate, manifest, sweep};
use std::path::Path;

fn bench(c: &mut Criterion) {
    let d = manifest::read(Path::new("datasets/design/silicone_fillers.toml")).expect("design");
    let template = step_scene(&d);
    let cand = candidate::build(&d, 0, 0.2).expect("candidate");
    c.bench_function("rank: one evaluation (Sylgard 184 + BaTiO3 20 wt%)", |b| {
        b.iter(|| evaluate(&template, "stack", &cand, d.drive.level, 0))
    });
    let sw = sweep::Sweep::parse(&["loading=0:0.6:13".into(), "voltage=600V:900V:4".into()])
        .expect("sweep");
    let points: Vec<_> = sweep::Points::new(&d, &sw)
        .expect("points")
        .iter(None)
        .collect();
    c.bench_function(&format!("rank: sweep of {} points", points.len()), |b| {
        b.iter(|| sweep::run(&d, &points, &|| {}).expect("runs"))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
