// Homogeneous media (twin: src/cpu/medium.rs): exact exponential free paths, the
// Henyey-Greenstein phase function, transmittance. Only in kernels for scenes with media.

//#if MEDIA
// A distance to the next interaction, exponentially distributed, from a uniform u in [0, 1).
fn free_flight(density: f32, u: f32) -> f32 {
    return -log(1.0 - u) / density;
}

fn transmittance(density: f32, distance: f32) -> f32 {
    return exp(-density * distance);
}

// The phase function for the cosine between the directions of travel before and after; also
// the solid-angle pdf of sample_hg.
fn hg_pdf(g: f32, cos: f32) -> f32 {
    let d = max(1.0 + g * g - 2.0 * g * cos, 1e-12);
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

// The cosine of a scattering angle: the inverse cdf; isotropic for g near 0.
fn hg_cosine(g: f32, u: f32) -> f32 {
    if abs(g) < 1e-3 {
        return 2.0 * u - 1.0;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    return clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

// A direction scattered from unit dir (the direction of travel); its weight is exactly 1.
fn sample_hg(g: f32, dir: vec3f, u1: f32, u2: f32) -> vec3f {
    let cos_theta = hg_cosine(g, u1);
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let phi = PI * (2.0 * u2 - 1.0);
    let frame = basis(dir);
    return normalize(cos_theta * dir + sin_theta * (cos(phi) * frame.t + sin(phi) * frame.b));
}
//#endif
