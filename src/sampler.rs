//! Where a sample's random numbers come from (twin: `shaders/sampler.wgsl`; integer arithmetic
//! only, so both backends draw bit-identical values).
//!
//! - `independent`: one PCG stream per (pixel, sample index, seed) — plain Monte Carlo.
//! - `sobol` (the default): Owen-scrambled Sobol points with padding by shuffling, as in Burley,
//!   "Practical Hash-based Owen Scrambling" (JCGT 2020). A sample's numbers come in *groups* of
//!   up to four dimensions, one group per purpose (the integrator calls [`Sampler::begin`]: camera
//!   = pixel 2D + lens 2D; per bounce: light pick + light point, then the BSDF, then roulette).
//!   Within a group the numbers are dimensions 0..3 of the Sobol sequence, whose 2D projections
//!   are well stratified, each Owen-scrambled by a hash (nested uniform scrambling, which keeps
//!   the stratification and makes every point uniformly distributed). Across groups the
//!   sequence index is itself scrambled with a per-group seed, which decorrelates the groups
//!   (padding). Any sample index can be drawn on its own, so renders can be sliced, continued and
//!   merged exactly as with independent numbers.
//!
//! Honest error estimates need independent randomisations: sample index `i` belongs to replica
//! `i % REPLICAS` and is point `i / REPLICAS` of that replica's own scrambled sequence, so each
//! replica is an independent randomised-QMC estimate, and the spread of the replica means
//! measures the error (see `film::PixelStats`).

use crate::options::SamplerKind;
use crate::rng::{Rng, pcg_hash};

/// Independently scrambled sequences a pixel's samples are dealt into, in turn.
pub const REPLICAS: u32 = 2;
/// Dimensions per group: Sobol's first four, whose projections are good.
pub const GROUP_DIMENSIONS: u32 = 4;

/// Sobol generator matrices of dimensions 0..3 as 32 direction numbers each (column k is the
/// contribution of index bit k), from Joe & Kuo's primitive polynomials and initial numbers
/// (new-joe-kuo-6.21201: dimension 2: s 1, a 0, m 1; dimension 3: s 2, a 1, m 1 3;
/// dimension 4: s 3, a 1, m 1 3 1). Dimension 0 is van der Corput's radical inverse.
pub const SOBOL_DIRECTIONS: [u32; 128] = sobol_directions();

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
/// the definition [`sobol4`] is tested against.
pub fn sobol(mut index: u32, dim: u32) -> u32 {
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

/// Dimensions 0..3 of Sobol point `index` at once, the direction numbers of dimensions 1..3
/// made on the fly by their recurrences, v(k+s) = v(k) ^ v(k) >> s ^ (taps of the polynomial),
/// so the kernel needs no table (a table indexed at run time is slow on lavapipe).
#[inline]
pub fn sobol4(index: u32) -> [u32; 4] {
    let mut x = [index.reverse_bits(), 0, 0, 0];
    let mut d1 = 0x8000_0000u32;
    let mut d2 = [0x8000_0000u32, 0xc000_0000];
    let mut d3 = [0x8000_0000u32, 0xc000_0000, 0x2000_0000];
    let mut i = index;
    while i != 0 {
        if i & 1 == 1 {
            x[1] ^= d1;
            x[2] ^= d2[0];
            x[3] ^= d3[0];
        }
        d1 ^= d1 >> 1;
        d2 = [d2[1], d2[0] ^ (d2[0] >> 2) ^ d2[1]];
        d3 = [d3[1], d3[2], d3[0] ^ (d3[0] >> 3) ^ d3[1]];
        i >>= 1;
    }
    x
}

/// [`sobol4`] of `rev(y)` with every dimension bit-reversed, computed from `y` without
/// reversing: index bit k is bit 31 - k of `y`, and reversed direction numbers follow the
/// recurrences with left shifts. Scrambling works on reversed values, so the kernel saves two
/// bit reversals per number this way.
#[inline]
pub fn sobol4_reversed(y: u32) -> [u32; 4] {
    let mut x = [y.reverse_bits(), 0, 0, 0];
    let mut r1 = 1u32;
    let mut r2 = [1u32, 3];
    let mut r3 = [1u32, 3, 4];
    let mut t = y;
    while t != 0 {
        if t & 0x8000_0000 != 0 {
            x[1] ^= r1;
            x[2] ^= r2[0];
            x[3] ^= r3[0];
        }
        r1 ^= r1 << 1;
        r2 = [r2[1], r2[0] ^ (r2[0] << 2) ^ r2[1]];
        r3 = [r3[1], r3[2], r3[0] ^ (r3[0] << 3) ^ r3[1]];
        t <<= 1;
    }
    x
}

/// The Owen-scrambling seed of dimension `dim` of a group: a cheap integer mix (a
/// multiply-xorshift round) of the group's seed, which is itself a full hash.
#[inline]
pub fn dimension_seed(group_seed: u32, dim: u32) -> u32 {
    let h = (group_seed ^ dim.wrapping_mul(0x9e37_79b9)).wrapping_mul(0x85eb_ca6b);
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

/// The index a group draws its Sobol point at: Burley's nested uniform scramble of the index,
/// XORed with the scramble of 0. Scrambling keeps every aligned block [0, 2^k) together, moving
/// it by a constant in the bits above k, which the XOR removes: the result stays below 2^k
/// (so the Sobol loop runs over the index's own bits, not 32), and the point moves by a
/// constant digital shift, which the Owen scrambling that follows absorbs (a shift is one of
/// the scrambles it picks uniformly among).
#[inline]
pub fn shuffle(index: u32, seed: u32) -> u32 {
    nested_uniform_scramble(index, seed) ^ nested_uniform_scramble(0, seed)
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
    /// the current group, its seed and Sobol point (at the index shuffled for the group, each
    /// dimension bit-reversed), and the next dimension in it.
    pixel_seed: u32,
    index: u32,
    group: u32,
    group_seed: u32,
    point: [u32; 4],
    dim: u32,
}

impl Sampler {
    /// The numbers of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    pub fn for_sample(kind: SamplerKind, pixel: u32, sample: u32, seed: u32) -> Self {
        let mut out = Sampler {
            kind,
            rng: Rng::for_sample(pixel, sample, seed),
            pixel_seed: 0,
            index: sample / REPLICAS,
            group: 0,
            group_seed: 0,
            point: [0; 4],
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
        self.group_seed = pcg_hash(self.pixel_seed ^ self.group.wrapping_mul(0x9e37_79b9));
        // rev(shuffle(index)), without its two reversals (see `shuffle`).
        let y = laine_karras_permutation(self.index.reverse_bits(), self.group_seed)
            ^ laine_karras_permutation(0, self.group_seed);
        self.point = sobol4_reversed(y);
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
                let seed = dimension_seed(self.group_seed, self.dim);
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
    fn sobol4_recurrences_match_the_generator_matrices() {
        for index in (0..5000).chain([u32::MAX, 0x8000_0000, 0x1234_5678]) {
            let expected = [0, 1, 2, 3].map(|d| sobol(index, d));
            assert_eq!(sobol4(index), expected, "index {index}");
        }
    }

    #[test]
    fn reversed_sobol_matches_sobol_reversed() {
        for n in (0..5000u32).chain([u32::MAX, 0x8000_0000, 0x1234_5678]) {
            let expected = sobol4(n).map(u32::reverse_bits);
            assert_eq!(sobol4_reversed(n.reverse_bits()), expected, "index {n}");
        }
    }

    #[test]
    fn shuffling_permutes_every_aligned_block_and_stays_inside_it() {
        for seed in [0, 1, 0xdead_beef] {
            for k in [0, 1, 5, 10] {
                let mut seen = vec![false; 1 << k];
                for i in 0..1u32 << k {
                    let j = shuffle(i, seed);
                    assert!(j < 1 << k, "seed {seed}: {i} -> {j} leaves [0, 2^{k})");
                    seen[j as usize] = true;
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
