// A metal (twin: src/material/conductor.rs): exact conductor Fresnel of eta + i k per channel,
// smooth (alpha 0: a delta lobe) or on GGX microfacets sampled by visible normals. Random
// numbers per sample: 2 when rough, none when smooth. Its parameters: ConductorParams.

// Exact unpolarised Fresnel reflectance from index 1 into eta + i k, per channel.
fn fresnel_conductor(cos_i: f32, eta: vec3f, k: vec3f) -> vec3f {
    let c = clamp(cos_i, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - vec3f(s2);
    let a2pb2 = sqrt(t1 * t1 + 4.0 * k * k * eta * eta);
    let a = sqrt(max(0.5 * (a2pb2 + t1), vec3f(0.0)));
    let term1 = a2pb2 + vec3f(c2);
    let term2 = 2.0 * c * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + vec3f(s4);
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    return 0.5 * (rs + rp);
}

fn conductor_samples_lights(m: Material) -> bool {
    return conductor_params(m).alpha > 0.0;
}

fn conductor_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let p = conductor_params(m);
    if !(p.alpha > 0.0) {
        out.wi = reflect_dir(-wo, hit.shading);
        out.weight = fresnel_conductor(dot(wo, hit.shading), p.eta, p.k);
        // Reflected below the surface by a shading normal: absorbed.
        out.lobe = select(0u, LOBE_REFLECTION | LOBE_DELTA, dot(out.wi, hit.normal) > 0.0);
        return out;
    }
//#if MICROFACET
    let u1 = sampler_next_in_group(sampler);
    let u2 = sampler_next_in_group(sampler);
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    if !(wo_local.z > MIN_COSINE) {
        return out;
    }
    let mf = ggx_sample_visible(p.alpha, wo_local, u1, u2);
    let wi_local = reflect_dir(-wo_local, mf);
    let wi = to_world(frame, wi_local);
    if !(wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return out;
    }
    // f cos / pdf = F G2 / G1.
    out.weight = fresnel_conductor(dot(wo_local, mf), p.eta, p.k)
        * (ggx_g2(p.alpha, wo_local, wi_local) / ggx_g1(p.alpha, wo_local));
    out.wi = wi;
    out.pdf = ggx_reflection_pdf(p.alpha, wo_local, mf);
    out.lobe = LOBE_REFLECTION | LOBE_GLOSSY;
//#endif
    return out;
}

//#if MICROFACET
// wo and wi in the shading frame and their half vector (`m`), where both are above the
// shading surface and wi above the geometric one; `ok` false elsewhere.
struct ReflectionPair {
    wo: vec3f,
    wi: vec3f,
    m: vec3f,
    ok: bool,
}

fn reflection_half_vector(wo: vec3f, wi: vec3f, hit: Hit) -> ReflectionPair {
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    let h = wo_local + wi_local;
    let len2 = dot(h, h);
    let ok = wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE && !below_surface(hit, wi) && len2 > 0.0;
    return ReflectionPair(wo_local, wi_local, h / sqrt(len2), ok);
}
//#endif

fn conductor_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
//#if MICROFACET
    let c = conductor_params(m);
    let p = reflection_half_vector(wo, wi, hit);
    if p.ok && c.alpha > 0.0 {
        return fresnel_conductor(dot(p.wo, p.m), c.eta, c.k)
            * (ggx_d(c.alpha, p.m) * ggx_g2(c.alpha, p.wo, p.wi) / (4.0 * p.wo.z));
    }
//#endif
    return vec3f(0.0);
}

fn conductor_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
//#if MICROFACET
    let alpha = conductor_params(m).alpha;
    let p = reflection_half_vector(wo, wi, hit);
    if p.ok && alpha > 0.0 {
        return ggx_reflection_pdf(alpha, p.wo, p.m);
    }
//#endif
    return 0.0;
}
