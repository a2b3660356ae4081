//! Where a sample's random numbers come from (twin: `shaders/sampler.wgsl`; integer arithmetic
//! only, so both backends draw bit-identical values).
//!
//! - `independent`: one PCG stream per (pixel, sample index, seed) — plain Monte Carlo.
//! - `sobol` (the default): Owen-scrambled Sobol points with padding by shuffling, as in Burley,
//!   "Practical Hash-based Owen Scrambling" (JCGT 2020), in pbrt-v4's padded layout: a sample's
//!   numbers come in *2D groups*, one per purpose (the integrator calls [`Sampler::begin`]:
//!   pixel 2D, lens 2D; per bounce: light pick 1D, light point 2D, BSDF 2D, roulette 1D). A
//!   group's numbers are dimensions 0 and 1 of the Sobol sequence (a (0, 2)-sequence: every
//!   elementary interval holds its share of points), each Owen-scrambled by a hash (nested
//!   uniform scrambling, which keeps the stratification and makes every point uniformly
//!   distributed). Across groups the sequence index is itself scrambled with a per-group seed,
//!   which decorrelates the groups (padding). Any sample index can be drawn on its own, so
//!   renders can be sliced, continued and merged exactly as with independent numbers.
//!
//! Honest error estimates need independent randomisations: sample index `i` belongs to replica
//! `i % REPLICAS` and is point `i / REPLICAS` of that replica's own scrambled sequence, so each
//! replica is an independent randomised-QMC estimate, and the spread of the replica means
//! measures the error (see `film::PixelStats`).

use crate::options::SamplerKind;
use crate::shared::rng::{Rng, pcg_hash};

/// Independently scrambled sequences a pixel's samples are dealt into, in turn.
pub const REPLICAS: u32 = 2;
// shaders/sampler.wgsl's `replica_seeds` hashes the seeds of two.
const _: () = assert!(REPLICAS == 2);
/// Dimensions per group: Sobol's first two, a (0, 2)-sequence, computed without a loop.
pub const GROUP_DIMENSIONS: u32 = 2;

/// Dimensions 0 and 1 of Sobol point `n`, each bit-reversed, without a loop (tested against
/// the generator matrices of Joe & Kuo's direction numbers). Dimension 0 is
/// the radical inverse, so reversed it is `n` itself. Dimension 1's direction numbers are the rows
/// of Pascal's triangle mod 2, which are palindromes, so reversed, bit j of the result is the
/// parity of the index bits k with C(k, j) odd, that is (Lucas) with j a bitwise subset of k: a
/// superset-sum transform over the five bits of a bit position, five shift-xor steps.
#[inline]
pub fn sobol2_reversed(n: u32) -> [u32; 2] {
    let mut x = n;
    x ^= (x >> 1) & 0x5555_5555;
    x ^= (x >> 2) & 0x3333_3333;
    x ^= (x >> 4) & 0x0f0f_0f0f;
    x ^= (x >> 8) & 0x00ff_00ff;
    x ^= (x >> 16) & 0x0000_ffff;
    [n, x]
}

/// A seed derived from `seed` (itself a full hash) for its `k`-th group or dimension: a cheap
/// multiply-xorshift round, enough to decorrelate the Laine-Karras hashes it seeds.
#[inline]
pub fn mix(seed: u32, k: u32) -> u32 {
    let h = (seed ^ k.wrapping_mul(0x9e37_79b9)).wrapping_mul(0x85eb_ca6b);
    h ^ (h >> 15)
}

/// Burley's Laine-Karras-style hash: each output bit depends only on the input bits below it,
/// so applied to bit-reversed values it permutes like a nested uniform (Owen) scramble.
#[inline]
pub fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen scrambling of a 32-bit fraction (or, applied to an index, a shuffle that keeps every
/// aligned power-of-two block of indices together).
#[inline]
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// Uniform in [0, 1) from the top 24 bits, as `Rng::next_f32`.
#[inline]
fn to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// One sample's source of numbers.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    kind: SamplerKind,
    /// Independent: the PCG stream.
    rng: Rng,
    /// Sobol: this pixel's and replica's seed, the point's index in the replica's sequence,
    /// the current group, its seed and Sobol point (at the index shuffled for the group by a
    /// nested uniform scramble, each dimension bit-reversed), and the next dimension in it.
    pixel_seed: u32,
    index: u32,
    group: u32,
    group_seed: u32,
    point: [u32; 2],
    dim: u32,
}

impl Sampler {
    /// The numbers of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    pub fn for_sample(kind: SamplerKind, pixel: u32, sample: u32, seed: u32) -> Self {
        let mut out = Sampler {
            kind,
            // Only independent samples draw from the PCG stream: Sobol ones skip its hashes.
            rng: match kind {
                SamplerKind::Independent => Rng::for_sample(pixel, sample, seed),
                SamplerKind::Sobol => Rng::default(),
            },
            pixel_seed: 0,
            index: sample / REPLICAS,
            group: 0,
            group_seed: 0,
            point: [0; 2],
            dim: 0,
        };
        if kind == SamplerKind::Sobol {
            let replica = sample % REPLICAS;
            out.pixel_seed = pcg_hash(seed.wrapping_add(pcg_hash(
                replica.wrapping_add(pcg_hash(pixel ^ 0x5b0b_5eed)),
            )));
            out.start_group();
        }
        out
    }

    /// Plain Monte Carlo numbers, as the tests of single functions use.
    pub fn independent(pixel: u32, sample: u32, seed: u32) -> Self {
        Sampler::for_sample(SamplerKind::Independent, pixel, sample, seed)
    }

    fn start_group(&mut self) {
        self.group_seed = mix(self.pixel_seed, self.group);
        self.point = sobol2_reversed(nested_uniform_scramble(self.index, self.group_seed));
        self.dim = 0;
    }

    /// Starts the numbers of a new purpose: they come from a fresh group of dimensions.
    #[inline]
    pub fn begin(&mut self) {
        if self.kind == SamplerKind::Sobol {
            self.group += 1;
            self.start_group();
        }
    }

    /// The next number, uniform in [0, 1). A group's fifth number starts a new group.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        match self.kind {
            SamplerKind::Independent => self.rng.next_f32(),
            SamplerKind::Sobol => {
                if self.dim == GROUP_DIMENSIONS {
                    self.begin();
                }
                // Owen scrambling, rev(LK(rev(v))), of a point kept bit-reversed.
                let seed = mix(self.group_seed, self.dim);
                let scrambled =
                    laine_karras_permutation(self.point[self.dim as usize], seed).reverse_bits();
                self.dim += 1;
                to_unit(scrambled)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sobol generator matrices of dimensions 0..3 as 32 direction numbers each (column k is the
    /// contribution of index bit k), from Joe & Kuo's primitive polynomials and initial numbers
    /// (new-joe-kuo-6.21201: dimension 2: s 1, a 0, m 1; dimension 3: s 2, a 1, m 1 3;
    /// dimension 4: s 3, a 1, m 1 3 1). Dimension 0 is van der Corput's radical inverse.
    const SOBOL_DIRECTIONS: [u32; 128] = sobol_directions();

    const fn sobol_directions() -> [u32; 128] {
        let mut out = [0u32; 128];
        let mut k = 0;
        while k < 32 {
            out[k] = 1 << (31 - k);
            k += 1;
        }
        // (degree s, coefficients a, initial m values) of dimensions 1, 2, 3.
        let params: [(usize, u32, [u32; 3]); 3] =
            [(1, 0, [1, 0, 0]), (2, 1, [1, 3, 0]), (3, 1, [1, 3, 1])];
        let mut d = 0;
        while d < 3 {
            let (s, a, m) = params[d];
            let mut v = [0u32; 32];
            let mut k = 0;
            while k < 32 {
                if k < s {
                    v[k] = m[k] << (31 - k);
                } else {
                    v[k] = v[k - s] ^ (v[k - s] >> s);
                    let mut i = 1;
                    while i < s {
                        if (a >> (s - 1 - i)) & 1 == 1 {
                            v[k] ^= v[k - i];
                        }
                        i += 1;
                    }
                }
                out[32 * (d + 1) + k] = v[k];
                k += 1;
            }
            d += 1;
        }
        out
    }

    /// Dimension `dim` (0..3) of Sobol point `index`, as 32 bits of a fraction, from the tables:
    /// the definition `sobol2_reversed` is tested against.
    fn sobol(mut index: u32, dim: u32) -> u32 {
        let mut x = 0;
        let mut k = 32 * dim as usize;
        while index != 0 {
            if index & 1 == 1 {
                x ^= SOBOL_DIRECTIONS[k];
            }
            index >>= 1;
            k += 1;
        }
        x
    }

    /// Points 0..2^m of dimensions `a` and `b` (after `map`) in a 2^m x 2^m grid's elementary
    /// intervals of every shape 2^i x 2^(m-i): the largest count in one.
    fn worst_elementary_count(m: u32, value: impl Fn(u32, u32) -> u32, a: u32, b: u32) -> u32 {
        let n = 1u32 << m;
        let mut worst = 0;
        for i in 0..=m {
            let mut counts = vec![0u32; n as usize];
            for index in 0..n {
                let (x, y) = (value(index, a), value(index, b));
                let cell = if i == 0 { 0 } else { x >> (32 - i) };
                let row = if i == m { 0 } else { y >> (32 - (m - i)) };
                counts[(cell << (m - i) | row) as usize] += 1;
            }
            worst = worst.max(*counts.iter().max().unwrap_or(&0));
        }
        worst
    }

    #[test]
    fn sobol_first_two_dimensions_form_nets_and_scrambling_keeps_them() {
        // Dimensions 0 and 1 of Sobol are a (0, 2)-sequence: every elementary interval of area
        // 2^-m holds exactly one of the first 2^m points; Owen scrambling preserves it.
        for m in [4, 8, 10] {
            assert_eq!(worst_elementary_count(m, sobol, 0, 1), 1, "m = {m}");
            let scrambled = |i, d| nested_uniform_scramble(sobol(i, d), 77 + d);
            assert_eq!(worst_elementary_count(m, scrambled, 0, 1), 1, "m = {m}");
        }
        // Each dimension alone: one point per interval of length 2^-m.
        for dim in 0..4 {
            let mut seen = vec![false; 256];
            for i in 0..256 {
                seen[(sobol(i, dim) >> 24) as usize] = true;
            }
            assert!(seen.iter().all(|&s| s), "dimension {dim}");
        }
        // A negative control: independent hashes are not a net.
        let hashed = |i: u32, d: u32| pcg_hash(i.wrapping_mul(4).wrapping_add(d));
        assert!(worst_elementary_count(8, hashed, 0, 1) > 1);
    }

    #[test]
    fn loop_free_sobol_matches_the_generator_matrices() {
        for n in (0..5000u32).chain([u32::MAX, 0x8000_0000, 0x1234_5678, 0xdead_beef]) {
            let expected = [sobol(n, 0), sobol(n, 1)].map(u32::reverse_bits);
            assert_eq!(sobol2_reversed(n), expected, "index {n}");
        }
    }

    #[test]
    fn shuffling_permutes_every_aligned_block() {
        // Nested uniform scrambling of an index keeps each aligned block of 2^k indices
        // together (moved as a whole by the same high bits): a padding that does not break the
        // stratification of any power-of-two prefix.
        for seed in [0, 1, 0xdead_beef] {
            for k in [1, 5, 10] {
                let high = nested_uniform_scramble(0, seed) >> k;
                let mut seen = vec![false; 1 << k];
                for i in 0..1u32 << k {
                    let j = nested_uniform_scramble(i, seed);
                    assert_eq!(j >> k, high, "seed {seed}: {i} -> {j} leaves its block");
                    seen[(j & ((1 << k) - 1)) as usize] = true;
                }
                assert!(seen.iter().all(|&s| s));
            }
        }
    }

    #[test]
    fn direction_numbers_match_published_values() {
        // Dimension 1 (Joe-Kuo's second): 1, 3, 5, 15, 17, 51, ... times 2^(31-k) (Pascal's
        // triangle mod 2).
        let expected = [1u32, 3, 5, 15, 17, 51, 85, 255];
        for (k, m) in expected.iter().enumerate() {
            assert_eq!(SOBOL_DIRECTIONS[32 + k], m << (31 - k), "k = {k}");
        }
    }

    #[test]
    fn a_samples_numbers_are_uniform_and_groups_differ() {
        let mut sum = 0.0f64;
        let n = 4096;
        for sample in 0..n {
            let mut s = Sampler::for_sample(SamplerKind::Sobol, 3, sample, 9);
            let a = s.next_f32();
            assert!((0.0..1.0).contains(&a));
            sum += a as f64;
            s.begin();
            let b = s.next_f32();
            assert_ne!(a, b);
        }
        assert!((sum / n as f64 - 0.5).abs() < 1e-3, "{}", sum / n as f64);
    }
}
