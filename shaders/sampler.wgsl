// Where a sample's random numbers come from (twin: src/shared/sampler.rs; integer arithmetic only, so
// both backends draw bit-identical values): independent PCG numbers, or Owen-scrambled Sobol
// points in 2D groups, one per purpose, padded by shuffling (Burley 2020; pbrt-v4's padded
// layout). The kernel holds one of them (feature SOBOL): on lavapipe a loop inside a
// branch not taken still cost loop-budget iterations.

struct Sampler {
    rng: u32,           // independent: the PCG state
    pixel_seed: u32,    // sobol: this pixel's and replica's seed
    index: u32,         // sobol: the point's index in its replica's sequence
    group: u32,
    group_seed: u32,
    point: vec2u,       // the current group's Sobol point, each dimension bit-reversed
    dim: u32,           // the next dimension in the group
}

//#if SOBOL
// Dimensions 0 and 1 of Sobol point n, each bit-reversed, without a loop (see
// sobol2_reversed in src/shared/sampler.rs).
fn sobol2_reversed(n: u32) -> vec2u {
    var x = n;
    x ^= (x >> 1u) & 0x55555555u;
    x ^= (x >> 2u) & 0x33333333u;
    x ^= (x >> 4u) & 0x0f0f0f0fu;
    x ^= (x >> 8u) & 0x00ff00ffu;
    x ^= (x >> 16u) & 0x0000ffffu;
    return vec2u(n, x);
}

fn mix(seed: u32, k: u32) -> u32 {
    let h = (seed ^ (k * 0x9e3779b9u)) * 0x85ebca6bu;
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
    (*s).group_seed = mix((*s).pixel_seed, (*s).group);
    // The index shuffled for the group: a nested uniform scramble.
    let shuffled = reverseBits(laine_karras_permutation(reverseBits((*s).index), (*s).group_seed));
    (*s).point = sobol2_reversed(shuffled);
    (*s).dim = 0u;
}

//#endif

// The seeds of a pixel's two replicas (REPLICAS is 2), which the kernel hashes once per
// pixel rather than once per sample: on lavapipe the code that starts a sample runs at every
// path segment. Independent samples use none.
fn replica_seeds(pixel: u32, seed: u32) -> vec2u {
//#if SOBOL
    let hashed = pcg_hash(pixel ^ 0x5b0b5eedu);
    return vec2u(pcg_hash(seed + pcg_hash(hashed)), pcg_hash(seed + pcg_hash(1u + hashed)));
//#else
    return vec2u(0u);
//#endif
}

// The numbers of sample `sample` of pixel `pixel` under `seed`, whose replicas' seeds are
// `seeds` (`replica_seeds`).
fn sampler_with_seeds(seeds: vec2u, pixel: u32, sample: u32, seed: u32) -> Sampler {
    var s = Sampler(0u, 0u, sample / REPLICAS, 0u, 0u, vec2u(0u), 0u);
//#if SOBOL
    // Sobol samples draw no PCG numbers: their stream is left unset, as on the CPU.
    s.pixel_seed = select(seeds.x, seeds.y, sample % REPLICAS == 1u);
    sampler_start_group(&s);
//#else
    s.rng = rng_for_sample(pixel, sample, seed);
//#endif
    return s;
}

fn sampler_for_sample(pixel: u32, sample: u32, seed: u32) -> Sampler {
    return sampler_with_seeds(replica_seeds(pixel, seed), pixel, sample, seed);
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
//#endif
    return sampler_next_in_group(s);
}

// sampler_next where the group surely has a number left: the first or second number after
// sampler_begin or a new sample. Lavapipe runs the body of sampler_next's test for a group's
// end for all lanes, taken or not: a group's start (two hashes, two bit reversals) at every
// number drawn.
fn sampler_next_in_group(s: ptr<function, Sampler>) -> f32 {
//#if SOBOL
    // Owen scrambling, rev(LK(rev(v))), of a point kept bit-reversed.
    let seed = mix((*s).group_seed, (*s).dim);
    let bits = select((*s).point.y, (*s).point.x, (*s).dim == 0u);
    let scrambled = reverseBits(laine_karras_permutation(bits, seed));
    (*s).dim += 1u;
    return f32(scrambled >> 8u) * (1.0 / 16777216.0);
//#else
    var state = (*s).rng;
    let u = rng_next(&state);
    (*s).rng = state;
    return u;
//#endif
}
