//! Helical actuator geometry (seed Chapter 4, Eq. 4.1–4.22, 4.47).
//!
//! Generalised coordinate: λ = z/z0, the vertical thickness stretch of an element.
//! Pitch P = Ne·z (4.1), height Z_T = Np·P (4.2), slant c = P/2π.
//! * Complementary angle: the exact helix gives tan α = 2πR/P at radius R; we use the
//!   mean radius Rm = (Ro + Ri)/2. The seed's Eq. 4.4 writes atan(4·Ro/P);
//!   [`HelixGeometry::elatrache2021_alpha`] gives it for comparison.
//! * Electrode gap h = z·sin α (4.3); electrode area of one period Eq. 4.12.
//! * Volume: an element is an annulus sheared along z, so its volume is exactly
//!   π(Ro² − Ri²)·z (Cavalieri). With Eq. 4.18 (Ro and Ri move oppositely, Rm fixed)
//!   conservation gives the width w = w0/λ in closed form; the seed's Eq. 4.20 uses
//!   A_e·z (helicoid area × vertical thickness), which over-counts the volume by
//!   ≈ c²/(2R²) (≈ 1e-4 here) and needs a root solve each step — we do not need it.
//! * Lateral kinematics: `planar` (Eq. 4.18: the hoop length at Rm is fixed, the
//!   material is in planar compression) or `free` (Rm and w scale as λ^-1/2: the
//!   equibiaxial state of a stack layer; then α → π/2 reduces the helix to a stack).
//! * Capacitance Eq. 4.47: C = ε·A_e·Np·Ne/h.

use super::scene::{HelixGeometry, Lateral};
use std::f64::consts::PI;

impl HelixGeometry {
    /// Reference height Z_T0 = Np·Ne·z0 (m).
    pub fn length0(&self) -> f64 {
        (self.periods * self.per_period) as f64 * self.thickness_m
    }
    /// Annulus area π(Ro0² − Ri0²) (m²).
    pub fn area0(&self) -> f64 {
        PI * (self.outer_m.powi(2) - self.inner_m.powi(2))
    }
    /// Elastomer volume Np·Ne·π(Ro0² − Ri0²)·z0 (m³).
    pub fn volume(&self) -> f64 {
        self.area0() * self.length0()
    }
    /// (Ro, Ri, c) at stretch λ.
    pub fn radii(&self, lam: f64) -> (f64, f64, f64) {
        let rm0 = 0.5 * (self.outer_m + self.inner_m);
        let w0 = self.outer_m - self.inner_m;
        let (rm, w) = match self.lateral {
            Lateral::Planar => (rm0, w0 / lam),
            Lateral::Free => (rm0 / lam.sqrt(), w0 / lam.sqrt()),
        };
        let c = self.per_period as f64 * self.thickness_m * lam / (2.0 * PI);
        (rm + 0.5 * w, rm - 0.5 * w, c)
    }
    /// Complementary angle α at the mean radius: tan α = Rm/c = 2πRm/P.
    pub fn alpha(&self, lam: f64) -> f64 {
        let (ro, ri, c) = self.radii(lam);
        (0.5 * (ro + ri)).atan2(c)
    }
    /// The seed's Eq. 4.4: α = atan(4·Ro/P).
    pub fn elatrache2021_alpha(&self, lam: f64) -> f64 {
        let (ro, _, c) = self.radii(lam);
        (4.0 * ro).atan2(2.0 * PI * c)
    }
    /// Electrode area of one period, Eq. 4.12.
    pub fn electrode_area(&self, lam: f64) -> f64 {
        let (ro, ri, c) = self.radii(lam);
        let so = (ro * ro + c * c).sqrt();
        let si = (ri * ri + c * c).sqrt();
        PI * (ro * so - ri * si + c * c * ((ro + so) / (ri + si)).ln())
    }
    fn cap(&self, eps: f64, lam: f64) -> f64 {
        let h = self.thickness_m * lam * self.alpha(lam).sin();
        eps * self.electrode_area(lam) * (self.periods * self.per_period) as f64 / h
    }
    /// Capacitance (Eq. 4.47) and its first two λ-derivatives (5-point stencils).
    pub fn capacitance(&self, eps: f64, lam: f64) -> (f64, f64, f64) {
        let d = 1e-3 * lam;
        let c0 = self.cap(eps, lam);
        let (p1, m1) = (self.cap(eps, lam + d), self.cap(eps, lam - d));
        let (p2, m2) = (self.cap(eps, lam + 2.0 * d), self.cap(eps, lam - 2.0 * d));
        let d1 = (m2 - 8.0 * m1 + 8.0 * p1 - p2) / (12.0 * d);
        let d2 = (-m2 + 16.0 * m1 - 30.0 * c0 + 16.0 * p1 - p2) / (12.0 * d * d);
        (c0, d1, d2)
    }
}
