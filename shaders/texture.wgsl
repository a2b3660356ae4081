// Texture lookups (twin: src/cpu/texture.rs): a material's albedo at a hit.

//#if CHECKER || UV_CHECKER
// floor(x) mod 2, as 0 or 1, in f32 arithmetic (exact below 2^24; no integer conversion).
fn parity(x: f32) -> f32 {
    let cell = floor(x);
    return cell - 2.0 * floor(cell * 0.5);
}
//#endif

//#if UV_CHECKER
// A sphere's (longitude, latitude) at unit outward direction n (Ray Tracing: The Next Week).
fn sphere_uv(n: vec3f) -> vec2f {
    let u = (atan2(-n.z, n.x) + PI) / (2.0 * PI);
    let v = acos(clamp(-n.y, -1.0, 1.0)) / PI;
    return vec2f(u, v);
}
//#endif

fn albedo_at(m: Material, hit: Hit) -> vec3f {
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
