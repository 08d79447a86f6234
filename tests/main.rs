//! One integration-test binary (fewer links on a 2-core CI): one module per area.

mod bad_cli;
mod bench;
mod cli;
mod completions;
mod datasets;
mod estimation;
mod exit_status;
mod export;
mod fuzz;
mod html_report;
mod identify;
mod identify_mass_fraction;
mod material_file;
mod models;
mod permittivity;
mod rank;
mod relaxation;
mod sampling;
mod scene_input;
mod search;
mod sim;
mod sim_derivatives;
mod sim_sensitivities;
mod sim_stream;
mod support;
mod trace;
