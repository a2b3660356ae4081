//! A pixel's 8-bit values, decided on its exact sum: level k is shown where the mean
//! `sum / n` is at least the level's threshold, the smallest f32 a transfer curve sends to k or
//! above. Deciding on the exact sum rather than a rounded mean makes the choice the same
//! wherever it is made: here for image files, and in the viewer's display pass
//! (`shaders/display.wgsl`, this file's twin), which reads the accumulator on the device.

use crate::film::PixelStats;
use crate::shared::exact_sum::{ExactSum, SUM_WORDS};

/// Levels 0-255 of one transfer curve, as the thresholds between them.
#[derive(Clone, Debug)]
pub struct Levels {
    encode: fn(f32, f32) -> u8,
    parameter: f32,
    /// `thresholds[k]`: the smallest non-negative f32 that `encode` sends to k or above
    /// (+infinity for a level it never reaches); `thresholds[0]` is 0.
    pub thresholds: [f32; 256],
}

impl Levels {
    /// The levels of `encode(linear, parameter)`, a curve non-decreasing in `linear` from 0 at
    /// 0 (a plain function and its parameter, so that the levels stay `Clone` and cheap).
    pub fn new(encode: fn(f32, f32) -> u8, parameter: f32) -> Self {
        let mut thresholds = [0.0; 256];
        for (k, t) in thresholds.iter_mut().enumerate().skip(1) {
            *t = smallest_reaching(|x| encode(x, parameter) as usize >= k);
        }
        Levels {
            encode,
            parameter,
            thresholds,
        }
    }

    /// The 8-bit level of a channel whose `n` samples sum to `sum` (0 with no samples).
    pub fn level(&self, sum: &ExactSum, n: u64) -> u8 {
        if n == 0 {
            return 0;
        }
        // The rounded mean's level is right but within a rounding of a threshold; the exact
        // comparisons settle it.
        let mut k = (self.encode)((sum.to_f64() / n as f64) as f32, self.parameter) as usize;
        while k < 255 && at_least(sum, n, self.thresholds[k + 1]) {
            k += 1;
        }
        while k > 0 && !at_least(sum, n, self.thresholds[k]) {
            k -= 1;
        }
        k as u8
    }

    /// A pixel's three levels.
    pub fn pixel(&self, p: &PixelStats) -> [u8; 3] {
        std::array::from_fn(|c| self.level(&p.sum[c], p.n))
    }
}

/// The smallest non-negative finite f32 where `reaches` turns true (true from there on), or
/// +infinity if it never does. Non-negative floats are ordered as their bits.
fn smallest_reaching(reaches: impl Fn(f32) -> bool) -> f32 {
    let (mut lo, mut hi) = (0u32, f32::MAX.to_bits());
    if !reaches(f32::from_bits(hi)) {
        return f32::INFINITY;
    }
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if reaches(f32::from_bits(mid)) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    f32::from_bits(lo)
}

/// Whether `sum / n >= threshold`, exactly: `sum` against `n x threshold` in the sum's units
/// of 2^-149, word by word from the top.
pub fn at_least(sum: &ExactSum, n: u64, threshold: f32) -> bool {
    if !threshold.is_finite() {
        return false;
    }
    let (mantissa, position) = crate::shared::exact_sum::decompose(threshold);
    // n x threshold: a product below 2^88 shifted to its bit, in words of the sum's width and
    // one more (a product past the sum's top word is larger than any sum).
    let product = n as u128 * mantissa as u128;
    let (word, bit) = ((position / 32) as usize, position % 32);
    let mut scaled = [0u32; SUM_WORDS + 4];
    for (i, slot) in scaled.iter_mut().enumerate().skip(word).take(4) {
        let shift = 32 * (i - word) as i32 - bit as i32;
        *slot = if shift >= 0 {
            (product >> shift) as u32
        } else {
            (product << -shift) as u32
        };
    }
    if scaled[SUM_WORDS..].iter().any(|&w| w != 0) {
        return false;
    }
    for i in (0..SUM_WORDS).rev() {
        let (s, t) = (sum.word(i), scaled[i]);
        if s != t {
            return s > t;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::output::Transfer;
    use crate::shared::rng::Rng;

    fn srgb(x: f32, _: f32) -> u8 {
        Transfer::Srgb.encode(x)
    }

    fn sum_of(values: &[f32]) -> ExactSum {
        let mut s = ExactSum::default();
        for &v in values {
            s.add_f32(v);
        }
        s
    }

    /// Of one sample, the level is the curve's level of that value: on every threshold, the
    /// float below it, and random values across the range.
    #[test]
    fn one_sample_gets_the_curve_s_own_level() {
        let levels = Levels::new(srgb, 0.0);
        let mut values = vec![0.0, 1e-30, 1.0, 1e30, f32::MAX];
        for &t in &levels.thresholds[1..] {
            values.extend([
                t,
                f32::from_bits(t.to_bits() - 1),
                f32::from_bits(t.to_bits() + 1),
            ]);
        }
        let mut rng = Rng::for_sample(7, 1, 0);
        values.extend((0..100_000).map(|_| rng.next_f32() * 1.2));
        for v in values {
            assert_eq!(
                levels.level(&sum_of(&[v]), 1),
                srgb(v, 0.0),
                "value {v:e} ({:#x})",
                v.to_bits()
            );
        }
    }

    /// Means that are not floats: n samples at a threshold are at it; one ulp of one sample
    /// below is below it, however many samples (where a rounded mean would say equal).
    #[test]
    fn exact_means_decide_at_the_threshold() {
        let levels = Levels::new(srgb, 0.0);
        for k in [1usize, 2, 17, 128, 254, 255] {
            let t = levels.thresholds[k];
            for n in [1u64, 3, 1000, 1 << 20] {
                let mut sum = ExactSum::default();
                for _ in 0..n {
                    sum.add_f32(t);
                }
                assert_eq!(levels.level(&sum, n) as usize, k, "n {n} at level {k}");
                let mut below = ExactSum::default();
                for i in 0..n {
                    below.add_f32(if i == 0 {
                        f32::from_bits(t.to_bits() - 1)
                    } else {
                        t
                    });
                }
                assert_eq!(
                    levels.level(&below, n) as usize,
                    k - 1,
                    "n {n} below level {k}"
                );
            }
        }
        assert_eq!(levels.level(&ExactSum::default(), 0), 0);
        assert!(!at_least(&sum_of(&[f32::MAX]), 1, f32::INFINITY));
    }

    #[test]
    fn every_gamma_2_level_has_a_threshold() {
        let levels = Levels::new(|x, g| Transfer::Gamma(g).encode(x), 2.0);
        assert!(levels.thresholds.windows(2).all(|w| w[0] <= w[1]));
        assert!(levels.thresholds.iter().all(|t| t.is_finite()));
    }
}
