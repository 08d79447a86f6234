//! `simulate` at any sample count (issue 12): samples streamed to the trajectory
//! CSV, the charts drawn from a decimated copy whose bands hold every skipped sample,
//! the file written atomically, and `--no-report` writing nothing it was not asked for.

use crate::support::{names_in, repo, run_ok};
use dea_fit::io::write::AtomicFile;
use dea_fit::sim::scene::Scene;
use dea_fit::sim::{simulate, simulate_streaming, RunOptions, Sample};
use std::io::Write;

fn shipped(name: &str) -> Scene {
    Scene::read(&repo().join(format!("datasets/scenes/{name}.toml"))).unwrap()
}

fn with_samples(s: &Scene, span: f64, n: usize) -> Scene {
    let mut s = s.clone();
    s.time.span = span;
    s.time.samples = (1..=n).map(|i| span * i as f64 / n as f64).collect();
    s
}

/// The streamed samples are those `simulate` keeps, bit for bit; the kept copy is
/// every k-th and the last; each kept sample's band holds every sample it stands
/// for; the summary (extremes, warnings, status) is over all of them. Both a ringing
/// stack sampled too coarsely (bands from the integrator's steps too) and a
/// well-sampled damped one (bands from the samples alone).
#[test]
fn streaming_sends_every_sample_and_keeps_a_faithful_decimated_copy() {
    for (scene, n) in [
        (with_samples(&shipped("stack_step_5kV"), 0.05, 997), 997),
        (
            with_samples(&shipped("stack_step_5kV_damped"), 1.0, 1003),
            1003,
        ),
    ] {
        let full = simulate(&scene, &RunOptions::default()).unwrap();
        let mut streamed: Vec<Sample> = Vec::new();
        let mut sink = |r: &dea_fit::sim::Row| -> dea_fit::Result<()> {
            streamed.push(*r.sample);
            Ok(())
        };
        let charted = 100;
        let o =
            simulate_streaming(&scene, &RunOptions::default(), charted, Some(&mut sink)).unwrap();
        // bit for bit (α and the reference are NaN for a stack: compared as text)
        let same = |a: &[Sample], b: &[Sample]| format!("{a:?}") == format!("{b:?}");
        assert!(same(&streamed, &full.samples), "{}", scene.name);
        assert_eq!(o.sample_count, n + 1);
        assert_eq!(full.decimation, 1);
        let k = o.decimation;
        assert_eq!(k, (n + 1).div_ceil(charted - 1));
        assert!(o.samples.len() <= charted, "{}", o.samples.len());
        let mut want: Vec<Sample> = streamed.iter().step_by(k).copied().collect();
        if !n.is_multiple_of(k) {
            want.push(streamed[n]);
        }
        assert!(same(&o.samples, &want));
        let env = o.envelope.as_ref().expect("bands for a decimated copy");
        assert_eq!(env.len(), o.samples.len());
        for (j, band) in env.iter().enumerate().skip(1) {
            let (a, b) = (((j - 1) * k).min(n), (j * k).min(n));
            for s in &streamed[a..=b] {
                assert!(
                    band.length_m.lo <= s.length_m && s.length_m <= band.length_m.hi,
                    "band {j}: {} outside {:?}",
                    s.length_m,
                    band.length_m
                );
            }
        }
        assert_eq!(o.extremes(), full.extremes());
        assert_eq!(o.warnings, full.warnings);
        assert_eq!(o.integrator, full.integrator);
    }
}

/// A sink that fails stops the writing and its error is the run's; nothing else is
/// lost (the run itself is not changed by where its samples go).
#[test]
fn a_failing_sink_is_the_runs_error() {
    let scene = shipped("stack_step_5kV_damped");
    let mut rows = 0;
    let mut sink = |_: &dea_fit::sim::Row| -> dea_fit::Result<()> {
        rows += 1;
        match rows {
            5 => Err(dea_fit::Error::settings("disk full".to_string())),
            _ => Ok(()),
        }
    };
    let e = simulate_streaming(&scene, &RunOptions::default(), 100, Some(&mut sink))
        .expect_err("the sink's error");
    assert!(e.to_string().contains("disk full"), "{e}");
    assert_eq!(rows, 5, "no row after the error");
}

/// A streamed file appears only when committed: dropped half-written (an error),
/// neither it nor its temporary file is left; committed, it replaces the target;
/// `commit_keeping` keeps a different old file aside and refreshes an equal one.
#[test]
fn an_atomic_file_appears_only_when_complete() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.csv");
    let mut f = AtomicFile::create(&path).unwrap();
    f.write_all(b"half").unwrap();
    drop(f);
    assert!(
        names_in(dir.path()).is_empty(),
        "{:?}",
        names_in(dir.path())
    );
    let mut f = AtomicFile::create(&path).unwrap();
    f.write_all(b"whole\n").unwrap();
    f.commit().unwrap();
    assert_eq!(names_in(dir.path()), ["t.csv"]);
    let mut f = AtomicFile::create(&path).unwrap();
    f.write_all(b"whole\n").unwrap();
    assert_eq!(
        f.commit_keeping().unwrap(),
        dea_fit::io::write::Replaced::Same
    );
    let mut f = AtomicFile::create(&path).unwrap();
    f.write_all(b"other\n").unwrap();
    assert!(matches!(
        f.commit_keeping().unwrap(),
        dea_fit::io::write::Replaced::KeptAs(_)
    ));
    assert_eq!(names_in(dir.path()), ["t.csv", "t.previous-1.csv"]);
    assert_eq!(std::fs::read(&path).unwrap(), b"other\n");
    assert_eq!(
        std::fs::read(dir.path().join("t.previous-1.csv")).unwrap(),
        b"whole\n"
    );
}

/// `--no-report` without `--out` leaves the working folder untouched (it once wrote
/// the whole trajectory under reports/); with `--out`, that file alone. The CLI's
/// CSV holds every sample even where the report charts a decimated copy.
#[test]
fn no_report_writes_nothing_it_was_not_asked_for() {
    let scene = repo().join("datasets/scenes/stack_step_5kV_damped.toml");
    let scene = scene.to_str().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let o = run_ok(dir.path(), &["simulate", scene, "--no-report", "--json"]);
    assert!(
        names_in(dir.path()).is_empty(),
        "{:?}",
        names_in(dir.path())
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["trajectory"].is_null(), "{}", j["trajectory"]);
    run_ok(
        dir.path(),
        &["simulate", scene, "--no-report", "--out", "t.csv"],
    );
    assert_eq!(names_in(dir.path()), ["t.csv"]);
    let rows = std::fs::read_to_string(dir.path().join("t.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(rows, 1 + 2001, "header and every sample");
    // With the report: the charts from at most 4000 of 8001 samples, the CSV all.
    let mut text = std::fs::read_to_string(scene).unwrap();
    text = text.replace("samples = 2000", "samples = 8000");
    std::fs::write(dir.path().join("many.toml"), text).unwrap();
    run_ok(dir.path(), &["simulate", "many.toml", "--report", "r"]);
    let csv = std::fs::read_to_string(dir.path().join("r/trajectory.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 8001);
    let page = std::fs::read_to_string(dir.path().join("r/index.md")).unwrap();
    assert!(page.contains("one sample in 3 of the 8001"), "{page}");
}

/// The drive's largest |V| (the tolerance scales) of a triangle or a
/// piecewise-linear input is taken at its corners, not from 20 001 samples (a tenth
/// of the 100 Hz triangle's run): exact at the peak, whatever lies between the
/// corners, and the same as dense sampling.
#[test]
fn the_largest_drive_of_linear_pieces_is_at_their_corners() {
    use dea_fit::sim::input::{Term, Waveform};
    let w = Waveform {
        terms: vec![
            Term::Triangle {
                start: 0.001,
                amplitude: 5000.0,
                frequency: 100.0,
                cycles: 5.0,
                offset: -200.0,
            },
            Term::Pwl {
                points: vec![(0.0, 0.0), (0.0123, -7000.0), (0.03, 300.0)],
            },
        ],
    };
    let dense = (0..=200_000)
        .map(|i| w.eval(0.05 * i as f64 / 200_000.0).0.abs())
        .chain(w.kinks(0.0, 0.05).iter().map(|&t| w.eval(t).0.abs()))
        .fold(0.0, f64::max);
    let got = w.max_abs(0.0, 0.05);
    assert!((got - dense).abs() <= 1e-9 * dense, "{got} vs {dense}");
    // not below any corner's value
    for t in w.kinks(0.0, 0.05) {
        assert!(got >= w.eval(t).0.abs(), "{got} at {t}");
    }
}
