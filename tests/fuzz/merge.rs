//! The `merge` surface (issue 32): `rank merge` (the library's `rank::shard::merge`)
//! of altered shard files. The seeds are the three shards of the shipped design's
//! own sweep (and one shard of another shard count), made with the library at the
//! start of every process; a case alters them:
//!
//! * a text mutation of one file (numbers, bytes, lines; [`super::mutate::text`]);
//! * one or two structural edits of one file's JSON: a number changed (by 1 ulp,
//!   1e-3, +1, negated, 0, −800, 1e300, ×1000, to an integer past u64), a key
//!   dropped, added or renamed, a string changed (units, names, notes, sources), a
//!   value nulled, the shard's K or N, the run's points, sweep or design hash, an
//!   evaluation dropped, repeated or moved to another index, the digest edited;
//!   half of these with the digest made again over the edit (as one who knows the
//!   format would), so that the merge's checks beyond the digest are reached;
//! * the set of files: a shard dropped, given twice, replaced by a shard of another
//!   run, the files given in another order or under each other's names;
//! * the file reformatted (whitespace, key order).
//!
//! What the merge must do ([`Expect`]): a reformatted file, another order or other
//! names are accepted and give the unaltered merge; a missing, repeated or foreign
//! shard or an edited digest is refused; any other alteration without a new digest
//! is refused unless it is semantically void, so an accepted merge equals the
//! unaltered one. With a new digest the merge cannot tell a simulated value (or a
//! state, a note, a source) from another one in its domain, so an accepted merge
//! must then hold, at every point, the unaltered candidate (names, loading, basis,
//! rules, catalogue figures but their σ, the candidate's warnings), the point's
//! drive voltage (or none in state `failed`), the unaltered units, a state
//! consistent with the static stroke, finite values, strokes in [0, 1) and
//! standard errors finite and ≥ 0.

use super::mutate;
use super::readers::{Case, Oracle, Verdict};
use dea_fit::rank::figures::{Evaluated, Evaluation, State};
use dea_fit::rank::shard::{self, RunInfo, ShardFile};
use dea_fit::rank::sweep::{self, Points, Shard, Sweep};
use dea_fit::rank::{manifest, Figure};
use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// What a correct merge does with a case.
pub enum Expect {
    /// Accept it, with the unaltered merge's evaluations.
    Equal,
    /// Refuse it, or accept it with the unaltered merge's evaluations.
    EqualIfAccepted,
    /// Refuse it (why).
    Refuse(String),
    /// Refuse it, or accept it with what the design gives at every point (a file
    /// whose digest was made again after the edit).
    Plausible,
}

/// The seed files: the three shards, then a shard of the same sweep in two.
const SHARDS: usize = 3;
const FOREIGN: &str = "other-run.json";

/// The shards of the shipped design's own sweep, and a foreign one.
pub fn seeds() -> Vec<Vec<(String, Vec<u8>)>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/design/silicone_fillers.toml");
    let d = manifest::read(&path).expect("the shipped design");
    let sw = Sweep::default();
    let pts = Points::new(&d, &sw).expect("its points");
    let info = RunInfo::new(&d, &sw, pts.len());
    let file = |s: Shard| {
        let ev = sweep::run_all(&d, &pts, Some(s), &|| {}).expect("the sweep runs");
        serde_json::to_vec(&ShardFile::new(info.clone(), &sw, s, ev)).unwrap()
    };
    let mut set: Vec<(String, Vec<u8>)> = (0..SHARDS)
        .map(|k| (format!("s{k}.json"), file(Shard { k, n: SHARDS })))
        .collect();
    set.push((FOREIGN.into(), file(Shard { k: 0, n: 2 })));
    vec![set]
}

/// The unaltered merge (once per process).
fn reference() -> &'static Vec<Evaluated> {
    static REF: OnceLock<Vec<Evaluated>> = OnceLock::new();
    REF.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let set = seeds().remove(0);
        let paths: Vec<PathBuf> = set[..SHARDS]
            .iter()
            .map(|(n, b)| {
                let p = dir.path().join(n);
                std::fs::write(&p, b).unwrap();
                p
            })
            .collect();
        shard::merge(&paths, None)
            .expect("the unaltered shards merge")
            .1
    })
}

/// A step of a path into a JSON value.
#[derive(Clone, Debug)]
enum Step {
    Key(String),
    At(usize),
}

/// Every path of `v` (its nodes, the root first).
fn paths(v: &Value, here: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    out.push(here.clone());
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                here.push(Step::Key(k.clone()));
                paths(x, here, out);
                here.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                here.push(Step::At(i));
                paths(x, here, out);
                here.pop();
            }
        }
        _ => {}
    }
}

fn at<'a>(v: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(v, |v, s| match s {
        Step::Key(k) => &mut v[k.as_str()],
        Step::At(i) => &mut v[*i],
    })
}

fn show(path: &[Step]) -> String {
    path.iter()
        .map(|s| match s {
            Step::Key(k) => format!(".{k}"),
            Step::At(i) => format!("[{i}]"),
        })
        .collect()
}

/// Names a renamed or added key takes: misspellings and keys of other places.
const KEYS: [&str; 8] = [
    "extra",
    "note",
    "std_error",
    "filler",
    "value",
    "unit",
    "Value",
    "sha256",
];

/// Strings a string is replaced by: units, names, notes.
const STRINGS: [&str; 9] = [
    "kPa",
    "V",
    "1",
    "",
    "BaTiO3",
    "Sylgard 184",
    "measured",
    "none",
    "ok",
];

/// One structural edit of `v` (never the digest when `resign`: that one is made
/// again): what was done and its kind.
fn edit(v: &mut Value, resign: bool, rng: &mut ChaCha8Rng) -> (String, String) {
    let mut all = Vec::new();
    paths(v, &mut Vec::new(), &mut all);
    let pick = |rng: &mut ChaCha8Rng, f: &dyn Fn(&Value) -> bool, v: &mut Value| {
        let c: Vec<&Vec<Step>> = all.iter().filter(|p| f(at(v, p))).collect();
        c.choose(rng).map(|p| (*p).clone())
    };
    let evals = v["evaluations"].as_array().map_or(0, Vec::len);
    let op = rng.gen_range(0..12);
    match op {
        0 | 1 => {
            let Some(p) = pick(rng, &|x| x.is_number(), v) else {
                return ("nothing to edit".into(), "none".into());
            };
            let x = at(v, &p);
            let old = x.clone();
            let f = old.as_f64().unwrap_or(0.0);
            let new = match rng.gen_range(0..9) {
                0 => Value::from(f64::from_bits(f.to_bits() + 1)),
                1 => Value::from(f * (1.0 + 1e-3)),
                2 => Value::from(f + 1.0),
                3 => Value::from(-f),
                4 => Value::from(0),
                5 => Value::from(-800.0),
                6 => Value::from(1e300),
                7 => Value::from(f * 1000.0),
                _ => Value::from(u64::MAX),
            };
            *x = new.clone();
            (format!("{}: {old} → {new}", show(&p)), "number".into())
        }
        2 => {
            let Some(p) = pick(rng, &|x| x.is_object(), v) else {
                return ("nothing to edit".into(), "none".into());
            };
            let m = at(v, &p).as_object_mut().unwrap();
            let keys: Vec<String> = m.keys().cloned().collect();
            let Some(k) = keys.choose(rng) else {
                return ("nothing".into(), "none".into());
            };
            m.remove(k);
            (
                format!("{}: key {k} dropped", show(&p)),
                "key dropped".into(),
            )
        }
        3 => {
            let Some(p) = pick(rng, &|x| x.is_object(), v) else {
                return ("nothing to edit".into(), "none".into());
            };
            let k = *KEYS.choose(rng).unwrap();
            let m = at(v, &p).as_object_mut().unwrap();
            let value = m.values().next().cloned().unwrap_or(Value::Null);
            m.insert(k.into(), value);
            (
                format!("{}: key {k} added or replaced", show(&p)),
                "key added".into(),
            )
        }
        4 => {
            let Some(p) = pick(rng, &|x| x.as_object().is_some_and(|m| !m.is_empty()), v) else {
                return ("nothing to edit".into(), "none".into());
            };
            let m = at(v, &p).as_object_mut().unwrap();
            let keys: Vec<String> = m.keys().cloned().collect();
            let k = keys.choose(rng).unwrap().clone();
            let new = match rng.gen_bool(0.5) {
                true => format!("{k}_"),
                false => KEYS.choose(rng).unwrap().to_string(),
            };
            let x = m.remove(&k).unwrap();
            m.insert(new.clone(), x);
            (
                format!("{}: key {k} renamed {new}", show(&p)),
                "key renamed".into(),
            )
        }
        5 | 6 => {
            let Some(p) = pick(rng, &|x| x.is_string(), v) else {
                return ("nothing to edit".into(), "none".into());
            };
            let x = at(v, &p);
            let old = x.as_str().unwrap().to_string();
            let new = match rng.gen_range(0..3) {
                0 => format!("{old} "),
                1 => old.to_uppercase(),
                _ => STRINGS.choose(rng).unwrap().to_string(),
            };
            *x = Value::from(new.clone());
            (format!("{}: '{old}' → '{new}'", show(&p)), "string".into())
        }
        7 => {
            let Some(p) = pick(rng, &|x| !x.is_object() && !x.is_array(), v) else {
                return ("nothing to edit".into(), "none".into());
            };
            *at(v, &p) = Value::Null;
            (format!("{}: nulled", show(&p)), "null".into())
        }
        8 => {
            let (k, what) = match rng.gen_range(0..5) {
                0 => ("k", Value::from(rng.gen_range(0..4))),
                1 => (
                    "n",
                    Value::from(*[0u64, 1, 2, 4, 1000, u64::MAX].choose(rng).unwrap()),
                ),
                2 => ("points", Value::from(rng.gen_range(0..60))),
                3 => ("sweep", Value::from("voltage=600V:900V:2")),
                _ => ("sha256", Value::from("0".repeat(64))),
            };
            let target = match k {
                "k" | "n" => &mut v["shard"][k],
                _ => &mut v["run"][k],
            };
            *target = what.clone();
            (format!("{k} → {what}"), format!("{k} changed"))
        }
        9 if evals > 0 => {
            let i = rng.gen_range(0..evals);
            let a = v["evaluations"].as_array_mut().unwrap();
            match rng.gen_range(0..3) {
                0 => {
                    a.remove(i);
                    (
                        format!("evaluation [{i}] dropped"),
                        "evaluation dropped".into(),
                    )
                }
                1 => {
                    let e = a[i].clone();
                    a.push(e);
                    (
                        format!("evaluation [{i}] repeated"),
                        "evaluation repeated".into(),
                    )
                }
                _ => {
                    let to = rng.gen_range(0..40);
                    a[i]["evaluation"]["index"] = Value::from(to);
                    (
                        format!("evaluation [{i}] moved to index {to}"),
                        "evaluation moved".into(),
                    )
                }
            }
        }
        10 if !resign => {
            let d = v["sha256"].as_str().unwrap_or("").to_string();
            let new = format!(
                "{}{}",
                if d.starts_with('0') { "1" } else { "0" },
                &d[1.min(d.len())..]
            );
            v["sha256"] = Value::from(new);
            ("digest edited".into(), "digest".into())
        }
        _ => {
            // a figure's value or σ in another place of its domain
            let Some(p) = pick(
                rng,
                &|x| x.get("unit").is_some() && x["value"].is_number(),
                v,
            ) else {
                return ("nothing to edit".into(), "none".into());
            };
            let x = at(v, &p);
            let f = x["value"].as_f64().unwrap();
            let key = *["value", "std_error"].choose(rng).unwrap();
            x[key] = Value::from(f * rng.gen_range(0.5..1.5));
            (
                format!("{}.{key} scaled", show(&p)),
                format!("figure {key}"),
            )
        }
    }
}

/// A case: the files given to the merge, in order, and what it must do.
pub fn generate(seeds: &[Vec<(String, Vec<u8>)>], rng: &mut ChaCha8Rng) -> Case {
    let set = &seeds[0];
    let mut files: Vec<(String, Vec<u8>)> = set[..SHARDS].to_vec();
    let foreign = set[SHARDS].clone();
    let i = rng.gen_range(0..SHARDS);
    let (what, kind, expect) = match rng.gen_range(0..20) {
        0..=3 => {
            let m = mutate::text(&files[i].1, rng);
            files[i].1 = m.bytes;
            (m.what, format!("text: {}", m.kind), Expect::EqualIfAccepted)
        }
        4..=12 => {
            let resign = rng.gen_bool(0.5);
            let mut v: Value = serde_json::from_slice(&files[i].1).unwrap();
            let digest = v["sha256"].clone();
            let mut done = vec![edit(&mut v, resign, rng)];
            if rng.gen_bool(0.25) {
                done.push(edit(&mut v, resign, rng));
            }
            let v_digest = v["sha256"].clone();
            let mut bytes = serde_json::to_vec(&v).unwrap();
            if resign {
                if let Ok(mut f) = serde_json::from_value::<ShardFile>(v) {
                    f.sha256 = f.digest();
                    bytes = serde_json::to_vec(&f).unwrap();
                }
            }
            files[i].1 = bytes;
            let (what, kind): (Vec<String>, Vec<String>) = done.into_iter().unzip();
            let signed = if resign { "re-signed " } else { "" };
            (
                what.join("; "),
                format!("{signed}{}", kind.join(", ")),
                // (two edits of the digest may give it back)
                match (
                    resign,
                    kind.iter().any(|k| k == "digest") && v_digest != digest,
                ) {
                    (_, true) => Expect::Refuse("an edited digest".into()),
                    (true, false) => Expect::Plausible,
                    (false, false) => Expect::EqualIfAccepted,
                },
            )
        }
        13 | 14 => {
            let v: Value = serde_json::from_slice(&files[i].1).unwrap();
            files[i].1 = serde_json::to_string_pretty(&v).unwrap().into_bytes();
            (
                "reformatted (whitespace, keys sorted)".into(),
                "reformatted".into(),
                Expect::Equal,
            )
        }
        15 => {
            files.remove(i);
            (
                format!("shard {i} dropped"),
                "shard dropped".into(),
                Expect::Refuse("a missing shard".into()),
            )
        }
        16 => {
            let copy = (format!("copy-of-s{i}.json"), files[i].1.clone());
            files.push(copy);
            (
                format!("shard {i} given twice"),
                "shard repeated".into(),
                Expect::Refuse("a repeated shard".into()),
            )
        }
        17 => {
            files[i] = foreign;
            (
                format!("shard {i} replaced by a shard of another run"),
                "foreign shard".into(),
                Expect::Refuse("a foreign shard".into()),
            )
        }
        18 => {
            files.shuffle(rng);
            (
                "the files in another order".into(),
                "order".into(),
                Expect::Equal,
            )
        }
        _ => {
            let j = (i + 1) % SHARDS;
            let (a, b) = (files[i].1.clone(), files[j].1.clone());
            files[i].1 = b;
            files[j].1 = a;
            (
                format!("shards {i} and {j} under each other's names"),
                "names swapped".into(),
                Expect::Equal,
            )
        }
    };
    Case {
        what,
        files,
        kind,
        oracle: Oracle::Merge(expect),
        model: "",
    }
}

/// The command that replays a case written to `dir`.
pub fn replay(case: &Case, dir: &Path) -> String {
    let files: Vec<String> = case
        .files
        .iter()
        .map(|(n, _)| dir.join(n).display().to_string())
        .collect();
    format!("dea-fit rank merge {} --no-report", files.join(" "))
}

/// A figure without its standard error.
fn bare(f: &Figure) -> Figure {
    f.clone().with_std_error(None)
}

/// Why `got` cannot be what the design gives where it gave `want`, or none.
fn implausible(got: &Evaluation, want: &Evaluation) -> Option<String> {
    let (mut g, mut w) = (got.clone(), want.clone());
    let same = g.index == w.index
        && g.name == w.name
        && g.series == w.series
        && g.matrix == w.matrix
        && g.filler == w.filler
        && g.loading.to_bits() == w.loading.to_bits()
        && g.basis == w.basis
        && g.volume_fraction.to_bits() == w.volume_fraction.to_bits()
        && g.rules == w.rules;
    if !same {
        return Some("another candidate or loading".into());
    }
    // The drive: the point's, or none in a run that failed before it.
    if !(g.voltage.value == w.voltage.value
        || (g.state == State::Failed && g.voltage.value.is_none()))
    {
        return Some(format!(
            "drive {:?} V in state {}",
            g.voltage.value, g.state
        ));
    }
    // The candidate's warnings, and at most one of the standard errors (a state that
    // a 1σ move changes: the merge cannot tell whether it is so).
    let spread = format!("{}: with ", w.name);
    let own = |ws: &[String]| -> Vec<String> {
        ws.iter()
            .filter(|s| !s.starts_with(&spread))
            .cloned()
            .collect()
    };
    if own(&g.warnings) != own(&w.warnings) || g.warnings.len() > own(&g.warnings).len() + 1 {
        return Some("other warnings".into());
    }
    let catalogue = [
        "eps_r",
        "youngs_modulus",
        "beta",
        "fm",
        "tan_delta",
        "breakdown_field",
    ];
    let wf = w.figures_mut().map(|(_, f)| f.clone());
    for ((name, f), want) in g.figures_mut().into_iter().zip(wf) {
        if catalogue.contains(&name) && bare(f) != bare(&want) {
            return Some(format!("{name}: another catalogue figure"));
        }
        if f.unit != want.unit {
            return Some(format!("{name}: unit {}", f.unit));
        }
        if let Some(v) = f.value {
            let stroke = name.ends_with("stroke");
            if !v.is_finite() || (stroke && !(-1e-9..1.0).contains(&v)) {
                return Some(format!("{name} = {v}"));
            }
        }
        if f.std_error.is_some_and(|s| !(s.is_finite() && s >= 0.0)) {
            return Some(format!("{name}: σ {:?}", f.std_error));
        }
    }
    match (g.state, g.static_stroke.value) {
        (State::Ok, None) | (State::PullIn | State::Breakdown, Some(_)) => Some(format!(
            "state {} with static stroke {:?}",
            g.state, g.static_stroke.value
        )),
        _ => None,
    }
}

/// Merge the case's files as given and hold the result to what the case expects.
pub fn run(case: &Case, dir: &Path) -> Verdict {
    let Oracle::Merge(expect) = &case.oracle else {
        panic!("a merge case has a merge oracle")
    };
    let paths: Vec<PathBuf> = case.files.iter().map(|(n, _)| dir.join(n)).collect();
    let fail = |class: &str, detail: String| Verdict::Failed {
        class: format!("merge: {class}"),
        detail,
    };
    let got = match shard::merge(&paths, None) {
        Err(e) => {
            return match expect {
                Expect::Equal => fail(
                    "a semantically void alteration refused",
                    format!("{}: {e}", case.what),
                ),
                _ => Verdict::Refused,
            }
        }
        Ok((_, got)) => got,
    };
    let want = reference();
    match expect {
        Expect::Refuse(why) => fail(&format!("{why} accepted"), case.what.clone()),
        Expect::Equal | Expect::EqualIfAccepted if &got != want => fail(
            "an altered shard accepted with another result",
            case.what.clone(),
        ),
        Expect::Plausible => {
            if got.len() != want.len() {
                return fail("another number of points accepted", case.what.clone());
            }
            match got
                .iter()
                .zip(want)
                .find_map(|(g, w)| implausible(&g.evaluation, &w.evaluation))
            {
                Some(why) => fail(
                    "a re-signed shard accepted with what the design cannot give",
                    format!("{}: {why}", case.what),
                ),
                None => Verdict::Accepted,
            }
        }
        _ => Verdict::Accepted,
    }
}
