//! Charts and samples that would show motion that does not exist (issue 9, class 7):
//! the sampling check against the damped axial mode and the min/max envelope per
//! output interval from the integrator's steps.

use dea_fit::sim::fidelity::AxialMode;
use dea_fit::sim::sampling::{hidden_motion, Envelope};
use dea_fit::sim::scene::Scene;
use dea_fit::sim::{simulate, Outcome, RunOptions};
use std::path::Path;

fn mode(f: f64, zeta: f64) -> AxialMode {
    AxialMode {
        frequency_hz: f,
        damping_ratio: zeta,
        q_factor: 0.5 / zeta,
        dashpot_share: 0.0,
    }
}

/// 200 Hz samples over 1 s.
fn times() -> Vec<f64> {
    (1..=200).map(|i| i as f64 / 200.0).collect()
}

/// The rule: Nyquist against the damped mode, unless the ringing dies within one
/// output interval, and no ringing without inertia.
#[test]
fn the_sampling_rule_weighs_frequency_and_decay() {
    // 1 kHz, Q ≈ 5000 (the shipped 5 kV stack): 2·f·Δt = 10, nothing decays.
    assert!(!Envelope::new(true, &mode(1000.0, 1e-4), &times()).resolved());
    // 1 kHz at ζ = 0.3: e^(−ζ·ω·Δt) = e^(−9.4) ≈ 8e-5 after one interval.
    assert!(Envelope::new(true, &mode(1000.0, 0.3), &times()).resolved());
    // 50 Hz: 2·f·Δt = 0.5, resolved.
    assert!(Envelope::new(true, &mode(50.0, 1e-4), &times()).resolved());
    // 99.9 Hz is resolved, 100.1 Hz is not (Nyquist at 100 Hz).
    assert!(Envelope::new(true, &mode(99.9, 1e-4), &times()).resolved());
    assert!(!Envelope::new(true, &mode(100.1, 1e-4), &times()).resolved());
    // Quasi-static runs carry no inertia, hence no ringing.
    assert!(Envelope::new(false, &mode(1000.0, 1e-4), &times()).resolved());
}

fn shipped(name: &str) -> Scene {
    Scene::read(Path::new(&format!("datasets/scenes/{name}.toml"))).unwrap()
}

fn with_samples(s: &Scene, span: f64, n: usize) -> Scene {
    let mut s = s.clone();
    s.time.span = span;
    s.time.samples = (1..=n).map(|i| span * i as f64 / n as f64).collect();
    s
}

fn stroke_svg(o: &Outcome) -> String {
    let dir = tempfile::tempdir().unwrap();
    let check = dea_fit::sim::breakdown::check(None, o.extremes().field, "the largest field");
    dea_fit::report::simulation::write(o, "scene.toml", dir.path(), "completed", &check).unwrap();
    std::fs::read_to_string(dir.path().join("stroke.svg")).unwrap()
}

/// The shipped 5 kV stack rings at 1009 Hz (Q ≈ 4800) and is sampled at 200 Hz: the
/// run warns and the stroke chart draws the envelope band, not the aliased line.
/// The envelope's width matches the ringing amplitude seen by 200 kHz samples of the
/// same trajectory (the samples are interpolated from the same steps) over every
/// 5 ms interval after the first (which holds the 1 ms voltage rise): within 3 % of
/// the largest ringing width plus 3 % of the interval's own, the ≈ 1 − cos(π/m)
/// that accepted steps (m ≈ 20 per period here) miss of each peak.
#[test]
fn the_5kv_stack_warns_and_its_envelope_is_the_ringing() {
    let full = shipped("stack_step_5kV");
    let o = simulate(&full, &RunOptions::default()).unwrap();
    assert!(
        o.warnings
            .iter()
            .any(|w| w.contains("do not resolve the axial mode")),
        "{:?}",
        o.warnings
    );
    let env = o.envelope.as_ref().expect("an envelope");
    assert_eq!(env.len(), o.samples.len());
    let svg = stroke_svg(&o);
    assert!(svg.contains("min/max per output interval") && svg.contains("<polygon"));

    let span = 0.3;
    let coarse = simulate(&with_samples(&full, span, 60), &RunOptions::default()).unwrap();
    let dense = simulate(&with_samples(&full, span, 60_000), &RunOptions::default()).unwrap();
    assert!(dense.envelope.is_none(), "{:?}", dense.warnings);
    let env = coarse.envelope.as_ref().unwrap();
    let widths: Vec<(f64, f64)> = (2..coarse.samples.len())
        .map(|k| {
            let (a, b) = (coarse.samples[k - 1].time_s, coarse.samples[k].time_s);
            let (lo, hi) = dense
                .samples
                .iter()
                .filter(|s| s.time_s >= a - 1e-12 && s.time_s <= b + 1e-12)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| {
                    (l.min(s.length_m), h.max(s.length_m))
                });
            (env[k].length_m.hi - env[k].length_m.lo, hi - lo)
        })
        .collect();
    let largest = widths.iter().map(|w| w.1).fold(0.0, f64::max);
    // A ringing stack: the widths are the ringing, micrometres, not zero.
    assert!(largest > 1e-6, "{largest}");
    for (k, (got, want)) in widths.iter().enumerate() {
        assert!(
            (got - want).abs() <= 0.03 * largest + 0.03 * want && *got <= want * (1.0 + 1e-6),
            "interval {}: envelope {got:e} m, dense samples {want:e} m",
            k + 2
        );
    }
    // The hidden motion the warning quotes is the ringing's peak-to-peak (≈ 2A).
    let hidden = hidden_motion(env, &coarse.samples);
    assert!(
        (hidden / largest - 1.0).abs() < 0.2,
        "{hidden:e} vs {largest:e}"
    );
}

/// The damped 5 kV stack (Nv = 1875 Pa·s) is well sampled at 200 Hz: no warning, no
/// envelope, the line chart.
#[test]
fn a_well_sampled_scene_does_not_warn() {
    let o = simulate(&shipped("stack_step_5kV_damped"), &RunOptions::default()).unwrap();
    assert!(o.envelope.is_none());
    assert!(!o.warnings.iter().any(|w| w.contains("do not resolve")));
    assert!(!stroke_svg(&o).contains("min/max per output interval"));
}
