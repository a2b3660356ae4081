// A diffuse area light (twin: src/material/light.rs): emits from its front face unless
// two-sided, reflects nothing. Its radiance is GpuMaterial's albedo (albedo_at); its
// parameters: LightParams.

fn light_emitted(m: Material, hit: Hit) -> vec3f {
    let p = light_params(m);
    return select(vec3f(0.0), texture_at(m, hit) * p.strength, hit.front_face || p.two_sided != 0u);
}

fn light_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    return BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
}
