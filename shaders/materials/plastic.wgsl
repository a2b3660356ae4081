// Plastic (twin: src/material/plastic.rs, whose comment gives the model): a clear coat, smooth
// or on GGX microfacets, over a lambertian base, the light between them summed in closed form.
// Random numbers per sample: 3. Packed: albedo (and texture_*); param: ior; alpha: GGX alpha (0:
// smooth); internal_reflectance: the coat's K.

// Smooth Fresnel reflectance from outside into index ior at incidence cosine cos.
fn coat_fresnel(cos: f32, ior: f32) -> f32 {
    let eta = 1.0 / ior;
    let c = clamp(cos, 0.0, 1.0);
    let sin2_t = eta * eta * max(1.0 - c * c, 0.0);
    if sin2_t < 1.0 {
        return fresnel(c, sqrt(1.0 - sin2_t), eta);
    }
    return 1.0;
}

// The chance of sampling the coat rather than the base.
fn coat_chance(f_o: f32, albedo: vec3f) -> f32 {
    let base = (1.0 - f_o) * (albedo.x + albedo.y + albedo.z) / 3.0;
    return select(1.0, f_o / (f_o + base), f_o + base > 0.0);
}

fn plastic_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return vec3f(0.0);
    }
    let albedo = albedo_at(m, hit);
    let f_o = coat_fresnel(wo_local.z, m.param);
    let f_i = coat_fresnel(wi_local.z, m.param);
    let base = albedo * ((1.0 - f_o) * (1.0 - f_i) / (m.param * m.param))
        / (vec3f(1.0) - albedo * m.internal_reflectance) * (wi_local.z / PI);
    if m.alpha > 0.0 {
        let mf = normalize(wo_local + wi_local);
        let coat = coat_fresnel(dot(wo_local, mf), m.param) * ggx_d(m.alpha, mf)
            * ggx_g2(m.alpha, wo_local, wi_local) / (4.0 * wo_local.z);
        return base + vec3f(coat);
    }
    return base;
}

fn plastic_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return 0.0;
    }
    let chance = coat_chance(coat_fresnel(wo_local.z, m.param), albedo_at(m, hit));
    let base = (1.0 - chance) * cosine_pdf(hit, wi);
    if m.alpha > 0.0 {
        let mf = normalize(wo_local + wi_local);
        return base + chance * ggx_reflection_pdf(m.alpha, wo_local, mf);
    }
    return base;
}

fn plastic_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let u = sampler_next(sampler);
    let u1 = sampler_next(sampler);
    let u2 = sampler_next(sampler);
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    if !(wo_local.z > MIN_COSINE) {
        return out;
    }
    let f_o = coat_fresnel(wo_local.z, m.param);
    let chance = coat_chance(f_o, albedo_at(m, hit));
    let coat = u < chance;
    var wi: vec3f;
    if coat {
        if !(m.alpha > 0.0) {
            // The smooth coat's mirror: a delta lobe, weighed by its chance alone.
            out.wi = reflect_dir(-wo, hit.shading);
            out.weight = vec3f(f_o / chance);
            out.lobe = select(0u, LOBE_REFLECTION | LOBE_DELTA, !below_surface(hit, out.wi));
            return out;
        }
        let mf = ggx_sample_visible(m.alpha, wo_local, u1, u2);
        wi = to_world(frame, reflect_dir(-wo_local, mf));
    } else {
        // normal + a uniform unit vector is cosine-distributed about the normal.
        let d = hit.shading + unit_vector(u1, u2);
        let len2 = dot(d, d);
        wi = select(hit.shading, d / sqrt(len2), len2 > 1e-12);
    }
    let pdf = plastic_pdf(m, wo, wi, hit);
    if !(pdf > 0.0) {
        return out;
    }
    // Either lobe's direction is weighed by both lobes' BSDF over both densities.
    out.weight = plastic_eval(m, wo, wi, hit) / pdf;
    out.wi = wi;
    out.pdf = pdf;
    out.lobe = LOBE_REFLECTION | select(LOBE_DIFFUSE, LOBE_GLOSSY, coat);
    return out;
}
