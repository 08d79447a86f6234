//! Dielectric relations: the parallel-plate capacitor, conversions between the
//! impedance/admittance pairs LCR meters report, the complex permittivity of a
//! coupon, Kirchhoff's edge capacitance, weight↔volume fractions, the mixing rules
//! of two-phase composites with their derivatives, and a composite's εr as a
//! function of its filler mass fraction ([`Mixture`]). SI throughout (F, m, m², Hz,
//! Ω, S, kg/m³).

use nalgebra::Complex;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Vacuum permittivity ε0 (F/m), CODATA 2018.
pub const EPS0: f64 = 8.854_187_812_8e-12;

/// Parallel-plate capacitance C = ε0·εr·A/d (seed Eq. 5.1–5.2), fringe field ignored.
pub fn parallel_plate_capacitance(eps_r: f64, area: f64, thickness: f64) -> f64 {
    EPS0 * eps_r * area / thickness
}

/// Relative permittivity from a parallel-plate capacitance: εr = C·d/(ε0·A)
/// (seed Eq. 5.2 solved for εr).
pub fn eps_r_from_capacitance(c: f64, area: f64, thickness: f64) -> f64 {
    c * thickness / (EPS0 * area)
}

/// Kirchhoff's edge (fringe) capacitance of two equal circular plates of radius `r`
/// at gap `d` in vacuum, the second term of Kirchhoff's (1877) formula
/// C = ε0·[π r²/d + r·(ln(16π r/d) − 1)], valid for d ≪ r (also the basis of the
/// edge correction for unguarded electrodes in ASTM D150).
pub fn kirchhoff_edge_capacitance(radius: f64, thickness: f64) -> f64 {
    EPS0 * radius * ((16.0 * PI * radius / thickness).ln() - 1.0)
}

/// The pair of quantities an LCR meter or impedance analyser reports per frequency.
/// Series (s) and parallel (p) equivalent circuits are converted exactly through the
/// complex admittance Y = G + jB (Z = 1/Y = R + jX).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pair {
    /// Parallel capacitance and dissipation factor: Y = ωCp·D + jωCp.
    CpD,
    /// Parallel capacitance and quality factor Q = 1/D.
    CpQ,
    /// Parallel capacitance and parallel conductance: Y = G + jωCp.
    CpG,
    /// Parallel capacitance and parallel resistance: Y = 1/Rp + jωCp.
    CpRp,
    /// Series capacitance and dissipation factor: Z = D/(ωCs) − j/(ωCs).
    CsD,
    /// Series capacitance and quality factor Q = 1/D.
    CsQ,
    /// Series capacitance and series resistance: Z = Rs − j/(ωCs).
    CsRs,
    /// Series inductance and series resistance: Z = Rs + jωLs.
    LsRs,
    /// Parallel inductance and parallel resistance: Y = 1/Rp − j/(ωLp).
    LpRp,
    /// Resistance and reactance: Z = R + jX.
    RX,
    /// Impedance magnitude and phase (radians inside): Z = |Z|·e^{jθ}.
    ZTheta,
    /// Conductance and susceptance: Y = G + jB.
    GB,
    /// Admittance magnitude and phase (radians inside): Y = |Y|·e^{jθ}.
    YTheta,
}

impl Pair {
    /// Every pair.
    pub const ALL: [Pair; 13] = [
        Pair::CpD,
        Pair::CpQ,
        Pair::CpG,
        Pair::CpRp,
        Pair::CsD,
        Pair::CsQ,
        Pair::CsRs,
        Pair::LsRs,
        Pair::LpRp,
        Pair::RX,
        Pair::ZTheta,
        Pair::GB,
        Pair::YTheta,
    ];

    /// Name as a user writes it (`cp-d`, `z-theta`, …).
    pub fn name(self) -> &'static str {
        match self {
            Pair::CpD => "cp-d",
            Pair::CpQ => "cp-q",
            Pair::CpG => "cp-g",
            Pair::CpRp => "cp-rp",
            Pair::CsD => "cs-d",
            Pair::CsQ => "cs-q",
            Pair::CsRs => "cs-rs",
            Pair::LsRs => "ls-rs",
            Pair::LpRp => "lp-rp",
            Pair::RX => "r-x",
            Pair::ZTheta => "z-theta",
            Pair::GB => "g-b",
            Pair::YTheta => "y-theta",
        }
    }

    /// Parse a pair name; also accepts the E4980A function names (`CPD`, `CSRS`,
    /// `ZTD`, …; `ZTR`/`YTR` are the radian variants, see [`Pair::degrees`]).
    pub fn parse(s: &str) -> Option<(Pair, bool)> {
        let k: String = s
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .collect::<String>()
            .to_ascii_lowercase();
        let deg = !matches!(k.as_str(), "ztr" | "ytr" | "zthetarad" | "ythetarad");
        let p = match k.as_str() {
            "cpd" => Pair::CpD,
            "cpq" => Pair::CpQ,
            "cpg" => Pair::CpG,
            "cprp" => Pair::CpRp,
            "csd" => Pair::CsD,
            "csq" => Pair::CsQ,
            "csrs" => Pair::CsRs,
            "lsrs" => Pair::LsRs,
            "lprp" => Pair::LpRp,
            "rx" => Pair::RX,
            "ztheta" | "ztd" | "ztr" | "zthetadeg" | "zthetarad" => Pair::ZTheta,
            "gb" => Pair::GB,
            "ytheta" | "ytd" | "ytr" | "ythetadeg" | "ythetarad" => Pair::YTheta,
            _ => return None,
        };
        Some((p, deg))
    }

    /// Whether the pair's second quantity is an angle.
    pub fn has_angle(self) -> bool {
        matches!(self, Pair::ZTheta | Pair::YTheta)
    }

    /// Complex admittance Y = G + jB (S) of a reading (a, b) at angular frequency
    /// ω = 2πf (rad/s). Angles in radians.
    pub fn to_admittance(self, a: f64, b: f64, omega: f64) -> Complex<f64> {
        let z = |r: f64, x: f64| Complex::new(r, x).inv();
        match self {
            Pair::CpD => Complex::new(omega * a * b, omega * a),
            Pair::CpQ => Complex::new(omega * a / b, omega * a),
            Pair::CpG => Complex::new(b, omega * a),
            Pair::CpRp => Complex::new(1.0 / b, omega * a),
            Pair::CsD => z(b / (omega * a), -1.0 / (omega * a)),
            Pair::CsQ => z(1.0 / (b * omega * a), -1.0 / (omega * a)),
            Pair::CsRs => z(b, -1.0 / (omega * a)),
            Pair::LsRs => z(b, omega * a),
            Pair::LpRp => Complex::new(1.0 / b, -1.0 / (omega * a)),
            Pair::RX => z(a, b),
            Pair::ZTheta => Complex::from_polar(a, b).inv(),
            Pair::GB => Complex::new(a, b),
            Pair::YTheta => Complex::from_polar(a, b),
        }
    }

    /// The reading (a, b) this pair gives for admittance `y` at ω: the inverse of
    /// [`Pair::to_admittance`]. Angles in radians.
    pub fn from_admittance(self, y: Complex<f64>, omega: f64) -> (f64, f64) {
        let z = y.inv();
        let cs = -1.0 / (omega * z.im);
        match self {
            Pair::CpD => (y.im / omega, y.re / y.im),
            Pair::CpQ => (y.im / omega, y.im / y.re),
            Pair::CpG => (y.im / omega, y.re),
            Pair::CpRp => (y.im / omega, 1.0 / y.re),
            Pair::CsD => (cs, z.re * omega * cs),
            Pair::CsQ => (cs, 1.0 / (z.re * omega * cs)),
            Pair::CsRs => (cs, z.re),
            Pair::LsRs => (z.im / omega, z.re),
            Pair::LpRp => (-1.0 / (omega * y.im), 1.0 / y.re),
            Pair::RX => (z.re, z.im),
            Pair::ZTheta => (z.norm(), z.arg()),
            Pair::GB => (y.re, y.im),
            Pair::YTheta => (y.norm(), y.arg()),
        }
    }
}

/// Complex relative permittivity ε* = ε′ − jε″ of a coupon whose gap (empty)
/// capacitance is `c0` = ε0·A/d, from its admittance: ε* = Y/(jω·C0), so
/// ε′ = B/(ω C0) = Cp/C0 and ε″ = G/(ω C0); tan δ = ε″/ε′ = G/B = D (IEC 60250).
pub fn complex_permittivity(y: Complex<f64>, omega: f64, c0: f64) -> (f64, f64) {
    (y.im / (omega * c0), y.re / (omega * c0))
}

/// AC conductivity σ = ω·ε0·ε″ (S/m).
pub fn ac_conductivity(eps_loss: f64, omega: f64) -> f64 {
    omega * EPS0 * eps_loss
}

/// Filler volume fraction from its weight fraction w and the densities of filler
/// and matrix: φ = (w/ρf) / (w/ρf + (1 − w)/ρm).
pub fn volume_fraction(w: f64, rho_filler: f64, rho_matrix: f64) -> f64 {
    let vf = w / rho_filler;
    vf / (vf + (1.0 - w) / rho_matrix)
}

/// dφ/dw of [`volume_fraction`]: with u = w/ρf and v = (1 − w)/ρm, φ = u/(u + v) and
/// dφ/dw = (u′v − uv′)/(u + v)² = 1/(ρf·ρm·(u + v)²).
pub fn dvolume_fraction_dw(w: f64, rho_filler: f64, rho_matrix: f64) -> f64 {
    let s = w / rho_filler + (1.0 - w) / rho_matrix;
    1.0 / (rho_filler * rho_matrix * s * s)
}

/// Filler weight fraction from its volume fraction (inverse of [`volume_fraction`]):
/// w = φρf / (φρf + (1 − φ)ρm).
pub fn weight_fraction(phi: f64, rho_filler: f64, rho_matrix: f64) -> f64 {
    let mf = phi * rho_filler;
    mf / (mf + (1.0 - phi) * rho_matrix)
}

/// A two-phase mixing rule: εr of a composite from εm (matrix), εf (filler) and the
/// filler volume fraction φ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MixingRule {
    /// Maxwell Garnett (spherical inclusions, dilute):
    /// ε = εm·(εf + 2εm + 2φ(εf − εm)) / (εf + 2εm − φ(εf − εm)).
    MaxwellGarnett,
    /// Symmetric Bruggeman effective-medium approximation:
    /// φ(εf − ε)/(εf + 2ε) + (1 − φ)(εm − ε)/(εm + 2ε) = 0, the positive root.
    Bruggeman,
    /// Lichtenecker's logarithmic rule: ln ε = φ ln εf + (1 − φ) ln εm.
    Lichtenecker,
    /// Looyenga (1965): ε^(1/3) = φ εf^(1/3) + (1 − φ) εm^(1/3).
    Looyenga,
    /// Yamada et al. (1982) with shape factor n (n = 3: Maxwell Garnett):
    /// ε = εm·[1 + nφ(εf − εm) / (n εm + (εf − εm)(1 − φ))].
    Yamada,
    /// Jayasundere & Smith (1993):
    /// ε = [εm(1−φ) + εf φ a] / [(1−φ) + φ a], a = 3εm/(εf+2εm)·[1 + 3φ(εf−εm)/(εf+2εm)].
    JayasundereSmith,
}

impl MixingRule {
    /// Every rule.
    pub const ALL: [MixingRule; 6] = [
        MixingRule::MaxwellGarnett,
        MixingRule::Bruggeman,
        MixingRule::Lichtenecker,
        MixingRule::Looyenga,
        MixingRule::Yamada,
        MixingRule::JayasundereSmith,
    ];

    /// Name as written in files and flags.
    pub fn name(self) -> &'static str {
        match self {
            MixingRule::MaxwellGarnett => "maxwell-garnett",
            MixingRule::Bruggeman => "bruggeman",
            MixingRule::Lichtenecker => "lichtenecker",
            MixingRule::Looyenga => "looyenga",
            MixingRule::Yamada => "yamada",
            MixingRule::JayasundereSmith => "jayasundere-smith",
        }
    }

    /// Parse a rule name.
    pub fn parse(s: &str) -> Option<MixingRule> {
        Self::ALL.into_iter().find(|r| r.name() == s.trim())
    }

    /// Whether the rule has a shape parameter (Yamada's n).
    pub fn has_shape(self) -> bool {
        self == MixingRule::Yamada
    }

    /// Composite εr. `shape` is Yamada's n (ignored by the other rules).
    pub fn eval(self, eps_m: f64, eps_f: f64, phi: f64, shape: f64) -> f64 {
        let d = eps_f - eps_m;
        match self {
            MixingRule::MaxwellGarnett => {
                eps_m * (eps_f + 2.0 * eps_m + 2.0 * phi * d) / (eps_f + 2.0 * eps_m - phi * d)
            }
            MixingRule::Bruggeman => {
                let b = (3.0 * phi - 1.0) * eps_f + (2.0 - 3.0 * phi) * eps_m;
                (b + (b * b + 8.0 * eps_f * eps_m).sqrt()) / 4.0
            }
            MixingRule::Lichtenecker => (phi * eps_f.ln() + (1.0 - phi) * eps_m.ln()).exp(),
            MixingRule::Looyenga => (phi * eps_f.cbrt() + (1.0 - phi) * eps_m.cbrt()).powi(3),
            MixingRule::Yamada => {
                eps_m * (1.0 + shape * phi * d / (shape * eps_m + d * (1.0 - phi)))
            }
            MixingRule::JayasundereSmith => {
                let s = eps_f + 2.0 * eps_m;
                let a = 3.0 * eps_m / s * (1.0 + 3.0 * phi * d / s);
                (eps_m * (1.0 - phi) + eps_f * phi * a) / ((1.0 - phi) + phi * a)
            }
        }
    }

    /// ∂ε/∂φ of [`MixingRule::eval`] at φ (εm, εf, shape fixed), in closed form, with
    /// d = εf − εm:
    /// * Maxwell Garnett: 3εm·d·A/(A − φd)², A = εf + 2εm;
    /// * Bruggeman: ¾d·(1 + b/√(b² + 8εfεm)), b = (3φ − 1)εf + (2 − 3φ)εm;
    /// * Lichtenecker: ε·ln(εf/εm);
    /// * Looyenga: 3s²·(εf^⅓ − εm^⅓), s = φεf^⅓ + (1 − φ)εm^⅓;
    /// * Yamada: εm·n·d·(nεm + d)/(nεm + d(1 − φ))²;
    /// * Jayasundere–Smith: ε = N/M with N = εm(1 − φ) + εfφa, M = 1 − φ + φa, so
    ///   ε′ = (N′ − εM′)/M with a′ = 9εm·d/S², S = εf + 2εm, N′ = εf(a + φa′) − εm,
    ///   M′ = a + φa′ − 1.
    pub fn deps_dphi(self, eps_m: f64, eps_f: f64, phi: f64, shape: f64) -> f64 {
        let d = eps_f - eps_m;
        match self {
            MixingRule::MaxwellGarnett => {
                let a = eps_f + 2.0 * eps_m;
                3.0 * eps_m * d * a / (a - phi * d).powi(2)
            }
            MixingRule::Bruggeman => {
                let b = (3.0 * phi - 1.0) * eps_f + (2.0 - 3.0 * phi) * eps_m;
                0.75 * d * (1.0 + b / (b * b + 8.0 * eps_f * eps_m).sqrt())
            }
            MixingRule::Lichtenecker => {
                self.eval(eps_m, eps_f, phi, shape) * (eps_f.ln() - eps_m.ln())
            }
            MixingRule::Looyenga => {
                let s = phi * eps_f.cbrt() + (1.0 - phi) * eps_m.cbrt();
                3.0 * s * s * (eps_f.cbrt() - eps_m.cbrt())
            }
            MixingRule::Yamada => {
                let n = shape;
                eps_m * n * d * (n * eps_m + d) / (n * eps_m + d * (1.0 - phi)).powi(2)
            }
            MixingRule::JayasundereSmith => {
                let s = eps_f + 2.0 * eps_m;
                let a = 3.0 * eps_m / s * (1.0 + 3.0 * phi * d / s);
                let da = 9.0 * eps_m * d / (s * s);
                let m = (1.0 - phi) + phi * a;
                let eps = self.eval(eps_m, eps_f, phi, shape);
                let dn = eps_f * (a + phi * da) - eps_m;
                let dm = a + phi * da - 1.0;
                (dn - eps * dm) / m
            }
        }
    }

    /// Filler permittivity εf for which the rule gives `eps` at φ (εm, shape fixed),
    /// searched in [εm, 1e9] by bisection on ln εf; `None` if even εf = 1e9 does not
    /// reach `eps` (or `eps` ≤ εm).
    pub fn filler_for(self, eps_m: f64, phi: f64, shape: f64, eps: f64) -> Option<f64> {
        let f = |ef: f64| self.eval(eps_m, ef, phi, shape) - eps;
        let (mut lo, mut hi) = (eps_m.ln(), 1e9f64.ln());
        if f(lo.exp()) > 0.0 || f(hi.exp()) < 0.0 {
            return None;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid.exp()) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo < 1e-13 {
                break;
            }
        }
        Some((0.5 * (lo + hi)).exp())
    }
}

/// εr of a two-phase composite as a function of its filler mass fraction w: the
/// volume fraction φ(w) from the phase densities ([`volume_fraction`]), then a mixing
/// rule εr(φ) with the matrix and filler permittivities (and Yamada's n) that a
/// composite fit found at one frequency (`dea-fit composite`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Mixture {
    /// The rule.
    pub rule: MixingRule,
    /// Matrix permittivity εm.
    pub eps_matrix: f64,
    /// Filler permittivity εf (the effective value the rule was fitted with).
    pub eps_filler: f64,
    /// Yamada's shape factor n (unused by the other rules).
    pub shape_n: f64,
    /// Matrix density ρm (kg/m³).
    #[serde(rename = "matrix_density_kg_per_m3")]
    pub rho_matrix: f64,
    /// Filler density ρf (kg/m³).
    #[serde(rename = "filler_density_kg_per_m3")]
    pub rho_filler: f64,
}

impl Mixture {
    /// εr(w) = rule(εm, εf, φ(w), n).
    pub fn eps_r(&self, w: f64) -> f64 {
        let phi = volume_fraction(w, self.rho_filler, self.rho_matrix);
        self.rule
            .eval(self.eps_matrix, self.eps_filler, phi, self.shape_n)
    }

    /// dεr/dw = ∂εr/∂φ · dφ/dw ([`MixingRule::deps_dphi`], [`dvolume_fraction_dw`]),
    /// exact.
    pub fn deps_dw(&self, w: f64) -> f64 {
        let phi = volume_fraction(w, self.rho_filler, self.rho_matrix);
        self.rule
            .deps_dphi(self.eps_matrix, self.eps_filler, phi, self.shape_n)
            * dvolume_fraction_dw(w, self.rho_filler, self.rho_matrix)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yamada_with_n3_is_maxwell_garnett() {
        for phi in [0.0, 0.1, 0.37, 0.9] {
            let a = MixingRule::Yamada.eval(2.7, 150.0, phi, 3.0);
            let b = MixingRule::MaxwellGarnett.eval(2.7, 150.0, phi, 0.0);
            assert!((a - b).abs() < 1e-12 * b, "{phi}: {a} vs {b}");
        }
    }

    #[test]
    fn filler_for_inverts_eval() {
        for r in MixingRule::ALL {
            let e = r.eval(2.72, 120.0, 0.15, 4.0);
            let ef = r.filler_for(2.72, 0.15, 4.0, e).unwrap();
            assert!((ef - 120.0).abs() < 1e-7 * 120.0, "{}: {ef}", r.name());
        }
    }

    /// The chained derivative dεr/dw of every rule against a central difference
    /// (h = 10⁻⁶ in w: truncation ≈ h²·ε‴/6 ≈ 10⁻¹¹ and rounding ≈ 10⁻¹⁶·ε/h ≈
    /// 10⁻⁹ relative, so 10⁻⁷ relative is a stated margin), over the mass fractions
    /// of a composite series (BaTiO3 in Sylgard: ρf = 6020, ρm = 1030 kg/m³).
    #[test]
    fn chained_mass_fraction_derivative_matches_a_finite_difference() {
        for rule in MixingRule::ALL {
            let m = Mixture {
                rule,
                eps_matrix: 2.72,
                eps_filler: 150.0,
                shape_n: 4.6,
                rho_matrix: 1030.0,
                rho_filler: 6020.0,
            };
            for w in [0.0, 0.05, 0.2, 0.45, 0.7, 0.95] {
                let h = 1e-6;
                let (lo, hi) = if w == 0.0 {
                    (w, w + 2.0 * h)
                } else {
                    (w - h, w + h)
                };
                let fd = (m.eps_r(hi) - m.eps_r(lo)) / (hi - lo);
                let at = 0.5 * (lo + hi);
                let exact = m.deps_dw(at);
                assert!(
                    (exact - fd).abs() <= 1e-7 * exact.abs().max(1.0),
                    "{} at w = {w}: {exact} vs {fd}",
                    rule.name()
                );
            }
        }
    }
}
