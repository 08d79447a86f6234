//! Reports: SVG charts (plotters) and a Markdown page linking them, plus aligned
//! text tables and SI formatting for terminal output.

pub mod bench;
pub mod format;
pub mod hyperelastic;
pub mod identify;
pub mod permittivity;
pub mod plot;
pub mod relaxation;
pub mod simulation;

/// The closing Markdown sections every fit page has: warnings, then the solver report.
pub fn warnings_and_solver(warnings: &[String], solver: &crate::fit::SolverReport) -> String {
    let mut s = String::new();
    if !warnings.is_empty() {
        s.push_str("\n## Warnings\n\n");
        for w in warnings {
            s.push_str(&format!("- {w}\n"));
        }
    }
    s.push_str(&format!(
        "\n## Solver\n\n{}; {} start(s), {} at the best objective; {} iterations, {} evaluations, {:.3} ms; {}.\n",
        solver.method,
        solver.starts,
        solver.starts_at_best,
        solver.iterations,
        solver.evaluations,
        solver.seconds * 1e3,
        solver.termination
    ));
    s
}
