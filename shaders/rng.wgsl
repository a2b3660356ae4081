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

//#if ALPHA
// A see-through surface's number in [0, 1) for a ray meeting primitive `primitive` (an
// instance's `triangle`, else 0) (twin: alpha_number in src/shared/rng.rs).
fn alpha_number(origin: vec3f, dir: vec3f, primitive: u32, triangle: u32) -> f32 {
    var h = pcg_hash(primitive ^ pcg_hash(triangle));
    let o = bitcast<vec3u>(origin);
    let d = bitcast<vec3u>(dir);
    h = pcg_hash(h ^ o.x);
    h = pcg_hash(h ^ o.y);
    h = pcg_hash(h ^ o.z);
    h = pcg_hash(h ^ d.x);
    h = pcg_hash(h ^ d.y);
    h = pcg_hash(h ^ d.z);
    return f32(h >> 8u) * (1.0 / 16777216.0);
}
//#endif
