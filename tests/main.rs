//! One integration-test binary (fewer links on a 2-core CI): one module per area.

mod estimation;
mod models;
mod sim;
