//! Forward sensitivities of every channel a trace can measure (stretch, length,
//! capacitance, current) against central differences of whole `simulate` runs, for
//! a stack behind a resistance (RC charging: the current depends on the source
//! state), a stack behind a rise-time supply with a triangle (restarts), and the
//! seed's helix; `trajectory` against `simulate`; parameters without a rest state.
//!
//! Tolerance: the runs use BDF at rtol 1e-10 and the differences a relative step
//! h = 1e-5 of each θj, so the difference quotient is good to ≈ 1e-5 of a
//! channel's largest effect (integration error 1e-10 / h, truncation h²); each
//! channel is compared on one absolute scale, the largest effect θj·∂y/∂θj of any
//! parameter on it (a parameter with a tiny effect, e.g. Yeoh's C30 at small
//! strain, is compared on that scale too), at 1e-4 (room for the adaptive step
//! pattern, which differs between the perturbed runs).

use crate::sim::perturbed;
use dea_fit::sim::integrate::Method;
use dea_fit::sim::scene::{FidelityChoice, Scene};
use dea_fit::sim::{simulate, trajectory, Outcome, RunOptions, RunStatus, Sample};
use std::path::Path;

fn shipped(name: &str) -> String {
    std::fs::read_to_string(format!("datasets/scenes/{name}.toml")).unwrap()
}

fn scene(text: &str) -> Scene {
    Scene::parse(text, Path::new("test.toml")).expect("valid scene")
}

fn tight(sens: bool) -> RunOptions {
    RunOptions {
        method: Some(Method::Bdf),
        rtol: Some(1e-10),
        sensitivities: sens,
        ..Default::default()
    }
}

/// The channels: name, the sample's value, the sensitivity rows.
type Channel = (
    &'static str,
    fn(&Sample) -> f64,
    fn(&dea_fit::sim::Sensitivities) -> &dea_fit::sim::Rows,
);

const CHANNELS: [Channel; 4] = [
    ("stretch", |s| s.stretch, |se| &se.stretch),
    ("length", |s| s.length_m, |se| &se.length),
    ("capacitance", |s| s.capacitance_f, |se| &se.capacitance),
    ("current", |s| s.current_a, |se| &se.current),
];

/// Every channel's forward sensitivity at every sample within 1e-4 of the channel's
/// largest effect of the central difference (module documentation); returns the
/// worst per channel.
fn check_all_channels(s: &Scene) -> [f64; 4] {
    // `perturbed` moves the scene's own arms: none may be lumped away
    let mut s = s.clone();
    s.time.fidelity = FidelityChoice::Dynamic;
    let s = &s;
    let o = simulate(s, &tight(true)).unwrap();
    assert_eq!(o.integrator.status, RunStatus::Completed, "{}", o.scene);
    let se = o.sensitivities.as_ref().unwrap();
    let n = o.samples.len();
    for (name, _, rows) in CHANNELS {
        assert_eq!(rows(se).len(), n, "{name}: one row per sample");
        assert!(rows(se).iter().all(|r| r.len() == se.theta.len()));
    }
    let h = 1e-5;
    let runs: Vec<(Outcome, Outcome)> = (0..se.theta.len())
        .map(|j| {
            let up = simulate(&perturbed(s, j, h), &tight(false)).unwrap();
            let dn = simulate(&perturbed(s, j, -h), &tight(false)).unwrap();
            assert_eq!((up.samples.len(), dn.samples.len()), (n, n));
            (up, dn)
        })
        .collect();
    let mut worst = [0.0; 4];
    for (c, (name, value, rows)) in CHANNELS.into_iter().enumerate() {
        let fd = |j: usize, k: usize| {
            (value(&runs[j].0.samples[k]) - value(&runs[j].1.samples[k])) / (2.0 * h)
        };
        let scale = (0..se.theta.len())
            .flat_map(|j| (0..n).map(move |k| (j, k)))
            .fold(0.0_f64, |m, (j, k)| m.max(fd(j, k).abs()));
        assert!(scale > 0.0, "{name}: no effect at all");
        for j in 0..se.theta.len() {
            for k in 0..n {
                let an = se.theta[j] * rows(se)[k][j];
                let d = (an - fd(j, k)).abs() / scale;
                worst[c] = f64::max(worst[c], d);
                assert!(
                    d <= 1e-4,
                    "{}: {name} to {} at t = {}: forward {an:e}, differences {:e} (scale {scale:e})",
                    o.scene,
                    se.params[j],
                    o.samples[k].time_s,
                    fd(j, k)
                );
            }
        }
    }
    eprintln!(
        "{}: worst of the largest effect: stretch {:.1e}, length {:.1e}, capacitance {:.1e}, current {:.1e}",
        o.scene, worst[0], worst[1], worst[2], worst[3]
    );
    worst
}

/// A 5 kV step through 100 MΩ on the damped seed stack (RC ≈ 1.2 ms with the
/// leakage in parallel), sampled every 0.25 ms through the charging, then every
/// 50 ms to 1.5 s.
fn rc_stack() -> Scene {
    let text =
        shipped("stack_step_5kV_damped").replace("rise_time = \"1 ms\"", "resistance_ohm = 1e8");
    assert!(text.contains("resistance_ohm"));
    let mut s = scene(&text);
    s.time.span = 1.5;
    s.time.samples = (1..=20)
        .map(|i| 2.5e-4 * i as f64)
        .chain((1..=30).map(|i| 0.05 * i as f64))
        .collect();
    s
}

#[test]
fn every_channel_of_a_stack_behind_a_resistance_matches_differences() {
    check_all_channels(&rc_stack());
}

#[test]
fn every_channel_of_a_stack_through_triangle_restarts_matches_differences() {
    let text = shipped("stack_step_5kV_damped").replace(
        "kind = \"step\"\nat = \"0 s\"\namplitude = \"5 kV\"",
        "kind = \"triangle\"\namplitude = \"5 kV\"\nfrequency = \"2 Hz\"\ncycles = 3",
    );
    let mut s = scene(&text);
    s.time.span = 2.0;
    s.time.samples = (1..=40).map(|i| 0.05 * i as f64).collect();
    check_all_channels(&s);
}

#[test]
fn every_channel_of_the_helix_matches_differences() {
    let mut s = scene(&shipped("hdea_step_10N"));
    s.time.span = 0.3;
    s.time.samples = (1..=30).map(|i| 0.01 * i as f64).collect();
    check_all_channels(&s);
}

/// `trajectory` runs what `simulate` runs: the same samples and sensitivities, bit
/// for bit, the same status, method and counts.
#[test]
fn trajectory_is_the_run_of_simulate() {
    for s in [
        rc_stack(),
        scene(&shipped("hdea_step_10N")),
        scene(&shipped("stack_pid_triangle")),
    ] {
        for sens in [false, true] {
            let o = RunOptions {
                sensitivities: sens,
                ..Default::default()
            };
            let full = simulate(&s, &o).unwrap();
            let t = trajectory(&s, &o).unwrap();
            // Debug prints every f64 exactly, NaN (α of a stack) included
            let bits = |x: &dyn std::fmt::Debug| format!("{x:?}");
            assert_eq!(bits(&t.samples), bits(&full.samples), "{}", s.name);
            assert_eq!(bits(&t.sensitivities), bits(&full.sensitivities));
            assert_eq!(t.status, full.integrator.status);
            assert_eq!(t.message, full.integrator.message);
            assert_eq!(
                (t.method, t.stats),
                (full.integrator.method, full.integrator.stats)
            );
            assert_eq!(t.rest_stretch, full.rest_stretch);
            assert_eq!(t.rest_length_m, full.rest_length_m);
            assert_eq!(t.samples.len(), s.time.samples.len() + 1);
        }
    }
}

/// A pull-in sample has NaN sensitivities in every channel (its time moves with θ).
#[test]
fn a_pull_in_sample_has_no_sensitivities() {
    // the Neo-Hookean layer of tests/sim.rs (pull-in near 37 kV) ramped to 60 kV
    let s = scene(&crate::sim::nh_layer(
        "{ nv = \"20 Pa s\" }",
        "[[input]]\nkind = \"ramp\"\nstart = \"0 s\"\nend = \"1 s\"\nto = \"60 kV\"",
        "span = \"1 s\"\nsamples = 20",
    ));
    let t = trajectory(&s, &tight(true)).unwrap();
    assert_eq!(t.status, RunStatus::PullIn, "{}", t.message);
    let se = t.sensitivities.unwrap();
    for (name, _, rows) in CHANNELS {
        let rows = rows(&se);
        assert_eq!(rows.len(), t.samples.len());
        let last = rows.len() - 1;
        assert!(rows[last].iter().all(|v| v.is_nan()), "{name}");
        assert!(
            rows.iter().take(last).flatten().all(|v| v.is_finite()),
            "{name}"
        );
    }
}

/// Identification sets θ on the scene and calls `trajectory`: a θ without a stable
/// rest state (a modulus too soft for the load, a Gent limit below the rest
/// stretch) is an error saying so, never a run from a made-up rest state.
#[test]
fn parameters_without_a_rest_state_are_an_error() {
    let mut s = scene(&shipped("hdea_step_10N"));
    // C10 a thousand times softer: the 10 N weight pulls the layer apart
    s.material.params[0] *= 1e-3;
    let e = trajectory(&s, &RunOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no stable rest state"), "{e}");
    assert!(simulate(&s, &RunOptions::default()).is_err());
    assert!(dea_fit::sim::full_plant(&s).is_err());
    // the plant's own constructor and `with_theta` say so too
    let ok = scene(&shipped("hdea_step_10N"));
    let p = dea_fit::sim::full_plant(&ok).unwrap();
    let mut th = p.theta();
    th[0] *= 1e-3;
    assert!(p.with_theta(&th).is_err());
    assert!(p.with_theta(&p.theta()).is_ok());
    // a non-finite constant is refused before any plant is built
    let mut s = ok.clone();
    s.material.params[1] = f64::NAN;
    assert!(trajectory(&s, &RunOptions::default()).is_err());
}

/// Sensitivities are not in the step-size control: at the scene's own tolerance
/// (rtol 1e-6) they ride on the state's steps. Against the same run at rtol 1e-10,
/// every channel's θ·∂y/∂θ stays within 10·rtol = 1e-5 of the channel's largest
/// effect: errors of the order of the tolerance, as the state's (measured 4.8e-7
/// for the stretch, 2.3e-7 for the current; the state itself 1.4e-9 and 2.2e-7 of
/// its largest value).
#[test]
fn sensitivities_at_the_scene_tolerance_follow_the_state_accuracy() {
    let s = scene(&shipped("stack_step_5kV_damped"));
    let at = |rtol: f64| {
        trajectory(
            &s,
            &RunOptions {
                rtol: Some(rtol),
                sensitivities: true,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let (coarse, fine) = (at(1e-6), at(1e-10));
    let (sc, sf) = (
        coarse.sensitivities.as_ref().unwrap(),
        fine.sensitivities.as_ref().unwrap(),
    );
    for (name, value, rows) in CHANNELS {
        let state = (0..coarse.samples.len())
            .map(|k| (value(&coarse.samples[k]) - value(&fine.samples[k])).abs())
            .fold(0.0, f64::max)
            / fine
                .samples
                .iter()
                .map(|x| value(x).abs())
                .fold(0.0, f64::max);
        let effect =
            |se: &dea_fit::sim::Sensitivities, k: usize, j: usize| se.theta[j] * rows(se)[k][j];
        let n = coarse.samples.len();
        let np = sf.theta.len();
        let scale = (0..n)
            .flat_map(|k| (0..np).map(move |j| (k, j)))
            .fold(0.0_f64, |m, (k, j)| m.max(effect(sf, k, j).abs()));
        let worst = (0..n)
            .flat_map(|k| (0..np).map(move |j| (k, j)))
            .fold(0.0_f64, |m, (k, j)| {
                m.max((effect(sc, k, j) - effect(sf, k, j)).abs())
            })
            / scale;
        eprintln!("{name}: state error {state:.1e} of its largest value, sensitivity error {worst:.1e} of the largest effect");
        assert!(worst <= 1e-5, "{name}: {worst:e}");
    }
}

/// `simulate --sensitivities` writes every sensitivity output the simulator has —
/// the derivatives of stretch, length, capacitance and current to each parameter —
/// as trajectory columns headed with their units, each value finite; the current's
/// sensitivity to εr and the length's to C10 (whole columns, through the RC charging
/// of a stack behind 100 MΩ) agree with central differences of runs within 1e-4 of
/// the column's largest effect (the tolerance of the module documentation: BDF at
/// rtol 1e-10, relative step 1e-5).
#[test]
fn the_trajectory_csv_has_every_sensitivity_with_units() {
    let text = shipped("stack_step_5kV_damped")
        .replace("rise_time = \"1 ms\"", "resistance_ohm = 1e8")
        .replace("span = \"10 s\"", "span = \"20 ms\"")
        .replace("samples = 2000", "samples = 40\nfidelity = \"dynamic\"");
    assert!(text.contains("resistance_ohm") && text.contains("20 ms") && text.contains("dynamic"));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rc.toml");
    std::fs::write(&path, &text).unwrap();
    let o = crate::support::run(
        dir.path(),
        &[
            "simulate",
            "rc.toml",
            "--sensitivities",
            "--method",
            "bdf",
            "--rtol",
            "1e-10",
            "--no-report",
            "--out",
            "run.csv",
        ],
    );
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let csv = std::fs::read_to_string(dir.path().join("run.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let s = Scene::read(&path).unwrap();
    let full = simulate(&s, &tight(true)).unwrap();
    let se = full.sensitivities.as_ref().unwrap();
    let np = se.params.len();
    let sens: Vec<&str> = header
        .iter()
        .copied()
        .filter(|h| h.starts_with('d'))
        .collect();
    assert_eq!(sens.len(), 4 * np, "{header:?}");
    for h in [
        "dstretch_d_C10_per_Pa",
        "dlength_d_C10_m_per_Pa",
        "dcapacitance_d_nv_F_per_Pa_s",
        "dcurrent_d_eps_r_A",
        "dlength_d_arm1.tau_m_per_s",
    ] {
        assert!(header.contains(&h), "no column {h} in {header:?}");
    }
    let col = |h: &str| header.iter().position(|c| *c == h).unwrap();
    for h in &sens {
        let c = col(h);
        assert!(
            rows.iter().all(|r| r[c].is_finite()),
            "{h}: a value is not finite"
        );
    }
    // central differences of whole runs (`perturbed` scales θj by 1 ± h)
    let h = 1e-5;
    let j_of = |name: &str| {
        se.params
            .iter()
            .position(|p| p.split(' ').next() == Some(name))
            .unwrap()
    };
    // (column, parameter, output as `CHANNELS` names it)
    let checks = [
        ("dcurrent_d_eps_r_A", "eps_r", "current"),
        ("dlength_d_C10_m_per_Pa", "C10", "length"),
    ];
    for (column, param, output) in checks {
        let (_, value, _) = CHANNELS.into_iter().find(|c| c.0 == output).unwrap();
        let j = j_of(param);
        let up = simulate(&perturbed(&s, j, h), &tight(false)).unwrap();
        let dn = simulate(&perturbed(&s, j, -h), &tight(false)).unwrap();
        let fd: Vec<f64> = (0..rows.len())
            .map(|k| (value(&up.samples[k]) - value(&dn.samples[k])) / (2.0 * h))
            .collect();
        let scale = fd.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{column}: no effect");
        let c = col(column);
        let worst = rows
            .iter()
            .zip(&fd)
            .map(|(r, d)| (se.theta[j] * r[c] - d).abs() / scale)
            .fold(0.0, f64::max);
        eprintln!("{column}: worst {worst:.1e} of the largest effect {scale:.3e}");
        assert!(worst <= 1e-4, "{column}: {worst:e} of {scale:e}");
    }
}

/// A run without the current's sensitivities (what identification runs when no
/// current is fitted) gives the stretch, length and capacitance rows of the full
/// run bit for bit (closed forms of the same expressions the lanes evaluate), the
/// same samples, and no current rows; on a stack behind a resistance, the rig
/// scene (rise-time source, sine) and the helix, at bdf (which integrates only
/// the states before the quadratures) and esdirk34 (every state).
#[test]
fn sensitivities_without_the_current_are_those_of_the_full_run() {
    for s in [
        rc_stack(),
        scene(&shipped("stack_rig_7s")),
        scene(&shipped("hdea_step_10N")),
    ] {
        for method in [Method::Bdf, Method::Esdirk34] {
            let full = RunOptions {
                method: Some(method),
                sensitivities: true,
                ..Default::default()
            };
            let lean = RunOptions {
                no_current_sensitivity: true,
                ..full
            };
            let (f, l) = (
                trajectory(&s, &full).unwrap(),
                trajectory(&s, &lean).unwrap(),
            );
            let bits = |x: &dyn std::fmt::Debug| format!("{x:?}");
            assert_eq!(bits(&f.samples), bits(&l.samples), "{}", s.name);
            let (fs, ls) = (f.sensitivities.unwrap(), l.sensitivities.unwrap());
            for (name, _, rows) in &CHANNELS[..3] {
                assert_eq!(bits(rows(&fs)), bits(rows(&ls)), "{} {name}", s.name);
            }
            assert_eq!(fs.current.len(), f.samples.len());
            assert_eq!(ls.current.len(), 0, "{}: no current rows", s.name);
        }
    }
}

/// A run that carries some of θ's sensitivity columns
/// ([`RunOptions::sensitivities_of`]: what a search with held constants asks)
/// gives those columns of the full run bit for bit (the integrators' error control
/// looks at the states alone, so the steps are the same), in θ's order, with their
/// names, and the same samples; with and without the current, on a stack behind a
/// resistance (whose initial charge depends on εr), the rig scene and the helix,
/// at bdf, esdirk34 and the explicit tsit45 (each integrator and each scene once
/// at least: the subset is taken in the plant, below every integrator).
#[test]
fn a_subset_of_sensitivity_columns_is_those_columns_of_the_full_run() {
    let (rc, rig, helix) = (
        rc_stack(),
        scene(&shipped("stack_rig_7s")),
        scene(&shipped("hdea_step_10N")),
    );
    let cases = [
        (&rc, Method::Bdf, false),
        (&rc, Method::Esdirk34, true),
        (&rig, Method::Bdf, true),
        (&helix, Method::Tsit45, true),
        (&helix, Method::Bdf, false),
    ];
    let bits = |x: &dyn std::fmt::Debug| format!("{x:?}");
    for (s, method, no_current) in cases {
        let what = format!("{} {method:?} no_current {no_current}", s.name);
        let full = RunOptions {
            method: Some(method),
            sensitivities: true,
            no_current_sensitivity: no_current,
            ..Default::default()
        };
        let f = trajectory(s, &full).unwrap();
        let fs = f.sensitivities.as_ref().unwrap();
        let n = fs.columns.len();
        assert_eq!(fs.columns, (0..n).collect::<Vec<_>>(), "{what}");
        // the first, the last (εr) and every third entry between
        let keep: Vec<usize> = (0..n)
            .filter(|&k| k % 3 == 1 || k == 0 || k == n - 1)
            .collect();
        let lean = RunOptions {
            sensitivities_of: Some(keep.iter().fold(0u128, |m, &k| m | 1 << k)),
            ..full
        };
        let l = trajectory(s, &lean).unwrap();
        let ls = l.sensitivities.as_ref().unwrap();
        assert_eq!(bits(&f.samples), bits(&l.samples), "{what}");
        assert_eq!(ls.columns, keep, "{what}");
        assert_eq!(ls.column(n - 2).is_some(), keep.contains(&(n - 2)));
        for (c, &k) in keep.iter().enumerate() {
            assert_eq!(ls.column(k), Some(c), "{what}");
            assert_eq!(ls.params[c], fs.params[k], "{what}");
            assert_eq!(ls.peak_stretch[c], fs.peak_stretch[k], "{what}");
            for (name, _, rows) in &CHANNELS {
                let (fr, lr) = (rows(fs), rows(ls));
                assert_eq!(fr.len(), lr.len(), "{what} {name}");
                for i in 0..fr.len() {
                    let (a, b) = (fr[i][k], lr[i][c]);
                    assert_eq!(a.to_bits(), b.to_bits(), "{what} {name} sample {i} θ{k}");
                }
            }
        }
    }
    // no column (the profile of a model's only free constant holds it): the run
    // is the plain one, with empty sensitivities
    let none = RunOptions {
        sensitivities: true,
        sensitivities_of: Some(0),
        ..Default::default()
    };
    let (p, z) = (
        trajectory(&rc, &RunOptions::default()).unwrap(),
        trajectory(&rc, &none).unwrap(),
    );
    assert_eq!(bits(&p.samples), bits(&z.samples));
    let zs = z.sensitivities.unwrap();
    assert!(zs.columns.is_empty() && zs.params.is_empty());
    assert!(zs.stretch.iter().all(|row| row.is_empty()));
}
