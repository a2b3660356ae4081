// A disk (twin: src/shape/disk.rs). `Closest::shape.w` keeps its plane's offset.

// Distance along the ray to disk s, or -1 for a miss: where it crosses the plane (from the
// ray's origin to the centre first, as for quads), if within the radius. Rays parallel to the
// plane (|denom| < PARALLEL_DENOMINATOR) miss.
fn disk_distance(s: Disk, ray: Ray) -> f32 {
    let denom = dot(s.normal, ray.dir);
    let facing = abs(denom) >= PARALLEL_DENOMINATOR;
    let to_center = s.center - ray.origin;
    let t = dot(s.normal, to_center) / select(1.0, denom, facing);
    let planar = t * ray.dir - to_center;
    return select(-1.0, t, facing && dot(planar, planar) <= s.radius * s.radius);
}

fn consider_disk(s: Disk, index: u32, ray: Ray, in_order: bool, c: ptr<function, Closest>) {
    let t = disk_distance(s, ray);
    if select(replaces(t, (KIND_DISK << PRIMITIVE_INDEX_BITS) | index, c), replaces_in_order(t, c), in_order) {
        record_hit(t, (KIND_DISK << PRIMITIVE_INDEX_BITS) | index, c);
        (*c).material = s.material;
        (*c).outward = s.normal;
        (*c).shape.w = s.d;
//#if READS_UVS
        // Polar: the angle from the tangent over 2 pi, the distance from the centre over the
        // radius (see Disk::uv).
        let from_center = ray.origin + t * ray.dir - s.center;
        let angle = atan2(dot(from_center, s.bitangent), dot(from_center, s.tangent));
        let u = select(angle, angle + 2.0 * PI, angle < 0.0) / (2.0 * PI);
        (*c).uv = vec2f(min(u, ONE_BELOW), length(from_center) / s.radius);
//#endif
    }
}

// Projected onto its plane, as a quad's point.
fn disk_surface(c: Closest, along_ray: vec3f, n: vec3f) -> Surface {
    return plane_surface(along_ray, n, c.shape.w);
}

fn disk_hit_uv(c: Closest, point: vec3f) -> vec2f {
    return c.uv;
}

//#if NEE
// Uniform on its area (l: position its centre, u and v its frame's axes times its radius).
fn disk_light_sample(l: Light, x: vec3f, u1: f32, u2: f32) -> LightSample {
    let a = unit_disk(u1, u2);
    return area_light_sample(l, x, l.position + a.x * l.u + a.y * l.v);
}

fn disk_light_pdf(l: Light, x: vec3f, p: vec3f, dir: vec3f) -> f32 {
    return area_pdf(l, x, p, dir);
}
//#endif
