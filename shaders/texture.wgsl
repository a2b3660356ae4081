// Texture lookups (twins: src/material/texture.rs, and src/assets/image_lookup.rs for reading images): a material's albedo at a hit.

//#if CHECKER || UV_CHECKER
// floor(x) mod 2, as 0 or 1, in f32 arithmetic (exact below 2^24; no integer conversion).
fn parity(x: f32) -> f32 {
    let cell = floor(x);
    return cell - 2.0 * floor(cell * 0.5);
}
//#endif

//#if READS_UVS
// A sphere's (longitude, latitude) at unit outward direction n (Ray Tracing: The Next Week).
fn sphere_uv(n: vec3f) -> vec2f {
    let u = (polynomial_atan2(-n.z, n.x) + PI) / (2.0 * PI);
    let v = polynomial_acos(-n.y) / PI;
    return vec2f(u, v);
}
//#endif

//#if IMAGE_TEXTURE || ENVIRONMENT || NORMAL_MAPS || METALLIC_ROUGHNESS || ALPHA || LAYER_IMAGES
// Texel (x, y) of the image of `width` columns whose texels start at `start` among the images.
fn texel(start: u32, width: u32, x: u32, y: u32) -> vec3f {
    return image_value(start + y * width + x).xyz;
}

// Integer-valued texel index i of an axis of n texels brought into 0..n by wrap mode `mode`
// (ImageLookup's codes), in f32 arithmetic as the CPU does it; kept in range whatever i was.
fn wrapped(mode: u32, i: f32, n: f32) -> u32 {
    var j = i - n * floor(i / n);
    if mode == WRAP_CLAMP {
        j = i;
    } else if mode == WRAP_MIRROR {
        // Period 2n: the image, then the image reversed.
        let m = i - 2.0 * n * floor(i / (2.0 * n));
        j = select(m, 2.0 * n - 1.0 - m, m >= n);
    }
    return min(u32(clamp(j, 0.0, n - 1.0)), u32(n) - 1u);
}

// The texture coordinates an image read as `lookup` says is read at on hit: its UV set's
// (twin: material::texture::uv_at).
fn uv_at(lookup: u32, hit: Hit) -> vec2f {
    return select(hit.uv, hit.uv1, (lookup & LOOKUP_UV1) != 0u);
}

// The image of `size` texels starting at `start` at surface coordinates uv (u across, v up),
// wrapped on each axis and filtered as `lookup` (ImageLookup::bits) says.
fn image_at(start: u32, size: vec2f, lookup: u32, uv: vec2f) -> vec3f {
    return filtered(start, size, lookup, uv.x, 1.0 - uv.y);
}

// An image filtered bilinearly at image coordinates (s across, t down; texel centres at
// half-integers), wrapping around both edges: how environments read their images.
fn bilinear(start: u32, width: u32, height: u32, s: f32, t: f32) -> vec3f {
    return filtered(start, vec2f(f32(width), f32(height)), 0u, s, t);
}

// The image at image coordinates (s across, t down), wrapped and filtered as `lookup` says.
fn filtered(start: u32, size: vec2f, lookup: u32, s: f32, t: f32) -> vec3f {
    let width = u32(size.x);
    let wrap_u = lookup & 3u;
    let wrap_v = (lookup >> 2u) & 3u;
    if (lookup & LOOKUP_NEAREST) != 0u {
        return texel(start, width, wrapped(wrap_u, floor(s * size.x), size.x), wrapped(wrap_v, floor(t * size.y), size.y));
    }
    let x = s * size.x - 0.5;
    let y = t * size.y - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xa = wrapped(wrap_u, x0, size.x);
    let xb = wrapped(wrap_u, x0 + 1.0, size.x);
    let ya = wrapped(wrap_v, y0, size.y);
    let yb = wrapped(wrap_v, y0 + 1.0, size.y);
    let top = texel(start, width, xa, ya) * (1.0 - fx) + texel(start, width, xb, ya) * fx;
    let bottom = texel(start, width, xa, yb) * (1.0 - fx) + texel(start, width, xb, yb) * fx;
    return top * (1.0 - fy) + bottom * fy;
}
//#endif

// The material's colour at hit times the hit's vertex colour (glTF's base colour x COLOR_0;
// twin: material::texture::albedo).
fn albedo_at(m: Material, hit: Hit) -> vec3f {
//#if VERTEX_COLORS
    return texture_at(m, hit) * hit.color;
//#else
    return texture_at(m, hit);
//#endif
}

// The material's texture (its colour: checker, image, or plain) at hit (twin:
// material::texture::value).
fn texture_at(m: Material, hit: Hit) -> vec3f {
//#if IMAGE_TEXTURE
    if m.texture == TEXTURE_IMAGE {
        // Times the image's factor (glTF's factor x texture), which its albedo holds.
        return image_at(m.texture_image, m.texture_odd.xy, m.texture_lookup, uv_at(m.texture_lookup, hit)) * m.albedo;
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

//#if CHECKER || UV_CHECKER || IMAGE_TEXTURE || METALLIC_ROUGHNESS || LAYER_IMAGES
// m with its albedo looked up at hit once, for the several uses a path vertex makes of it (light
// sample, BSDF sample, emission): each lookup in an image costs four gathers on lavapipe. And
// with pbr's metallic and alpha scaled by its metallic-roughness image there (pbr_with_texel;
// a rough plastic's parameter image is its coat table, read by cosine), and its clear coat and
// sheen by its layer images, its specular by its specular images (pbr_with_layers).
fn with_albedo_at(m: Material, hit: Hit) -> Material {
    var out = m;
    out.albedo = texture_at(m, hit);
    out.texture = TEXTURE_NONE;
//#if METALLIC_ROUGHNESS
//#if PBR
    if m.kind == MAT_PBR && m.parameter_image_size.x > 0.0 {
        let uv = uv_at(m.parameter_image_lookup, hit);
        let texel = image_at(m.parameter_image, m.parameter_image_size, m.parameter_image_lookup, uv);
        out = pbr_with_texel(out, texel);
        out.parameter_image_size = vec2f(0.0);
    }
//#endif
//#endif
//#if LAYER_IMAGES
//#if PBR
    let layers = m.layer_image_size.x > 0.0 || m.sheen_image_size.x > 0.0;
    let specular = m.specular_image_size.x > 0.0 || m.specular_color_image_size.x > 0.0;
    if m.kind == MAT_PBR && (layers || specular) {
        out = pbr_with_layers(out, hit);
        out.layer_image_size = vec2f(0.0);
        out.sheen_image_size = vec2f(0.0);
        out.specular_image_size = vec2f(0.0);
        out.specular_color_image_size = vec2f(0.0);
    }
//#endif
//#endif
    return out;
}
//#endif
