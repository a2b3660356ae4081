// The material interface (twin: src/material/mod.rs): pbrt-v4's and Mitsuba 3's sample, eval
// and pdf, with directions away from the surface (wo toward where the path came from, wi
// toward where it goes) and BsdfSample generated from src/material/bsdf.rs. Each material's
// functions are in shaders/materials/<name>.wgsl, included when the scene uses it;
// `emitted`, `samples_lights`, `bsdf_sample`, `bsdf_eval` and `bsdf_pdf`, which dispatch on
// the kind, are generated after them from the registry (see material_dispatch in
// src/gpu/shader.rs). The path loop never names a material.

//#if INLINE_SCENE
// material_at is generated with the scene's constants (see inline_materials in
// src/gpu/shader.rs): lavapipe gathers buffer loads at dynamic indices lane by lane.
//#else
fn material_at(i: u32) -> Material {
    return materials[i];
}
//#endif

fn reflect_dir(d: vec3f, n: vec3f) -> vec3f {
    return d - 2.0 * dot(d, n) * n;
}
