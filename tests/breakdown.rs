//! `dea-fit breakdown` and `synth breakdown` end to end: the fit file passes the
//! core's reader and its strength is the command's actuator α, bad series are
//! refused at file:line:col with nothing written, `--json` holds the fields,
//! the status agrees with the exit code under `--strict`, the report draws the
//! probability plot, synth is deterministic and its law is recovered, and the
//! shipped series' output is golden.

use crate::cli::golden;
use crate::support::{names_in, repo, run, run_ok};
use dea_fit::material::file::read_breakdown;
use serde_json::Value;
use std::path::Path;

fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("tempdir")
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A synthetic series in `dir` (n specimens, the given limit), its file name.
fn synth(dir: &Path, name: &str, n: &str, limit: Option<&str>, seed: &str) -> String {
    let mut args = vec![
        "synth",
        "breakdown",
        "--alpha",
        "30V/um",
        "--beta",
        "8",
        "--n",
        n,
        "--thickness",
        "300um",
        "--thickness-spread",
        "5%",
        "--area",
        "1cm2",
        "--seed",
        seed,
        "--out",
        name,
    ];
    if let Some(l) = limit {
        args.extend(["--limit", l]);
    }
    run_ok(dir, &args);
    name.to_string()
}

fn json(o: &std::process::Output) -> Value {
    serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("not JSON: {e}\n{}", stdout(o)))
}

/// The fit file is what scenes and the ranking read: `read_breakdown` accepts it,
/// and `BreakdownFit::strength` at the actuator's area is the α the command prints
/// for `--area` (both the weakest-link law on the same α and β: relative 1e-9,
/// rounding of two pows), with the parameters in SI and the fields the issue names.
#[test]
fn fit_file_passes_the_core_reader_and_agrees_on_the_area_law() {
    let dir = tempdir();
    let file = synth(dir.path(), "s.csv", "15", Some("9kV"), "1");
    let o = run_ok(
        dir.path(),
        &[
            "breakdown",
            &file,
            "--area",
            "40cm2",
            "--json",
            "--no-report",
            "--out",
            "f.json",
        ],
    );
    let v = json(&o);
    for key in [
        "status",
        "method",
        "n",
        "failures",
        "survived",
        "parameters",
        "beta_unbiased",
        "log_likelihood",
        "percentiles",
        "fit_file",
    ] {
        assert!(v.get(key).is_some(), "--json lacks {key}: {v}");
    }
    assert_eq!(v["fit_file"], "f.json");
    assert_eq!(v["method"], "mle");
    let n = v["n"].as_u64().unwrap();
    assert_eq!(
        n,
        v["failures"].as_u64().unwrap() + v["survived"].as_u64().unwrap()
    );
    assert!(
        v["survived"].as_u64().unwrap() > 0,
        "the 9 kV limit censors"
    );
    let alpha = &v["parameters"][0];
    assert_eq!(alpha["name"], "alpha");
    assert_eq!(alpha["unit"], "V/m");
    let a = alpha["value"].as_f64().unwrap();
    // α in V/m near the 30 V/µm that made the data (15 specimens: within 20 %).
    assert!((a / 30e6 - 1.0).abs() < 0.2, "{a}");
    let ci = alpha["ci95"].as_array().unwrap();
    assert!(ci[0].as_f64().unwrap() < a && a < ci[1].as_f64().unwrap());
    let fit = read_breakdown(&dir.path().join("f.json")).expect("the core reads the file");
    assert_eq!(fit.n as u64, n);
    // 100 mm² read as 100 · 1e-6 m²: relative 1e-15.
    assert!((fit.reference_area.unwrap() / 1e-4 - 1.0).abs() < 1e-15);
    let s = fit.strength(Some(40e-4), None, None, "f.json");
    let at_area = v["actuator"]["percentiles"][2]["value"].as_f64().unwrap();
    assert!(
        (s.field / at_area - 1.0).abs() < 1e-9,
        "{} vs {at_area}",
        s.field
    );
    assert!(s.notes[0].contains("weakest link"), "{:?}", s.notes);
    // 40× the area at β ≈ 8: α × 40^(−1/β) ≈ 0.63.
    assert!(s.field < a && s.field > 0.5 * a);
}

/// Bad series are refused where they are wrong (file:line:col, a hint), exit 2, and
/// nothing is written: no fit file, no report folder.
#[test]
fn bad_series_are_refused_at_their_place_and_nothing_is_written() {
    let dir = tempdir();
    for (text, want) in [
        (
            "field_V_per_um\n30\n-2\n",
            "bad.csv:3:1: field must be positive",
        ),
        (
            "field_V_per_um,survived\n30,0\n31,yes\n",
            "bad.csv:3:2: survived must be 0 or 1",
        ),
        (
            "field_V_per_um,survived\n30,1\n31,1\n",
            "bad.csv:1:2: every one of the 2 specimens survived",
        ),
        (
            "field_V_per_um,survived\n30,0\n31,1\n",
            "1 breakdown among 2",
        ),
        (
            "field_V_per_um,voltage_kV\n30,9\n31,9\n",
            "bad.csv:1:2: a second breakdown field column",
        ),
        ("field\n30\n31\n", "bad.csv:1:1: column 'field' has no unit"),
        (
            "voltage_kV\n9\n9.5\n",
            "is a voltage: the field needs the film thickness",
        ),
    ] {
        std::fs::write(dir.path().join("bad.csv"), text).unwrap();
        let o = run(dir.path(), &["breakdown", "bad.csv"]);
        assert_eq!(o.status.code(), Some(2), "{text:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(want), "{text:?}: {e}");
        assert!(e.contains("hint:"), "{text:?}: {e}");
        assert_eq!(
            names_in(dir.path()),
            ["bad.csv"],
            "{text:?} wrote something"
        );
    }
    // A flag that does not fit the data: --area without any specimen area.
    std::fs::write(dir.path().join("s.csv"), "field_V_per_um\n30\n31\n33\n").unwrap();
    let o = run(dir.path(), &["breakdown", "s.csv", "--area", "40cm2"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--specimen-area"), "{}", stderr(&o));
    assert_eq!(names_in(dir.path()), ["bad.csv", "s.csv"]);
}

/// Rank regression names its plotting position in the JSON, the file and the
/// summary, and the choice of position moves β (the issue: "in the second digit").
#[test]
fn rank_regression_names_its_plotting_position() {
    let dir = tempdir();
    let file = synth(dir.path(), "s.csv", "12", None, "3");
    let beta = |pos: &str| {
        let v = json(&run_ok(
            dir.path(),
            &[
                "breakdown",
                &file,
                "--method",
                "rry",
                "--positions",
                pos,
                "--json",
                "--no-report",
                "--out",
                "f.json",
            ],
        ));
        assert_eq!(v["method"], "rry");
        assert_eq!(v["positions"], pos);
        v["parameters"][1]["value"].as_f64().unwrap()
    };
    let (b, e) = (beta("bernard"), beta("exact"));
    assert_ne!(b, e);
    let o = run_ok(
        dir.path(),
        &[
            "breakdown",
            &file,
            "--method",
            "rrx",
            "--positions",
            "ieee930",
            "--no-report",
        ],
    );
    assert!(
        stdout(&o).contains("plotting positions ieee930"),
        "{}",
        stdout(&o)
    );
}

/// Fewer than ten specimens is a warning (with β's interval), never blocking: the
/// printed status is `warning` and the exit status 0, with and without --strict.
#[test]
fn a_small_series_warns_and_the_exit_code_agrees() {
    let dir = tempdir();
    let file = synth(dir.path(), "s.csv", "6", None, "5");
    for strict in [false, true] {
        let mut args = vec!["breakdown", file.as_str(), "--no-report"];
        if strict {
            args.push("--strict");
        }
        let o = run(dir.path(), &args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let out = stdout(&o);
        assert!(out.contains("status: warning"), "{out}");
        assert!(out.contains("only 6 specimens"), "{out}");
    }
}

/// The report: a Weibull probability plot whose y ticks read in % of specimens
/// failed, with open marks for the survivors, a page with the table, the run's
/// metadata and the folder's run list.
#[test]
fn report_draws_the_probability_plot() {
    let dir = tempdir();
    let file = synth(dir.path(), "s.csv", "15", Some("9kV"), "1");
    let o = run_ok(dir.path(), &["breakdown", &file]);
    assert!(stdout(&o).contains("report: reports"), "{}", stdout(&o));
    let rep = dir.path().join("reports");
    let run_dir = rep.join(
        names_in(&rep)
            .into_iter()
            .find(|n| n.ends_with("-breakdown"))
            .expect("a breakdown report folder"),
    );
    for f in ["index.html", "index.md", "run.json", "weibull.svg"] {
        assert!(run_dir.join(f).exists(), "{f}");
    }
    assert!(rep.join("index.html").exists(), "the run list");
    let svg = std::fs::read_to_string(run_dir.join("weibull.svg")).unwrap();
    let doc = scraper::Html::parse_document(&svg);
    let texts: Vec<String> = doc
        .select(&scraper::Selector::parse("text").unwrap())
        .map(|t| t.text().collect::<String>().trim().to_string())
        .collect();
    for tick in ["1 %", "10 %", "63.2 %", "90 %"] {
        assert!(texts.iter().any(|t| t == tick), "no tick {tick}: {texts:?}");
    }
    // Field ticks exist on the short log axis (less than a decade of field).
    assert!(
        texts.iter().filter(|t| t.parse::<f64>().is_ok()).count() >= 3,
        "{texts:?}"
    );
    // Survivors are open circles (no fill), breakdowns filled.
    let circles: Vec<_> = doc
        .select(&scraper::Selector::parse("circle").unwrap())
        .collect();
    let open = circles
        .iter()
        .filter(|c| c.value().attr("fill") == Some("none"))
        .count();
    let v = json(&run_ok(
        dir.path(),
        &["breakdown", &file, "--json", "--no-report"],
    ));
    let survivors = v["survived"].as_u64().unwrap() as usize;
    // One open legend key besides the survivors.
    assert_eq!(open, survivors + 1, "{open} open circles");
    let md = std::fs::read_to_string(run_dir.join("index.md")).unwrap();
    assert!(md.contains("β unbiased") && md.contains("E_1%"), "{md}");
}

/// synth breakdown is deterministic by seed (same bytes), and a long uncensored
/// series recovers its law: at n = 2000, σ(α)/α ≈ 1.05/(β√n) = 0.3 % and σ(β)/β ≈
/// 0.78/√n = 1.7 % (Cohen 1965, the MLE's asymptotic variances), so 1.5 % on α and
/// 9 % on β are five σ. With a limit, every specimen at or beyond it is a survivor
/// at the limit.
#[test]
fn synth_is_deterministic_and_its_law_is_recovered() {
    let dir = tempdir();
    synth(dir.path(), "a.csv", "40", Some("9kV"), "11");
    synth(dir.path(), "b.csv", "40", Some("9kV"), "11");
    let a = std::fs::read_to_string(dir.path().join("a.csv")).unwrap();
    assert_eq!(
        a,
        std::fs::read_to_string(dir.path().join("b.csv")).unwrap()
    );
    assert!(a.contains("# param alpha = 3e7 V/m, beta = 8e0"), "{a}");
    for line in a.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let v: f64 = f[1].parse().unwrap();
        assert_eq!(f[3] == "1", v >= 9.0, "{line}");
    }
    synth(dir.path(), "big.csv", "2000", None, "12");
    let v = json(&run_ok(
        dir.path(),
        &["breakdown", "big.csv", "--json", "--no-report"],
    ));
    let alpha = v["parameters"][0]["value"].as_f64().unwrap();
    let beta = v["parameters"][1]["value"].as_f64().unwrap();
    assert!((alpha / 30e6 - 1.0).abs() < 0.015, "α {alpha}");
    assert!((beta / 8.0 - 1.0).abs() < 0.09, "β {beta}");
}

/// The shipped series: the summary `dea-fit breakdown datasets/breakdown/
/// vhb4910-coupons.csv --area 40cm2` prints (numbers rounded to four digits,
/// compared as text) is golden; its bounds hold the generating α and β.
#[test]
fn golden_shipped_series() {
    let dir = tempdir();
    let out = dir.path().join("f.json");
    let o = run_ok(
        &repo(),
        &[
            "breakdown",
            "datasets/breakdown/vhb4910-coupons.csv",
            "--area",
            "40cm2",
            "--no-report",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let text: String = stdout(&o)
        .lines()
        .map(|l| match l.starts_with("fit: ") {
            true => "fit: <out>\n".to_string(),
            false => format!("{l}\n"),
        })
        .collect();
    golden("breakdown-vhb4910-coupons.txt", &text, |want| {
        (want != text).then(|| "the text differs".to_string())
    });
    let fit = read_breakdown(&out).unwrap();
    let bounds = |name: &str| fit.parameter(name).unwrap().ci95.unwrap();
    let [lo, hi] = bounds("alpha");
    assert!(lo < 25e6 && 25e6 < hi, "α bounds {lo}..{hi}");
    let [lo, hi] = bounds("beta");
    assert!(lo < 10.0 && 10.0 < hi, "β bounds {lo}..{hi}");
}
