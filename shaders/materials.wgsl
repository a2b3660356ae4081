// Materials (twin: src/cpu/material.rs) as the integrator sees them: emitted, scatter (the BSDF
// sampled) and, for BSDFs light sampling can reach, bsdf toward a direction; the path loop
// never names a material. Random numbers per bounce: lambertian 2, metal 2, dielectric 1, light 0.

struct Scattered {
    attenuation: vec3f,
    ok: bool,            // false: the path ends here
    dir: vec3f,
}

//#if INLINE_SCENE
// material_at is generated with the scene's constants (see inline_materials in
// src/gpu/shader.rs): lavapipe gathers buffer loads at dynamic indices lane by lane.
//#else
fn material_at(i: u32) -> Material {
    return materials[i];
}
//#endif

fn emitted(m: Material, front_face: bool) -> vec3f {
//#if LIGHT
    if m.kind == MAT_LIGHT {
        if front_face || m.param > 0.5 {
            return m.emission;
        }
        return vec3f(0.0);
    }
//#endif
//#if EMISSIVE
    if m.kind == MAT_LAMBERTIAN {
        return m.emission;
    }
//#endif
    return vec3f(0.0);
}

//#if NEE
// Whether next-event estimation samples lights here: the BSDF is neither a delta nor absent.
fn samples_lights(m: Material) -> bool {
    return m.kind == MAT_LAMBERTIAN;
}

// The BSDF toward unit `dir`: weight = BSDF x cos / pdf, and the solid-angle pdf with which
// scatter picks `dir`; pdf 0 where scatter cannot pick it.
struct Bsdf {
    weight: vec3f,
    pdf: f32,
}

fn bsdf(m: Material, hit: Hit, dir: vec3f) -> Bsdf {
    var out = Bsdf(vec3f(0.0), 0.0);
//#if LAMBERTIAN
    if m.kind == MAT_LAMBERTIAN {
        // Cosine-weighted: pdf = cos / pi, BSDF x cos / pdf = albedo.
        let cos = dot(hit.normal, dir);
        if cos > 0.0 {
            out = Bsdf(m.albedo, cos / PI);
        }
    }
//#endif
    return out;
}
//#endif

fn reflect_dir(d: vec3f, n: vec3f) -> vec3f {
    return d - 2.0 * dot(d, n) * n;
}

fn scatter(m: Material, dir_in: vec3f, hit: Hit, rng: ptr<function, u32>) -> Scattered {
    var out = Scattered(vec3f(0.0), false, vec3f(0.0, 1.0, 0.0));
//#if LAMBERTIAN
    if m.kind == MAT_LAMBERTIAN {
        // normal + a uniform unit vector is cosine-distributed about the normal.
        let u1 = rng_next(rng);
        let u2 = rng_next(rng);
        let d = hit.normal + unit_vector(u1, u2);
        let len2 = dot(d, d);
        out.dir = select(hit.normal, d / sqrt(len2), len2 > 1e-12);
        out.attenuation = m.albedo;
        out.ok = true;
    }
//#endif
//#if METAL
    if m.kind == MAT_METAL {
        let u1 = rng_next(rng);
        let u2 = rng_next(rng);
        let fuzzed = reflect_dir(dir_in, hit.normal) + m.param * unit_vector(u1, u2);
        let len2 = dot(fuzzed, fuzzed);
        if len2 > 1e-12 {
            out.dir = fuzzed / sqrt(len2);
            out.attenuation = m.albedo;
            // Fuzzed below the surface: absorbed.
            out.ok = dot(out.dir, hit.normal) > 0.0;
        }
    }
//#endif
//#if DIELECTRIC
    if m.kind == MAT_DIELECTRIC {
        let eta = select(m.param, 1.0 / m.param, hit.front_face);
        let cos_i = clamp(dot(-dir_in, hit.normal), 0.0, 1.0);
        let u = rng_next(rng);
        var dir = reflect_dir(dir_in, hit.normal);
        let sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
        if sin2_t < 1.0 {
            let cos_t = sqrt(1.0 - sin2_t);
            if u >= fresnel(cos_i, cos_t, eta) {
                dir = eta * dir_in + (eta * cos_i - cos_t) * hit.normal;
            }
        }
        out.dir = normalize(dir);
        out.attenuation = vec3f(1.0);
        out.ok = true;
    }
//#endif
    return out;
}

//#if DIELECTRIC
// Exact unpolarised Fresnel reflectance; eta = n_incident / n_transmitted.
fn fresnel(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}
//#endif

fn background(dir: vec3f) -> vec3f {
//#if SKY
    let t = 0.5 * (dir.y + 1.0);
    return (1.0 - t) * vec3f(1.0) + t * SKY_ZENITH;
//#else
    return params.background;
//#endif
}
