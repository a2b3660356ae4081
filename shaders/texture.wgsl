// Texture lookups (twin: src/material/texture.rs): a material's albedo at a hit.

//#if CHECKER || UV_CHECKER
// floor(x) mod 2, as 0 or 1, in f32 arithmetic (exact below 2^24; no integer conversion).
fn parity(x: f32) -> f32 {
    let cell = floor(x);
    return cell - 2.0 * floor(cell * 0.5);
}
//#endif

//#if UV_CHECKER || IMAGE_TEXTURE || NORMAL_MAPS
// A sphere's (longitude, latitude) at unit outward direction n (Ray Tracing: The Next Week).
fn sphere_uv(n: vec3f) -> vec2f {
    let u = (atan2(-n.z, n.x) + PI) / (2.0 * PI);
    let v = acos(clamp(-n.y, -1.0, 1.0)) / PI;
    return vec2f(u, v);
}
//#endif

//#if IMAGE_TEXTURE || ENVIRONMENT || NORMAL_MAPS
// Texel (x, y) of the image of `width` columns whose texels start at `start` among the images.
fn texel(start: u32, width: u32, x: u32, y: u32) -> vec3f {
    return image_value(start + y * width + x).xyz;
}

// Integer-valued i wrapped into 0..n in f32 arithmetic (as the CPU does), then kept in range
// whatever i was (NaN included): the kernel runs without bounds checks.
fn wrap(i: f32, n: f32) -> u32 {
    return min(u32(clamp(i - n * floor(i / n), 0.0, n - 1.0)), u32(n) - 1u);
}

// An image filtered bilinearly at image coordinates (s across, t down; texel centres at
// half-integers), wrapping around both edges.
fn bilinear(start: u32, width: u32, height: u32, s: f32, t: f32) -> vec3f {
    let w = f32(width);
    let h = f32(height);
    let x = s * w - 0.5;
    let y = t * h - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xa = wrap(x0, w);
    let xb = wrap(x0 + 1.0, w);
    let ya = wrap(y0, h);
    let yb = wrap(y0 + 1.0, h);
    let top = texel(start, width, xa, ya) * (1.0 - fx) + texel(start, width, xb, ya) * fx;
    let bottom = texel(start, width, xa, yb) * (1.0 - fx) + texel(start, width, xb, yb) * fx;
    return top * (1.0 - fy) + bottom * fy;
}
//#endif

fn albedo_at(m: Material, hit: Hit) -> vec3f {
//#if IMAGE_TEXTURE
    if m.texture == TEXTURE_IMAGE {
        return bilinear(m.texture_image, u32(m.texture_odd.x), u32(m.texture_odd.y), hit.uv.x, 1.0 - hit.uv.y);
    }
//#endif
    var parities = 0.0;
//#if CHECKER
    if m.texture == TEXTURE_CHECKER {
        let p = (hit.point + m.texture_shift) / m.texture_scale;
        parities = parity(p.x) + parity(p.y) + parity(p.z);
    }
//#endif
//#if UV_CHECKER
    if m.texture == TEXTURE_UV_CHECKER {
        let p = hit.uv * m.texture_scale;
        parities = parity(p.x) + parity(p.y);
    }
//#endif
//#if CHECKER || UV_CHECKER
    return select(m.albedo, m.texture_odd, parity(parities) != 0.0);
//#else
    return m.albedo;
//#endif
}

//#if CHECKER || UV_CHECKER || IMAGE_TEXTURE
// m with its albedo looked up at hit once, for the several uses a path vertex makes of it (light
// sample, BSDF sample, emission): each lookup in an image costs four gathers on lavapipe.
fn with_albedo_at(m: Material, hit: Hit) -> Material {
    var out = m;
    out.albedo = albedo_at(m, hit);
    out.texture = TEXTURE_NONE;
    return out;
}
//#endif
