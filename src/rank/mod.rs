//! Materials design: rank fillers and composites by what they buy an actuator
//! (`dea-fit rank`, docs/rank.md).
//!
//! ```text
//! design.toml ──manifest::read (units → SI, file:line:col errors)──► Design
//! Design + Sweep ──sweep::Points──► Point (series, loading, voltage), in one fixed order
//! Point ──candidate::build──► Candidate (εr, modulus, tan δ, Eb with provenance; the material)
//! Candidate + drive ──figures::evaluate (static curve, pull-in, breakdown, damped step)──► Evaluation
//! Evaluations ──ranking::rank──► Ranking (order by an objective, Pareto front, best loading per series)
//! Ranking ──report──► table, CSV, JSON, reports/rank-<name>/{*.svg, index.md}
//! ```
//! A slice of the points (`--shard K/N`) is written as a shard file
//! ([`shard`]); `rank merge` joins the shards of one sweep into the evaluations a
//! single run gives, so the same ranking follows byte for byte.

pub mod candidate;
pub mod figures;
pub mod manifest;
pub mod ranking;
pub mod report;
pub mod shard;
pub mod sweep;

use serde::{Deserialize, Serialize};

/// A computed number for names, notes and sources: 4 significant digits, trailing
/// zeros dropped (0.05 → "0.05", 4.999999999999999 → "5", 734.9057 → "734.9").
pub fn short(v: f64) -> String {
    let s = crate::report::format::sig(v, 4);
    match s.contains('.') && !s.contains('e') {
        true => s.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => s,
    }
}

/// What a number is, by where it comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Provenance {
    /// Read from a data file (a measured series).
    Measured,
    /// From a fit file (hyperelastic, relaxation, identified, composite, breakdown).
    Fitted,
    /// From a stated model (a mixing rule, a stiffening rule, an interpolation) or
    /// the simulator.
    Predicted,
    /// Typed into the design manifest or the actuator scene, with or without `± σ`
    /// (its `file:line` says where). Without ± it carries no standard error: the
    /// ranking takes it as exact and says when an order rests on it.
    Stated,
}

impl std::fmt::Display for Provenance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Provenance::Measured => "measured",
            Provenance::Fitted => "fitted",
            Provenance::Predicted => "predicted",
            Provenance::Stated => "stated",
        })
    }
}

/// One number of the output with its unit and where it comes from. `value` is
/// `None` where the figure does not exist (a stroke past pull-in); `note` says why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figure {
    /// Value (SI), or none.
    pub value: Option<f64>,
    /// SI unit (`1` for dimensionless).
    pub unit: String,
    /// Measured, fitted, predicted or stated.
    pub provenance: Provenance,
    /// The file (with line) or the rule it comes from.
    pub source: String,
    /// Why there is no value, or what limits it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Standard error (SI), to first order, from the standard errors the fit files
    /// state and the `± σ` written in the manifest ([`sweep::run`]): values stated
    /// without ± count as exact, so it is a lower bound of the whole uncertainty.
    /// None: no input with a standard error reaches it, or a ±1σ change moves the
    /// candidate into another state (a warning says so).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_error: Option<f64>,
}

impl Figure {
    /// A figure with a value.
    pub fn new(value: f64, unit: &str, provenance: Provenance, source: impl Into<String>) -> Self {
        Figure {
            value: Some(value),
            unit: unit.to_string(),
            provenance,
            source: source.into(),
            note: None,
            std_error: None,
        }
    }

    /// A figure without a value, with the reason.
    pub fn none(
        unit: &str,
        provenance: Provenance,
        source: impl Into<String>,
        why: impl Into<String>,
    ) -> Self {
        Figure {
            value: None,
            unit: unit.to_string(),
            provenance,
            source: source.into(),
            note: Some(why.into()),
            std_error: None,
        }
    }

    /// The same figure with a standard error.
    pub fn with_std_error(mut self, s: Option<f64>) -> Self {
        self.std_error = s;
        self
    }

    /// The same figure with a note.
    pub fn noted(mut self, note: impl Into<String>) -> Self {
        self.note = Some(note.into());
        self
    }
}
