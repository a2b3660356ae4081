// Entry points: one invocation per pixel of the current tile.

// Per pixel of the tile, four vec4s: the running mean (w: count of non-finite samples, as
// bits), the Kahan compensation of the mean (w: samples accumulated, as bits, so the host can
// prove no loop was cut short), Welford's M2, and the running mean of the odd-index samples
// (replica 1 of a stratified sampler; see src/film.rs). Updated sample by sample in sample order, so
// the result does not depend on how a render is sliced into dispatches.
@group(0) @binding(4) var<storage, read_write> accum: array<vec4f>;

// WGSL lets implementations assume floats are finite, so test the exponent bits instead.
fn all_finite(v: vec3f) -> bool {
    let exponent = bitcast<vec3u>(v) & vec3u(0x7f800000u);
    return all(exponent != vec3u(0x7f800000u));
}

// Workgroups overhang the tile's edges; those invocations do nothing.
fn in_tile(gid: vec3u) -> bool {
    return gid.x < dispatch.tile_size.x && gid.y < dispatch.tile_size.y;
}

@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn render(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid) {
        return;
    }
    let x = dispatch.tile_origin.x + gid.x;
    let y = dispatch.tile_origin.y + gid.y;
    let pixel = y * params.width + x;
    let slot = 4u * (gid.y * dispatch.tile_size.x + gid.x);
    let first = accum[slot];
    var mean = first.xyz;
    var invalid = bitcast<u32>(first.w);
    let second = accum[slot + 1u];
    var compensation = second.xyz;
    var count = bitcast<u32>(second.w);
    var m2 = accum[slot + 2u].xyz;
    var odd_mean = accum[slot + 3u].xyz;
    // Odd sample indices so far: those in [first of the render, first of this dispatch).
    let render_first = dispatch.first_sample - dispatch.samples_before;
    var odd_n = dispatch.first_sample / 2u - render_first / 2u;
    for (var s = 0u; s < dispatch.sample_count; s++) {
        let index = dispatch.first_sample + s;
        var sampler = sampler_for_sample(pixel, index, dispatch.seed);
        let ray = generate_ray(x, y, &sampler);
        var l = radiance(ray, &sampler);
        if !all_finite(l) {
            l = vec3f(0.0);
            invalid += 1u;
        }
        let n = f32(dispatch.samples_before + s + 1u);
        let delta = l - mean;
        // Kahan-compensated mean += delta / n. Drivers may compile with fast-math, under which
        // (mean + step - mean) - step folds to 0; passing `next` through a select on a value
        // the compiler cannot know (the image width is never 0) keeps the rounding error real.
        let step = delta / n - compensation;
        let next = select(vec3f(0.0), mean + step, params.width != 0u);
        compensation = (next - mean) - step;
        mean = next;
        m2 += delta * (l - mean);
//#if SOBOL
        // Only stratified renders need their replicas' statistics.
        if (index & 1u) == 1u {
            odd_n += 1u;
            odd_mean += (l - odd_mean) / f32(odd_n);
        }
//#endif
        count += 1u;
    }
    accum[slot] = vec4f(mean, bitcast<f32>(invalid));
    accum[slot + 1u] = vec4f(compensation, bitcast<f32>(count));
    accum[slot + 2u] = vec4f(m2, 0.0);
    accum[slot + 3u] = vec4f(odd_mean, 0.0);
}

//#if DEBUG
// The first bounce of one sample per pixel, for comparing paths with the CPU reference.
@group(0) @binding(5) var<storage, read_write> bounces: array<FirstBounce>;

// The closest hit of `ray` as a FirstBounce (not yet scattered), and the hit itself.
fn trace_debug(ray: Ray, hit: ptr<function, Hit>) -> FirstBounce {
    var out = FirstBounce(vec3f(0.0), 0u, vec3f(0.0), 0u, ray.dir, 0u);
    if intersect(ray, hit) {
        out.point = (*hit).point;
        out.primitive = (*hit).primitive;
        out.normal = (*hit).normal;
        out.hit = 1u;
    }
    return out;
}

@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn first_bounce(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid) {
        return;
    }
    let x = dispatch.tile_origin.x + gid.x;
    let y = dispatch.tile_origin.y + gid.y;
    let pixel = y * params.width + x;
    var sampler = sampler_for_sample(pixel, dispatch.first_sample, dispatch.seed);
    let ray = generate_ray(x, y, &sampler);
    var hit: Hit;
    var out = trace_debug(ray, &hit);
    out.dir = vec3f(0.0);
    if out.hit == 1u {
        let s = scatter(material_at(hit.material), ray.dir, hit, &sampler);
        out.dir = s.dir;
        out.scattered = select(0u, 1u, s.ok);
    }
    bounces[gid.y * dispatch.tile_size.x + gid.x] = out;
}

// The first numbers of each pixel's sample dispatch.first_sample, as bits, for comparing the
// sampler with its CPU twin: 4 (a whole group), begin, 3, begin, 5 (the fifth wraps into a new
// group).
@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn draw_samples(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid) {
        return;
    }
    let pixel = (dispatch.tile_origin.y + gid.y) * params.width + dispatch.tile_origin.x + gid.x;
    var sampler = sampler_for_sample(pixel, dispatch.first_sample, dispatch.seed);
    var u: array<u32, 12>;
    for (var i = 0u; i < 12u; i++) {
        if i == 4u || i == 7u {
            sampler_begin(&sampler);
        }
        u[i] = bitcast<u32>(sampler_next(&sampler));
    }
    bounces[gid.y * dispatch.tile_size.x + gid.x] = FirstBounce(
        bitcast<vec3f>(vec3u(u[0], u[1], u[2])), u[3],
        bitcast<vec3f>(vec3u(u[4], u[5], u[6])), u[7],
        bitcast<vec3f>(vec3u(u[8], u[9], u[10])), u[11],
    );
}

// Closest hits of arbitrary rays, for robustness tests: each slot holds a ray on input (point:
// origin, dir: direction) and its hit on output (dir is kept).
@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn trace_rays(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid) {
        return;
    }
    let slot = gid.y * dispatch.tile_size.x + gid.x;
    var hit: Hit;
    bounces[slot] = trace_debug(Ray(bounces[slot].point, bounces[slot].dir), &hit);
}
//#endif
