// Where a sample's random numbers come from (twin: src/sampler.rs; integer arithmetic only, so
// both backends draw bit-identical values): independent PCG numbers, or Owen-scrambled Sobol
// points in groups of up to four dimensions, one group per purpose, padded by shuffling
// (Burley 2020). The kernel holds one of them (feature SOBOL): on lavapipe a loop inside a
// branch not taken still cost loop-budget iterations.

struct Sampler {
    rng: u32,           // independent: the PCG state
    pixel_seed: u32,    // sobol: this pixel's and replica's seed
    index: u32,         // sobol: the point's index in its replica's sequence
    group: u32,
    group_seed: u32,
    point: vec4u,       // the current group's Sobol point (its index scrambled for the group)
    dim: u32,           // the next dimension in the group
}

//#if SOBOL
// Dimensions 0..3 of Sobol point index, as 32-bit fractions, the direction numbers made on
// the fly by their recurrences (see sobol4 in src/sampler.rs).
fn sobol4(index_in: u32) -> vec4u {
    var index = index_in;
    var x = vec4u(reverseBits(index_in), 0u, 0u, 0u);
    var d1 = 0x80000000u;
    var d2 = vec2u(0x80000000u, 0xc0000000u);
    var d3 = vec3u(0x80000000u, 0xc0000000u, 0x20000000u);
    while index != 0u {
        if (index & 1u) == 1u {
            x.y ^= d1;
            x.z ^= d2.x;
            x.w ^= d3.x;
        }
        d1 ^= d1 >> 1u;
        d2 = vec2u(d2.y, d2.x ^ (d2.x >> 2u) ^ d2.y);
        d3 = vec3u(d3.y, d3.z, d3.x ^ (d3.x >> 3u) ^ d3.y);
        index >>= 1u;
    }
    return x;
}

fn laine_karras_permutation(x_in: u32, seed: u32) -> u32 {
    var x = x_in + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    return reverseBits(laine_karras_permutation(reverseBits(x), seed));
}

fn sampler_start_group(s: ptr<function, Sampler>) {
    (*s).group_seed = pcg_hash((*s).pixel_seed + pcg_hash((*s).group));
    (*s).point = sobol4(nested_uniform_scramble((*s).index, (*s).group_seed));
    (*s).dim = 0u;
}

//#endif

fn sampler_for_sample(pixel: u32, sample: u32, seed: u32) -> Sampler {
    var s = Sampler(rng_for_sample(pixel, sample, seed), 0u, sample / REPLICAS, 0u, 0u, vec4u(0u), 0u);
//#if SOBOL
    let replica = sample % REPLICAS;
    s.pixel_seed = pcg_hash(seed + pcg_hash(replica + pcg_hash(pixel ^ 0x5b0b5eedu)));
    sampler_start_group(&s);
//#endif
    return s;
}

// Starts the numbers of a new purpose: a fresh group of dimensions.
fn sampler_begin(s: ptr<function, Sampler>) {
//#if SOBOL
    (*s).group += 1u;
    sampler_start_group(s);
//#endif
}

// The next number, uniform in [0, 1).
fn sampler_next(s: ptr<function, Sampler>) -> f32 {
//#if SOBOL
    if (*s).dim == GROUP_DIMENSIONS {
        sampler_begin(s);
    }
    let bits = (*s).point[(*s).dim];
    let scrambled = nested_uniform_scramble(bits, pcg_hash((*s).group_seed + (*s).dim));
    (*s).dim += 1u;
    return f32(scrambled >> 8u) * (1.0 / 16777216.0);
//#else
    var state = (*s).rng;
    let u = rng_next(&state);
    (*s).rng = state;
    return u;
//#endif
}
