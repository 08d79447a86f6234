//! Reports: SVG charts (plotters) and a Markdown page linking them, plus aligned
//! text tables and SI formatting for terminal output.

pub mod bench;
pub mod format;
pub mod hyperelastic;
pub mod permittivity;
pub mod plot;
pub mod relaxation;
pub mod simulation;
