// A clear dielectric coat over a lambertian base, in closed form (twin: src/material/coat.rs,
// whose comment gives the model): plastic, and the dielectric part of pbr. k: the coat's
// internal diffuse reflectance; saturates: whether light between coat and base saturates the
// base's colour; table: where a rough plastic's coat table starts (CoatTable), else NO_COAT_TABLE;
// spec: Fresnel's reshaping by glTF's specular (shaders/specular.wgsl), else NO_SPECULAR.

//#if PLASTIC || PBR
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

//#if COAT_TABLE
// A rough coat's opacity at incidence cosine cos from outside, linear between the
// COAT_TABLE_SIZE cosines of its table, which starts at `table` among the images.
fn coat_table_opacity(table: u32, cos: f32) -> f32 {
    let x = clamp(cos, 0.0, 1.0) * f32(COAT_TABLE_SIZE - 1u);
    let i = min(u32(x), COAT_TABLE_SIZE - 2u);
    let w = x - f32(i);
    return (1.0 - w) * image_value(table + i).x + w * image_value(table + i + 1u).x;
}
//#endif

// The coat's opacity at incidence cosine cos from outside, the share of light that does not cross
// it: its table's where it has one (plastic's rough coat), else smooth Fresnel's (reshaped by
// spec where given).
fn coat_opacity(table: u32, spec: vec4f, cos: f32, ior: f32) -> f32 {
//#if COAT_TABLE
    if table != NO_COAT_TABLE {
        return coat_table_opacity(table, cos);
    }
//#endif
//#if SPECULAR
    if spec.x >= 0.0 {
        return specular_opacity(spec, cos, ior);
    }
//#endif
    return coat_fresnel(cos, ior);
}

// What the coat's surface, or a microfacet of it, reflects at cosine cos: Fresnel, or its
// reshaping by spec (a colour).
fn coat_reflectance(spec: vec4f, cos: f32, ior: f32) -> vec3f {
//#if SPECULAR
    if spec.x >= 0.0 {
        return specular_reflectance(spec, cos, ior);
    }
//#endif
    return vec3f(coat_fresnel(cos, ior));
}

// The chance of sampling the coat rather than the base.
fn coat_chance(f_o: f32, albedo: vec3f) -> f32 {
    let base = (1.0 - f_o) * (albedo.x + albedo.y + albedo.z) / 3.0;
    return select(1.0, f_o / (f_o + base), f_o + base > 0.0);
}

fn coat_eval(albedo: vec3f, ior: f32, alpha: f32, k: f32, saturates: bool, table: u32, spec: vec4f, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return vec3f(0.0);
    }
    let f_o = coat_opacity(table, spec, wo_local.z, ior);
    let f_i = coat_opacity(table, spec, wi_local.z, ior);
    let s = select(vec3f(1.0), albedo, saturates);
    let base = albedo * ((1.0 - f_o) * (1.0 - f_i) / (ior * ior))
        / (vec3f(1.0) - s * k) * (wi_local.z / PI);
    if alpha > 0.0 {
        let mf = normalize(wo_local + wi_local);
        let coat = coat_reflectance(spec, dot(wo_local, mf), ior) * ggx_d(alpha, mf)
            * ggx_g2(alpha, wo_local, wi_local) / (4.0 * wo_local.z);
        return base + coat;
    }
    return base;
}

fn coat_pdf(albedo: vec3f, ior: f32, alpha: f32, table: u32, spec: vec4f, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return 0.0;
    }
    let chance = coat_chance(coat_opacity(table, spec, wo_local.z, ior), albedo);
    let base = (1.0 - chance) * cosine_pdf(hit, wi);
    if alpha > 0.0 {
        let mf = normalize(wo_local + wi_local);
        return base + chance * ggx_reflection_pdf(alpha, wo_local, mf);
    }
    return base;
}

// A direction for light leaving toward wo, from numbers u (which lobe), u1, u2.
fn coat_sample(albedo: vec3f, ior: f32, alpha: f32, k: f32, saturates: bool, table: u32, spec: vec4f, wo: vec3f, hit: Hit, u: f32, u1: f32, u2: f32) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    if !(wo_local.z > MIN_COSINE) {
        return out;
    }
    let f_o = coat_opacity(table, spec, wo_local.z, ior);
    let chance = coat_chance(f_o, albedo);
    let coat = u < chance;
    var wi: vec3f;
    if coat {
        if !(alpha > 0.0) {
            // The smooth coat's mirror: a delta lobe, weighed by its chance alone.
            out.wi = reflect_dir(-wo, hit.shading);
            var reflected = vec3f(f_o);
//#if SPECULAR
            if spec.x >= 0.0 {
                reflected = specular_reflectance(spec, wo_local.z, ior);
            }
//#endif
            out.weight = reflected / chance;
            out.lobe = select(0u, LOBE_REFLECTION | LOBE_DELTA, !below_surface(hit, out.wi));
            return out;
        }
        let mf = ggx_sample_visible(alpha, wo_local, u1, u2);
        wi = to_world(frame, reflect_dir(-wo_local, mf));
    } else {
        wi = cosine_direction(hit.shading, u1, u2);
    }
    let pdf = coat_pdf(albedo, ior, alpha, table, spec, wo, wi, hit);
    if !(pdf > 0.0) {
        return out;
    }
    // Either lobe's direction is weighed by both lobes' BSDF over both densities.
    out.weight = coat_eval(albedo, ior, alpha, k, saturates, table, spec, wo, wi, hit) / pdf;
    out.wi = wi;
    out.pdf = pdf;
    out.lobe = LOBE_REFLECTION | select(LOBE_DIFFUSE, LOBE_GLOSSY, coat);
    return out;
}
//#endif
