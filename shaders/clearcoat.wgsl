// glTF's clear coat (KHR_materials_clearcoat) over pbr (twin: src/material/clearcoat.rs, whose
// comment gives the model): a clear dielectric of index 1.5 with its own GGX alpha over the
// whole pbr mix, shading with its own normal (hit.coat); factor: glTF's clearcoatFactor (0:
// none). Only pbr has one.

//#if PBR
//#if CLEARCOAT
const CLEARCOAT_IOR: f32 = 1.5;

// hit as the coat sees it: shading with the coat's normal.
fn on_coat(hit: Hit) -> Hit {
    var h = hit;
    h.shading = hit.coat;
    return h;
}

// The share of light met at cosine cos to the normal (either side) that the coat reflects;
// also the chance of sampling the coat.
fn clearcoat_reflectance(factor: f32, cos: f32) -> f32 {
    return factor * coat_fresnel(abs(cos), CLEARCOAT_IOR);
}

// What of the mix below is seen through the coat toward wo.
fn clearcoat_through(factor: f32, wo: vec3f, hit: Hit) -> f32 {
    return 1.0 - clearcoat_reflectance(factor, dot(wo, hit.coat));
}

// The rough coat's BSDF x cos (times the factor; x) and the density of its directions (y) at
// (wo, wi); 0 for a smooth coat.
fn clearcoat_lobe(factor: f32, alpha: f32, wo: vec3f, wi: vec3f, surface: Hit) -> vec2f {
    if !(alpha > 0.0) {
        return vec2f(0.0);
    }
    let hit = on_coat(surface);
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return vec2f(0.0);
    }
    let mf = normalize(wo_local + wi_local);
    let f = factor * coat_fresnel(dot(wo_local, mf), CLEARCOAT_IOR) * ggx_d(alpha, mf)
        * ggx_g2(alpha, wo_local, wi_local) / (4.0 * wo_local.z);
    return vec2f(f, ggx_reflection_pdf(alpha, wo_local, mf));
}

// A direction reflected by the coat toward wo from two numbers: a BsdfSample whose lobe is
// the mirror's (weight 1: its reflectance over its chance), a rough one's (to be weighed), or
// 0 where it would leave below the surface.
fn clearcoat_sample(alpha: f32, wo: vec3f, surface: Hit, u1: f32, u2: f32) -> BsdfSample {
    let hit = on_coat(surface);
    var out = BsdfSample(vec3f(1.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    if !(wo_local.z > MIN_COSINE) {
        return out;
    }
    if !(alpha > 0.0) {
        out.wi = reflect_dir(-wo, hit.shading);
        out.lobe = select(0u, LOBE_REFLECTION | LOBE_DELTA, !below_surface(hit, out.wi));
        return out;
    }
    let wi_local = reflect_dir(-wo_local, ggx_sample_visible(alpha, wo_local, u1, u2));
    out.wi = to_world(frame, wi_local);
    out.lobe = select(0u, LOBE_REFLECTION | LOBE_GLOSSY, wi_local.z > MIN_COSINE && !below_surface(hit, out.wi));
    return out;
}
//#endif
//#endif
