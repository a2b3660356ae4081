// The film's exact sums, twin of src/shared/exact_sum.rs: every non-negative f32 is an integer multiple
// of 2^-149 below 2^128, so a pixel's sum of fewer than 2^32 samples is an integer below 2^309
// in units of 2^-149: ten 32-bit words per channel, least significant first, carried by hand
// (WGSL has no 64-bit integers). Integer addition is associative, so any split of a render's
// samples (dispatches, passes, checkpoints, shards) sums to the same bits, and no finite sample
// is rounded away, however dim or bright.
struct Wide {
    w0: vec3u,
    w1: vec3u,
    w2: vec3u,
    w3: vec3u,
    w4: vec3u,
    w5: vec3u,
    w6: vec3u,
    w7: vec3u,
    w8: vec3u,
    w9: vec3u,
}

// Every channel finite and non-negative (or -0), tested on the bits (WGSL lets implementations
// assume floats are finite). Twin of film::is_valid_sample.
fn valid_sample(v: vec3f) -> bool {
    let bits = bitcast<vec3u>(v);
    return all((bits < vec3u(NOT_FINITE_BITS)) | (bits == vec3u(0x80000000u)));
}

// A valid sample as the word its unit falls in and the two words it adds there: the integer
// mantissa shifted to its place (twin of exact_sum::decompose).
struct Addend {
    word: vec3u,
    lo: vec3u,
    hi: vec3u,
}

fn decompose(v: vec3f) -> Addend {
    let bits = bitcast<vec3u>(v) & vec3u(0x7fffffffu);
    let exponent = bits >> vec3u(23u);
    let fraction = bits & vec3u(0x7fffffu);
    let normal = exponent != vec3u(0u);
    let mantissa = select(fraction, fraction | vec3u(0x800000u), normal);
    let position = select(vec3u(0u), exponent - vec3u(1u), normal);
    let shift = position & vec3u(31u);
    // A shift by 32 is a shift by 0 in WGSL: the high part of an unshifted mantissa is zero.
    let hi = select(mantissa >> (vec3u(32u) - shift), vec3u(0u), shift == vec3u(0u));
    return Addend(position >> vec3u(5u), mantissa << shift, hi);
}

// Word i of the sum plus what the addend puts there and the carry in; the carry out in `carry`.
fn add_word(word: vec3u, i: u32, a: Addend, carry: ptr<function, vec3u>) -> vec3u {
    let part = select(vec3u(0u), a.lo, a.word == vec3u(i))
        | select(vec3u(0u), a.hi, a.word + vec3u(1u) == vec3u(i));
    let s = word + part;
    let t = s + *carry;
    *carry = select(vec3u(0u), vec3u(1u), (s < part) | (t < *carry));
    return t;
}

fn wide_add(a: Wide, v: vec3f) -> Wide {
    let d = decompose(v);
    var c = vec3u(0u);
    let w0 = add_word(a.w0, 0u, d, &c);
    let w1 = add_word(a.w1, 1u, d, &c);
    let w2 = add_word(a.w2, 2u, d, &c);
    let w3 = add_word(a.w3, 3u, d, &c);
    let w4 = add_word(a.w4, 4u, d, &c);
    let w5 = add_word(a.w5, 5u, d, &c);
    let w6 = add_word(a.w6, 6u, d, &c);
    let w7 = add_word(a.w7, 7u, d, &c);
    let w8 = add_word(a.w8, 8u, d, &c);
    let w9 = add_word(a.w9, 9u, d, &c);
    return Wide(w0, w1, w2, w3, w4, w5, w6, w7, w8, w9);
}
