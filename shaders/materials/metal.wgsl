// Mirror reflection perturbed by fuzz (twin: src/material/metal.rs); rays fuzzed below the
// surface are absorbed. Random numbers per scatter: 2. Packed: albedo; param: fuzz.

fn metal_scatter(m: Material, dir_in: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> Scattered {
    var out = Scattered(vec3f(0.0), false, vec3f(0.0, 1.0, 0.0));
    let u1 = sampler_next(sampler);
    let u2 = sampler_next(sampler);
    let fuzzed = reflect_dir(dir_in, hit.shading) + m.param * unit_vector(u1, u2);
    let len2 = dot(fuzzed, fuzzed);
    if len2 > 1e-12 {
        out.dir = fuzzed / sqrt(len2);
        out.attenuation = albedo_at(m, hit);
        // Fuzzed (or, by a shading normal, reflected) below the surface: absorbed.
        out.ok = dot(out.dir, hit.normal) > 0.0;
    }
    return out;
}
