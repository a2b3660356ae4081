// Glass (twin: src/material/dielectric.rs): exact unpolarised Fresnel, refraction by Snell's
// law, total internal reflection; smooth (alpha 0: two delta lobes) or on GGX microfacets
// (Walter et al. 2007) sampled by visible normals. Random numbers per sample: 1 when smooth, 3
// when rough. Its parameters: DielectricParams; the glass_* functions take them and a specular's
// reshaping of its Fresnel (shaders/specular.wgsl; NO_SPECULAR: none), for pbr's glass too.

fn dielectric_samples_lights(m: Material) -> bool {
//#if MICROFACET
    return dielectric_params(m).alpha > 0.0;
//#else
    return false;
//#endif
}

// Whether wi, sampled in the lobe `reflected` says, leaves on that lobe's side of the geometric
// surface: a shading normal can send a reflection into the surface or a refraction out of it
// (then absorbed; the geometric normal decides sides, as for the medium inside).
fn on_its_side(hit: Hit, wi: vec3f, reflected: bool) -> bool {
//#if SHADING_NORMALS
    return all(hit.shading == hit.normal) || (dot(wi, hit.normal) > 0.0) == reflected;
//#else
    return true;
//#endif
}

fn dielectric_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    return glass_sample(dielectric_params(m), NO_SPECULAR, wo, hit, sampler);
}

fn dielectric_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    return glass_eval(dielectric_params(m), NO_SPECULAR, wo, wi, hit);
}

fn dielectric_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    return glass_pdf(dielectric_params(m), NO_SPECULAR, wo, wi, hit);
}

// What the glass reflects at a (micro)surface where exact Fresnel reflectance is f (1 under
// total internal reflection), in xyz, and in w the chance that a sample reflects: f and f, or
// where spec reshapes it, factor x Fr and its largest channel (Dielectric::reflectance).
fn glass_reflectance(spec: vec4f, f: f32, ior: f32) -> vec4f {
//#if SPECULAR
//#if PLASTIC || PBR
    if spec.x >= 0.0 && f < 1.0 {
        let r = spec.x * (spec.yzw + (vec3f(1.0) - spec.yzw) * specular_shape(f, coat_fresnel(1.0, ior)));
        return vec4f(r, max(max(r.x, r.y), r.z));
    }
//#endif
//#endif
    return vec4f(f);
}

fn glass_sample(g: DielectricParams, spec: vec4f, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
//#if MICROFACET
    if g.alpha > 0.0 {
        return rough_glass_sample(g, spec, wo, hit, sampler);
    }
//#endif
    let eta = select(g.ior, 1.0 / g.ior, hit.front_face);
    let n = hit.shading;
    let dir_in = -wo;
    let cos_i = clamp(dot(wo, n), 0.0, 1.0);
    let u = sampler_next_in_group(sampler);
    var wi = reflect_dir(dir_in, n);
    var reflected = true;
    var weight = vec3f(1.0);
    let sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if sin2_t < 1.0 {
        let cos_t = sqrt(1.0 - sin2_t);
        let r = glass_reflectance(spec, fresnel(cos_i, cos_t, eta), g.ior);
        if u >= r.w {
            wi = eta * dir_in + (eta * cos_i - cos_t) * n;
            reflected = false;
        } else {
            // What it reflects over its chance: 1 without a specular.
            weight = r.xyz / r.w;
        }
    }
    wi = normalize(wi);
    var lobe = select(LOBE_TRANSMISSION | LOBE_DELTA, LOBE_REFLECTION | LOBE_DELTA, reflected);
    if !on_its_side(hit, wi, reflected) {
        lobe = 0u;
    }
    return BsdfSample(weight, wi, 0.0, lobe);
}

//#if MICROFACET
// Fresnel reflectance at a microfacet at cosine cos_i from the incident direction (1 under total
// internal reflection, then cos_t is 0) and the refracted direction's cosine.
struct Interface {
    f: f32,
    cos_t: f32,
}

fn fresnel_and_cos_t(cos_i: f32, eta: f32) -> Interface {
    let sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if sin2_t < 1.0 {
        let cos_t = sqrt(1.0 - sin2_t);
        return Interface(fresnel(cos_i, cos_t, eta), cos_t);
    }
    return Interface(1.0, 0.0);
}

// The Fresnel reflectance of a pair of directions at microfacet normal m, from their cosines to
// it: a refraction's own cos_t, not Snell's law's, which cancels near the critical angle.
fn pair_fresnel(cos_o: f32, cos_i: f32, eta: f32, reflected: bool) -> f32 {
    if reflected {
        return fresnel_and_cos_t(cos_o, eta).f;
    }
    return fresnel(cos_o, -cos_i, eta);
}

fn rough_glass_sample(g: DielectricParams, spec: vec4f, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let u1 = sampler_next_in_group(sampler);
    let u2 = sampler_next_in_group(sampler);
    let u = sampler_next(sampler);
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    if !(wo_local.z > MIN_COSINE) {
        return out;
    }
    let eta = select(g.ior, 1.0 / g.ior, hit.front_face);
    let mf = ggx_sample_visible(g.alpha, wo_local, u1, u2);
    let cos_i = dot(wo_local, mf);
    let fr = fresnel_and_cos_t(cos_i, eta);
    let r = glass_reflectance(spec, fr.f, g.ior);
    // Reflection with its chance, F without a specular: the BSDF's and the pdf's cancel in the
    // weight but for the reflectance's colour.
    var wi_local: vec3f;
    var reflected = true;
    var tint = vec3f(1.0);
    if fr.f < 1.0 && u >= r.w {
        wi_local = (eta * cos_i - fr.cos_t) * mf - eta * wo_local;
        let denom = dot(wi_local, mf) + eta * cos_i;
        let jacobian = abs(dot(wi_local, mf)) / (denom * denom);
        out.pdf = (1.0 - r.w) * ggx_visible_pdf(g.alpha, wo_local, mf) * jacobian;
        reflected = false;
    } else {
        wi_local = reflect_dir(-wo_local, mf);
        out.pdf = r.w * ggx_reflection_pdf(g.alpha, wo_local, mf);
        tint = r.xyz / r.w;
    }
    let wi = to_world(frame, wi_local);
    let on_side = select((wi_local.z < -MIN_COSINE), (wi_local.z > MIN_COSINE), reflected);
    if !(on_side && on_its_side(hit, wi, reflected) && out.pdf > 0.0) {
        out.pdf = 0.0;
        return out;
    }
    // f cos / pdf = G2 / G1 for either lobe (Walter's BTDF over its pdf), tinted.
    out.weight = tint * (ggx_g2(g.alpha, wo_local, wi_local) / ggx_g1(g.alpha, wo_local));
    out.wi = wi;
    out.lobe = select(LOBE_TRANSMISSION, LOBE_REFLECTION, reflected) | LOBE_GLOSSY;
    return out;
}

// wo and wi in the shading frame and the microfacet normal taking one to the other (the half
// vector of a reflection, Walter's generalised one of a refraction), with the lobe; `ok` false
// where no microfacet does.
struct RoughPair {
    wo: vec3f,
    wi: vec3f,
    m: vec3f,
    reflected: bool,
    ok: bool,
}

fn rough_pair(wo: vec3f, wi: vec3f, hit: Hit, eta: f32) -> RoughPair {
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    let reflected = wi_local.z > 0.0;
    // n_i wo + n_t wi, over n_t; toward wo's side.
    let h = select(eta * wo_local + wi_local, wo_local + wi_local, reflected);
    let len2 = dot(h, h);
    let mf = h / sqrt(len2) * sign(h.z);
    let ok = wo_local.z > MIN_COSINE && abs(wi_local.z) > MIN_COSINE && on_its_side(hit, wi, reflected)
        && len2 > 0.0 && dot(wo_local, mf) > 0.0 && (dot(wi_local, mf) > 0.0) == reflected;
    return RoughPair(wo_local, wi_local, mf, reflected, ok);
}
//#endif

fn glass_eval(g: DielectricParams, spec: vec4f, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
//#if MICROFACET
    let eta = select(g.ior, 1.0 / g.ior, hit.front_face);
    let p = rough_pair(wo, wi, hit, eta);
    if p.ok && g.alpha > 0.0 {
        let cos_i = dot(p.wo, p.m);
        let r = glass_reflectance(spec, pair_fresnel(cos_i, dot(p.wi, p.m), eta, p.reflected), g.ior);
        let dg = ggx_d(g.alpha, p.m) * ggx_g2(g.alpha, p.wo, p.wi);
        if p.reflected {
            return r.xyz * dg / (4.0 * p.wo.z);
        }
        let denom = dot(p.wi, p.m) + eta * cos_i;
        return vec3f((1.0 - r.w) * dg * abs(dot(p.wi, p.m)) * cos_i / (p.wo.z * denom * denom));
    }
//#endif
    return vec3f(0.0);
}

fn glass_pdf(g: DielectricParams, spec: vec4f, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
//#if MICROFACET
    let eta = select(g.ior, 1.0 / g.ior, hit.front_face);
    let p = rough_pair(wo, wi, hit, eta);
    if p.ok && g.alpha > 0.0 {
        let cos_i = dot(p.wo, p.m);
        let chance = glass_reflectance(spec, pair_fresnel(cos_i, dot(p.wi, p.m), eta, p.reflected), g.ior).w;
        if p.reflected {
            return chance * ggx_reflection_pdf(g.alpha, p.wo, p.m);
        }
        let denom = dot(p.wi, p.m) + eta * cos_i;
        return (1.0 - chance) * ggx_visible_pdf(g.alpha, p.wo, p.m) * abs(dot(p.wi, p.m)) / (denom * denom);
    }
//#endif
    return 0.0;
}
