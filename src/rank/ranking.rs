//! Ranking of evaluated candidates: the order by one objective, the Pareto front
//! over two, the best loading of every series, and the run's status.
//!
//! A candidate is ranked on an objective only where the objective has a value: one
//! past pull-in or breakdown at the drive has no static stroke, no response and no
//! energy figures, and is listed after the ranked ones with the reason — never
//! ranked on the numbers of a state it cannot reach. Equal values keep the run's
//! order.
//!
//! Ties: the ranking is cut into groups of candidates that cannot be told apart.
//! A group starts at the best candidate not yet in one; the next ones join it while
//! they cannot be told apart from that first ([`told_apart`]: by [`APART`]
//! standard errors of the difference, or where either has none by the tie
//! tolerance, [`TOLERANCE`] by default, `--tie-tolerance`). Each member is compared
//! with the group's first, not with its neighbour: in a dense sweep neighbours
//! differ by less than any tolerance, and a chain of neighbour comparisons would
//! call a whole slow drift one tie; anchored at its first, a group spans at most
//! the tolerance, so the groups themselves are a ranking.

use super::figures::{Evaluation, State, SMALL_MARGIN};
use super::Figure;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// What to rank by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// Static stroke at the drive (larger is better).
    Stroke,
    /// Largest stroke before pull-in or breakdown.
    MaxStroke,
    /// Blocked force at the drive.
    Force,
    /// 10–90 % response time of a step (smaller is better).
    Speed,
    /// Figure of merit 3ε0εrEb²/Y.
    Fm,
    /// εr/Y.
    Beta,
    /// Dielectric loss per cycle (smaller is better).
    Loss,
}

impl Objective {
    /// Every objective.
    pub const ALL: [Objective; 7] = [
        Objective::Stroke,
        Objective::MaxStroke,
        Objective::Force,
        Objective::Speed,
        Objective::Fm,
        Objective::Beta,
        Objective::Loss,
    ];

    /// Name as written on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Objective::Stroke => "stroke",
            Objective::MaxStroke => "max-stroke",
            Objective::Force => "force",
            Objective::Speed => "speed",
            Objective::Fm => "fm",
            Objective::Beta => "beta",
            Objective::Loss => "loss",
        }
    }

    /// Parse a name.
    pub fn parse(s: &str) -> Result<Objective> {
        Self::ALL
            .into_iter()
            .find(|o| o.name() == s.trim())
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|o| o.name()).collect();
                Error::settings(format!("unknown objective '{s}'"))
                    .with_hint(format!("use one of {}", names.join(", ")))
            })
    }

    /// The figure it reads, with its unit, for tables and axes.
    pub fn label(self) -> &'static str {
        match self {
            Objective::Stroke => "static stroke at the drive",
            Objective::MaxStroke => "largest stroke before pull-in or breakdown",
            Objective::Force => "blocked force (N)",
            Objective::Speed => "10–90 % response time (s)",
            Objective::Fm => "figure of merit Fm",
            Objective::Beta => "εr/Y (1/Pa)",
            Objective::Loss => "dielectric loss per cycle (J)",
        }
    }

    /// Whether a larger value is better.
    pub fn higher_is_better(self) -> bool {
        !matches!(self, Objective::Speed | Objective::Loss)
    }

    /// The figure of an evaluation this objective ranks on.
    fn figure(self, e: &Evaluation) -> &Figure {
        match self {
            Objective::Stroke => &e.static_stroke,
            Objective::MaxStroke => &e.max_stroke,
            Objective::Force => &e.blocked_force,
            Objective::Speed => &e.response_time,
            Objective::Fm => &e.fm,
            Objective::Beta => &e.beta,
            Objective::Loss => &e.loss_per_cycle,
        }
    }

    /// The candidate's properties the objective depends on, named, with their
    /// figures: εr and Y always; Eb for all but β (Fm holds it, and it sets the
    /// states and limits the simulated figures have); tan δ for the loss.
    pub fn inputs(self, e: &Evaluation) -> Vec<(&'static str, &Figure)> {
        let mut v = vec![("εr", &e.eps_r), ("Y", &e.youngs_modulus)];
        if self != Objective::Beta {
            v.push(("Eb", &e.breakdown_field));
        }
        if self == Objective::Loss {
            v.push(("tan δ", &e.tan_delta));
        }
        v
    }

    /// The value of the objective for an evaluation (None: not ranked on it).
    pub fn value(self, e: &Evaluation) -> Option<f64> {
        self.figure(e).value.filter(|v| v.is_finite())
    }

    /// The standard error of the objective for an evaluation, where known.
    pub fn std_error(self, e: &Evaluation) -> Option<f64> {
        self.figure(e).std_error.filter(|s| s.is_finite())
    }

    /// Why an evaluation has no value of the objective.
    pub fn why_not(self, e: &Evaluation) -> String {
        self.figure(e)
            .note
            .clone()
            .unwrap_or_else(|| e.state_note.clone())
    }

    /// A value oriented so that larger is better.
    fn goodness(self, v: f64) -> f64 {
        match self.higher_is_better() {
            true => v,
            false => -v,
        }
    }
}

/// The status of a ranking run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Every candidate evaluated; every property from data or a stated model.
    Ok,
    /// Some properties were held or extrapolated, or candidates are driven close
    /// to breakdown or pull-in (the warnings say which).
    Warning,
    /// Some candidates could not be evaluated (they are listed, not ranked):
    /// blocking under `--strict`.
    Incomplete,
    /// No candidate could be ranked.
    Failed,
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Status::Ok => "ok",
            Status::Warning => "warning",
            Status::Incomplete => "incomplete",
            Status::Failed => "failed",
        })
    }
}

impl Status {
    /// Exit code: 1 for `failed`, and for `incomplete` under `--strict`.
    pub fn exit_code(self, strict: bool) -> i32 {
        match self {
            Status::Failed => 1,
            Status::Incomplete if strict => 1,
            _ => 0,
        }
    }
}

/// A member of the Pareto front.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrontPoint {
    /// Index of the evaluation.
    pub index: usize,
    /// Candidate name.
    pub name: String,
    /// Drive voltage (V).
    #[serde(rename = "voltage_V")]
    pub voltage_v: f64,
    /// Values of the two objectives.
    pub values: [f64; 2],
}

/// The Pareto front over two objectives.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pareto {
    /// The two objectives.
    pub objectives: [Objective; 2],
    /// Candidates no other candidate beats on both (better or equal on both and
    /// strictly better on one), ordered by the first objective, best first.
    pub front: Vec<FrontPoint>,
}

/// The best loading of a series at one drive level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BestLoading {
    /// Series.
    pub series: String,
    /// Filler.
    pub filler: Option<String>,
    /// Drive voltage (V) of the best candidate.
    #[serde(rename = "voltage_V")]
    pub voltage_v: f64,
    /// The best candidate's name and index.
    pub name: String,
    /// Its index.
    pub index: usize,
    /// Its loading.
    pub loading: f64,
    /// Its basis.
    pub basis: crate::fit::composite::Basis,
    /// The objective there.
    pub value: f64,
    /// Half the distance to the neighbouring loadings of the sweep (the optimum's
    /// resolution); null with one loading.
    pub resolution: Option<f64>,
    /// The best loading is an end of the swept range: the optimum may lie beyond.
    pub at_edge: bool,
}

/// What the order of the first two ranked candidates rests on: the inputs of the
/// objective, of either, that carry no standard error (stated without ±, a
/// preset, or predicted from such values only), which the standard errors and
/// `apart` take as exact.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Lead {
    /// The first-ranked candidate.
    pub first: String,
    /// The second.
    pub second: String,
    /// Whether the two are told apart within their standard errors (null: either
    /// has none).
    pub apart: Option<bool>,
    /// Those inputs in words, grouped by source: "Eb of A, B: stated, design.toml:23".
    pub without_std_error: Vec<String>,
}

/// The ranking of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Ranking {
    /// Objective.
    pub by: Objective,
    /// Evaluations in output order: ranked (best first), then unranked (run order).
    pub order: Vec<usize>,
    /// Rank (1-based) of each evaluation by index in `evals` (None: unranked).
    pub ranks: Vec<Option<usize>>,
    /// For each evaluation (by index in `evals`), the earlier evaluation it repeats:
    /// the matrix alone, the 0 % point of several series of one matrix, is the
    /// same candidate in each (at one drive). A repeat is neither ranked nor on the
    /// Pareto front (it stays in its series' best loading and curve), and goes
    /// last in `order`.
    pub same_as: Vec<Option<usize>>,
    /// Whether each ranked evaluation (by index in `evals`) can be told apart from
    /// the first of the tie group above it (then it starts a group of its own), and
    /// how that was judged ([`Apart`]). None for the first (and for the unranked).
    pub apart: Vec<Option<Apart>>,
    /// The tie groups, best first: the ranks (1-based, inclusive) of each group's
    /// first and last member (a candidate told apart from both neighbours is a
    /// group of one).
    pub ties: Vec<[usize; 2]>,
    /// The relative tolerance ties were judged by where a standard error is
    /// missing ([`TOLERANCE`] unless `--tie-tolerance` says otherwise).
    pub tie_tolerance: f64,
    /// The count of candidates not ranked, per reason.
    pub not_ranked: NotRanked,
    /// The lead of the first over the second, where it rests on inputs without a
    /// standard error (None: fewer than two ranked, or every input has one).
    pub lead: Option<Lead>,
    /// Pareto front.
    pub pareto: Pareto,
    /// Best loading per series and drive level.
    pub best: Vec<BestLoading>,
    /// Status.
    pub status: Status,
    /// Distinct warnings, in the order they first appear.
    pub warnings: Vec<String>,
}

/// How many standard errors of their difference two objectives must differ by to
/// be told apart: 2, about 95 % two-sided for a normal difference.
pub const APART: f64 = 2.0;

/// How far apart (relative to the larger magnitude) two objectives must be to be
/// told apart when either has no standard error, unless `--tie-tolerance` says
/// otherwise: 1 %. A value stated without ±
/// is known to the digits it is written with (2.72, 250 kPa, 0.01: 0.2–5 % in the
/// last digit), a predicted modulus rests on a stiffening rule, and the response
/// time is read between the samples of its window (0.5 % of the window at 200
/// samples): a difference below 1 % is below what such inputs tell.
pub const TOLERANCE: f64 = 0.01;

/// How two neighbours of the ranking were compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Compared {
    /// Both objectives have a standard error: apart when they differ by more than
    /// [`APART`] standard errors of the difference.
    StdError,
    /// Either has none: apart when they differ by more than [`TOLERANCE`] of the
    /// larger magnitude.
    Tolerance,
}

impl std::fmt::Display for Compared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Compared::StdError => "std_error",
            Compared::Tolerance => "tolerance",
        })
    }
}

/// Whether a ranked candidate is told apart from the one ranked just above it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Apart {
    /// Told apart.
    pub apart: bool,
    /// How it was judged.
    pub by: Compared,
}

/// Whether objectives `a` and `b` (with their standard errors, where known) are
/// told apart: by [`APART`] standard errors of the difference when both have
/// one, else by the relative `tolerance` of the larger magnitude.
pub fn told_apart(a: f64, b: f64, sa: Option<f64>, sb: Option<f64>, tolerance: f64) -> Apart {
    match (sa, sb) {
        (Some(sa), Some(sb)) => Apart {
            apart: (a - b).abs() > APART * sa.hypot(sb),
            by: Compared::StdError,
        },
        _ => Apart {
            apart: (a - b).abs() > tolerance * a.abs().max(b.abs()),
            by: Compared::Tolerance,
        },
    }
}

/// Read a `--tie-tolerance`: a relative tolerance in [0, 1), as a fraction or a
/// percentage (`0.01`, `1%`; 0: only equal values tie).
pub fn parse_tie_tolerance(text: &str) -> Result<f64> {
    let bad = |why: String| {
        Error::settings(format!("--tie-tolerance {text}: {why}"))
            .with_hint("e.g. --tie-tolerance 1% (the default) or 0 (only equal values tie)")
    };
    let t = crate::units::parse_quantity(text, crate::units::Dimension::Fraction).map_err(bad)?;
    match (0.0..1.0).contains(&t) {
        true => Ok(t),
        false => Err(bad(
            "expected a relative tolerance from 0 to below 1 (100 %)".into(),
        )),
    }
}

/// How many candidates are not ranked, per reason (those of the text summary's
/// "1967 past pull-in, 507 past breakdown").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct NotRanked {
    /// Past pull-in at the drive.
    pub past_pull_in: usize,
    /// Past breakdown at the drive (or on the way up).
    pub past_breakdown: usize,
    /// Could not be evaluated.
    pub not_evaluated: usize,
    /// Evaluated, but without a value of the objective.
    pub no_value: usize,
    /// The same candidate as an earlier one (the matrix alone in several series),
    /// listed once.
    pub same_candidate: usize,
}

impl NotRanked {
    /// The count of the unranked candidates in `state` (repeats aside).
    pub fn of(&self, state: State) -> usize {
        match state {
            State::PullIn => self.past_pull_in,
            State::Breakdown => self.past_breakdown,
            State::Failed => self.not_evaluated,
            State::Ok => self.no_value,
        }
    }

    fn add(&mut self, state: State) {
        *match state {
            State::PullIn => &mut self.past_pull_in,
            State::Breakdown => &mut self.past_breakdown,
            State::Failed => &mut self.not_evaluated,
            State::Ok => &mut self.no_value,
        } += 1;
    }
}

/// Whether `b` repeats `a`: the same matrix alone (both at loading 0) at the same
/// drive. It is one material whatever the series: where the series' models give
/// it different values (a composite fit's own εm against the matrix's stated εr),
/// the first series' stands, and the repeat's listing says how much the other
/// differs.
fn repeats(a: &Evaluation, b: &Evaluation) -> bool {
    a.matrix == b.matrix
        && a.loading == 0.0
        && b.loading == 0.0
        && a.voltage.value.map(f64::to_bits) == b.voltage.value.map(f64::to_bits)
}

/// Rank `evals` (in run order) by `by`, with the Pareto front over `pareto`, ties
/// judged by [`TOLERANCE`] where a standard error is missing.
pub fn rank(evals: &[Evaluation], by: Objective, pareto: [Objective; 2]) -> Ranking {
    rank_with(evals, by, pareto, TOLERANCE)
}

/// [`rank`] with the relative tie tolerance `tie_tolerance` (`--tie-tolerance`).
pub fn rank_with(
    evals: &[Evaluation],
    by: Objective,
    pareto: [Objective; 2],
    tie_tolerance: f64,
) -> Ranking {
    // only the loading-0 points can repeat one another: compare those alone
    let zero: Vec<usize> = (0..evals.len())
        .filter(|&i| evals[i].loading == 0.0)
        .collect();
    let mut same_as = vec![None; evals.len()];
    for (k, &i) in zero.iter().enumerate() {
        same_as[i] = zero[..k]
            .iter()
            .copied()
            .find(|&j| repeats(&evals[j], &evals[i]));
    }
    let mut ranked: Vec<(usize, f64)> = evals
        .iter()
        .enumerate()
        .filter(|(i, _)| same_as[*i].is_none())
        .filter_map(|(i, e)| by.value(e).map(|v| (i, by.goodness(v))))
        .collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut ranks = vec![None; evals.len()];
    for (r, (i, _)) in ranked.iter().enumerate() {
        ranks[*i] = Some(r + 1);
    }
    // tie groups: each member against the group's first (the module's notes)
    let mut apart = vec![None; evals.len()];
    let mut ties: Vec<[usize; 2]> = Vec::new();
    for (r, &(i, _)) in ranked.iter().enumerate() {
        let b = &evals[i];
        let joined = ties.last_mut().and_then(|g| {
            let a = &evals[ranked[g[0] - 1].0];
            let x = told_apart(
                by.value(a)?,
                by.value(b)?,
                by.std_error(a),
                by.std_error(b),
                tie_tolerance,
            );
            apart[i] = Some(x);
            (!x.apart).then(|| g[1] = r + 1)
        });
        if joined.is_none() {
            ties.push([r + 1, r + 1]);
        }
    }
    let mut not_ranked = NotRanked::default();
    for (i, e) in evals.iter().enumerate() {
        match (same_as[i], ranks[i]) {
            (Some(_), _) => not_ranked.same_candidate += 1,
            (None, None) => not_ranked.add(e.state),
            (None, Some(_)) => {}
        }
    }
    let order: Vec<usize> = ranked
        .iter()
        .map(|x| x.0)
        .chain((0..evals.len()).filter(|&i| ranks[i].is_none() && same_as[i].is_none()))
        .chain((0..evals.len()).filter(|&i| same_as[i].is_some()))
        .collect();

    let mut warnings: Vec<String> = Vec::new();
    for w in evals.iter().flat_map(|e| e.warnings.iter()) {
        if !warnings.contains(w) {
            warnings.push(w.clone());
        }
    }
    warnings.extend(small_margins(evals, ranked.first().map(|x| x.0)));
    let failed: Vec<&Evaluation> = evals.iter().filter(|e| e.state == State::Failed).collect();
    if let Some(f) = failed.first() {
        warnings.push(format!(
            "{} candidate(s) could not be evaluated (first: {}: {})",
            failed.len(),
            f.name,
            f.state_note
        ));
    }
    if ranked.is_empty() {
        warnings.extend(lowest_limit(evals, by));
    }
    let status = if ranked.is_empty() {
        Status::Failed
    } else if !failed.is_empty() {
        Status::Incomplete
    } else if !warnings.is_empty() {
        Status::Warning
    } else {
        Status::Ok
    };
    let lead = match ranked[..] {
        [(a, _), (b, _), ..] => lead(
            &evals[a],
            &evals[b],
            by,
            apart[b]
                .filter(|x| x.by == Compared::StdError)
                .map(|x| x.apart),
        ),
        _ => None,
    };
    Ranking {
        by,
        lead,
        pareto: front(evals, &same_as, pareto),
        best: best_loadings(evals, by),
        order,
        ranks,
        apart,
        ties,
        tie_tolerance,
        not_ranked,
        same_as,
        status,
        warnings,
    }
}

/// When nothing is ranked: the lowest voltage at which a candidate meets its first
/// limit (breakdown or pull-in on the way up), to drive below.
fn lowest_limit(evals: &[Evaluation], by: Objective) -> Option<String> {
    let (v, e, what) = evals
        .iter()
        .flat_map(|e| {
            [(e.breakdown, "breakdown"), (e.pull_in, "pull-in")]
                .into_iter()
                .filter_map(move |(p, what)| p.map(|p| (p.voltage_v, e, what)))
        })
        .filter(|x| x.0.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    Some(format!(
        "no candidate has a value of {} at its drive; the first limit on the way up is {what} of {} at {}: drive below it (e.g. --sweep voltage with a range under it)",
        by.name(),
        e.name,
        crate::report::format::si(v, "V")
    ))
}

/// A warning for each kind of margin (to breakdown, to pull-in) that some
/// candidates in state `ok` have below [`SMALL_MARGIN`]: how many, the smallest,
/// and the leader (`lead`, by index in `evals`) when it is one of them.
fn small_margins(evals: &[Evaluation], lead: Option<usize>) -> Vec<String> {
    type Get = fn(&Evaluation) -> &Figure;
    let kinds: [(&str, Get); 2] = [
        (
            "breakdown (the field at the static stroke against Eb)",
            |e| &e.breakdown_margin,
        ),
        ("pull-in (the drive against the pull-in voltage)", |e| {
            &e.pull_in_margin
        }),
    ];
    let pct = |m: f64| format!("{} %", super::short(100.0 * m));
    let mut out = Vec::new();
    for (what, get) in kinds {
        let small = |e: &Evaluation| {
            get(e)
                .value
                .filter(|m| e.state == State::Ok && *m < SMALL_MARGIN)
        };
        let close: Vec<(usize, f64)> = evals
            .iter()
            .enumerate()
            .filter_map(|(i, e)| small(e).map(|m| (i, m)))
            .collect();
        let Some(&(least, m)) = close.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
            continue;
        };
        let leader = lead
            .and_then(|i| close.iter().find(|c| c.0 == i))
            .map_or(String::new(), |&(i, m)| {
                format!("; the leader {} among them, at {}", evals[i].name, pct(m))
            });
        out.push(format!(
            "{} candidate(s) driven within {} of {what}: smallest margin {} ({} at {}){leader}",
            close.len(),
            pct(SMALL_MARGIN),
            pct(m),
            evals[least].name,
            crate::report::format::si(evals[least].voltage.value.unwrap_or(f64::NAN), "V"),
        ));
    }
    out
}

/// The lead of `a` over `b` on `by` when it rests on inputs without a standard
/// error (grouped by property and source, in the order met).
fn lead(a: &Evaluation, b: &Evaluation, by: Objective, apart: Option<bool>) -> Option<Lead> {
    let mut groups: Vec<(&str, String, Vec<&str>)> = Vec::new();
    for e in [a, b] {
        for (what, f) in by.inputs(e) {
            if f.std_error.is_some() || f.value.is_none() {
                continue;
            }
            let from = format!("{}, {}", f.provenance, f.source);
            match groups.iter_mut().find(|g| g.0 == what && g.1 == from) {
                Some(g) => g.2.push(&e.name),
                None => groups.push((what, from, vec![&e.name])),
            }
        }
    }
    (!groups.is_empty()).then(|| Lead {
        first: a.name.clone(),
        second: b.name.clone(),
        apart,
        without_std_error: groups
            .into_iter()
            .map(|(what, from, names)| format!("{what} of {}: {from}", names.join(", ")))
            .collect(),
    })
}

/// The Pareto front: sorted by the first objective's goodness (then the second's),
/// a group of equal first values is on the front where its best second value beats
/// every strictly better first value's.
fn front(evals: &[Evaluation], same_as: &[Option<usize>], obj: [Objective; 2]) -> Pareto {
    let mut pts: Vec<(usize, f64, f64)> = evals
        .iter()
        .enumerate()
        .filter(|(i, _)| same_as[*i].is_none())
        .filter_map(|(i, e)| match (obj[0].value(e), obj[1].value(e)) {
            (Some(a), Some(b)) => Some((i, obj[0].goodness(a), obj[1].goodness(b))),
            _ => None,
        })
        .collect();
    pts.sort_by(|a, b| {
        b.1.total_cmp(&a.1)
            .then(b.2.total_cmp(&a.2))
            .then(a.0.cmp(&b.0))
    });
    let mut front = Vec::new();
    let mut best2 = f64::NEG_INFINITY;
    let mut i = 0;
    while i < pts.len() {
        let g1 = pts[i].1;
        let group_end = pts[i..]
            .iter()
            .position(|p| p.1 != g1)
            .map_or(pts.len(), |k| i + k);
        let top = pts[i].2;
        if top > best2 {
            for p in pts[i..group_end].iter().filter(|p| p.2 == top) {
                let e = &evals[p.0];
                front.push(FrontPoint {
                    index: e.index,
                    name: e.name.clone(),
                    voltage_v: e.voltage.value.unwrap_or(f64::NAN),
                    values: [obj[0].goodness(p.1), obj[1].goodness(p.2)],
                });
            }
            best2 = top;
        }
        i = group_end;
    }
    Pareto {
        objectives: obj,
        front,
    }
}

/// For every series and drive voltage, the loading with the best objective.
fn best_loadings(evals: &[Evaluation], by: Objective) -> Vec<BestLoading> {
    let mut keys: Vec<(String, u64)> = Vec::new();
    for e in evals {
        let k = (
            e.series.clone(),
            e.voltage.value.unwrap_or(f64::NAN).to_bits(),
        );
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .filter_map(|(series, vbits)| {
            let group: Vec<&Evaluation> = evals
                .iter()
                .filter(|e| {
                    e.series == series && e.voltage.value.unwrap_or(f64::NAN).to_bits() == vbits
                })
                .collect();
            let mut loadings: Vec<f64> = group.iter().map(|e| e.loading).collect();
            loadings.sort_by(f64::total_cmp);
            loadings.dedup();
            let best = group
                .iter()
                .filter_map(|e| by.value(e).map(|v| (*e, v)))
                .fold(None::<(&Evaluation, f64)>, |acc, (e, v)| match acc {
                    Some((_, bv)) if by.goodness(bv) >= by.goodness(v) => acc,
                    _ => Some((e, v)),
                })?;
            let (e, v) = best;
            let at = loadings.iter().position(|&x| x == e.loading).unwrap_or(0);
            let gaps: Vec<f64> = [
                at.checked_sub(1).map(|j| e.loading - loadings[j]),
                loadings.get(at + 1).map(|x| x - e.loading),
            ]
            .into_iter()
            .flatten()
            .collect();
            Some(BestLoading {
                series,
                filler: e.filler.clone(),
                voltage_v: f64::from_bits(vbits),
                name: e.name.clone(),
                index: e.index,
                loading: e.loading,
                basis: e.basis,
                value: v,
                resolution: gaps.iter().copied().reduce(f64::min).map(|g| 0.5 * g),
                at_edge: loadings.len() > 1 && (at == 0 || at == loadings.len() - 1),
            })
        })
        .collect()
}
