// The environment light (twin: src/cpu/environment.rs): what an escaped ray sees, and
// directions sampled in proportion to luminance x sin(theta), with their solid-angle pdf. Its
// texels and tables are in `images` (see ImageArray in src/gpu/layout.rs).

//#if ENVIRONMENT
// dir turned by -rotate_y: the image's own frame.
fn environment_local(dir: vec3f) -> vec3f {
    let c = params.environment_rotation.x;
    let s = params.environment_rotation.y;
    return vec3f(c * dir.x - s * dir.z, dir.y, s * dir.x + c * dir.z);
}

// Image coordinates (s across, t down) of unit local direction.
fn environment_coordinates(local: vec3f) -> vec2f {
    let s = (atan2(-local.z, local.x) + PI) / (2.0 * PI);
    let t = acos(clamp(local.y, -1.0, 1.0)) / PI;
    return vec2f(s, t);
}

fn environment_radiance(dir: vec3f) -> vec3f {
    let st = environment_coordinates(environment_local(dir));
    // Rows do not wrap over the poles.
    let h = f32(params.environment_height);
    let t = clamp(st.y, 0.5 / h, 1.0 - 0.5 / h);
    let texels = bilinear(params.environment_texels, params.environment_width, params.environment_height, st.x, t);
    return texels * params.environment_strength;
}

// The cell of the cumulative table of n + 1 values at `start` that u in [0, 1) falls in: the
// last i with table[i] <= u.
fn find_cell(start: u32, n: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = n;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if table(start + mid) <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

struct EnvironmentSample {
    dir: vec3f,
    pdf: f32,   // 0: no sample (a pole)
}

fn environment_sample(u1: f32, u2: f32) -> EnvironmentSample {
    let w = params.environment_width;
    let h = params.environment_height;
    let rows = params.environment_rows;
    let y = find_cell(rows, h, u1);
    let row_share = table(rows + y + 1u) - table(rows + y);
    let t = (f32(y) + min((u1 - table(rows + y)) / row_share, 1.0)) / f32(h);
    let columns = params.environment_columns + y * (w + 1u);
    let x = find_cell(columns, w, u2);
    let column_share = table(columns + x + 1u) - table(columns + x);
    let s = (f32(x) + min((u2 - table(columns + x)) / column_share, 1.0)) / f32(w);
    let sin_theta = sin(PI * t);
    if !(sin_theta > 0.0) {
        return EnvironmentSample(vec3f(0.0, 1.0, 0.0), 0.0);
    }
    let phi = 2.0 * PI * s - PI;
    let local = vec3f(sin_theta * cos(phi), cos(PI * t), -sin_theta * sin(phi));
    let c = params.environment_rotation.x;
    let sn = params.environment_rotation.y;
    let dir = vec3f(c * local.x + sn * local.z, local.y, -sn * local.x + c * local.z);
    let density = row_share * f32(h) * column_share * f32(w);
    return EnvironmentSample(dir, density / (2.0 * PI * PI * sin_theta));
}

// The solid-angle pdf with which environment_sample picks unit direction dir.
fn environment_pdf(dir: vec3f) -> f32 {
    let local = environment_local(dir);
    let sin_theta = sqrt(local.x * local.x + local.z * local.z);
    if !(sin_theta > 0.0) {
        return 0.0;
    }
    let st = environment_coordinates(local);
    let w = params.environment_width;
    let h = params.environment_height;
    let x = min(u32(max(floor(st.x * f32(w)), 0.0)), w - 1u);
    let y = min(u32(max(floor(st.y * f32(h)), 0.0)), h - 1u);
    let rows = params.environment_rows;
    let columns = params.environment_columns + y * (w + 1u);
    let density = (table(rows + y + 1u) - table(rows + y)) * f32(h)
        * (table(columns + x + 1u) - table(columns + x)) * f32(w);
    return density / (2.0 * PI * PI * sin_theta);
}
//#endif
