// Shading normals as microfacets, Schüssler et al. 2017 (twin: src/material/microsurface.rs,
// which explains the model and its split into first-order walks and the rest). bsdf_sample,
// bsdf_eval and bsdf_pdf are the path loop's BSDF here: the material's own (facet_sample,
// facet_eval, facet_pdf, generated from the registry) on a microsurface where the material's
// normal map bends the hit's shading normal and the material only reflects.

//#if NORMAL_MAPS
// MICROSURFACE_MAX_SCATTERINGS, _MIN_SIN and _MIN_COS are generated from their Rust twins.

struct Microsurface {
    n: vec3f,
    wp: vec3f,
    wt: vec3f,
    sin: f32,
    cos: f32,
    // The hit as the shading facet sees it.
    facet: Hit,
    // Whether there is one here (else the material's own BSDF at the hit).
    on: bool,
}

fn microsurface_at(m: Material, hit: Hit) -> Microsurface {
    var s: Microsurface;
    s.on = false;
    if m.microsurface == 0u || all(hit.shading == hit.normal) {
        return s;
    }
    let cos = dot(hit.shading, hit.normal);
    let tilt = hit.shading - cos * hit.normal;
    let sin = length(tilt);
    if !(sin > MICROSURFACE_MIN_SIN && cos > MICROSURFACE_MIN_COS) {
        return s;
    }
    s.n = hit.normal;
    s.wp = hit.shading;
    s.wt = -tilt / sin;
    s.sin = sin;
    s.cos = cos;
    s.facet = hit;
    s.facet.normal = hit.shading;
    s.on = true;
    return s;
}

fn microsurface_projected(s: Microsurface, w: vec3f) -> f32 {
    return (max(dot(w, s.wp), 0.0) + max(dot(w, s.wt), 0.0) * s.sin) / s.cos;
}

fn microsurface_meets_shading_facet(s: Microsurface, w: vec3f) -> f32 {
    let total = microsurface_projected(s, w);
    return select(0.0, max(dot(w, s.wp), 0.0) / s.cos / total, total > 0.0);
}

fn microsurface_escapes(s: Microsurface, w: vec3f) -> f32 {
    let up = dot(w, s.n);
    if !(up > 0.0) {
        return 0.0;
    }
    return min(up / microsurface_projected(s, w), 1.0);
}

fn microsurface_mirrored(s: Microsurface, w: vec3f) -> vec3f {
    return reflect_dir(w, s.wt);
}

fn bsdf_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    let s = microsurface_at(m, hit);
    if !s.on {
        return facet_sample(m, wo, hit, sampler);
    }
    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let direct = sampler_next_in_group(sampler) < microsurface_meets_shading_facet(s, wo);
    var arriving = select(microsurface_mirrored(s, wo), wo, direct);
    var weight = vec3f(1.0);
    for (var scattering = 0u; scattering < MICROSURFACE_MAX_SCATTERINGS; scattering++) {
        if !(dot(arriving, s.wp) > 0.0) {
            break;
        }
        sampler_begin(sampler);
        let f = facet_sample(m, arriving, s.facet, sampler);
        if f.lobe == 0u {
            break;
        }
        weight *= f.weight;
        sampler_begin(sampler);
        let u1 = sampler_next_in_group(sampler);
        let u2 = sampler_next_in_group(sampler);
        var wi = f.wi;
        var first_order = scattering == 0u;
        if !(u1 < microsurface_escapes(s, f.wi)) {
            let after = microsurface_mirrored(s, f.wi);
            if !(u2 < microsurface_escapes(s, after)) {
                arriving = -after;
                continue;
            }
            wi = after;
            first_order = first_order && direct;
        }
        var pdf = 0.0;
//#if NEE
        if first_order && (f.lobe & LOBE_DELTA) == 0u {
            pdf = microsurface_pdf(m, s, wo, wi);
        }
//#endif
        out = BsdfSample(weight, wi, pdf, f.lobe);
        break;
    }
    return out;
}

//#if NEE
// The shading facet's eval, or with pdf its pdf (in x, y and z).
fn microsurface_facet(m: Material, s: Microsurface, a: vec3f, b: vec3f, pdf: bool) -> vec3f {
    if pdf {
        return vec3f(facet_pdf(m, a, b, s.facet));
    }
    return facet_eval(m, a, b, s.facet);
}

// The sum over the first-order walks from wo to wi of the shading facet's eval (or pdf) times
// the chances of the facet events (twin: Microsurface::first_order).
fn microsurface_first_order(m: Material, s: Microsurface, wo: vec3f, wi: vec3f, pdf: bool) -> vec3f {
    let out = microsurface_escapes(s, wi);
    if !(out > 0.0) {
        return vec3f(0.0);
    }
    let direct = microsurface_meets_shading_facet(s, wo);
    var sum = vec3f(0.0);
    if direct > 0.0 {
        let after = microsurface_mirrored(s, wi);
        sum += direct * microsurface_facet(m, s, wo, wi, pdf);
        sum += direct * (1.0 - microsurface_escapes(s, after)) * microsurface_facet(m, s, wo, after, pdf);
    }
    let mirrored = microsurface_mirrored(s, wo);
    if direct < 1.0 && dot(mirrored, s.wp) > 0.0 {
        sum += (1.0 - direct) * microsurface_facet(m, s, mirrored, wi, pdf);
    }
    return sum * out;
}

fn microsurface_pdf(m: Material, s: Microsurface, wo: vec3f, wi: vec3f) -> f32 {
    return microsurface_first_order(m, s, wo, wi, true).x;
}

fn bsdf_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let s = microsurface_at(m, hit);
    if !s.on {
        return facet_eval(m, wo, wi, hit);
    }
    return microsurface_first_order(m, s, wo, wi, false);
}

fn bsdf_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    let s = microsurface_at(m, hit);
    if !s.on {
        return facet_pdf(m, wo, wi, hit);
    }
    return microsurface_pdf(m, s, wo, wi);
}
//#endif
//#endif
