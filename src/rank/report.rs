//! What a ranking run writes: the table (stdout), the JSON, the CSV and the report
//! (`index.md` and `index.html` with SVG charts: ranking bars, objective against loading per series
//! naming its rules, the Pareto chart, stroke–voltage curves of the leaders).
//! Each is a pure function of the run's identity, its evaluations and the ranking,
//! so a merged sweep writes the same bytes as a single run.

use super::candidate::loading_label;
use super::figures::{Evaluated, Evaluation, State};
use super::ranking::{Compared, NotRanked, Objective, Ranking, APART};
use super::shard::RunInfo;
use super::short;
use super::Figure;
use crate::error::Result;
use crate::fit::composite::Basis;
use crate::report::format::{si, si_column, sig};
use crate::report::page::{code, strong, text, Page};
use crate::report::plot::{band, Chart, Series, Style};
use crate::report::runs::Run;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Schema tag of the JSON output.
pub const SCHEMA: &str = "dea-fit/rank/1";

/// A value of an objective in the unit tables and charts show.
pub fn shown(o: Objective, v: f64) -> f64 {
    match o {
        Objective::Stroke | Objective::MaxStroke => 100.0 * v,
        Objective::Beta => 1e6 * v,
        _ => v,
    }
}

/// The unit of [`shown`] values.
pub fn shown_unit(o: Objective) -> &'static str {
    match o {
        Objective::Stroke | Objective::MaxStroke => "%",
        Objective::Force => "N",
        Objective::Speed => "s",
        Objective::Fm => "",
        Objective::Beta => "1/MPa",
        Objective::Loss => "J",
    }
}

/// An objective's value as text.
fn fmt_objective(o: Objective, v: f64) -> String {
    match o {
        Objective::Stroke | Objective::MaxStroke => format!("{} %", sig(100.0 * v, 4)),
        Objective::Force => si(v, "N"),
        Objective::Speed => si(v, "s"),
        Objective::Loss => si(v, "J"),
        Objective::Fm => sig(v, 4),
        Objective::Beta => format!("{} /MPa", sig(1e6 * v, 4)),
    }
}

/// A figure as text ("—" without a value).
fn fmt_fig(f: &Figure, fmt: impl Fn(f64) -> String) -> String {
    f.value.map_or("—".into(), fmt)
}

/// The whole output as JSON: what `--json` prints.
#[derive(Serialize)]
struct Output<'a> {
    schema: &'static str,
    run: &'a RunInfo,
    by: Objective,
    status: super::ranking::Status,
    warnings: &'a [String],
    /// How many candidates are not ranked, per reason.
    not_ranked: NotRanked,
    /// The tie groups and the rule they were made by.
    ties: Ties,
    candidates: Vec<Row<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lead: Option<&'a super::ranking::Lead>,
    pareto: &'a super::ranking::Pareto,
    best_loading: &'a [super::ranking::BestLoading],
}

/// The tie groups of the JSON: the rule and the groups of more than one.
#[derive(Serialize)]
struct Ties {
    /// Standard errors of the difference that tell two apart (where both have one).
    std_errors: f64,
    /// The relative tolerance that tells two apart where either has none.
    tolerance: f64,
    /// The groups of more than one candidate: ranks of the first and the last.
    groups: Vec<[usize; 2]>,
}

#[derive(Serialize)]
struct Row<'a> {
    rank: Option<usize>,
    /// The rank of the first of its tie group (its own rank when it ties with none).
    #[serde(skip_serializing_if = "Option::is_none")]
    tie_group: Option<usize>,
    objective: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    objective_std_error: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    apart_from_above: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    apart_by: Option<Compared>,
    #[serde(skip_serializing_if = "Option::is_none")]
    same_as: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    not_ranked: Option<String>,
    #[serde(flatten)]
    evaluation: &'a Evaluation,
}

/// The JSON output.
pub fn json(info: &RunInfo, evals: &[Evaluated], r: &Ranking) -> String {
    let candidates = r
        .order
        .iter()
        .map(|&i| {
            let e = &evals[i].evaluation;
            let v = r.by.value(e);
            Row {
                rank: r.ranks[i],
                tie_group: r.ranks[i].and_then(|k| group_of(r, k)).map(|g| g[0]),
                objective: v,
                objective_std_error: v.and(r.by.std_error(e)),
                apart_from_above: r.apart[i].map(|a| a.apart),
                apart_by: r.apart[i].map(|a| a.by),
                same_as: r.same_as[i].map(|j| evals[j].evaluation.name.as_str()),
                not_ranked: match r.same_as[i] {
                    Some(j) => Some(format!(
                        "the same candidate as {}",
                        evals[j].evaluation.name
                    )),
                    None => v.is_none().then(|| r.by.why_not(e)),
                },
                evaluation: e,
            }
        })
        .collect();
    let out = Output {
        schema: SCHEMA,
        run: info,
        by: r.by,
        status: r.status,
        warnings: &r.warnings,
        not_ranked: r.not_ranked,
        ties: Ties {
            std_errors: APART,
            tolerance: r.tie_tolerance,
            groups: r.ties.iter().copied().filter(|g| g[1] > g[0]).collect(),
        },
        candidates,
        lead: r.lead.as_ref(),
        pareto: &r.pareto,
        best_loading: &r.best,
    };
    serde_json::to_string_pretty(&out).expect("the ranking serialises")
}

/// The tie group (ranks of its first and last) of the candidate ranked `k`.
fn group_of(r: &Ranking, k: usize) -> Option<[usize; 2]> {
    r.ties.iter().copied().find(|g| (g[0]..=g[1]).contains(&k))
}

/// The leaders table: the first `top` ranked candidates (all with 0), columns with
/// a unit in one SI prefix each, the objective's σ, and what the σ and "≈" mean.
fn leaders(page: &mut Page, evals: &[Evaluated], r: &Ranking, top: usize) {
    let ranked = r.ranks.iter().filter(|x| x.is_some()).count();
    let shown_n = if top == 0 { ranked } else { top.min(ranked) };
    // The objective gets its own column unless one of the fixed ones shows it.
    let extra = matches!(r.by, Objective::Force | Objective::Beta | Objective::Loss);
    // Columns with a unit: one SI prefix each, in the header ("—" where missing).
    let column = |f: &dyn Fn(&Evaluation) -> &Figure, unit: &str| {
        let values: Vec<f64> = r.order[..shown_n]
            .iter()
            .map(|&i| f(&evals[i].evaluation).value.unwrap_or(f64::NAN))
            .collect();
        let (unit, cells) = si_column(&values, unit, 5);
        let cells: Vec<String> = values
            .iter()
            .zip(cells)
            .map(|(v, c)| if v.is_finite() { c } else { "—".into() })
            .collect();
        (unit, cells)
    };
    let (drive_unit, drive) = column(&|e| &e.voltage, "V");
    let (y_unit, youngs) = column(&|e| &e.youngs_modulus, "Pa");
    let (t_unit, rise) = column(&|e| &e.response_time, "s");
    let percent = |f: &Figure| fmt_fig(f, |v| sig(100.0 * v, 4));
    let margin = |f: &Figure| fmt_fig(f, |v| sig(100.0 * v, 2));
    let rows: Vec<Vec<String>> = r.order[..shown_n]
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            let e = &evals[i].evaluation;
            let close = r.apart[i].is_some_and(|a| !a.apart);
            let mut row = vec![
                r.ranks[i].map_or("—".into(), |x| match close {
                    true => format!("{x}≈"),
                    false => x.to_string(),
                }),
                e.name.clone(),
                drive[k].clone(),
                fmt_fig(&e.eps_r, |v| sig(v, 4)),
                youngs[k].clone(),
                fmt_fig(&e.fm, |v| sig(v, 3)),
                percent(&e.static_stroke),
                format!("{} ({})", percent(&e.max_stroke), e.max_stroke_limit),
                rise[k].clone(),
                format!(
                    "{} / {}",
                    margin(&e.breakdown_margin),
                    margin(&e.pull_in_margin)
                ),
            ];
            if extra {
                row.push(r.by.value(e).map_or("—".into(), |v| fmt_objective(r.by, v)));
            }
            row.push(
                r.by.std_error(e)
                    .map_or("—".into(), |v| fmt_objective(r.by, v)),
            );
            row
        })
        .collect();
    let (drive_h, y_h, t_h) = (
        format!("drive ({drive_unit})"),
        format!("Y ({y_unit})"),
        format!("t10–90 ({t_unit})"),
    );
    let mut header = vec![
        "#",
        "candidate",
        &drive_h,
        "εr",
        &y_h,
        "Fm",
        "stroke (%)",
        "max stroke % (limit)",
        &t_h,
        "margin % Eb / Vpi",
    ];
    if extra {
        header.push(r.by.name());
    }
    let sigma = format!("σ {}", r.by.name());
    header.push(&sigma);
    page.heading("The leaders");
    page.table(&header, rows);
    page.text(format!(
        "εr, Y: predicted by the series' rules, fitted, or stated in the manifest (their \
         provenance per candidate: --csv, --json); Fm: figure of merit; t10–90: rise time \
         of the step response; margin at the operating point to breakdown 1 − E/Eb (E \
         the true field at the static stroke) / to pull-in 1 − V/Vpi (below {} %: a \
         warning).",
        short(100.0 * super::figures::SMALL_MARGIN)
    ));
    if r.apart[..].iter().any(|a| a.is_some()) {
        // the tie groups of more than one among the rows shown
        let shown: Vec<String> = r
            .ties
            .iter()
            .filter(|g| g[1] > g[0] && g[0] <= shown_n)
            .map(|g| format!("{}–{}", g[0], g[1]))
            .collect();
        page.text(format!(
            "σ: first-order standard error from the fit files' standard errors and the ± written in the manifest (values stated without ± count as exact); n≈: cannot be told apart from the first of its tie group, the nearest rank above without ≈ (within {} σ of their difference, or, where either has no σ, within {} % of the larger: --tie-tolerance); ties {}.",
            APART,
            short(100.0 * r.tie_tolerance),
            match shown.is_empty() {
                true => "among these: none".to_string(),
                false => format!("among these (ranks): {}", shown.join(", ")),
            }
        ));
    }
    if let Some(l) = &r.lead {
        page.text(format!(
            "The lead of {} over {} on {} rests on inputs without a standard error, taken as exact{}:",
            l.first,
            l.second,
            r.by.name(),
            match l.apart {
                Some(true) => " (they are told apart by the others' σ alone)",
                Some(false) => " (and within the others' σ they cannot be told apart)",
                None => "",
            }
        ));
        page.bullets(l.without_std_error.clone());
    }
    if ranked > shown_n {
        page.text(format!(
            "… {} more ranked (--top 0 shows all; --csv, --json).",
            ranked - shown_n
        ));
    }
}

/// The candidates not ranked, summarised: how many past pull-in, past breakdown,
/// not evaluated or without a value of the objective, then one line per series and
/// state (the first `top`) with the count, the loadings and drive levels and the
/// reason at the first; and those that repeat another (the matrix alone in several
/// series), one line per pair.
fn unranked(page: &mut Page, evals: &[Evaluated], r: &Ranking, top: usize) {
    let ranked = r.ranks.iter().filter(|x| x.is_some()).count();
    let (repeats, rest): (Vec<usize>, Vec<usize>) = r.order[ranked..]
        .iter()
        .partition(|&&i| r.same_as[i].is_some());
    let unranked: Vec<&Evaluation> = rest.iter().map(|&i| &evals[i].evaluation).collect();
    if !unranked.is_empty() {
        page.heading(format!("Not ranked on {}", r.by.name()));
        page.text(format!(
            "{} candidate(s): {}.",
            unranked.len(),
            not_ranked_counts(&r.not_ranked, r.by)
        ));
        // one line per series and state: how many, their loadings and drive
        // levels, and the reason at the first (the lowest drive, then loading)
        let mut groups: Vec<(&str, State, Vec<&Evaluation>)> = Vec::new();
        for e in &unranked {
            match groups
                .iter_mut()
                .find(|g| g.0 == e.series.as_str() && g.1 == e.state)
            {
                Some(g) => g.2.push(e),
                None => groups.push((&e.series, e.state, vec![e])),
            }
        }
        let shown = if top == 0 { usize::MAX } else { top };
        let span = |lo: String, hi: String| match lo == hi {
            true => lo,
            false => format!("{lo} – {hi}"),
        };
        let mut items: Vec<String> = groups
            .iter()
            .take(shown)
            .map(|(series, state, es)| {
                let v = |e: &Evaluation| e.voltage.value.unwrap_or(f64::INFINITY);
                let first = es
                    .iter()
                    .min_by(|a, b| v(a).total_cmp(&v(b)).then(a.loading.total_cmp(&b.loading)))
                    .copied()
                    .unwrap_or(es[0]);
                let fold = |f: fn(f64, f64) -> f64, x: &dyn Fn(&Evaluation) -> f64| {
                    es.iter().map(|e| x(e)).reduce(f).unwrap_or(f64::NAN)
                };
                let volts = span(
                    si(fold(f64::min, &v), "V"),
                    si(
                        fold(f64::max, &|e| e.voltage.value.unwrap_or(f64::NEG_INFINITY)),
                        "V",
                    ),
                );
                let loadings = match first.filler {
                    None => String::new(),
                    Some(_) => format!(
                        "{}, ",
                        span(
                            loading_label(fold(f64::min, &|e| e.loading), first.basis),
                            loading_label(fold(f64::max, &|e| e.loading), first.basis)
                        )
                    ),
                };
                let at = fmt_fig(&first.voltage, |x| si(x, "V"));
                let at = match first.filler {
                    None => format!("at {at}"),
                    Some(_) => format!("{} at {at}", loading_label(first.loading, first.basis)),
                };
                format!(
                    "{series}: {} {} ({loadings}{volts}); first {at}: {}",
                    es.len(),
                    state_words(*state, r.by),
                    r.by.why_not(first)
                )
            })
            .collect();
        if groups.len() > shown {
            items.push(format!(
                "… {} more series and state(s) (--top 0 lists all)",
                groups.len() - shown
            ));
        }
        page.bullets(items);
    }
    let mut pairs: Vec<(usize, usize, usize)> = Vec::new();
    for &i in &repeats {
        let j = r.same_as[i].unwrap_or(i);
        let (a, b) = (&evals[i].evaluation.name, &evals[j].evaluation.name);
        match pairs
            .iter_mut()
            .find(|p| &evals[p.0].evaluation.name == a && &evals[p.1].evaluation.name == b)
        {
            Some(p) => p.2 += 1,
            None => pairs.push((i, j, 1)),
        }
    }
    page.bullets(pairs.iter().map(|&(i, j, n)| {
        let (a, b) = (&evals[i].evaluation, &evals[j].evaluation);
        // the series' models may give the one material other values: say how much
        let differs = match (r.by.value(a), r.by.value(b)) {
            (Some(x), Some(y)) if x != y => format!(
                "; its series' model gives {} {} against {}",
                r.by.name(),
                fmt_objective(r.by, x),
                fmt_objective(r.by, y)
            ),
            _ => String::new(),
        };
        format!(
            "{}: the matrix alone, the same candidate as {} (listed once){}{differs}",
            a.name,
            b.name,
            match n {
                1 => String::new(),
                n => format!(", at {n} drive levels"),
            }
        )
    }));
}

/// What keeps candidates in `state` off a ranking by `by`, in words.
fn state_words(state: State, by: Objective) -> String {
    match state {
        State::PullIn => "past pull-in".into(),
        State::Breakdown => "past breakdown".into(),
        State::Failed => "not evaluated".into(),
        State::Ok => format!("no {} value", by.name()),
    }
}

/// The count of unranked candidates per reason: "1967 past pull-in, 507 past
/// breakdown" (the JSON's `not_ranked`, in words).
fn not_ranked_counts(counts: &NotRanked, by: Objective) -> String {
    [State::PullIn, State::Breakdown, State::Failed, State::Ok]
        .into_iter()
        .filter_map(|s| {
            let n = counts.of(s);
            (n > 0).then(|| format!("{n} {}", state_words(s, by)))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Every evaluation as CSV, in run order, with rank and objective.
pub fn csv(evals: &[Evaluated], r: &Ranking) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let num = |f: &Figure| f.value.map_or(String::new(), |v| v.to_string());
    let prov = |f: &Figure| f.provenance.to_string();
    let _ = w.write_record([
        "index",
        "name",
        "series",
        "matrix",
        "filler",
        "loading",
        "basis",
        "volume_fraction",
        "rules",
        "voltage_V",
        "eps_r",
        "eps_r_provenance",
        "youngs_modulus_Pa",
        "youngs_modulus_provenance",
        "beta_per_Pa",
        "fm",
        "tan_delta",
        "tan_delta_provenance",
        "breakdown_field_V_per_m",
        "breakdown_field_provenance",
        "state",
        "static_stroke",
        "pull_in_V",
        "breakdown_V",
        "max_stroke",
        "max_stroke_limit",
        "blocked_force_N",
        "response_time_s",
        "energy_in_J",
        "loss_per_cycle_J",
        "breakdown_margin",
        "pull_in_margin",
        "rank",
        "objective",
        "objective_std_error",
        "apart_from_above",
        "apart_by",
    ]);
    for (i, ev) in evals.iter().enumerate() {
        let e = &ev.evaluation;
        let _ = w.write_record([
            e.index.to_string(),
            e.name.clone(),
            e.series.clone(),
            e.matrix.clone(),
            e.filler.clone().unwrap_or_default(),
            e.loading.to_string(),
            e.basis.to_string(),
            e.volume_fraction.to_string(),
            e.rules.clone(),
            num(&e.voltage),
            num(&e.eps_r),
            prov(&e.eps_r),
            num(&e.youngs_modulus),
            prov(&e.youngs_modulus),
            num(&e.beta),
            num(&e.fm),
            num(&e.tan_delta),
            prov(&e.tan_delta),
            num(&e.breakdown_field),
            prov(&e.breakdown_field),
            e.state.to_string(),
            num(&e.static_stroke),
            e.pull_in.map_or(String::new(), |p| p.voltage_v.to_string()),
            e.breakdown
                .map_or(String::new(), |p| p.voltage_v.to_string()),
            num(&e.max_stroke),
            e.max_stroke_limit.to_string(),
            num(&e.blocked_force),
            num(&e.response_time),
            num(&e.energy_in),
            num(&e.loss_per_cycle),
            num(&e.breakdown_margin),
            num(&e.pull_in_margin),
            r.ranks[i].map_or(String::new(), |x| x.to_string()),
            r.by.value(e).map_or(String::new(), |v| v.to_string()),
            r.by.std_error(e).map_or(String::new(), |v| v.to_string()),
            r.apart[i].map_or(String::new(), |a| a.apart.to_string()),
            r.apart[i].map_or(String::new(), |a| a.by.to_string()),
        ]);
    }
    String::from_utf8(w.into_inner().expect("a CSV in memory")).expect("UTF-8 CSV")
}

/// How many leaders the bar and stroke–voltage charts show.
const LEADERS: usize = 10;

/// Write the report into `dir` (claimed by the caller): the charts and the page
/// (`index.md`, `index.html`, `run.json`). Returns the HTML page's path.
pub fn write(
    dir: &Path,
    info: &RunInfo,
    evals: &[Evaluated],
    r: &Ranking,
    top: usize,
) -> Result<PathBuf> {
    let by = r.by;
    let label = |o: Objective| match shown_unit(o) {
        "" => o.label().to_string(),
        u => format!(
            "{} ({u})",
            o.label().split(" (").next().unwrap_or(o.label())
        ),
    };
    let ranked: Vec<usize> = r
        .order
        .iter()
        .copied()
        .filter(|&i| r.ranks[i].is_some())
        .collect();

    // Ranking bars.
    let bars: Vec<Series> = ranked
        .iter()
        .take(LEADERS)
        .enumerate()
        .map(|(k, &i)| {
            let e = &evals[i].evaluation;
            let v = shown(by, by.value(e).unwrap_or(0.0));
            let x = (k + 1) as f64;
            Series {
                label: format!(
                    "#{} {} at {}",
                    k + 1,
                    e.name,
                    si(e.voltage.value.unwrap_or(f64::NAN), "V")
                ),
                points: band(&[x - 0.4, x + 0.4], &[0.0, 0.0], &[v, v]),
                color: k,
                style: Style::Band,
            }
        })
        .collect();
    let ranking_chart = Chart {
        title: format!("{}: the {} best by {}", info.design, bars.len(), by.name()),
        x_label: "rank".into(),
        y_label: label(by),
        series: bars,
        log_x: false,
        x_unit: None,
        y_unit: None,
    };

    // Objective against filler volume fraction, per series, at the leader's drive.
    let lead_v = ranked
        .first()
        .and_then(|&i| evals[i].evaluation.voltage.value);
    let mut series_names: Vec<&str> = Vec::new();
    for ev in evals {
        if !series_names.contains(&ev.evaluation.series.as_str()) {
            series_names.push(&ev.evaluation.series);
        }
    }
    let lines: Vec<Series> = series_names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let pts: Vec<&Evaluation> = evals
                .iter()
                .map(|x| &x.evaluation)
                .filter(|e| e.series == *name && lead_v.is_none_or(|v| e.voltage.value == Some(v)))
                .collect();
            let rules = pts.first().map_or(String::new(), |e| e.rules.clone());
            let valued: Vec<(f64, f64)> = pts
                .iter()
                .filter_map(|e| {
                    by.value(e)
                        .map(|v| (100.0 * e.volume_fraction, shown(by, v)))
                })
                .collect();
            Series {
                label: format!("{name} ({rules})"),
                // a single ranked point is drawn as a marker (a line of one point is invisible)
                style: if valued.len() < 2 {
                    Style::Points
                } else {
                    Style::Line
                },
                points: valued,
                color: k,
            }
        })
        .collect();
    let loading_chart = Chart {
        title: format!(
            "{} against filler volume fraction{}",
            by.name(),
            lead_v.map_or(String::new(), |v| format!(" at {}", si(v, "V")))
        ),
        x_label: "filler volume fraction φ (%)".into(),
        y_label: label(by),
        series: lines,
        log_x: false,
        x_unit: None,
        y_unit: None,
    };

    // Pareto chart.
    let [a, b] = r.pareto.objectives;
    let all: Vec<(f64, f64)> = evals
        .iter()
        .filter_map(|x| match (a.value(&x.evaluation), b.value(&x.evaluation)) {
            (Some(p), Some(q)) => Some((shown(a, p), shown(b, q))),
            _ => None,
        })
        .collect();
    let front: Vec<(f64, f64)> = r
        .pareto
        .front
        .iter()
        .map(|p| (shown(a, p.values[0]), shown(b, p.values[1])))
        .collect();
    let pareto_chart = Chart {
        title: format!("Pareto front: {} against {}", a.name(), b.name()),
        x_label: label(a),
        y_label: label(b),
        series: vec![
            Series {
                label: "candidates".into(),
                points: all,
                color: 8,
                style: Style::Points,
            },
            Series {
                label: format!("front ({} candidates)", front.len()),
                points: front.clone(),
                color: 1,
                style: Style::Line,
            },
            Series {
                label: "front members".into(),
                points: front,
                color: 1,
                style: Style::Points,
            },
        ],
        log_x: false,
        x_unit: None,
        y_unit: None,
    };

    // Static stroke–voltage curves of the leaders, each with its drive point.
    let mut names: Vec<&str> = Vec::new();
    let mut curves = Vec::new();
    for &i in &ranked {
        let ev = &evals[i];
        let e = &ev.evaluation;
        if names.contains(&e.name.as_str()) || names.len() == 5 {
            continue;
        }
        names.push(&e.name);
        let k = names.len() - 1;
        curves.push(Series {
            label: format!("{} (to {})", e.name, e.max_stroke_limit),
            points: ev
                .curve
                .iter()
                .map(|p| (1e-3 * p.voltage_v, 100.0 * p.stroke))
                .collect(),
            color: k,
            style: Style::Line,
        });
        if let (Some(v), Some(st)) = (e.voltage.value, e.static_stroke.value) {
            curves.push(Series {
                label: format!("drive {}", si(v, "V")),
                points: vec![(1e-3 * v, 100.0 * st)],
                color: k,
                style: Style::Points,
            });
        }
    }
    let stroke_chart = Chart {
        title: "static stroke against voltage: the leaders".into(),
        x_label: "voltage (kV)".into(),
        y_label: "static stroke (%)".into(),
        series: curves,
        log_x: false,
        x_unit: None,
        y_unit: None,
    };

    let page = page(info, evals, r, top, |page| {
        page.chart(dir, "ranking.svg", "ranking", &ranking_chart)?;
        page.chart(
            dir,
            "objective-vs-loading.svg",
            "objective against loading",
            &loading_chart,
        )?;
        page.chart(dir, "pareto.svg", "Pareto", &pareto_chart)?;
        page.chart(
            dir,
            "stroke-voltage.svg",
            "stroke against voltage",
            &stroke_chart,
        )
    })?;
    let leader = ranked.first().map(|&i| {
        let e = &evals[i].evaluation;
        format!(
            "leader {} ({} {})",
            e.name,
            by.name(),
            by.value(e).map_or("—".into(), |v| fmt_objective(by, v))
        )
    });
    let run = Run::new("rank", info.manifest.clone(), info.design.clone()).headline(
        leader
            .into_iter()
            .chain(std::iter::once(format!("{} points", info.points)))
            .collect(),
    );
    page.write(dir, "index", run)
}

/// The summary `dea-fit rank` prints: the report's page without its charts.
pub fn summary(info: &RunInfo, evals: &[Evaluated], r: &Ranking, top: usize) -> Result<String> {
    Ok(page(info, evals, r, top, |_| Ok(()))?.terminal())
}

/// The one rendering of a ranking (the terminal, Markdown and HTML all show this
/// page): the run (manifest, actuator, drive, sweep, objective), status, `charts`
/// (added by the report), the leaders, the candidates not ranked, the Pareto front,
/// the best loading per series and the warnings.
fn page(
    info: &RunInfo,
    evals: &[Evaluated],
    r: &Ranking,
    top: usize,
    charts: impl FnOnce(&mut Page) -> Result<()>,
) -> Result<Page> {
    let by = r.by;
    let mut page = Page::new(format!("Ranking: {}", info.design));
    page.para(vec![
        text("Manifest "),
        code(&info.manifest),
        text(" (sha256 "),
        code(&info.sha256),
        text("), actuator "),
        code(&info.scene),
        text(format!(
            "; drive {}; sweep: {}; {} points. Ranked by ",
            info.drive, info.sweep, info.points
        )),
        strong(by.name()),
        text(format!(" ({}).", by.label())),
    ]);
    page.status_line(r.status, r.status);
    charts(&mut page)?;
    leaders(&mut page, evals, r, top);
    unranked(&mut page, evals, r, top);
    let [a, b] = r.pareto.objectives;
    page.heading(format!("Pareto front ({} against {})", a.name(), b.name()));
    page.text(format!("{} candidate(s):", r.pareto.front.len()));
    page.bullets(r.pareto.front.iter().map(|p| {
        format!(
            "{} at {}: {} {}, {} {}",
            p.name,
            si(p.voltage_v, "V"),
            a.name(),
            fmt_objective(a, p.values[0]),
            b.name(),
            fmt_objective(b, p.values[1])
        )
    }));
    page.heading(format!("Best loading per series ({})", by.name()));
    let rows: Vec<Vec<String>> = r
        .best
        .iter()
        .map(|b| {
            let unit = match b.basis {
                Basis::Weight => "wt%",
                Basis::Volume => "vol%",
            };
            vec![
                b.series.clone(),
                si(b.voltage_v, "V"),
                match &b.filler {
                    None => "—".into(),
                    Some(_) => format!("{} {unit}", short(100.0 * b.loading)),
                },
                b.resolution
                    .map_or("—".into(), |x| format!("± {} {unit}", short(100.0 * x))),
                fmt_objective(by, b.value),
                if b.at_edge {
                    "end of the swept range".into()
                } else {
                    String::new()
                },
            ]
        })
        .collect();
    page.table(
        &[
            "series",
            "drive",
            "best loading",
            "resolution",
            by.name(),
            "note",
        ],
        rows,
    );
    page.text("resolution: half the distance to the neighbouring loadings of the sweep.");
    page.warnings(&r.warnings);
    Ok(page)
}
