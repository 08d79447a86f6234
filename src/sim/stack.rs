//! Multilayer stack geometry (seed Chapter 3, Eq. 3.2–3.3, 3.8, 3.22).
//!
//! Generalised coordinate: the thickness stretch λ = zd/zd0 of the layers. The
//! electrodes follow the elastomer (Eq. 3.3): Z_T = (nd·zd0 + ne·ze0)·λ, and — to keep
//! the model energy-consistent — they are taken to be of the elastomer's material
//! (the seed: they "deform equally as the elastomeric film"), so the strained volume
//! is π r0²·Z_T0 while the field acts in the nd dielectric layers only.
//! Incompressible, free lateral faces: r = r0·λ^-1/2, so A_e = π r0²/λ and
//! C = nd·ε·A_e/zd = nd·ε·π r0²/(zd0·λ²) (Eq. 3.22).

use super::scene::StackGeometry;

impl StackGeometry {
    /// Reference length Z_T0 = nd·zd0 + ne·ze0 (m).
    pub fn length0(&self) -> f64 {
        self.layers as f64 * self.layer_m + self.electrodes as f64 * self.electrode_m
    }
    /// Reference electrode area π r0² (m²).
    pub fn area0(&self) -> f64 {
        std::f64::consts::PI * self.radius_m * self.radius_m
    }
    /// Strained volume (m³).
    pub fn volume(&self) -> f64 {
        self.area0() * self.length0()
    }
    /// Capacitance and its first two λ-derivatives for permittivity `eps` (F/m).
    #[inline(always)]
    pub fn capacitance(&self, eps: f64, lam: f64) -> (f64, f64, f64) {
        let c = self.layers as f64 * eps * self.area0() / (self.layer_m * lam * lam);
        (c, -2.0 * c / lam, 6.0 * c / (lam * lam))
    }
}
