//! Constitutive models: hyperelastic strain-energy functions (and, later,
//! dielectric laws) and linear viscoelasticity (Prony series, Kelvin-Maxwell arms).

pub mod check;
pub mod dielectric;
pub mod file;
pub mod hyperelastic;
pub mod viscoelastic;
