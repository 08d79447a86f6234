//! Reports: SVG charts (plotters) and pages describing a run ([`page::Page`]), each
//! written as Markdown and as self-contained HTML, with the folder's run list
//! ([`runs`]); plus aligned text tables and SI formatting for terminal output.

pub mod bench;
pub mod breakdown;
pub mod format;
pub mod hyperelastic;
pub mod identify;
pub mod page;
pub mod permittivity;
pub mod plot;
pub mod relaxation;
pub mod runs;
pub mod simulation;
pub mod static_curve;

/// The closing sections every fit page has: warnings, then the solver report (the
/// method and how it ended; the work and its time).
pub fn warnings_and_solver(
    page: &mut page::Page,
    warnings: &[String],
    solver: &crate::fit::SolverReport,
) {
    page.warnings(warnings);
    page.heading("Solver");
    page.text(format!("{}; {}.", solver.method, solver.termination));
    page.text(format!(
        "{} start(s), {} at the best objective; {} iterations, {} evaluations, {:.3} ms.",
        solver.starts,
        solver.starts_at_best,
        solver.iterations,
        solver.evaluations,
        solver.seconds * 1e3,
    ));
}
