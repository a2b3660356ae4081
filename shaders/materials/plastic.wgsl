// Plastic (twin: src/material/plastic.rs): a clear coat, smooth or on GGX microfacets, over a
// lambertian base, the light between them summed in closed form (a saturating coat,
// shaders/coat.wgsl), a rough coat's reflectance tabulated. Random numbers per sample: 3. Its
// albedo is GpuMaterial's (albedo_at); its parameters: PlasticParams.

// Where its rough coat's table starts among the images (its parameter image), else NO_COAT_TABLE.
fn plastic_table(m: Material) -> u32 {
    return select(NO_COAT_TABLE, m.parameter_image, m.parameter_image_size.x > 0.0);
}

fn plastic_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let p = plastic_params(m);
    return coat_eval(albedo_at(m, hit), p.ior, p.alpha, p.internal_reflectance, true, plastic_table(m), NO_SPECULAR, wo, wi, hit);
}

fn plastic_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    let p = plastic_params(m);
    return coat_pdf(albedo_at(m, hit), p.ior, p.alpha, plastic_table(m), NO_SPECULAR, wo, wi, hit);
}

fn plastic_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    let u = sampler_next_in_group(sampler);
    let u1 = sampler_next_in_group(sampler);
    let u2 = sampler_next(sampler);
    let p = plastic_params(m);
    return coat_sample(albedo_at(m, hit), p.ior, p.alpha, p.internal_reflectance, true, plastic_table(m), NO_SPECULAR, wo, hit, u, u1, u2);
}
