// Smooth glass (twin: src/material/dielectric.rs): exact unpolarised Fresnel, refraction by
// Snell's law, total internal reflection. Random numbers per scatter: 1. Packed: param: ior.

fn dielectric_scatter(m: Material, dir_in: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> Scattered {
    let eta = select(m.param, 1.0 / m.param, hit.front_face);
    let n = hit.shading;
    let cos_i = clamp(dot(-dir_in, n), 0.0, 1.0);
    let u = sampler_next(sampler);
    var dir = reflect_dir(dir_in, n);
    var reflected = true;
    let sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if sin2_t < 1.0 {
        let cos_t = sqrt(1.0 - sin2_t);
        if u >= fresnel(cos_i, cos_t, eta) {
            dir = eta * dir_in + (eta * cos_i - cos_t) * n;
            reflected = false;
        }
    }
    dir = normalize(dir);
    // A shading normal can send a reflection into the surface or a refraction out of it:
    // absorbed (the geometric normal decides sides, as for the medium inside).
    var ok = true;
//#if SHADING_NORMALS
    ok = all(hit.shading == hit.normal) || (dot(dir, hit.normal) > 0.0) == reflected;
//#endif
    return Scattered(vec3f(1.0), ok, dir);
}

// Exact unpolarised Fresnel reflectance; eta = n_incident / n_transmitted.
fn fresnel(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}
