// The environment light (twin: src/cpu/environment.rs): what an escaped ray sees, and
// directions sampled in proportion to filtered luminance above the sky's mean x sin(theta),
// with their solid-angle pdf (the distribution is built on the host:
// assets::environment::Distribution). Its
// texels and CDFs (with its cells' densities) are in `images` (see ImageArray in
// src/gpu/layout.rs).

//#if ENVIRONMENT
// dir turned by -rotate_y: the image's own frame.
fn environment_local(dir: vec3f) -> vec3f {
    let c = params.environment_rotation.x;
    let s = params.environment_rotation.y;
    return vec3f(c * dir.x - s * dir.z, dir.y, s * dir.x + c * dir.z);
}

// Image coordinates (s across, t down) of unit local direction.
fn environment_coordinates(local: vec3f) -> vec2f {
    let s = (polynomial_atan2(-local.z, local.x) + PI) / (2.0 * PI);
    let t = polynomial_acos(local.y) / PI;
    return vec2f(s, t);
}

// The image filtered at st, times the strength; rows do not wrap over the poles.
fn environment_radiance_at(st: vec2f) -> vec3f {
    let h = f32(params.environment_height);
    let t = clamp(st.y, 0.5 / h, 1.0 - 0.5 / h);
    let texels = bilinear(params.environment_texels, params.environment_width, params.environment_height, st.x, t);
    return texels * params.environment_strength;
}

fn environment_radiance(dir: vec3f) -> vec3f {
    return environment_radiance_at(environment_coordinates(environment_local(dir)));
}

struct EnvironmentSample {
    dir: vec3f,
    pdf: f32,   // 0: no sample (a pole)
}

struct CdfPick {
    index: u32,
    rest: f32,      // u's remainder, uniform in [0, 1) again
}

// The slot of the table of n slots at `start` (a vec4f per value: the value, and the guide's
// slot for u = k / n as a number) that u in [0, 1) picks: the last whose value is at most u,
// walked to from the guide's slot as Cdfs::pick does.
fn cdf_pick(start: u32, n: u32, u: f32) -> CdfPick {
    var i = u32(image_value(start + min(u32(u * f32(n)), n - 1u)).y);
    while i + 1u < n && image_value(start + i + 1u).x <= u {
        i += 1u;
    }
    while i > 0u && image_value(start + i).x > u {
        i -= 1u;
    }
    let low = image_value(start + i).x;
    let high = image_value(start + i + 1u).x;
    var rest = 0.0;
    if high > low {
        rest = clamp((u - low) / (high - low), 0.0, ONE_BELOW);
    }
    return CdfPick(i, rest);
}

// The environment distribution's cells across and down: its texels' times cells_per_texel.
fn environment_cells() -> vec2u {
    let texels = vec2u(params.environment_width, params.environment_height);
    if texels.x * texels.y <= SUBDIVIDED_MAX_TEXELS {
        return 2u * texels;
    }
    return texels;
}

// Where the CDF of the environment's cells in row y starts (after the rows' CDF); entry x
// holds cell x's density in .z.
fn environment_row_cdf(y: u32, w: u32, h: u32) -> u32 {
    return params.environment_cdfs + h + 1u + y * (w + 1u);
}

// A direction from the environment's distribution: u1 picks a row of cells from the rows' CDF,
// u2 a cell from that row's; their remainders place the direction across the cell
// (Distribution::pick and cpu::environment::sample).
fn environment_sample(u1: f32, u2: f32) -> EnvironmentSample {
    let cells = environment_cells();
    let w = cells.x;
    let h = cells.y;
    let row = cdf_pick(params.environment_cdfs, h, u1);
    let start = environment_row_cdf(row.index, w, h);
    let column = cdf_pick(start, w, u2);
    let density = image_value(start + column.index).z;
    let s = (f32(column.index) + column.rest) / f32(w);
    let t = (f32(row.index) + row.rest) / f32(h);
    let sin_theta = sin(PI * t);
    if !(sin_theta > 0.0) {
        return EnvironmentSample(vec3f(0.0, 1.0, 0.0), 0.0);
    }
    let phi = 2.0 * PI * s - PI;
    let local = vec3f(sin_theta * cos(phi), cos(PI * t), -sin_theta * sin(phi));
    let c = params.environment_rotation.x;
    let sn = params.environment_rotation.y;
    let dir = vec3f(c * local.x + sn * local.z, local.y, -sn * local.x + c * local.z);
    return EnvironmentSample(dir, density / (2.0 * PI * PI * sin_theta));
}

// The radiance from unit direction dir and the solid-angle pdf with which environment_sample
// picks it (the image coordinates found once: what an escaped ray needs).
struct EnvironmentLookup {
    radiance: vec3f,
    pdf: f32,
}

fn environment_lookup(dir: vec3f) -> EnvironmentLookup {
    let local = environment_local(dir);
    let st = environment_coordinates(local);
    return EnvironmentLookup(environment_radiance_at(st), environment_pdf_at(local, st));
}

fn environment_pdf(dir: vec3f) -> f32 {
    let local = environment_local(dir);
    return environment_pdf_at(local, environment_coordinates(local));
}

// The pdf of local direction `local` at image coordinates st: its cell's density over the
// solid angle's 2 pi^2 sin(theta).
fn environment_pdf_at(local: vec3f, st: vec2f) -> f32 {
    let sin_theta = sqrt(local.x * local.x + local.z * local.z);
    if !(sin_theta > 0.0) {
        return 0.0;
    }
    let cells = environment_cells();
    let w = cells.x;
    let h = cells.y;
    let x = min(u32(max(floor(st.x * f32(w)), 0.0)), w - 1u);
    let y = min(u32(max(floor(st.y * f32(h)), 0.0)), h - 1u);
    let density = image_value(environment_row_cdf(y, w, h) + x).z;
    return density / (2.0 * PI * PI * sin_theta);
}
//#endif
