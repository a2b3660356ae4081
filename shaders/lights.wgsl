// Light sampling for next-event estimation (twin: src/cpu/lights.rs). Only in kernels for
// the nee integrator and scenes with lights.

//#if NEE
//#if INLINE_SCENE
// pick_light, light_of and light_at are generated with the scene's constants (see
// inline_lights in src/gpu/shader.rs): no buffer loads at dynamic indices, which lavapipe
// gathers lane by lane.
//#else
// The light whose cumulative share first exceeds u in [0, 1), by binary search (the last when
// none does): the same steps as pick_light in src/cpu/lights.rs.
fn pick_light(u: f32) -> u32 {
    var lo = 0u;
    var hi = params.light_count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if u < lights[mid].cdf {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

// 1 + the light index of a (packed) primitive, or 0.
fn light_of(primitive: u32) -> u32 {
    let index = primitive_index(primitive);
//#if TRIANGLES
    if primitive_kind(primitive) == KIND_TRIANGLE {
        return triangles[index].light;
    }
//#endif
    // The shapes' (generated: src/gpu/shape_dispatch.rs).
    return shape_light_of(primitive);
}

fn light_at(i: u32) -> Light {
    return lights[i];
}
//#endif

// Solid-angle pdf of picking flat light l (size: 1 / area), uniform on its area, and its point p
// from x, seen along unit dir (twin: shape::area_pdf).
fn area_pdf(l: Light, x: vec3f, p: vec3f, dir: vec3f) -> f32 {
    let cos_light = abs(dot(l.normal, dir));
    if !(cos_light > MIN_LIGHT_COSINE) {
        return 0.0;
    }
    let to_p = p - x;
    return l.pick * l.size * dot(to_p, to_p) / cos_light;
}

// A sample of flat light l at its point p, seen from x.
fn area_light_sample(l: Light, x: vec3f, p: vec3f) -> LightSample {
    var out = LightSample(vec3f(0.0, 1.0, 0.0), 0.0, x);
    let to_light = p - x;
    let dist2 = dot(to_light, to_light);
    if dist2 > 0.0 {
        out.dir = to_light / sqrt(dist2);
        out.pdf = area_pdf(l, x, p, out.dir);
        out.point = p;
    }
    return out;
}

// Solid-angle pdf of light sampling choosing the direction from x that reaches l at p.
fn light_pdf(l: Light, x: vec3f, p: vec3f, dir: vec3f) -> f32 {
//#if ENVIRONMENT
    if l.kind == KIND_ENVIRONMENT {
        return l.pick * environment_pdf(dir);
    }
//#endif
//#if PUNCTUAL
    // A ray never meets a light of no area.
    if l.kind == KIND_POINT || l.kind == KIND_DIRECTIONAL {
        return 0.0;
    }
//#endif
//#if TRIANGLES
    if l.kind == KIND_TRIANGLE {
        return area_pdf(l, x, p, dir);
    }
//#endif
    // The shapes' (generated: src/gpu/shape_dispatch.rs).
    return shape_light_pdf(l, x, p, dir);
}

//#if PUNCTUAL
// What punctual light l sends to x (what multiplies BSDF x cos): a point's or spot's intensity
// times its falloff over the squared distance, the sun's irradiance.
fn punctual_arriving(l: Light, x: vec3f) -> vec3f {
    if l.kind == KIND_DIRECTIONAL {
        return l.u;
    }
    let from_light = x - l.position;
    let d2 = dot(from_light, from_light);
    if !(d2 > 0.0) {
        return vec3f(0.0);
    }
    let cos_axis = dot(l.normal, from_light) / sqrt(d2);
    let t = clamp(cos_axis * l.v.x + l.v.y, 0.0, 1.0);
    return l.u * (t * t / max(d2, MIN_DISTANCE_SQUARED));
}

fn is_punctual(l: Light) -> bool {
    return l.kind == KIND_POINT || l.kind == KIND_DIRECTIONAL;
}
//#endif

struct LightSample {
    dir: vec3f,
    pdf: f32,       // 0: no sample
    point: vec3f,   // where it meets the light: the shadow ray aims here (not the environment's)
}

// A unit direction from x toward l and its solid-angle pdf (with the pick probability).
fn sample_light(l: Light, x: vec3f, u1: f32, u2: f32) -> LightSample {
    var out = LightSample(vec3f(0.0, 1.0, 0.0), 0.0, x);
//#if PUNCTUAL
    // Punctual lights: one direction, with the probability of picking the light.
    if l.kind == KIND_DIRECTIONAL {
        if l.pick > 0.0 {
            out.dir = l.normal;
            out.pdf = l.pick;
            out.point = x + l.normal;
        }
        return out;
    }
    if l.kind == KIND_POINT {
        let to_light = l.position - x;
        let dist2 = dot(to_light, to_light);
        if dist2 > 0.0 && l.pick > 0.0 {
            out.dir = to_light / sqrt(dist2);
            out.pdf = l.pick;
            out.point = l.position;
        }
        return out;
    }
//#endif
//#if ENVIRONMENT
    if l.kind == KIND_ENVIRONMENT {
        let e = environment_sample(u1, u2);
        out.dir = e.dir;
        out.pdf = l.pick * e.pdf;
        out.point = x + e.dir;
        return out;
    }
//#endif
//#if TRIANGLES
    // Uniform on its area: (1 - sqrt(u1)) on the corner's weight.
    if l.kind == KIND_TRIANGLE {
        let s = sqrt(u1);
        let a = s * (1.0 - u2);
        let b = s * u2;
        return area_light_sample(l, x, l.position + a * l.u + b * l.v);
    }
//#endif
    // The shapes' (generated: src/gpu/shape_dispatch.rs).
    return shape_light_sample(l, x, u1, u2);
}

// Power heuristic (beta = 2) weight of a strategy with pdf own against other, on values
// scaled to at most 1 so no square overflows.
fn power_heuristic(own: f32, other: f32) -> f32 {
    let m = max(own, other);
    if !(m > 0.0) {
        return 1.0;
    }
    let a = own / m;
    let b = other / m;
    return a * a / (a * a + b * b);
}

// The light sample's power-heuristic weight over its pdf: a / (a^2 + b^2) / m for a, b the two
// pdfs scaled by their maximum m.
fn light_sample_weight(light_pdf: f32, bsdf_pdf: f32) -> f32 {
    let m = max(light_pdf, bsdf_pdf);
    if !(m > 0.0) {
        return 0.0;
    }
    let a = light_pdf / m;
    let b = bsdf_pdf / m;
    return a / (a * a + b * b) / m;
}

// In a medium: phase_pdf / light_pdf times the light sample's MIS weight: ab / (a^2 + b^2), at
// most 1/2.
fn light_sample_factor(light_pdf: f32, bsdf_pdf: f32) -> f32 {
    let m = max(light_pdf, bsdf_pdf);
    if !(m > 0.0) {
        return 0.0;
    }
    let a = light_pdf / m;
    let b = bsdf_pdf / m;
    return a * b / (a * a + b * b);
}
//#endif
