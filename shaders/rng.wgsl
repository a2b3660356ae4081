// Counter-based random numbers, bit for bit the same as src/shared/rng.rs.

fn pcg_hash(input: u32) -> u32 {
    let state = input * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rng_for_sample(pixel: u32, sample: u32, seed: u32) -> u32 {
    return pcg_hash(seed + pcg_hash(sample + pcg_hash(pixel)));
}

// Uniform in [0, 1) from the top 24 bits.
fn rng_next(state: ptr<function, u32>) -> f32 {
    let s = *state * 747796405u + 2891336453u;
    *state = s;
    let word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return f32(((word >> 22u) ^ word) >> 8u) * (1.0 / 16777216.0);
}
