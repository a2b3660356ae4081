//! An exact sum of f32 values: a fixed-point integer wide enough for every finite f32 (Kulisch's
//! long accumulator). Every non-negative f32 is an integer multiple of 2^-149 (the smallest
//! subnormal) below 2^128, so the sum of fewer than 2^32 of them is an integer below 2^309 in
//! units of 2^-149: ten 32-bit words. Integer addition is associative, so a pixel's sum has the
//! same bits however its samples were grouped (dispatches, passes, resumes, shards), and no
//! sample is rounded, however dim or bright. Twin: `Wide` in shaders/film.wgsl.

/// 32-bit words in a sum (the kernel's unit; here they are paired into u64 limbs).
pub const SUM_WORDS: usize = 10;
const LIMBS: usize = SUM_WORDS / 2;

/// The unit of a sum: 2^-149, as the exponent.
pub const UNIT_EXPONENT: i32 = -149;

/// A sum of non-negative f32 values in units of 2^-149, least significant limb first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ExactSum {
    limbs: [u64; LIMBS],
}

/// A non-negative finite f32 as (integer mantissa, bit position of its unit above 2^-149):
/// `value = mantissa * 2^(position - 149)`. Shared with `decompose` in shaders/film.wgsl.
#[inline]
pub fn decompose(value: f32) -> (u32, u32) {
    let bits = value.to_bits() & 0x7fff_ffff; // -0 is 0
    let exponent = bits >> 23;
    let fraction = bits & 0x7f_ffff;
    if exponent == 0 {
        (fraction, 0)
    } else {
        (fraction | 0x80_0000, exponent - 1)
    }
}

impl ExactSum {
    pub const ZERO: ExactSum = ExactSum { limbs: [0; LIMBS] };

    /// Adds `value`, which must be finite and non-negative (or -0): see `film::is_valid_sample`.
    #[inline]
    pub fn add_f32(&mut self, value: f32) {
        debug_assert!(value.is_finite() && !(value < 0.0), "{value}");
        let (mantissa, position) = decompose(value);
        let (limb, shift) = ((position / 64) as usize, position % 64);
        let wide = (mantissa as u128) << shift;
        // The highest position is 253 (limb 3): limbs `limb` and `limb + 1` always exist, and
        // are added to as one 128-bit integer, whose carry out is rare.
        let low = self.limbs[limb] as u128 | (self.limbs[limb + 1] as u128) << 64;
        let (sum, mut carry) = low.overflowing_add(wide);
        self.limbs[limb] = sum as u64;
        self.limbs[limb + 1] = (sum >> 64) as u64;
        let mut above = limb + 2;
        while carry && above < LIMBS {
            (self.limbs[above], carry) = self.limbs[above].overflowing_add(1);
            above += 1;
        }
    }

    /// `self + other`, exactly; saturating (all ones) past 2^320, which fewer than 2^32 f32
    /// values cannot reach but a corrupted film might.
    pub fn plus(&self, other: &ExactSum) -> ExactSum {
        let mut out = ExactSum::ZERO;
        let mut carry = false;
        for i in 0..LIMBS {
            let (a, c1) = self.limbs[i].overflowing_add(other.limbs[i]);
            let (b, c2) = a.overflowing_add(carry as u64);
            out.limbs[i] = b;
            carry = c1 || c2;
        }
        if carry {
            out.limbs = [u64::MAX; LIMBS];
        }
        out
    }

    /// `self - other`, exactly, or `None` if `other` is the larger.
    pub fn minus(&self, other: &ExactSum) -> Option<ExactSum> {
        let mut out = ExactSum::ZERO;
        let mut borrow = false;
        for i in 0..LIMBS {
            let (a, b1) = self.limbs[i].overflowing_sub(other.limbs[i]);
            let (b, b2) = a.overflowing_sub(borrow as u64);
            out.limbs[i] = b;
            borrow = b1 || b2;
        }
        (!borrow).then_some(out)
    }

    /// The sum as an f64 (within a few ulps; the same bits for the same sum).
    pub fn to_f64(&self) -> f64 {
        // Most significant limb first, so each smaller term is added to what it refines.
        self.limbs
            .iter()
            .enumerate()
            .rev()
            .fold(0.0, |total, (i, &limb)| {
                total + limb as f64 * 2f64.powi(64 * i as i32 + UNIT_EXPONENT)
            })
    }

    /// 32-bit word `i` (0 the least significant), as the kernel and film files hold them.
    pub fn word(&self, i: usize) -> u32 {
        (self.limbs[i / 2] >> (32 * (i % 2))) as u32
    }

    /// A sum from its ten 32-bit words, least significant first: `from_words` of an array,
    /// which the GPU's read-back does for every pixel's six sums.
    #[inline]
    pub fn from_word_array(words: &[u32; SUM_WORDS]) -> ExactSum {
        ExactSum {
            limbs: std::array::from_fn(|k| words[2 * k] as u64 | (words[2 * k + 1] as u64) << 32),
        }
    }

    /// A sum from its 32-bit words, least significant first (missing words are zero).
    pub fn from_words(words: impl IntoIterator<Item = u32>) -> ExactSum {
        let mut out = ExactSum::ZERO;
        for (i, w) in words.into_iter().take(SUM_WORDS).enumerate() {
            out.limbs[i / 2] |= (w as u64) << (32 * (i % 2));
        }
        out
    }

    /// A sum from an integer in units of 2^-`fraction_bits` (older film files' fixed point:
    /// 2^-32), exactly.
    pub fn from_fixed(value: u128, fraction_bits: u32) -> ExactSum {
        let shift = (-UNIT_EXPONENT) as u32 - fraction_bits;
        let (limb, bit) = ((shift / 64) as usize, shift % 64);
        let mut out = ExactSum::ZERO;
        let parts = [
            (value as u64) << bit,
            if bit == 0 {
                (value >> 64) as u64
            } else {
                (value >> (64 - bit)) as u64
            },
            if bit == 0 {
                0
            } else {
                (value >> (128 - bit)) as u64
            },
        ];
        for (k, part) in parts.into_iter().enumerate() {
            if limb + k < LIMBS {
                out.limbs[limb + k] = part;
            }
        }
        out
    }

    pub fn is_zero(&self) -> bool {
        self.limbs == [0; LIMBS]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sum_of(values: &[f32]) -> ExactSum {
        let mut s = ExactSum::ZERO;
        values.iter().for_each(|&v| s.add_f32(v));
        s
    }

    #[test]
    fn every_f32_is_kept_exactly_from_the_smallest_subnormal_to_the_largest() {
        for v in [
            f32::from_bits(1),
            f32::MIN_POSITIVE,
            1e-30,
            1e-12,
            0.1,
            1.0,
            15.0,
            1e12,
            1e30,
            f32::MAX,
        ] {
            let s = sum_of(&[v]);
            assert_eq!(s.to_f64(), v as f64, "{v:e}");
            // The sum minus itself, and the value twice, are exact too.
            assert!(s.minus(&s).expect("not negative").is_zero());
            assert_eq!(sum_of(&[v, v]).to_f64(), 2.0 * v as f64, "{v:e}");
        }
        assert!(sum_of(&[0.0, -0.0]).is_zero());
    }

    #[test]
    fn sums_do_not_depend_on_grouping_or_order_across_any_range_of_values() {
        // Values over 70 orders of magnitude whose float sum depends on the order.
        let values: Vec<f32> = (0..1000)
            .map(|i| 10f32.powi((i * 37 % 71) - 35) * (1.0 + (i % 7) as f32 * 0.13))
            .collect();
        let all = sum_of(&values);
        let mut reversed = values.clone();
        reversed.reverse();
        assert_eq!(sum_of(&reversed), all);
        for cut in [1, 333, 999] {
            let (a, b) = values.split_at(cut);
            assert_eq!(sum_of(a).plus(&sum_of(b)), all);
            assert_eq!(all.minus(&sum_of(a)), Some(sum_of(b)));
        }
        // A dim sample beside a bright one is not lost: the difference is exact.
        let bright_and_dim = sum_of(&[1e30, 1e-30]);
        let dim = bright_and_dim
            .minus(&sum_of(&[1e30]))
            .expect("bright <= both");
        assert_eq!(dim.to_f64(), 1e-30f32 as f64);
    }

    #[test]
    fn the_largest_possible_sum_fits_and_words_round_trip() {
        // 2^32 - 1 samples of f32::MAX, added as the sum of doublings would be.
        let mut s = sum_of(&[f32::MAX]);
        let one = s;
        for _ in 0..32 {
            s = s.plus(&s);
        }
        let s = s.minus(&one).expect("positive");
        assert!((s.to_f64() / (f32::MAX as f64 * (u32::MAX as f64)) - 1.0).abs() < 1e-12);
        assert_eq!(ExactSum::from_words((0..SUM_WORDS).map(|i| s.word(i))), s);
        assert!(s.minus(&s.plus(&one)).is_none());
    }

    #[test]
    fn older_fixed_point_sums_convert_exactly() {
        // 2^-32 units: 1.5 = 3 * 2^31.
        assert_eq!(ExactSum::from_fixed(3 << 31, 32).to_f64(), 1.5);
        let big = (u32::MAX as u128) << 64 | 12345;
        let expected = big as f64 / 2f64.powi(32);
        assert!((ExactSum::from_fixed(big, 32).to_f64() / expected - 1.0).abs() < 1e-15);
        assert_eq!(ExactSum::from_fixed(1, 32), sum_of(&[2f32.powi(-32)]));
    }
}
