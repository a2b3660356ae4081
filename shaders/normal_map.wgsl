// Normal maps (twin: normal_mapped in src/cpu/shapes.rs; scene::normal_map).

//#if NORMAL_MAPS
fn corner_tangent(at: u32) -> vec4f {
    return vec4f(triangle_tangents[at], triangle_tangents[at + 1u], triangle_tangents[at + 2u],
        triangle_tangents[at + 3u]);
}

// Unit shading (on unit outward's side) bent by material m's normal map at texture coordinates
// uv, in the frame of triangle i's corner tangents interpolated at weights (MikkTSpace's
// per-pixel rule: the tangent as interpolated, the bitangent its sign x shading x tangent);
// shading where the tangent or the result vanishes; reflected into outward's hemisphere.
fn normal_mapped(m: Material, i: u32, weights: vec2f, uv: vec2f, shading: vec3f, outward: vec3f) -> vec3f {
    let at = 12u * i;
    let t = (1.0 - weights.x - weights.y) * corner_tangent(at) + weights.x * corner_tangent(at + 4u)
        + weights.y * corner_tangent(at + 8u);
    let tangent = t.xyz;
    if !(dot(tangent, tangent) > 1e-12) {
        return shading;
    }
    let sign = select(1.0, -1.0, t.w < 0.0);
    let bitangent = sign * cross(shading, tangent);
    let texel = image_at(m.normal_map_image, m.normal_map_size, m.normal_map_lookup, uv);
    let local = (2.0 * texel - vec3f(1.0)) * vec3f(m.normal_map_scale, m.normal_map_scale, 1.0);
    let bent = local.x * tangent + local.y * bitangent + local.z * shading;
    let len2 = dot(bent, bent);
    if !(len2 > 1e-12) {
        return shading;
    }
    // Reflected, not negated, into outward's hemisphere: a steep texel keeps the way it slopes.
    let unit = bent / sqrt(len2);
    let reflected = unit - 2.0 * min(dot(unit, outward), 0.0) * outward;
    return reflected / sqrt(dot(reflected, reflected));
}
//#endif
