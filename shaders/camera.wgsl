// Primary rays (twin: src/cpu/camera.rs): pixel x covers [x, x+1)/width, row 0 is the top.

fn generate_ray(x: u32, y: u32, sampler: ptr<function, Sampler>) -> Ray {
    let jx = sampler_next_in_group(sampler);
    let jy = sampler_next_in_group(sampler);
    let s = (f32(x) + jx) / f32(params.width);
    let t = (f32(y) + jy) / f32(params.height);
    // Relative to the camera, so the direction's precision does not depend on where it is.
    var to_target = params.to_upper_left + s * params.horizontal - t * params.vertical;
    var origin = params.origin;
//#if LENS
    sampler_begin(sampler);
    let u1 = sampler_next_in_group(sampler);
    let u2 = sampler_next_in_group(sampler);
    let d = unit_disk(u1, u2);
    let on_lens = params.lens_radius * (d.x * params.right + d.y * params.up);
    origin += on_lens;
    to_target -= on_lens;
//#endif
    return Ray(origin, normalize(to_target));
}
