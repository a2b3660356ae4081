// GGX microfacets with height-correlated Smith masking-shadowing, in a local frame whose z is
// the shading normal (twin: src/material/microfacet.rs, which says why these forms).

//#if MICROFACET || PLASTIC || PBR
fn ggx_d(alpha: f32, m: vec3f) -> f32 {
    let a2 = alpha * alpha;
    let t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
    return select(0.0, 1.0 / (PI * a2 * t * t), m.z > 0.0);
}

// w.z > MIN_COSINE: nearer the horizon tan^2 overflows.
fn ggx_lambda(alpha: f32, w: vec3f) -> f32 {
    let x = alpha * alpha * (w.x * w.x + w.y * w.y) / (w.z * w.z);
    return 0.5 * (sqrt(1.0 + x) - 1.0);
}

fn ggx_g1(alpha: f32, w: vec3f) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(alpha, w));
}

fn ggx_g2(alpha: f32, wo: vec3f, wi: vec3f) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(alpha, wo) + ggx_lambda(alpha, wi));
}

// A microfacet normal visible from wo (wo.z > 0), on spherical caps (Dupuy and Benyoub 2023).
fn ggx_sample_visible(alpha: f32, wo: vec3f, u1: f32, u2: f32) -> vec3f {
    let v = normalize(vec3f(alpha * wo.x, alpha * wo.y, wo.z));
    let phi = PI * (2.0 * u1 - 1.0);
    let z = (1.0 - u2) * (1.0 + v.z) - v.z;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let h = vec3f(r * cos(phi), r * sin(phi), z) + v;
    let m = vec3f(alpha * h.x, alpha * h.y, max(h.z, 0.0));
    let len2 = dot(m, m);
    return select(vec3f(0.0, 0.0, 1.0), m / sqrt(len2), len2 > 1e-30);
}

// The density of ggx_sample_visible: G1(wo) max(0, wo.m) D(m) / wo.z.
fn ggx_visible_pdf(alpha: f32, wo: vec3f, m: vec3f) -> f32 {
    return ggx_g1(alpha, wo) * max(dot(wo, m), 0.0) * ggx_d(alpha, m) / wo.z;
}

// The density of reflect(-wo, m) for m from ggx_sample_visible: G1(wo) D(m) / (4 wo.z).
fn ggx_reflection_pdf(alpha: f32, wo: vec3f, m: vec3f) -> f32 {
    return ggx_g1(alpha, wo) * ggx_d(alpha, m) / (4.0 * wo.z);
}

// The shading frame: x, y from basis (sampling.wgsl), z the shading normal.
struct Frame {
    s: vec3f,
    t: vec3f,
    n: vec3f,
}

fn frame_of(n: vec3f) -> Frame {
    let b = basis(n);
    return Frame(b.t, b.b, n);
}

fn to_local(f: Frame, v: vec3f) -> vec3f {
    return vec3f(dot(v, f.s), dot(v, f.t), dot(v, f.n));
}

fn to_world(f: Frame, v: vec3f) -> vec3f {
    return f.s * v.x + f.t * v.y + f.n * v.z;
}
//#endif
