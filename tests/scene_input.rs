//! Scenes and fit files under bad input (issue 9, classes 1–3), through the
//! library: the simulator guards itself without the reader, the run budget is an
//! estimate made before the run, and a relaxation fit drives the viscous arms.

use dea_fit::sim::budget::{self, TABLE};
use dea_fit::sim::input::Term;
use dea_fit::sim::scene::Scene;
use dea_fit::sim::{full_plant, simulate, RunOptions};
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn shipped(name: &str) -> Scene {
    Scene::read(&repo().join("datasets/scenes").join(name)).expect("a shipped scene")
}

fn gent(jm: &str) -> String {
    std::fs::read_to_string(repo().join("datasets/scenes/stack_step_5kV_damped.toml"))
        .unwrap()
        .replace(
            "hyperelastic = { preset = \"vhb4910-yeoh\" }",
            &format!("hyperelastic = {{ model = \"gent\", parameters = {{ mu = \"46 kPa\", Jm = {jm} }} }}"),
        )
}

#[test]
fn static_stretch_and_simulate_never_panic_on_parameters_changed_without_the_reader() {
    // what identification does: take a valid scene and change its constants
    let good = Scene::parse(&gent("100"), Path::new("g.toml")).unwrap();
    for jm in [0.0, -2.5, 1e-300, f64::NAN, f64::INFINITY] {
        let mut s = good.clone();
        s.material.params[1] = jm;
        // the plant itself answers with an error (no rest state), never a panic
        if let Ok(p) = full_plant(&s) {
            let _ = p.static_stretch(0.0, 1.0);
        }
        let e = simulate(&s, &RunOptions::default())
            .expect_err("refused")
            .to_string();
        assert!(e.contains("material.hyperelastic.parameters.Jm"), "{e}");
    }
    let mut s = good.clone();
    s.material.eps_r = f64::INFINITY;
    match full_plant(&s) {
        Ok(p) => assert!(p.static_stretch(5e3, 1.0).is_err()),
        Err(e) => assert!(e.to_string().contains("no stable rest state"), "{e}"),
    }
    let e = simulate(&s, &RunOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("material.relative_permittivity") && e.contains("finite"),
        "{e}"
    );
    let mut s = good;
    s.time.span = 1e200;
    let e = simulate(&s, &RunOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("time.span"), "{e}");
}

#[test]
fn the_reader_refuses_the_issue_values_at_their_key() {
    for (jm, want) in [
        ("0", "Jm = 0"),
        ("-2.5", "Jm = -2.5"),
        ("1e-300", "Jm = 1e-300"),
    ] {
        let e = Scene::parse(&gent(jm), Path::new("g.toml"))
            .err()
            .unwrap()
            .to_string();
        // line 13 holds the hyperelastic table; the column is that of Jm
        assert!(e.starts_with("g.toml:13:") && e.contains(want), "{e}");
    }
}

#[test]
fn kinks_are_listed_without_following_a_users_count() {
    let t = Term::Triangle {
        start: 0.0,
        amplitude: 1.0,
        frequency: 10.0,
        cycles: 1e30,
        offset: 0.0,
    };
    // corners every 50 ms over 1 s: 21 corners (the end at 1e29 s lies outside)
    assert_eq!(t.kinks(0.0, 1.0).len(), 21);
    assert_eq!(t.kink_count(0.0, 1.0), 22.0);
    // a huge window lists at most MAX_KINKS + 1 corners and the end, and counts them all
    assert_eq!(t.kinks(0.0, 1e30).len(), budget::MAX_KINKS + 2);
    assert!(t.kink_count(0.0, 1e30) > 1e30);
}

#[test]
fn the_step_estimate_is_made_before_the_run_and_does_not_refuse_real_scenes() {
    // measured steps of the shipped scenes (docs/scenes.md) against the estimate:
    // the estimate must not exceed 3× the measured count (it refuses only scenes
    // that could not finish), and for the ringing stack it must be within 3× too
    // (it is a real estimate, not a bound that never fires).
    for name in [
        "stack_step_5kV.toml",
        "stack_step_5kV_damped.toml",
        "stack_triangle_100Hz.toml",
        "hdea_step_10N.toml",
        "hdea_ramp_25kV_10N.toml",
        "stack_pid_triangle.toml",
    ] {
        let s = shipped(name);
        let c = budget::check(&s).expect("within budget");
        let o = simulate(&s, &RunOptions::default()).unwrap();
        let steps = o.integrator.stats.steps as f64;
        assert!(
            c.steps <= 3.0 * steps + 1000.0,
            "{name}: estimate {} vs {steps}",
            c.steps
        );
        if name == "stack_step_5kV.toml" {
            assert!(
                c.steps >= steps / 3.0,
                "{name}: estimate {} vs {steps}",
                c.steps
            );
        }
    }
    // the undamped stack for 1e6 s: refused from the estimate, in microseconds
    // (auto stays explicit: BDF would need even more steps on the undamped mode)
    let mut s = shipped("stack_step_5kV.toml");
    s.time.span = 1e6;
    s.time.samples = vec![1e6];
    let t = std::time::Instant::now();
    let e = simulate(&s, &RunOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(t.elapsed().as_secs_f64() < 1.0);
    assert!(
        e.contains("axial mode") && e.contains("steps, more than the budget"),
        "{e}"
    );
}

#[test]
fn every_plausible_range_is_documented() {
    let doc = std::fs::read_to_string(repo().join("docs/scenes.md")).unwrap();
    for d in TABLE {
        let row = format!("| {} |", d.what);
        assert!(doc.contains(&row), "docs/scenes.md lacks the row {row}");
    }
}

#[test]
fn a_relaxation_fit_drives_the_viscous_arms_like_the_same_arms_inline() {
    let dir = tempfile::tempdir().unwrap();
    let fit = dir.path().join("relax.json");
    let out = Command::new(env!("CARGO_BIN_EXE_dea-fit"))
        .current_dir(dir.path())
        .args([
            "relaxation",
            repo()
                .join("datasets/vhb4910/relaxation.csv")
                .to_str()
                .unwrap(),
        ])
        .args([
            "--strain",
            "0.5",
            "--no-report",
            "--out",
            fit.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    let inline: Vec<String> = json["kelvin_maxwell"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| {
            format!(
                "{{ k = \"{} Pa\", eta = \"{} Pa s\" }}",
                a["k_Pa"], a["n_Pa_s"]
            )
        })
        .collect();
    let base = std::fs::read_to_string(repo().join("datasets/scenes/stack_step_5kV.toml"))
        .unwrap()
        .replace("span = \"10 s\"", "span = \"2 s\"")
        // 20 samples per period of the ≈ 1 kHz axial mode: the swing is resolved
        .replace("samples = 2000", "samples = 40000");
    let with = |viscous: &str| {
        let text = base.replace(
            "viscous = { preset = \"elatrache2021-table-3.3\" }",
            &format!("viscous = {viscous}"),
        );
        assert!(text.contains(viscous));
        let s = Scene::parse(&text, &dir.path().join("s.toml")).unwrap();
        simulate(&s, &RunOptions::default()).unwrap()
    };
    let from_fit = with("{ fit = \"relax.json\" }");
    let by_hand = with(&format!("{{ arms = [ {} ] }}", inline.join(", ")));
    let elastic = with("{ preset = \"elastic\" }");
    // the same numbers by two routes: the same trajectory, bit for bit (the
    // columns that are not NaN by design: α and the reference are NaN here)
    let traj = |o: &dea_fit::sim::Outcome| -> Vec<[f64; 4]> {
        o.samples
            .iter()
            .map(|x| [x.time_s, x.stretch, x.voltage_v, x.current_a])
            .collect()
    };
    assert_eq!(traj(&from_fit), traj(&by_hand));
    // damped: the ringing after the step decays (the elastic one does not)
    let swing = |o: &dea_fit::sim::Outcome, a: f64, b: f64| {
        let v: Vec<f64> = o
            .samples
            .iter()
            .filter(|x| x.time_s >= a && x.time_s <= b)
            .map(|x| x.stretch)
            .collect();
        v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().cloned().fold(f64::INFINITY, f64::min)
    };
    let early = swing(&from_fit, 0.1, 0.3);
    let late = swing(&from_fit, 1.7, 1.9);
    // ζ ≈ 1.1e-4 at ≈ 1 kHz: e^(−ζω·1.6 s) ≈ 0.33, and the arms' creep adds a drift;
    // the elastic run keeps its swing within 10 %
    assert!(late < 0.6 * early, "{late} vs {early}");
    let (ee, el) = (swing(&elastic, 0.1, 0.3), swing(&elastic, 1.7, 1.9));
    assert!((el / ee - 1.0).abs() < 0.1, "{el} vs {ee}");
}

/// The README's scene with its `breakdown = "25 V/um"` line (line 19) replaced.
fn with_breakdown(value: &str) -> String {
    let text = std::fs::read_to_string(repo().join("datasets/scenes/stack_step_5kV.toml")).unwrap();
    assert!(text.lines().nth(18) == Some("breakdown = \"25 V/um\""));
    text.replace("breakdown = \"25 V/um\"", &format!("breakdown = {value}"))
}

/// A breakdown fit file as `dea-fit breakdown --out` writes it: α = 30 V/µm at a
/// 1 cm² specimen, β = 10, with standard errors 0.8 V/µm and 2 (correlation 0.3).
fn breakdown_fit() -> dea_fit::material::file::BreakdownFit {
    crate::support::breakdown_fit(0.8e6, 2.0, 0.3)
}

/// Every wrong `material.breakdown` is refused at its line and column, naming the
/// key, with a hint: non-positive, implausible, wrong unit, not a quantity, an
/// unknown key of the fit table, a missing file, a fit file of another schema, a
/// prestretch that is not a stretch.
#[test]
fn a_wrong_breakdown_is_refused_at_its_key() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo().join("tests/data/bad_cli/files/fitfile_yeoh.json"),
        dir.path().join("yeoh.json"),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("b.json"),
        serde_json::to_string(&breakdown_fit()).unwrap(),
    )
    .unwrap();
    for (value, at, want) in [
        (
            "\"-5 V/um\"",
            "s.toml:19:1:",
            "not a plausible breakdown field",
        ),
        (
            "\"0 V/um\"",
            "s.toml:19:1:",
            "not a plausible breakdown field",
        ),
        ("25", "s.toml:19:1:", "not a plausible breakdown field"),
        ("\"25 kPa\"", "s.toml:19:1:", "material.breakdown"),
        ("\"25 ± 2 kV\"", "s.toml:19:1:", "material.breakdown"),
        ("true", "s.toml:19:1:", "expected a field such as"),
        ("{ fitt = \"b.json\" }", "s.toml:19:", "did you mean 'fit'?"),
        ("{ fit = \"none.json\" }", "s.toml:19:", "cannot read"),
        (
            "{ fit = \"b.json\", prestretch = 0.5 }",
            "s.toml:19:",
            "a stretch from 1 to 100",
        ),
        ("{ fit = \"yeoh.json\" }", "yeoh.json", "breakdown"),
    ] {
        let e = Scene::parse(&with_breakdown(value), &dir.path().join("s.toml"))
            .err()
            .unwrap_or_else(|| panic!("{value} was accepted"));
        let s = e.to_string();
        let s = s.trim_start_matches(&format!("{}/", dir.path().display()));
        assert!(s.starts_with(at) && s.contains(want), "{value}: {s}");
        if at.starts_with("s.toml") {
            assert!(s.contains("material.breakdown"), "{value}: {s}");
        }
        assert!(s.contains("hint:"), "{value}: no hint: {s}");
    }
}

/// A stated breakdown keeps its σ (or none) and names its line; a scene without one
/// has none (nothing is checked).
#[test]
fn a_stated_breakdown_carries_its_sigma_and_source() {
    use dea_fit::material::breakdown::StrengthOrigin;
    let s = Scene::parse(&with_breakdown("\"25 ± 2 V/um\""), Path::new("s.toml")).unwrap();
    let b = s.breakdown.expect("stated");
    // Unit conversion only: 1e-12 relative.
    assert!((b.field / 25e6 - 1.0).abs() < 1e-12);
    assert!((b.std_error.unwrap() / 2e6 - 1.0).abs() < 1e-12);
    assert_eq!(b.origin, StrengthOrigin::Stated);
    assert!(b.source.starts_with("s.toml:19:1"), "{}", b.source);
    let s = Scene::parse(&with_breakdown("\"25 kV/mm\""), Path::new("s.toml")).unwrap();
    assert_eq!(s.breakdown.unwrap().std_error, None);
    let none = with_breakdown("\"1 V/um\"").replace("breakdown = \"1 V/um\"\n", "");
    assert!(Scene::parse(&none, Path::new("s.toml"))
        .unwrap()
        .breakdown
        .is_none());
}

/// A fitted breakdown is α carried by the weakest-link law from the specimens' area
/// to the whole film under field — all nd layers of a stack (nd·π·r0²), every
/// element of a helix (Np·Ne·A_e) — and by a thickness exponent to the layer
/// thickness; the notes say so, and a prestretch exponent without the scene's
/// `prestretch` is said not to be applied.
#[test]
fn a_fitted_breakdown_is_scaled_to_the_film_under_field() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, fit: &dea_fit::material::file::BreakdownFit| {
        std::fs::write(dir.path().join(name), serde_json::to_string(fit).unwrap()).unwrap()
    };
    let plain = breakdown_fit();
    write("b.json", &plain);
    let s = Scene::parse(
        &with_breakdown("{ fit = \"b.json\" }"),
        &dir.path().join("s.toml"),
    )
    .unwrap();
    let b = s.breakdown.expect("fitted");
    let area = 10.0 * std::f64::consts::PI * 2.25e-3f64.powi(2);
    let want = 30e6 * (1e-4 / area).powf(0.1);
    // One pow: 1e-12 relative.
    assert!(
        (b.field / want - 1.0).abs() < 1e-12,
        "{} vs {want}",
        b.field
    );
    assert!(b.std_error.is_some_and(|e| e > 0.0));
    assert!(b.law.is_some());
    assert!(
        b.notes[0].contains(&format!("× {:.3}", (1e-4 / area).powf(0.1))),
        "{:?}",
        b.notes
    );
    assert!(s.files.iter().any(|f| f.ends_with("b.json")));

    // A helix: the film is every element's electrode area (Eq. 4.12 at λ = 1).
    let helix = std::fs::read_to_string(repo().join("datasets/scenes/hdea_step_10N.toml"))
        .unwrap()
        .replace(
            "breakdown = \"25 V/um\"",
            "breakdown = { fit = \"b.json\" }",
        );
    let h = Scene::parse(&helix, &dir.path().join("h.toml")).unwrap();
    let a = h.actuator.film_area();
    assert!(a > 100.0 * std::f64::consts::PI * (0.03f64.powi(2) - 0.01f64.powi(2)) * 0.99);
    let hb = h.breakdown.unwrap();
    assert!((hb.field / (30e6 * (1e-4 / a).powf(0.1)) - 1.0).abs() < 1e-12);

    // Covariates: thickness applied (500 µm against the fit's 100 µm), prestretch
    // not applied without the scene's prestretch, applied with it.
    let mut cov = breakdown_fit();
    cov.parameters
        .push(dea_fit::material::file::BreakdownParameter {
            name: "thickness_exponent".into(),
            unit: "1".into(),
            value: -0.4,
            std_error: Some(0.05),
            ci95: None,
        });
    cov.parameters
        .push(dea_fit::material::file::BreakdownParameter {
            name: "prestretch_exponent".into(),
            unit: "1".into(),
            value: 0.5,
            std_error: Some(0.05),
            ci95: None,
        });
    cov.correlation = Vec::new();
    cov.reference_thickness = Some(100e-6);
    cov.reference_prestretch = Some(3.0);
    write("c.json", &cov);
    let s = Scene::parse(
        &with_breakdown("{ fit = \"c.json\" }"),
        &dir.path().join("s.toml"),
    )
    .unwrap();
    let b = s.breakdown.unwrap();
    assert!((b.field / (want * 5f64.powf(-0.4)) - 1.0).abs() < 1e-12);
    assert!(
        b.notes
            .iter()
            .any(|n| n.contains("prestretch_exponent not applied")),
        "{:?}",
        b.notes
    );
    let s = Scene::parse(
        &with_breakdown("{ fit = \"c.json\", prestretch = 4 }"),
        &dir.path().join("s.toml"),
    )
    .unwrap();
    let b4 = s.breakdown.unwrap();
    assert!((b4.field / (b.field * (4.0f64 / 3.0).powf(0.5)) - 1.0).abs() < 1e-12);
}
