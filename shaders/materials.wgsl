// The material interface (twin: src/material/mod.rs). Each material's functions are in
// shaders/materials/<name>.wgsl, included when the scene uses it; `emitted`, `samples_lights`,
// `bsdf` and `scatter`, which dispatch on the kind, are generated after them from the registry
// (see material_dispatch in src/gpu/shader.rs). The path loop never names a material.

struct Scattered {
    attenuation: vec3f,
    ok: bool,            // false: the path ends here
    dir: vec3f,
}

// The BSDF toward unit `dir`: weight = BSDF x cos / pdf, and the solid-angle pdf with which
// scatter picks `dir`; pdf 0 where scatter cannot pick it.
struct Bsdf {
    weight: vec3f,
    pdf: f32,
}

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
