// Smooth glass (twin: src/material/dielectric.rs): exact unpolarised Fresnel, refraction by
// Snell's law, total internal reflection. Random numbers per sample: 1. Packed: param: ior.

fn dielectric_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    let eta = select(m.param, 1.0 / m.param, hit.front_face);
    let n = hit.shading;
    let dir_in = -wo;
    let cos_i = clamp(dot(wo, n), 0.0, 1.0);
    let u = sampler_next(sampler);
    var wi = reflect_dir(dir_in, n);
    var reflected = true;
    let sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if sin2_t < 1.0 {
        let cos_t = sqrt(1.0 - sin2_t);
        if u >= fresnel(cos_i, cos_t, eta) {
            wi = eta * dir_in + (eta * cos_i - cos_t) * n;
            reflected = false;
        }
    }
    wi = normalize(wi);
    var lobe = select(LOBE_TRANSMISSION | LOBE_DELTA, LOBE_REFLECTION | LOBE_DELTA, reflected);
    // A shading normal can send a reflection into the surface or a refraction out of it:
    // absorbed (the geometric normal decides sides, as for the medium inside).
//#if SHADING_NORMALS
    if !(all(hit.shading == hit.normal) || (dot(wi, hit.normal) > 0.0) == reflected) {
        lobe = 0u;
    }
//#endif
    return BsdfSample(vec3f(1.0), wi, 0.0, lobe);
}

// Exact unpolarised Fresnel reflectance; eta = n_incident / n_transmitted.
fn fresnel(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}
