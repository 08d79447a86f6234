//! The points of a ranking run and their evaluation in parallel.
//!
//! Points are enumerated in one fixed order — series (manifest order) × loading
//! (ascending) × drive level (ascending) — and numbered; each point's evaluation is
//! a pure function of the design and the point, so the results are the same bit for
//! bit whatever the number of threads (rayon), and a shard `K/N` (the points whose
//! index is K modulo N) evaluates exactly the points a single run gives those
//! indices.

use super::candidate;
use super::figures::{evaluate, step_scene, Evaluated};
use super::manifest::{Design, Level};
use super::short;
use crate::error::{Error, Result};
use crate::units::{parse_quantity, Dimension};
use rayon::prelude::*;

/// Most points a range may hold (a sweep beyond it is a slip of the count).
pub const MAX_RANGE_POINTS: usize = 1_000_000;

/// `start:stop:count` → `count` evenly spaced values (ends included, each rounded
/// to 12 significant digits); each end a quantity of `dim` (a bare number is SI;
/// `1kV`, `40 %`).
pub fn range(text: &str, dim: Dimension) -> std::result::Result<Vec<f64>, String> {
    let parts: Vec<&str> = text.split(':').collect();
    let [a, b, n] = parts[..] else {
        return Err(format!(
            "'{text}' is not start:stop:count (e.g. 0:0.4:41 or 1kV:8kV:15)"
        ));
    };
    let q = |s: &str| parse_quantity(s, dim);
    let (a, b) = (q(a)?, q(b)?);
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("count '{}' in '{text}' is not a whole number", n.trim()))?;
    if n == 0 || n > MAX_RANGE_POINTS {
        return Err(format!(
            "count {n} in '{text}': expected 1 … {MAX_RANGE_POINTS}"
        ));
    }
    if n == 1 && a != b {
        return Err(format!(
            "'{text}': one point needs start = stop (or a count of 2 or more)"
        ));
    }
    // Rounded to 12 significant digits: 0:0.6:7 gives 0.2, not 0.19999999999999998.
    let round = |v: f64| format!("{v:.11e}").parse::<f64>().unwrap_or(v);
    Ok((0..n)
        .map(|i| match n {
            1 => a,
            _ => round(a + (b - a) * i as f64 / (n - 1) as f64),
        })
        .collect())
}

/// The sweep a run asks for on top of the manifest: loadings (on each series'
/// basis) and drive voltages replacing the manifest's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Sweep {
    /// Loadings for every series with a filler.
    pub loadings: Option<Vec<f64>>,
    /// Drive voltages (V).
    pub voltages: Option<Vec<f64>>,
    /// The flags as given, in a canonical order (for shard keys and reports).
    pub text: Vec<String>,
}

impl Sweep {
    /// Parse `--sweep key=start:stop:count` flags (`loading`, `voltage`).
    pub fn parse(flags: &[String]) -> Result<Sweep> {
        let mut s = Sweep::default();
        for f in flags {
            let bad = |why: String| {
                Error::settings(format!("--sweep {f}: {why}"))
                    .with_hint("--sweep loading=0:0.4:41 or --sweep voltage=1kV:8kV:15")
            };
            let (key, r) = f
                .split_once('=')
                .ok_or_else(|| bad("expected key=start:stop:count".into()))?;
            match key.trim() {
                "loading" => {
                    let v = range(r, Dimension::Fraction).map_err(bad)?;
                    if let Some(x) = v.iter().find(|x| !(0.0..1.0).contains(*x)) {
                        return Err(bad(format!(
                            "loading {} is not a fraction in [0, 1)",
                            short(*x)
                        )));
                    }
                    if s.loadings.replace(v).is_some() {
                        return Err(bad("loading is swept twice".into()));
                    }
                }
                "voltage" => {
                    let v = range(r, Dimension::Voltage).map_err(bad)?;
                    if let Some(x) = v
                        .iter()
                        .find(|x| !(**x >= 0.0 && **x <= crate::sim::budget::VOLTAGE.max))
                    {
                        return Err(bad(format!("{} V is not a drive voltage", short(*x))));
                    }
                    if s.voltages.replace(v).is_some() {
                        return Err(bad("voltage is swept twice".into()));
                    }
                }
                other => {
                    return Err(
                        bad(format!("unknown key '{other}'")).with_hint("sweep loading or voltage")
                    )
                }
            }
            s.text.push(format!("{}={}", key.trim(), r.trim()));
        }
        s.text.sort();
        Ok(s)
    }

    /// The sweep in words ("manifest" when nothing is swept).
    pub fn describe(&self) -> String {
        match self.text.is_empty() {
            true => "manifest".into(),
            false => self.text.join(" "),
        }
    }
}

/// One point: a series at a loading and a drive level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// Place in the run's order.
    pub index: usize,
    /// Series index.
    pub series: usize,
    /// Loading on the series' basis.
    pub loading: f64,
    /// Drive.
    pub level: Level,
}

/// Every point of a design under a sweep, in the run's order.
pub fn points(d: &Design, sweep: &Sweep) -> Vec<Point> {
    let levels: Vec<Level> = match &sweep.voltages {
        Some(v) => v.iter().map(|&x| Level::Voltage(x)).collect(),
        None => vec![d.drive.level],
    };
    let mut out = Vec::new();
    for (si, s) in d.series.iter().enumerate() {
        let loadings = match (&sweep.loadings, s.filler) {
            (Some(l), Some(_)) => l.clone(),
            _ => s.loadings.clone(),
        };
        for &loading in &loadings {
            for &level in &levels {
                out.push(Point {
                    index: out.len(),
                    series: si,
                    loading,
                    level,
                });
            }
        }
    }
    out
}

/// A slice of a sweep: shard `k` of `n` holds the points with index ≡ k (mod n).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// This shard (0-based).
    pub k: usize,
    /// Number of shards.
    pub n: usize,
}

impl Shard {
    /// Parse `K/N` (0 ≤ K < N).
    pub fn parse(s: &str) -> Result<Shard> {
        let bad = || {
            Error::settings(format!("--shard {s}: expected K/N with 0 ≤ K < N"))
                .with_hint("e.g. --shard 3/16 (shards are numbered 0 … N−1, as Slurm array tasks)")
        };
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (k, n): (usize, usize) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        match k < n {
            true => Ok(Shard { k, n }),
            false => Err(bad()),
        }
    }

    /// Whether point `i` belongs to this shard.
    pub fn holds(&self, i: usize) -> bool {
        i % self.n == self.k
    }
}

/// Evaluate `points` of the design in parallel; `on_done` is called after each.
/// The result is in the order of `points`. A candidate with properties that have
/// standard errors is evaluated once more per such property, moved up by its σ,
/// for the figures' standard errors ([`super::figures::Evaluation::spread`]).
pub fn run(d: &Design, points: &[Point], on_done: &(dyn Fn() + Sync)) -> Result<Vec<Evaluated>> {
    let template = step_scene(d);
    let scene_name = d.scene_path.display().to_string();
    points
        .par_iter()
        .map(|pt| {
            let c = candidate::build(d, pt.series, pt.loading)?;
            let mut e = evaluate(&template, &scene_name, &c, pt.level, pt.index);
            let shifted = c
                .one_sigma()
                .into_iter()
                .map(|(what, c)| {
                    let s = evaluate(&template, &scene_name, &c, pt.level, pt.index);
                    (what, s.evaluation)
                })
                .collect();
            e.evaluation.spread(shifted);
            on_done();
            Ok(e)
        })
        .collect()
}
