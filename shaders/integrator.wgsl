// The path loop (twin: src/cpu/integrator.rs): segment k adds the emission it hits, or the
// background it escapes to, for k <= max_depth. With NEE, each hit on a material that samples
// lights also samples a light (a path of one more segment, so only while that stays within
// max_depth), and light found both ways is weighted by the power heuristic.

//#if NEE
// One light sample at `hit`: the BSDF's weight toward it (BSDF x cos / BSDF pdf) and the light
// arriving times the MIS weight and the BSDF pdf over the light pdf; their product is the
// sample's contribution (zero if the light is below the surface or occluded).
struct DirectLight {
    weight: vec3f,
    light: vec3f,
}

fn direct_light(m: Material, hit: Hit, u0: f32, u1: f32, u2: f32) -> DirectLight {
    let none = DirectLight(vec3f(0.0), vec3f(0.0));
    let index = pick_light(u0);
    let s = sample_light(light_at(index), hit.point, u1, u2);
    if !(s.pdf > 0.0) {
        return none;
    }
    let b = bsdf(m, hit, s.dir);
    if !(b.pdf > 0.0) {
        return none;
    }
    // The shadow ray leaves the offset origin aimed at the sampled point itself (a tiny light
    // is not missed by the width of the offset); whatever it hits first must be that light.
    let origin = leave(hit, hit.normal);
    let to_light = s.point - origin;
    if !(dot(to_light, to_light) > 0.0) {
        return none;
    }
    var shadow: Hit;
    if !intersect(Ray(origin, normalize(to_light)), &shadow) || light_of(shadow.primitive) != index + 1u {
        return none;
    }
    let le = emitted(material_at(shadow.material), shadow.front_face);
    return DirectLight(b.weight, le * light_sample_factor(s.pdf, b.pdf));
}
//#endif

fn radiance(primary: Ray, sampler: ptr<function, Sampler>) -> vec3f {
    var ray = primary;
    var total = vec3f(0.0);
    var throughput = vec3f(1.0);
//#if NEE
    // The pdf with which the BSDF chose `ray` from `origin`; 0 when light sampling could not
    // have chosen it (camera rays, delta BSDFs), so light it finds counts in full.
    var bsdf_pdf = 0.0;
    var origin = ray.origin;
//#endif
    for (var segment = 0u; segment < params.max_depth; segment++) {
        var hit: Hit;
        if !intersect(ray, &hit) {
            total += throughput * background(ray.dir);
            break;
        }
        let m = material_at(hit.material);
        var weight = 1.0;
//#if NEE
        if bsdf_pdf > 0.0 {
            let light = light_of(hit.primitive);
            if light > 0u {
                let l = light_at(light - 1u);
                weight = power_heuristic(bsdf_pdf, light_pdf(l, origin, hit.point, ray.dir));
            }
        }
//#endif
        total += throughput * weight * emitted(m, hit.front_face);
        if segment + 1u == params.max_depth {
            break; // no longer path counts
        }
//#if NEE
        bsdf_pdf = 0.0;
        let light_sampled = samples_lights(m);
        if light_sampled {
            // Purposes: the light pick (1D), the point on the light (2D).
            sampler_begin(sampler);
            let u0 = sampler_next(sampler);
            sampler_begin(sampler);
            let u1 = sampler_next(sampler);
            let u2 = sampler_next(sampler);
            let d = direct_light(m, hit, u0, u1, u2);
            total += throughput * d.weight * d.light;
        }
//#endif
        sampler_begin(sampler);
        let s = scatter(m, ray.dir, hit, sampler);
        if !s.ok {
            break;
        }
        throughput *= s.attenuation;
//#if NEE
        if light_sampled {
            bsdf_pdf = bsdf(m, hit, s.dir).pdf;
        }
        origin = hit.point;
//#endif
        ray = spawn(hit, s.dir);
        if params.roulette_depth > 0u && segment + 1u >= params.roulette_depth {
            let survival = min(max(throughput.x, max(throughput.y, throughput.z)), MAX_SURVIVAL);
            sampler_begin(sampler);
            if !(sampler_next(sampler) < survival) {
                break;
            }
            throughput /= survival;
        }
    }
    return total;
}
