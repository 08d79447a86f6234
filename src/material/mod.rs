//! Constitutive models: hyperelastic strain-energy functions, dielectric mixing
//! laws and linear viscoelasticity (Prony series, Kelvin-Maxwell arms); the
//! material files a scene references (`file`) and the plausibility checks of
//! material constants (`check`), below both the estimators and the simulator.

pub mod check;
pub mod dielectric;
pub mod file;
pub mod hyperelastic;
pub mod viscoelastic;
