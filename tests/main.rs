//! The integration-test binary: one module per subsystem.

mod relaxation;
