//! The single integration-test binary; each subsystem is a module.

mod permittivity;
