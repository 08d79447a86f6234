//! Stage 5: the term count, given or chosen by an information criterion among the
//! counts whose terms are all identifiable.

use super::assess::Assessed;
use super::{Kernels, Search};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// How `auto` scores term counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Criterion {
    /// Corrected Akaike information criterion (default).
    #[default]
    Aicc,
    /// Bayesian information criterion (stricter for n > 7).
    Bic,
}

/// One row of the term-count comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Number of Prony terms.
    pub terms: usize,
    /// Number of parameters (2N + 1).
    pub k: usize,
    /// RMSE (Pa).
    #[serde(rename = "rmse_Pa")]
    pub rmse_pa: f64,
    /// Relative RMSE (fraction).
    pub rel_rmse: f64,
    /// AICc (None when n ≤ k + 1).
    pub aicc: Option<f64>,
    /// BIC.
    pub bic: f64,
    /// Score minus the smallest score.
    pub delta: f64,
    /// Relaxation times (s).
    pub tau_s: Vec<f64>,
    /// Whether the automatic choice may take it.
    pub eligible: bool,
    /// Why not, if not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// How the term count was chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// The rule, in words.
    pub rule: String,
    /// Why this count.
    pub reason: String,
    /// Every count tried.
    pub candidates: Vec<Candidate>,
}

/// The rule `auto` applies; `window` names the window of τ the data support
/// ([`Kernels::WINDOW`]).
pub fn auto_rule(settings: &Search, window: &str) -> String {
    let base = format!("among term counts whose fit converged and whose terms are all identifiable, non-negligible, a factor 1.25 apart and inside {window}");
    let rule = match (settings.tolerance, settings.criterion) {
        (Some(t), _) => format!(
            "{base}, take the fewest whose relative RMSE is at most {:.3} %",
            100.0 * t
        ),
        (None, Criterion::Aicc) => format!(
            "{base}, take the fewest within ΔAICc ≤ 2 of the smallest AICc (BIC where AICc is undefined)"
        ),
        (None, Criterion::Bic) => format!("{base}, take the fewest within ΔBIC ≤ 2 of the smallest BIC"),
    };
    format!(
        "{rule}. Identifiable: {} (E∞ at the bound 0 its law allows, or with an interval reaching it, by its correlations only)",
        crate::fit::identifiability::RULE
    )
}

/// The term counts to fit: the one asked for (refused if the data hold too few
/// points: N terms need 2N + 3), or 0 to `max_terms` as far as the points allow.
pub fn term_counts(settings: &Search, m: usize) -> Result<Vec<usize>> {
    let max_by_points = (m.saturating_sub(3)) / 2;
    if let Some(nt) = settings.terms {
        if nt > max_by_points {
            return Err(Error::settings(format!(
                "{nt} term(s) need at least {} points, the file has {m}",
                2 * nt + 3
            ))
            .with_hint("use fewer terms (--terms auto chooses what the data support)"));
        }
    }
    Ok(match settings.terms {
        Some(nt) => vec![nt],
        None => (0..=settings.max_terms.min(max_by_points)).collect(),
    })
}

/// The term count reported and, for `--terms auto`, how it was chosen.
pub struct Choice {
    /// Index into the assessed counts.
    pub index: usize,
    /// The comparison (auto only).
    pub selection: Option<Selection>,
    /// Index of the count of smallest score, eligible or not (auto only).
    pub best: Option<usize>,
}

/// The score `auto` compares: AICc (BIC where AICc is undefined) or BIC.
pub fn score<K: Kernels>(settings: &Search, a: &Assessed<K>) -> f64 {
    match settings.criterion {
        Criterion::Aicc => a.aicc.unwrap_or(a.bic),
        Criterion::Bic => a.bic,
    }
}

/// Choose among the assessed counts by [`auto_rule`] (the only one when the count was
/// given); notes on what the choice leaves out go to `notes`.
pub fn choose<K: Kernels>(
    assessed: &[Assessed<K>],
    settings: &Search,
    notes: &mut Vec<String>,
) -> Choice {
    if settings.terms.is_some() {
        return Choice {
            index: 0,
            selection: None,
            best: None,
        };
    }
    let score = |a: &Assessed<K>| score(settings, a);
    let eligible: Vec<usize> = (0..assessed.len())
        .filter(|&i| assessed[i].problems.is_empty())
        .collect();
    let pool = if eligible.is_empty() {
        (0..assessed.len()).collect()
    } else {
        eligible
    };
    let chosen = match settings.tolerance {
        Some(tol) => within_tolerance(assessed, &pool, tol, notes),
        None => {
            let best_pool = pool
                .iter()
                .map(|&i| score(&assessed[i]))
                .fold(f64::INFINITY, f64::min);
            *pool
                .iter()
                .find(|&&i| score(&assessed[i]) <= best_pool + 2.0)
                .expect("the best is in the pool")
        }
    };
    let best_any = (0..assessed.len())
        .min_by(|&a, &b| score(&assessed[a]).total_cmp(&score(&assessed[b])))
        .expect("non-empty");
    let reason = reason(assessed, chosen, best_any, settings, notes);
    Choice {
        index: chosen,
        selection: Some(Selection {
            rule: auto_rule(settings, K::WINDOW),
            reason,
            candidates: candidates(assessed, settings),
        }),
        best: Some(best_any),
    }
}

/// The fewest terms of `pool` whose relative RMSE is at most `tol`, else (said in
/// `notes`) the count of smallest relative RMSE.
fn within_tolerance<K: Kernels>(
    assessed: &[Assessed<K>],
    pool: &[usize],
    tol: f64,
    notes: &mut Vec<String>,
) -> usize {
    pool.iter()
        .copied()
        .find(|&i| assessed[i].rel_rmse <= tol)
        .unwrap_or_else(|| {
            notes.push(format!(
                "no term count reaches the relative RMSE tolerance {:.3} %; the best is used",
                100.0 * tol
            ));
            *pool
                .iter()
                .min_by(|&&a, &&b| assessed[a].rel_rmse.total_cmp(&assessed[b].rel_rmse))
                .expect("non-empty")
        })
}

/// Why count `chosen` was taken, and (into the reason and `notes`) what a better
/// scoring but ineligible count `best_any` would have said.
fn reason<K: Kernels>(
    assessed: &[Assessed<K>],
    chosen: usize,
    best_any: usize,
    settings: &Search,
    notes: &mut Vec<String>,
) -> String {
    let score = |a: &Assessed<K>| score(settings, a);
    let c = &assessed[chosen];
    let name = if settings.criterion == Criterion::Bic {
        "BIC"
    } else {
        "AICc"
    };
    let mut reason = if let Some(tol) = settings.tolerance {
        format!(
            "{} term(s) {} a relative RMSE of {:.3} %",
            c.tf.n_terms,
            if c.rel_rmse <= tol {
                "reach"
            } else {
                "come closest to the tolerance, with"
            },
            100.0 * c.rel_rmse
        )
    } else if chosen == best_any {
        format!(
            "{} term(s) have the smallest {name} and no fewer terms are within 2 of it",
            c.tf.n_terms
        )
    } else {
        format!(
            "{} term(s): the fewest within Δ{name} ≤ 2 of the best eligible count; more terms are not supported by the data",
            c.tf.n_terms
        )
    };
    if assessed[best_any].tf.n_terms > c.tf.n_terms && !assessed[best_any].problems.is_empty() {
        let b = &assessed[best_any];
        reason.push_str(&format!(
            "; {} terms score better ({name} {:.2} lower) but: {}",
            b.tf.n_terms,
            score(c) - score(b),
            b.problems[0].1
        ));
        notes.push(format!(
            "more relaxation may be present than these data resolve: with {} terms, {}",
            b.tf.n_terms, b.problems[0].1
        ));
    }
    reason
}

/// The comparison's rows, one a count.
fn candidates<K: Kernels>(assessed: &[Assessed<K>], settings: &Search) -> Vec<Candidate> {
    let best = assessed
        .iter()
        .map(|a| score(settings, a))
        .fold(f64::INFINITY, f64::min);
    assessed
        .iter()
        .map(|a| Candidate {
            terms: a.tf.n_terms,
            k: 1 + 2 * a.tf.n_terms,
            rmse_pa: a.rmse,
            rel_rmse: a.rel_rmse,
            aicc: a.aicc,
            bic: a.bic,
            delta: score(settings, a) - best,
            tau_s: a.si[1 + a.tf.n_terms..].to_vec(),
            eligible: a.problems.is_empty(),
            note: a.problems.first().map(|p| p.1.clone()),
        })
        .collect()
}
