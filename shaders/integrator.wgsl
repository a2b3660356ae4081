// The path loop (twin: src/cpu/integrator.rs): segment k adds the emission it hits, or the
// background it escapes to, for k <= max_depth.

fn radiance(primary: Ray, rng: ptr<function, u32>) -> vec3f {
    var ray = primary;
    var total = vec3f(0.0);
    var throughput = vec3f(1.0);
    for (var segment = 0u; segment < params.max_depth; segment++) {
        var hit: Hit;
        if !intersect(ray, &hit) {
            total += throughput * background(ray.dir);
            break;
        }
        let m = materials[hit.material];
        total += throughput * emitted(m, hit.front_face);
        let s = scatter(m, ray.dir, hit, rng);
        if !s.ok {
            break;
        }
        throughput *= s.attenuation;
        ray = spawn(hit, s.dir);
    }
    return total;
}
