//! Constitutive models: hyperelastic strain-energy functions (and, later,
//! viscoelastic and dielectric laws).

pub mod dielectric;
pub mod hyperelastic;
