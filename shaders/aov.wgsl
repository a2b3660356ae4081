// The feature buffers a denoiser reads (twin: src/cpu/aov.rs), as the albedo and normal
// integrators: a path goes on through delta lobes, weighted by them, and ends at the first
// other event with the albedo (one BSDF sample's weight; a light's or the background's colour;
// a medium's albedo) or the shading normal facing the ray, stored as (n + 1) / 2 (0.5 where
// there is none). One segment per call, as extend_path.

// A radiance's colour: over its largest channel (black stays black).
fn aov_colour(radiance: vec3f) -> vec3f {
    let largest = max(radiance.x, max(radiance.y, radiance.z));
    return select(vec3f(0.0), radiance / largest, largest > 0.0);
}

// What the path records where it ends on `albedo` with shading normal `shading`.
fn aov_value(albedo: vec3f, shading: vec3f) -> vec3f {
//#if AOV_NORMAL
    return clamp(0.5 * shading + vec3f(0.5), vec3f(0.0), vec3f(1.0));
//#else
    return albedo;
//#endif
}

// Traces the feature path's next segment; whether it goes on (its value is then in `total`).
fn extend_aov_path(path: ptr<function, Path>, sampler: ptr<function, Sampler>) -> bool {
    let segment = (*path).segment;
    if segment >= params.max_depth {
        (*path).total = aov_value(vec3f(0.0), vec3f(0.0));
        return false;
    }
    (*path).segment = segment + 1u;
    var hit: Hit;
//#if MEDIA
    // As in extend_path (through locals for naga's SPIR-V writer), which keeps its copy inline:
    // lavapipe keeps calls, a cost in the hottest loop.
    var ray = (*path).ray;
    var medium = (*path).medium;
    var throughput = (*path).throughput;
    let event = next_event(&ray, &medium, &throughput, &hit, sampler);
    (*path).ray = ray;
    (*path).medium = medium;
    (*path).throughput = throughput;
    if event.kind == EVENT_IN_MEDIUM {
        (*path).total = aov_value((*path).throughput * material_at((*path).medium - 1u).medium_albedo, vec3f(0.0));
        return false;
    }
    if event.kind != EVENT_SURFACE {
        if event.kind == EVENT_ESCAPED {
            (*path).total = aov_value((*path).throughput * aov_colour(background((*path).ray.dir)), vec3f(0.0));
        } else {
            (*path).total = aov_value(vec3f(0.0), vec3f(0.0));
        }
        return false;
    }
//#else
    if !intersect((*path).ray, &hit) {
        (*path).total = aov_value((*path).throughput * aov_colour(background((*path).ray.dir)), vec3f(0.0));
        return false;
    }
//#endif
//#if CHECKER || UV_CHECKER || IMAGE_TEXTURE || METALLIC_ROUGHNESS || LAYER_IMAGES
    let m = with_albedo_at(material_at(hit.material), hit);
//#else
    let m = material_at(hit.material);
//#endif
    sampler_begin(sampler);
    let s = bsdf_sample(m, -(*path).ray.dir, hit, sampler);
    if (s.lobe & LOBE_DELTA) != 0u && segment + 1u < params.max_depth {
        (*path).throughput *= s.weight;
//#if MEDIA
        if has_interior(m) && dot(s.wi, hit.normal) < 0.0 {
            (*path).medium = entered(hit);
        }
//#endif
        (*path).ray = spawn(hit, s.wi);
        return true;
    }
    let albedo = select(aov_colour(emitted(m, hit)), s.weight, s.lobe != 0u);
    (*path).total = aov_value((*path).throughput * albedo, hit.shading);
    return false;
}
