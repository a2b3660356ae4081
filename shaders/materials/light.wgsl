// A diffuse area light (twin: src/material/light.rs): emits from its front face unless
// two-sided, reflects nothing. Packed: albedo (and texture_*): radiance; emission: strength;
// param: 1 if two-sided.

fn light_emitted(m: Material, hit: Hit) -> vec3f {
    return select(vec3f(0.0), albedo_at(m, hit) * m.emission, hit.front_face || m.param > 0.5);
}

fn light_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    return BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
}
