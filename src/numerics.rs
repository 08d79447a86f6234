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
/// Test `exp_is_exp_to_rounding`. [`ExpTable::exp`] is the same arithmetic with
/// its constants read from a table (a loop over lanes).
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    ExpTable::<1>::SPLAT.exp(x, 0)
}

/// The floating-point constants of [`exp`], each repeated across `L` lanes. A loop
/// over `L` lanes that reads them from a table in memory the compiler cannot see
/// into (`std::hint::black_box(&ExpTable::<L>::SPLAT)`) takes each as an operand
/// straight from memory; with constants it knows, the compiler (lacking registers
/// for all twenty) loads every one again into a register, one broadcast an
/// operation: ≈ 20 instructions of the ≈ 55 of an exponential of four lanes.
/// The arithmetic is the same either way, so the same bits
/// (test `table_exp_is_exp_bit_for_bit`).
#[derive(Debug, Clone, Copy)]
pub struct ExpTable<const L: usize> {
    log2e: [f64; L],
    shifter: [f64; L],
    ln2_hi: [f64; L],
    ln2_lo: [f64; L],
    twice_taylor: [[f64; L]; 14],
    ln_max: [f64; L],
    lowest: [f64; L],
    infinity: [f64; L],
}

/// 1.5·2⁵²: adding it rounds to an integer, kept in the low mantissa bits.
const SHIFTER: f64 = 6755399441055744.0;

/// 2/j! for j = 13 down to 0.
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

/// Below this, [`exp`] is 0.
const LOWEST: f64 = -708.0;

impl<const L: usize> ExpTable<L> {
    /// Every constant in every lane.
    pub const SPLAT: ExpTable<L> = {
        let mut twice_taylor = [[0.0; L]; 14];
        let mut j = 0;
        while j < 14 {
            twice_taylor[j] = [TWICE_TAYLOR[j]; L];
            j += 1;
        }
        ExpTable {
            log2e: [std::f64::consts::LOG2_E; L],
            shifter: [SHIFTER; L],
            // fdlibm's ln2_hi (32 significant bits) and ln2_lo = ln 2 − ln2_hi.
            ln2_hi: [f64::from_bits(0x3fe6_2e42_fee0_0000); L],
            ln2_lo: [f64::from_bits(0x3dea_39ef_3579_3c76); L],
            twice_taylor,
            ln_max: [LN_MAX; L],
            lowest: [LOWEST; L],
            infinity: [f64::INFINITY; L],
        }
    };

    /// [`exp`] of `x` with the constants of lane `i`.
    #[inline(always)]
    pub fn exp(&self, x: f64, i: usize) -> f64 {
        let shifter = self.shifter[i];
        let z = x * self.log2e[i] + shifter;
        let k = z - shifter;
        let r = (x - k * self.ln2_hi[i]) - k * self.ln2_lo[i];
        let mut p = self.twice_taylor[0][i];
        for c in &self.twice_taylor[1..] {
            p = p * r + c[i];
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
        let e = if x > self.ln_max[i] {
            self.infinity[i]
        } else {
            e
        };
        if x < self.lowest[i] {
            0.0
        } else {
            e
        }
    }
}

/// ln(f64::MAX), rounded down: e^x is finite up to here.
const LN_MAX: f64 = 709.782712893384;

/// Below this x, [`one_minus_exp_neg`] takes its Taylor series instead of 1 − a.
const SERIES_BELOW: f64 = 1.0 / 16.0;

/// 1 − e^(−x) for x ≥ 0, given `a` = e^(−x) from [`exp`], in straight-line
/// arithmetic (two values and a select, which the vectoriser turns into a blend),
/// without the cancellation of 1 − a at small x: there a's rounding (≤ 3·2⁻⁵³ of a)
/// is a relative error of ≈ 3·2⁻⁵³/x in 1 − a, all of it once x < 2⁻⁵³ (a = 1, and
/// a ramp of 10⁻¹⁷ s against τ = 0.15 s relaxes nothing), so below x = 1/16 the
/// Taylor series x − x²/2 + … − x⁹/9!… by Horner is taken instead: its truncation
/// is below x·x⁹/10! ≤ 4·10⁻¹⁸·x and its rounding a few 2⁻⁵³ relative. Above 1/16,
/// 1 − a has a relative error ≤ 3·2⁻⁵³·16 + 2⁻⁵³ ≈ 5·10⁻¹⁵. So 1 − e^(−x) to
/// ≤ 5·10⁻¹⁵ relative for every x ≥ 0 (= −expm1(−x); test
/// `one_minus_exp_neg_is_expm1`).
#[inline(always)]
pub fn one_minus_exp_neg(x: f64, a: f64) -> f64 {
    let series = x
        * (1.0
            - x * (1.0 / 2.0
                - x * (1.0 / 6.0
                    - x * (1.0 / 24.0
                        - x * (1.0 / 120.0
                            - x * (1.0 / 720.0
                                - x * (1.0 / 5040.0 - x * (1.0 / 40320.0 - x / 362880.0))))))));
    if x < SERIES_BELOW {
        series
    } else {
        1.0 - a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1 − e^(−x) against libm's −expm1(−x) (≤ 1 ulp) from x = 10⁻³⁰⁰ to 700, at
    /// 5·10⁻¹⁵ relative (the bound proven in the doc comment plus libm's ulp).
    #[test]
    fn one_minus_exp_neg_is_expm1() {
        let mut worst: f64 = 0.0;
        for k in 0..=20_000 {
            let x = 10f64.powf(-300.0 + 302.845 * k as f64 / 20_000.0);
            let got = one_minus_exp_neg(x, exp(-x));
            let want = -(-x).exp_m1();
            worst = worst.max(((got - want) / want).abs());
        }
        assert!(worst < 5e-15, "{worst:e}");
        assert_eq!(one_minus_exp_neg(0.0, 1.0), 0.0);
        // a 10⁻¹⁷ s interval against τ = 0.153 s: 1 − a is off by over 50 % (the
        // subtraction this replaces), the series gives x to rounding
        let x = 1e-17 / 0.153;
        assert!(((1.0 - exp(-x)) / x - 1.0).abs() > 0.5);
        assert!((one_minus_exp_neg(x, exp(-x)) / x - 1.0).abs() < 1e-15);
    }

    /// The libm exponential's own error bound (≤ 1 ulp ≤ 2·2⁻⁵³) on top of
    /// [`exp`]'s proven 3·2⁻⁵³: the tolerance of comparing the two.
    const TOL: f64 = 5.0 * f64::EPSILON / 2.0;

    /// [`ExpTable::exp`] in every lane of a table the compiler cannot see into is
    /// [`exp`], bit for bit (the same arithmetic), on arguments across the whole
    /// range, the edges and NaN included.
    #[test]
    fn table_exp_is_exp_bit_for_bit() {
        let table = std::hint::black_box(ExpTable::<4>::SPLAT);
        let args = (0..=200_000)
            .map(|i| -745.0 + 1460.0 * i as f64 / 2e5)
            .chain([0.0, -0.0, LOWEST, LN_MAX, f64::INFINITY, f64::NEG_INFINITY]);
        for x in args {
            for lane in 0..4 {
                assert_eq!(table.exp(x, lane).to_bits(), exp(x).to_bits(), "e^{x}");
            }
        }
        assert!(table.exp(f64::NAN, 2).is_nan());
    }

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
