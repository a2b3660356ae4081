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
    point: vec4u,       // the current group's Sobol point, each dimension bit-reversed
    dim: u32,           // the next dimension in the group
}

//#if SOBOL
// Dimensions 0..3 of Sobol point rev(y), each bit-reversed, from y (see sobol4_reversed in
// src/sampler.rs): the recurrences of the direction numbers, reversed.
fn sobol4_reversed(y: u32) -> vec4u {
    var x = vec4u(reverseBits(y), 0u, 0u, 0u);
    var r1 = 1u;
    var r2 = vec2u(1u, 3u);
    var r3 = vec3u(1u, 3u, 4u);
    var t = y;
    while t != 0u {
        if (t & 0x80000000u) != 0u {
            x.y ^= r1;
            x.z ^= r2.x;
            x.w ^= r3.x;
        }
        r1 ^= r1 << 1u;
        r2 = vec2u(r2.y, r2.x ^ (r2.x << 2u) ^ r2.y);
        r3 = vec3u(r3.y, r3.z, r3.x ^ (r3.x << 3u) ^ r3.y);
        t <<= 1u;
    }
    return x;
}

fn dimension_seed(group_seed: u32, dim: u32) -> u32 {
    let h = (group_seed ^ (dim * 0x9e3779b9u)) * 0x85ebca6bu;
    return h ^ (h >> 15u);
}

fn laine_karras_permutation(x_in: u32, seed: u32) -> u32 {
    var x = x_in + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

fn sampler_start_group(s: ptr<function, Sampler>) {
    (*s).group_seed = pcg_hash((*s).pixel_seed ^ ((*s).group * 0x9e3779b9u));
    // rev(shuffle(index)) without its reversals (see start_group in src/sampler.rs).
    let y = laine_karras_permutation(reverseBits((*s).index), (*s).group_seed)
        ^ laine_karras_permutation(0u, (*s).group_seed);
    (*s).point = sobol4_reversed(y);
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
    // Owen scrambling, rev(LK(rev(v))), of a point kept bit-reversed.
    let seed = dimension_seed((*s).group_seed, (*s).dim);
    let scrambled = reverseBits(laine_karras_permutation((*s).point[(*s).dim], seed));
    (*s).dim += 1u;
    return f32(scrambled >> 8u) * (1.0 / 16777216.0);
//#else
    var state = (*s).rng;
    let u = rng_next(&state);
    (*s).rng = state;
    return u;
//#endif
}
