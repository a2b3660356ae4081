// Mirror reflection perturbed by fuzz (twin: src/material/metal.rs); rays fuzzed below the
// surface are absorbed. The fuzzed lobe's density is not evaluated: it counts as a delta.
// Random numbers per sample: 2. Its albedo is GpuMaterial's (albedo_at); its parameters:
// MetalParams.

fn metal_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let u1 = sampler_next_in_group(sampler);
    let u2 = sampler_next_in_group(sampler);
    let fuzzed = reflect_dir(-wo, hit.shading) + metal_params(m).fuzz * unit_vector(u1, u2);
    let len2 = dot(fuzzed, fuzzed);
    if len2 > 1e-12 {
        out.wi = fuzzed / sqrt(len2);
        out.weight = albedo_at(m, hit);
        // Fuzzed (or, by a shading normal, reflected) below the surface: absorbed.
        out.lobe = select(0u, LOBE_REFLECTION | LOBE_DELTA, dot(out.wi, hit.normal) > 0.0);
    }
    return out;
}
