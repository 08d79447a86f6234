//! `dea-fit synth hyperelastic`: synthetic tensile data from known constants;
//! `dea-fit synth relaxation`: a stress-relaxation curve from a Prony series (the
//! `io::relaxation` format); `dea-fit synth lcr`: an LCR sweep of a lossy capacitor
//! (the `io::lcr` plain-CSV format); `dea-fit synth trace SCENE`: an actuator trace
//! simulated from a scene (the `io::trace` format); `dea-fit synth breakdown`: a
//! breakdown series from a Weibull law with a thickness spread and a rig limit (the
//! `io::breakdown` format); `dea-fit synth dma`: DMA isotherms from a Prony series and
//! a WLF or Arrhenius shift law (the `dma::read` format). Gaussian noise from a seeded
//! generator; the generating command and parameters are written into the file's
//! comment lines. Each prints a `status:` line (`--strict`: a blocking status exits 1).

use dea_fit::io::trace::ChannelKind;
use dea_fit::material::hyperelastic::{Mode, ModelSpec, OgdenForm};
use dea_fit::sim::{self, scene::Scene, RunStatus};
use dea_fit::units::{parse_quantity, CountRange, Dimension, Quantity, MAX_POINTS};
use dea_fit::{Error, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The COUNT of `--time` and `--stretch`: points of the file `synth` writes.
const FILE_POINTS: CountRange = CountRange::new(2, MAX_POINTS, "rows of one synthetic file");

/// Generate synthetic data.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to generate: hyperelastic, relaxation, lcr, trace or breakdown.
    what: String,
    /// The scene to simulate (synth trace).
    scene: Option<PathBuf>,
    /// Model name (as for `hyperelastic --model`; synth hyperelastic).
    #[arg(long)]
    model: Option<String>,
    /// Ogden form of the given parameters: abaqus (2μ/α²) or original (μ/α).
    #[arg(long, default_value = "abaqus")]
    ogden_form: String,
    /// Parameter NAME=VALUE (moduli with a unit, e.g. C10=69.3kPa; bare numbers SI).
    /// synth relaxation: E_inf, E1…EN (stress units) and tau1…tauN (time units).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    params: Vec<String>,
    /// synth relaxation: a published Prony series in place of --param
    /// (elatrache2021-table-3.3, elatrache2021-table-4.2).
    #[arg(long)]
    preset: Option<String>,
    /// synth relaxation: the held engineering strain.
    #[arg(long)]
    strain: Option<f64>,
    /// synth relaxation: the strain is reached by a linear ramp over this time from
    /// t = 0 (e.g. 0.8s); default an ideal step.
    #[arg(long)]
    ramp_time: Option<String>,
    /// synth relaxation: sample times START:STOP:COUNT in seconds, log-spaced.
    #[arg(long, default_value = "0.01:1000:200")]
    time: String,
    /// synth lcr: the coupon's relative permittivity εr′ (flat in frequency).
    #[arg(long)]
    eps_r: Option<f64>,
    /// synth lcr: its loss tangent tan δ (flat in frequency).
    #[arg(long, default_value_t = 0.0)]
    tan_delta: f64,
    /// synth lcr: electrode area (m² or with a unit, e.g. 14.39cm2); synth
    /// breakdown: every specimen's electrode area (written as an area_mm2 column).
    #[arg(long)]
    area: Option<String>,
    /// synth lcr: electrode diameter (e.g. 30mm).
    #[arg(long)]
    diameter: Option<String>,
    /// synth lcr: coupon thickness (e.g. 1mm); synth breakdown: the films' mean
    /// thickness (e.g. 300um).
    #[arg(long)]
    thickness: Option<String>,
    /// synth lcr: log sweep FMIN:FMAX:COUNT, COUNT frequencies log-spaced from
    /// FMIN to FMAX, both included (e.g. 100Hz:100kHz:13, 4 a decade).
    #[arg(long, default_value = "100Hz:1MHz:17")]
    sweep: String,
    /// synth lcr: lossless stray capacitance added to every Cp (e.g. 0.3pF).
    #[arg(long, default_value = "0")]
    stray: String,
    /// synth lcr: the pair the file records (cp-d, cp-rp, cs-d, cs-rs, z-theta, r-x, g-b, …).
    #[arg(long, default_value = "cp-d")]
    pair: String,
    /// synth breakdown: the Weibull characteristic field α (e.g. 30V/um).
    #[arg(long)]
    alpha: Option<String>,
    /// synth breakdown: the Weibull shape β (e.g. 8).
    #[arg(long)]
    beta: Option<f64>,
    /// synth breakdown: number of specimens.
    #[arg(long)]
    n: Option<String>,
    /// synth breakdown: the rig's limit, a voltage (9kV) or a field (40V/um): a
    /// specimen that would break down beyond it is written as survived at it.
    #[arg(long)]
    limit: Option<String>,
    /// synth breakdown: relative standard deviation of the thickness (e.g. 5% or
    /// 0.05; Gaussian).
    #[arg(long)]
    thickness_spread: Option<String>,
    /// Mode: uniaxial, equibiaxial or planar.
    #[arg(long, default_value = "uniaxial")]
    mode: String,
    /// Stretches START:STOP:COUNT (evenly spaced).
    #[arg(long, default_value = "1.0:3.0:25")]
    stretch: String,
    /// Noise. synth hyperelastic and relaxation: relative standard deviation as a
    /// fraction of the stress (e.g. 0.01); synth lcr: of Cp and of D. synth trace: CHANNEL=SIGMA, repeatable, an absolute
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
    /// synth dma: the reference temperature of the Prony series and the shift law,
    /// e.g. 25C or 298.15K.
    #[arg(long, allow_hyphen_values = true)]
    reference_temperature: Option<String>,
    /// synth dma: WLF constants C1,C2 (C2 in K), e.g. 8.86,101.6.
    #[arg(long, value_name = "C1,C2")]
    wlf: Option<String>,
    /// synth dma: Arrhenius activation energy in J/mol (or with kJ/mol), e.g. 200kJ/mol.
    #[arg(long, value_name = "EA")]
    arrhenius: Option<String>,
    /// synth dma: isotherm temperatures START:STOP:COUNT, evenly spaced, e.g. -20C:80C:21.
    #[arg(long, allow_hyphen_values = true)]
    temperatures: Option<String>,
    /// synth dma: frequencies of each sweep FMIN:FMAX:COUNT, log-spaced.
    #[arg(long, default_value = "0.01Hz:100Hz:10")]
    frequencies: String,
    /// synth dma: a vertical shift bT = ρ(T)·T/(ρ₀·Tr) with ρ(T)/ρ₀ = 1 − α_V (T − Tr),
    /// α_V this volumetric expansion (1/K), e.g. 6e-4.
    #[arg(long, value_name = "ALPHA_V")]
    volume_expansion: Option<f64>,
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
        "relaxation" => relaxation(a),
        "lcr" => lcr(a),
        "trace" => trace(a),
        "breakdown" => breakdown(a),
        "dma" => dma(a),
        w => Err(
            Error::settings(format!("cannot synthesise '{w}'")).with_hint(
                "use: dea-fit synth hyperelastic, relaxation, lcr, breakdown, dma, or trace SCENE",
            ),
        ),
    }
}

/// The one relative `--noise` of synth hyperelastic, relaxation and lcr (0 without).
fn relative_noise(a: &Args, of: &str) -> Result<f64> {
    let noise = match a.noise.as_slice() {
        [] => 0.0,
        [x] => x.trim().parse::<f64>().map_err(|_| {
            Error::settings(format!(
                "--noise '{x}': expected a fraction of {of}, e.g. 0.01"
            ))
        })?,
        _ => {
            return Err(Error::settings(format!(
                "synth {} takes one --noise (a fraction of {of})",
                a.what
            )))
        }
    };
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(Error::settings("noise must be finite and ≥ 0"));
    }
    Ok(noise)
}

/// The command line that made a file, without its output path (the data do not
/// depend on it).
fn command_line() -> String {
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
    format!("dea-fit {}", args.join(" "))
}

/// Refuse the flags of the other kinds of data (a flag that would be ignored).
fn refuse_unused(a: &Args, used: &[&str]) -> Result<()> {
    let given = [
        ("SCENE", a.scene.is_some()),
        ("--model", a.model.is_some()),
        ("--param", !a.params.is_empty()),
        ("--preset", a.preset.is_some()),
        ("--strain", a.strain.is_some()),
        ("--ramp-time", a.ramp_time.is_some()),
        ("--eps-r", a.eps_r.is_some()),
        ("--area", a.area.is_some()),
        ("--diameter", a.diameter.is_some()),
        ("--thickness", a.thickness.is_some()),
        ("--alpha", a.alpha.is_some()),
        ("--beta", a.beta.is_some()),
        ("--n", a.n.is_some()),
        ("--limit", a.limit.is_some()),
        ("--thickness-spread", a.thickness_spread.is_some()),
        ("--reference-temperature", a.reference_temperature.is_some()),
        ("--wlf", a.wlf.is_some()),
        ("--arrhenius", a.arrhenius.is_some()),
        ("--temperatures", a.temperatures.is_some()),
        ("--volume-expansion", a.volume_expansion.is_some()),
    ];
    match given.iter().find(|(f, set)| *set && !used.contains(f)) {
        Some((f, _)) => Err(Error::settings(format!("synth {} takes no {f}", a.what))
            .with_hint("see dea-fit synth --help: each kind of data has its own flags")),
        None => Ok(()),
    }
}

/// `synth relaxation`: σ(t) = E(t)·ε0 for an ideal step (or the exact hereditary
/// integral of a linear ramp) of a Prony series E(t) = E∞ + Σ Eᵢ·exp(−t/τᵢ), at
/// log-spaced times, with relative Gaussian noise: the file `dea-fit relaxation`
/// reads (`time_s,stress_kPa`), parameters in its `#` lines.
fn relaxation(a: Args) -> Result<i32> {
    use dea_fit::io::relaxation::{log_times, Synthetic};
    use dea_fit::material::viscoelastic::{preset, PRESET_NAMES};
    refuse_unused(&a, &["--param", "--preset", "--strain", "--ramp-time"])?;
    let noise = relative_noise(&a, "the stress")?;
    let strain = a.strain.ok_or_else(|| {
        Error::settings("synth relaxation needs --strain").with_hint("e.g. --strain 0.5")
    })?;
    if !(strain.is_finite() && strain > 0.0 && strain <= 10.0) {
        return Err(Error::settings(format!(
            "--strain {strain}: expected an engineering strain in (0, 10]"
        )));
    }
    let (prony, source) = match (&a.preset, a.params.is_empty()) {
        (Some(name), true) => {
            let p = preset(name).map_err(|e| {
                e.with_hint(format!("presets: {}", PRESET_NAMES.join(", ")))
            })?;
            (p.prony, format!("preset {}: {}", p.name, p.source))
        }
        (None, false) => (prony_from_params(&a.params)?, "--param".to_string()),
        (Some(_), false) => {
            return Err(Error::settings("give --preset or --param, not both"))
        }
        (None, true) => {
            return Err(Error::settings("synth relaxation needs the series").with_hint(
                "--preset elatrache2021-table-3.3, or --param E_inf=43kPa --param E1=106kPa --param tau1=0.15s …",
            ))
        }
    };
    let ramp_time = match &a.ramp_time {
        None => None,
        Some(t) => Some(
            parse_quantity(t, Dimension::Time)
                .map_err(|e| Error::settings(format!("--ramp-time: {e}")))?,
        ),
    };
    let (t0, t1, count) = range(&a.time, ("--time", "START:STOP:COUNT"), FILE_POINTS, |x| {
        x.trim().parse::<f64>().map_err(|_| x.to_string())
    })?;
    if !(t0 > 0.0 && t1 > t0 && t1.is_finite()) {
        return Err(Error::settings(format!(
            "--time '{}': expected 0 < START < STOP (s)",
            a.time
        )));
    }
    let synthetic = Synthetic {
        prony,
        strain,
        ramp_time,
        times: log_times(t0, t1, count, false),
        noise,
        seed: a.seed,
        record_strain: false,
    };
    let head = format!(
        "synthetic data made by dea-fit {} (dea-fit synth relaxation)",
        env!("CARGO_PKG_VERSION")
    );
    let command = format!("command: {}", command_line());
    let source = format!("source: {source}");
    let text = synthetic.csv(&[&head, &command, &source])?;
    super::write_noted(&a.out, text.as_bytes())?;
    eprintln!("wrote {} ({count} points)", a.out.display());
    println!("status: ok");
    Ok(0)
}

/// `synth dma`: isotherms of a Prony series at the reference temperature shifted by a
/// WLF or Arrhenius law (and a vertical shift), with relative noise: the file
/// `dea-fit dma` reads, parameters in its `#` lines (`dma::synth`).
fn dma(a: Args) -> Result<i32> {
    use dea_fit::dma::law::Law;
    use dea_fit::dma::synth::Synthetic;
    use dea_fit::dma::temperature;
    refuse_unused(
        &a,
        &[
            "--param",
            "--reference-temperature",
            "--wlf",
            "--arrhenius",
            "--temperatures",
            "--volume-expansion",
        ],
    )?;
    let noise = relative_noise(&a, "each modulus")?;
    let prony = prony_from_params(&a.params)?;
    if prony.terms.is_empty() {
        return Err(Error::settings("synth dma needs a Prony series")
            .with_hint("--param E_inf=0.1MPa --param E1=1MPa --param tau1=1e-3s …"));
    }
    let temp = |flag: &str, t: &str| {
        temperature::parse(t).map_err(|e| Error::settings(format!("{flag}: {e}")))
    };
    let tr = temp(
        "--reference-temperature",
        a.reference_temperature.as_deref().ok_or_else(|| {
            Error::settings("synth dma needs --reference-temperature")
                .with_hint("e.g. --reference-temperature 25C")
        })?,
    )?;
    let law = match (&a.wlf, &a.arrhenius) {
        (Some(w), None) => {
            let c: Vec<f64> = w
                .split(',')
                .map(|x| x.trim().parse::<f64>())
                .collect::<std::result::Result<_, _>>()
                .map_err(|_| {
                    Error::settings(format!("--wlf '{w}': expected C1,C2, e.g. 8.86,101.6"))
                })?;
            match c.as_slice() {
                [c1, c2] if c1.is_finite() && c2.is_finite() && *c2 > 0.0 => Law::wlf(tr, *c1, *c2),
                _ => {
                    return Err(Error::settings(format!(
                        "--wlf '{w}': expected C1,C2 with C2 > 0 (K), e.g. 8.86,101.6"
                    )))
                }
            }
        }
        (None, Some(e)) => {
            let e = e.trim();
            let ea = match e.strip_suffix("kJ/mol") {
                Some(k) => k.trim().parse::<f64>().map(|v| v * 1e3),
                None => e.strip_suffix("J/mol").unwrap_or(e).trim().parse::<f64>(),
            }
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
            .ok_or_else(|| {
                Error::settings(format!(
                    "--arrhenius '{e}': expected an activation energy > 0, e.g. 200kJ/mol"
                ))
            })?;
            Law::arrhenius(tr, ea)
        }
        _ => {
            return Err(Error::settings(
                "synth dma needs one shift law: --wlf C1,C2 or --arrhenius EA",
            )
            .with_hint("e.g. --wlf 8.86,101.6"))
        }
    };
    let spec = a.temperatures.as_deref().ok_or_else(|| {
        Error::settings("synth dma needs --temperatures START:STOP:COUNT")
            .with_hint("e.g. --temperatures -20C:80C:21")
    })?;
    let (t0, t1, n) = range(
        spec,
        ("--temperatures", "START:STOP:COUNT"),
        TEMPERATURES,
        temperature::parse,
    )?;
    if !(t1 > t0 || n == 1) {
        return Err(Error::settings(format!(
            "--temperatures '{spec}': expected START < STOP"
        )));
    }
    let temperatures_k: Vec<f64> = (0..n)
        .map(|i| t0 + (t1 - t0) * i as f64 / (n.max(2) - 1) as f64)
        .collect();
    if let Some(t) = temperatures_k.iter().find(|t| law.log_at(**t).is_nan()) {
        return Err(Error::settings(format!(
            "WLF is undefined at {} (at or below its Vogel temperature Tr − C2)",
            temperature::celsius(*t)
        )));
    }
    let (f0, f1, count) = range(
        &a.frequencies,
        ("--frequencies", "FMIN:FMAX:COUNT"),
        SWEEP_POINTS,
        |x| parse_quantity(x, Dimension::Frequency),
    )?;
    if !(f0 > 0.0 && f1 > f0) {
        return Err(Error::settings(format!(
            "--frequencies '{}': expected 0 < FMIN < FMAX",
            a.frequencies
        )));
    }
    if let Some(av) = a.volume_expansion {
        if !(av.is_finite() && av.abs() < 1e-2) {
            return Err(Error::settings(format!(
                "--volume-expansion {av}: expected a volumetric expansion in 1/K, |α_V| < 0.01"
            )));
        }
    }
    let synthetic = Synthetic {
        prony,
        law,
        vertical: a.volume_expansion,
        temperatures_k,
        frequencies_hz: dea_fit::io::relaxation::log_times(f0, f1, count, false),
        noise,
        seed: a.seed,
    };
    let head = format!(
        "synthetic data made by dea-fit {} (dea-fit synth dma)",
        env!("CARGO_PKG_VERSION")
    );
    let command = format!("command: {}", command_line());
    let text = synthetic.csv(&[&head, &command])?;
    super::write_noted(&a.out, text.as_bytes())?;
    eprintln!(
        "wrote {} ({n} isotherms of {count} points)",
        a.out.display()
    );
    println!("status: ok");
    Ok(0)
}

/// Isotherms of `synth dma --temperatures`.
const TEMPERATURES: CountRange = CountRange::new(1, 1000, "isotherms of one synthetic DMA sweep");

/// A Prony series from `--param E_inf=… E1=… tau1=…` (every index from 1 to N once).
fn prony_from_params(params: &[String]) -> Result<dea_fit::material::viscoelastic::Prony> {
    let mut e_inf = None;
    let mut e: Vec<Option<f64>> = Vec::new();
    let mut tau: Vec<Option<f64>> = Vec::new();
    for kv in params {
        let (k, v) = kv
            .split_once('=')
            .ok_or_else(|| Error::settings(format!("--param '{kv}': expected NAME=VALUE")))?;
        let k = k.trim();
        let bad_name = || {
            Error::settings(format!("a Prony series has no parameter '{k}'"))
                .with_hint("E_inf, E1…EN (stress) and tau1…tauN (time)")
        };
        // (index of the term, whether a time) for E1…EN, tau1…tauN; None for E_inf
        let term = if k == "E_inf" {
            None
        } else if let Some(i) = k.strip_prefix("tau") {
            Some((i, true))
        } else if let Some(i) = k.strip_prefix('E') {
            Some((i, false))
        } else {
            return Err(bad_name());
        };
        let dim = match term {
            Some((_, true)) => Dimension::Time,
            _ => Dimension::Stress,
        };
        let value =
            parse_quantity(v, dim).map_err(|e| Error::settings(format!("--param {k}: {e}")))?;
        let slot = match term {
            None => &mut e_inf,
            Some((i, is_tau)) => {
                let i: usize = i.parse().ok().filter(|&i| i >= 1).ok_or_else(bad_name)?;
                let list = if is_tau { &mut tau } else { &mut e };
                if list.len() < i {
                    list.resize(i, None);
                }
                &mut list[i - 1]
            }
        };
        if slot.replace(value).is_some() {
            return Err(Error::settings(format!("--param {k} given twice")));
        }
    }
    let e_inf = e_inf.ok_or_else(|| Error::settings("missing --param E_inf=…"))?;
    let n = e.len().max(tau.len());
    let mut terms = Vec::with_capacity(n);
    for i in 0..n {
        match (tau.get(i).copied().flatten(), e.get(i).copied().flatten()) {
            (Some(t), Some(m)) => terms.push((t, m)),
            (None, _) => return Err(Error::settings(format!("missing --param tau{}=…", i + 1))),
            (_, None) => return Err(Error::settings(format!("missing --param E{}=…", i + 1))),
        }
    }
    dea_fit::material::viscoelastic::Prony::new(e_inf, &terms)
}

/// `START:STOP:COUNT` (`form` names the three, e.g. `FMIN:FMAX:PER_DECADE`) with
/// START and STOP read by `parse` and COUNT a whole number in `count` (checked
/// before anything is sized by it).
fn range(
    text: &str,
    (flag, form): (&str, &str),
    count: CountRange,
    parse: impl Fn(&str) -> std::result::Result<f64, String>,
) -> Result<(f64, f64, usize)> {
    let bad = |why: &str| Error::settings(format!("{flag} '{text}': expected {form}{why}"));
    let parts: Vec<&str> = text.split(':').collect();
    let [a, b, n] = parts.as_slice() else {
        return Err(bad(""));
    };
    let a = parse(a).map_err(|e| bad(&format!(" ({e})")))?;
    let b = parse(b).map_err(|e| bad(&format!(" ({e})")))?;
    let last = form.rsplit(':').next().unwrap_or(form);
    let n = count
        .parse(n)
        .map_err(|e| bad(&format!(" ({last}: {e})")))?;
    Ok((a, b, n))
}

/// Points of `synth lcr --sweep`: a count like every range's third number.
const SWEEP_POINTS: CountRange = CountRange::new(2, MAX_POINTS, "points of one log sweep");

/// `count` frequencies log-spaced from `f0` to `f1` (Hz), both included, each
/// rounded to four significant digits as a meter's frequency list prints them.
/// Refused where the sweep at the density the count makes, rounded up to whole
/// points a decade, is one `lcr::log_sweep_points` refuses (0 < f0 < f1,
/// frequencies a meter measures, at most 1000 a decade so that the rounded
/// frequencies stay distinct).
fn log_sweep(f0: f64, f1: f64, count: usize) -> std::result::Result<Vec<f64>, String> {
    let per_decade = (count - 1) as f64 / (f1 / f0).log10();
    // a float-to-int cast saturates: an absurd density is refused by the check
    dea_fit::io::lcr::log_sweep_points(f0, f1, per_decade.ceil().max(1.0) as usize)?;
    Ok(dea_fit::io::relaxation::log_times(f0, f1, count, false)
        .into_iter()
        .map(|f| format!("{f:.3e}").parse().unwrap_or(f))
        .collect())
}

/// `synth lcr`: a lossy parallel-plate capacitor, εr′ and tan δ flat in frequency,
/// C0 = ε0·A/d, Cp = εr′·C0·(1 + e₁) + stray, D = tan δ·(1 + e₂) with relative
/// Gaussian noise, written in the plain-CSV format `dea-fit permittivity` reads,
/// as the chosen pair, parameters in its `#` lines.
fn lcr(a: Args) -> Result<i32> {
    use dea_fit::fit::permittivity::Geometry;
    use dea_fit::io::lcr::{synthetic_points, write_csv};
    use dea_fit::material::check::PERMITTIVITY;
    use dea_fit::material::dielectric::Pair;
    use dea_fit::rank::manifest::TAN_DELTA;
    refuse_unused(&a, &["--eps-r", "--area", "--diameter", "--thickness"])?;
    let noise = relative_noise(&a, "Cp and of D")?;
    let eps = a.eps_r.ok_or_else(|| {
        Error::settings("synth lcr needs --eps-r").with_hint("e.g. --eps-r 4.7 --tan-delta 0.005")
    })?;
    // The plausible ranges of the readers (εr 1 … 1e5, tan δ 0 or 1e-7 … 10).
    for (flag, v, dom) in [
        ("--eps-r", eps, &PERMITTIVITY),
        ("--tan-delta", a.tan_delta, &TAN_DELTA),
    ] {
        dom.check(flag, v).map_err(|e| {
            Error::settings(format!(
                "{}; expected εr ≥ 1 and tan δ ≥ 0 in their plausible ranges",
                e.msg
            ))
            .with_hint(e.hint)
        })?;
    }
    let q = |flag: &str, v: &Option<String>, dim| -> Result<_> {
        v.as_deref()
            .map(|t| {
                parse_quantity(t, dim)
                    .map(|value| Quantity {
                        value,
                        tolerance: None,
                    })
                    .map_err(|e| Error::settings(format!("{flag}: {e}")))
            })
            .transpose()
    };
    let geometry = Geometry::new(
        q("--area", &a.area, Dimension::Area)?,
        q("--diameter", &a.diameter, Dimension::Length)?,
        q("--thickness", &a.thickness, Dimension::Length)?,
    )?;
    let stray = parse_quantity(&a.stray, Dimension::Capacitance)
        .map_err(|e| Error::settings(format!("--stray: {e}")))?;
    let (pair, _) = Pair::parse(&a.pair).ok_or_else(|| {
        Error::settings(format!("--pair '{}': unknown pair", a.pair))
            .with_hint("cp-d, cp-rp, cs-d, cs-rs, z-theta, r-x, g-b, …")
    })?;
    let (f0, f1, count) = range(
        &a.sweep,
        ("--sweep", "FMIN:FMAX:COUNT"),
        SWEEP_POINTS,
        |x| parse_quantity(x, Dimension::Frequency).map_err(|e| e.to_string()),
    )?;
    let freqs = log_sweep(f0, f1, count).map_err(|e| {
        Error::settings(format!("--sweep '{}': {e}", a.sweep))
            .with_hint("e.g. --sweep 100Hz:1MHz:17 (4 a decade)")
    })?;
    let normal = Normal::new(0.0, noise).map_err(|e| Error::settings(format!("--noise: {e}")))?;
    let mut rng = ChaCha8Rng::seed_from_u64(a.seed);
    let c0 = geometry.empty_capacitance();
    let pts = synthetic_points(&freqs, c0, stray, &normal, &mut rng, |_| (eps, a.tan_delta));
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# synthetic LCR sweep made by dea-fit {} (dea-fit synth lcr)",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(s, "# command: {}", command_line());
    let _ = writeln!(
        s,
        "# param eps_r = {eps:e}, tan_delta = {:e} (flat in frequency)",
        a.tan_delta
    );
    let _ = writeln!(
        s,
        "# geometry: area = {:e} m2, thickness = {:e} m, empty-gap capacitance C0 = {c0:e} F (no fringe field), stray = {stray:e} F (lossless)",
        geometry.area, geometry.thickness
    );
    let _ = writeln!(
        s,
        "# noise: relative {noise} on Cp and on D (Gaussian standard deviations), seed {} (ChaCha8)",
        a.seed
    );
    s.push_str(&write_csv(pair, &pts)?);
    super::write_noted(&a.out, s.as_bytes())?;
    eprintln!("wrote {} ({} frequencies)", a.out.display(), freqs.len());
    println!("status: ok");
    Ok(0)
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
    let noise = relative_noise(&a, "the stress")?;
    let form = match a.ogden_form.as_str() {
        "abaqus" => OgdenForm::Abaqus,
        "seed" => {
            eprintln!("{}", OgdenForm::FORMER_NAME_NOTE);
            OgdenForm::Abaqus
        }
        "original" => OgdenForm::Original,
        f => {
            return Err(Error::settings(format!("unknown Ogden form '{f}'"))
                .with_hint("abaqus or original"))
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
    let (l0, l1, count) = range(
        &a.stretch,
        ("--stretch", "START:STOP:COUNT"),
        FILE_POINTS,
        |x| x.trim().parse::<f64>().map_err(|_| x.to_string()),
    )?;
    // The same tensile domain the reader enforces.
    let (lo, hi) = dea_fit::data::STRETCH_RANGE;
    if ![l0, l1].iter().all(|l| (lo..=hi).contains(l)) {
        return Err(Error::settings(format!(
            "--stretch '{}': expected START:STOP:COUNT with stretches within {lo}–{hi}",
            a.stretch
        )));
    }
    let noise_abs = parse_quantity(&a.noise_abs, Dimension::Stress)
        .map_err(|e| Error::settings(format!("--noise-abs: {e}")))?;
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
            Some(d) => parse_quantity(v, d).map_err(|e| bad(&e))?,
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
    let _ = writeln!(s, "# command: {}", command_line());
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
    // Every row (time, voltage, each channel in its unit) before any is written.
    let mut rows: Vec<Vec<f64>> = Vec::with_capacity(out.samples.len());
    for smp in &out.samples {
        let mut v = smp.voltage_v;
        if let Some(n) = vn {
            v += n.sigma(v) * unit.sample(&mut rng);
        }
        let mut row = vec![smp.time_s, v];
        for &k in &kinds {
            let mut x = k.simulated(smp, out.rest_length_m).expect("not a force");
            if let Some(n) = noise_of(k.name()) {
                x += n.sigma(x) * unit.sample(&mut rng);
            }
            row.push(x * column(k).1);
        }
        rows.push(row);
    }
    dea_fit::io::finite_output(
        "the synthetic trace",
        rows.iter()
            .flat_map(|r| header.iter().map(String::as_str).zip(r.iter().copied())),
    )?;
    for row in &rows {
        let _ = write!(s, "{:.7},{:.3}", row[0], row[1]);
        for (&k, x) in kinds.iter().zip(&row[2..]) {
            let _ = write!(s, ",{:.*}", column(k).2, x);
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

/// The COUNT of `--n`: specimens of one synthetic breakdown series.
const SPECIMENS: CountRange = CountRange::new(2, MAX_POINTS, "specimens of one series");

/// `synth breakdown`: a breakdown series of `--n` specimens. Each film's thickness is
/// h·(1 + s·z) (z standard normal, redrawn until positive), its breakdown field
/// E = α·(−ln U)^(1/β) (U uniform: the two-parameter Weibull law F(E) =
/// 1 − exp[−(E/α)^β], IEEE Std 930-2004) and its breakdown voltage E·h; a voltage
/// beyond the rig's limit is written as survived at the limit (right-censored).
/// Written as `specimen,voltage_kV,thickness_um,survived[,area_mm2]`, the
/// generating parameters in the `#` lines.
fn breakdown(a: Args) -> Result<i32> {
    use rand_distr::Weibull;
    refuse_unused(
        &a,
        &[
            "--alpha",
            "--beta",
            "--n",
            "--limit",
            "--thickness",
            "--thickness-spread",
            "--area",
        ],
    )?;
    if !a.noise.is_empty() || a.noise_abs != "0" {
        return Err(Error::settings("synth breakdown takes no --noise")
            .with_hint("the scatter is the Weibull law's own: set it with --beta"));
    }
    let need = |flag: &str, v: &Option<String>| {
        v.clone().ok_or_else(|| {
            Error::settings(format!("synth breakdown needs {flag}")).with_hint(
                "e.g. dea-fit synth breakdown --alpha 30V/um --beta 8 --n 15 --limit 9kV --thickness 300um --out s.csv",
            )
        })
    };
    let positive = |flag: &str, text: &str, dim: Dimension| -> Result<f64> {
        match parse_quantity(text, dim) {
            Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
            Ok(v) => Err(Error::settings(format!("{flag} must be > 0, found {v}"))),
            Err(e) => Err(Error::settings(format!("{flag}: {e}"))),
        }
    };
    let alpha = positive(
        "--alpha",
        &need("--alpha", &a.alpha)?,
        Dimension::ElectricField,
    )?;
    let beta = a.beta.ok_or_else(|| need("--beta", &None).unwrap_err())?;
    if !(beta.is_finite() && beta > 0.0) {
        return Err(Error::settings(format!("--beta must be > 0, found {beta}")));
    }
    let n = SPECIMENS
        .parse(&need("--n", &a.n)?)
        .map_err(|e| Error::settings(format!("--n: {e}")))?;
    let thickness = positive(
        "--thickness",
        &need("--thickness", &a.thickness)?,
        Dimension::Length,
    )?;
    let spread = match &a.thickness_spread {
        None => 0.0,
        Some(t) => match parse_quantity(t, Dimension::Fraction) {
            Ok(v) if v.is_finite() && (0.0..0.5).contains(&v) => v,
            Ok(v) => {
                return Err(Error::settings(format!(
                    "--thickness-spread must be from 0 to 50 %, found {v}"
                )))
            }
            Err(e) => return Err(Error::settings(format!("--thickness-spread: {e}"))),
        },
    };
    let area = a
        .area
        .as_deref()
        .map(|t| positive("--area", t, Dimension::Area))
        .transpose()?;
    // The limit as a voltage, or as a field (then the voltage at each film's thickness).
    let limit = a
        .limit
        .as_deref()
        .map(|t| {
            positive("--limit", t, Dimension::Voltage)
                .map(|v| (v, true))
                .or_else(|_| positive("--limit", t, Dimension::ElectricField).map(|e| (e, false)))
                .map_err(|_| {
                    Error::settings(format!("--limit '{t}': expected a voltage or a field"))
                        .with_hint("e.g. --limit 9kV (the supply's) or --limit 40V/um")
                })
        })
        .transpose()?;
    let law =
        Weibull::new(alpha, beta).map_err(|e| Error::settings(format!("--alpha/--beta: {e}")))?;
    let normal = Normal::new(0.0, 1.0).expect("a unit normal");
    let mut rng = ChaCha8Rng::seed_from_u64(a.seed);
    let mut rows = Vec::with_capacity(n);
    for _ in 0..n {
        let h = loop {
            let h = thickness * (1.0 + spread * normal.sample(&mut rng));
            if h > 0.0 {
                break h;
            }
        };
        let e: f64 = law.sample(&mut rng);
        let v_limit = limit.map(|(l, volts)| if volts { l } else { l * h });
        // Rounded as written (0.1 V, 0.01 µm), so the fit sees what the file holds.
        let (v, survived) = match v_limit {
            Some(l) if e * h >= l => (l, true),
            _ => (e * h, false),
        };
        rows.push(((v * 1e1).round() / 1e4, (h * 1e8).round() / 1e2, survived));
    }
    dea_fit::io::finite_output(
        "the synthetic breakdown series",
        rows.iter()
            .flat_map(|r| [("voltage_kV", r.0), ("thickness_um", r.1)]),
    )?;
    let survivors = rows.iter().filter(|r| r.2).count();
    if n - survivors < 2 {
        return Err(Error::settings(format!(
            "the limit leaves {} breakdown(s) among {n} specimens: a series needs two or more; nothing was written",
            n - survivors
        ))
        .with_hint("raise --limit, or lower --alpha"));
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# synthetic breakdown series made by dea-fit {} (dea-fit synth breakdown)",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(s, "# command: {}", command_line());
    let _ = writeln!(
        s,
        "# param alpha = {alpha:e} V/m, beta = {beta:e} (two-parameter Weibull F(E) = 1 - exp(-(E/alpha)^beta){})",
        match area {
            Some(ar) => format!(", at the specimens' electrode area {ar:e} m2"),
            None => String::new(),
        }
    );
    let _ = writeln!(
        s,
        "# thickness: {thickness:e} m, relative spread {spread} (Gaussian standard deviation); the field law does not depend on it"
    );
    match limit {
        Some((l, true)) => {
            let _ = writeln!(
                s,
                "# limit: {l:e} V (the rig's: beyond it a specimen is written as survived at it)"
            );
        }
        Some((l, false)) => {
            let _ = writeln!(
                s,
                "# limit: {l:e} V/m (the rig's: beyond it a specimen is written as survived at it)"
            );
        }
        None => {}
    }
    let _ = writeln!(
        s,
        "# specimens: {n}, breakdowns {}, survived {survivors}; seed {} (ChaCha8)",
        n - survivors,
        a.seed
    );
    let _ = writeln!(
        s,
        "specimen,voltage_kV,thickness_um,survived{}",
        if area.is_some() { ",area_mm2" } else { "" }
    );
    for (i, (v, h, survived)) in rows.iter().enumerate() {
        let _ = write!(s, "s{:02},{v:.4},{h:.2},{}", i + 1, u8::from(*survived));
        if let Some(ar) = area {
            let _ = write!(s, ",{}", ar * 1e6);
        }
        s.push('\n');
    }
    super::write_noted(&a.out, s.as_bytes())?;
    eprintln!(
        "wrote {} ({n} specimens, {survivors} survived at the limit)",
        a.out.display()
    );
    println!("status: ok");
    Ok(0)
}
