// The film's exact sums, twin of src/film.rs: a sample rounded to a multiple of 2^-32 and added
// as an integer, so any split of a render's samples (dispatches, passes, checkpoints, shards)
// sums to the same bits. WGSL has no 64-bit integers: a sum is four 32-bit words per channel,
// least significant first (w0 holds the fraction), carried by hand.
struct Fixed {
    w0: vec3u,
    w1: vec3u,
    w2: vec3u,
    w3: vec3u,
}

// Every channel finite, non-negative (or -0) and below 2^64, tested on the bits (WGSL lets
// implementations assume floats are finite). Twin of film::is_valid_sample.
fn valid_sample(v: vec3f) -> bool {
    let bits = bitcast<vec3u>(v);
    return all((bits < vec3u(0x5f800000u)) | (bits == vec3u(0x80000000u)));
}

// A valid sample in fixed point, rounded to nearest with ties to even: every step but the last
// is exact (powers of two, floor, and differences of a float and its own leading bits).
fn to_fixed(v: vec3f) -> Fixed {
    let high = floor(ldexp(v, vec3i(-32)));
    let rest = v - ldexp(high, vec3i(32));
    let low = floor(rest);
    let fraction = round(ldexp(rest - low, vec3i(32)));
    return Fixed(vec3u(fraction), vec3u(low), vec3u(high), vec3u(0u));
}

fn carry(sum: vec3u, addend: vec3u) -> vec3u {
    return select(vec3u(0u), vec3u(1u), sum < addend);
}

fn fixed_add(a: Fixed, b: Fixed) -> Fixed {
    let s0 = a.w0 + b.w0;
    let c0 = carry(s0, b.w0);
    let t1 = a.w1 + b.w1;
    let s1 = t1 + c0;
    let c1 = carry(t1, b.w1) + carry(s1, c0);
    let t2 = a.w2 + b.w2;
    let s2 = t2 + c1;
    let c2 = carry(t2, b.w2) + carry(s2, c1);
    return Fixed(s0, s1, s2, a.w3 + b.w3 + c2);
}
