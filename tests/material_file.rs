//! Material files (issue 10): the identified material written and read back, as a
//! scene's whole material and by part, refused when edited inconsistently; the
//! estimators' fit files read as the same material part they hold; and the module
//! sits below both `fit` and `sim`.

use crate::support::repo;
use dea_fit::fit::hyperelastic::HyperelasticFit;
use dea_fit::material::file::{
    self, Arm, FittedRanges, HyperelasticPart, IdentifiedMaterial, ParamUncertainty, StretchRange,
    Viscous,
};
use dea_fit::material::hyperelastic::{Mode, ModelSpec, OgdenForm};
use dea_fit::sim::scene::Scene;
use dea_fit::sim::{simulate, RunOptions};
use serde_json::{json, Value};
use std::path::Path;

/// The fast damped stack (≈ 300 steps) with its material block replaced.
pub fn scene_with(material: &str) -> String {
    let text =
        std::fs::read_to_string(repo().join("datasets/scenes/stack_step_5kV_damped.toml")).unwrap();
    let block = "hyperelastic = { preset = \"vhb4910-yeoh\" }\nviscous = { preset = \"elatrache2021-table-4.2\" }\nrelative_permittivity = 4.7\n";
    assert!(text.contains(block), "the scene's material block changed");
    text.replace(block, material)
}

fn unc(name: &str, unit: &str, value: f64, se: Option<f64>, ok: bool) -> ParamUncertainty {
    ParamUncertainty {
        name: name.into(),
        unit: unit.into(),
        value,
        std_error: se,
        identifiable: ok,
    }
}

/// Stated constants: the seed's VHB4910 Yeoh (C30 held fixed), one arm, Nv, εr.
pub fn material() -> IdentifiedMaterial {
    IdentifiedMaterial {
        hyperelastic: HyperelasticPart {
            spec: ModelSpec::new("yeoh", OgdenForm::Abaqus),
            params: vec![69.3e3, -888.0, 16.7],
            ranges: Some(FittedRanges {
                per_mode: vec![StretchRange {
                    mode: Mode::Uniaxial,
                    stretch_min: 0.98,
                    stretch_max: 1.01,
                }],
            }),
        },
        viscous: Some(Viscous {
            nv_pa_s: 1875.0,
            arms: vec![Arm {
                k_pa: 2e4,
                eta_pa_s: 1e4,
            }],
        }),
        eps_r: Some(4.7),
        composite: None,
        uncertainty: vec![
            unc("C10", "Pa", 69.3e3, Some(410.0), true),
            unc("C20", "Pa", -888.0, Some(2.1e3), false),
            unc("nv", "Pa s", 1875.0, Some(90.0), true),
            unc("arm1.k", "Pa", 2e4, Some(800.0), true),
            unc("arm1.tau", "s", 0.5, None, false),
            unc("eps_r", "1", 4.7, Some(0.1), true),
        ],
        status: Some("ill_posed".into()),
        provenance: json!({
            "traces": [{ "path": "trace.csv", "sha256": "00" }],
            "scene": { "path": "stack.toml", "sha256": "00" },
            "settings": { "free": ["C10", "C20", "nv", "arm1.k", "arm1.tau", "eps_r"] }
        }),
    }
}

pub fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Time, stretch, voltage and current of every sample of a default run of `s`.
pub(crate) fn trajectory(s: &Scene) -> Vec<[f64; 4]> {
    simulate(s, &RunOptions::default())
        .unwrap()
        .samples
        .iter()
        .map(|x| [x.time_s, x.stretch, x.voltage_v, x.current_a])
        .collect()
}

#[test]
fn an_identified_material_is_read_back_and_drives_a_scene_like_its_constants_inline() {
    let dir = tempfile::tempdir().unwrap();
    let m = material();
    let path = write(dir.path(), "id.json", &m.to_json().unwrap());
    let back = IdentifiedMaterial::read(&path).unwrap();
    assert_eq!(back.hyperelastic, m.hyperelastic);
    assert_eq!(back.eps_r, m.eps_r);
    assert_eq!(back.uncertainty, m.uncertainty);
    assert_eq!(back.provenance, m.provenance);
    assert_eq!(back.status, m.status);
    // the file holds τ = η/k: η comes back as k·(η/k), within one rounding each way
    let (v, w) = (back.viscous.unwrap(), m.viscous.unwrap());
    assert_eq!((v.nv_pa_s, v.arms[0].k_pa), (w.nv_pa_s, w.arms[0].k_pa));
    assert!((v.arms[0].eta_pa_s / w.arms[0].eta_pa_s - 1.0).abs() < 4.0 * f64::EPSILON);

    // the whole material from the file, the parts from the file, and the same
    // numbers inline: the same trajectory, bit for bit
    let s = |material: &str| Scene::parse(&scene_with(material), &dir.path().join("s.toml"));
    let whole = s("identified = \"id.json\"\n").unwrap();
    let parts = s("hyperelastic = { fit = \"id.json\" }\nviscous = { fit = \"id.json\" }\nrelative_permittivity = 4.7\n").unwrap();
    let inline = s(&format!(
        "hyperelastic = {{ model = \"yeoh\", parameters = {{ C10 = 69300, C20 = -888, C30 = 16.7 }} }}\nviscous = {{ nv = {}, arms = [ {{ k = {}, eta = {} }} ] }}\nrelative_permittivity = 4.7\n",
        v.nv_pa_s, v.arms[0].k_pa, v.arms[0].eta_pa_s
    ))
    .unwrap();
    assert_eq!(whole.material.params, inline.material.params);
    assert_eq!(whole.material.viscous, inline.material.viscous);
    assert_eq!(whole.material.eps_r, 4.7);
    assert!(whole.material.fit.is_some() && inline.material.fit.is_none());
    let t = trajectory(&whole);
    assert_eq!(t, trajectory(&parts));
    assert_eq!(t, trajectory(&inline));
    // the file's fitted range reaches the simulator's extrapolation warnings
    let o = simulate(&whole, &RunOptions::default()).unwrap();
    assert!(
        !o.warnings.iter().any(|w| w.contains("extrapolated")),
        "{:?}",
        o.warnings
    );
}

#[test]
fn a_part_the_file_lacks_and_keys_given_twice_are_refused_at_their_key() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = material();
    m.viscous = None;
    m.eps_r = None;
    m.uncertainty.retain(|u| u.name.starts_with('C'));
    write(dir.path(), "elastic.json", &m.to_json().unwrap());
    write(dir.path(), "id.json", &material().to_json().unwrap());
    let e = |material: &str| {
        Scene::parse(&scene_with(material), &dir.path().join("s.toml"))
            .err()
            .expect("refused")
            .to_string()
    };
    let got = e("hyperelastic = { preset = \"vhb4910-yeoh\" }\nviscous = { fit = \"elastic.json\" }\nrelative_permittivity = 4.7\n");
    assert!(
        got.contains("elastic.json: viscous: missing") && got.contains("hint:"),
        "{got}"
    );
    // an identified file without εr leaves it to the scene, which must give it
    let got = e("identified = \"elastic.json\"\n");
    assert!(
        got.contains("material.relative_permittivity: is missing"),
        "{got}"
    );
    let s = Scene::parse(
        &scene_with("identified = \"elastic.json\"\nrelative_permittivity = 3.2\n"),
        &dir.path().join("s.toml"),
    )
    .unwrap();
    assert_eq!((s.material.eps_r, s.material.viscous.arms.len()), (3.2, 0));
    for (material, key) in [
        (
            "identified = \"id.json\"\nhyperelastic = { preset = \"vhb4910-yeoh\" }\n",
            "material.hyperelastic: conflicts with material.identified",
        ),
        (
            "identified = \"id.json\"\nviscous = { preset = \"elastic\" }\n",
            "material.viscous: conflicts with material.identified",
        ),
        (
            "identified = \"id.json\"\nrelative_permittivity = 4.7\n",
            "material.relative_permittivity: conflicts with material.identified",
        ),
        (
            "hyperelastic = { fit = \"id.json\" }\nviscous = { fit = \"id.json\", nv = \"1 Pa s\" }\nrelative_permittivity = 4.7\n",
            "material.viscous.nv: conflicts with the nv of material.viscous.fit",
        ),
    ] {
        let got = e(material);
        // located at the key (line 13 onwards is the material block)
        assert!(got.contains("s.toml:1") && got.contains(key), "{got}");
    }
}

#[test]
fn an_identified_file_edited_inconsistently_is_refused_with_file_key_and_expectation() {
    let dir = tempfile::tempdir().unwrap();
    let good: Value = serde_json::from_str(&material().to_json().unwrap()).unwrap();
    type Edit = fn(&mut Value);
    let cases: [(Edit, &str, &str); 10] = [
        (
            |v| v["hyperelastic"]["parameters"][1]["name"] = json!("C02"),
            "hyperelastic.parameters[1].name: 'C02' is not a parameter of yeoh",
            "yeoh takes C10 [Pa], C20 [Pa], C30 [Pa]",
        ),
        (
            |v| v["hyperelastic"]["parameters"][0]["unit"] = json!("kPa"),
            "hyperelastic.parameters[0].unit: C10 is in 'Pa', found 'kPa'",
            "SI values",
        ),
        (
            |v| v["hyperelastic"]["parameters"][0]["value"] = json!(70e3),
            "hyperelastic.initial_shear_modulus_Pa: the file states 138600 Pa but its yeoh parameters give 140000 Pa",
            "edited",
        ),
        (
            |v| v.as_object_mut().unwrap().remove("hyperelastic").map(|_| ()).unwrap(),
            "hyperelastic: missing",
            "identify again",
        ),
        (
            |v| v["viscous"]["parameters"][2]["name"] = json!("arm1.t"),
            "viscous.parameters[2].name: 'arm1.t' is not a parameter of a viscous part with 1 arm",
            "nv [Pa s], arm1.k [Pa], arm1.tau [s]",
        ),
        (
            |v| v["viscous"]["parameters"][0]["unit"] = json!("Pa·s"),
            "viscous.parameters[0].unit: nv is in 'Pa s', found 'Pa·s'",
            "SI values",
        ),
        (
            |v| v["viscous"]["parameters"][2]["value"] = json!(-1.0),
            "viscous.parameters.arm1.tau: tau = -1 s is not a plausible relaxation time",
            "is the unit right?",
        ),
        (
            |v| v["dielectric"]["parameters"][0]["name"] = json!("epsr"),
            "dielectric.parameters[0].name: 'epsr' is not a parameter of the dielectric part",
            "did you mean 'eps_r'?",
        ),
        (
            |v| v["hyperelastic"]["parameters"][0]["std_error"] = json!(-3.0),
            "hyperelastic.parameters[0].std_error: -3 is not a standard error",
            "≥ 0",
        ),
        (
            |v| v["provenance"] = json!("by hand"),
            "provenance: missing or not a JSON object",
            "traces",
        ),
    ];
    for (edit, msg, hint) in cases {
        let mut v = good.clone();
        edit(&mut v);
        let p = write(dir.path(), "edited.json", &v.to_string());
        let got = IdentifiedMaterial::read(&p)
            .expect_err("refused")
            .to_string();
        assert!(
            got.contains(&format!("edited.json: {msg}")) && got.contains(hint),
            "{got}"
        );
    }
    // another schema is named, with the way to use it
    let fit = repo().join("tests/data/bad_cli/files/fitfile_yeoh.json");
    let got = IdentifiedMaterial::read(&fit).err().unwrap().to_string();
    assert!(
        got.contains("schema: expected \"dea-fit/identified/1\"")
            && got.contains("material.hyperelastic = { fit = ... }"),
        "{got}"
    );
}

#[test]
fn writing_refuses_an_uncertainty_that_is_not_a_parameter_of_the_material() {
    for (edit, want) in [
        (
            (|m: &mut IdentifiedMaterial| m.uncertainty[0].name = "C01".into())
                as fn(&mut IdentifiedMaterial),
            "'C01' [Pa]",
        ),
        (|m| m.uncertainty[3].unit = "kPa".into(), "'arm1.k' [kPa]"),
        (|m| m.uncertainty[5].value = 4.8, "'eps_r' [1] = 4.8"),
        (|m| m.viscous = None, "'nv' [Pa s]"),
        (|m| m.provenance = json!(null), "provenance"),
        // what the reader would refuse is never written
        (
            |m| {
                m.eps_r = Some(0.5);
                m.uncertainty[5].value = 0.5;
            },
            "eps_r = 0.5 is not a plausible relative permittivity",
        ),
    ] {
        let mut m = material();
        edit(&mut m);
        let got = m.to_json().expect_err("refused").to_string();
        assert!(got.contains(want), "{got}");
    }
}

#[test]
fn a_hyperelastic_fit_file_reads_as_the_material_part_the_fit_holds() {
    let mut n = 0;
    for e in std::fs::read_dir(repo().join("tests/golden")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "json") {
            continue;
        }
        let fit: HyperelasticFit =
            serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        let part = file::read_hyperelastic(&p).unwrap();
        assert_eq!(part, fit.material(), "{}", p.display());
        assert!(part.ranges.is_some());
        n += 1;
    }
    assert!(n >= 2, "the golden hyperelastic fits moved");
}

/// Every `use` path of the Rust files under `src/<dir>`.
fn uses(dir: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut stack = vec![repo().join("src").join(dir)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&p).unwrap();
                out.extend(
                    text.lines()
                        .filter(|l| l.contains("crate::"))
                        .map(|l| (p.display().to_string(), l.trim().to_string())),
                );
            }
        }
    }
    out
}

#[test]
fn material_files_sit_below_fit_and_sim() {
    for (f, l) in uses("material") {
        assert!(
            !l.contains("crate::fit") && !l.contains("crate::sim"),
            "{f}: {l}"
        );
    }
    for (f, l) in uses("sim") {
        assert!(!l.contains("crate::fit"), "{f}: {l}");
    }
}
