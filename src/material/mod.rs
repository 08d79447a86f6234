//! Constitutive models: hyperelastic strain-energy functions, dielectric mixing
//! laws, linear viscoelasticity (Prony series, Kelvin-Maxwell arms) and the
//! Weibull law of breakdown strength; the
//! material files a scene references (`file`) and the plausibility checks of
//! material constants (`check`), below both the estimators and the simulator.

pub mod breakdown;
pub mod check;
pub mod dielectric;
pub mod file;
pub mod hyperelastic;
pub mod viscoelastic;
