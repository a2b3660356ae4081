// The invisible surface bounding a medium (twin: src/material/medium.rs). The path loop steps
// through it before it would scatter here; this passes the ray on unchanged. Random numbers: 0.
// Its medium is GpuMaterial's medium_*; it has no parameters of its own.

fn medium_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    return BsdfSample(vec3f(1.0), -wo, 0.0, LOBE_TRANSMISSION | LOBE_DELTA);
}
