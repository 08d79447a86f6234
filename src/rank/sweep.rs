//! The points of a ranking run and their evaluation in parallel.
//!
//! Points are enumerated in one fixed order — series (manifest order) × loading
//! (ascending) × drive level (ascending) — and numbered; each point's evaluation is
//! a pure function of the design and the point, so the results are the same bit for
//! bit whatever the number of threads (rayon), and a shard `K/N` (the points whose
//! index is K modulo N) evaluates exactly the points a single run gives those
//! indices. The number of points is checked against [`MAX_POINTS`] before any is
//! made ([`Points::new`]); points are then made one at a time from their index and
//! evaluated in parallel chunks ([`run_all`]), never all built at once.

use super::candidate;
use super::figures::{evaluate, step_scene, Evaluated};
use super::manifest::{Design, Level};
use super::short;
use crate::error::{Error, Result};
use crate::units::{parse_quantity, CountRange, Dimension};
use rayon::prelude::*;

/// Most points a run (or a merge of its shards) may hold. Every evaluation is kept
/// for the ranking, its table, JSON, CSV and report: measured, a 16 010-point run
/// peaks at 190 MB resident (≈ 10 KB a point: the evaluations and the ranking's
/// copy; a shard file holds ≈ 4.8 KB a point), so a run at the budget holds about
/// 1 GB and takes about 25 s of two cores (≈ 4 000 evaluations/s). A range's count
/// and the product of the sweep's dimensions (series × loadings × drive levels) are
/// checked against it before any point is made.
pub const MAX_POINTS: usize = 100_000;

/// Most shards of a sweep (`--shard K/N`): `rank merge` opens every one of them.
/// N is also at most the number of points (a shard without points is a slip).
pub const MAX_SHARDS: usize = 10_000;

/// Points evaluated per parallel chunk ([`run_all`]): enough to keep every thread
/// busy, few enough that only a chunk of points exists at a time.
const CHUNK: usize = 1024;

/// The count of one `--sweep` range: a whole number (never through a float).
const RANGE_POINTS: CountRange = CountRange::new(
    1,
    MAX_POINTS,
    "points of one range; the product of the sweep's dimensions is checked against the same budget",
);

/// The N of `--shard K/N` (and of the shards `rank merge` reads).
pub const SHARD_COUNT: CountRange = CountRange::new(
    1,
    MAX_SHARDS,
    "shards of one sweep: rank merge opens every one",
);

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
    let n = RANGE_POINTS
        .parse(n)
        .map_err(|why| format!("'{text}': count {why}"))?;
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

/// The points of a design under a sweep, in the run's order, made from their index
/// on demand: their number is checked first (against [`MAX_POINTS`], without
/// overflow), and no list of them is ever built.
#[derive(Clone)]
pub struct Points<'a> {
    design: &'a Design,
    sweep: &'a Sweep,
    /// The drive levels (the sweep's voltages, or the manifest's drive).
    levels: Vec<Level>,
    /// Index of each series' first point (ascending).
    firsts: Vec<usize>,
    len: usize,
}

impl<'a> Points<'a> {
    /// The points of `d` under `sweep`, refused when there are more than
    /// [`MAX_POINTS`] (the sweep's dimensions in the message).
    pub fn new(d: &'a Design, sweep: &'a Sweep) -> Result<Points<'a>> {
        let levels: Vec<Level> = match &sweep.voltages {
            Some(v) => v.iter().map(|&x| Level::Voltage(x)).collect(),
            None => vec![d.drive.level],
        };
        let mut firsts = Vec::with_capacity(d.series.len());
        let mut len: Option<usize> = Some(0);
        for si in 0..d.series.len() {
            let here = len.unwrap_or(usize::MAX);
            firsts.push(here);
            let n = loadings_of(d, sweep, si).len().checked_mul(levels.len());
            len = len.zip(n).and_then(|(a, b)| a.checked_add(b));
        }
        match len {
            Some(n) if n <= MAX_POINTS => Ok(Points {
                design: d,
                sweep,
                levels,
                firsts,
                len: n,
            }),
            _ => {
                let loadings = sweep.loadings.as_ref().map_or(0, Vec::len);
                let total = len.map_or("more than 2^64".to_string(), |n| n.to_string());
                Err(Error::settings(format!(
                    "the sweep has {total} points ({} series; {} drive level(s){}): a run holds at most {MAX_POINTS}",
                    d.series.len(),
                    levels.len(),
                    match loadings {
                        0 => String::new(),
                        n => format!("; {n} loadings per filled series"),
                    }
                ))
                .with_hint(format!(
                    "every evaluation is kept for the ranking (about 10 KB each): sweep fewer points, e.g. a coarse sweep first and then a finer one around its best loading (dea-fit rank ... --sweep loading=A:B:N --sweep voltage=A:B:N with a product of counts of {MAX_POINTS} or less)"
                )))
            }
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Point `i` (none past the end).
    pub fn get(&self, i: usize) -> Option<Point> {
        if i >= self.len {
            return None;
        }
        let series = self.firsts.partition_point(|&f| f <= i) - 1;
        let j = i - self.firsts[series];
        let nl = self.levels.len();
        Some(Point {
            index: i,
            series,
            loading: loadings_of(self.design, self.sweep, series)[j / nl],
            level: self.levels[j % nl],
        })
    }

    /// The points in the run's order (of shard `s` only, when given).
    pub fn iter(&self, s: Option<Shard>) -> impl Iterator<Item = Point> + '_ {
        let (first, step) = s.map_or((0, 1), |s| (s.k, s.n));
        (first..self.len).step_by(step).filter_map(|i| self.get(i))
    }

    /// Number of points of shard `s` (all points when none).
    pub fn count(&self, s: Option<Shard>) -> usize {
        match s {
            None => self.len,
            Some(s) => self.len.saturating_sub(s.k).div_ceil(s.n),
        }
    }
}

/// The loadings of series `si` under `sweep`: the sweep's for a filled series,
/// else its own.
fn loadings_of<'a>(d: &'a Design, sweep: &'a Sweep, si: usize) -> &'a [f64] {
    let s = &d.series[si];
    match (&sweep.loadings, s.filler) {
        (Some(l), Some(_)) => l,
        _ => &s.loadings,
    }
}

/// A slice of a sweep: shard `k` of `n` holds the points with index ≡ k (mod n).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
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
        let n = SHARD_COUNT.parse(n).map_err(|why| {
            Error::settings(format!("--shard {s}: {why}")).with_hint(format!(
                "at most {MAX_SHARDS} shards, and at most one per point of the sweep"
            ))
        })?;
        let k: usize = k.trim().parse().map_err(|_| bad())?;
        match k < n {
            true => Ok(Shard { k, n }),
            false => Err(bad()),
        }
    }

    /// This shard checked against a sweep of `points` points: N is at most the
    /// number of points (each shard then holds one or more).
    pub fn check(self, points: usize) -> Result<Shard> {
        match self.n <= points {
            true => Ok(self),
            false => Err(Error::settings(format!(
                "{} shards of a {points}-point sweep: at most one shard per point",
                self.n
            ))
            .with_hint(format!("use {points} shards or fewer"))),
        }
    }

    /// Whether point `i` belongs to this shard.
    pub fn holds(&self, i: usize) -> bool {
        i % self.n == self.k
    }
}

/// Evaluate `points` of the design in parallel; `on_done` is called after each.
/// The result is in the order of `points`. A candidate with properties that reach
/// the simulator with standard errors is evaluated twice more per such property,
/// moved by ±1σ, for the figures' standard errors by central differences
/// ([`super::figures::Evaluation::spread`]).
pub fn run(d: &Design, points: &[Point], on_done: &(dyn Fn() + Sync)) -> Result<Vec<Evaluated>> {
    let template = step_scene(d);
    let scene_name = d.scene_path.display().to_string();
    points
        .par_iter()
        .map(|pt| {
            let c = candidate::build(d, pt.series, pt.loading)?;
            let eval = |c: &candidate::Candidate| {
                evaluate(&template, &scene_name, c, pt.level, pt.index).evaluation
            };
            let mut e = evaluate(&template, &scene_name, &c, pt.level, pt.index);
            let shifted = c
                .shifts()
                .into_iter()
                .map(|s| (s.what, eval(&s.up), s.down.as_ref().map(eval)))
                .collect();
            e.evaluation.spread(shifted);
            on_done();
            Ok(e)
        })
        .collect()
}

/// Evaluate the points of `pts` (of shard `s` only, when given) in the run's
/// order: made from their indices a chunk at a time and each chunk evaluated in
/// parallel ([`run`]), so only the evaluations are kept. The result is the same
/// bit for bit as [`run`] on every point at once.
pub fn run_all(
    d: &Design,
    pts: &Points,
    s: Option<Shard>,
    on_done: &(dyn Fn() + Sync),
) -> Result<Vec<Evaluated>> {
    let mut out = Vec::with_capacity(pts.count(s));
    let mut it = pts.iter(s).peekable();
    while it.peek().is_some() {
        let chunk: Vec<Point> = it.by_ref().take(CHUNK).collect();
        out.extend(run(d, &chunk, on_done)?);
    }
    Ok(out)
}
