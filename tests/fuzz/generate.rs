//! The `generate` surface: `composite --generate` on the shipped synthetic manifest
//! with one to three of its [synthetic] values replaced (extremes, scale and sign
//! errors, values near the edges of the physical, a wrong type), through the library
//! path the command takes (`io::manifest::parse`, `fit::composite::synthesize`). An
//! accepted table must generate exports whose every number is finite and which the
//! LCR reader takes back.

use super::mutate::Mutated;
use super::readers::Verdict;
use dea_fit::fit::composite;
use dea_fit::io::lcr::{self, LcrOptions};
use dea_fit::io::manifest;
use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::path::Path;

/// The seed: the shipped synthetic series' manifest.
pub const SEED: &str = "datasets/composites/sylgard_batio3.toml";

/// The keys of a [synthetic] table (`fit::composite::Synthetic`).
const KEYS: [&str; 14] = [
    "rule",
    "eps_matrix",
    "eps_matrix_per_decade",
    "eps_filler",
    "eps_filler_per_decade",
    "shape",
    "tan_delta_matrix",
    "tan_delta_filler",
    "noise_pct",
    "seed",
    "freq_min",
    "freq_max",
    "points_per_decade",
    "stray_pf",
];

/// A value for `key` replacing `old`: an extreme, a sign or scale error, a value
/// near the edge of what generates a physical series, or the wrong type.
fn value(key: &str, old: &toml::Value, rng: &mut ChaCha8Rng) -> toml::Value {
    use toml::Value::{Float, Integer, String as Str};
    let x = old
        .as_float()
        .or_else(|| old.as_integer().map(|i| i as f64))
        .unwrap_or(1.0);
    match rng.gen_range(0..12) {
        0 => Float(
            *[0.0, -1.0, 1e300, -1e300, 1e-300, 1e30, -0.3, 0.5]
                .choose(rng)
                .unwrap(),
        ),
        1 => Float(
            *[f64::INFINITY, f64::NEG_INFINITY, f64::NAN]
                .choose(rng)
                .unwrap(),
        ),
        2 => Integer(
            *[0, -1, 100_000_000, i64::MAX, 2_147_483_648, 10_001]
                .choose(rng)
                .unwrap(),
        ),
        3 => Float(-x),
        4 => Float(x * 1000.0),
        5 => Float(x / 1000.0),
        // within a decade of the shipped value, either sign
        6 | 7 => Float(x * rng.gen_range(-10.0..10.0)),
        8 if key == "rule" => Str([
            "maxwell-garnett",
            "bruggeman",
            "lichtenecker",
            "looyenga",
            "yamada",
            "jayasundere-smith",
            "nope",
        ]
        .choose(rng)
        .unwrap()
        .to_string()),
        8 => Float(1e8),
        9 => Integer(rng.gen_range(-5..20_000)),
        10 => Str("garbage".into()),
        _ => Float(x * (1.0 + rng.gen_range(-0.5..0.5))),
    }
}

/// One to three [synthetic] values replaced (a key absent from the table is added:
/// `shape` with the rule it does not belong to).
pub fn mutate(text: &str, rng: &mut ChaCha8Rng) -> Mutated {
    let mut doc: toml::Table = toml::from_str(text).expect("the seed manifest parses");
    let table = doc
        .get_mut("synthetic")
        .and_then(|t| t.as_table_mut())
        .expect("the seed has a [synthetic] table");
    let n = *[1, 1, 2, 3].choose(rng).unwrap();
    let (mut what, mut kind) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let key = *KEYS.choose(rng).unwrap();
        let old = table.get(key).cloned().unwrap_or(toml::Value::Float(3.0));
        let new = value(key, &old, rng);
        what.push(format!("{key}: {old} → {new}"));
        kind.push(format!("{key} → {}", new.type_str()));
        table.insert(key.to_string(), new);
    }
    Mutated {
        bytes: toml::to_string(&doc).expect("a TOML table").into_bytes(),
        what: what.join("; "),
        kind: kind.join(" + "),
    }
}

/// Every field of every line that is a number is finite (`inf`, `NaN` are not).
fn finite_text(name: &str, text: &str) -> Result<(), String> {
    for (i, line) in text.lines().enumerate() {
        for field in line.split([',', ';', '\t']) {
            let f = field.trim().trim_matches('"');
            if let Ok(v) = f.parse::<f64>() {
                if !v.is_finite() {
                    return Err(format!("{name}:{}: {f}", i + 1));
                }
            }
        }
    }
    Ok(())
}

/// Read the manifest as `composite --generate` does and generate its exports; an
/// accepted table's exports hold finite numbers only, and the reader takes each back.
pub fn run(path: &Path, dir: &Path) -> Verdict {
    let Ok(m) = manifest::read(path) else {
        return Verdict::Refused;
    };
    let Ok(files) = composite::synthesize(&m) else {
        return Verdict::Refused;
    };
    for (target, text) in &files {
        let name = target.file_name().unwrap().to_string_lossy().into_owned();
        if let Err(detail) = finite_text(&name, text) {
            return Verdict::Failed {
                class: "generate: a non-finite value in a generated export".into(),
                detail,
            };
        }
        let back = dir.join(format!("generated-{name}"));
        std::fs::write(&back, text).unwrap();
        if let Err(e) = lcr::read(&back, &LcrOptions::default()) {
            return Verdict::Failed {
                class: "generate: a generated export the LCR reader refuses".into(),
                detail: e.to_string(),
            };
        }
    }
    Verdict::Accepted
}
