// The invisible surface bounding a medium (twin: src/material/medium.rs). The path loop steps
// through it before it would scatter here; this passes the ray on unchanged. Random numbers: 0.
// Packed: medium_*: the medium inside.

fn medium_scatter(m: Material, dir_in: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> Scattered {
    return Scattered(vec3f(1.0), true, dir_in);
}
