// Entry points: one invocation per pixel of the current tile.

// Per pixel of the tile, ACCUM_WORDS u32s: a running f32 mean (only for Welford's M2) and the
// count of samples taken (so the host can prove no loop was cut short), M2 and the count of
// invalid samples, each channel's exponent that its mean and M2 are scaled by (8 bits each: see
// the sample loop), then the exact sums (film.wgsl) of the even-index and of the
// odd-index samples (the replicas of a stratified sampler, see src/film/mod.rs; renders without
// them put every sample in the first). Updated sample by sample in sample order, so the result
// does not depend on how a render is sliced into dispatches.
@group(0) @binding(BINDING_ACCUM) var<storage, read_write> accum: array<u32>;

fn load3(at: u32) -> vec3u {
    return vec3u(accum[at], accum[at + 1u], accum[at + 2u]);
}

fn store3(at: u32, v: vec3u) {
    accum[at] = v.x;
    accum[at + 1u] = v.y;
    accum[at + 2u] = v.z;
}

fn load_wide(at: u32) -> Wide {
    return Wide(
        load3(at), load3(at + 3u), load3(at + 6u), load3(at + 9u), load3(at + 12u),
        load3(at + 15u), load3(at + 18u), load3(at + 21u), load3(at + 24u), load3(at + 27u),
    );
}

fn store_wide(at: u32, f: Wide) {
    store3(at, f.w0);
    store3(at + 3u, f.w1);
    store3(at + 6u, f.w2);
    store3(at + 9u, f.w3);
    store3(at + 12u, f.w4);
    store3(at + 15u, f.w5);
    store3(at + 18u, f.w6);
    store3(at + 21u, f.w7);
    store3(at + 24u, f.w8);
    store3(at + 27u, f.w9);
}

// 1 / m2_scale(exponent) of src/gpu/renderer.rs, per channel: the power of two that brings a
// sample whose exponent bits are `exponent` near 1 (1 while there is none), a normal f32 however
// bright or dim.
fn inverse_m2_scale(exponent: vec3u) -> vec3f {
    let scale = bitcast<vec3f>((vec3u(254u) - clamp(exponent, vec3u(1u), vec3u(253u))) << vec3u(23u));
    return select(scale, vec3f(1.0), exponent == vec3u(0u));
}

// 2^-k, exactly (0 from k = 127 on).
fn power_of_two_below(k: vec3u) -> vec3f {
    return bitcast<vec3f>((vec3u(127u) - min(k, vec3u(127u))) << vec3u(23u));
}

// Workgroups overhang the tile's edges; those invocations do nothing.
fn in_tile(gid: vec3u, tile_size: vec2u) -> bool {
    return gid.x < tile_size.x && gid.y < tile_size.y;
}

@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn render(@builtin(global_invocation_id) gid: vec3u) {
    // Read before any branch: lavapipe reads a storage word once for all its SIMD lanes only
    // where they all run; past a branch, each lane reads it on its own, every sample.
    let d = dispatch;
    if !in_tile(gid, d.tile_size) {
        return;
    }
    let x = d.tile_origin.x + gid.x;
    let y = d.tile_origin.y + gid.y;
    let pixel = y * params.width + x;
    let slot = ACCUM_WORDS * (gid.y * d.tile_size.x + gid.x);
    var mean = bitcast<vec3f>(load3(slot + ACCUM_MEAN));
    var count = accum[slot + ACCUM_COUNT];
    var m2 = bitcast<vec3f>(load3(slot + ACCUM_M2));
    var invalid = accum[slot + ACCUM_INVALID];
    let packed_exponents = accum[slot + ACCUM_M2_EXPONENT];
    var m2_exponent = (vec3u(packed_exponents) >> vec3u(0u, 8u, 16u)) & vec3u(0xffu);
    // Samples add to windows (film.wgsl), which join the exact sums when the dispatch ends.
    var base = vec3u(NO_BASE);
    var even_window = Window();
//#if SOBOL
    var odd_window = Window();
//#endif
    // A sample that fits no window ends the pixel's dispatch and is added after the loop, once
    // (the next dispatch continues the pixel): lavapipe runs every branch of the loop for all
    // its SIMD lanes, so a rare one still costs every iteration.
    var unfit = false;
    var unfit_sample = vec3f(0.0);
    // Samples first_sample + count onward, until the pixel holds samples_before + sample_count:
    // a pixel left short by an earlier dispatch continues where it stopped, so the image does
    // not depend on how the render was sliced. Still at most sample_count samples, however short
    // the pixel, as the host sized them to lavapipe's loop budget (a non-BVH kernel counts no
    // iterations of its own).
    let wanted = min(d.samples_before + d.sample_count, count + d.sample_count);
    // One iteration per path segment (integrator.wgsl): a lane whose path ends adds its sample
    // and starts the next at once, while its group's other lanes go on with theirs.
    if count < wanted {
        var fresh = true;
        var index = d.first_sample + count;
        let seeds = replica_seeds(pixel, d.seed);
        var sampler = sampler_with_seeds(seeds, pixel, index, d.seed);
        var path = start_path(generate_ray(x, y, &sampler));
//#if BVH
//#if LOOP_BUDGET
        // Every loop of a sample other than BVH traversals is bounded by the host; traversals
        // count their own iterations (accel.wgsl).
        loop_iterations += params.sample_loop_cost;
//#endif
//#endif
        loop {
//#if AOV_ALBEDO || AOV_NORMAL
            var goes_on = extend_aov_path(&path, &sampler);
//#else
            var goes_on = extend_path(&path, &sampler);
//#endif
//#if BVH
//#if LOOP_BUDGET
            goes_on = goes_on && !budget_spent;
//#endif
//#endif
            if goes_on {
                continue;
            }
            var l = path.total;
//#if BVH
//#if LOOP_BUDGET
            if budget_spent {
                if !fresh {
                    // Left to the next dispatch, which starts with a whole budget.
                    break;
                }
                // Not even a whole budget was enough for this one sample: recorded as invalid
                // (black, and counted) rather than retried forever.
                l = vec3f(-1.0);
            }
//#endif
//#endif
            fresh = false;
            if !valid_sample(l) {
                l = vec3f(0.0);
                invalid += 1u;
            }
            // Each channel's mean and M2 are of samples scaled by a power of two: set at its
            // first non-zero sample, raised when a sample is 2^32 brighter (mean and M2 scaled
            // down exactly, in sample order), so f32 squares stay in range at any radiance.
            let exponent = (bitcast<vec3u>(l) & vec3u(0x7fffffffu)) >> vec3u(23u);
            let raise = (exponent > m2_exponent + vec3u(32u))
                | ((m2_exponent == vec3u(0u)) & (exponent != vec3u(0u)));
            let raised = select(m2_exponent, exponent, raise);
            let down = power_of_two_below(raised - m2_exponent);
            mean *= down;
            m2 *= down * down;
            m2_exponent = raised;
            let scaled = l * inverse_m2_scale(m2_exponent);
            let delta = scaled - mean;
            mean += delta / f32(count + 1u);
            m2 += delta * (scaled - mean);
            let a = decompose(l);
            let nonzero = (a.lo | a.hi) != vec3u(0u);
            base = select(base, window_base(a), nonzero & (base == vec3u(NO_BASE)));
            unfit = !all(fits_window(a, base));
            unfit_sample = l;
//#if SOBOL
            // Only stratified renders need their replicas' statistics.
            // One window addition: lavapipe runs this block at every path segment, for all
            // lanes, so two additions (one of zero) cost twice at every segment.
            let odd = (index & 1u) == 1u;
            let added = window_add(select_window(even_window, odd_window, odd), base, only_if(a, !unfit));
            even_window = select_window(added, even_window, odd);
            odd_window = select_window(odd_window, added, odd);
//#else
            even_window = window_add(even_window, base, only_if(a, !unfit));
//#endif
            count += 1u;
            if count >= wanted || unfit {
                break;
            }
            index = d.first_sample + count;
            sampler = sampler_with_seeds(seeds, pixel, index, d.seed);
            path = start_path(generate_ray(x, y, &sampler));
//#if BVH
//#if LOOP_BUDGET
            loop_iterations += params.sample_loop_cost;
//#endif
//#endif
        }
    }
    store3(slot + ACCUM_MEAN, bitcast<vec3u>(mean));
    accum[slot + ACCUM_COUNT] = count;
    store3(slot + ACCUM_M2, bitcast<vec3u>(m2));
    accum[slot + ACCUM_INVALID] = invalid;
    accum[slot + ACCUM_M2_EXPONENT] = m2_exponent.x | (m2_exponent.y << 8u) | (m2_exponent.z << 16u);
    var even_sum = wide_add_window(load_wide(slot + ACCUM_EVEN_SUM), base, even_window);
//#if SOBOL
    var odd_sum = wide_add_window(load_wide(slot + ACCUM_ODD_SUM), base, odd_window);
    // An unfit sample was the pixel's last: its index is the one before `count`.
    if unfit && ((d.first_sample + count - 1u) & 1u) == 1u {
        odd_sum = wide_add(odd_sum, unfit_sample);
    } else if unfit {
        even_sum = wide_add(even_sum, unfit_sample);
    }
    store_wide(slot + ACCUM_ODD_SUM, odd_sum);
//#else
    if unfit {
        even_sum = wide_add(even_sum, unfit_sample);
    }
//#endif
    store_wide(slot + ACCUM_EVEN_SUM, even_sum);
}

//#if DEBUG
// The first bounce of one sample per pixel, for comparing paths with the CPU reference.
@group(0) @binding(BINDING_BOUNCES) var<storage, read_write> bounces: array<FirstBounce>;

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
    if !in_tile(gid, dispatch.tile_size) {
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
//#if CHECKER || UV_CHECKER || IMAGE_TEXTURE || METALLIC_ROUGHNESS || LAYER_IMAGES
        let m = with_albedo_at(material_at(hit.material), hit);
//#else
        let m = material_at(hit.material);
//#endif
        // A new group, as the CPU's next number after the camera's two starts one: a
        // material's first numbers are drawn unchecked (sampler_next_in_group).
        sampler_begin(&sampler);
        let s = bsdf_sample(m, -ray.dir, hit, &sampler);
        out.dir = s.wi;
        out.scattered = select(0u, 1u, s.lobe != 0u);
    }
    bounces[gid.y * dispatch.tile_size.x + gid.x] = out;
}

// The first numbers of each pixel's sample dispatch.first_sample, as bits, for comparing the
// sampler with its CPU twin: 4 (a whole group), begin, 3, begin, 5 (the fifth wraps into a new
// group).
@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn draw_samples(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid, dispatch.tile_size) {
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

// Albedo lookups, for comparing textures with the CPU: each slot holds a point (`point`), a
// material index (`primitive`) and UV coordinates (`normal.xy`) on input, and that material's
// albedo there (`dir`) on output.
@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn look_up_albedo(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid, dispatch.tile_size) {
        return;
    }
    let slot = gid.y * dispatch.tile_size.x + gid.x;
    let s = bounces[slot];
    var hit: Hit;
    hit.point = s.point;
    hit.uv = s.normal.xy;
    hit.uv1 = hit.uv;
    bounces[slot].dir = albedo_at(material_at(s.primitive), hit);
}

//#if ENVIRONMENT
// The environment, for comparing it with the CPU: each slot holds a unit direction (`point`)
// and two uniform numbers (`normal.xy`) on input; on output the radiance from that direction
// (`point`), its pdf (`primitive`, as bits), the direction sampled with the two numbers
// (`normal`) and that sample's pdf (`hit`, as bits; 0: none).
@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn look_up_environment(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid, dispatch.tile_size) {
        return;
    }
    let slot = gid.y * dispatch.tile_size.x + gid.x;
    let s = bounces[slot];
    let e = environment_sample(s.normal.x, s.normal.y);
    bounces[slot] = FirstBounce(
        environment_radiance(s.point), bitcast<u32>(environment_pdf(s.point)),
        e.dir, bitcast<u32>(e.pdf),
        vec3f(0.0), 0u,
    );
}
//#endif

//#if NEE
// The BSDF interface, for comparing materials with the CPU: each slot holds wo (`point`), a
// material index (`primitive`), the shading, coat and geometric normal (`normal`), whether the hit is
// on the front face (`hit`, 1) and a direction wi (`dir`) on input; on output bsdf_sample's weight (`point`), pdf (`primitive`, as bits), wi
// (`normal`) and lobe (`hit`), and bsdf_eval (`dir`) and bsdf_pdf (`scattered`, as bits) at
// the input's wo and wi. The sample's numbers are sample dispatch.first_sample's, after one
// sampler_begin.
@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn sample_bsdf(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid, dispatch.tile_size) {
        return;
    }
    let slot = gid.y * dispatch.tile_size.x + gid.x;
    let pixel = (dispatch.tile_origin.y + gid.y) * params.width + dispatch.tile_origin.x + gid.x;
    let input = bounces[slot];
    var hit: Hit;
    hit.normal = input.normal;
    hit.shading = input.normal;
    hit.coat = input.normal;
    hit.front_face = input.hit != 0u;
    hit.material = input.primitive;
    let m = material_at(input.primitive);
    var sampler = sampler_for_sample(pixel, dispatch.first_sample, dispatch.seed);
    sampler_begin(&sampler);
    let s = bsdf_sample(m, input.point, hit, &sampler);
    bounces[slot] = FirstBounce(
        s.weight, bitcast<u32>(s.pdf),
        s.wi, s.lobe,
        bsdf_eval(m, input.point, input.dir, hit), bitcast<u32>(bsdf_pdf(m, input.point, input.dir, hit)),
    );
}
//#endif

// Closest hits of arbitrary rays, for robustness tests: each slot holds a ray on input (point:
// origin, dir: direction) and its hit on output (dir is kept; in BVH kernels `scattered` holds
// the traversal's loop count).
@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn trace_rays(@builtin(global_invocation_id) gid: vec3u) {
    if !in_tile(gid, dispatch.tile_size) {
        return;
    }
    let slot = gid.y * dispatch.tile_size.x + gid.x;
    var hit: Hit;
//#if BVH
//#if LOOP_BUDGET
    loop_iterations = 0u;
//#endif
//#endif
    var out = trace_debug(Ray(bounces[slot].point, bounces[slot].dir), &hit);
//#if BVH
//#if LOOP_BUDGET
    // The traversal's loop count, which the CPU's model of it (src/cpu/traversal_stats.rs)
    // must match ray for ray (debug kernels count, whatever the device).
    out.scattered = loop_iterations;
//#endif
//#endif
    bounces[slot] = out;
}
//#endif
