// The film's exact sums, twin of src/film.rs: a sample rounded to a multiple of 2^-32 and added
// as an integer, so any split of a render's samples (dispatches, passes, checkpoints, shards)
// sums to the same bits. WGSL has no 64-bit integers: a sum is three 32-bit words per channel,
// least significant first (w0 holds the fraction), carried by hand. Samples are below 2^32 and
// a pixel takes fewer than 2^32 of them, so a sum stays below 2^64 and never overflows.
struct Fixed {
    w0: vec3u,
    w1: vec3u,
    w2: vec3u,
}

// Every channel finite, non-negative (or -0) and below 2^32, tested on the bits (WGSL lets
// implementations assume floats are finite). Twin of film::is_valid_sample.
fn valid_sample(v: vec3f) -> bool {
    let bits = bitcast<vec3u>(v);
    return all((bits < vec3u(TOO_LARGE_BITS)) | (bits == vec3u(0x80000000u)));
}

const TWO_TO_32: f32 = 4294967296.0;

// A valid sample in fixed point (two words), rounded to nearest with ties to even: every step
// but the last is exact (floor, and a float minus its own leading bits).
fn to_fixed(v: vec3f) -> array<vec3u, 2> {
    let whole = floor(v);
    let fraction = round((v - whole) * TWO_TO_32);
    return array<vec3u, 2>(vec3u(fraction), vec3u(whole));
}

fn carry(sum: vec3u, addend: vec3u) -> vec3u {
    return select(vec3u(0u), vec3u(1u), sum < addend);
}

fn fixed_add(a: Fixed, b: array<vec3u, 2>) -> Fixed {
    let s0 = a.w0 + b[0];
    let c0 = carry(s0, b[0]);
    let t1 = a.w1 + b[1];
    let s1 = t1 + c0;
    let c1 = carry(t1, b[1]) + carry(s1, c0);
    return Fixed(s0, s1, a.w2 + c1);
}
