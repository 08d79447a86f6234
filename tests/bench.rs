//! `dea-fit bench hyperelastic` and the full-LM baseline it compares against.

use dea_fit::bench::{objective, shipped_datasets, TRELOAR_ALL};
use dea_fit::fit::hyperelastic::{fit, Search, Settings};
use dea_fit::material::hyperelastic::ModelSpec;
use std::path::Path;
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Variable projection and plain full-parameter LM from the same starts minimise the
/// same objective, so on Treloar's three modes both must end at the same optimum
/// (tolerance 1e-9 relative: both finish with the same full-LM polish, which stops
/// on a relative cost change of 1e-12); the solver report names the method used.
#[test]
fn full_lm_and_varpro_reach_the_same_optimum() {
    let sets = shipped_datasets(&root().join("datasets")).unwrap();
    let treloar = &sets.iter().find(|d| d.name == TRELOAR_ALL).unwrap().data;
    let spec = ModelSpec::new("ogden2", Default::default());
    let vp = Settings::default();
    let full = Settings {
        method: Search::Full,
        ..Settings::default()
    };
    let a = fit(treloar, &spec, &vp).unwrap();
    let b = fit(treloar, &spec, &full).unwrap();
    let (oa, ob) = (
        objective(&a, treloar, &vp).unwrap(),
        objective(&b, treloar, &full).unwrap(),
    );
    assert!((oa - ob).abs() <= 1e-9 * oa, "{oa} vs {ob}");
    assert!(a.solver.method.starts_with("variable projection"));
    assert!(b
        .solver
        .method
        .starts_with("bounded Levenberg-Marquardt over all"));
    assert_eq!(a.solver.starts, b.solver.starts);
    assert!(a.solver.starts_at_best >= 1 && b.solver.starts_at_best >= 1);
}

fn bench(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_dea-fit"))
        .current_dir(root())
        .arg("bench")
        .arg("hyperelastic")
        .args(args)
        .output()
        .unwrap()
}

/// One timed run per case: every study is written as CSV rows, charts and a page
/// linking them, and the headline is printed.
#[test]
fn bench_hyperelastic_writes_csv_charts_and_page() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let o = bench(&[
        "--budget",
        "0",
        "--min-repeats",
        "1",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("Yeoh on vhb4910-uniaxial"), "{stdout}");
    assert!(stdout.contains("Ogden-3 on treloar-3modes"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("hyperelastic.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("study,dataset,model,setting,value,fit_median_s"));
    // 8 models × 3 datasets, 7 start counts, 7 tolerances, 5 models × 2 methods.
    assert_eq!(lines.len() - 1, 24 + 7 + 7 + 10);
    for study in ["models,", "starts,", "tolerance,", "method,"] {
        assert!(
            lines.iter().any(|l| l.starts_with(study)),
            "no {study} rows"
        );
    }
    let page = std::fs::read_to_string(out.join("hyperelastic.md")).unwrap();
    let mut charts = 0;
    for entry in std::fs::read_dir(&out).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".svg") {
            charts += 1;
            assert!(page.contains(&format!("]({name})")), "{name} not linked");
            let svg = std::fs::read_to_string(out.join(&name)).unwrap();
            assert!(svg.contains("<svg"), "{name}");
        }
    }
    assert_eq!(charts, 3 + 3, "one chart per dataset and per sweep");
}

#[test]
fn bench_rejects_bad_settings_and_missing_data() {
    let o = bench(&["--min-repeats", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("repeats must satisfy"));
    let o = bench(&["--data-dir", "no/such/dir"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no/such/dir") && err.contains("hint"), "{err}");
}

/// `bench scale` on small sizes: every estimator timed at each size, a finite log-log
/// slope per estimator (no timing threshold: the machine is shared), and the CSV,
/// JSON, chart and page written. Bad size settings are refused.
#[test]
fn bench_scale_writes_rows_slopes_and_chart() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_dea-fit"))
            .current_dir(root())
            .args(["bench", "scale", "--budget", "0", "--min-repeats", "1"])
            .args(["--out-dir", out.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&[
        "--min-rows",
        "30",
        "--max-rows",
        "300",
        "--max-fit-rows",
        "90",
        "--max-relaxation-rows",
        "90",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("scale.json")).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    // Sizes: 30, 95, 300 read; 30, 90 fitted by the automatic choices.
    for (estimator, sizes) in [
        ("read", vec![30, 95, 300]),
        ("read+yeoh", vec![30, 95, 300]),
        ("hyperelastic-auto", vec![30, 90]),
        ("relaxation-auto", vec![30, 90]),
        ("relaxation-report", vec![30, 90]),
    ] {
        let got: Vec<u64> = rows
            .iter()
            .filter(|r| r["estimator"] == estimator)
            .map(|r| r["rows"].as_u64().unwrap())
            .collect();
        assert_eq!(got, sizes, "{estimator}");
        let slope = json["slopes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["estimator"] == estimator)
            .unwrap();
        assert!(slope["slope"].as_f64().unwrap().is_finite(), "{slope}");
        assert!(stdout.contains(estimator), "{stdout}");
    }
    for r in rows {
        let t = r["median_s"].as_f64().unwrap();
        assert!(t > 0.0 && t.is_finite(), "{r}");
    }
    let csv = std::fs::read_to_string(out.join("scale.csv")).unwrap();
    assert!(csv.starts_with("estimator,rows,median_s,min_s,repeats,per_row_s,peak_rss_mb\n"));
    // the peak resident memory of each size's runs (Linux: VmHWM after a reset)
    if cfg!(target_os = "linux") {
        for r in rows {
            let mb = r["peak_rss_mb"].as_f64().unwrap_or(f64::NAN);
            assert!(mb > 1.0 && mb < 1e5, "{r}");
        }
    }
    assert_eq!(csv.lines().count(), 1 + rows.len());
    assert!(std::fs::read_to_string(out.join("scale.svg"))
        .unwrap()
        .contains("<svg"));
    assert!(std::fs::read_to_string(out.join("scale.md"))
        .unwrap()
        .contains("](scale.svg)"));

    let o = run(&["--min-rows", "300", "--max-rows", "100"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--min-rows"));
}

/// `bench identify`'s rows carry the interval stage's time apart from the whole
/// run's: positive (the stage ran: covariance, profile checks) and part of it. A
/// one-arm stack stepped for 1 s at 200 samples, one start, so the case is quick.
#[test]
fn bench_identify_times_the_interval_stage_apart() {
    let text = format!(
        "name = \"bench_case\"\n{}[material]\nhyperelastic = {{ model = \"neo-hookean\", parameters = {{ mu = \"138.6 kPa\" }} }}\nviscous = {{ nv = \"1875 Pa s\", arms = [ {{ k = \"50 kPa\", tau = \"0.2 s\" }} ] }}\nrelative_permittivity = 4.7\ndensity = \"960 kg/m3\"\n[source]\nrise_time = \"20 ms\"\n[[input]]\nkind = \"step\"\namplitude = \"5 kV\"\n[time]\nspan = \"1 s\"\nsamples = 200\n",
        super::support::SEED_STACK_ACTUATOR
    );
    let scene = dea_fit::sim::scene::Scene::parse(&text, Path::new("bench_case.toml")).unwrap();
    let rows = dea_fit::bench::identify_rows(
        &scene,
        &[dea_fit::bench::Drive::ClosedForm],
        &[1e-6],
        &[1],
        1,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    assert!(
        r.interval_s > 0.0 && r.interval_s < r.seconds,
        "interval stage {} s of {} s",
        r.interval_s,
        r.seconds
    );
}
