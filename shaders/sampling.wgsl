// Warps from uniform numbers (twin: src/shared/warp.rs). Angles stay in [-pi, pi), where
// Vulkan bounds the error of sin and cos.

const PI: f32 = 3.14159265358979;

fn unit_vector(u1: f32, u2: f32) -> vec3f {
    let z = 1.0 - 2.0 * u1;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = PI * (2.0 * u2 - 1.0);
    return vec3f(r * cos(phi), r * sin(phi), z);
}

// Two unit vectors completing unit n to an orthonormal basis (Duff et al. 2017).
struct Basis {
    t: vec3f,
    b: vec3f,
}

fn basis(n: vec3f) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(
        vec3f(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3f(b, sign + n.y * n.y * a, -n.y),
    );
}

// A direction cosine-distributed about unit n from two uniform numbers: n plus a uniform
// unit vector, normalised (n itself where they cancel; twin: warp::cosine_direction).
fn cosine_direction(n: vec3f, u1: f32, u2: f32) -> vec3f {
    let d = n + unit_vector(u1, u2);
    let len2 = dot(d, d);
    return select(n, d / sqrt(len2), len2 > 1e-12);
}

// Uniform on the unit disk (the lens, disk lights).
fn unit_disk(u1: f32, u2: f32) -> vec2f {
    let r = sqrt(u1);
    let phi = PI * (2.0 * u2 - 1.0);
    return vec2f(r * cos(phi), r * sin(phi));
}

// Cosine-weighted about a hit's shading normal: pdf = cos / pi (so a lambertian BSDF x cos =
// albedo x pdf), 0 below the surface.
fn cosine_pdf(hit: Hit, wi: vec3f) -> f32 {
    let cos = dot(hit.shading, wi);
    return select(0.0, cos / PI, cos > 0.0 && !below_surface(hit, wi));
}
