//! Estimation: least-squares machinery shared by every estimator, and the
//! estimators themselves.

pub mod composite;
pub mod diagnostics;
pub mod drucker;
pub mod hyperelastic;
pub mod identifiability;
pub mod linear;
pub mod lm;
pub mod multistart;
pub mod nnls;
pub mod permittivity;
pub mod problem;
pub mod prony;
pub mod relaxation;
pub mod weibull;

use serde::{Deserialize, Serialize};

/// One fitted parameter, in SI.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// Name (`mu`, `C10`, `alpha1`, ...).
    pub name: String,
    /// Value (SI).
    pub value: f64,
    /// Unit (`Pa`, `1`, ...).
    pub unit: String,
    /// Standard error (None if not identifiable from the data).
    pub std_error: Option<f64>,
    /// 95 % confidence interval (Student t on n − k degrees of freedom).
    pub ci95: Option<[f64; 2]>,
    /// Whether the data pin the parameter down by the one rule
    /// ([`identifiability::RULE`]); None where the estimator does not judge it
    /// (and in files written before it did).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identifiable: Option<bool>,
}

/// Outcome of a fit as a whole. `Err` is kept for unusable input; everything else,
/// including a fit that should not be trusted, is a status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Converged, identifiable, stable over the data: nothing to report.
    Ok,
    /// Usable, with warnings worth reading.
    Warning,
    /// Parameters not identifiable from the data (exponents at bounds, vanishing
    /// terms, singular information matrix).
    IllPosed,
    /// Drucker-unstable within the stretch range of the data.
    Unstable,
    /// The search did not converge.
    NotConverged,
    /// Identified constants that miss, or cannot run, a held-out trace
    /// (`identify --validate`): they fit the traces they came from but do not
    /// predict another measurement of the same actuator.
    NotValidated,
    /// No result: an input could not be used (a batch with a file that failed).
    Failed,
}

impl std::fmt::Display for Status {
    /// The same name the JSON uses (`ok`, `warning`, `ill_posed`, `unstable`,
    /// `not_converged`, `not_validated`, `failed`): the one spelling of a status in every output.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Status::Ok => "ok",
            Status::Warning => "warning",
            Status::IllPosed => "ill_posed",
            Status::Unstable => "unstable",
            Status::NotConverged => "not_converged",
            Status::NotValidated => "not_validated",
            Status::Failed => "failed",
        })
    }
}

impl Status {
    /// Statuses that `--strict` turns into exit status 1.
    pub fn is_blocking(self) -> bool {
        matches!(
            self,
            Status::IllPosed
                | Status::Unstable
                | Status::NotConverged
                | Status::NotValidated
                | Status::Failed
        )
    }

    /// Raise this status by a finding of status `s`: a warning replaces `ok`, and
    /// the first blocking status found stays (later ones do not replace it).
    pub fn escalate(&mut self, s: Status) {
        if *self == Status::Ok || (*self == Status::Warning && s != Status::Warning) {
            *self = s;
        }
    }

    /// The exit status of a command that ends with this status: 1 for a blocking
    /// status under `--strict`, else 0 (README, "Exit status and statuses").
    pub fn exit_code(self, strict: bool) -> i32 {
        i32::from(strict && self.is_blocking())
    }
}

/// What the solver did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolverReport {
    /// Method used.
    pub method: String,
    /// Number of starts of the multi-start search (1 for exact solvers).
    pub starts: usize,
    /// Starts whose search ended at the best objective (within 1e-6 relative).
    pub starts_at_best: usize,
    /// Iterations (summed over starts).
    pub iterations: usize,
    /// Residual evaluations (summed over starts).
    pub evaluations: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Why the final search stopped.
    pub termination: String,
}
