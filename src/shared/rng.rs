//! Counter-based random numbers shared bit for bit by the CPU reference and the WGSL kernel
//! (`shaders/rng.wgsl` is this file's twin).
//!
//! Every sample owns an independent stream keyed by (pixel, sample index, seed), so an image does
//! not depend on thread count, scheduling or how a render is sliced into dispatches. Only 32-bit
//! integer multiply, add, xor and shifts are used: WGSL's `u32` arithmetic wraps exactly like
//! Rust's `wrapping_*`, so both sides draw identical numbers.

/// The PCG "RXS-M-XS" output permutation applied to one LCG step (Jarzynski & Olano, 2020).
#[inline]
pub fn pcg_hash(input: u32) -> u32 {
    let state = input.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// A see-through surface's number in [0, 1) for a ray (`origin`, `dir`) meeting primitive
/// `primitive` (packed; an instance's `triangle`, else 0): a hash of all of them, so that each
/// test of one ray against one surface draws the same number and surfaces behind one another
/// draw independent ones (see `assets::alpha`).
#[inline]
pub fn alpha_number(origin: [f32; 3], dir: [f32; 3], primitive: u32, triangle: u32) -> f32 {
    let mut h = pcg_hash(primitive ^ pcg_hash(triangle));
    for x in origin.into_iter().chain(dir) {
        h = pcg_hash(h ^ x.to_bits());
    }
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A PCG32 stream with 32 bits of state: ample for the few dozen numbers one path uses.
/// `Default` is an unused stream (state 0), for samplers that draw no PCG numbers.
#[derive(Clone, Copy, Debug, Default)]
pub struct Rng {
    state: u32,
}

impl Rng {
    /// The stream of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    pub fn for_sample(pixel: u32, sample: u32, seed: u32) -> Self {
        Rng {
            state: pcg_hash(seed.wrapping_add(pcg_hash(sample.wrapping_add(pcg_hash(pixel))))),
        }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.state = self
            .state
            .wrapping_mul(747_796_405)
            .wrapping_add(2_891_336_453);
        let word =
            ((self.state >> ((self.state >> 28) + 4)) ^ self.state).wrapping_mul(277_803_737);
        (word >> 22) ^ word
    }

    /// Uniform in [0, 1): the top 24 bits, so every value is exact in f32 and never rounds to 1.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_floats_stay_in_unit_interval_and_average_one_half() {
        let mut rng = Rng::for_sample(7, 3, 1);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = rng.next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        // Standard error of the mean of U(0,1) is sqrt(1/12/n) ~ 0.0009; 5 sigma.
        assert!((sum / n as f64 - 0.5).abs() < 0.0046);
    }

    /// Alpha numbers of rays from nearby origins (the bits that vary are the low ones) and of
    /// surfaces behind one another are uniform: chi-square over 16 bins of 160 000 numbers, at
    /// 0.001 (37.7 for 15 degrees of freedom), for each.
    #[test]
    fn alpha_numbers_are_uniform_over_rays_and_surfaces() {
        let bins = |numbers: &mut dyn Iterator<Item = f32>| {
            let mut counts = [0u32; 16];
            let mut n = 0;
            for x in numbers {
                assert!((0.0..1.0).contains(&x));
                counts[(x * 16.0) as usize] += 1;
                n += 1;
            }
            let expected = n as f64 / 16.0;
            counts
                .iter()
                .map(|&c| (c as f64 - expected).powi(2) / expected)
                .sum::<f64>()
        };
        let n = 160_000;
        let along_x = bins(
            &mut (0..n)
                .map(|i| alpha_number([0.5 + i as f32 * 1e-6, 0.25, 1.0], [0.0, 0.0, -1.0], 7, 0)),
        );
        let behind =
            bins(&mut (0..n).map(|i| alpha_number([0.5, 0.25, 1.0], [0.0, 0.0, -1.0], i, 0)));
        assert!(
            along_x < 37.7 && behind < 37.7,
            "chi-square {along_x}, {behind}"
        );
    }

    #[test]
    fn streams_differ_by_pixel_sample_and_seed() {
        let first = |p, s, seed| Rng::for_sample(p, s, seed).next_u32();
        assert_ne!(first(0, 0, 0), first(1, 0, 0));
        assert_ne!(first(0, 0, 0), first(0, 1, 0));
        assert_ne!(first(0, 0, 0), first(0, 0, 1));
        assert_eq!(first(5, 6, 7), first(5, 6, 7));
    }
}
