//! Simulator speed on seed scenes at the scenes' tolerance (rtol 1e-6).

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::sim::{scene::Scene, simulate, RunOptions};
use std::path::Path;

fn bench(c: &mut Criterion) {
    for name in [
        "stack_step_5kV_damped",
        "stack_triangle_100Hz",
        "hdea_step_10N",
    ] {
        let s = Scene::read(Path::new(&format!("datasets/scenes/{name}.toml"))).expect("scene");
        c.bench_function(name, |b| {
            b.iter(|| simulate(&s, &RunOptions::default()).expect("runs"))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
