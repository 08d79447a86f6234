//! An identification without a result (status `failed`): no start could simulate
//! the traces, each start with its reason, or the best constants could not be
//! simulated again. Unusable input is an `Err` before any search instead: a refused
//! trace, scene or setting, and a scene the simulator refuses to start on a trace at
//! its own constants ([`super::identify_with`]).

use super::problem::Problem;
use super::SolverSummary;
use crate::fit::lm::Termination;
use crate::fit::multistart::MultiStart;
use crate::fit::Status;
use serde::Serialize;

/// A free constant's value at a start.
#[derive(Debug, Clone, Serialize)]
pub struct StartValue {
    /// Name.
    pub name: String,
    /// Value (SI).
    pub value: f64,
    /// SI unit.
    pub unit: String,
}

/// A start the search could not go on from.
#[derive(Debug, Clone, Serialize)]
pub struct FailedStart {
    /// Index of the start (0: the scene's own constants).
    pub start: usize,
    /// The free constants there.
    pub constants: Vec<StartValue>,
    /// Why the traces could not be simulated there (or the search not run).
    pub reason: String,
}

/// A failed identification: nothing was estimated, and no material file is written.
#[derive(Debug, Clone, Serialize)]
pub struct Failure {
    /// Always [`Status::Failed`].
    pub status: Status,
    /// What failed, in words.
    pub reason: String,
    /// What to do about it.
    pub hint: String,
    /// The free constants.
    pub free: Vec<String>,
    /// The starts that failed (every start, when none could be searched from).
    pub starts: Vec<FailedStart>,
    /// What the search did.
    pub solver: SolverSummary,
}

impl Failure {
    /// No start of `ms` could be searched from: each start's constants and reason.
    pub fn no_start(problem: &Problem, ms: &MultiStart, solver: SolverSummary) -> Failure {
        let starts: Vec<FailedStart> = ms
            .runs
            .iter()
            .enumerate()
            .map(|(i, (_, res))| FailedStart {
                start: i,
                constants: problem
                    .free
                    .iter()
                    .zip(&res.x)
                    .map(|(c, &x)| StartValue {
                        name: c.name.clone(),
                        value: c.space.theta(x),
                        unit: c.unit.to_string(),
                    })
                    .collect(),
                reason: match &res.termination {
                    Termination::Failed(why) => why.clone(),
                    other => other.to_string(),
                },
            })
            .collect();
        Failure {
            status: Status::Failed,
            reason: format!(
                "no start could simulate the traces: all {} failed at their start",
                starts.len()
            ),
            hint: "the scene with these constants does not run the traces' drive (a pull-in or a failed run at every start): free the constants that set the response (the moduli, eps_r), start from constants nearer the actuator's, or check the scene's geometry and load".into(),
            free: free(problem),
            starts,
            solver,
        }
    }

    /// The best constants of the search could not be simulated again (`why`).
    pub fn at_best(problem: &Problem, why: String, solver: SolverSummary) -> Failure {
        Failure {
            status: Status::Failed,
            reason: format!("the best constants could not be simulated again: {why}"),
            hint: "the search simulated these constants, so this is a defect of dea-fit: report it with the command and files".into(),
            free: free(problem),
            starts: Vec::new(),
            solver,
        }
    }
}

/// The names of the free constants.
fn free(problem: &Problem) -> Vec<String> {
    problem.free.iter().map(|c| c.name.clone()).collect()
}
