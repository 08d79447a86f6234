//! `dea-fit synth hyperelastic`: synthetic tensile data from known constants, with
//! Gaussian noise from a seeded generator, the generating parameters written into the
//! file's comment lines.

use dea_fit::material::hyperelastic::{Mode, ModelSpec, OgdenForm};
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
    /// What to generate: hyperelastic.
    what: String,
    /// Model name (as for `hyperelastic --model`).
    #[arg(long)]
    model: String,
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
    /// Relative noise: standard deviation as a fraction of the stress.
    #[arg(long, default_value_t = 0.0)]
    noise: f64,
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
    if a.what != "hyperelastic" {
        return Err(Error::settings(format!("cannot synthesise '{}'", a.what))
            .with_hint("use: dea-fit synth hyperelastic"));
    }
    let form = match a.ogden_form.as_str() {
        "seed" => OgdenForm::Seed,
        "original" => OgdenForm::Original,
        f => {
            return Err(
                Error::settings(format!("unknown Ogden form '{f}'")).with_hint("seed or original")
            )
        }
    };
    let spec = ModelSpec::new(&a.model, form);
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
                Error::settings(format!("{} has no parameter '{k}'", a.model))
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
    if !(a.noise.is_finite() && a.noise >= 0.0 && noise_abs.is_finite() && noise_abs >= 0.0) {
        return Err(Error::settings("noise must be finite and ≥ 0"));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(a.seed);
    let unit = Normal::new(0.0, 1.0).expect("valid");
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# synthetic data made by dea-fit {} (dea-fit synth hyperelastic)",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        s,
        "# model: {}{}",
        a.model,
        if a.model.starts_with("ogden") {
            format!(" ({} form)", a.ogden_form)
        } else {
            String::new()
        }
    );
    for (i, v) in info.iter().zip(&p) {
        let _ = writeln!(s, "# param {} = {v:e} {}", i.name, i.unit);
    }
    let _ = writeln!(s, "# noise: relative {} and absolute {noise_abs:e} Pa (Gaussian, standard deviations), seed {} (ChaCha8)", a.noise, a.seed);
    let _ = writeln!(s, "# mode: {mode}");
    let _ = writeln!(s, "stretch,nominal_stress_kPa");
    for i in 0..count {
        let l = l0 + (l1 - l0) * i as f64 / (count - 1) as f64;
        let clean = model.nominal_stress(&p, mode, l);
        let e1: f64 = unit.sample(&mut rng);
        let e2: f64 = unit.sample(&mut rng);
        let y = clean * (1.0 + a.noise * e1) + noise_abs * e2;
        if !y.is_finite() {
            return Err(Error::settings(format!(
                "the model gives a non-finite stress ({y}) at stretch {l}: no data written"
            ))
            .with_hint(
                "keep --stretch inside the model's domain (e.g. below Gent's locking stretch)",
            ));
        }
        let _ = writeln!(s, "{l:.6},{:.6}", y / 1e3);
    }
    super::write_noted(&a.out, s.as_bytes())?;
    eprintln!("wrote {} ({count} points)", a.out.display());
    Ok(0)
}
