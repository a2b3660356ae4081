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

// Word i of the sum plus `part` and the carry in; the carry out in `carry`.
fn add_word(word: vec3u, part: vec3u, carry: ptr<function, vec3u>) -> vec3u {
    let s = word + part;
    let t = s + *carry;
    *carry = select(vec3u(0u), vec3u(1u), (s < part) | (t < *carry));
    return t;
}

// Samples of one pixel summed exactly in five words from word `base` of a wide sum: a pixel's
// samples nearly always start in one of three neighbouring words (every sample within a factor
// of 2^32 of the first fits, and some up to 2^64 away), so each adds to four words and a carry
// rather than rippling through all ten; `wide_add_window` puts a window into its wide sum when
// the dispatch ends. The fifth word takes at most one carry a sample, and cannot overflow.
struct Window {
    v0: vec3u,
    v1: vec3u,
    v2: vec3u,
    v3: vec3u,
    v4: vec3u,
}

// No sample has anchored the window's channel yet.
const NO_BASE: u32 = 0xffffffffu;

// The base of a window first meeting the addend (per channel): a word below it, so samples
// up to 2^32 dimmer fit too.
fn window_base(a: Addend) -> vec3u {
    return max(a.word, vec3u(1u)) - vec3u(1u);
}

// Whether the addend fits the window anchored at `base` (zero fits anywhere), per channel.
fn fits_window(a: Addend, base: vec3u) -> vec3<bool> {
    return ((a.lo | a.hi) == vec3u(0u)) | (a.word - base < vec3u(3u));
}

// The addend where `keep` holds, else zero (which any window takes without effect).
fn only_if(a: Addend, keep: bool) -> Addend {
    let zero = vec3u(0u);
    return Addend(a.word, select(zero, a.lo, keep), select(zero, a.hi, keep));
}

// The window plus an addend that fits it (`fits_window`).
fn window_add(w: Window, base: vec3u, a: Addend) -> Window {
    let offset = a.word - base;
    let first = offset == vec3u(0u);
    let second = offset == vec3u(1u);
    let third = offset == vec3u(2u);
    let zero = vec3u(0u);
    var c = vec3u(0u);
    let v0 = add_word(w.v0, select(zero, a.lo, first), &c);
    let v1 = add_word(w.v1, select(select(zero, a.lo, second), a.hi, first), &c);
    let v2 = add_word(w.v2, select(select(zero, a.lo, third), a.hi, second), &c);
    let v3 = add_word(w.v3, select(zero, a.hi, third), &c);
    return Window(v0, v1, v2, v3, w.v4 + c);
}

// `w` where `pick` is false, else `v`.
fn select_window(w: Window, v: Window, pick: bool) -> Window {
    return Window(select(w.v0, v.v0, pick), select(w.v1, v.v1, pick), select(w.v2, v.v2, pick),
        select(w.v3, v.v3, pick), select(w.v4, v.v4, pick));
}

// Word `offset` of the window (0 past its fifth).
fn window_word(w: Window, offset: vec3u) -> vec3u {
    return select(vec3u(0u), w.v0, offset == vec3u(0u))
        | select(vec3u(0u), w.v1, offset == vec3u(1u))
        | select(vec3u(0u), w.v2, offset == vec3u(2u))
        | select(vec3u(0u), w.v3, offset == vec3u(3u))
        | select(vec3u(0u), w.v4, offset == vec3u(4u));
}

// The wide sum plus a window anchored at `base`. A window from word 6 (the highest a sample
// anchors) reaches past word 9, but nothing is there: fewer than 2^32 samples sum below 2^309.
fn wide_add_window(a: Wide, base: vec3u, w: Window) -> Wide {
    var c = vec3u(0u);
    let w0 = add_word(a.w0, window_word(w, vec3u(0u) - base), &c);
    let w1 = add_word(a.w1, window_word(w, vec3u(1u) - base), &c);
    let w2 = add_word(a.w2, window_word(w, vec3u(2u) - base), &c);
    let w3 = add_word(a.w3, window_word(w, vec3u(3u) - base), &c);
    let w4 = add_word(a.w4, window_word(w, vec3u(4u) - base), &c);
    let w5 = add_word(a.w5, window_word(w, vec3u(5u) - base), &c);
    let w6 = add_word(a.w6, window_word(w, vec3u(6u) - base), &c);
    let w7 = add_word(a.w7, window_word(w, vec3u(7u) - base), &c);
    let w8 = add_word(a.w8, window_word(w, vec3u(8u) - base), &c);
    let w9 = add_word(a.w9, window_word(w, vec3u(9u) - base), &c);
    return Wide(w0, w1, w2, w3, w4, w5, w6, w7, w8, w9);
}

// The wide sum plus one sample.
fn wide_add(a: Wide, v: vec3f) -> Wide {
    let d = decompose(v);
    let zero = vec3u(0u);
    return wide_add_window(a, d.word, Window(d.lo, d.hi, zero, zero, zero));
}
