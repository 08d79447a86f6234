//! Elementary functions in straight-line arithmetic, for loops that the compiler
//! keeps in vector registers (the relaxation kernels' lanes, Ogden's stress over a
//! block of points): no call, no branch, the same bits in every lane width.

/// e^x in straight-line arithmetic (no call, no branch), so that a loop over lanes
/// computes it in vector registers; relative error ≤ 3·2⁻⁵³ against the exact
/// value for −708 ≤ x ≤ ln(f64::MAX) ≈ 709.78 (where e^x rounds up past f64::MAX
/// within that error it is +∞); 0 below −708, where e^x < 3.4·10⁻³⁰⁸ (no
/// subnormal results: a kernel multiplying by one would run the processor's slow
/// path), +∞ above ln(f64::MAX), NaN for NaN.
///
/// Cody & Waite's reduction (Muller, *Elementary Functions*, 2016, §11.2):
/// x = k·ln 2 + r with k = round(x/ln 2) (by the 1.5·2⁵² shifter) and |r| ≤ ln 2/2,
/// r = (x − k·ln2_hi) − k·ln2_lo with fdlibm's split of ln 2 (k·ln2_hi exact for
/// |k| < 2²⁰); 2·e^r by Horner on twice its Taylor polynomial of degree 13 (every
/// coefficient doubled, so every step is twice the undoubled one's, exactly);
/// e^x = 2·e^r·2^(k−1) with 2^(k−1) built in the exponent bits (exact while
/// e^x ≥ 2⁻¹⁰²¹·0.7 is normal; 2^(k−1) stays a finite number up to k = 1024,
/// x ≈ 710.1, where 2ᵏ would not). Error: the Taylor remainder |r|¹⁴/14!·e^|r|
/// ≤ 6·10⁻¹⁸ (0.08·2⁻⁵³ of e^r ≥ 0.7), the reduction's rounding ≤ |r|·2⁻⁵³
/// ≤ 0.35·2⁻⁵³, Horner's ≤ 2.4·2⁻⁵³ (the last step's two roundings,
/// 2⁻⁵³·(e^r + |e^r − 1|), plus the inner sum's error ≤ 1.9·2⁻⁵³ scaled by
/// |r| ≤ 0.35, over e^r ≥ 0.7). On −708 ≤ x ≤ 0 these are the bits of the
/// relaxation kernels' former `exp_neg` (e^r·2ᵏ there, the same product exactly).
/// Test `exp_is_exp_to_rounding`.
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    // 1.5·2⁵²: adding it rounds to an integer, kept in the low mantissa bits.
    const SHIFTER: f64 = 6755399441055744.0;
    // fdlibm's ln2_hi (32 significant bits) and ln2_lo = ln 2 − ln2_hi.
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
    // 2/j! for j = 13 down to 0.
    const TWICE_TAYLOR: [f64; 14] = [
        2.0 / 6227020800.0,
        2.0 / 479001600.0,
        2.0 / 39916800.0,
        2.0 / 3628800.0,
        2.0 / 362880.0,
        2.0 / 40320.0,
        2.0 / 5040.0,
        2.0 / 720.0,
        2.0 / 120.0,
        2.0 / 24.0,
        2.0 / 6.0,
        1.0,
        2.0,
        2.0,
    ];
    let z = x * std::f64::consts::LOG2_E + SHIFTER;
    let k = z - SHIFTER;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let mut p = TWICE_TAYLOR[0];
    for c in &TWICE_TAYLOR[1..] {
        p = p * r + c;
    }
    // The shifter's low mantissa bits hold k + 2⁵¹; 2^(k−1) has exponent field
    // k + 1022.
    let bits = z
        .to_bits()
        .wrapping_sub(SHIFTER.to_bits())
        .wrapping_add(1022)
        << 52;
    let e = p * f64::from_bits(bits);
    // Two selects of two values each (a three-way choice is not one the
    // vectoriser turns into blends).
    let e = if x > LN_MAX { f64::INFINITY } else { e };
    if x < -708.0 {
        0.0
    } else {
        e
    }
}

/// ln(f64::MAX), rounded down: e^x is finite up to here.
const LN_MAX: f64 = 709.782712893384;

#[cfg(test)]
mod tests {
    use super::*;

    /// The libm exponential's own error bound (≤ 1 ulp ≤ 2·2⁻⁵³) on top of
    /// [`exp`]'s proven 3·2⁻⁵³: the tolerance of comparing the two.
    const TOL: f64 = 5.0 * f64::EPSILON / 2.0;

    /// [`exp`] is e^x to its proven bound against `f64::exp` (see [`TOL`]) over
    /// −708…ln(f64::MAX) (2·10⁶ even steps, and 10⁴ magnitudes of either sign from
    /// 10⁻³⁰⁰ to 1 where k = 0); exactly 1 at ±0 (a kernel over dt = 0 keeps its
    /// state); the edges: 0 below −708 and at −∞, finite at ln(f64::MAX) and +∞
    /// past it, NaN for NaN.
    #[test]
    fn exp_is_exp_to_rounding() {
        let even =
            (0..=2_000_000).map(|i| (-708.0 + (708.0 + LN_MAX) * i as f64 / 2e6).min(LN_MAX));
        let small = (0..=10_000).map(|i| 10f64.powf(-300.0 + 300.0 * i as f64 / 1e4));
        let mut worst: f64 = 0.0;
        for x in even.chain(small.clone()).chain(small.map(|x| -x)) {
            let want = x.exp();
            let err = (exp(x) - want).abs() / want;
            worst = worst.max(err);
            assert!(err <= TOL, "e^{x}: {} vs {want}", exp(x));
        }
        assert!(worst > 0.0, "compared with a different rounding somewhere");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
        assert_eq!(exp(-708.5), 0.0);
        assert_eq!(exp(-1e6), 0.0);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        let top = exp(LN_MAX);
        assert!(top.is_finite() && (top - LN_MAX.exp()).abs() <= TOL * top);
        for x in [
            LN_MAX + 1e-12,
            709.8,
            710.0,
            710.2,
            745.0,
            1e6,
            f64::INFINITY,
        ] {
            assert_eq!(exp(x), f64::INFINITY, "e^{x}");
        }
        assert!(exp(f64::NAN).is_nan());
    }
}
