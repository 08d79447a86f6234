//! `dea-fit synth hyperelastic`: synthetic tensile data from known constants;
//! `dea-fit synth trace SCENE`: an actuator trace simulated from a scene (the
//! `io::trace` format). Gaussian noise from a seeded generator; the generating
//! command and parameters are written into the file's comment lines. Each prints a
//! `status:` line (`--strict`: a blocking status exits 1).

use dea_fit::io::trace::ChannelKind;
use dea_fit::material::hyperelastic::{Mode, ModelSpec, OgdenForm};
use dea_fit::sim::{self, scene::Scene, RunStatus};
use dea_fit::units::{parse_quantity, Dimension};
use dea_fit::{Error, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Most points `synth` writes (a 10⁶-row file is about 20 MB).
const MAX_POINTS: usize = 1_000_000;

/// Generate synthetic data.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to generate: hyperelastic or trace.
    what: String,
    /// The scene to simulate (synth trace).
    scene: Option<PathBuf>,
    /// Model name (as for `hyperelastic --model`; synth hyperelastic).
    #[arg(long)]
    model: Option<String>,
    /// Ogden form of the given parameters.
    #[arg(long, default_value = "seed")]
    ogden_form: String,
    /// Parameter NAME=VALUE (moduli with a unit, e.g. C10=69.3kPa; bare numbers SI).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    params: Vec<String>,
    /// Mode: uniaxial, equibiaxial or planar.
    #[arg(long, default_value = "uniaxial")]
    mode: String,
    /// Stretches START:STOP:COUNT (evenly spaced).
    #[arg(long, default_value = "1.0:3.0:25")]
    stretch: String,
    /// Noise. synth hyperelastic: relative standard deviation as a fraction of the
    /// stress (e.g. 0.01). synth trace: CHANNEL=SIGMA, repeatable, an absolute
    /// quantity (contraction=0.5um, voltage=5V) or a share (capacitance=0.2%).
    #[arg(long)]
    noise: Vec<String>,
    /// synth trace: measured channels, comma-separated (contraction, length,
    /// stretch, capacitance, current).
    #[arg(long, default_value = "contraction,capacitance")]
    channels: String,
    /// synth trace: irregular sample times (logging bursts, seeded), as many as the
    /// scene's samples over its span.
    #[arg(long)]
    irregular: bool,
    /// Exit with status 1 on a blocking status (unstable model, pull-in).
    #[arg(long)]
    strict: bool,
    /// Absolute noise: standard deviation with a stress unit, e.g. 100Pa.
    #[arg(long, default_value = "0")]
    noise_abs: String,
    /// Seed of the noise generator (ChaCha8).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output CSV (stress in kPa).
    #[arg(long)]
    out: PathBuf,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    match a.what.as_str() {
        "hyperelastic" => hyperelastic(a),
        "trace" => trace(a),
        w => Err(Error::settings(format!("cannot synthesise '{w}'"))
            .with_hint("use: dea-fit synth hyperelastic or dea-fit synth trace SCENE")),
    }
}

fn hyperelastic(a: Args) -> Result<i32> {
    let Some(model_name) = a.model.clone() else {
        return Err(
            Error::settings("synth hyperelastic needs --model").with_hint("e.g. --model yeoh")
        );
    };
    if a.scene.is_some() {
        return Err(Error::settings("synth hyperelastic takes no scene")
            .with_hint("did you mean synth trace SCENE?"));
    }
    let noise = match a.noise.as_slice() {
        [] => 0.0,
        [x] => x.trim().parse::<f64>().map_err(|_| {
            Error::settings(format!(
                "--noise '{x}': expected a fraction of the stress, e.g. 0.01"
            ))
        })?,
        _ => {
            return Err(Error::settings(
                "synth hyperelastic takes one --noise (a fraction of the stress)",
            ))
        }
    };
    let form = match a.ogden_form.as_str() {
        "seed" => OgdenForm::Seed,
        "original" => OgdenForm::Original,
        f => {
            return Err(
                Error::settings(format!("unknown Ogden form '{f}'")).with_hint("seed or original")
            )
        }
    };
    let spec = ModelSpec::new(&model_name, form);
    let model = spec.build()?;
    let info = model.params();
    let mut p = vec![f64::NAN; info.len()];
    for kv in &a.params {
        let (k, v) = kv
            .split_once('=')
            .ok_or_else(|| Error::settings(format!("--param '{kv}': expected NAME=VALUE")))?;
        let j = info
            .iter()
            .position(|i| i.name == k.trim())
            .ok_or_else(|| {
                let names: Vec<&str> = info.iter().map(|i| i.name.as_str()).collect();
                Error::settings(format!("{model_name} has no parameter '{k}'"))
                    .with_hint(format!("its parameters: {}", names.join(", ")))
            })?;
        p[j] = if info[j].unit == "Pa" {
            parse_quantity(v, Dimension::Stress)
                .map_err(|e| Error::settings(format!("--param {k}: {e}")))?
                .value
        } else {
            v.trim().parse().map_err(|_| {
                Error::settings(format!("--param {k}: expected a number, found '{v}'"))
            })?
        };
    }
    if let Some(j) = p.iter().position(|v| v.is_nan()) {
        return Err(Error::settings(format!(
            "missing --param {}=…",
            info[j].name
        )));
    }
    let mode = Mode::parse(&a.mode)
        .ok_or_else(|| Error::settings(format!("unknown mode '{}'", a.mode)))?;
    let parts: Vec<&str> = a.stretch.split(':').collect();
    let bad = || {
        Error::settings(format!(
            "--stretch '{}': expected START:STOP:COUNT",
            a.stretch
        ))
    };
    if parts.len() != 3 {
        return Err(bad());
    }
    let (l0, l1): (f64, f64) = (
        parts[0].parse().map_err(|_| bad())?,
        parts[1].parse().map_err(|_| bad())?,
    );
    let count: usize = parts[2].parse().map_err(|_| bad())?;
    // The same tensile domain the reader enforces, and a count a file can hold.
    let (lo, hi) = dea_fit::data::STRETCH_RANGE;
    if !(2..=MAX_POINTS).contains(&count) || ![l0, l1].iter().all(|l| (lo..=hi).contains(l)) {
        return Err(bad().with_hint(format!(
            "stretches within {lo}–{hi}, a count from 2 to {MAX_POINTS}"
        )));
    }
    let noise_abs = parse_quantity(&a.noise_abs, Dimension::Stress)
        .map_err(|e| Error::settings(format!("--noise-abs: {e}")))?
        .value;
    if !(noise.is_finite() && noise >= 0.0 && noise_abs.is_finite() && noise_abs >= 0.0) {
        return Err(Error::settings("noise must be finite and ≥ 0"));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(a.seed);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# synthetic data made by dea-fit {} (dea-fit synth hyperelastic)",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        s,
        "# model: {}{}",
        model_name,
        if model_name.starts_with("ogden") {
            format!(" ({} form)", a.ogden_form)
        } else {
            String::new()
        }
    );
    for (i, v) in info.iter().zip(&p) {
        let _ = writeln!(s, "# param {} = {v:e} {}", i.name, i.unit);
    }
    let _ = writeln!(s, "# noise: relative {noise} and absolute {noise_abs:e} Pa (Gaussian, standard deviations), seed {} (ChaCha8)", a.seed);
    let _ = writeln!(s, "# mode: {mode}");
    let _ = writeln!(s, "stretch,nominal_stress_kPa");
    dea_fit::io::tensile::synthetic_rows(
        model.as_ref(),
        &p,
        mode,
        (0..count).map(|i| l0 + (l1 - l0) * i as f64 / (count - 1) as f64),
        (noise, noise_abs),
        &mut rng,
        &mut s,
    )?;
    // Drucker stability (dP/dλ > 0) over the requested stretches in this mode
    let check = dea_fit::fit::drucker::drucker(model.as_ref(), &p);
    let stable = check
        .iter()
        .find(|c| c.mode == mode)
        .is_none_or(|c| l0.min(l1) >= c.stretch_min && l0.max(l1) <= c.stretch_max);
    super::write_noted(&a.out, s.as_bytes())?;
    eprintln!("wrote {} ({count} points)", a.out.display());
    if stable {
        println!("status: ok");
        return Ok(0);
    }
    println!(
        "warning: the model is not Drucker-stable (dP/dλ ≤ 0) over stretches {l0}–{l1} in {mode}"
    );
    println!("status: unstable");
    Ok(i32::from(a.strict))
}

/// Noise of one column: an absolute σ (SI) or a share of the value.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Noise {
    Abs(f64),
    Rel(f64),
}

impl Noise {
    fn sigma(self, value: f64) -> f64 {
        match self {
            Noise::Abs(s) => s,
            Noise::Rel(r) => r * value.abs(),
        }
    }
}

/// The columns `synth trace` writes per channel: header, unit factor from SI, decimals.
fn column(kind: ChannelKind) -> (&'static str, f64, usize) {
    match kind {
        ChannelKind::Contraction => ("contraction_um", 1e6, 4),
        ChannelKind::Length => ("length_mm", 1e3, 7),
        ChannelKind::Stretch => ("stretch", 1.0, 8),
        ChannelKind::Capacitance => ("capacitance_pF", 1e12, 4),
        ChannelKind::Current => ("current_uA", 1e6, 5),
        ChannelKind::Force => ("force_N", 1.0, 6),
    }
}

fn parse_noise(spec: &str, kinds: &[ChannelKind]) -> Result<(String, Noise)> {
    let bad = |why: &str| Error::settings(format!("--noise '{spec}': {why}"));
    let (k, v) = spec.split_once('=').ok_or_else(|| {
        bad("expected CHANNEL=SIGMA")
            .with_hint("e.g. --noise contraction=0.5um --noise capacitance=0.2%")
    })?;
    let (k, v) = (k.trim(), v.trim());
    let dim = match k {
        "voltage" => Some(Dimension::Voltage),
        _ => match ChannelKind::parse(k) {
            Some(c) if kinds.contains(&c) => c.dimension(),
            _ => {
                return Err(bad(&format!("'{k}' is not a written channel"))
                    .with_hint("voltage or one of --channels"))
            }
        },
    };
    let n = if let Some(pct) = v.strip_suffix('%') {
        Noise::Rel(
            pct.trim()
                .parse::<f64>()
                .map_err(|_| bad("expected a percentage"))?
                / 100.0,
        )
    } else {
        Noise::Abs(match dim {
            Some(d) => parse_quantity(v, d).map_err(|e| bad(&e))?.value,
            None => v.parse().map_err(|_| bad("expected a number"))?,
        })
    };
    match n {
        Noise::Abs(x) | Noise::Rel(x) if x.is_finite() && x >= 0.0 => Ok((k.to_string(), n)),
        _ => Err(bad("a standard deviation is finite and ≥ 0")),
    }
}

/// Logging bursts: 100 samples at half the mean interval, then 50 at twice it, each
/// interval jittered by ±20 %, rescaled to end at `span` (ChaCha8, seeded).
pub fn burst_times(span: f64, count: usize, seed: u64) -> Vec<f64> {
    use rand::Rng;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dt = span / count as f64;
    let mut t = Vec::with_capacity(count);
    let mut now = 0.0;
    for k in 0..count {
        let base = if k % 150 < 100 { 0.5 * dt } else { 2.0 * dt };
        now += base * rng.gen_range(0.8..1.2);
        t.push(now);
    }
    let scale = span / now;
    t.iter_mut().for_each(|x| *x *= scale);
    t
}

fn trace(a: Args) -> Result<i32> {
    let Some(path) = a.scene.clone() else {
        return Err(Error::settings("synth trace needs a SCENE")
            .with_hint("dea-fit synth trace my_stack.toml --out trace.csv"));
    };
    if a.model.is_some() || !a.params.is_empty() {
        return Err(Error::settings(
            "synth trace takes its constants from the scene, not --model/--param",
        ));
    }
    let mut scene = Scene::read(&path)?;
    if scene.control.is_some() {
        return Err(
            Error::settings(format!("{}: a closed-loop scene", path.display()))
                .with_hint("a trace records a voltage program: use a scene with [[input]]"),
        );
    }
    let mut kinds: Vec<ChannelKind> = Vec::new();
    for name in a.channels.split(',').map(str::trim) {
        match ChannelKind::parse(name) {
            Some(ChannelKind::Force) => {
                return Err(Error::settings(
                    "--channels force: the simulator drives a given load and computes no force",
                ))
            }
            Some(k) if !kinds.contains(&k) => kinds.push(k),
            Some(_) => {}
            None => {
                return Err(
                    Error::settings(format!("--channels: unknown channel '{name}'"))
                        .with_hint("contraction, length, stretch, capacitance, current"),
                )
            }
        }
    }
    let mut noise: Vec<(String, Noise)> = Vec::new();
    for spec in &a.noise {
        noise.push(parse_noise(spec, &kinds)?);
    }
    let noise_of = |name: &str| noise.iter().rev().find(|n| n.0 == name).map(|n| n.1);
    if a.irregular {
        scene.time.samples = burst_times(
            scene.time.span,
            scene.time.samples.len(),
            a.seed.wrapping_add(1),
        );
    }
    let out = sim::simulate(&scene, &sim::RunOptions::default())?;
    let status = out.integrator.status;
    if status == RunStatus::Failed {
        println!("error: {}", out.integrator.message);
        println!("status: failed");
        return Ok(1);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(a.seed);
    let unit = Normal::new(0.0, 1.0).expect("valid");
    let m = &scene.material;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# synthetic trace made by dea-fit {} (dea-fit synth trace)",
        env!("CARGO_PKG_VERSION")
    );
    // the command without its output path (the data do not depend on it)
    let mut args: Vec<String> = Vec::new();
    let mut it = std::env::args().skip(1);
    while let Some(x) = it.next() {
        match x.as_str() {
            "--out" => {
                it.next();
            }
            o if o.starts_with("--out=") => {}
            _ => args.push(x),
        }
    }
    let _ = writeln!(s, "# command: dea-fit {}", args.join(" "));
    let _ = writeln!(s, "# scene: {} ({})", scene.name, path.display());
    let names: Vec<String> = m.model.params().iter().map(|p| p.name.clone()).collect();
    let units: Vec<String> = m
        .model
        .params()
        .iter()
        .map(|p| p.unit.to_string())
        .collect();
    let _ = writeln!(s, "# hyperelastic: {}", m.spec.name);
    for ((n, u), v) in names.iter().zip(&units).zip(&m.params) {
        let _ = writeln!(s, "# param {n} = {v:e} {u}");
    }
    let _ = writeln!(s, "# param nv = {:e} Pa s", m.viscous.nv_pa_s);
    for (i, arm) in m.viscous.arms.iter().enumerate() {
        let _ = writeln!(
            s,
            "# param arm{}.k = {:e} Pa, arm{}.tau = {:e} s",
            i + 1,
            arm.k_pa,
            i + 1,
            arm.eta_pa_s / arm.k_pa
        );
    }
    let _ = writeln!(s, "# param eps_r = {:e}", m.eps_r);
    if let Some(c) = &m.composite {
        let _ = writeln!(
            s,
            "# param mass_fraction = {:e} (eps_r by the {} rule fitted at {} Hz)",
            c.mass_fraction,
            c.mixture.rule.name(),
            c.freq_hz
        );
    }
    let shown = &a.noise;
    let _ = writeln!(
        s,
        "# noise: {} (Gaussian standard deviations), seed {} (ChaCha8){}",
        if shown.is_empty() {
            "none".to_string()
        } else {
            shown.join(", ")
        },
        a.seed,
        if a.irregular {
            format!("; irregular times seeded {}", a.seed.wrapping_add(1))
        } else {
            String::new()
        }
    );
    let _ = writeln!(s, "# status: {status}");
    let mut header = vec!["time_s".to_string(), "voltage_V".to_string()];
    header.extend(kinds.iter().map(|&k| column(k).0.to_string()));
    let _ = writeln!(s, "{}", header.join(","));
    let vn = noise_of("voltage");
    for smp in &out.samples {
        let mut v = smp.voltage_v;
        if let Some(n) = vn {
            v += n.sigma(v) * unit.sample(&mut rng);
        }
        let _ = write!(s, "{:.7},{v:.3}", smp.time_s);
        for &k in &kinds {
            let (_, f, dec) = column(k);
            let mut x = k.simulated(smp, out.rest_length_m).expect("not a force");
            if let Some(n) = noise_of(k.name()) {
                x += n.sigma(x) * unit.sample(&mut rng);
            }
            let _ = write!(s, ",{:.*}", dec, x * f);
        }
        s.push('\n');
    }
    super::write_noted(&a.out, s.as_bytes())?;
    eprintln!("wrote {} ({} rows)", a.out.display(), out.samples.len());
    for w in &out.warnings {
        println!("warning: {w}");
    }
    println!("status: {status}");
    Ok(i32::from(a.strict && status == RunStatus::PullIn))
}
