// The viewer's display pass: each window pixel shows its film pixel's 8-bit levels, decided on
// the accumulator's exact sums in place (twin of src/film/levels.rs): level k where sum >= n x
// threshold k, compared as wide integers, so that the window shows what the image file of the
// same samples holds, byte for byte. The host prepends `struct Display` (generated from
// `GpuDisplay`) and the accumulator's layout constants (ACCUM_WORDS, ACCUM_COUNT,
// ACCUM_EVEN_SUM, ACCUM_ODD_SUM, SUM_WORDS).

@group(0) @binding(0) var<uniform> display: Display;
@group(0) @binding(1) var<storage, read> accum: array<u32>;
// Level k's threshold as f32 bits at thresholds[k / 4][k % 4] (levels::Levels); level 0's is
// unused.
@group(0) @binding(2) var<uniform> thresholds: array<vec4u, 64>;

// One triangle over the whole viewport.
@vertex
fn vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let corner = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4f(corner * 2.0 - 1.0, 0.0, 1.0);
}

// a x b as (low word, high word).
fn mul_wide(a: u32, b: u32) -> vec2u {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2u((mid << 16u) | (p00 & 0xffffu), a1 * b1 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

// Word i of `product` shifted left by `bit` bits and then by `word` words.
fn shifted_word(product: vec2u, word: u32, bit: u32, i: u32) -> u32 {
    // A shift by 32 is a shift by 0 in WGSL: the parts that would cross are zero at bit 0.
    let down = select(0u, 32u - bit, bit != 0u);
    if i == word {
        return product.x << bit;
    }
    if i == word + 1u {
        return select(0u, product.x >> down, bit != 0u) | (product.y << bit);
    }
    if i == word + 2u {
        return select(0u, product.y >> down, bit != 0u);
    }
    return 0u;
}

// Whether the channel's sum of n samples is at least n x the threshold with f32 bits `t`
// (twin of levels::at_least).
fn at_least(sum: ptr<function, array<u32, SUM_WORDS>>, n: u32, t: u32) -> bool {
    if t >= 0x7f800000u {
        return false;
    }
    let exponent = t >> 23u;
    let fraction = t & 0x7fffffu;
    let normal = exponent != 0u;
    let mantissa = select(fraction, fraction | 0x800000u, normal);
    let position = select(0u, exponent - 1u, normal);
    let product = mul_wide(n, mantissa);
    let word = position >> 5u;
    let bit = position & 31u;
    for (var i = i32(SUM_WORDS) - 1; i >= 0; i--) {
        let s = (*sum)[i];
        let p = shifted_word(product, word, bit, u32(i));
        if s != p {
            return s > p;
        }
    }
    return true;
}

fn threshold(k: u32) -> u32 {
    return thresholds[k >> 2u][k & 3u];
}

// The mean to f32 precision, near enough to find the level's neighbourhood.
fn rounded_mean(sum: ptr<function, array<u32, SUM_WORDS>>, n: u32) -> f32 {
    var m = 0.0;
    // Words below 3 are below 2^-53 (they cannot move a level's neighbourhood); a word past
    // f32's range makes the mean infinite, which the exact comparisons then settle.
    for (var w = 3u; w < SUM_WORDS; w++) {
        if (*sum)[w] != 0u {
            m += f32((*sum)[w]) * exp2(f32(32u * w) - 149.0);
        }
    }
    return m / f32(n);
}

// The channel's level: the largest k whose threshold the exact mean reaches (thresholds do
// not decrease with k). The rounded mean's level, found among the thresholds as floats, is
// within a step or two; the exact comparisons settle it, as levels::Levels::level does.
fn level(sum: ptr<function, array<u32, SUM_WORDS>>, n: u32) -> u32 {
    let mean = rounded_mean(sum, n);
    var lo = 0u;
    var hi = 255u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if mean >= bitcast<f32>(threshold(mid)) {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    var k = lo;
    while k < 255u && at_least(sum, n, threshold(k + 1u)) {
        k++;
    }
    while k > 0u && !at_least(sum, n, threshold(k)) {
        k--;
    }
    return k;
}

@fragment
fn fragment(@builtin(position) position: vec4f) -> @location(0) vec4f {
    let x = u32(position.x) / display.scale;
    let y = u32(position.y) / display.scale;
    if x >= display.film_size.x || y >= display.film_size.y {
        return vec4f(0.0, 0.0, 0.0, 1.0);
    }
    let slot = ACCUM_WORDS * (y * display.film_size.x + x);
    let n = accum[slot + ACCUM_COUNT];
    var levels = vec3u(0u);
    if n > 0u {
        for (var c = 0u; c < 3u; c++) {
            // The pixel's sum: its even-index samples' plus its odd-index samples'.
            var sum: array<u32, SUM_WORDS>;
            var carry = 0u;
            for (var w = 0u; w < SUM_WORDS; w++) {
                let even = accum[slot + ACCUM_EVEN_SUM + 3u * w + c];
                let odd = accum[slot + ACCUM_ODD_SUM + 3u * w + c];
                let s = even + odd;
                let t = s + carry;
                carry = select(0u, 1u, (s < even) | (t < carry));
                sum[w] = t;
            }
            levels[c] = level(&sum, n);
        }
    }
    // k / 255 is within an f32 rounding of k when stored as 8-bit unorm (rounded to nearest).
    return vec4f(vec3f(levels) / 255.0, 1.0);
}
