// The path loop (twin: src/cpu/integrator.rs): segment k adds the emission it hits, or the
// background it escapes to, for k <= max_depth. With NEE, each hit on a material that samples
// lights, and each scattering event in a medium, also samples a light (a path of one more
// segment, so only while that stays within max_depth), and light found both ways is weighted
// by the power heuristic. Media: the ray knows the medium it is in (1 + the index of the
// material filled with it; 0: none) and samples a free path in it; invisible boundaries are
// stepped through without ending a segment.

//#if MEDIA
// The medium on the far side of hit's surface, for a surface filled with one.
fn entered(hit: Hit) -> u32 {
    return select(0u, hit.material + 1u, hit.front_face);
}

const EVENT_ESCAPED: u32 = 0u;
const EVENT_SURFACE: u32 = 1u;
const EVENT_IN_MEDIUM: u32 = 2u;
// More invisible boundaries than the scene can have (a degenerate ray): the path ends.
const EVENT_LOST: u32 = 3u;

struct Event {
    kind: u32,
    point: vec3f,       // EVENT_IN_MEDIUM: where it scatters
}

// Whether material m fills what it bounds with a medium (Material::interior).
fn has_interior(m: Material) -> bool {
//#if ABSORPTION
    return m.medium_density > 0.0 || any(m.medium_absorption > vec3f(0.0));
//#else
    return m.medium_density > 0.0;
//#endif
}

// The fraction of each channel crossing `distance` of the medium inside m (Medium::transmittance):
// its extinction's and its absorption's.
fn medium_transmittance(m: Material, distance: f32) -> vec3f {
//#if ABSORPTION
    let sigma = vec3f(m.medium_density) + m.medium_absorption;
    return select(exp(-sigma * distance), vec3f(1.0), sigma == vec3f(0.0));
//#else
    return vec3f(transmittance(m.medium_density, distance));
//#endif
}

//#if ABSORPTION
// What the absorption of the medium inside m leaves of light travelling `distance`
// (Medium::absorbed_over).
fn absorbed_over(m: Material, distance: f32) -> vec3f {
    // Out of an open mesh nothing bounds the stretch (and no infinity is computed).
    let attenuated = select(exp(-m.medium_absorption * distance), vec3f(0.0), distance >= F32_MAX);
    return select(attenuated, vec3f(1.0), m.medium_absorption == vec3f(0.0));
}
//#endif

// Follows the ray to the end of its segment, through invisible medium boundaries (updating ray
// and medium), sampling a free path in each medium of some density on the way and weighing
// `throughput` by what the media's absorption leaves of it; EVENT_SURFACE leaves the hit in
// `hit`. Random numbers: 1 per stretch travelled in a medium of some density.
fn next_event(ray: ptr<function, Ray>, medium: ptr<function, u32>, throughput: ptr<function, vec3f>, hit: ptr<function, Hit>, sampler: ptr<function, Sampler>) -> Event {
    for (var i = 0u; i <= MEDIUM_CROSSINGS; i++) {
        let found = intersect(*ray, hit);
        if *medium != 0u {
//#if ABSORPTION
            let interior = material_at(*medium - 1u);
            let far = select(F32_MAX, (*hit).t, found);
            if interior.medium_density > 0.0 {
                sampler_begin(sampler);
                let distance = free_flight(interior.medium_density, sampler_next_in_group(sampler));
                if distance < far {
                    *throughput *= absorbed_over(interior, distance);
                    return Event(EVENT_IN_MEDIUM, (*ray).origin + distance * (*ray).dir);
                }
            }
            *throughput *= absorbed_over(interior, far);
//#else
            // Without absorption every medium has a density (Medium::check).
            sampler_begin(sampler);
            let distance = free_flight(material_at(*medium - 1u).medium_density, sampler_next_in_group(sampler));
            if distance < select(F32_MAX, (*hit).t, found) {
                return Event(EVENT_IN_MEDIUM, (*ray).origin + distance * (*ray).dir);
            }
//#endif
        }
        if !found {
            return Event(EVENT_ESCAPED, vec3f(0.0));
        }
        if material_at((*hit).material).kind != MAT_MEDIUM {
            return Event(EVENT_SURFACE, vec3f(0.0));
        }
        *medium = entered(*hit);
        *ray = spawn(*hit, (*ray).dir);
    }
    return Event(EVENT_LOST, vec3f(0.0));
}
//#endif

//#if NEE
//#if MEDIA
// The radiance light `index` sends to `start` along sample `s` (toward its point; the
// environment and the sun along its direction), where the shadow ray starts in `medium_in`: its
// emission (a punctual light: what reaches start) times the media's transmittance on the way,
// through invisible boundaries; zero when anything else is hit first.
fn light_arriving(start: vec3f, s: LightSample, index: u32, medium_in: u32) -> vec3f {
    var dir = s.dir;
//#if ENVIRONMENT
    let environment = index + 1u == params.light_count;
//#else
    let environment = false;
//#endif
    // A punctual light: what it sends to start, reached unless something lies before reach.
    var punctual = false;
    var sent = vec3f(0.0);
    var at_infinity = environment;
    var reach = 3.0e38; // the sun and the environment: no distance stops the ray
//#if PUNCTUAL
    let l = light_at(index);
    punctual = is_punctual(l);
    if punctual {
        sent = punctual_arriving(l, start);
        at_infinity = l.kind == KIND_DIRECTIONAL;
    }
//#endif
    if !at_infinity {
        let to_light = s.point - start;
        if !(dot(to_light, to_light) > 0.0) {
            return vec3f(0.0);
        }
        dir = normalize(to_light);
        reach = length(to_light);
    }
    var ray = Ray(start, dir);
    var medium = medium_in;
    var transmitted = vec3f(1.0);
    for (var i = 0u; i <= MEDIUM_CROSSINGS; i++) {
        var hit: Hit;
        let found = intersect(ray, &hit);
        if punctual && (!found || hit.t >= reach) {
            if medium != 0u {
                transmitted *= medium_transmittance(material_at(medium - 1u), reach);
            }
            return sent * transmitted;
        }
        if !found {
//#if ENVIRONMENT
            if environment {
                return environment_radiance(dir) * transmitted;
            }
//#endif
            return vec3f(0.0);
        }
        if medium != 0u {
            transmitted *= medium_transmittance(material_at(medium - 1u), hit.t);
        }
        let m = material_at(hit.material);
        if !punctual && light_of(hit.primitive) == index + 1u {
            return emitted(m, hit) * transmitted;
        }
        if m.kind != MAT_MEDIUM {
            return vec3f(0.0);
        }
        medium = entered(hit);
        ray = spawn(hit, ray.dir);
        reach -= hit.t;
    }
    return vec3f(0.0);
}

// One light sample at a scattering event at `point` for a ray that travelled along `dir`: the
// light arriving times the MIS weight and the phase function over the light pdf.
fn medium_direct_light(point: vec3f, dir: vec3f, g: f32, medium: u32, u0: f32, u1: f32, u2: f32) -> vec3f {
    let index = pick_light(u0);
    let s = sample_light(light_at(index), point, u1, u2);
    if !(s.pdf > 0.0) {
        return vec3f(0.0);
    }
    let phase_pdf = hg_pdf(g, dot(dir, s.dir));
//#if PUNCTUAL
    if is_punctual(light_at(index)) {
        return light_arriving(point, s, index, medium) * (phase_pdf / s.pdf);
    }
//#endif
    return light_arriving(point, s, index, medium) * light_sample_factor(s.pdf, phase_pdf);
}
//#endif

// One light sample at `hit`, reached along `dir`: the light arriving times BSDF x cos and the
// MIS weight over the light pdf (zero if the BSDF is zero toward it or the light is occluded).
fn direct_light(m: Material, hit: Hit, dir: vec3f, medium: u32, u0: f32, u1: f32, u2: f32) -> vec3f {
    let index = pick_light(u0);
    let s = sample_light(light_at(index), hit.point, u1, u2);
    if !(s.pdf > 0.0) {
        return vec3f(0.0);
    }
    let f = bsdf_eval(m, -dir, s.dir, hit);
    if all(f == vec3f(0.0)) {
        return vec3f(0.0);
    }
    // A punctual light's sample is a direction with probability: no MIS (BSDF sampling never
    // finds it).
    var weight: f32;
//#if PUNCTUAL
    let punctual = is_punctual(light_at(index));
    if punctual {
        weight = 1.0 / s.pdf;
    } else {
        weight = light_sample_weight(s.pdf, bsdf_pdf(m, -dir, s.dir, hit));
    }
//#else
    weight = light_sample_weight(s.pdf, bsdf_pdf(m, -dir, s.dir, hit));
//#endif
    // The shadow ray leaves the offset origin aimed at the sampled point itself (a tiny light
    // is not missed by the width of the offset); whatever it hits first must be that light.
    // Through the surface (rough glass), it leaves on the far side, into the medium there.
    let through = dot(s.dir, hit.normal) < 0.0;
    let origin = leave(hit, select(hit.normal, -hit.normal, through));
//#if MEDIA
    let le = light_arriving(origin, s, index, select(medium, entered(hit), through && has_interior(m)));
//#else
//#if ENVIRONMENT
    if index + 1u == params.light_count {
        var blocker: Hit;
        if intersect(Ray(origin, s.dir), &blocker) {
            return vec3f(0.0);
        }
        return f * (environment_radiance(s.dir) * weight);
    }
//#endif
//#if PUNCTUAL
    if punctual {
        let l = light_at(index);
        var blocker: Hit;
        if l.kind == KIND_DIRECTIONAL {
            if intersect(Ray(origin, s.dir), &blocker) {
                return vec3f(0.0);
            }
        } else {
            let to_point = s.point - origin;
            if !(dot(to_point, to_point) > 0.0) {
                return vec3f(0.0);
            }
            if intersect(Ray(origin, normalize(to_point)), &blocker) && blocker.t < length(to_point) {
                return vec3f(0.0);
            }
        }
        return f * (punctual_arriving(l, origin) * weight);
    }
//#endif
    let to_light = s.point - origin;
    if !(dot(to_light, to_light) > 0.0) {
        return vec3f(0.0);
    }
    var shadow: Hit;
    if !intersect_emitter(Ray(origin, normalize(to_light)), &shadow) || light_of(shadow.primitive) != index + 1u {
        return vec3f(0.0);
    }
    let le = emitted(material_at(shadow.material), shadow);
//#endif
    return f * (le * weight);
}
//#endif

// The background a ray escapes to along dir, chosen by the BSDF with pdf bsdf_pdf (0: not by one
// that light sampling could match), times its MIS weight against sampling the environment (the
// last light).
fn escaped(bsdf_pdf: f32, dir: vec3f) -> vec3f {
//#if NEE
//#if ENVIRONMENT
    if bsdf_pdf > 0.0 {
        let e = environment_lookup(dir);
        return power_heuristic(bsdf_pdf, light_at(params.light_count - 1u).pick * e.pdf) * e.radiance;
    }
//#endif
//#endif
    return background(dir);
}

// Path, a path under way (twin: the loop of radiance in src/cpu/integrator.rs, one iteration per
// extend_path call, advanced a segment at a time: path regeneration), is generated from
// src/gpu/kernel_state.rs.

fn start_path(primary: Ray) -> Path {
    return Path(primary, vec3f(0.0), vec3f(1.0), 0u, 0u, 0.0, primary.origin);
}

// Traces the path's next segment and adds what it finds to `total`: whether the path goes on.
fn extend_path(path: ptr<function, Path>, sampler: ptr<function, Sampler>) -> bool {
    let segment = (*path).segment;
    if segment >= params.max_depth {
        return false;
    }
    (*path).segment = segment + 1u;
    var hit: Hit;
//#if MEDIA
    // Through locals: naga 30's SPIR-V writer fails on pointers into a pointed-to struct
    // passed on to a function.
    var ray = (*path).ray;
    var medium = (*path).medium;
    var throughput = (*path).throughput;
    let event = next_event(&ray, &medium, &throughput, &hit, sampler);
    (*path).ray = ray;
    (*path).medium = medium;
    (*path).throughput = throughput;
    if event.kind == EVENT_IN_MEDIUM {
        // Nothing is emitted here; this vertex can only extend the path.
        if segment + 1u == params.max_depth {
            return false;
        }
        let interior = material_at((*path).medium - 1u);
        (*path).throughput *= interior.medium_albedo;
//#if NEE
        (*path).bsdf_pdf = 0.0;
        {
            sampler_begin(sampler);
            let u0 = sampler_next_in_group(sampler);
            sampler_begin(sampler);
            let u1 = sampler_next_in_group(sampler);
            let u2 = sampler_next_in_group(sampler);
            (*path).total += (*path).throughput * medium_direct_light(event.point, (*path).ray.dir, interior.medium_g, (*path).medium, u0, u1, u2);
        }
//#endif
        sampler_begin(sampler);
        let u1 = sampler_next_in_group(sampler);
        let u2 = sampler_next_in_group(sampler);
        let dir = sample_hg(interior.medium_g, (*path).ray.dir, u1, u2);
//#if NEE
        (*path).bsdf_pdf = hg_pdf(interior.medium_g, dot((*path).ray.dir, dir));
        (*path).origin = event.point;
//#endif
        (*path).ray = Ray(event.point, dir);
        // Russian roulette: the path goes on with the chance of its largest throughput
        // component (at most MAX_SURVIVAL), reweighted. Random numbers: 1 when it plays.
        if params.roulette_depth > 0u && segment + 1u >= params.roulette_depth {
            let survival = min(max((*path).throughput.x, max((*path).throughput.y, (*path).throughput.z)), MAX_SURVIVAL);
            sampler_begin(sampler);
            if !(sampler_next_in_group(sampler) < survival) {
                return false;
            }
            (*path).throughput /= survival;
        }
        return true;
    }
    if event.kind != EVENT_SURFACE {
        if event.kind == EVENT_ESCAPED {
            (*path).total += (*path).throughput * escaped((*path).bsdf_pdf, (*path).ray.dir);
        }
        return false;
    }
//#else
    if !intersect((*path).ray, &hit) {
        (*path).total += (*path).throughput * escaped((*path).bsdf_pdf, (*path).ray.dir);
        return false;
    }
//#endif
//#if CHECKER || UV_CHECKER || IMAGE_TEXTURE || METALLIC_ROUGHNESS || LAYER_IMAGES
    let m = with_albedo_at(material_at(hit.material), hit);
//#else
    let m = material_at(hit.material);
//#endif
    var weight = 1.0;
//#if NEE
    if (*path).bsdf_pdf > 0.0 {
        let light = light_of(hit.primitive);
        if light > 0u {
            let l = light_at(light - 1u);
            weight = power_heuristic((*path).bsdf_pdf, light_pdf(l, (*path).origin, hit.point, (*path).ray.dir));
        }
    }
//#endif
    (*path).total += (*path).throughput * weight * emitted(m, hit);
    if segment + 1u == params.max_depth {
        return false; // no longer path counts
    }
//#if NEE
    (*path).bsdf_pdf = 0.0;
    let light_sampled = samples_lights(m);
    if light_sampled {
        // Purposes: the light pick (1D), the point on the light (2D).
        sampler_begin(sampler);
        let u0 = sampler_next_in_group(sampler);
        sampler_begin(sampler);
        let u1 = sampler_next_in_group(sampler);
        let u2 = sampler_next_in_group(sampler);
        (*path).total += (*path).throughput * direct_light(m, hit, (*path).ray.dir, (*path).medium, u0, u1, u2);
    }
//#endif
    sampler_begin(sampler);
    let s = bsdf_sample(m, -(*path).ray.dir, hit, sampler);
    if s.lobe == 0u {
        return false;
    }
    (*path).throughput *= s.weight;
//#if NEE
    if light_sampled && (s.lobe & LOBE_DELTA) == 0u {
        (*path).bsdf_pdf = s.pdf;
    }
    (*path).origin = hit.point;
//#endif
//#if MEDIA
    if has_interior(m) && dot(s.wi, hit.normal) < 0.0 {
        (*path).medium = entered(hit); // refracted through a surface filled with a medium
    }
//#endif
    (*path).ray = spawn(hit, s.wi);
    // Russian roulette (as after a scattering event in a medium above). Written out, not
    // a function: lavapipe keeps the call, a cost in this hottest loop.
    if params.roulette_depth > 0u && segment + 1u >= params.roulette_depth {
        let survival = min(max((*path).throughput.x, max((*path).throughput.y, (*path).throughput.z)), MAX_SURVIVAL);
        sampler_begin(sampler);
        if !(sampler_next_in_group(sampler) < survival) {
            return false;
        }
        (*path).throughput /= survival;
    }
    return true;
}
