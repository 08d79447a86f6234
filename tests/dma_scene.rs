//! A DMA fit as a material file (issue 36): read as a relaxation fit is, its Prony
//! series at a scene's `material.temperature` by its time–temperature shift, and
//! written with the shift law by `export`.

use crate::export::{DMA_ARRHENIUS, DMA_FREE, DMA_WLF};
use crate::material_file::trajectory;
use dea_fit::export::{self, Options, Target};
use dea_fit::material::file::{read_material, read_viscous, MaterialFile, RelaxationPart};
use dea_fit::sim::scene::Scene;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The fit file as JSON.
fn json(path: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn relaxation(path: &str) -> RelaxationPart {
    match read_material(Path::new(path)).unwrap().0 {
        MaterialFile::Relaxation(r) => r,
        _ => panic!("{path}: not read as a relaxation fit"),
    }
}

/// A one-layer Neo-Hookean stack with the DMA fit `fit` as its viscous part and
/// `extra` lines in [material], read as if it were in tests/data/dma/.
fn scene_text(fit: &str, extra: &str) -> String {
    crate::sim::nh_layer(
        &format!("{fit}\n{extra}"),
        "[[input]]\nkind = \"step\"\namplitude = \"3 kV\"",
        "span = \"2 s\"\nsamples = 40",
    )
}

fn parse(text: &str) -> dea_fit::Result<Scene> {
    Scene::parse(text, Path::new("tests/data/dma/scene.toml"))
}

fn scene(fit_file: &str, extra: &str) -> Scene {
    let name = Path::new(fit_file).file_name().unwrap().to_str().unwrap();
    parse(&scene_text(&format!("{{ fit = \"{name}\" }}"), extra)).expect("valid scene")
}

/// A Prony term (τ in s, E in Pa).
type Term = (f64, f64);

/// An edit of a fit file's JSON.
type Edit = Box<dyn Fn(&mut Value)>;

/// The fit's terms (τ, E) of nonzero modulus, in file order.
fn terms(v: &Value) -> Vec<Term> {
    v["prony"]["terms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| (t["tau"].as_f64().unwrap(), t["E"].as_f64().unwrap()))
        .filter(|t| t.1 != 0.0)
        .collect()
}

/// A DMA fit is read through the relaxation-fit path: the same RelaxationPart
/// (parallel reading, arms kⱼ = Eⱼ, ηⱼ = Eⱼτⱼ), its terms of modulus exactly 0
/// left out, its shift law with it; `read_viscous` gives the same arms (at Tr).
#[test]
fn a_dma_fit_reads_as_a_relaxation_fit_with_its_shift() {
    let v = json(DMA_WLF);
    let r = relaxation(DMA_WLF);
    let want = terms(&v);
    assert_eq!(v["prony"]["terms"].as_array().unwrap().len(), 14);
    assert_eq!(r.arms.len(), want.len(), "the zero terms are left out");
    assert!(
        want.len() < 14,
        "the shipped fit has zero terms to leave out"
    );
    for (a, (tau, e)) in r.arms.iter().zip(&want) {
        assert_eq!(a.k_pa, *e);
        assert_eq!(a.eta_pa_s, e * tau);
    }
    assert_eq!(r.long_term_pa, v["prony"]["E_inf"].as_f64().unwrap());
    assert_eq!(r.formulation.to_string(), "parallel");
    let s = r.shift.expect("a shift law");
    let law = s.law.expect("WLF");
    assert_eq!(law.c1, v["shift_model"]["C1"].as_f64());
    assert_eq!(law.c2, v["shift_model"]["C2"].as_f64());
    assert!((s.reference_k - 298.15).abs() < 1e-9);
    assert_eq!(s.measured.len(), 21);
    let (arms, nv) = read_viscous(Path::new(DMA_WLF)).unwrap();
    assert_eq!(arms, r.arms);
    assert_eq!(nv, None);
    assert!(relaxation(DMA_FREE).shift.unwrap().law.is_none());
    assert!(relaxation(DMA_ARRHENIUS)
        .shift
        .unwrap()
        .law
        .unwrap()
        .activation_energy
        .is_some());
}

/// At T = Tr the scene is the scene without a temperature, bit for bit (aT = bT = 1
/// exactly), for a law and for free shifts.
#[test]
fn at_the_reference_temperature_nothing_changes() {
    for f in [DMA_WLF, DMA_FREE] {
        let plain = scene(f, "");
        for t in ["temperature = \"25 C\"", "temperature = \"298.15 K\""] {
            let at = scene(f, t);
            assert_eq!(at.material.viscous, plain.material.viscous, "{f} {t}");
            assert!(at.doubts.len() == plain.doubts.len(), "{:?}", at.doubts);
        }
        assert_eq!(
            trajectory(&scene(f, "temperature = \"25 C\"")),
            trajectory(&plain)
        );
    }
}

/// At T ≠ Tr every relaxation time is aT(T) times the fit's and the moduli are as
/// fitted (no vertical shift), aT computed here from the file's own constants:
/// WLF log10 aT = −C1 (T − Tr)/(C2 + T − Tr), Arrhenius Ea/(R ln 10)(1/T − 1/Tr),
/// free shifts at a measured temperature its measured log10 aT. Tolerance 1e-13
/// relative: one power of ten and one product each (a few ulp; a wrong sign or
/// base is a factor of 10 or more). The simulator runs what was built: the scene
/// at 40 °C is, bit for bit, the scene with those arms inline, and not the one at Tr.
#[test]
fn relaxation_times_scale_by_exactly_at() {
    let (t, tr) = (313.15, 298.15);
    let wlf = json(DMA_WLF);
    let (c1, c2) = (
        wlf["shift_model"]["C1"].as_f64().unwrap(),
        wlf["shift_model"]["C2"].as_f64().unwrap(),
    );
    let arr = json(DMA_ARRHENIUS);
    let ea = arr["shift_model"]["activation_energy_J_mol"]
        .as_f64()
        .unwrap();
    let free = json(DMA_FREE);
    let measured = free["shift_factors"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| (f["temperature_K"].as_f64().unwrap() - t).abs() < 1e-9)
        .unwrap()["log10_aT"]
        .as_f64()
        .unwrap();
    let r_ln10 = 8.314_462_618 * std::f64::consts::LN_10;
    for (f, v, log_at) in [
        (DMA_WLF, &wlf, -c1 * (t - tr) / (c2 + t - tr)),
        (DMA_ARRHENIUS, &arr, ea / r_ln10 * (1.0 / t - 1.0 / tr)),
        (DMA_FREE, &free, measured),
    ] {
        assert!(log_at < -0.5, "{f}: 40 °C relaxes faster than 25 °C");
        let s = scene(f, "temperature = \"40 C\"");
        let at = 10f64.powf(log_at);
        // arms faster than 1 ns at 40 °C are folded into the dashpot (k·τ·aT)
        let (want, fast): (Vec<Term>, Vec<Term>) =
            terms(v).into_iter().partition(|(tau, _)| tau * at >= 1e-9);
        assert_eq!(s.material.viscous.arms.len(), want.len(), "{f}");
        for (a, (tau, e)) in s.material.viscous.arms.iter().zip(&want) {
            assert_eq!(a.k_pa, *e, "{f}");
            let got = a.eta_pa_s / a.k_pa;
            let exp = tau * at;
            assert!(
                (got / exp - 1.0).abs() < 1e-13,
                "{f}: tau {got} vs aT*tau {exp}"
            );
        }
        let nv: f64 = fast.iter().map(|(tau, e)| e * tau * at).sum();
        assert!(
            (s.material.viscous.nv_pa_s - nv).abs() <= 1e-13 * nv,
            "{f}: nv {} vs {nv}",
            s.material.viscous.nv_pa_s
        );
    }
    let hot = scene(DMA_WLF, "temperature = \"40 C\"");
    let arms: Vec<String> = hot
        .material
        .viscous
        .arms
        .iter()
        .map(|a| format!("{{ k = {:?}, eta = {:?} }}", a.k_pa, a.eta_pa_s))
        .collect();
    let inline = parse(&scene_text(
        &format!("{{ arms = [ {} ] }}", arms.join(", ")),
        "",
    ))
    .unwrap();
    assert_eq!(inline.material.viscous, hot.material.viscous);
    let th = trajectory(&hot);
    assert_eq!(th, trajectory(&inline));
    assert_ne!(th, trajectory(&scene(DMA_WLF, "")));
}

/// Outside the measured temperatures (−20 … 80 °C) the scene warns with the
/// numbers; an arm faster than 1 ns there is folded into the dashpot as k·τ, said.
#[test]
fn outside_the_measured_temperatures_is_a_warning_with_the_numbers() {
    let s = scene(DMA_WLF, "temperature = \"90 C\"");
    let all = s.doubts.join("\n");
    assert!(
        all.contains("scene.toml:")
            && all.contains(
                "temperature 90 °C is outside the DMA fit's measured temperatures -20 °C … 80 °C"
            )
            && all.contains("extrapolated by the WLF law"),
        "{all}"
    );
    // folded arms: their k·τ·aT is the dashpot
    let v = json(DMA_WLF);
    let (c1, c2) = (
        v["shift_model"]["C1"].as_f64().unwrap(),
        v["shift_model"]["C2"].as_f64().unwrap(),
    );
    let at = 10f64.powf(-c1 * 65.0 / (c2 + 65.0));
    let fast: Vec<(f64, f64)> = terms(&v)
        .into_iter()
        .filter(|(tau, _)| tau * at < 1e-9)
        .collect();
    assert!(!fast.is_empty());
    let nv: f64 = fast.iter().map(|(tau, e)| e * tau * at).sum();
    assert!((s.material.viscous.nv_pa_s / nv - 1.0).abs() < 1e-12);
    assert_eq!(s.material.viscous.arms.len() + fast.len(), terms(&v).len());
    assert!(all.contains("a dashpot k*tau, added to Nv"), "{all}");
    // inside the range: no warning of it
    assert!(!scene(DMA_WLF, "temperature = \"-5 C\"")
        .doubts
        .iter()
        .any(|d| d.contains("outside")));
    assert!(scene(DMA_FREE, "temperature = \"-30 C\"")
        .doubts
        .iter()
        .any(|d| d.contains("extrapolated from the nearest two measured shifts")));
}

fn error(fit: &str, extra: &str) -> String {
    parse(&scene_text(fit, extra))
        .err()
        .expect("refused")
        .to_string()
}

/// Located errors: below the WLF singularity, a temperature without a shift law (a
/// relaxation fit, inline arms, no viscous part), a temperature without a unit.
#[test]
fn temperature_errors_are_located() {
    let dma = "{ fit = \"vhb_like-wlf.json\" }";
    let e = error(dma, "temperature = \"-100 C\"");
    assert!(
        e.contains("scene.toml:")
            && e.contains("material.temperature")
            && e.contains("WLF singularity"),
        "{e}"
    );
    // Arrhenius has no singularity, but at −100 °C its slowest arm exceeds 10¹² s
    let e = error(
        "{ fit = \"vhb_like-arrhenius.json\" }",
        "temperature = \"-100 C\"",
    );
    assert!(
        e.contains("material.temperature") && e.contains("glassy"),
        "{e}"
    );
    assert!(parse(&scene_text(
        "{ fit = \"vhb_like-arrhenius.json\" }",
        "temperature = \"-30 C\""
    ))
    .is_ok());
    for v in [
        "{ fit = \"../export/vhb4910-relaxation.json\" }",
        "{ arms = [ { k = \"10 kPa\", tau = \"1 s\" } ] }",
        "{ preset = \"elastic\" }",
    ] {
        let e = error(v, "temperature = \"40 C\"");
        assert!(
            e.contains("material.temperature") && e.contains("no time–temperature shift"),
            "{v}: {e}"
        );
        assert!(e.contains("dea-fit dma"), "the hint names the way: {e}");
    }
    let e = error(dma, "temperature = \"40\"");
    assert!(
        e.contains("material.temperature") && e.contains("no unit"),
        "{e}"
    );
    let e = error(dma, "temperature = 40");
    assert!(e.contains("material.temperature"), "{e}");
}

/// A malformed DMA fit is refused at its key: a term edited against the fit's
/// parameters, a law without its constants, an unknown shift, shifts out of order.
#[test]
fn a_malformed_dma_fit_is_refused_at_its_key() {
    let dir = tempfile::tempdir().unwrap();
    let base = json(DMA_WLF);
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "term",
            Box::new(|v| v["prony"]["terms"][3]["tau"] = 1.5.into()),
            "prony.terms[3]: term 4 disagrees",
        ),
        (
            "law",
            Box::new(|v| v["shift_model"] = Value::Null),
            "shift_model: missing",
        ),
        (
            "c2",
            Box::new(|v| v["shift_model"]["C2"] = (-5.0).into()),
            "shift_model: not a WLF law",
        ),
        (
            "shift",
            Box::new(|v| v["shift"] = "vogel".into()),
            "shift: 'vogel' is not free, wlf or arrhenius",
        ),
        (
            "order",
            Box::new(|v| v["shift_factors"][2]["temperature_K"] = 200.0.into()),
            "shift_factors[2].temperature_K",
        ),
        (
            "type",
            Box::new(|v| v["prony"]["E_inf"] = "big".into()),
            "not a material file of its schema",
        ),
    ];
    for (name, edit, want) in cases {
        let mut v = base.clone();
        edit(&mut v);
        let p: PathBuf = dir.path().join(format!("{name}.json"));
        std::fs::write(&p, serde_json::to_string_pretty(&v).unwrap()).unwrap();
        let e = read_material(&p).expect_err(name).to_string();
        assert!(
            e.contains(&p.display().to_string()) && e.contains(want),
            "{name}: {e}"
        );
    }
}

fn card(files: &[&str], t: Target) -> export::Card {
    let paths: Vec<PathBuf> = files.iter().map(PathBuf::from).collect();
    export::card(&export::read(&paths).unwrap(), t, &Options::default()).unwrap()
}

/// The line after `keyword` in `text`, as numbers.
fn data_after(text: &str, keyword: &str) -> Vec<f64> {
    let mut lines = text.lines().skip_while(|l| !l.starts_with(keyword));
    assert!(lines.next().is_some(), "no {keyword} in\n{text}");
    let l = lines.next().unwrap();
    let l = l.strip_prefix("TBDATA,1,").unwrap_or(l);
    l.split(',').map(|x| x.trim().parse().unwrap()).collect()
}

/// The shift law in each code's card, read back: Abaqus *TRS (WLF θ0, C1, C2;
/// Arrhenius θ0, E0 with R in *PHYSICAL CONSTANTS), ANSYS TB,SHIFT (WLF Tr, C1, C2;
/// TN Tr, Ea/R), COMSOL's shift-function parameters; free shifts and codes without
/// a shift write none and say so. Abaqus rounds to 20 characters (5e-13 relative).
#[test]
fn cards_carry_the_shift_law() {
    let v = json(DMA_WLF);
    let (c1, c2) = (
        v["shift_model"]["C1"].as_f64().unwrap(),
        v["shift_model"]["C2"].as_f64().unwrap(),
    );
    let close = |a: f64, b: f64| (a - b).abs() <= 5e-13 * b.abs();
    let a = card(&[DMA_WLF], Target::Abaqus);
    assert_eq!(a.status, "ill_posed", "the fit's status travels");
    let d = data_after(&a.text, "*TRS, DEFINITION=WLF");
    assert!(
        close(d[0], 298.15) && close(d[1], c1) && close(d[2], c2),
        "{d:?}"
    );
    assert!(a.text.contains("temperatures in K"));
    let ans = card(&[DMA_WLF], Target::Ansys);
    let d = data_after(&ans.text, "TB,SHIFT,1,,3,WLF");
    assert!(close(d[0], 298.15) && d[1] == c1 && d[2] == c2, "{d:?}");
    let com = card(&[DMA_WLF], Target::Comsol);
    assert!(
        com.text.contains(&format!("C1_WLF {}", export::num(c1))),
        "{}",
        com.text
    );
    assert!(com.text.contains("T_ref 2.9815E2[K]"), "{}", com.text);

    let ea = json(DMA_ARRHENIUS)["shift_model"]["activation_energy_J_mol"]
        .as_f64()
        .unwrap();
    let a = card(&[DMA_ARRHENIUS], Target::Abaqus);
    let d = data_after(&a.text, "*TRS, DEFINITION=ARRHENIUS");
    assert!(close(d[0], 298.15) && close(d[1], ea), "{d:?}");
    assert!(a
        .text
        .contains("*PHYSICAL CONSTANTS, ABSOLUTE ZERO=0., UNIVERSAL GAS CONSTANT=8.314462618E0"));
    let d = data_after(
        &card(&[DMA_ARRHENIUS], Target::Ansys).text,
        "TB,SHIFT,1,,2,TN",
    );
    assert!(close(d[1], ea / 8.314_462_618), "{d:?}");

    for t in [Target::Abaqus, Target::Ansys, Target::Comsol] {
        let c = card(&[DMA_FREE], t);
        assert!(
            !c.text.lines().any(|l| l.starts_with("*TRS")
                || l.starts_with("TB,SHIFT")
                || l.starts_with("T_ref")),
            "{t:?}: {}",
            c.text
        );
        assert!(
            c.warnings.iter().any(|w| w.contains("shifts are free")),
            "{t:?}: {:?}",
            c.warnings
        );
    }
    // CalculiX (no *VISCOELASTIC), LS-DYNA and FEBio (no shift in their cards):
    // the card is the material at Tr, said as a warning
    let c = card(&[crate::export::YEOH, DMA_WLF], Target::Calculix);
    assert!(!c.text.lines().any(|l| l.starts_with("*TRS")));
    assert!(c
        .warnings
        .iter()
        .any(|w| w.contains("CalculiX (it ignores *VISCOELASTIC) has no WLF")));
    let mut m =
        export::read(&[PathBuf::from(crate::export::YEOH), PathBuf::from(DMA_WLF)]).unwrap();
    m.relaxation.as_mut().unwrap().terms.truncate(6);
    let opts = Options {
        density: Some(960.0),
        ..Options::default()
    };
    for t in [Target::Lsdyna, Target::Febio] {
        let c = export::card(&m, t, &opts).unwrap();
        assert!(
            c.warnings.iter().any(
                |w| w.contains("has no WLF time-temperature shift") && w.contains("2.9815E2 K")
            ),
            "{t:?}: {:?}",
            c.warnings
        );
    }
}
