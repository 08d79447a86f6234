//! Actuator traces: the measured-voltage input (corners found, none invented in
//! noise, the signal reconstructed), the trace reader, `Trace::scene`, and
//! `synth trace` round trips.

use dea_fit::sim::input::measured::Work;
use dea_fit::sim::input::Measured;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;
use std::time::{Duration, Instant};

/// A noisy record of `truth` at `times`: Gaussian noise σ, seeded.
fn record(times: &[f64], truth: &dyn Fn(f64) -> f64, sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = Normal::new(0.0, sigma).expect("valid σ");
    times
        .iter()
        .map(|&t| truth(t) + n.sample(&mut rng))
        .collect()
}

fn regular(span: f64, dt: f64) -> Vec<f64> {
    (0..=(span / dt).round() as usize)
        .map(|i| i as f64 * dt)
        .collect()
}

/// Bursts: 100 samples at dt/2, then 50 at 2·dt, with ±20 % jitter (seeded).
fn bursts(span: f64, dt: f64, seed: u64) -> Vec<f64> {
    use rand::Rng;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut t = vec![0.0];
    let mut k = 0usize;
    while *t.last().unwrap() < span {
        let base = if k % 150 < 100 { 0.5 * dt } else { 2.0 * dt };
        let step = base * rng.gen_range(0.8..1.2);
        t.push(t.last().unwrap() + step);
        k += 1;
    }
    t.pop();
    t
}

const A: f64 = 5000.0;
const SIGMA: f64 = 0.01 * A;

fn ramp(t: f64, t0: f64, t1: f64, a: f64) -> f64 {
    a * ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
}

fn triangle(t: f64) -> f64 {
    // 1 Hz, 2 cycles from 0.5 s, 0 … A
    let s = t - 0.5;
    if !(0.0..2.0).contains(&s) {
        return 0.0;
    }
    let ph = s - s.floor();
    A * if ph < 0.5 { 2.0 * ph } else { 2.0 * (1.0 - ph) }
}

/// A true corner: a step edge (either corner of the pair lies within one sample
/// interval of it) or a slope jump, located within its tolerance in sample
/// intervals.
#[derive(Debug, Clone, Copy)]
enum Corner {
    S(f64),
    K(f64, f64),
}
use Corner::{K, S};

/// How far the slope corners of [`cases`] may lie from the truth, in sample
/// intervals. At σ = 50 V the slope jumps are 20 V per sample at the triangle's
/// peaks, 10 V at the ramp's ends and 6 V at the sum's (on a curving sine): the
/// least-squares location of two lines meeting at a corner, n samples a side, has
/// the standard error σ/Δs·√(8/n) intervals, 0.32 and 0.63 here (n ≈ 500; 0.39 and
/// 0.57 measured as the RMS over 20 seeds), and about 4 of them is allowed; the
/// sum's sides curve, so they are fitted as parabolas or cubics meeting at the
/// corner, which places it less well (1.2–1.8 intervals RMS over 20 seeds, the
/// largest error seen 3.8).
const TRIANGLE_INTERVALS: f64 = 1.5;
const RAMP_INTERVALS: f64 = 2.5;
const SUM_INTERVALS: f64 = 5.0;

/// A true signal.
type Signal = Box<dyn Fn(f64) -> f64>;

/// The cases: name, truth, true interior corners (a step's pair: its time twice).
fn cases() -> Vec<(&'static str, Signal, Vec<Corner>)> {
    vec![
        (
            "step",
            Box::new(|t| if t >= 0.5004 { A } else { 0.0 }),
            vec![S(0.5004), S(0.5004)],
        ),
        (
            "ramp-hold",
            Box::new(|t| ramp(t, 0.5, 1.0, A)),
            vec![K(0.5, RAMP_INTERVALS), K(1.0, RAMP_INTERVALS)],
        ),
        (
            "triangle",
            Box::new(triangle),
            [0.5, 1.0, 1.5, 2.0, 2.5]
                .map(|t| K(t, TRIANGLE_INTERVALS))
                .to_vec(),
        ),
        (
            "sine",
            Box::new(|t| 0.5 * A * (1.0 - (2.0 * PI * t).cos())),
            vec![],
        ),
        (
            "sum",
            Box::new(|t| {
                ramp(t, 0.5, 1.0, 0.6 * A)
                    + 0.05 * A * (1.0 - (2.0 * PI * t).cos())
                    + if t >= 2.0 { 0.3 * A } else { 0.0 }
            }),
            vec![K(0.5, SUM_INTERVALS), K(1.0, SUM_INTERVALS), S(2.0), S(2.0)],
        ),
    ]
}

fn check_case(
    name: &str,
    times: &[f64],
    truth: &dyn Fn(f64) -> f64,
    corners: &[Corner],
    seed: u64,
) {
    let v = record(times, truth, SIGMA, seed);
    let m = Measured::fit(times, &v).expect("a valid record");
    let found = m.corners();
    let inner = &found[1..found.len() - 1];
    // the largest sample interval near each true corner bounds its error
    let interval = |tc: f64| {
        let i = times.partition_point(|&t| t < tc).clamp(1, times.len() - 1);
        (times[i] - times[i - 1]).max(times[(i + 1).min(times.len() - 1)] - times[i])
    };
    assert_eq!(
        inner.len(),
        corners.len(),
        "{name} (seed {seed}): corners {inner:?}, expected {corners:?}"
    );
    for (f, c) in inner.iter().zip(corners) {
        let (c, tol) = match *c {
            S(c) => (c, 1.0),
            K(c, tol) => (c, tol),
        };
        assert!(
            (f - c).abs() <= tol * interval(c) * (1.0 + 1e-9),
            "{name} (seed {seed}): corner {f} s, true {c} s, {:.2} intervals off",
            (f - c).abs() / interval(c)
        );
    }
    // between corners (two sample intervals away), within 2σ of the truth: the
    // fitted curve averages the noise, so its error is a fraction of σ
    let mut worst: f64 = 0.0;
    for &t in times {
        if found.iter().any(|&c| (t - c).abs() <= 2.0 * interval(c)) {
            continue;
        }
        worst = worst.max((m.eval(t).0 - truth(t)).abs());
    }
    assert!(
        worst <= 2.0 * SIGMA,
        "{name} (seed {seed}): reconstruction off by {worst} V"
    );
}

#[test]
fn measured_corners_regular_sampling() {
    let times = regular(3.0, 1e-3);
    for (name, f, c) in cases() {
        for seed in 1..=3 {
            check_case(name, &times, f.as_ref(), &c, seed);
        }
    }
}

#[test]
fn measured_corners_irregular_sampling() {
    let times = bursts(3.0, 1e-3, 7);
    for (name, f, c) in cases() {
        for seed in 1..=3 {
            check_case(name, &times, f.as_ref(), &c, seed);
        }
    }
}

/// Noise alone (1 %, on a hold and on slow sines) is never a corner, over many seeds.
#[test]
fn measured_invents_no_corners_in_noise() {
    let times = regular(3.0, 1e-3);
    for seed in 10..40 {
        for (name, f) in [
            ("hold", Box::new(|_| 0.5 * A) as Box<dyn Fn(f64) -> f64>),
            (
                "sine 0.5 Hz",
                Box::new(|t| 0.5 * A * (1.0 - (PI * t).cos())),
            ),
            (
                "sine 2 Hz",
                Box::new(|t| 0.5 * A + 0.4 * A * (4.0 * PI * t).sin()),
            ),
        ] {
            let v = record(&times, f.as_ref(), SIGMA, seed);
            let m = Measured::fit(&times, &v).expect("valid");
            let c = m.corners();
            assert_eq!(c.len(), 2, "{name} (seed {seed}): invented corners {c:?}");
        }
    }
}

/// A triangle's peaks in noise (σ = 0.5 % of its 5 kV, a slope jump of 20 V, 0.8 σ,
/// per sample) are placed within one sample interval (on bursty times, the mean
/// interval of the samples that place it), on regular and on bursty times, over
/// 10 seeds: the two straight lines on either side, fitted over up to
/// the neighbouring corners and meeting at the corner time of least squares, have
/// a standard error of σ/Δs·√(8/n) = 0.16 intervals (n ≈ 500 samples a side), so
/// one interval is six of them. On regular times the RMS error over the 50 corners
/// is within 1.5 times that bound: the corner finder loses little to the least-squares
/// limit (a cubic and a hinge over 4 samples, before, lost a factor of ten).
#[test]
fn measured_places_triangle_peaks_within_a_sample_interval() {
    let sigma = 0.005 * A;
    let truth = [0.5, 1.0, 1.5, 2.0, 2.5];
    for (times, regular) in [(regular(3.0, 1e-3), true), (bursts(3.0, 1e-3, 7), false)] {
        let mut sq = Vec::new();
        for seed in 1..=10 {
            let v = record(&times, &triangle, sigma, seed);
            let m = Measured::fit(&times, &v).expect("a valid record");
            let found = m.corners();
            let inner = &found[1..found.len() - 1];
            assert_eq!(inner.len(), truth.len(), "seed {seed}: {inner:?}");
            for (&f, &c) in inner.iter().zip(&truth) {
                // the mean interval of the samples within 0.25 s (those that place
                // the corner; bursty times alternate 0.5 and 2 ms)
                let near = times.iter().filter(|&&t| (t - c).abs() <= 0.25).count();
                let dt = 0.5 / (near - 1) as f64;
                let e = (f - c) / dt;
                assert!(
                    e.abs() <= 1.0,
                    "seed {seed} (regular {regular}): corner {f} s, true {c} s, {e:.2} intervals off"
                );
                sq.push(e * e);
            }
        }
        let rms = (sq.iter().sum::<f64>() / sq.len() as f64).sqrt();
        // the slope turns from +2A/s to −2A/s: a jump of 4A·1 ms per sample
        let jump = 4.0 * A * 1e-3;
        let bound = sigma / jump * (8.0_f64 / 500.0).sqrt();
        println!("triangle peaks (regular {regular}): RMS {rms:.3} intervals, bound {bound:.3}");
        if regular {
            assert!(
                rms <= 1.5 * bound,
                "RMS {rms} intervals against the bound {bound}"
            );
        }
    }
}

/// A supply's first-order rise A·(1 − e^(−(t − t0)/τ)) sampled every 2 ms, 0.1 %
/// noise: at τ = 10 ms (five samples a time constant) the rise is recorded, so it is
/// no step: a corner within one interval of t0 and smooth pieces that follow the
/// rise within 4σ at every sample (graded knots after the corner); at τ = 0.5 ms the
/// jump falls within one interval: a step there, which `Measured::steps` names.
#[test]
fn measured_tells_a_recorded_rise_from_a_step() {
    let (t0, sigma) = (0.2, 0.001 * A);
    let times = regular(1.0, 2e-3);
    for (tau, resolved) in [(10e-3, true), (0.5e-3, false)] {
        let truth = move |t: f64| {
            if t > t0 {
                A * (1.0 - (-(t - t0) / tau).exp())
            } else {
                0.0
            }
        };
        let v = record(&times, &truth, sigma, 3);
        let m = Measured::fit(&times, &v).expect("a valid record");
        if resolved {
            assert!(m.steps().is_empty(), "τ = {tau}: steps {:?}", m.steps());
            assert!(
                m.corners()
                    .iter()
                    .any(|&c| (c - t0).abs() <= 2e-3 * (1.0 + 1e-9)),
                "τ = {tau}: corners {:?}",
                m.corners()
            );
            let worst = times
                .iter()
                .map(|&t| (m.eval(t).0 - truth(t)).abs())
                .fold(0.0, f64::max);
            assert!(worst <= 4.0 * sigma, "τ = {tau}: off by {worst} V");
        } else {
            assert_eq!(m.steps().len(), 1, "τ = {tau}: steps {:?}", m.steps());
            let (a, b) = m.steps()[0];
            assert!(
                a <= t0 + 1e-9 && b >= t0 && b - a <= 2.0 * 2e-3 + 1e-9,
                "{a} … {b}"
            );
        }
    }
}

/// Every shipped trace is what its README command writes, bit for bit.
#[test]
fn identify_datasets_regenerate() {
    let readme =
        std::fs::read_to_string(crate::support::repo().join("datasets/identify/README.md"))
            .expect("README");
    let dir = tempfile::tempdir().expect("temp dir");
    let mut n = 0;
    for line in readme
        .lines()
        .filter(|l| l.starts_with("dea-fit synth trace "))
    {
        let args: Vec<&str> = line.split_whitespace().skip(1).collect();
        let k = args.iter().position(|a| *a == "--out").expect("--out");
        let shipped = crate::support::repo().join(args[k + 1]);
        let out = dir.path().join(format!("{n}.csv"));
        let mut run: Vec<&str> = args.clone();
        let o = out.display().to_string();
        run[k + 1] = &o;
        let r = crate::support::run(&crate::support::repo(), &run);
        assert!(
            r.status.success(),
            "{line}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let (a, b) = (
            std::fs::read(&out).unwrap(),
            std::fs::read(&shipped).unwrap(),
        );
        assert!(
            a == b,
            "{} differs from what `{line}` writes",
            shipped.display()
        );
        assert!(b.len() < 200_000, "{} is over 200 kB", shipped.display());
        n += 1;
    }
    assert_eq!(n, 4, "four traces in the README");
}

/// synth trace → io::trace::read → Trace::scene → simulate reproduces the noiseless
/// channels. The trace's voltage is the terminal voltage (the scene's 10 ms supply
/// rise already in it), so the rerun drives the actuator through an ideal source,
/// as `identify` does; the measured drive follows the recorded rise (a corner at its
/// start, graded knots after it), and the runs agree within 0.1 % of the range in
/// RMS (the largest difference, in the fast transient after the step where the
/// rebuilt drive differs from the true one between samples, within 1 %).
#[test]
fn synth_trace_round_trip() {
    use dea_fit::io::trace::ChannelKind;
    use dea_fit::sim::{
        self,
        scene::{Scene, Source},
    };
    for scene_file in [
        "datasets/identify/stack.toml",
        "datasets/identify/validate.toml",
    ] {
        let t = synth_trace(
            scene_file,
            &["--channels", "contraction,capacitance,current"],
        );
        let base = Scene::read(&crate::support::repo().join(scene_file)).expect("scene");
        let mut scene = t.scene(&base, None).expect("trace scene");
        scene.source = Source::Ideal;
        let run = sim::simulate(&scene, &sim::RunOptions::default()).expect("runs");
        assert_eq!(run.samples.len(), t.time_s.len());
        for kind in [ChannelKind::Contraction, ChannelKind::Capacitance] {
            let ch = t.channel(kind).expect("written");
            let (lo, hi) = ch
                .values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            let d: Vec<f64> = run
                .samples
                .iter()
                .zip(&ch.values)
                .map(|(s, &v)| kind.simulated(s, run.rest_length_m).unwrap() - v)
                .collect();
            let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
            let worst = d.iter().fold(0.0, |a: f64, x| a.max(x.abs()));
            eprintln!(
                "{scene_file} {kind}: rms {:.2e} worst {:.2e} of range",
                rms / (hi - lo),
                worst / (hi - lo)
            );
            assert!(
                rms <= 1e-3 * (hi - lo) && worst <= 1e-2 * (hi - lo),
                "{scene_file} {kind}: rms {rms:e}, worst {worst:e} of range {:e}",
                hi - lo
            );
        }
    }
}

fn read_text(name: &str, text: &str) -> dea_fit::Result<dea_fit::io::trace::Trace> {
    let dir = tempfile::tempdir().expect("temp dir");
    let p = dir.path().join(name);
    std::fs::write(&p, text).expect("write");
    dea_fit::io::trace::read(&p)
}

/// The reader: units to SI, missing cells kept as NaN, and located refusals.
#[test]
fn trace_reader_units_missing_and_errors() {
    use dea_fit::io::trace::ChannelKind;
    let t = read_text(
        "ok.csv",
        "time_ms,voltage_kV,contraction_um,capacitance_pF\n0,0,0,13.2\n2,1.5,,\n4,3,12.5,13.9\n",
    )
    .expect("reads");
    assert_eq!(t.time_s, vec![0.0, 0.002, 0.004]);
    assert_eq!(t.voltage_v, vec![0.0, 1500.0, 3000.0]);
    let c = t.channel(ChannelKind::Contraction).expect("contraction");
    assert!(c.values[1].is_nan());
    // 12.5 µm in m, exact to rounding (1e-18 m)
    assert!((c.values[2] - 12.5e-6).abs() < 1e-18);
    assert_eq!(ChannelKind::Capacitance.to_string(), "capacitance");
    assert_eq!(ChannelKind::Capacitance.unit(), "F");
    for (text, want) in [
        (
            "time_s,voltage_V,contraction_um\n0,0,0\n0,1,1\n",
            "x.csv:3:1: time 0 s repeats line 2",
        ),
        (
            "time_s,voltage_V,contraction_um\n0,0,0\n,1,1\n",
            "x.csv:3:1",
        ),
        (
            "time_s,voltage_V,contraction_um\n0,,0\n1,1,1\n",
            "x.csv:2:2",
        ),
        ("time_s,voltage_V\n0,0\n1,1\n", "no measured channel"),
        (
            "time_s,voltage_V,capacitance_F\n0,0,13.2\n1,1,13.3\n",
            "x.csv:2:3: capacitance_F = 13.2 F is not a plausible capacitance",
        ),
        (
            "time_s,voltage_V,contraction\n0,0,0\n1,1,1\n",
            "x.csv:1:3: column 'contraction' has no unit",
        ),
        (
            "time_s,voltage_V,contraction_um,capacitance_pF\n0,0,0,\n1,1,1,\n",
            "column 'capacitance_pF' holds no value",
        ),
        (
            "time_s,voltage_V,contraction_um\n0,0,0\n1,1e7,1\n",
            "x.csv:3:2",
        ),
    ] {
        let e = read_text("x.csv", text).expect_err(text).to_string();
        assert!(e.contains(want), "{text:?}: {e}");
    }
}

/// Trace::scene: times line up, a trace that does not start at rest is refused.
#[test]
fn trace_scene_times_and_start() {
    use dea_fit::sim::scene::Scene;
    let base =
        Scene::read(&crate::support::repo().join("datasets/identify/stack.toml")).expect("scene");
    let t = read_text(
        "a.csv",
        "time_s,voltage_V,contraction_um\n10,0,0\n10.5,100,1\n11.25,100,2\n",
    )
    .expect("reads");
    let s = t.scene(&base, None).expect("scene");
    assert_eq!(s.time.samples, vec![0.5, 1.25]);
    assert_eq!(s.time.span, 1.25);
    let t = read_text(
        "b.csv",
        "time_s,voltage_V,contraction_um\n0,4000,0\n1,5000,1\n2,5000,2\n",
    )
    .expect("reads");
    let e = t.scene(&base, None).err().expect("not at rest").to_string();
    assert!(e.contains("b.csv:2:2") && e.contains("at rest"), "{e}");
}

/// [time] sample_times: explicit times, validated at their key.
#[test]
fn scene_sample_times() {
    use dea_fit::sim::scene::Scene;
    let text = std::fs::read_to_string(crate::support::repo().join("datasets/identify/stack.toml"))
        .unwrap();
    let p = crate::support::repo().join("datasets/identify/x.toml");
    let with = |times: &str| text.replace("samples = 1500", &format!("sample_times = {times}"));
    let s = Scene::parse(&with("[0.1, \"250 ms\", 3]"), &p).expect("reads");
    assert_eq!(s.time.samples, vec![0.1, 0.25, 3.0]);
    for (bad, want) in [
        ("[0.2, 0.1]", "time.sample_times[1]: 0.1 s is not after"),
        ("[0, 0.1]", "time.sample_times[0]: 0 s must be after 0"),
        ("[4]", "after the end of the span"),
        ("[\"1 parsec\"]", "time.sample_times[0]"),
    ] {
        let e = Scene::parse(&with(bad), &p).err().expect(bad).to_string();
        assert!(e.contains(want), "{bad}: {e}");
    }
    let both = text.replace("samples = 1500", "samples = 10\nsample_times = [1]");
    let e = Scene::parse(&both, &p).err().expect("both").to_string();
    assert!(e.contains("conflicts with time.samples"), "{e}");
}

/// synth prints its status; --strict makes `unstable` exit 1.
#[test]
fn synth_status_and_strict() {
    let dir = tempfile::tempdir().expect("temp dir");
    let args = |strict: bool| {
        let mut a = vec![
            "synth",
            "hyperelastic",
            "--model",
            "yeoh",
            "--param",
            "C10=69.3kPa",
            "--param",
            "C20=-20kPa",
            "--param",
            "C30=0.1kPa",
            "--stretch",
            "1:4:10",
            "--out",
            "u.csv",
        ];
        if strict {
            a.push("--strict");
        }
        a
    };
    let r = crate::support::run(dir.path(), &args(false));
    let out = String::from_utf8_lossy(&r.stdout);
    assert_eq!(r.status.code(), Some(0), "{out}");
    assert!(out.contains("status: unstable"), "{out}");
    let r = crate::support::run(dir.path(), &args(true));
    assert_eq!(r.status.code(), Some(1));
    let s = crate::support::repo().join("datasets/identify/stack.toml");
    let r = crate::support::run(
        dir.path(),
        &[
            "synth",
            "trace",
            &s.display().to_string(),
            "--strict",
            "--out",
            "t.csv",
        ],
    );
    assert_eq!(r.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&r.stdout).contains("status: completed"));
}

/// The measured-input fit is linear in the record's length: a slow sine in noise
/// (whose long record once gave hundreds of candidate corners, each removal
/// refitting splines over ever longer spans: 60 000 rows 6.4 s, 300 000 rows 93 s)
/// takes at most 6 times the least-squares work (samples visited by its fits,
/// [`Work::samples`]: a count, not a time) on a record 5 times as long. The
/// allowance over 5 is the spline's knot-count search on the final segments, which
/// grows with the logarithm of their length.
#[test]
fn measured_fit_work_grows_linearly_with_the_record() {
    let work = |span: f64| {
        let times = regular(span, 1e-3);
        let v = record(
            &times,
            &|t| 0.5 * A * (1.0 - (4.0 * PI * t).cos()),
            SIGMA,
            3,
        );
        let w = Work::until(None);
        Measured::fit_with(&times, &v, &w).expect("a valid record");
        w.samples()
    };
    let (short, long) = (work(8.0), work(40.0));
    let ratio = long as f64 / short as f64;
    println!("work {short} → {long} samples, ×{ratio:.2} for ×5 the record");
    assert!(ratio <= 6.0, "work {short} → {long}: ×{ratio:.2}");
}

/// A fit past its deadline ends in an error that says so (never a partial signal),
/// and so does a trace's scene built under a spent time budget, with the hint.
#[test]
fn a_measured_fit_past_its_deadline_is_an_error() {
    let times = regular(3.0, 1e-3);
    let v = record(&times, &triangle, SIGMA, 1);
    let past = Instant::now()
        .checked_sub(Duration::from_secs(1))
        .expect("a second ago");
    let w = Work::until(Some(past));
    let e = Measured::fit_with(&times, &v, &w).expect_err("deadline passed");
    assert!(e.contains("time budget ran out"), "{e}");
    assert_eq!(w.samples(), 0, "no fit runs past the deadline");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.csv");
    let mut csv = String::from("time_s,voltage_V,contraction_um\n");
    for (t, x) in times.iter().zip(&v) {
        csv.push_str(&format!("{t},{},0\n", x - v[0]));
    }
    std::fs::write(&file, csv).unwrap();
    let t = dea_fit::io::trace::read(&file).expect("a trace");
    let base = dea_fit::sim::scene::Scene::read(
        &super::support::repo().join("datasets/identify/stack.toml"),
    )
    .unwrap();
    let e = t
        .scene(&base, Some(past))
        .err()
        .expect("budget spent")
        .to_string();
    assert!(e.contains("time budget") && e.contains("--max-time"), "{e}");
}

/// The rig's drive (datasets/scenes/stack_rig_7s.toml): 3 kV behind a 1 ms supply,
/// sampled every 2 ms, held, then a 1 kV, 1 Hz sine from 2 s, with 5 V noise and
/// without (the record's mV rounding only). The sine's start is a slope jump of
/// 6.3 kV/s, 12.6 V a sample: a corner within one sample interval of 2 s (two
/// allowed: the least-squares location's standard error is a fraction of one,
/// measured 0.45 and 0.55 intervals off). The C¹ Hermite pieces before missed it:
/// a spline with knots a few samples apart imitated the turn, and the record was
/// followed 27 V (5σ) off around it. Between corners the fit stays within 2σ.
#[test]
fn the_start_of_a_sine_on_a_hold_is_a_corner() {
    let truth = |t: f64| {
        let rise = 3000.0 * (1.0 - (-t / 1e-3).exp());
        let sine = if t > 2.0 {
            1000.0 * (2.0 * PI * (t - 2.0)).sin()
        } else {
            0.0
        };
        rise + sine
    };
    let times = regular(7.0, 2e-3);
    for (sigma, seed) in [(5.0_f64, 1), (5.0, 2), (5.0, 3), (0.0, 0)] {
        let v: Vec<f64> = record(&times, &truth, sigma.max(1e-300), seed)
            .into_iter()
            .map(|x| (x * 1e3).round() / 1e3)
            .collect();
        let m = Measured::fit(&times, &v).expect("a valid record");
        let c = m.corners();
        assert!(
            c.iter().any(|&x| (x - 2.0).abs() <= 2.0 * 2e-3),
            "σ = {sigma} V (seed {seed}): corners {c:?}"
        );
        let worst = times
            .iter()
            .filter(|&&t| c.iter().all(|&x| (t - x).abs() > 4e-3))
            .map(|&t| (m.eval(t).0 - truth(t)).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= 2.0 * sigma.max(2.0),
            "σ = {sigma} V (seed {seed}): off by {worst} V"
        );
    }
}

/// A measured drive costs the integrator about what the same drive in closed form
/// costs: the rig scene (BDF, rtol 1e-6) driven by its own `synth trace` voltage
/// (5 V noise) takes at most 1.5 times the accepted steps and 40 times the
/// rejected steps (never more than a tenth of the accepted) of its analytic step
/// and sine. Counts, not times: they are the same on every machine. With the C¹
/// Hermite pieces before: 4 026 steps and 734 rejected against 956 and 4, as the
/// third derivative of the solution jumped at every knot.
#[test]
fn a_measured_drive_costs_about_what_its_closed_form_costs() {
    use dea_fit::sim::{self, scene::Scene};
    let scene_file = "datasets/scenes/stack_rig_7s.toml";
    let t = synth_trace(scene_file, &["--noise", "voltage=5V", "--seed", "1"]);
    let base = Scene::read(&crate::support::repo().join(scene_file)).expect("scene");
    let measured = t.scene(&base, None).expect("trace scene");
    let opts = sim::RunOptions::default();
    let a = sim::simulate(&base, &opts).expect("runs").integrator.stats;
    let m = sim::simulate(&measured, &opts)
        .expect("runs")
        .integrator
        .stats;
    eprintln!("analytic {a:?}\nmeasured {m:?}");
    assert!(
        m.steps as f64 <= 1.5 * a.steps as f64,
        "steps: measured {} against analytic {}",
        m.steps,
        a.steps
    );
    assert!(
        m.rejected <= (40 * a.rejected).max(1) && 10 * m.rejected <= m.steps,
        "rejected: measured {} against analytic {}",
        m.rejected,
        a.rejected
    );
}

/// The trace `dea-fit synth trace <scene_file> <args>` writes, read back.
fn synth_trace(scene_file: &str, args: &[&str]) -> dea_fit::io::trace::Trace {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("t.csv");
    let o = out.display().to_string();
    let mut all = vec!["synth", "trace", scene_file];
    all.extend_from_slice(args);
    all.extend(["--out", &o]);
    let r = crate::support::run(&crate::support::repo(), &all);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    dea_fit::io::trace::read(&out).expect("a synth trace reads")
}
