//! Mutations: of any text (numbers, bytes, lines), of a scene's TOML structure, and
//! of the JSON structure of a fit file and an identified material file. Each returns a description for the reproducer and a
//! short kind (what it did, without the values) that names hangs and aborts.

use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A mutated file and what was done to it.
pub struct Mutated {
    pub bytes: Vec<u8>,
    /// What was done, with the values (for the reproducer).
    pub what: String,
    /// What was done, without the values (for grouping).
    pub kind: String,
}

/// Values a number is replaced by: zero, signs, the ends of f64, non-finite, a scale
/// error and integers past i32 and u64.
const EXTREMES: [&str; 11] = [
    "0",
    "-1",
    "1e300",
    "1e-300",
    "inf",
    "nan",
    "1e30",
    "2147483648",
    "99999999999999999999",
    "-x",
    "x*1000",
];

fn extreme(rng: &mut ChaCha8Rng, x: &str) -> String {
    match *EXTREMES.choose(rng).unwrap() {
        "-x" => x.strip_prefix('-').map_or(format!("-{x}"), str::to_string),
        "x*1000" => x
            .parse::<f64>()
            .map_or("1000".into(), |v| format!("{}", v * 1000.0)),
        v => v.to_string(),
    }
}

/// Byte ranges of the numbers in `b`: digits not glued to a name before them (`C10`,
/// `s00_cpd`), with a sign, a fraction and an exponent.
fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let glued = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if !b[i].is_ascii_digit() || glued {
            i += 1;
            continue;
        }
        let start = if i > 0 && (b[i - 1] == b'-' || b[i - 1] == b'+') {
            i - 1
        } else {
            i
        };
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        if i + 1 < b.len() && (b[i] == b'e' || b[i] == b'E') {
            let j = i + 1 + usize::from(b[i + 1] == b'-' || b[i + 1] == b'+');
            if j < b.len() && b[j].is_ascii_digit() {
                i = j;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
        }
        out.push((start, i));
    }
    out
}

/// Line ranges (each with its terminator).
fn lines(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            out.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < b.len() {
        out.push((start, b.len()));
    }
    out
}

fn line_of(b: &[u8], at: usize) -> usize {
    b[..at.min(b.len())].iter().filter(|&&c| c == b'\n').count() + 1
}

/// One text mutation of `b` in place; returns (what, kind).
fn text_once(b: &mut Vec<u8>, rng: &mut ChaCha8Rng) -> (String, String) {
    let nums = numbers(b);
    let ls = lines(b);
    match rng.gen_range(0..10) {
        0..=4 if !nums.is_empty() => {
            let (s, e) = *nums.choose(rng).unwrap();
            let old = String::from_utf8_lossy(&b[s..e]).into_owned();
            let new = extreme(rng, &old);
            let what = format!("line {}: number {old} → {new}", line_of(b, s));
            b.splice(s..e, new.bytes());
            let kind = match EXTREMES.iter().find(|x| **x == new) {
                Some(x) => format!("number → {x}"),
                None => "number → scaled".into(),
            };
            (what, kind)
        }
        5 if !b.is_empty() => {
            let at = rng.gen_range(0..b.len());
            b[at] ^= 1 << rng.gen_range(0..8);
            (
                format!("line {}: bit flipped", line_of(b, at)),
                "bit flip".into(),
            )
        }
        6 => {
            let at = rng.gen_range(0..=b.len());
            let c = *[
                b',', b'\n', b'"', b'#', b'=', b'[', b'e', b'-', b'.', 0xff, b' ', b'\t',
            ]
            .choose(rng)
            .unwrap();
            b.insert(at, c);
            (
                format!("line {}: byte {c:#04x} inserted", line_of(b, at)),
                "byte inserted".into(),
            )
        }
        7 if !b.is_empty() => {
            let at = rng.gen_range(0..b.len());
            let n = rng.gen_range(1..=4).min(b.len() - at);
            b.drain(at..at + n);
            (
                format!("line {}: {n} byte(s) deleted", line_of(b, at)),
                "bytes deleted".into(),
            )
        }
        8 if !ls.is_empty() => {
            let (s, e) = *ls.choose(rng).unwrap();
            let what = format!("line {}", line_of(b, s));
            if rng.gen_bool(0.5) {
                let copy = b[s..e].to_vec();
                b.splice(s..s, copy);
                (format!("{what} duplicated"), "line duplicated".into())
            } else {
                b.drain(s..e);
                (format!("{what} deleted"), "line deleted".into())
            }
        }
        _ if ls.len() >= 2 => {
            let i = rng.gen_range(0..ls.len() - 1);
            let (a, b2) = (ls[i], ls[i + 1]);
            let mut swapped = b[b2.0..b2.1].to_vec();
            swapped.extend_from_slice(&b[a.0..a.1]);
            b.splice(a.0..b2.1, swapped);
            (
                format!("lines {} and {} swapped", i + 1, i + 2),
                "lines swapped".into(),
            )
        }
        _ => ("nothing".into(), "none".into()),
    }
}

/// One to three text mutations (numbers, bytes, lines) of `b`.
pub fn text(b: &[u8], rng: &mut ChaCha8Rng) -> Mutated {
    let mut bytes = b.to_vec();
    let n = *[1, 1, 1, 2, 3].choose(rng).unwrap();
    let (mut what, mut kind) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let (w, k) = text_once(&mut bytes, rng);
        what.push(w);
        kind.push(k);
    }
    Mutated {
        bytes,
        what: what.join("; "),
        kind: kind.join(" + "),
    }
}

/// A path to a value in a TOML document.
type Path = Vec<PathStep>;

#[derive(Clone)]
enum PathStep {
    Key(String),
    Index(usize),
}

fn show(path: &[PathStep]) -> String {
    let mut s = String::new();
    for p in path {
        match p {
            PathStep::Key(k) if s.is_empty() => s.push_str(k),
            PathStep::Key(k) => s.push_str(&format!(".{k}")),
            PathStep::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    if s.is_empty() {
        s.push_str("top level");
    }
    s
}

/// Paths of every table (`tables`) and every key (`keys`) below `v`.
fn walk(v: &toml::Value, at: &mut Path, tables: &mut Vec<Path>, keys: &mut Vec<Path>) {
    match v {
        toml::Value::Table(t) => {
            tables.push(at.clone());
            for (k, x) in t {
                at.push(PathStep::Key(k.clone()));
                keys.push(at.clone());
                walk(x, at, tables, keys);
                at.pop();
            }
        }
        toml::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                at.push(PathStep::Index(i));
                walk(x, at, tables, keys);
                at.pop();
            }
        }
        _ => {}
    }
}

fn get_mut<'a>(v: &'a mut toml::Value, path: &[PathStep]) -> &'a mut toml::Value {
    path.iter().fold(v, |v, p| match p {
        PathStep::Key(k) => &mut v[k.as_str()],
        PathStep::Index(i) => &mut v[*i],
    })
}

/// A misspelling of `k`: a letter doubled, dropped, swapped or capitalised.
fn typo(k: &str, rng: &mut ChaCha8Rng) -> String {
    let mut c: Vec<char> = k.chars().collect();
    let i = rng.gen_range(0..c.len());
    match rng.gen_range(0..4) {
        0 => c.insert(i, c[i]),
        1 if c.len() > 1 => {
            c.remove(i);
        }
        2 if c.len() > 1 => {
            let j = i.min(c.len() - 2);
            c.swap(j, j + 1)
        }
        _ => c[i] = c[i].to_ascii_uppercase(),
    }
    c.into_iter().collect()
}

const UNITS: [&str; 17] = [
    "um", "mm", "m", "kV", "V", "s", "ms", "Hz", "kg", "N", "%", "kPa", "kg/m3", "g/cm3", "",
    "furlong", "V/um",
];
const KINDS: [&str; 9] = [
    "stack", "helix", "step", "ramp", "triangle", "sine", "csv", "pid", "free",
];
const PRESETS: [&str; 3] = [
    "vhb4910-yeoh",
    "elatrache2021-table-3.3",
    "elatrache2021-table-4.2",
];
/// Keys no table of a scene knows, some of them plausible.
const UNKNOWN_KEYS: [&str; 5] = ["colour", "presett", "damping", "spann", "fit_file"];

/// A structure-aware mutation of a scene: a value or its unit changed, a key
/// removed, an unknown or misspelt key added, a kind swapped. The string is the reason
/// the scene must be refused (without values, it names a class of failures), if the
/// mutation makes it invalid whatever the numbers.
/// One of `keys` removed from `doc`: what, the kind of mutation, no refusal due.
fn remove_key(
    doc: &mut toml::Value,
    keys: &[Path],
    rng: &mut ChaCha8Rng,
) -> (String, String, Option<String>) {
    let p = keys.choose(rng).unwrap().clone();
    let (last, parent) = p.split_last().unwrap();
    if let (PathStep::Key(k), toml::Value::Table(t)) = (last, get_mut(doc, parent)) {
        t.remove(k);
    }
    (format!("{} removed", show(&p)), "key removed".into(), None)
}

pub fn scene(text: &str, rng: &mut ChaCha8Rng) -> (Mutated, Option<String>) {
    let mut doc: toml::Value = text.parse::<toml::Table>().expect("a shipped scene").into();
    let (mut tables, mut keys) = (Vec::new(), Vec::new());
    walk(&doc, &mut Vec::new(), &mut tables, &mut keys);
    let leaves: Vec<Path> = keys
        .iter()
        .filter(|p| {
            let v = get_mut(&mut doc, p);
            !v.is_table() && !v.is_array()
        })
        .cloned()
        .collect();
    // a `kind` or preset to swap (a project file has none: a key is removed instead)
    let swappable = leaves
        .iter()
        .any(|p| matches!(p.last(), Some(PathStep::Key(k)) if k == "kind" || k == "preset"));
    let (what, kind, refuse) = match rng.gen_range(0..6) {
        5 if !swappable => remove_key(&mut doc, &keys, rng),
        0 | 1 => {
            let p = leaves.choose(rng).unwrap();
            let v = get_mut(&mut doc, p);
            let old = v.to_string();
            *v = match v.clone() {
                toml::Value::String(s) => {
                    let n = numbers(s.as_bytes());
                    match n.first() {
                        Some(&(a, e)) if rng.gen_bool(0.6) => {
                            let x = extreme(rng, &s[a..e]);
                            toml::Value::String(format!("{}{x}{}", &s[..a], &s[e..]))
                        }
                        Some(&(_, e)) => toml::Value::String(format!(
                            "{} {}",
                            &s[..e],
                            UNITS.choose(rng).unwrap()
                        )),
                        None => toml::Value::String(KINDS.choose(rng).unwrap().to_string()),
                    }
                }
                toml::Value::Integer(_) => toml::Value::Integer(
                    *[0, -1, 2_147_483_648, i64::MAX, 1_000_000_000]
                        .choose(rng)
                        .unwrap(),
                ),
                _ => toml::Value::Float(
                    *[0.0, -1.0, 1e300, 1e-300, f64::INFINITY, f64::NAN, 1e30]
                        .choose(rng)
                        .unwrap(),
                ),
            };
            let what = format!("{} = {old} → {v}", show(p));
            (what, "value changed".to_string(), None)
        }
        2 => remove_key(&mut doc, &keys, rng),
        3 => {
            let p = tables.choose(rng).unwrap();
            let k = UNKNOWN_KEYS.choose(rng).unwrap();
            get_mut(&mut doc, p)
                .as_table_mut()
                .unwrap()
                .insert(k.to_string(), toml::Value::String("1".into()));
            (
                format!("unknown key {k} added to {}", show(p)),
                "unknown key added".into(),
                Some(format!("unknown key in [{}]", show(p))),
            )
        }
        4 => {
            let p = keys.choose(rng).unwrap().clone();
            let (last, parent) = p.split_last().unwrap();
            let PathStep::Key(k) = last else {
                unreachable!("keys end in a key")
            };
            let t = get_mut(&mut doc, parent).as_table_mut().unwrap();
            let new = typo(k, rng);
            let refuse =
                (!t.contains_key(&new)).then(|| format!("misspelt key in [{}]", show(parent)));
            if refuse.is_some() {
                let v = t.remove(k).unwrap();
                t.insert(new.clone(), v);
            }
            (
                format!("{} renamed {new}", show(&p)),
                "key misspelt".into(),
                refuse,
            )
        }
        _ => {
            let kinds: Vec<&Path> = leaves
                .iter()
                .filter(
                    |p| matches!(p.last(), Some(PathStep::Key(k)) if k == "kind" || k == "preset"),
                )
                .collect();
            let p = kinds.choose(rng).unwrap();
            let v = get_mut(&mut doc, p);
            let old = v.to_string();
            let pool: &[&str] = if old.contains("seed") || old.contains("vhb") {
                &PRESETS
            } else {
                &KINDS
            };
            *v = toml::Value::String(pool.choose(rng).unwrap().to_string());
            (
                format!("{} = {old} → {v}", show(p)),
                "kind swapped".into(),
                None,
            )
        }
    };
    let bytes = toml::to_string(&doc)
        .expect("a TOML table prints")
        .into_bytes();
    (Mutated { bytes, what, kind }, refuse)
}

/// Parameter names of other models, and misspellings, for renamed parameters.
const PARAM_NAMES: [&str; 7] = ["mu", "C01", "C11", "alpha1", "Jm", "c10", "mu1"];

/// Mutation `op` (0–5) of parameter `i` of a material file's parameter list
/// (`[{name, unit, value, …}]`): the list reversed, the parameter removed, renamed
/// (to one of `names`), duplicated, given another unit (of `units`) or an extreme
/// value. Returns what was done and its kind.
fn parameter_list(
    params: &mut Vec<serde_json::Value>,
    op: usize,
    i: usize,
    names: &[&str],
    units: &[&str],
    rng: &mut ChaCha8Rng,
) -> (String, &'static str) {
    use serde_json::{json, Value};
    match op {
        0 => {
            params.reverse();
            ("parameters reversed".to_string(), "parameters reordered")
        }
        1 => {
            let p = params.remove(i);
            (
                format!("parameter {} removed", p["name"]),
                "parameter removed",
            )
        }
        2 => {
            let new = *names.choose(rng).unwrap();
            let what = format!("parameter {} renamed {new}", params[i]["name"]);
            params[i]["name"] = json!(new);
            (what, "parameter renamed")
        }
        3 => {
            let p = params[i].clone();
            params.push(p);
            (
                format!("parameter {} duplicated", params[i]["name"]),
                "parameter duplicated",
            )
        }
        4 => {
            let unit = *units.choose(rng).unwrap();
            let what = format!("parameter {} unit → {unit}", params[i]["name"]);
            params[i]["unit"] = json!(unit);
            (what, "unit changed")
        }
        _ => {
            let x = params[i]["value"].as_f64().unwrap_or(1.0);
            let new = [
                json!(0.0),
                json!(-x),
                json!(1e300),
                json!(1e-300),
                json!(x * 1e3),
                Value::Null,
            ]
            .choose(rng)
            .unwrap()
            .clone();
            let what = format!("parameter {} value → {new}", params[i]["name"]);
            params[i]["value"] = new;
            (what, "value changed")
        }
    }
}

/// A structure-aware mutation of a hyperelastic fit file: parameters reordered,
/// removed, renamed, duplicated or given another unit or an extreme value; the model
/// renamed; a count changed.
pub fn fit(text: &str, rng: &mut ChaCha8Rng) -> Mutated {
    use serde_json::{json, Value};
    let mut v: Value = serde_json::from_str(text).expect("a shipped fit file");
    let params = v["parameters"].as_array_mut().expect("parameters");
    let n = params.len();
    let i = rng.gen_range(0..n);
    let (what, kind) = match rng.gen_range(0..8) {
        op @ 0..=5 => parameter_list(
            params,
            op,
            i,
            &PARAM_NAMES,
            &["kPa", "1", "m", "MPa", ""],
            rng,
        ),
        6 => {
            let m = *dea_fit::material::hyperelastic::MODEL_NAMES
                .choose(rng)
                .unwrap();
            let what = format!("model {} → {m}", v["model"]);
            v["model"] = json!(m);
            (what, "model renamed")
        }
        _ => {
            let key = *["points", "aicc", "rmse_Pa", "initial_shear_modulus_Pa"]
                .choose(rng)
                .unwrap();
            let new = [json!(0), json!(-1), json!(1e300), Value::Null]
                .choose(rng)
                .unwrap()
                .clone();
            let what = format!("{key} → {new}");
            v[key] = new;
            (what, "field changed")
        }
    };
    let bytes = serde_json::to_vec_pretty(&v).expect("JSON prints");
    Mutated {
        bytes,
        what,
        kind: kind.into(),
    }
}

/// Names a parameter of an identified file is renamed to: of every part, of other
/// models, of arms that do not follow on, and misspelt.
const IDENTIFIED_NAMES: [&str; 14] = [
    "C10", "C30", "C01", "mu", "alpha1", "nv", "eps_r", "arm1.k", "arm1.tau", "arm2.k", "arm5.k",
    "arm0.tau", "arm1.K", "Nv",
];

/// A structure-aware mutation of an identified material file (schema
/// `dea-fit/identified/1`): a parameter list of one part (hyperelastic, viscous,
/// dielectric) mutated as a fit file's; a parameter's uncertainty made inconsistent
/// (a negative or absurd σ, `identifiable` dropped, null or not a boolean); a part
/// removed; the fitted stretch range inverted, extreme or of an unknown mode; the
/// model renamed; the schema or the provenance replaced.
pub fn identified(text: &str, rng: &mut ChaCha8Rng) -> Mutated {
    use serde_json::{json, Value};
    let mut v: Value = serde_json::from_str(text).expect("a shipped identified file");
    let parts: Vec<&str> = ["hyperelastic", "viscous", "dielectric"]
        .into_iter()
        .filter(|p| v[*p].is_object())
        .collect();
    let part = *parts.choose(rng).unwrap();
    let (what, kind) = match rng.gen_range(0..10) {
        op @ 0..=5 => {
            let params = v[part]["parameters"].as_array_mut().expect("parameters");
            let i = rng.gen_range(0..params.len());
            let units = ["Pa", "kPa", "s", "ms", "Pa s", "1", ""];
            let (what, kind) = parameter_list(params, op, i, &IDENTIFIED_NAMES, &units, rng);
            (format!("{part}: {what}"), kind)
        }
        6 => {
            let params = v[part]["parameters"].as_array_mut().expect("parameters");
            let i = rng.gen_range(0..params.len());
            let p = &mut params[i];
            let name = p["name"].clone();
            let (key, new) = match rng.gen_range(0..5) {
                0 => ("std_error", json!(-1.0)),
                1 => ("std_error", json!(1e300)),
                2 => ("identifiable", Value::Null),
                3 => ("identifiable", json!("yes")),
                _ => ("identifiable", json!(p["identifiable"] != json!(true))),
            };
            let what = format!("{part}: parameter {name} {key} → {new}");
            p[key] = new;
            (what, "uncertainty changed")
        }
        7 => {
            v.as_object_mut().unwrap().remove(part);
            (format!("part {part} removed"), "part removed")
        }
        8 => {
            let ranges = v["hyperelastic"]["per_mode"]
                .as_array_mut()
                .expect("per_mode");
            let k = rng.gen_range(0..ranges.len());
            let r = &mut ranges[k];
            let what = match rng.gen_range(0..3) {
                0 => {
                    let (lo, hi) = (r["stretch_min"].clone(), r["stretch_max"].clone());
                    r["stretch_min"] = hi;
                    r["stretch_max"] = lo;
                    "stretch range inverted".to_string()
                }
                1 => {
                    let new = [json!(0.0), json!(-1.0), json!(1e300), Value::Null]
                        .choose(rng)
                        .unwrap()
                        .clone();
                    let what = format!("stretch_max → {new}");
                    r["stretch_max"] = new;
                    what
                }
                _ => {
                    r["mode"] = json!("biaxial");
                    "mode → biaxial".to_string()
                }
            };
            (what, "stretch range changed")
        }
        _ => match rng.gen_range(0..3) {
            0 => {
                let m = *dea_fit::material::hyperelastic::MODEL_NAMES
                    .choose(rng)
                    .unwrap();
                let what = format!("model {} → {m}", v["hyperelastic"]["model"]);
                v["hyperelastic"]["model"] = json!(m);
                (what, "model renamed")
            }
            1 => {
                let new = *[
                    "dea-fit/hyperelastic-fit/1",
                    "dea-fit/relaxation-fit/1",
                    "dea-fit/identified/2",
                ]
                .choose(rng)
                .unwrap();
                v["schema"] = json!(new);
                (format!("schema → {new}"), "schema changed")
            }
            _ => {
                let new = [Value::Null, json!([]), json!("scene.toml")]
                    .choose(rng)
                    .unwrap()
                    .clone();
                let what = format!("provenance → {new}");
                v["provenance"] = new;
                (what, "provenance changed")
            }
        },
    };
    let bytes = serde_json::to_vec_pretty(&v).expect("JSON prints");
    Mutated {
        bytes,
        what,
        kind: kind.into(),
    }
}
