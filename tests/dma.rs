//! `dea-fit dma`: the reader's located errors, `synth dma`, the shifts' standard
//! errors against the truth on synthetic replicates, WLF recovery, law and
//! monotonicity warnings, a reference temperature between isotherms, the command line
//! (negative Celsius, a master curve, JSON) and its golden summary.

use crate::cli::golden;
use crate::support::{repo, run, run_ok};
use dea_fit::dma::fit::{self, Settings, ShiftMode};
use dea_fit::dma::law::{Law, LawKind};
use dea_fit::dma::read;
use dea_fit::dma::shift::{self, ShiftOn};
use dea_fit::dma::synth::Synthetic;
use dea_fit::dma::DmaData;
use dea_fit::fit::prony::frequency::FrequencyTerm;
use dea_fit::io::table::ColumnMap;
use dea_fit::material::viscoelastic::Prony;
use std::path::Path;

const C0: f64 = 273.15;

/// The VHB-like series of datasets/dma (E∞ and ten terms a decade apart).
fn vhb_prony() -> Prony {
    let terms: Vec<(f64, f64)> = [
        200e6, 100e6, 30e6, 10e6, 3e6, 1e6, 0.4e6, 0.2e6, 0.1e6, 0.05e6,
    ]
    .iter()
    .enumerate()
    .map(|(i, &e)| (10f64.powi(i as i32 - 8), e))
    .collect();
    Prony::new(0.08e6, &terms).unwrap()
}

/// Isotherms every `step` °C from `t0` to `t1` °C, 10 points 0.01–100 Hz.
fn synthetic(law: Law, t0: f64, t1: f64, step: f64, noise: f64, seed: u64) -> Synthetic {
    let n = ((t1 - t0) / step).round() as usize + 1;
    Synthetic {
        prony: vhb_prony(),
        law,
        vertical: None,
        temperatures_k: (0..n).map(|i| C0 + t0 + step * i as f64).collect(),
        frequencies_hz: dea_fit::io::relaxation::log_times(0.01, 100.0, 10, false),
        noise,
        seed,
    }
}

fn read_text(dir: &Path, name: &str, text: &str) -> DmaData {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    read::read_all(&[&p], &ColumnMap::default()).unwrap()
}

fn data(s: &Synthetic, dir: &Path) -> DmaData {
    read_text(dir, "iso.csv", &s.csv(&[]).unwrap())
}

fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("tempdir")
}

fn wlf25() -> Law {
    Law::wlf(C0 + 25.0, 8.06, 111.6)
}

/// The pair shifts' ±1.96σ hold the true shift (the law's difference between the
/// two temperatures) about 95 % of the time: 15 replicates × 20 pairs at each of
/// 0.3 %, 1 % and 3 % noise, on E′ and on E′ with E″. Binomial: 300 pairs at
/// p = 0.95 have σ = 1.3 %, so coverage within 90–99 % passes (pairs within a
/// replicate share isotherms, hence the wide band); at 0.3 % noise σ may be larger
/// than the scatter (conservative), never smaller.
#[test]
fn pair_shift_sigma_covers_the_truth() {
    let dir = tempdir();
    let law = wlf25();
    for (noise, on) in [
        (0.003, ShiftOn::Storage),
        (0.01, ShiftOn::Storage),
        (0.03, ShiftOn::Storage),
        (0.01, ShiftOn::Both),
    ] {
        let (mut inside, mut total) = (0, 0);
        let mut z2 = 0.0;
        for seed in 0..15 {
            let d = data(&synthetic(law, -20.0, 80.0, 5.0, noise, seed), dir.path());
            for w in d.isotherms.windows(2) {
                let p = shift::pair(&w[0], &w[1], on, false).unwrap();
                let truth = law.log_at(p.cold_k) - law.log_at(p.warm_k);
                let z = (p.log_shift - truth) / p.std_error;
                z2 += z * z;
                inside += usize::from(z.abs() <= 1.96);
                total += 1;
            }
        }
        let coverage = inside as f64 / total as f64;
        eprintln!(
            "noise {noise} on {}: coverage {coverage:.3} over {total} pairs, rms z {:.3}",
            on.name(),
            (z2 / total as f64).sqrt()
        );
        // below ≈ 1 % noise the interpolation's error between points 0.44 decades
        // apart is most of the residual scatter, and σ is conservative
        let top = if noise < 0.01 { 1.0 } else { 0.99 };
        assert!(
            (0.90..=top).contains(&coverage),
            "noise {noise}: coverage {coverage}"
        );
    }
}

fn settings(mode: ShiftMode, tr_c: f64) -> Settings {
    Settings {
        mode,
        reference_k: Some(C0 + tr_c),
        ..Settings::default()
    }
}

/// WLF C1 and C2 from the free shifts of `synth dma` isotherms (21 from −20 to 80 °C,
/// 1 % noise) hold the generating 8.06 and 111.6 K within 3σ on each of 5 seeds (C1
/// and C2 are strongly correlated: their σ come from the pair shifts' σ, checked
/// above), and the law fits its own data without a warning.
#[test]
fn wlf_constants_recovered_within_their_sigma() {
    let dir = tempdir();
    for seed in 0..5 {
        let d = data(
            &synthetic(wlf25(), -20.0, 80.0, 5.0, 0.01, seed),
            dir.path(),
        );
        let f = fit::fit(&d, &settings(ShiftMode::Law(LawKind::Wlf), 25.0)).unwrap();
        let m = f.shift_model.as_ref().unwrap();
        let (c1, c2) = (m.law.c1.unwrap(), m.law.c2.unwrap());
        let (s1, s2) = (m.c1_std_error.unwrap(), m.c2_std_error.unwrap());
        assert!((c1 - 8.06).abs() < 3.0 * s1, "seed {seed}: C1 {c1} ± {s1}");
        assert!((c2 - 111.6).abs() < 3.0 * s2, "seed {seed}: C2 {c2} ± {s2}");
        assert!(m.rms_decades < 0.05, "rms {}", m.rms_decades);
        assert!(
            !f.warnings.iter().any(|w| w.contains("WLF")),
            "{:?}",
            f.warnings
        );
    }
}

/// Arrhenius fitted to shifts made by WLF near the glass transition (the universal
/// constants C1 = 17.44, C2 = 51.6 K at Tr = Tg = −35 °C, isotherms −30 … 70 °C)
/// misses them by decades: the warning names the law.
#[test]
fn arrhenius_on_wlf_shifts_warns() {
    let dir = tempdir();
    let law = Law::wlf(C0 - 35.0, 17.44, 51.6);
    let d = data(&synthetic(law, -30.0, 70.0, 5.0, 0.01, 3), dir.path());
    let f = fit::fit(&d, &settings(ShiftMode::Law(LawKind::Arrhenius), 25.0)).unwrap();
    let m = f.shift_model.as_ref().unwrap();
    assert!(m.rms_decades > 0.25, "rms {}", m.rms_decades);
    assert!(
        f.warnings
            .iter()
            .any(|w| w.starts_with("Arrhenius fits the free shifts poorly")),
        "{:?}",
        f.warnings
    );
    assert_eq!(f.status, dea_fit::fit::Status::Warning);
}

/// A kinked law (Arrhenius with Ea = 250 kJ/mol below 30 °C, 60 kJ/mol above, both
/// referred to 30 °C, one file each): WLF cannot follow the kink and the tool says
/// it misses the shifts by more than their uncertainty.
#[test]
fn wlf_on_a_kinked_law_warns() {
    let dir = tempdir();
    let cold = synthetic(Law::arrhenius(C0 + 30.0, 250e3), -10.0, 30.0, 5.0, 0.01, 4);
    let hot = synthetic(Law::arrhenius(C0 + 30.0, 60e3), 35.0, 80.0, 5.0, 0.01, 5);
    let (a, b) = (dir.path().join("cold.csv"), dir.path().join("hot.csv"));
    std::fs::write(&a, cold.csv(&[]).unwrap()).unwrap();
    std::fs::write(&b, hot.csv(&[]).unwrap()).unwrap();
    let d = read::read_all(&[&a, &b], &ColumnMap::default()).unwrap();
    let f = fit::fit(&d, &settings(ShiftMode::Law(LawKind::Wlf), 30.0)).unwrap();
    assert!(
        f.warnings.iter().any(|w| w.starts_with("WLF ")),
        "{:?}",
        f.shift_model
    );
}

/// Two isotherms' temperatures swapped in the file (the 0 °C sweep labelled 5 °C and
/// the other way): the shift between them turns negative and the warning names
/// both temperatures and says why.
#[test]
fn non_monotonic_shifts_are_explained() {
    let dir = tempdir();
    let text = synthetic(wlf25(), -10.0, 30.0, 5.0, 0.01, 6)
        .csv(&[])
        .unwrap();
    let swapped: String = text
        .lines()
        .map(|l| {
            if let Some(r) = l.strip_prefix("0,") {
                format!("5,{r}\n")
            } else if let Some(r) = l.strip_prefix("5,") {
                format!("0,{r}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    // the swapped blocks are out of temperature order in the file: fine, one block each
    let d = read_text(dir.path(), "swapped.csv", &swapped);
    let f = fit::fit(&d, &settings(ShiftMode::Free, 25.0)).unwrap();
    let w: Vec<&String> = f
        .warnings
        .iter()
        .filter(|w| w.starts_with("shifts are not monotonic"))
        .collect();
    assert!(!w.is_empty(), "{:?}", f.warnings);
    assert!(
        w.iter()
            .any(|w| w.contains("0 °C") && w.contains("5 °C") && w.contains("cross")),
        "{w:?}"
    );
}

/// A reference temperature between isotherms (27.5 °C, isotherms every 5 °C): every
/// free shift holds the law's log aT(T) relative to 27.5 °C within 3σ plus 0.01
/// decade (the linear interpolation in T between 25 and 30 °C is off by < 0.003
/// decade for this law).
#[test]
fn reference_between_isotherms() {
    let dir = tempdir();
    let law = wlf25();
    let d = data(&synthetic(law, -20.0, 80.0, 5.0, 0.01, 7), dir.path());
    let f = fit::fit(&d, &settings(ShiftMode::Free, 27.5)).unwrap();
    let tr = C0 + 27.5;
    for s in &f.shift_factors {
        let truth = law.log_at(s.temperature_k) - law.log_at(tr);
        assert!(
            (s.log10_at - truth).abs() < 3.0 * s.std_error + 0.01,
            "{}: {} vs {truth} ± {}",
            s.temperature_k,
            s.log10_at,
            s.std_error
        );
    }
    assert!(!f.warnings.iter().any(|w| w.contains("outside")));
}

/// Bad files: each refused with exit status 2 at its file, line and column.
#[test]
fn bad_files_are_located() {
    let dir = tempdir();
    let cases = [
        (
            "negative.csv",
            "frequency_Hz,storage_modulus_MPa,loss_modulus_MPa\n0.1,1,0.2\n1,-2,0.3\n",
            "negative.csv:3:2: storage modulus must be in (0",
        ),
        (
            "repeated.csv",
            "# temperature: 25 C\nfrequency_Hz,storage_modulus_MPa,loss_modulus_MPa\n0.1,1,0.2\n1,2,0.3\n1,2.1,0.3\n",
            "repeated.csv:5:1: frequency repeats line 4",
        ),
        (
            "unordered.csv",
            "temperature_C,frequency_Hz,storage_modulus_MPa,tan_delta\n25,0.1,1,0.2\n25,1,2,0.3\n25,0.5,2.1,0.3\n",
            "unordered.csv:4:2: frequencies of the isotherm at 25 °C go up until line 3",
        ),
        (
            "no_unit.csv",
            "frequency,storage_modulus_MPa,loss_modulus_MPa\n0.1,1,0.2\n1,2,0.3\n",
            "no_unit.csv:1:1: column 'frequency' has no unit",
        ),
        (
            "not_finite.csv",
            "frequency_Hz,storage_modulus_MPa,loss_modulus_MPa\n0.1,1,0.2\n1,inf,0.3\n",
            "not_finite.csv:3:2:",
        ),
        (
            "back.csv",
            "temperature_C,frequency_Hz,storage_modulus_MPa,loss_modulus_MPa\n0,1,2,1\n0,10,3,1\n20,1,1,1\n20,10,2,1\n0,100,4,1\n",
            "back.csv:6: temperature 0 °C comes back",
        ),
    ];
    for (name, text, want) in cases {
        std::fs::write(dir.path().join(name), text).unwrap();
        let o = run(
            dir.path(),
            &["dma", name, "--reference-temperature", "25C", "--no-report"],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
    }
}

/// An instrument's export (preamble, units row, extra columns, both E″ and tan δ,
/// sweeps from high to low frequency) with a negative Celsius reference written
/// with `=` and without: read, shifted, JSON with the documented keys.
#[test]
fn export_with_negative_celsius_reference() {
    let dir = tempdir();
    let text = "Instrument: DMA 850\nSample: VHB\n\nTemperature,Frequency,Storage Modulus,Loss Modulus,Tan Delta,Strain amplitude\n(°C),(Hz),(MPa),(MPa),(),(%)\n0,100,10,5,0.5,1\n0,10,5,2,0.4,1\n0,1,2,0.8,0.4,1\n0,0.1,1,0.3,0.3,1\n20,100,4,1.5,0.4,1\n20,10,2,0.7,0.3,1\n20,1,1,0.3,0.3,1\n20,0.1,0.6,0.15,0.25,1\n";
    std::fs::write(dir.path().join("export.csv"), text).unwrap();
    for flag in [
        vec!["--reference-temperature=-5C"],
        vec!["--reference-temperature", "-5C"],
    ] {
        let mut args = vec![
            "dma",
            "export.csv",
            "--no-report",
            "--json",
            "--out",
            "f.json",
        ];
        args.extend(flag);
        let o = run_ok(dir.path(), &args);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!((v["reference_temperature_K"].as_f64().unwrap() - 268.15).abs() < 1e-9);
        let sf = v["shift_factors"].as_array().unwrap();
        assert_eq!(sf.len(), 2);
        for s in sf {
            assert!(
                s["temperature_K"].is_number()
                    && s["log10_aT"].is_number()
                    && s["std_error"].is_number()
            );
        }
        assert_eq!(v["fit_file"], "f.json");
        assert!(v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("columns not used: Tan Delta")));
    }
}

/// A master curve (no temperature; frequencies may repeat) is read as it is: no
/// shifts, its points sorted by frequency.
#[test]
fn master_curve_is_read_as_is() {
    let dir = tempdir();
    let text = "omega_rad_s,storage_modulus_kPa,loss_modulus_kPa\n1e-18,100,10\n1e-3,200,50\n1e-3,201,51\n1e12,9e5,1e5\n10,900,300\n";
    std::fs::write(dir.path().join("master.csv"), text).unwrap();
    let o = run_ok(
        dir.path(),
        &[
            "dma",
            "master.csv",
            "--terms",
            "auto",
            "--no-report",
            "--json",
            "--out",
            "m.json",
        ],
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["shift_factors"].as_array().unwrap().len(), 0);
    let m = v["master_curve"].as_array().unwrap();
    assert_eq!(m.len(), 5);
    assert_eq!(m[4]["reduced_omega_rad_s"].as_f64(), Some(1e12));
    assert!(v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().contains("sorted by frequency")));
}

/// `synth dma` is deterministic by seed: the shipped dataset is what its README's
/// command makes, byte for byte.
#[test]
fn shipped_dataset_is_its_command() {
    let dir = tempdir();
    let readme = std::fs::read_to_string(repo().join("datasets/dma/README.md")).unwrap();
    let cmd = readme
        .lines()
        .find(|l| l.starts_with("dea-fit synth dma"))
        .expect("the README gives the command");
    let args: Vec<&str> = cmd.split_whitespace().skip(1).collect();
    let out = dir.path().join("x.csv");
    let mut a: Vec<&str> = args
        .iter()
        .copied()
        .filter(|x| !x.starts_with("--out"))
        .collect();
    let shipped = args
        .iter()
        .find_map(|x| x.strip_prefix("--out="))
        .expect("--out=FILE");
    a.extend(["--out", out.to_str().unwrap()]);
    run_ok(&repo(), &a);
    let made = std::fs::read(&out).unwrap();
    assert_eq!(made, std::fs::read(repo().join(shipped)).unwrap());
}

/// The summary of `dea-fit dma datasets/dma/vhb_like_isotherms.csv
/// --reference-temperature 25C --shift wlf` is golden (text; the shifts are found on
/// a fixed grid and refined to 1e-6 decade, so only the last printed digit could
/// move with the platform's rounding).
#[test]
fn golden_vhb_like_wlf() {
    let dir = tempdir();
    let out = dir.path().join("f.json");
    let o = run_ok(
        &repo(),
        &[
            "dma",
            "datasets/dma/vhb_like_isotherms.csv",
            "--reference-temperature",
            "25C",
            "--shift",
            "wlf",
            "--no-report",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let text: String = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| match l.starts_with("fit: ") {
            true => "fit: <out>\n".to_string(),
            false => format!("{l}\n"),
        })
        .collect();
    golden("dma-vhb_like-wlf.txt", &text, |want| {
        (want != text).then(|| "the text differs".to_string())
    });
}

/// The Prony series of the master curve (`--terms auto`) from `synth dma` isotherms
/// (21 from −20 to 80 °C, WLF shifts, 1 % noise on E′ and E″) on 5 seeds: the
/// fitted E′ and E″ follow the generating series over the master curve's range
/// (rms ≤ 1.5 % of E′ and of |E*|, max ≤ 4 %: the fit averages the 1 % noise of 210
/// points, but the master curve is built with WLF shifts of σ ≈ 0.02 decades,
/// 2–3 % of E′ where its log-slope is ½; measured 0.25–0.93 % rms, 0.7–2.6 % max),
/// E(t) follows it over the τ range the data support (≤ 4 %, measured ≤ 2.5 %), and
/// E∞ holds
/// the true 80 kPa within 3σ; the status is `ok` or `warning`. On a 12-decade curve whose modulus spans 3.6 decades
/// the choice must keep terms of 0.02 % of E0 that carry the rubbery plateau (the
/// old rule, negligible below 0.1 % of E0, chose 4 terms: E∞ 86 kPa, 17 % rms).
#[test]
fn prony_of_the_master_curve_recovers_the_series() {
    let dir = tempdir();
    let truth = vhb_prony();
    for seed in 0..5 {
        let d = data(
            &synthetic(wlf25(), -20.0, 80.0, 5.0, 0.01, seed),
            dir.path(),
        );
        let f = fit::fit(&d, &settings(ShiftMode::Law(LawKind::Wlf), 25.0)).unwrap();
        let p = f.prony.fit.prony().unwrap();
        let [lo, hi] = f.reduced_omega_range_rad_s;
        let (mut s2, mut l2, mut worst) = (0.0, 0.0, 0.0f64);
        let n = 400;
        for i in 0..n {
            let w = lo * (hi / lo).powf(i as f64 / (n - 1) as f64);
            let (s, l) = p.storage_loss(w);
            let (st, lt) = truth.storage_loss(w);
            let (rs, rl) = ((s - st) / st, (l - lt) / st.hypot(lt));
            s2 += rs * rs;
            l2 += rl * rl;
            worst = worst.max(rs.abs()).max(rl.abs());
        }
        let (rs, rl) = ((s2 / n as f64).sqrt(), (l2 / n as f64).sqrt());
        let [a, b] = f.prony.fit.supported_tau_s;
        let worst_t = (0..n)
            .map(|i| a * (b / a).powf(i as f64 / (n - 1) as f64))
            .map(|t| (p.relaxation_modulus(t) / truth.relaxation_modulus(t) - 1.0).abs())
            .fold(0.0, f64::max);
        let (e_inf, se) = (f.prony.fit.e_inf_pa, f.prony.fit.e_inf_std_pa.unwrap());
        eprintln!(
            "seed {seed}: {} terms, rms E′ {rs:.4} E″ {rl:.4}, max {worst:.4}, E(t) max {worst_t:.4}, E∞ {e_inf:.0} ± {se:.0}",
            f.prony.terms.len()
        );
        assert!(rs <= 0.015 && rl <= 0.015 && worst <= 0.04, "seed {seed}");
        assert!(worst_t <= 0.04, "seed {seed}: E(t) off by {worst_t}");
        assert!(
            (e_inf - 80e3).abs() <= 3.0 * se,
            "seed {seed}: E∞ {e_inf} ± {se}"
        );
        // `warning` where a larger count scored better but is not identifiable (said)
        let status = f.prony.fit.status.to_string();
        assert!(
            status == "ok" || status == "warning",
            "{status}: {:?}",
            f.warnings
        );
    }
}

/// The σ of a DMA fit are honest: on 40 noise replicates of the `synth dma`
/// isotherms of the recovery test above (seeds 100–139, 1 % noise, WLF shifts,
/// `--terms auto`), with z = (estimate − truth)/σ:
///
/// - E∞'s 95 % interval (t quantile) and the WLF C1 and C2 intervals (±1.96σ) each
///   hold the generating value at least 34 times: the exact binomial bound, for 40
///   replicates at a true coverage of 95 % P(X ≤ 33) = 0.34 %;
/// - rms z of E∞ ≤ 1.2: for a correct σ, 40·rms z² is χ² with 40 degrees of
///   freedom and exceeds 40·1.2² = 57.6 with probability 3.5 % (the sampling error of
///   rms z over 40 replicates is 1/√80 ≈ 0.11);
/// - rms z of the terms' Eᵢ and of their τᵢ, pooled over the 10 terms of the fits
///   that chose the generating 10 (matched by rank of τ), within [0.8, 1.1] each
///   (400 values, correlated within a fit, so an effective count between 40 and
///   400: sampling error 0.04–0.11): not too small, and not too large either;
/// - the same for the terms of the master curves built with the free shifts
///   (`--shift free`, their full covariance carried);
/// - rms z of C1 and C2 ≤ 1.15;
/// - rms z of the free log10 aT (all isotherms but the reference's, whose σ is 0)
///   within [0.85, 1.15]: not too small, and not too large either (800 values,
///   correlated along each replicate's chain).
///
/// Measured (`cargo test --release --test main dma_intervals -- --nocapture`):
/// E∞ rms z 1.13, 38/40 intervals (over 200 replicates, seeds 100–299: 1.04, 95 %);
/// Eᵢ 0.94, τᵢ 0.96 (all 40 fits chose 10 terms; with free shifts Eᵢ 0.97, τᵢ
/// 0.95); C1 0.62 and C2 0.71, 40/40
/// (conservative: the law takes the pair shifts as independent); free log10 aT
/// 1.10 pooled (over 200 replicates 0.79–1.11 by temperature). Before the
/// accumulation took the correlation of adjacent pairs
/// ([`dea_fit::dma::shift::adjacent_correlations`]: they share an isotherm, and
/// their errors largely cancel in the sum), 0.79 pooled, 0.35–0.45 at the ends of
/// the chain: σ 2–3× too large.
/// Before the Prony covariance became the sandwich one
/// ([`dea_fit::fit::prony`], assess: the fit weighs storage and loss rows alike
/// but their noise differs), the same replicates gave E∞ 1.26 (36/40), Eᵢ 1.47,
/// τᵢ 1.69: this test failed. Master curves built with the true shifts gave the same
/// numbers within 0.02 (E∞ 1.28 before, 1.14 after; Eᵢ 0.95, τᵢ 0.97 after): the
/// shifts' uncertainty was not what σ missed most. It is carried now (the law's
/// shifts' covariance, [`dea_fit::dma::law::LawFit::shift_covariance`], through
/// the Prony fit's derivatives, assess): without it τᵢ had rms z 1.05; carried with
/// the law constants' conservative covariance instead of the sandwich, 0.77 (below
/// the band). The replicates run in parallel (rayon).
#[test]
fn dma_intervals_cover_the_truth() {
    use rayon::prelude::*;
    let dir = tempdir();
    let truth = vhb_prony();
    let law = wlf25();
    let seeds: Vec<u64> = (100..140).collect();
    struct Replicate {
        held: [bool; 3],
        z_inf: f64,
        z_c: [f64; 2],
        z_terms: Vec<(f64, f64)>,
        z_free_terms: Vec<(f64, f64)>,
        z_shifts: Vec<f64>,
    }
    let reps: Vec<Replicate> = seeds
        .par_iter()
        .map(|&seed| {
            let syn = synthetic(law, -20.0, 80.0, 5.0, 0.01, seed);
            let d = read_text(dir.path(), &format!("iso-{seed}.csv"), &syn.csv(&[]).unwrap());
            let f = fit::fit(&d, &settings(ShiftMode::Law(LawKind::Wlf), 25.0)).unwrap();
            let e_inf = &f.prony.fit.parameters[0];
            let [lo, hi] = e_inf.ci95.expect("E∞ has an interval");
            let m = f.shift_model.as_ref().expect("WLF fitted");
            let z = |v: Option<f64>, s: Option<f64>, truth: f64| (v.unwrap() - truth) / s.unwrap();
            let z_c = [
                z(m.law.c1, m.c1_std_error, 8.06),
                z(m.law.c2, m.c2_std_error, 111.6),
            ];
            let terms = &f.prony.fit.terms;
            let z_of = |terms: &[FrequencyTerm]| match terms.len() == truth.terms.len() {
                true => terms
                    .iter()
                    .zip(&truth.terms)
                    .map(|(t, g)| {
                        (
                            z(Some(t.modulus_pa), t.modulus_std_pa, g.modulus),
                            z(Some(t.tau_s), t.tau_std_s, g.tau),
                        )
                    })
                    .collect(),
                false => Vec::new(),
            };
            let z_terms = z_of(terms);
            let free = fit::fit(&d, &settings(ShiftMode::Free, 25.0)).unwrap();
            let z_free_terms = z_of(&free.prony.fit.terms);
            let z_shifts = f
                .shift_factors
                .iter()
                .filter(|s| s.temperature_k != C0 + 25.0)
                .map(|s| (s.log10_at - law.log_at(s.temperature_k)) / s.std_error)
                .collect();
            eprintln!(
                "seed {seed}: E∞ {:.0} [{lo:.0}, {hi:.0}], C1 {:.3} ± {:.3}, C2 {:.2} ± {:.2}, {} terms",
                e_inf.value,
                m.law.c1.unwrap(),
                m.c1_std_error.unwrap(),
                m.law.c2.unwrap(),
                m.c2_std_error.unwrap(),
                terms.len()
            );
            Replicate {
                held: [
                    (lo..=hi).contains(&80e3),
                    z_c[0].abs() <= 1.96,
                    z_c[1].abs() <= 1.96,
                ],
                z_inf: (e_inf.value - 80e3) / e_inf.std_error.unwrap(),
                z_c,
                z_terms,
                z_free_terms,
                z_shifts,
            }
        })
        .collect();
    for (j, name) in ["E∞", "C1", "C2"].iter().enumerate() {
        let count = reps.iter().filter(|r| r.held[j]).count();
        eprintln!("{name}: {count}/40 intervals hold the truth");
        assert!(
            count >= 34,
            "{name}: {count}/40 95 % intervals hold the truth"
        );
    }
    let rms = |z: Vec<f64>| (z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64).sqrt();
    let with_terms = reps.iter().filter(|r| !r.z_terms.is_empty()).count();
    assert!(with_terms >= 30, "{with_terms}/40 fits chose 10 terms");
    let pooled_of = |terms: fn(&Replicate) -> &Vec<(f64, f64)>, part: fn(&(f64, f64)) -> f64| {
        rms(reps
            .iter()
            .flat_map(|r| terms(r).iter().map(part))
            .collect())
    };
    let pooled = |part: fn(&(f64, f64)) -> f64| pooled_of(|r| &r.z_terms, part);
    for (name, value, limit) in [
        ("E∞", rms(reps.iter().map(|r| r.z_inf).collect()), 1.2),
        ("Eᵢ", pooled(|t| t.0), 1.1),
        ("τᵢ", pooled(|t| t.1), 1.1),
        ("C1", rms(reps.iter().map(|r| r.z_c[0]).collect()), 1.15),
        ("C2", rms(reps.iter().map(|r| r.z_c[1]).collect()), 1.15),
    ] {
        eprintln!("{name}: rms z {value:.3} (at most {limit})");
        assert!(value <= limit, "{name}: rms z {value:.3} > {limit}");
    }
    for (name, value) in [("Eᵢ", pooled(|t| t.0)), ("τᵢ", pooled(|t| t.1))] {
        assert!(value >= 0.8, "{name}: rms z {value:.3} < 0.8: σ too large");
    }
    let with_free = reps.iter().filter(|r| !r.z_free_terms.is_empty()).count();
    assert!(
        with_free >= 30,
        "{with_free}/40 free-shift fits chose 10 terms"
    );
    for (name, value) in [
        ("Eᵢ (free shifts)", pooled_of(|r| &r.z_free_terms, |t| t.0)),
        ("τᵢ (free shifts)", pooled_of(|r| &r.z_free_terms, |t| t.1)),
    ] {
        eprintln!("{name}: rms z {value:.3} (within 0.8 … 1.1)");
        assert!(
            (0.8..=1.1).contains(&value),
            "{name}: rms z {value:.3} outside 0.8 … 1.1"
        );
    }
    let shifts = rms(reps.iter().flat_map(|r| r.z_shifts.clone()).collect());
    eprintln!("log10 aT: rms z {shifts:.3} (within 0.85 … 1.15)");
    assert!(
        (0.85..=1.15).contains(&shifts),
        "log10 aT: rms z {shifts:.3} outside 0.85 … 1.15"
    );
}

/// 30 terms on the shipped 21 × 10 sweep (far more than its 12 decades resolve:
/// 16 come out negligible) converge: the joint polish stops where a step lowers
/// ½χ² by less than 10⁻³. Before, both polishes (the fit's and the Kramers–Kronig
/// check's) walked the negligible terms' flat valleys to the 200-iteration limit
/// for 0.06 in ½χ² (408 iterations, status `not_converged`, 2.3 G instructions;
/// then 211 iterations, `ill_posed` for the negligible terms, 1.2 G). The starts'
/// searches stop at their noise floor too (126 iterations, 0.45 G with the
/// Kramers–Kronig fit started from the joint fit's τ): the bound of 160 fails
/// without it.
#[test]
fn thirty_terms_converge_and_say_they_are_too_many() {
    let data = read::read_all(
        &[&repo().join("datasets/dma/vhb_like_isotherms.csv")],
        &ColumnMap::default(),
    )
    .unwrap();
    let s = Settings {
        terms: Some(30),
        ..settings(ShiftMode::Free, 25.0)
    };
    let f = fit::fit(&data, &s).unwrap().prony.fit;
    assert!(
        f.solver.termination.starts_with("converged"),
        "{}",
        f.solver.termination
    );
    assert!(
        f.solver.iterations < 160,
        "{} iterations",
        f.solver.iterations
    );
    assert_eq!(f.status.to_string(), "ill_posed", "{:?}", f.warnings);
    assert!(f.warnings.iter().any(|w| w.contains("negligible")));
}

/// pyvisco's published example master curve (its verification/freq_master, at
/// −5 °C, 206 points over 26 decades; origin, licence and SHA-256 in
/// datasets/dma/README.md), read through `--columns`: dea-fit's Prony series
/// follows E′ within 3 % rms and 10 % max (measured 2.10 % and 7.45 %; the ANSYS
/// table pyvisco publishes for the same curve: 2.41 % and 6.54 %, compared in
/// .ci/pyvisco-reference.sh) and E″ within 10 % of |E*| rms (7.31 %: the measured E″
/// is ≈ 11 % of a flat E′ on the rubbery end, which no series consistent with E′
/// gives), with E∞ > 0 fitted, and the Kramers–Kronig check says where.
#[test]
fn pyvisco_published_master_curve() {
    let dir = tempdir();
    let data = repo().join("datasets/dma/pyvisco_freq_user_master.csv");
    let o = run_ok(
        dir.path(),
        &[
            "dma",
            data.to_str().unwrap(),
            "--columns",
            "frequency=f:Hz,storage=E_stor:MPa,loss=E_loss:MPa",
            "--reference-temperature=-5C",
            "--no-report",
            "--json",
        ],
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let p = &v["prony"];
    let e_inf = p["E_inf"].as_f64().unwrap();
    let terms: Vec<(f64, f64)> = p["terms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| (t["tau"].as_f64().unwrap(), t["E"].as_f64().unwrap()))
        .collect();
    let prony = Prony::new(e_inf, &terms).unwrap();
    let master = v["master_curve"].as_array().unwrap();
    assert_eq!(master.len(), 206);
    let (mut s2, mut l2, mut worst) = (0.0, 0.0, 0.0f64);
    for m in master {
        let w = m["reduced_omega_rad_s"].as_f64().unwrap();
        let (s, l) = (
            m["storage_Pa"].as_f64().unwrap(),
            m["loss_Pa"].as_f64().unwrap(),
        );
        let (fs, fl) = prony.storage_loss(w);
        let (rs, rl) = (fs / s - 1.0, (fl - l) / s.hypot(l));
        s2 += rs * rs;
        l2 += rl * rl;
        worst = worst.max(rs.abs());
    }
    let n = master.len() as f64;
    let (rs, rl) = ((s2 / n).sqrt(), (l2 / n).sqrt());
    eprintln!("rms E′ {rs:.4}, max E′ {worst:.4}, rms E″/|E*| {rl:.4}, E∞ {e_inf:.4e} Pa");
    assert!(rs <= 0.03 && worst <= 0.10 && rl <= 0.10);
    assert!(e_inf > 0.0);
    assert!(v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().contains("Kramers–Kronig")));
}
