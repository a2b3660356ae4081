// A sphere (twin: src/shape/sphere.rs). `Closest::shape` keeps its centre and radius.

// Distance along the ray to the nearest crossing of sphere s ahead of its origin, or -1.
fn sphere_distance(s: Sphere, ray: Ray) -> f32 {
    let oc = s.center - ray.origin;
    let h = dot(ray.dir, oc);
    // r^2 - |oc - h d|^2: no cancellation for small or distant spheres.
    let perpendicular = oc - h * ray.dir;
    let disc = s.radius * s.radius - dot(perpendicular, perpendicular);
    let sq = sqrt(max(disc, 0.0));
    let near = h - sq;
    return select(-1.0, select(h + sq, near, near > 0.0), disc >= 0.0);
}

// `in_order`: met in the order of `replaces_in_order` (a constant where called).
fn consider_sphere(s: Sphere, index: u32, ray: Ray, in_order: bool, c: ptr<function, Closest>) {
    let t = sphere_distance(s, ray);
    if select(replaces(t, (KIND_SPHERE << PRIMITIVE_INDEX_BITS) | index, c), replaces_in_order(t, c), in_order) {
        record_hit(t, (KIND_SPHERE << PRIMITIVE_INDEX_BITS) | index, c);
        (*c).material = s.material;
        (*c).outward = (ray.origin + t * ray.dir - s.center) / s.radius;
        (*c).shape = vec4f(s.center, s.radius);
    }
}

// Along the ray's direction from the centre, at the radius.
fn sphere_surface(c: Closest, along_ray: vec3f, n: vec3f) -> Surface {
    let center = c.shape.xyz;
    let radius = c.shape.w;
    let from_center = along_ray - center;
    let point = center + from_center * (abs(radius) / length(from_center));
    let ce = abs(center);
    return Surface(point, POINT_ERROR * (max(ce.x, max(ce.y, ce.z)) + abs(radius)));
}

//#if READS_UVS
fn sphere_hit_uv(c: Closest, point: vec3f) -> vec2f {
    return sphere_uv((point - c.shape.xyz) / abs(c.shape.w));
}
//#endif

//#if NEE
// The cone a sphere subtends from x: unit axis and 1 - cos(half angle); w = 0 when x is
// inside the sphere or the cone is too thin to represent.
fn sphere_cone(center: vec3f, radius: f32, x: vec3f) -> vec4f {
    let to_center = center - x;
    let d2 = dot(to_center, to_center);
    let r2 = radius * radius;
    if !(d2 > r2) {
        return vec4f(0.0);
    }
    let sin2_max = r2 / d2;
    // 1 - sqrt(1 - s) without cancellation for small cones.
    let one_minus_cos = sin2_max / (1.0 + sqrt(1.0 - sin2_max));
    if !(one_minus_cos > 0.0) {
        return vec4f(0.0);
    }
    return vec4f(to_center / sqrt(d2), one_minus_cos);
}

// Uniform in the cone it subtends from x (l: position its centre, size its |radius|).
fn sphere_light_sample(l: Light, x: vec3f, u1: f32, u2: f32) -> LightSample {
    var out = LightSample(vec3f(0.0, 1.0, 0.0), 0.0, x);
    let cone = sphere_cone(l.position, l.size, x);
    if cone.w > 0.0 {
        let axis = cone.xyz;
        let a = u1 * cone.w;
        let cos_theta = 1.0 - a;
        let sin_theta = sqrt(max(a * (2.0 - a), 0.0));
        let phi = PI * (2.0 * u2 - 1.0);
        let frame = basis(axis);
        out.dir = normalize(cos_theta * axis + sin_theta * (cos(phi) * frame.t + sin(phi) * frame.b));
        out.pdf = l.pick / (2.0 * PI * cone.w);
        // Where it meets the sphere (a direction in the cone, from outside: the near root; at
        // the cone's rim, where rounding can miss, the closest approach).
        let dist = sphere_distance(Sphere(l.position, l.size, 0u, 0u), Ray(x, out.dir));
        out.point = x + select(dot(out.dir, l.position - x), dist, dist > 0.0) * out.dir;
    }
    return out;
}

fn sphere_light_pdf(l: Light, x: vec3f, p: vec3f, dir: vec3f) -> f32 {
    let cone = sphere_cone(l.position, l.size, x);
    if cone.w > 0.0 {
        return l.pick / (2.0 * PI * cone.w);
    }
    return 0.0;
}
//#endif
