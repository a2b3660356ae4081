// Ideal diffuse reflection (twin: src/material/lambertian.rs). Random numbers per sample: 2.
// Its albedo is GpuMaterial's (albedo_at); its parameters: LambertianParams.

fn lambertian_emitted(m: Material, hit: Hit) -> vec3f {
    return lambertian_params(m).emission;
}

fn lambertian_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    return albedo_at(m, hit) * cosine_pdf(hit, wi);
}

fn lambertian_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    return cosine_pdf(hit, wi);
}

fn lambertian_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    let u1 = sampler_next_in_group(sampler);
    let u2 = sampler_next_in_group(sampler);
    let wi = cosine_direction(hit.shading, u1, u2);
    let lobe = select(0u, LOBE_REFLECTION | LOBE_DIFFUSE, !below_surface(hit, wi));
    return BsdfSample(albedo_at(m, hit), wi, cosine_pdf(hit, wi), lobe);
}
