//! Integration tests: one module per area (each helper adds its own `mod` line).

mod cli;
