// Ideal diffuse reflection (twin: src/material/lambertian.rs). Random numbers per scatter: 2.
// Packed: albedo, emission.

fn lambertian_emitted(m: Material, hit: Hit) -> vec3f {
    return m.emission;
}

fn lambertian_bsdf(m: Material, hit: Hit, dir: vec3f) -> Bsdf {
    // Cosine-weighted about the shading normal: pdf = cos / pi, BSDF x cos / pdf = albedo.
    let cos = dot(hit.shading, dir);
    let above = cos > 0.0 && !below_surface(hit, dir);
    return Bsdf(select(vec3f(0.0), albedo_at(m, hit), above), select(0.0, cos / PI, above));
}

fn lambertian_scatter(m: Material, dir_in: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> Scattered {
    // normal + a uniform unit vector is cosine-distributed about the normal.
    let u1 = sampler_next(sampler);
    let u2 = sampler_next(sampler);
    let d = hit.shading + unit_vector(u1, u2);
    let len2 = dot(d, d);
    let dir = select(hit.shading, d / sqrt(len2), len2 > 1e-12);
    return Scattered(albedo_at(m, hit), !below_surface(hit, dir), dir);
}
