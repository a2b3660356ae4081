// Ideal diffuse reflection (twin: src/material/lambertian.rs). Random numbers per scatter: 2.
// Packed: albedo, emission.

fn lambertian_emitted(m: Material, hit: Hit) -> vec3f {
    return m.emission;
}

fn lambertian_bsdf(m: Material, hit: Hit, dir: vec3f) -> Bsdf {
    // Cosine-weighted: pdf = cos / pi, BSDF x cos / pdf = albedo.
    let cos = dot(hit.normal, dir);
    let above = cos > 0.0;
    return Bsdf(select(vec3f(0.0), albedo_at(m, hit), above), select(0.0, cos / PI, above));
}

fn lambertian_scatter(m: Material, dir_in: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> Scattered {
    // normal + a uniform unit vector is cosine-distributed about the normal.
    let u1 = sampler_next(sampler);
    let u2 = sampler_next(sampler);
    let d = hit.normal + unit_vector(u1, u2);
    let len2 = dot(d, d);
    return Scattered(albedo_at(m, hit), true, select(hit.normal, d / sqrt(len2), len2 > 1e-12));
}
