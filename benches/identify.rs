//! One identification start on a rig-log-sized trace (datasets/scenes/stack_rig_7s.toml:
//! 7 s, 3500 samples of contraction and capacitance, 9 free constants), from the
//! scene's constants 20 % off (`dea_fit::bench::identify_case`): the whole
//! identification with one start (search, σ re-estimation, polish, assessment), and
//! one sensitivity run of the same trace beside it for scale.

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::identify::{identify, Settings};
use dea_fit::sim::{scene::Scene, trajectory, RunOptions};
use std::path::Path;

fn bench(c: &mut Criterion) {
    let scene = Scene::read(Path::new("datasets/scenes/stack_rig_7s.toml")).expect("scene");
    let (exp, _) =
        dea_fit::bench::identify_case(&scene, dea_fit::bench::Drive::ClosedForm).expect("case");
    let settings = Settings {
        starts: 1,
        ..Settings::default()
    };
    let mut g = c.benchmark_group("identify");
    g.sample_size(10);
    g.bench_function("rig_7s one start, 9 constants", |b| {
        b.iter(|| {
            identify(vec![exp.clone()], &settings)
                .expect("runs")
                .identified()
                .expect("identifies")
        })
    });
    let opts = RunOptions {
        sensitivities: true,
        ..RunOptions::default()
    };
    g.bench_function("rig_7s one sensitivity run", |b| {
        b.iter(|| trajectory(&exp.scene, &opts).expect("runs"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
