//! Simulator speed on seed scenes at the scenes' tolerance (rtol 1e-6), with the
//! scenes' own sample counts and with 10 samples (the integration without most of the
//! output); and plain runs beside forward-sensitivity runs (`trajectory`, what
//! identification calls) of the damped step and of a rig-log-sized scene; and the
//! undamped 5 kV step (its first second, dynamic fidelity) with Tsitouras 5(4) beside
//! Dormand–Prince 5(4), the unchanged oracle, as the baseline of the same run
//! (issue 12, callgrind of the whole `dea-fit simulate` process: diffsol's
//! Tsitouras 1.04× dp54's instructions, ours 0.79×; with the cheaper steps of
//! docs/architecture.md, which dp54 shares, ours 0.72×: 1.22 G against 1.70 G
//! over the full 10 s).

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::sim::integrate::Method;
use dea_fit::sim::scene::FidelityChoice;
use dea_fit::sim::{scene::Scene, simulate, trajectory, RunOptions};
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
        let mut few = s.clone();
        few.time.samples = (1..=10).map(|i| s.time.span * i as f64 / 10.0).collect();
        c.bench_function(&format!("{name} (10 samples)"), |b| {
            b.iter(|| simulate(&few, &RunOptions::default()).expect("runs"))
        });
    }
    let mut ringing = Scene::read(Path::new("datasets/scenes/stack_step_5kV.toml")).expect("scene");
    ringing.time.fidelity = FidelityChoice::Dynamic;
    ringing.time.span = 1.0;
    ringing.time.samples = (1..=200).map(|i| i as f64 / 200.0).collect();
    for m in [Method::Tsit45, Method::Dp54] {
        let o = RunOptions {
            method: Some(m),
            ..Default::default()
        };
        c.bench_function(&format!("stack_step_5kV undamped 1 s {m}"), |b| {
            b.iter(|| simulate(&ringing, &o).expect("runs"))
        });
    }
    let damped =
        Scene::read(Path::new("datasets/scenes/stack_step_5kV_damped.toml")).expect("scene");
    // A rig log's size (issue 10): 7 s, 3500 samples, 9 θ (the scene file says how).
    let rig = Scene::read(Path::new("datasets/scenes/stack_rig_7s.toml")).expect("scene");
    let sens = RunOptions {
        sensitivities: true,
        ..Default::default()
    };
    for (name, s) in [("stack_step_5kV_damped", &damped), ("rig_7s", &rig)] {
        c.bench_function(&format!("{name} trajectory (plain)"), |b| {
            b.iter(|| trajectory(s, &RunOptions::default()).expect("runs"))
        });
        c.bench_function(&format!("{name} trajectory (sensitivities)"), |b| {
            b.iter(|| trajectory(s, &sens).expect("runs"))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
