//! The LM search machinery: checkpoint and resume, the iteration trace, the
//! wall-time limit, the multi-start design and the "starts at best" count.

use dea_fit::fit::lm::{self, Checkpoint, Control, LeastSquares, LmSettings, Termination};
use dea_fit::fit::multistart::{self, latin_hypercube, starts_at_best};
use dea_fit::observe::{Meter, Searches, Show, Trace};
use nalgebra::{DMatrix, DVector};
use std::time::Duration;

const FREE: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);

/// Rosenbrock as least squares, r = (10(y − x²), 1 − x): some twenty iterations from
/// (−1.2, 1), enough to interrupt in the middle.
#[derive(Clone)]
struct Rosen;

impl LeastSquares for Rosen {
    fn dims(&self) -> (usize, usize) {
        (2, 2)
    }
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        r[0] = 10.0 * (p[1] - p[0] * p[0]);
        r[1] = 1.0 - p[0];
        if let Some(j) = jac {
            j[(0, 0)] = -20.0 * p[0];
            j[(0, 1)] = 10.0;
            j[(1, 0)] = -1.0;
            j[(1, 1)] = 0.0;
        }
        true
    }
}

fn checkpoint(dir: &tempfile::TempDir) -> Checkpoint {
    Checkpoint {
        file: dir.path().join("search.ckpt"),
        every: 1,
        problem: Vec::new(),
    }
}

/// Exact equality: a resumed search repeats the same arithmetic on the same bits.
fn assert_same(a: &lm::LmResult, b: &lm::LmResult) {
    assert_eq!(a.x, b.x, "{a:?} vs {b:?}");
    assert_eq!(a.cost.to_bits(), b.cost.to_bits(), "{a:?} vs {b:?}");
    assert_eq!(
        (a.iterations, a.evaluations, &a.termination),
        (b.iterations, b.evaluations, &b.termination)
    );
}

#[test]
fn a_resumed_search_ends_as_an_uninterrupted_one() {
    let settings = LmSettings::default();
    let whole = lm::minimize(&mut Rosen, &[-1.2, 1.0], &[FREE; 2], &settings);
    assert!(matches!(whole.termination, Termination::Converged(_)));
    assert!(whole.iterations > 5, "{whole:?}");
    for k in [1, 3, whole.iterations - 1] {
        let dir = tempfile::tempdir().unwrap();
        // Stopped by the iteration limit after k iterations.
        let mut control = Control {
            checkpoint: Some(checkpoint(&dir)),
            ..Control::default()
        };
        let short = LmSettings {
            max_iterations: k,
            ..settings
        };
        let first = lm::search(&mut Rosen, &[-1.2, 1.0], &[FREE; 2], &short, &mut control);
        assert_eq!(
            (first.iterations, &first.termination),
            (k, &Termination::MaxIterations)
        );
        // Resumed with the full limit; the start given is ignored.
        let mut control = Control {
            checkpoint: Some(checkpoint(&dir)),
            resume: true,
            ..Control::default()
        };
        let rest = lm::search(&mut Rosen, &[9.0, 9.0], &[FREE; 2], &settings, &mut control);
        assert_same(&rest, &whole);
    }
}

#[test]
fn the_wall_time_limit_stops_and_the_search_resumes_from_there() {
    let settings = LmSettings::default();
    let whole = lm::minimize(&mut Rosen, &[-1.2, 1.0], &[FREE; 2], &settings);
    let dir = tempfile::tempdir().unwrap();
    // A zero limit is passed by the end of the first iteration; the checkpoint
    // cadence is long, and the stop saves anyway.
    let mut control = Control {
        checkpoint: Some(Checkpoint {
            every: 1000,
            ..checkpoint(&dir)
        }),
        max_wall: Some(Duration::ZERO),
        ..Control::default()
    };
    let first = lm::search(
        &mut Rosen,
        &[-1.2, 1.0],
        &[FREE; 2],
        &settings,
        &mut control,
    );
    assert_eq!(
        (first.iterations, &first.termination),
        (1, &Termination::WallTime)
    );
    let mut control = Control {
        checkpoint: Some(checkpoint(&dir)),
        resume: true,
        ..Control::default()
    };
    let rest = lm::search(
        &mut Rosen,
        &[-1.2, 1.0],
        &[FREE; 2],
        &settings,
        &mut control,
    );
    assert_same(&rest, &whole);
}

/// Three parameters: the checkpoint of the two-parameter Rosenbrock is not its own.
struct Line;

impl LeastSquares for Line {
    fn dims(&self) -> (usize, usize) {
        (2, 3)
    }
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        r[0] = p[0] + p[1] + p[2] - 1.0;
        r[1] = p[0] - p[2];
        if let Some(j) = jac {
            j.copy_from_slice(&[1.0, 1.0, 1.0, 0.0, 1.0, -1.0]);
        }
        true
    }
}

#[test]
fn a_checkpoint_of_another_problem_is_refused_and_one_not_asked_for_is_not_read() {
    let dir = tempfile::tempdir().unwrap();
    let settings = LmSettings {
        max_iterations: 2,
        ..LmSettings::default()
    };
    let mut control = Control {
        checkpoint: Some(checkpoint(&dir)),
        ..Control::default()
    };
    lm::search(
        &mut Rosen,
        &[-1.2, 1.0],
        &[FREE; 2],
        &settings,
        &mut control,
    );
    let mut resume = Control {
        checkpoint: Some(checkpoint(&dir)),
        resume: true,
        ..Control::default()
    };
    let other = lm::search(&mut Line, &[0.0; 3], &[FREE; 3], &settings, &mut resume);
    match &other.termination {
        Termination::Failed(why) => assert!(why.contains("written for a problem"), "{why}"),
        t => panic!("resumed another problem's checkpoint: {t:?}"),
    }
    // Other bounds, same sizes: refused too.
    let mut resume = Control {
        checkpoint: Some(checkpoint(&dir)),
        resume: true,
        ..Control::default()
    };
    let bounded = lm::search(
        &mut Rosen,
        &[-1.2, 1.0],
        &[(-2.0, 2.0); 2],
        &settings,
        &mut resume,
    );
    assert!(
        matches!(bounded.termination, Termination::Failed(_)),
        "{bounded:?}"
    );
    // Without `resume` a file that is not even a checkpoint is overwritten, not read.
    std::fs::write(dir.path().join("search.ckpt"), "not a checkpoint").unwrap();
    let mut fresh = Control {
        checkpoint: Some(checkpoint(&dir)),
        ..Control::default()
    };
    let res = lm::search(&mut Rosen, &[-1.2, 1.0], &[FREE; 2], &settings, &mut fresh);
    assert_same(
        &res,
        &lm::minimize(&mut Rosen, &[-1.2, 1.0], &[FREE; 2], &settings),
    );
    // With `resume` that file is refused with its name.
    std::fs::write(dir.path().join("search.ckpt"), "not a checkpoint").unwrap();
    let mut resume = Control {
        checkpoint: Some(checkpoint(&dir)),
        resume: true,
        ..Control::default()
    };
    let bad = lm::search(&mut Rosen, &[-1.2, 1.0], &[FREE; 2], &settings, &mut resume);
    match &bad.termination {
        Termination::Failed(why) => assert!(why.contains("search.ckpt"), "{why}"),
        t => panic!("read a file that is no checkpoint: {t:?}"),
    }
}

#[test]
fn the_trace_has_a_line_per_iteration_ending_at_the_result() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.jsonl");
    let trace = Trace::create(&path).unwrap();
    let mut control = Control {
        observers: vec![Box::new(trace.observer(7))],
        ..Control::default()
    };
    let res = lm::search(
        &mut Rosen,
        &[-1.2, 1.0],
        &[FREE; 2],
        &LmSettings::default(),
        &mut control,
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), res.iterations + 1, "{text}");
    for (k, line) in lines.iter().enumerate() {
        assert_eq!(line["start"], 7);
        assert_eq!(line["iteration"], k as u64);
        assert!(line["damping"].as_f64().unwrap() > 0.0, "{line}");
    }
    // Costs only decrease (every iteration is an accepted step).
    let costs: Vec<f64> = lines.iter().map(|l| l["cost"].as_f64().unwrap()).collect();
    assert!(costs.windows(2).all(|w| w[1] < w[0]), "{costs:?}");
    let last = lines.last().unwrap();
    assert_eq!(last["evaluations"], res.evaluations as u64);
    // JSON prints the shortest decimal that reads back as the same f64; 1e-15
    // relative allows a reader that rounds the last bit.
    for (j, v) in last["x"].as_array().unwrap().iter().enumerate() {
        let v = v.as_f64().unwrap();
        assert!(
            (v - res.x[j]).abs() <= 1e-15 * res.x[j].abs(),
            "{v} vs {}",
            res.x[j]
        );
    }
}

/// Which of `n` equal strata of [a, b] holds `v`.
fn stratum(v: f64, (a, b): (f64, f64), n: usize) -> usize {
    (((v - a) / (b - a) * n as f64).floor() as usize).min(n - 1)
}

#[test]
fn the_latin_hypercube_puts_one_start_in_every_stratum_reproducibly() {
    let bounds = [(-2.0, 3.0), (1e-3, 1e3), (0.0, 1e6), (5.0, 5.0)];
    let n = 16;
    let design = latin_hypercube(&bounds, n, 42).unwrap();
    assert_eq!(design.len(), n);
    for (j, &(lo, hi)) in bounds.iter().enumerate() {
        assert!(
            design.iter().all(|s| s[j] >= lo && s[j] <= hi),
            "{j}: {design:?}"
        );
        if lo == hi {
            continue;
        }
        // Log space for the positive lower bound: strata of equal ratio.
        let (t, range): (fn(f64) -> f64, _) = if lo > 0.0 {
            (f64::ln, (lo.ln(), hi.ln()))
        } else {
            (|v| v, (lo, hi))
        };
        let mut seen: Vec<usize> = design.iter().map(|s| stratum(t(s[j]), range, n)).collect();
        seen.sort();
        assert_eq!(seen, (0..n).collect::<Vec<_>>(), "parameter {j}");
    }
    assert_eq!(design, latin_hypercube(&bounds, n, 42).unwrap());
    assert_ne!(design, latin_hypercube(&bounds, n, 43).unwrap());
    let err = latin_hypercube(&[(0.0, f64::INFINITY)], 4, 1).unwrap_err();
    assert!(err.to_string().contains("finite"), "{err}");
}

#[test]
fn starts_at_best_counts_within_the_stated_tolerance() {
    // 1e-6 relative: 1 + 5e-7 is at the best, 1 + 2e-6 is not; NaN and ∞ never are.
    assert_eq!(
        starts_at_best(&[1.0, 1.0 + 5e-7, 1.0 + 2e-6, f64::INFINITY, f64::NAN], 0.0),
        2
    );
    // The absolute floor for an exact fit.
    assert_eq!(starts_at_best(&[0.0, 1e-25, 1e-19, 1e-17], 0.0), 3);
    assert_eq!(starts_at_best(&[f64::NAN, f64::INFINITY], 0.0), 0);
    // Searches stopped at a noise floor of 1e-3 (½χ²): within 2e-3 of the best.
    assert_eq!(starts_at_best(&[1.0, 1.0 + 1.9e-3, 1.0 + 2.2e-3], 1e-3), 2);
}

/// r = (p² − 1, 0.3 (p − 1)): the global minimum p = 1 (cost 0) and a local one near
/// p = −1 (cost ≈ 0.18), separated by a maximum near p = 0.
#[derive(Clone)]
struct TwoMinima;

impl LeastSquares for TwoMinima {
    fn dims(&self) -> (usize, usize) {
        (2, 1)
    }
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        r[0] = p[0] * p[0] - 1.0;
        r[1] = 0.3 * (p[0] - 1.0);
        if let Some(j) = jac {
            j[(0, 0)] = 2.0 * p[0];
            j[(1, 0)] = 0.3;
        }
        true
    }
}

#[test]
fn a_multi_start_counts_the_starts_that_reach_the_best_minimum() {
    let bounds = [(-2.0, 2.0)];
    let mut starts = latin_hypercube(&bounds, 12, 7).unwrap();
    starts.push(vec![-1.0]);
    let settings = LmSettings::default();
    // no racing (an infinite margin): every start runs as it would alone
    let ms = multistart::run(
        &TwoMinima,
        &starts,
        &bounds,
        &settings,
        f64::INFINITY,
        |_| Control::default(),
    );
    // Parallel runs are the sequential ones, start by start.
    for (x0, res) in &ms.runs {
        assert_same(res, &lm::minimize(&mut TwoMinima, x0, &bounds, &settings));
    }
    let global = ms
        .runs
        .iter()
        .filter(|(_, r)| (r.x[0] - 1.0).abs() < 1e-6)
        .count();
    assert!(global > 0 && global < starts.len(), "{:?}", ms.runs);
    let costs: Vec<f64> = ms.runs.iter().map(|(_, r)| r.cost).collect();
    assert_eq!(ms.at_best, global, "{costs:?}");
    // The others sit in the local minimum, far above the tolerance.
    assert!(ms
        .runs
        .iter()
        .filter(|(_, r)| (r.x[0] - 1.0).abs() >= 1e-6)
        .all(|(_, r)| r.cost > 0.1));
    let best = ms.best().unwrap();
    assert!(
        (best.x[0] - 1.0).abs() < 1e-6 && best.cost < 1e-20,
        "{best:?}"
    );
    let fall = ms.waterfall();
    assert!(fall.windows(2).all(|w| w[0] <= w[1]) && fall.len() == starts.len());
}

#[test]
fn the_progress_bar_counts_the_finished_starts() {
    let meter = Meter::shown(
        Show::Off,
        std::time::Duration::from_secs(5),
        "test",
        "searches",
        Some(3),
    );
    let searches = Searches::new(meter);
    let starts = vec![vec![-1.2, 1.0]; 3];
    let settings = LmSettings::default();
    let ms = multistart::run(&Rosen, &starts, &[FREE; 2], &settings, 0.0, |i| Control {
        observers: vec![Box::new(searches.observer(i))],
        ..Control::default()
    });
    assert_eq!(searches.meter().position(), (3, Some(3)));
    assert_eq!(ms.at_best, 3);
    let msg = searches.meter().message();
    assert!(msg.contains("cost"), "{msg}");
}

/// [`TwoMinima`] with a Jacobian ten times too large for p < 0: from there the
/// search creeps into the local minimum (cost ≈ 0.18) by about a tenth of the way
/// per iteration, while the global one (p = 1) has cost 0.
#[derive(Clone)]
struct Creeping;

impl LeastSquares for Creeping {
    fn dims(&self) -> (usize, usize) {
        (2, 1)
    }
    fn eval(&mut self, p: &[f64], r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) -> bool {
        let scale = if p[0] < 0.0 { 10.0 } else { 1.0 };
        match jac {
            Some(j) => {
                TwoMinima.eval(p, r, Some(&mut *j));
                *j *= scale;
                true
            }
            None => TwoMinima.eval(p, r, None),
        }
    }
}

/// Racing: starts creeping towards the local minimum are abandoned once they
/// cannot come within reach of the first start's cost (0, at the global minimum),
/// with fewer evaluations than they would take alone, and counted; a start that
/// reaches the global minimum is not abandoned; the result does not depend on the
/// number of threads.
#[test]
fn starts_out_of_reach_of_the_first_are_abandoned() {
    let bounds = [(-2.0, 2.0)];
    let starts = vec![vec![1.0], vec![-2.0], vec![-1.5], vec![0.5]];
    let settings = LmSettings::default();
    let race = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                multistart::run(&Creeping, &starts, &bounds, &settings, 0.0, |_| {
                    Control::default()
                })
            })
    };
    let ms = race(2);
    assert_eq!(ms.abandoned, 2, "{:?}", ms.runs);
    assert_eq!(ms.at_best, 2);
    for (x0, res) in &ms.runs {
        let alone = lm::minimize(&mut Creeping, x0, &bounds, &settings);
        match &res.termination {
            Termination::Abandoned(why) => {
                assert!(x0[0] < 0.0 && res.cost > 0.17, "{x0:?}: {res:?}");
                assert!(why.contains("above the best start's"), "{why}");
                assert!(res.evaluations < alone.evaluations, "{res:?} vs {alone:?}");
            }
            _ => assert_same(res, &alone),
        }
    }
    for (a, b) in ms.runs.iter().zip(&race(1).runs) {
        assert_same(&a.1, &b.1);
    }
}

/// A search's label (`Control::label`: the candidate of `identify --hyperelastic
/// auto`, a reduction round) reaches its progress line.
#[test]
fn the_progress_line_names_what_is_searched() {
    let meter = Meter::shown(
        Show::Off,
        std::time::Duration::from_secs(5),
        "test",
        "searches",
        Some(1),
    );
    let searches = Searches::new(meter);
    let mut control = Control {
        observers: vec![Box::new(searches.observer(0))],
        label: Some("candidate yeoh, 2 arm(s)".into()),
        ..Control::default()
    };
    lm::search(
        &mut Rosen,
        &[-1.2, 1.0],
        &[FREE; 2],
        &LmSettings::default(),
        &mut control,
    );
    let msg = searches.meter().message();
    assert!(
        msg.starts_with("candidate yeoh, 2 arm(s): start 0"),
        "{msg}"
    );
}
