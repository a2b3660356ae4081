// What escaped rays see (twin: src/cpu/background.rs).

fn background(dir: vec3f) -> vec3f {
//#if SKY
    let t = 0.5 * (dir.y + 1.0);
    return (1.0 - t) * vec3f(1.0) + t * SKY_ZENITH;
//#else
//#if ENVIRONMENT
    return environment_radiance(dir);
//#else
    return params.background;
//#endif
//#endif
}
