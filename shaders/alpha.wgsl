// See-through surfaces (twin: passes_through in src/cpu/intersect.rs; assets::alpha): whether a
// ray passes a triangle of a MASK or BLEND material where it meets it.

//#if ALPHA
// Whether `ray` passes through triangle `triangle` of material `material` at barycentric
// weights `weights`, the primitive packed as `packed` (with an instance's triangle
// `instanced`, else 0).
fn passes_through(material: u32, triangle: u32, weights: vec2f, ray: Ray, packed: u32, instanced: u32) -> bool {
    let m = materials[material];
    if m.alpha_mode == 0u {
        return false;
    }
    var texture = 1.0;
    if m.alpha_size.x > 0.0 {
        var uv = weights;
//#if TRIANGLE_UVS
        uv = interpolated_uv(triangle, weights);
//#endif
//#if TRIANGLE_UVS1
        if (m.alpha_lookup & LOOKUP_UV1) != 0u {
            uv = interpolated_uv1(triangle, weights);
        }
//#endif
        texture = image_at(m.alpha_image, m.alpha_size, m.alpha_lookup, uv).x;
    }
    let alpha = m.alpha_factor * texture;
    if m.alpha_mode == ALPHA_MASK {
        return alpha < m.alpha_cutoff;
    }
    return alpha_number(ray.origin, ray.dir, packed, instanced) >= alpha;
}
//#endif
