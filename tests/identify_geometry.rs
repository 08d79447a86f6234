//! The scene's geometry tolerances in identify's intervals (`identify::geometry`):
//! the implicit-function move of the optimum against a re-identification, εr's
//! closed-form dependence on the layer thickness and radius (C ∝ εr·r0²/zd0),
//! intervals that cover a geometry the scene does not know exactly, the note when
//! no tolerance is stated, and the reader's refusals.

use dea_fit::identify::geometry::Term;
use dea_fit::identify::problem::{simulated, ChannelKind, Experiment};
use dea_fit::identify::{identify, Identification, Settings};
use dea_fit::sim::scene::{Actuator, Length, Scene};
use dea_fit::sim::{simulate, RunOptions};
use std::path::Path;

/// The shipped damped stack (10 layers of 500 µm, r0 = 2.25 mm) under a 5 kV step
/// with a 1 ms rise, 1 s at 400 samples, with `layer_thickness` and `radius` as given.
fn stack_text(layer: &str, radius: &str) -> String {
    std::fs::read_to_string(
        super::support::repo().join("datasets/scenes/stack_step_5kV_damped.toml"),
    )
    .expect("shipped scene")
    .replace("span = \"10 s\"", "span = \"1 s\"")
    .replace("samples = 2000", "samples = 400")
    .replace(
        "layer_thickness = \"500 um\"",
        &format!("layer_thickness = \"{layer}\""),
    )
    .replace("radius = \"2.25 mm\"", &format!("radius = \"{radius}\""))
}

fn stack(layer: &str, radius: &str) -> Scene {
    Scene::parse(&stack_text(layer, radius), Path::new("stack.toml")).expect("valid scene")
}

/// Noise of the nominal stack's channels: contraction 0.5 % of its peak,
/// capacitance 0.1 % of its rest value.
fn noise() -> Vec<(ChannelKind, f64)> {
    let o = simulate(&stack("500 um", "2.25 mm"), &RunOptions::default()).unwrap();
    let s0 = o.samples[0];
    let peak = o
        .samples
        .iter()
        .map(|s| simulated(ChannelKind::Contraction, &s0, s).abs())
        .fold(0.0, f64::max);
    vec![
        (ChannelKind::Contraction, 0.005 * peak),
        (ChannelKind::Capacitance, 1e-3 * s0.capacitance_f),
    ]
}

/// C10, εr and nv identified from `exp` (one start, at the scene's constants).
fn identified(exp: Experiment) -> Identification {
    let settings = Settings {
        free: Some(vec!["C10".into(), "eps_r".into(), "nv".into()]),
        starts: 1,
        ..Settings::default()
    };
    identify(vec![exp], &settings)
        .expect("runs")
        .identified()
        .expect("identifies")
}

fn term<'a>(id: &'a Identification, name: &str) -> &'a Term {
    id.geometry
        .constants
        .iter()
        .find(|t| t.name == name)
        .unwrap_or_else(|| panic!("{name} in geometry"))
}

/// The move of `name` in % per +1 % of `length`, as the implicit-function step says.
fn per_percent(id: &Identification, name: &str, length: Length) -> f64 {
    term(id, name)
        .per_percent
        .iter()
        .find(|m| m.length == length)
        .and_then(|m| m.percent)
        .expect("a move in %")
}

/// The predicted move of the optimum per 1 % of a length agrees with identifying
/// again with the length moved by 1 % (by e^0.01, so that ln g moves by exactly
/// 0.01: every constant here is searched as ln θ, and 100·ln(θ₁/θ₀) is the move in
/// the prediction's units). Tolerance 0.01 % of the constant plus 1 % of the move
/// (measured: at most 0.2 % of the move, 0.005 % of the constant): the
/// Gauss–Newton step drops the curvature term (∂J/∂g)ᵀr, whose r is noise, the
/// forward difference is 10⁻³ of the move (`geometry::STEP`), the move's second
/// order (1 % of a 1 % move) is in the re-identification only, and a search stops
/// within 0.045 σ of its optimum (σ_trace 0.005 % for εr, 0.03 % for C10, 1.1 % for
/// nv, whose tolerance is 0.1 σ where that is larger).
#[test]
fn the_move_of_the_optimum_agrees_with_a_re_identification() {
    let exp = Experiment::synthetic(&stack("500 um", "2.25 mm"), &noise(), 3).unwrap();
    let id0 = identified(exp.clone());
    for length in [Length::LayerThickness, Length::Radius] {
        let mut moved = exp.clone();
        let a = moved.scene.actuator;
        moved.scene.actuator = a
            .with_length(length, a.length(length).unwrap() * 0.01f64.exp())
            .unwrap();
        let id1 = identified(moved);
        for (p0, p1) in id0.parameters.iter().zip(&id1.parameters) {
            let actual = 100.0 * (p1.value / p0.value).ln();
            let predicted = per_percent(&id0, &p0.name, length);
            let sigma_pct = 100.0 * p0.std_error.unwrap() / p0.value;
            println!(
                "{length} +1 %: {} moved {actual:+.4} %, predicted {predicted:+.4} % (σ_trace {sigma_pct:.4} %)",
                p0.name
            );
            let tol = (0.01 + 0.01 * predicted.abs()).max(0.1 * sigma_pct);
            assert!(
                (actual - predicted).abs() <= tol,
                "{length}, {}: {actual} vs {predicted} (tolerance {tol})",
                p0.name
            );
        }
    }
}

/// εr from a capacitance trace moves with the geometry as the stack's capacitance
/// law says: at rest C = εr·ε0·π·r0²·nd/zd0, so a capacitance at rest alone gives
/// d ln εr/d ln zd0 = 1 and d ln εr/d ln r0 = −2 exactly. Under voltage
/// C ∝ λ⁻² (seed Eq. 3.22) and the contraction is L0·(1 − λ) with L0 = nd·zd0 +
/// ne·ze0: a thicker layer asks for a smaller strain 1 − λ to give the same
/// contraction, which lowers C by up to 2·(1 − λ)·nd·zd0/L0 of the 1 %, made up by
/// εr. So the thickness ratio lies in [1, 1 + 2·s_max·nd·zd0/L0] (s_max the peak
/// strain), the radius ratio at −2 (r0 changes neither the stress nor the strain);
/// both within 0.005 for the finite difference and the Gauss–Newton step (see the
/// test above).
#[test]
fn permittivity_moves_with_the_layer_thickness_and_radius_as_the_capacitance_law_says() {
    let truth = stack("500 um", "2.25 mm");
    let o = simulate(&truth, &RunOptions::default()).unwrap();
    let rest = o.samples[0].stretch;
    let s_max = o
        .samples
        .iter()
        .map(|s| (rest - s.stretch) / rest)
        .fold(0.0, f64::max);
    let share = 10.0 * 500.0 / (10.0 * 500.0 + 11.0 * 50.0);
    let id = identified(Experiment::synthetic(&truth, &noise(), 5).unwrap());
    let thickness = per_percent(&id, "eps_r", Length::LayerThickness);
    let radius = per_percent(&id, "eps_r", Length::Radius);
    let upper = 1.0 + 2.0 * s_max * share;
    println!("εr per +1 %: layer_thickness {thickness:+.4} % (bound [1, {upper:.4}]), radius {radius:+.4} %; peak strain {s_max:.4}");
    assert!(
        (1.0 - 0.005..=upper + 0.005).contains(&thickness),
        "{thickness}"
    );
    assert!((radius + 2.0).abs() <= 0.005, "{radius}");
}

/// Replicates whose true layer thickness is drawn from the tolerance the scene
/// states (500 ± 10 µm, σ 2 %; the scene runs the nominal 500 µm): εr is then off
/// by the thickness's error, about 2 % against its σ from the trace of 0.03 %. The
/// trace-only interval misses it unless the draw is within ≈ 0.03 σ of the nominal;
/// the interval with the geometry term covers it as a 95 % interval does. Ten
/// replicates (fixed seeds, so the counts are fixed): εr's interval with the
/// geometry covers at least 8 (binomial(10, 0.95): 8 or more with probability
/// 0.99), the trace-only one at most 1, and at least 7 replicates are covered
/// only because of the geometry term. Every other constant's interval still covers
/// at least 17 of 20.
#[test]
fn with_tolerances_the_intervals_cover_a_thickness_the_scene_does_not_know() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let ch = noise();
    let given = stack("500 ± 10 um", "2.25 mm");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let z = Normal::new(0.0, 1.0).unwrap();
    let (mut with, mut trace_only, mut only_with, mut others, mut n_others) = (0, 0, 0, 0, 0);
    for i in 0..10 {
        let layer = 500.0 * (1.0 + 0.02 * z.sample(&mut rng));
        let truth = stack(&format!("{layer} um"), "2.25 mm");
        let mut exp = Experiment::synthetic(&truth, &ch, 100 + i).unwrap();
        exp.scene = given.clone();
        let id = identified(exp);
        assert!(id.geometry.included, "{}", id.geometry.note);
        for p in &id.parameters {
            let truth = match p.name.as_str() {
                "C10" => 69.3e3,
                "eps_r" => 4.7,
                _ => 1875.0,
            };
            let inside = |ci: Option<[f64; 2]>| ci.is_some_and(|[a, b]| a <= truth && truth <= b);
            let (w, t) = (inside(p.ci95), inside(term(&id, &p.name).ci95_trace));
            println!(
                "layer {layer:.1} µm: {} = {} ({:?}; trace only {:?}): with {w}, trace only {t}",
                p.name,
                p.value,
                p.ci95,
                term(&id, &p.name).ci95_trace
            );
            if p.name == "eps_r" {
                with += w as usize;
                trace_only += t as usize;
                only_with += (w && !t) as usize;
            } else {
                others += w as usize;
                n_others += 1;
            }
        }
    }
    println!("εr: {with} of 10 covered with the geometry, {trace_only} trace only, {only_with} only with; others {others} of {n_others}");
    assert!(with >= 8, "{with}");
    assert!(trace_only <= 1, "{trace_only}");
    assert!(only_with >= 7, "{only_with}");
    assert!(others >= 17, "{others} of {n_others}");
}

/// Without a tolerance the intervals are the trace's, the output says they exclude
/// the geometry and how far a 1 % error of each length moves each constant (εr by
/// +1.0x % per layer_thickness), as a note: the status stays ok, and no warning is
/// added. The page shows the geometry section with "excluded".
#[test]
fn without_tolerances_the_output_says_the_intervals_exclude_the_geometry() {
    let truth = stack("500 um", "2.25 mm");
    let exp = Experiment::synthetic(&truth, &noise(), 5).unwrap();
    let id = identified(exp.clone());
    let g = &id.geometry;
    assert!(!g.included && g.tolerances.is_empty());
    assert!(g.note.contains("exclude the geometry"), "{}", g.note);
    assert!(
        g.note.contains("a 1 % error in layer_thickness moves") && g.note.contains("eps_r by +1.0"),
        "{}",
        g.note
    );
    assert!(g.note.contains("a 1 % error in radius moves"), "{}", g.note);
    for t in &g.constants {
        assert_eq!(t.sigma_geometry, None, "{}", t.name);
        let p = id.parameters.iter().find(|p| p.name == t.name).unwrap();
        assert_eq!((p.std_error, p.ci95), (t.sigma_trace, t.ci95_trace));
    }
    assert_eq!(id.status.to_string(), "ok", "{:?}", id.warnings);
    assert!(id.warnings.iter().all(|w| !w.contains("geometry")));
    let v = serde_json::to_value(&id).unwrap();
    assert_eq!(v["geometry"]["included"], false);
    assert_eq!(v["geometry"]["note"], g.note.as_str());
    let page = dea_fit::report::identify::summary(&id, &[exp], &[], None).unwrap();
    assert!(
        page.contains("Geometry") && page.contains("excluded"),
        "{page}"
    );
}

/// `dea-fit identify --json` on the worked example with its scene stating
/// tolerances of the layer thickness (1 %) and the radius: `geometry` names the
/// tolerances that went in and the length taken as exact, each constant's σ is
/// sqrt(σ_trace² + σ_geometry²), and its interval is the trace's widened in ln θ
/// (each half width w → sqrt(w² + (1.96·σ_geometry/θ)²), to 10⁻⁹: arithmetic only).
#[test]
fn the_json_shows_both_parts_and_the_tolerances_that_went_in() {
    let d = super::support::repo().join("datasets/identify");
    let dir = tempfile::tempdir().unwrap();
    let scene = std::fs::read_to_string(d.join("stack.toml"))
        .unwrap()
        .replace(
            "layer_thickness = \"500 um\"",
            "layer_thickness = \"500 ± 5 um\"",
        )
        .replace("radius = \"2.25 mm\"", "radius = \"2.25 +/- 0.02 mm\"");
    std::fs::write(dir.path().join("tol.toml"), scene).unwrap();
    let trace = d.join("step.csv").display().to_string();
    let o = super::support::run_ok(
        dir.path(),
        &[
            "identify",
            &trace,
            "--scene",
            "tol.toml",
            "--free",
            "C10,arm1.k,arm1.tau,nv,eps_r",
            "--starts",
            "1",
            "--no-report",
            "--json",
        ],
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let g = &v["geometry"];
    assert_eq!(g["included"], true);
    let went_in: Vec<&str> = g["tolerances"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["length"].as_str().unwrap())
        .collect();
    assert_eq!(went_in, ["radius", "layer_thickness"]);
    assert_eq!(g["exact"], serde_json::json!(["electrode_thickness"]));
    for p in v["parameters"].as_array().unwrap() {
        let t = g["constants"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["name"] == p["name"])
            .unwrap();
        let f = |x: &serde_json::Value| x.as_f64().unwrap();
        let (value, sd) = (f(&p["value"]), f(&p["std_error"]));
        let (st, sg) = (f(&t["sigma_trace"]), f(&t["sigma_geometry"]));
        assert!((sd / st.hypot(sg) - 1.0).abs() < 1e-9, "{}", p["name"]);
        let z = 1.959_963_984_540_054 * sg / value;
        for k in 0..2 {
            let w_trace = (f(&t["ci95_trace"][k]) / value).ln().abs();
            let w = (f(&p["ci95"][k]) / value).ln().abs();
            assert!(
                (w / w_trace.hypot(z) - 1.0).abs() < 1e-9,
                "{} {k}",
                p["name"]
            );
        }
        println!(
            "{}: σ {st:e} from the trace, {sg:e} from the geometry",
            p["name"]
        );
    }
    // εr: C ∝ εr·r0²/zd0, so its geometry σ is about sqrt((2·0.02/2.25)² + 0.01²)
    let eps = g["constants"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["name"] == "eps_r")
        .unwrap();
    let rel = eps["sigma_geometry"].as_f64().unwrap() / 4.7;
    let closed = (2.0f64 * 0.02 / 2.25).hypot(0.01);
    println!("εr: geometry σ {rel:.5} relative, closed form {closed:.5}");
    // the thickness's share is up to a few % above 1 (see the test above): 5 %
    assert!((rel / closed - 1.0).abs() < 0.05, "{rel} vs {closed}");
}

/// A length with its tolerance is read as the nominal value and the tolerance (a
/// stack's and a helix's lengths; `±`, `+/-`); a bad tolerance is refused at its
/// key's line and column, naming it, with a hint, and the command exits 2: negative,
/// larger than the length (also any on a zero length), not finite, in the wrong unit.
#[test]
fn the_reader_takes_geometry_tolerances_and_refuses_bad_ones() {
    let s = stack("500 ± 5 um", "2.25 +/- 0.02 mm");
    let Actuator::Stack(g) = s.actuator else {
        panic!("a stack")
    };
    // unit conversion only: 1e-12 relative
    assert!((g.layer_m / 500e-6 - 1.0).abs() < 1e-12 && (g.radius_m / 2.25e-3 - 1.0).abs() < 1e-12);
    let want = [(Length::Radius, 0.02e-3), (Length::LayerThickness, 5e-6)];
    assert_eq!(s.tolerances.len(), 2);
    for (t, (l, sigma)) in s.tolerances.iter().zip(want) {
        assert_eq!(t.length, l);
        assert!((t.sigma_m / sigma - 1.0).abs() < 1e-12, "{t:?}");
    }
    assert!(stack("500 um", "2.25 mm").tolerances.is_empty());
    let helix =
        std::fs::read_to_string(super::support::repo().join("datasets/identify/helix.toml"))
            .unwrap();
    let line = helix
        .lines()
        .find(|l| l.trim_start().starts_with("thickness"))
        .expect("a helix thickness");
    let h = Scene::parse(
        &helix.replace(line, "thickness = \"1 ± 0.01 mm\""),
        Path::new("h.toml"),
    )
    .unwrap();
    assert_eq!(h.tolerances.len(), 1);
    assert_eq!(h.tolerances[0].length, Length::Thickness);
    assert!((h.tolerances[0].sigma_m / 1e-5 - 1.0).abs() < 1e-12);
    // where the scene states it (rank refuses it there: tests/rank.rs)
    assert_eq!(h.tolerances[0].at.to_string(), "h.toml:9:1");
    let dir = tempfile::tempdir().unwrap();
    for (layer, electrode, key, want) in [
        (
            "500 ± -5 um",
            "50 um",
            "layer_thickness",
            "must not be negative",
        ),
        (
            "500 ± 600 um",
            "50 um",
            "layer_thickness",
            "from 0 to the length",
        ),
        (
            "500 ± 1e999 um",
            "50 um",
            "layer_thickness",
            "not a finite number",
        ),
        ("500 ± 5 kV", "50 um", "layer_thickness", "layer_thickness"),
        (
            "500 um",
            "0 ± 1 um",
            "electrode_thickness",
            "from 0 to the length",
        ),
    ] {
        let text = stack_text(layer, "2.25 mm").replace(
            "electrode_thickness = \"50 um\"",
            &format!("electrode_thickness = \"{electrode}\""),
        );
        let line = 1 + text
            .lines()
            .position(|l| l.starts_with(key))
            .expect("the key");
        std::fs::write(dir.path().join("s.toml"), text).unwrap();
        let o = super::support::run(dir.path(), &["simulate", "s.toml", "--no-report"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{layer} {electrode}: {err}");
        assert!(
            err.contains(&format!("s.toml:{line}:1: actuator.{key}")) && err.contains(want),
            "{layer} {electrode}: {err}"
        );
        assert!(err.contains("hint:"), "{err}");
    }
}
