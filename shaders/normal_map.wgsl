// Normal maps (twin: normal_mapped in src/cpu/intersect.rs; assets::normal_map).

//#if NORMAL_MAPS
// A normal map as a material holds it: where its texels start, its width and height (0:
// none), its scale and how it is read.
struct NormalMap {
    image: u32,
    size: vec2f,
    scale: f32,
    lookup: u32,
}

// Material m's normal map, which bends its shading normal.
fn base_normal_map(m: Material) -> NormalMap {
    return NormalMap(m.normal_map_image, m.normal_map_size, m.normal_map_scale, m.normal_map_lookup);
}

//#if CLEARCOAT
// Material m's clear coat's normal map, which bends the coat's normal (hit.coat).
fn coat_normal_map(m: Material) -> NormalMap {
    return NormalMap(m.coat_normal_map_image, m.coat_normal_map_size, m.coat_normal_map_scale, m.coat_normal_map_lookup);
}
//#endif

//#if CLEARCOAT
// Unit n, a mapped normal on the side of the unit geometric normal ng that faces wo, bent toward
// ng where wo's mirror image about it would leave below min(0.9 wo.ng, 0.01) (twin:
// valid_reflection in src/assets/normal_map.rs, whose comment derives it).
fn valid_reflection(ng: vec3f, wo: vec3f, n: vec3f) -> vec3f {
    let iz = max(dot(wo, ng), 0.0);
    let threshold = min(0.9 * iz, 0.01);
    let reflected = 2.0 * dot(n, wo) * n - wo;
    if dot(reflected, ng) >= threshold {
        return n;
    }
    let along = n - dot(n, ng) * ng;
    let len2 = dot(along, along);
    if !(len2 > 1e-20) {
        return n;
    }
    let x = along / sqrt(len2);
    let ix = dot(wo, x);
    let a = ix * ix + iz * iz;
    if !(a > 1e-20) {
        return n;
    }
    let b = 2.0 * (a + iz * threshold);
    let c = (threshold + iz) * (threshold + iz);
    let root = sqrt(max(b * b - 4.0 * a * c, 0.0));
    // The smaller root as c / (b + root), which keeps its digits where it is near 0.
    let u = clamp(select(c / (b + root), 0.25 * (b + root) / a, ix < 0.0), 0.0, 1.0);
    let bent = sqrt(1.0 - u) * x + sqrt(u) * ng;
    return bent / length(bent);
}
//#endif

fn corner_tangent(at: u32) -> vec4f {
    return vec4f(triangle_tangents[at], triangle_tangents[at + 1u], triangle_tangents[at + 2u],
        triangle_tangents[at + 3u]);
}

// Unit shading (on unit outward's side) bent by normal map `map` at texture coordinates uv, in
// the frame of triangle i's corner tangents interpolated at weights (MikkTSpace's
// per-pixel rule: the tangent as interpolated, the bitangent its sign x shading x tangent);
// shading where the tangent or the result vanishes; reflected into outward's hemisphere.
fn normal_mapped(map: NormalMap, i: u32, weights: vec2f, uv: vec2f, shading: vec3f, outward: vec3f) -> vec3f {
    let at = 12u * i;
    let t = (1.0 - weights.x - weights.y) * corner_tangent(at) + weights.x * corner_tangent(at + 4u)
        + weights.y * corner_tangent(at + 8u);
    return bent_by_map(map, t, uv, shading, outward);
}

//#if INSTANCES
// A mesh corner's tangent in scene coordinates, as flattening places a copy's (twin:
// Instance::tangent_to_world): its direction by the instance's to_world, unit, its sign turned
// where the placement mirrors; zero stays zero.
fn instance_corner_tangent(inst: Instance, at: u32) -> vec4f {
    let t = corner_tangent(at);
    let along = vec3f(dot(inst.to_world_x.xyz, t.xyz), dot(inst.to_world_y.xyz, t.xyz),
        dot(inst.to_world_z.xyz, t.xyz));
    let len2 = dot(along, along);
    let unit = select(vec3f(0.0), along / sqrt(len2), len2 > 0.0);
    let mirrors = dot(inst.to_world_x.xyz, cross(inst.to_world_y.xyz, inst.to_world_z.xyz)) < 0.0;
    return vec4f(unit, select(t.w, -t.w, mirrors));
}

// normal_mapped for triangle i of an instanced mesh, its corner tangents placed by inst.
fn instanced_normal_mapped(map: NormalMap, inst: Instance, i: u32, weights: vec2f, uv: vec2f, shading: vec3f, outward: vec3f) -> vec3f {
    let at = 12u * i;
    let t = (1.0 - weights.x - weights.y) * instance_corner_tangent(inst, at)
        + weights.x * instance_corner_tangent(inst, at + 4u)
        + weights.y * instance_corner_tangent(inst, at + 8u);
    return bent_by_map(map, t, uv, shading, outward);
}
//#endif

// shading bent by `map` at uv in the frame of the interpolated tangent t.
fn bent_by_map(map: NormalMap, t: vec4f, uv: vec2f, shading: vec3f, outward: vec3f) -> vec3f {
    let tangent = t.xyz;
    if !(dot(tangent, tangent) > 1e-12) {
        return shading;
    }
    let sign = select(1.0, -1.0, t.w < 0.0);
    let bitangent = sign * cross(shading, tangent);
    let texel = image_at(map.image, map.size, map.lookup, uv);
    let local = (2.0 * texel - vec3f(1.0)) * vec3f(map.scale, map.scale, 1.0);
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
