//! The readers under test: their seeds (shipped files), how a case is made from a
//! seed, and how a case is run — read, then for an accepted input the cheap numerics
//! downstream, whose outputs must be finite unless the status says the result is not
//! to be used.

use super::mutate::{self, Mutated};
use dea_fit::fit::{composite, hyperelastic, permittivity, relaxation, Status};
use dea_fit::io::breakdown as breakdown_io;
use dea_fit::io::lcr::{self, LcrOptions};
use dea_fit::io::relaxation::RelaxationOptions;
use dea_fit::io::tensile::{self, TensileOptions};
use dea_fit::io::{manifest, relaxation as relaxation_io};
use dea_fit::material::hyperelastic::{ModelSpec, OgdenForm};
use dea_fit::sim::{self, scene::Scene, RunOptions, RunStatus};
use dea_fit::units::{parse_uncertain, Dimension};
use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Reader {
    Tensile,
    Relaxation,
    Lcr,
    Manifest,
    Scene,
    /// A hyperelastic fit file as a scene's material.
    Fit,
    /// An actuator trace, as identification reads it: the trace on the worked
    /// example's stack (its measured voltage rebuilt as the input), simulated.
    Trace,
    /// An identified material file (`dea-fit/identified/1`) as a scene's whole
    /// material (`[material] identified = ...`), simulated.
    Identified,
    /// A rank design manifest with its scene and fit files beside it (the manifest
    /// or its composite fit mutated), every point evaluated and ranked.
    Design,
    /// One or two material files for `dea-fit export`, each code's card made.
    Export,
    /// Shard files of a rank sweep, altered, merged (`rank merge`; fuzz/merge.rs).
    Merge,
    /// A checkpoint of `dea-fit identify`, resumed (`super::checkpoint`).
    Checkpoint,
    /// A composite manifest's [synthetic] values, its exports generated
    /// (`composite --generate`, tests/fuzz/generate.rs).
    Generate,
    /// Numeric flag values of the real commands (tests/fuzz/flags.rs).
    Flags,
    /// A breakdown series (`io::breakdown`), fitted, its fit file written and read
    /// back by the core's reader.
    Breakdown,
    /// DMA isotherms (`dma::read`), shifted (free and WLF) onto a master curve.
    Dma,
    /// A project file (`dea-fit.toml`) with the lab project's files beside it (the
    /// project file mutated, or the scene or design manifest whose targets it
    /// follows), read with every step, scene and manifest it names by `dea-fit
    /// status` (which runs nothing).
    Project,
}

impl Reader {
    pub const ALL: [Reader; 17] = [
        Reader::Tensile,
        Reader::Relaxation,
        Reader::Lcr,
        Reader::Manifest,
        Reader::Scene,
        Reader::Fit,
        Reader::Trace,
        Reader::Identified,
        Reader::Design,
        Reader::Export,
        Reader::Merge,
        Reader::Checkpoint,
        Reader::Generate,
        Reader::Flags,
        Reader::Breakdown,
        Reader::Dma,
        Reader::Project,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Reader::Tensile => "tensile",
            Reader::Relaxation => "relaxation",
            Reader::Lcr => "lcr",
            Reader::Manifest => "manifest",
            Reader::Scene => "scene",
            Reader::Fit => "fit",
            Reader::Trace => "trace",
            Reader::Identified => "identified",
            Reader::Design => "design",
            Reader::Export => "export",
            Reader::Merge => "merge",
            Reader::Checkpoint => "checkpoint",
            Reader::Generate => "generate",
            Reader::Flags => "flags",
            Reader::Breakdown => "breakdown",
            Reader::Dma => "dma",
            Reader::Project => "project",
        }
    }

    pub fn parse(name: &str) -> Option<Reader> {
        Reader::ALL.into_iter().find(|r| r.name() == name.trim())
    }
}

/// One input: files written side by side into one directory; the first is the one
/// the reader opens.
pub struct Case {
    pub files: Vec<(String, Vec<u8>)>,
    pub what: String,
    pub kind: String,
    pub oracle: Oracle,
    /// The model a tensile case is fitted with.
    pub model: &'static str,
}

/// What a correct reader must do with a case besides not failing.
pub enum Oracle {
    /// Nothing more: refusing and accepting are both fine.
    Any,
    /// Refuse it, for this reason (a class of failures: no values).
    Refuse(String),
    /// If accepted, the scene's material parameters are these (a fit file read by
    /// name gives its values in model order, whatever order the file lists them in).
    Params(Vec<f64>),
    /// If accepted, the scene's material is this (an identified file read by name,
    /// every part).
    Material(Material),
    /// What `rank merge` must do with altered shard files.
    Merge(super::merge::Expect),
}

/// The material an identified file states, by name: the hyperelastic parameters in
/// model order, and the parts it holds (Nv and the arms' (k, τ), εr).
pub struct Material {
    params: Vec<f64>,
    viscous: Option<(f64, Vec<(f64, f64)>)>,
    eps_r: Option<f64>,
}

/// How a case ended.
pub enum Verdict {
    Refused,
    Accepted,
    /// Accepted with a result that breaks a promise; `class` groups failures.
    Failed {
        class: String,
        detail: String,
    },
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn file(rel: &str) -> (String, Vec<u8>) {
    let name = rel.rsplit('/').next().unwrap().to_string();
    let bytes = std::fs::read(repo(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
    (name, bytes)
}

fn dir(rel: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(repo(rel))
        .unwrap_or_else(|e| panic!("{rel}: {e}"))
        .map(|e| format!("{rel}/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    v.sort();
    v
}

/// The scene a fit file is the material of (a fast one: 10 ms).
const FIT_HOST: &str = "datasets/scenes/stack_step_5kV_damped.toml";

/// The worked example whose stack scene hosts the trace cases.
const TRACE_HOST_DIR: &str = "datasets/identify";

/// The host scene's material block, which a material file's case replaces.
const HOST_MATERIAL: &str = "hyperelastic = { preset = \"vhb4910-yeoh\" }\nviscous = { preset = \"elatrache2021-table-4.2\" }\nrelative_permittivity = 4.7\n";

/// [`FIT_HOST`] with its material block replaced by `material`.
fn host(material: &str) -> Vec<u8> {
    let text = String::from_utf8(file(FIT_HOST).1).unwrap();
    assert!(
        text.contains(HOST_MATERIAL),
        "{FIT_HOST}: the material block changed"
    );
    text.replace(HOST_MATERIAL, material).into_bytes()
}

/// The design example whose manifest, scene and fit files seed the design cases.
const DESIGN_DIR: &str = "datasets/design";

/// The material files of the export cases.
const EXPORT_DIR: &str = "tests/data/export";

/// The lab project (datasets/lab) without its outputs: `dea-fit.toml` first, then
/// every file by its path in the project.
fn lab_files() -> Vec<(String, Vec<u8>)> {
    fn walk(rel: &str, out: &mut Vec<(String, Vec<u8>)>) {
        for f in dir(format!("{LAB_DIR}/{rel}").trim_end_matches('/')) {
            let inside = f[LAB_DIR.len() + 1..].to_string();
            if ["fits", "reports", ".dea-fit"].contains(&inside.as_str()) {
                continue;
            }
            if repo(&f).is_dir() {
                walk(&format!("{inside}/"), out);
            } else {
                out.push((inside, std::fs::read(repo(&f)).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk("", &mut out);
    let k = out
        .iter()
        .position(|f| f.0 == "dea-fit.toml")
        .expect("the lab project file");
    let project = out.remove(k);
    out.insert(0, project);
    out
}

/// The lab project, whose project file seeds the project cases.
const LAB_DIR: &str = "datasets/lab";

/// The shipped files a reader's cases start from; each seed is the file set of a
/// case before mutation.
pub fn seeds(r: Reader) -> Vec<Vec<(String, Vec<u8>)>> {
    let paths: Vec<String> = match r {
        Reader::Merge => return super::merge::seeds(),
        Reader::Tensile => [
            "datasets/treloar",
            "datasets/vhb4910",
            "datasets/tensile_exports",
            "tests/data/ok",
        ]
        .iter()
        .flat_map(|d| dir(d))
        .filter(|p| !p.ends_with("relaxation.csv") && !p.ends_with(".md"))
        .collect(),
        Reader::Relaxation => vec!["datasets/vhb4910/relaxation.csv".into()],
        Reader::Dma => dir("datasets/dma")
            .into_iter()
            .filter(|p| p.ends_with(".csv"))
            .collect(),
        Reader::Breakdown => dir("datasets/breakdown")
            .into_iter()
            .filter(|p| p.ends_with(".csv"))
            .collect(),
        Reader::Checkpoint => return super::checkpoint::seeds(),
        Reader::Trace => ["step.csv", "sine.csv", "validate.csv"]
            .iter()
            .map(|f| format!("{TRACE_HOST_DIR}/{f}"))
            .collect(),
        Reader::Lcr => dir("datasets/composites/sylgard_batio3"),
        Reader::Manifest => vec![
            "datasets/composites/sylgard_batio3.toml".into(),
            "datasets/composites/elatrache2021_bjb_batio3_claims.toml".into(),
        ],
        Reader::Scene => dir("datasets/scenes"),
        Reader::Fit => dir("tests/golden")
            .into_iter()
            .filter(|p| p.ends_with(".json"))
            .collect(),
        Reader::Identified => dir("tests/data/identified")
            .into_iter()
            .filter(|p| p.ends_with(".json"))
            .chain(["tests/data/bad_cli/files/material_file_identified.json".into()])
            .collect(),
        Reader::Design => vec![format!("{DESIGN_DIR}/silicone_fillers.toml")],
        Reader::Export => dir(EXPORT_DIR)
            .into_iter()
            .filter(|p| p.ends_with(".json"))
            .chain(["tests/data/identified/stack-step-identified.json".into()])
            .collect(),
        Reader::Generate => vec![super::generate::SEED.into()],
        // a case is made whole, not mutated from a file
        Reader::Flags => return vec![Vec::new()],
        // the project file first, every file of the lab project beside it
        Reader::Project => return vec![lab_files()],
    };
    paths
        .iter()
        .map(|p| {
            let mut set = vec![file(p)];
            match r {
                Reader::Manifest if p.ends_with("sylgard_batio3.toml") => {
                    set.extend(dir("datasets/composites/sylgard_batio3").iter().map(|e| {
                        let (n, b) = file(e);
                        (format!("sylgard_batio3/{n}"), b)
                    }))
                }
                Reader::Fit => {
                    let material = HOST_MATERIAL
                        .replace("{ preset = \"vhb4910-yeoh\" }", "{ fit = \"fit.json\" }");
                    set = vec![
                        ("scene.toml".into(), host(&material)),
                        ("fit.json".into(), set[0].1.clone()),
                    ];
                }
                Reader::Design => {
                    set.push(file(&format!("{DESIGN_DIR}/stack_silicone.toml")));
                    set.extend(dir(&format!("{DESIGN_DIR}/fits")).iter().map(|e| {
                        let (n, b) = file(e);
                        (format!("fits/{n}"), b)
                    }))
                }
                Reader::Identified => {
                    set = vec![
                        (
                            "scene.toml".into(),
                            host("identified = \"identified.json\"\n"),
                        ),
                        ("identified.json".into(), set[0].1.clone()),
                    ];
                }
                _ => {}
            }
            set
        })
        .chain(match r {
            // a hyperelastic fit with the relaxation fit of each reading
            Reader::Export => ["vhb4910-relaxation.json", "vhb4910-relaxation-qlv.json"]
                .iter()
                .map(|f| {
                    vec![
                        file(&format!("{EXPORT_DIR}/vhb4910-yeoh.json")),
                        file(&format!("{EXPORT_DIR}/{f}")),
                    ]
                })
                .collect(),
            _ => Vec::new(),
        })
        .collect()
}

/// The values of a material file's parameter list by name, in the order of `want`
/// (name, unit): Err(why it must be refused) for a count that does not match, a
/// name missing or repeated, a unit that does not match; Ok(None) when a value is
/// not a number (the reader refuses it by type).
fn by_name(params: &[Value], want: &[(String, String)]) -> Result<Option<Vec<f64>>, String> {
    if params.len() != want.len() {
        return Err("parameter count does not match the model".into());
    }
    let mut values = Vec::new();
    for (name, unit) in want {
        let found: Vec<_> = params.iter().filter(|p| p["name"] == *name).collect();
        match found.as_slice() {
            [p] if p["unit"] == *unit => match p["value"].as_f64() {
                Some(x) => values.push(x),
                None => return Ok(None),
            },
            [_] => return Err("parameter unit does not match the model".into()),
            _ => return Err("parameter name missing or repeated".into()),
        }
    }
    Ok(Some(values))
}

/// The parameters a hyperelastic part (`{model, form, parameters}`) must read as, by
/// name in model order ([`by_name`]; an unknown model must be refused); Ok(None)
/// when it is not shaped like one.
fn hyperelastic_by_name(v: &Value) -> Result<Option<Vec<f64>>, String> {
    let (Some(model), Some(params)) = (v["model"].as_str(), v["parameters"].as_array()) else {
        return Ok(None);
    };
    let form = serde_json::from_value(v["form"].clone()).unwrap_or(OgdenForm::Abaqus);
    let Ok(m) = ModelSpec::new(model, form).build() else {
        return Err("unknown model".into());
    };
    let want: Vec<(String, String)> = m
        .params()
        .iter()
        .map(|p| (p.name.clone(), p.unit.to_string()))
        .collect();
    by_name(params, &want)
}

/// An oracle from a by-name reading.
fn oracle_of<T>(read: Result<Option<T>, String>, f: impl FnOnce(T) -> Oracle) -> Oracle {
    match read {
        Ok(Some(x)) => f(x),
        Ok(None) => Oracle::Any,
        Err(why) => Oracle::Refuse(why),
    }
}

/// What a fit file must read as: its parameters by name in model order, or the
/// reason it must be refused (unknown model, a name, unit or count that does not
/// match the model). `Any` when it is not shaped like a fit file at all.
fn fit_oracle(json: &[u8]) -> Oracle {
    let Ok(v) = serde_json::from_slice::<Value>(json) else {
        return Oracle::Any;
    };
    oracle_of(hyperelastic_by_name(&v), Oracle::Params)
}

/// What an identified material file must read as: every part by name (the
/// hyperelastic parameters in model order; `nv`, then each arm's `k` and `tau` for
/// arms 1…N, N from the count of `armJ.k` names; `eps_r`), or the reason it must be
/// refused: another schema, provenance that is not an object, no hyperelastic part,
/// a part whose names, units or count do not match, or an uncertainty that is not
/// one (a negative σ, a σ without `identifiable`, an `identifiable` that is not a
/// boolean).
fn identified_oracle(json: &[u8]) -> Oracle {
    let Ok(v) = serde_json::from_slice::<Value>(json) else {
        return Oracle::Any;
    };
    if v["schema"] != dea_fit::material::file::IDENTIFIED_SCHEMA {
        return Oracle::Refuse("schema is not dea-fit/identified/1".into());
    }
    if !v["provenance"].is_object() {
        return Oracle::Refuse("provenance is not a JSON object".into());
    }
    if !v["hyperelastic"].is_object() {
        return Oracle::Refuse("no hyperelastic part".into());
    }
    let lists = ["hyperelastic", "viscous", "dielectric"]
        .iter()
        .filter_map(|k| v[*k]["parameters"].as_array());
    for p in lists.flatten() {
        let (se, id) = (&p["std_error"], &p["identifiable"]);
        if !(id.is_null() || id.is_boolean()) {
            return Oracle::Refuse("identifiable is not a boolean".into());
        }
        if se.as_f64().is_some_and(|s| s < 0.0) {
            return Oracle::Refuse("a negative std_error".into());
        }
        if id.is_null() && se.is_number() {
            return Oracle::Refuse("a std_error without identifiable".into());
        }
    }
    let viscous = match &v["viscous"] {
        Value::Null => Ok(Some(None)),
        part => {
            let params = part["parameters"].as_array().cloned().unwrap_or_default();
            let arms = params
                .iter()
                .filter_map(|p| p["name"].as_str())
                .filter(|n| n.starts_with("arm") && n.ends_with(".k"))
                .count();
            let mut want = vec![("nv".to_string(), "Pa s".to_string())];
            for j in 1..=arms {
                want.push((format!("arm{j}.k"), "Pa".into()));
                want.push((format!("arm{j}.tau"), "s".into()));
            }
            by_name(&params, &want)
                .map(|v| v.map(|v| Some((v[0], v[1..].chunks(2).map(|a| (a[0], a[1])).collect()))))
        }
    };
    let eps_r = match &v["dielectric"] {
        Value::Null => Ok(Some(None)),
        part => {
            let params = part["parameters"].as_array().cloned().unwrap_or_default();
            by_name(&params, &[("eps_r".into(), "1".into())]).map(|v| v.map(|v| Some(v[0])))
        }
    };
    oracle_of(hyperelastic_by_name(&v["hyperelastic"]), |params| {
        oracle_of(viscous, |viscous| {
            oracle_of(eps_r, |eps_r| {
                Oracle::Material(Material {
                    params,
                    viscous,
                    eps_r,
                })
            })
        })
    })
}

impl Material {
    /// How `scene`'s material differs from this one, if it does (exactly: both
    /// sides parse the same decimal text, and the reader's η is k·τ).
    fn differs(&self, scene: &Scene) -> Option<String> {
        let m = &scene.material;
        if m.params != self.params {
            return Some(format!(
                "hyperelastic: read {:?}, the file says {:?}",
                m.params, self.params
            ));
        }
        if let Some((nv, arms)) = &self.viscous {
            let read: Vec<(f64, f64)> = m
                .viscous
                .arms
                .iter()
                .map(|a| (a.k_pa, a.eta_pa_s))
                .collect();
            let want: Vec<(f64, f64)> = arms.iter().map(|&(k, tau)| (k, k * tau)).collect();
            if m.viscous.nv_pa_s != *nv || read != want {
                return Some(format!(
                    "viscous: read nv {} and (k, η) {read:?}, the file says nv {nv} and {want:?}",
                    m.viscous.nv_pa_s
                ));
            }
        }
        match self.eps_r {
            Some(e) if e != m.eps_r => Some(format!("eps_r: read {}, the file says {e}", m.eps_r)),
            _ => None,
        }
    }
}

/// A case from a seed: text mutations for every reader, structure-aware ones for
/// scenes, fit files and identified files half of the time.
pub fn generate(r: Reader, seeds: &[Vec<(String, Vec<u8>)>], rng: &mut ChaCha8Rng) -> Case {
    if r == Reader::Merge {
        return super::merge::generate(seeds, rng);
    }
    let mut files = seeds.choose(rng).unwrap().clone();
    let whole = match r {
        Reader::Flags => Some(("args.txt".to_string(), super::flags::case(rng))),
        Reader::Generate => Some((
            files[0].0.clone(),
            super::generate::mutate(&String::from_utf8_lossy(&files[0].1), rng),
        )),
        _ => None,
    };
    if let Some((name, Mutated { bytes, what, kind })) = whole {
        return Case {
            what: format!("{name} ({what})"),
            files: vec![(name, bytes)],
            kind,
            oracle: Oracle::Any,
            model: "",
        };
    }
    // a material file's case mutates the file, beside the scene that reads it; an
    // export case one of its files; a design case its manifest or, a quarter of the
    // time, its composite fit
    let main = match r {
        Reader::Fit | Reader::Identified => 1,
        Reader::Export => rng.gen_range(0..files.len()),
        Reader::Design if rng.gen_bool(0.25) => files
            .iter()
            .position(|f| f.0.ends_with("composite.json"))
            .expect("the design's composite fit"),
        Reader::Project if rng.gen_bool(0.25) => {
            let f = *["scenes/stack.toml", "design.toml"].choose(rng).unwrap();
            files.iter().position(|x| x.0 == f).expect("a lab file")
        }
        _ => 0,
    };
    let name = files[main].0.clone();
    // what a mutated export file is: a hyperelastic fit, an identified material or
    // a relaxation fit
    let hyperelastic_fit = r == Reader::Export && !name.contains("relaxation");
    let identified = r == Reader::Identified || (hyperelastic_fit && name.contains("identified"));
    let toml =
        name.ends_with(".toml") && matches!(r, Reader::Scene | Reader::Design | Reader::Project);
    let structured =
        (toml || r == Reader::Fit || identified || hyperelastic_fit) && rng.gen_bool(0.5);
    let seed_text = String::from_utf8_lossy(&files[main].1).into_owned();
    let (m, refuse) = match () {
        _ if structured && toml => mutate::scene(&seed_text, rng),
        _ if structured && identified => (mutate::identified(&seed_text, rng), None),
        _ if structured => (mutate::fit(&seed_text, rng), None),
        _ => (mutate::text(&files[main].1, rng), None),
    };
    let Mutated { bytes, what, kind } = m;
    let oracle = match (r, refuse) {
        // a project's names are free (a misspelt material name is another name), and
        // status reads a scene or manifest only for the targets and files it names
        (Reader::Project, Some(_)) if main != 0 || kind == "key misspelt" => Oracle::Any,
        (_, Some(why)) => Oracle::Refuse(why),
        (Reader::Identified, None) => identified_oracle(&bytes),
        (Reader::Fit, None) => fit_oracle(&bytes),
        (Reader::Export, None) if hyperelastic_fit && !identified => fit_oracle(&bytes),
        _ => Oracle::Any,
    };
    files[main].1 = bytes;
    Case {
        what: format!("{} ({what})", files[main].0),
        files,
        kind,
        oracle,
        model: MODELS.choose(rng).unwrap(),
    }
}

/// The models tensile cases are fitted with (one per case, chosen with the case).
const MODELS: [&str; 5] = ["neo-hookean", "yeoh", "gent", "ogden1", "ogden2"];

/// The command that replays a case written to `dir` (writing only into `dir`).
pub fn replay(r: Reader, case: &Case, dir: &Path) -> String {
    let f = dir.join(&case.files[0].0);
    let f = f.display();
    let out = format!("--no-report --out {}", dir.join("out.json").display());
    match r {
        Reader::Tensile => format!(
            "dea-fit hyperelastic {f} --area 22mm2 --gauge-length 80mm --max-starts 2 --model {} {out}",
            case.model
        ),
        Reader::Relaxation => format!("dea-fit relaxation {f} --strain 0.5 --max-terms 3 {out}"),
        Reader::Breakdown => format!("dea-fit breakdown {f} {out}"),
        Reader::Dma => format!("dea-fit dma {f} --reference-temperature 25C --shift wlf {out}"),
        Reader::Lcr => format!("dea-fit permittivity {f} --diameter 42.8mm --thickness 2.2mm"),
        Reader::Manifest => format!("dea-fit composite {f}"),
        Reader::Scene | Reader::Fit | Reader::Identified => format!(
            "dea-fit simulate {f} --no-report --out {}",
            dir.join("trajectory.csv").display()
        ),
        Reader::Trace => format!(
            "dea-fit identify {f} --scene {} --free eps_r --starts 1 {out}",
            repo(&format!("{TRACE_HOST_DIR}/stack.toml")).display()
        ),
        Reader::Design => format!("dea-fit rank {f} --no-report"),
        Reader::Merge => super::merge::replay(case, dir),
        Reader::Checkpoint => super::checkpoint::replay(&case.files[0].0, dir),
        Reader::Generate => format!("dea-fit composite {f} --generate"),
        Reader::Flags => super::flags::replay(&case.files[0].1, dir),
        Reader::Project => format!("dea-fit status -C {}", dir.display()),
        Reader::Export => {
            let files: Vec<String> = case
                .files
                .iter()
                .map(|(n, _)| dir.join(n).display().to_string())
                .collect();
            format!(
                "dea-fit export {} --to abaqus --density 1000kg/m3 --out {}",
                files.join(" "),
                dir.join("card.inp").display()
            )
        }
    }
}

fn finite(what: &str, values: impl IntoIterator<Item = f64>) -> Result<(), String> {
    match values.into_iter().find(|v| !v.is_finite()) {
        Some(v) => Err(format!("{what} = {v}")),
        None => Ok(()),
    }
}

/// A usable status (not blocking) with non-finite outputs is a lie, and so is one on
/// a fit that explains less than the data's mean (R² < 0) or whose R² is undefined
/// (`None` where the estimator has one).
fn check_fit(
    reader: &str,
    status: Status,
    r2: Option<f64>,
    outputs: Result<(), String>,
) -> Verdict {
    if status.is_blocking() {
        return Verdict::Accepted;
    }
    let failure = match outputs {
        Err(e) => Some((
            format!("{reader}: status {status} with a non-finite output"),
            e,
        )),
        Ok(()) if r2.is_none_or(|r2| r2 < 0.0) => Some((
            format!("{reader}: status {status} with R² < 0 or undefined"),
            format!("R² = {r2:?}"),
        )),
        Ok(()) => None,
    };
    match failure {
        Some((class, detail)) => Verdict::Failed { class, detail },
        None => Verdict::Accepted,
    }
}

/// A DMA case: read, shifted free and with WLF at 25 °C. A usable status with a
/// non-finite shift, σ or master-curve point is a failure.
fn dma(path: &Path) -> Verdict {
    use dea_fit::dma::fit::{self, Settings, ShiftMode};
    let Ok(data) = dea_fit::dma::read::read_all(&[path], &Default::default()) else {
        return Verdict::Refused;
    };
    for mode in [
        ShiftMode::Free,
        ShiftMode::Law(dea_fit::dma::law::LawKind::Wlf),
    ] {
        let settings = Settings {
            mode,
            reference_k: Some(298.15),
            ..Settings::default()
        };
        let Ok(f) = fit::fit(&data, &settings) else {
            continue;
        };
        let out = finite(
            "shift factor",
            f.shift_factors
                .iter()
                .flat_map(|s| [s.log10_at, s.std_error]),
        )
        .and(finite(
            "master curve",
            f.master_curve
                .iter()
                .flat_map(|p| [p.reduced_omega_rad_s, p.storage_pa, p.loss_pa]),
        ));
        if let Err(detail) = out {
            return Verdict::Failed {
                class: format!("dma: status {} with a non-finite output", f.status),
                detail,
            };
        }
    }
    Verdict::Accepted
}

/// A breakdown case: read, fitted (maximum likelihood), its fit file's object made,
/// written and read back by `material::file::read_breakdown`. A usable status with
/// a non-finite parameter, percentile or log-likelihood, or a fit file the core
/// refuses, is a failure.
fn breakdown(path: &Path, dir: &Path) -> Verdict {
    use dea_fit::fit::weibull;
    let Ok(series) = breakdown_io::read(path, &breakdown_io::BreakdownOptions::default()) else {
        return Verdict::Refused;
    };
    let specimens: Vec<weibull::Specimen> = series
        .specimens
        .iter()
        .map(breakdown_io::BreakdownSpecimen::weibull)
        .collect();
    let Ok(f) = weibull::fit(&specimens, &weibull::Settings::default()) else {
        return Verdict::Refused;
    };
    if f.status.is_blocking() {
        return Verdict::Accepted;
    }
    let r = match dea_fit::report::breakdown::result(&f, &[series], None, Value::Null) {
        Ok(r) => r,
        Err(e) => {
            return Verdict::Failed {
                class: format!("breakdown: status {} without percentiles", f.status),
                detail: e.to_string(),
            }
        }
    };
    let out = finite("parameter", r.fit.parameters.iter().map(|p| p.value))
        .and(finite(
            "percentile",
            r.fit.percentiles.iter().map(|p| p.value),
        ))
        .and(finite("log_likelihood", [r.fit.log_likelihood]));
    if let Err(detail) = out {
        return Verdict::Failed {
            class: format!("breakdown: status {} with a non-finite output", f.status),
            detail,
        };
    }
    let file = dir.join("breakdown-fit.json");
    std::fs::write(&file, serde_json::to_string_pretty(&r).unwrap()).unwrap();
    match dea_fit::material::file::read_breakdown(&file) {
        Ok(_) => Verdict::Accepted,
        Err(e) => Verdict::Failed {
            class: format!(
                "breakdown: status {} with a fit file the core refuses",
                f.status
            ),
            detail: e.to_string(),
        },
    }
}

fn geometry() -> permittivity::Geometry {
    let q = |s, d| Some(parse_uncertain(s, d).unwrap());
    permittivity::Geometry::new(
        None,
        q("42.8mm", Dimension::Length),
        q("2.2mm", Dimension::Length),
    )
    .unwrap()
}

/// Write the case into `dir`, read it, and run what follows an accepted input.
pub fn run(r: Reader, case: &Case, dir: &Path) -> Verdict {
    for (name, bytes) in &case.files {
        let p = dir.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, bytes).unwrap();
    }
    let path = dir.join(&case.files[0].0);
    match r {
        Reader::Tensile => {
            let opts = TensileOptions {
                area: Some(22e-6),
                gauge_length: Some(0.08),
                mode: None,
            };
            let Ok(data) = tensile::read(&path, &opts) else {
                return Verdict::Refused;
            };
            // The sanity checks with every option that changes the points.
            let sanity = hyperelastic::Sanity {
                until_break: true,
                zero_offset: true,
                ..Default::default()
            };
            let Ok(data) = hyperelastic::prepare(&data, &sanity) else {
                return Verdict::Refused;
            };
            let settings = hyperelastic::Settings {
                max_starts: Some(2),
                ..Default::default()
            };
            let spec = ModelSpec::new(case.model, settings.ogden_form);
            let Ok(f) = hyperelastic::fit(&data, &spec, &settings) else {
                return Verdict::Refused;
            };
            let out = finite("parameter", f.values())
                .and(finite("rmse_Pa", [f.rmse_pa]))
                .and(finite(
                    "initial_shear_modulus_Pa",
                    [f.initial_shear_modulus_pa],
                ));
            check_fit(&format!("hyperelastic {}", f.model), f.status, f.r2, out)
        }
        Reader::Relaxation => {
            let Ok(data) = relaxation_io::read(&path, &RelaxationOptions::default()) else {
                return Verdict::Refused;
            };
            let loading = relaxation::Loading {
                strain: data.strain.is_none().then_some(0.5),
                ramp_time: None,
            };
            let settings = relaxation::Settings {
                max_terms: 3,
                ..Default::default()
            };
            let Ok(f) = relaxation::fit(&data, &loading, None, &settings) else {
                return Verdict::Refused;
            };
            let out = finite("parameter", f.parameters.iter().map(|p| p.value))
                .and(finite("rmse_Pa", [f.rmse_pa, f.rel_rmse]))
                .and(finite("E_inf", [f.long_term_modulus_pa]));
            check_fit("fit", f.status, Some(f.r2), out)
        }
        Reader::Lcr => {
            let Ok(sweep) = lcr::read(&path, &LcrOptions::default()) else {
                return Verdict::Refused;
            };
            let settings = permittivity::Settings::default();
            let Ok(s) = permittivity::analyse(&sweep, "fuzz", &geometry(), &settings, "fuzz")
            else {
                return Verdict::Refused;
            };
            let out = points_finite(&s);
            check_fit("permittivity", s.status, Some(0.0), out)
        }
        Reader::Breakdown => breakdown(&path, dir),
        Reader::Dma => dma(&path),
        Reader::Manifest => {
            let Ok(m) = manifest::read(&path) else {
                return Verdict::Refused;
            };
            let Ok(f) = composite::fit_series(&m, &|| {}) else {
                return Verdict::Refused;
            };
            let usable: Vec<_> = f
                .fits
                .iter()
                .flat_map(|x| &x.rules)
                .filter(|x| !x.status.is_blocking())
                .collect();
            let out = f.samples.iter().try_for_each(points_finite).and_then(|()| {
                usable.iter().try_for_each(|x| {
                    finite(
                        &format!("{} parameter", x.rule.name()),
                        x.parameters.iter().map(|p| p.value),
                    )
                    .and(finite("rms_rel_pct", [x.rms_rel_pct]))
                })
            });
            if !f.status.is_blocking() && !f.fits.is_empty() && usable.is_empty() {
                return Verdict::Failed {
                    class: format!("composite: status {} with no usable rule", f.status),
                    detail: format!("{} frequencies", f.fits.len()),
                };
            }
            check_fit("composite", f.status, Some(0.0), out)
        }
        Reader::Scene | Reader::Fit | Reader::Identified => simulate(&path, &case.oracle),
        Reader::Design => design(&path),
        Reader::Merge => super::merge::run(case, dir),
        Reader::Generate => super::generate::run(&path, dir),
        Reader::Flags => super::flags::run(&case.files[0].1, dir),
        Reader::Project => project(dir),
        Reader::Export => {
            let paths: Vec<PathBuf> = case.files.iter().map(|(n, _)| dir.join(n)).collect();
            export(&paths, &case.oracle)
        }
        Reader::Checkpoint => super::checkpoint::run(&path),
        Reader::Trace => {
            let base = Scene::read(&repo(&format!("{TRACE_HOST_DIR}/stack.toml"))).unwrap();
            let Ok(t) = dea_fit::io::trace::read(&path) else {
                return Verdict::Refused;
            };
            match dea_fit::identify::problem::Experiment::from_trace(&t, &base) {
                Ok(e) => check_run(&e.scene),
                Err(_) => Verdict::Refused,
            }
        }
    }
}

/// `dea-fit status -C dir` on a project case: exit 0 (every step listed) or a
/// refusal (exit 2 with an error); anything else (a panic, a hang) fails.
fn project(dir: &Path) -> Verdict {
    let args = ["status".to_string(), "-C".into(), dir.display().to_string()];
    match super::flags::child(&args, dir, "project") {
        Err(v) => v,
        Ok((s, stderr)) => match s.code() {
            Some(0) => Verdict::Accepted,
            Some(2) if stderr.contains("error") => Verdict::Refused,
            code => Verdict::Failed {
                class: format!("project: exit {code:?} (an abort, or a refusal without an error)"),
                detail: super::flags::first_error(&stderr),
            },
        },
    }
}

/// The most points of a design case's sweep evaluated ([`design`]).
const DESIGN_POINTS: usize = 500;

/// Read a design manifest, evaluate the points of its own sweep (at most
/// [`DESIGN_POINTS`], evenly spread) and rank them: no
/// figure of any state has a non-finite value, and a candidate ranked `ok` has its
/// static stroke.
fn design(path: &Path) -> Verdict {
    use dea_fit::rank::{figures::State, manifest, ranking, sweep};
    let Ok(d) = manifest::read(path) else {
        return Verdict::Refused;
    };
    let Ok(s) = sweep::Sweep::parse(&[]) else {
        panic!("an empty sweep parses")
    };
    let Ok(points) = sweep::Points::new(&d, &s) else {
        return Verdict::Refused;
    };
    // At most DESIGN_POINTS points, every n-th (a shard): a point's evaluation does
    // not depend on how many there are, and a mutated count (7 → 7000 loadings)
    // took 13 s on a loaded 2-core machine, past the wall bound.
    let shard = (points.len() > DESIGN_POINTS).then(|| sweep::Shard {
        k: 0,
        n: points.len().div_ceil(DESIGN_POINTS),
    });
    let Ok(evals) = sweep::run_all(&d, &points, shard, &|| {}) else {
        return Verdict::Refused;
    };
    for e in evals.iter().map(|x| &x.evaluation) {
        for (name, f) in e.clone().figures_mut() {
            if let Some(v) = f.value.filter(|v| !v.is_finite()) {
                return Verdict::Failed {
                    class: format!("rank: {name} with a non-finite value"),
                    detail: format!("{}: {name} = {v} (state {:?})", e.name, e.state),
                };
            }
        }
        if e.state == State::Ok && e.static_stroke.value.is_none() {
            return Verdict::Failed {
                class: "rank: state ok without a static stroke".into(),
                detail: e.name.clone(),
            };
        }
    }
    let list: Vec<_> = evals.iter().map(|x| x.evaluation.clone()).collect();
    use ranking::Objective;
    ranking::rank(
        &list,
        Objective::Stroke,
        [Objective::Stroke, Objective::Speed],
    );
    Verdict::Accepted
}

/// Read material files for export and make every code's card: a hyperelastic fit
/// is read by name (the [`fit_oracle`]), and a card holds finite constants only.
fn export(paths: &[PathBuf], oracle: &Oracle) -> Verdict {
    use dea_fit::export::{self, Options, Target};
    let Ok(m) = export::read(paths) else {
        return Verdict::Refused;
    };
    let read = m.hyperelastic.as_ref().map(|h| h.params.clone());
    match oracle {
        Oracle::Refuse(why) => {
            return Verdict::Failed {
                class: format!("export accepted: {why}"),
                detail: "the material files were read".into(),
            }
        }
        Oracle::Params(want) if read.as_ref() != Some(want) => {
            return Verdict::Failed {
                class: "export: fit file parameters not read by name".into(),
                detail: format!("read {read:?}, the file says {want:?}"),
            }
        }
        _ => {}
    }
    let opts = Options {
        density: Some(1000.0),
        ..Options::default()
    };
    for t in Target::ALL {
        let Ok(card) = export::card(&m, t, &opts) else {
            continue;
        };
        let values = card.constants.iter().map(|c| c.value);
        if let Err(detail) = finite(&format!("{} constant", t.name()), values) {
            return Verdict::Failed {
                class: format!("export: a {} card with a non-finite constant", t.name()),
                detail,
            };
        }
    }
    Verdict::Accepted
}

fn points_finite(s: &permittivity::SamplePermittivity) -> Result<(), String> {
    let p = &s.points;
    finite("eps_r", p.iter().map(|p| p.eps_r))
        .and(finite("eps_loss", p.iter().map(|p| p.eps_loss)))
        .and(finite("tan_delta", p.iter().map(|p| p.tan_delta)))
        .and(finite("conductivity", p.iter().map(|p| p.conductivity)))
}

/// Read a scene, hold it to the oracle and simulate it with its own settings: a
/// completed run has a finite trajectory.
fn simulate(path: &Path, oracle: &Oracle) -> Verdict {
    let Ok(scene) = Scene::read(path) else {
        return Verdict::Refused;
    };
    match oracle {
        Oracle::Refuse(why) => {
            return Verdict::Failed {
                class: format!("accepted: {why}"),
                detail: "the scene was read".into(),
            }
        }
        // Exact: both sides parse the same decimal text with serde_json.
        Oracle::Params(want) if *want != scene.material.params => {
            return Verdict::Failed {
                class: "fit file: parameters not read by name".into(),
                detail: format!("read {:?}, the file says {want:?}", scene.material.params),
            }
        }
        Oracle::Material(want) => {
            if let Some(detail) = want.differs(&scene) {
                return Verdict::Failed {
                    class: "identified file: material not read by name".into(),
                    detail,
                };
            }
        }
        _ => {}
    }
    check_run(&scene)
}

/// Simulate an accepted scene with its own settings: a completed run has a finite
/// trajectory.
fn check_run(scene: &Scene) -> Verdict {
    let Ok(o) = sim::simulate(scene, &RunOptions::default()) else {
        return Verdict::Refused;
    };
    if o.integrator.status != RunStatus::Completed {
        return Verdict::Accepted;
    }
    let s = &o.samples;
    let out = finite("stretch", s.iter().map(|s| s.stretch))
        .and(finite("length_m", s.iter().map(|s| s.length_m)))
        .and(finite("voltage_V", s.iter().map(|s| s.voltage_v)))
        .and(finite("capacitance_F", s.iter().map(|s| s.capacitance_f)))
        .and(finite("current_A", s.iter().map(|s| s.current_a)))
        .and(finite("rest_stretch", [o.rest_stretch, o.rest_length_m]))
        .and(finite("energy", [o.energy.input_j, o.energy.residual_j]));
    match out {
        Ok(()) => Verdict::Accepted,
        Err(detail) => Verdict::Failed {
            class: "simulate: completed with a non-finite output".into(),
            detail,
        },
    }
}
