// A parallelogram (twin: src/shape/quad.rs). `Closest::shape.w` keeps its plane's offset.

// Distance along the ray to quad q, or -1 for a miss. Branch-free: SIMD drivers run every
// branch for some lane anyway. Rays parallel to the plane (|denom| < PARALLEL_DENOMINATOR) miss; their
// division is replaced by a harmless one. From the ray's origin to the corner first: exact
// far from the world's origin, where n . q - n . o would cancel. A quad counts as hit up to
// edge_tolerance (a fraction of each edge) past its edges, so that rays cannot slip between
// the quads meeting at a box edge (see src/shape/quad.rs).
fn quad_distance(q: Quad, ray: Ray) -> f32 {
    let denom = dot(q.normal, ray.dir);
    let facing = abs(denom) >= PARALLEL_DENOMINATOR;
    let to_corner = q.q - ray.origin;
    let t = dot(q.normal, to_corner) / select(1.0, denom, facing);
    let planar = t * ray.dir - to_corner;
    let alpha = dot(planar, q.alpha_axis);
    let beta = dot(planar, q.beta_axis);
    let lo = -q.edge_tolerance;
    let hi = 1.0 + q.edge_tolerance;
    let inside = alpha >= lo && alpha <= hi && beta >= lo && beta <= hi;
    return select(-1.0, t, facing && inside);
}

fn consider_quad(q: Quad, index: u32, ray: Ray, in_order: bool, c: ptr<function, Closest>) {
    consider_quad_at(quad_distance(q, ray), q, index, ray, in_order, c);
}

// Quad q met at t (-1: missed); kernels with the scene inlined compute t with their own copy of
// quad_distance per quad, its constant zeros left out (see inline_scene in src/gpu/shader.rs).
fn consider_quad_at(t: f32, q: Quad, index: u32, ray: Ray, in_order: bool, c: ptr<function, Closest>) {
    if select(replaces(t, (KIND_QUAD << PRIMITIVE_INDEX_BITS) | index, c), replaces_in_order(t, c), in_order) {
        record_hit(t, (KIND_QUAD << PRIMITIVE_INDEX_BITS) | index, c);
        (*c).material = q.material;
        (*c).outward = q.normal;
        (*c).shape.w = q.d;
//#if READS_UVS
        let along_corner = ray.origin + t * ray.dir - q.q;
        (*c).uv = vec2f(dot(along_corner, q.alpha_axis), dot(along_corner, q.beta_axis));
//#endif
    }
}

// Projected onto its plane.
fn quad_surface(c: Closest, along_ray: vec3f, n: vec3f) -> Surface {
    return plane_surface(along_ray, n, c.shape.w);
}

// (a, b) of q + a u + b v, found where it was hit.
fn quad_hit_uv(c: Closest, point: vec3f) -> vec2f {
    return c.uv;
}

//#if NEE
// Uniform on its area (l: position its corner, u and v its edges).
fn quad_light_sample(l: Light, x: vec3f, u1: f32, u2: f32) -> LightSample {
    return area_light_sample(l, x, l.position + u1 * l.u + u2 * l.v);
}

fn quad_light_pdf(l: Light, x: vec3f, p: vec3f, dir: vec3f) -> f32 {
    return area_pdf(l, x, p, dir);
}
//#endif
