//! Simulator speed on seed scenes at the scenes' tolerance (rtol 1e-6), with the
//! scenes' own sample counts and with 10 samples (the integration without most of the
//! output); and plain runs beside forward-sensitivity runs (`trajectory`, what
//! identification calls) of the damped step and of a rig-log-sized scene.

use criterion::{criterion_group, criterion_main, Criterion};
use dea_fit::sim::{scene::Scene, simulate, trajectory, RunOptions};
use std::path::Path;

/// A rig log's size (issue 10): the seed stack with Yeoh VHB4910, two Maxwell arms
/// and a dashpot (9 θ: C10, C20, C30, k1, τ1, k2, τ2, Nv, εr), a 3 kV step behind a
/// 1 ms supply, then a 1 kV, 1 Hz sine from 2 s; 7 s, 3500 samples.
const RIG: &str = r#"
name = "rig_7s"
[actuator]
kind = "stack"
radius = "2.25 mm"
layer_thickness = "500 um"
electrode_thickness = "50 um"
layers = 10
electrodes = 11
[material]
hyperelastic = { preset = "vhb4910-yeoh" }
viscous = { nv = "1875 Pa s", arms = [ { k = "106 kPa", tau = "0.32 s" }, { k = "45 kPa", tau = "2.26 s" } ] }
relative_permittivity = 4.7
density = "960 kg/m3"
[source]
rise_time = "1 ms"
[[input]]
kind = "step"
amplitude = "3 kV"
[[input]]
kind = "sine"
amplitude = "1 kV"
frequency = "1 Hz"
start = "2 s"
cycles = 5
[time]
span = "7 s"
samples = 3500
"#;

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
    let damped =
        Scene::read(Path::new("datasets/scenes/stack_step_5kV_damped.toml")).expect("scene");
    let rig = Scene::parse(RIG, Path::new("rig_7s.toml")).expect("scene");
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
