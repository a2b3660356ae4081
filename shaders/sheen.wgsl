// glTF's sheen (KHR_materials_sheen) over pbr's mix (twin: src/material/sheen.rs, whose
// comment gives the model): the Charlie distribution and Estevez and Kulla's visibility (of a,
// the roughness squared) times
// the sheen colour, the mix below scaled by 1 - m E(cos_o), E read off
// the albedo table the material's sheen_table points to in the images array.

//#if PBR
//#if SHEEN
const SHEEN_MIN_ROUGHNESS: f32 = 0.25;
const SHEEN_TABLE_SIZE: u32 = 32u;

// E(cos, roughness): the sheen's directional albedo, bilinear between the table's entries
// (cosine across, roughness down).
fn sheen_albedo(table: u32, cos: f32, roughness: f32) -> f32 {
    let last = f32(SHEEN_TABLE_SIZE - 1u);
    let x = clamp(cos, 0.0, 1.0) * last;
    let y = clamp((roughness - SHEEN_MIN_ROUGHNESS) / (1.0 - SHEEN_MIN_ROUGHNESS), 0.0, 1.0) * last;
    let i = min(u32(x), SHEEN_TABLE_SIZE - 2u);
    let j = min(u32(y), SHEEN_TABLE_SIZE - 2u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let row = table + j * SHEEN_TABLE_SIZE + i;
    let top = image_value(row).x * (1.0 - fx) + image_value(row + 1u).x * fx;
    let bottom = image_value(row + SHEEN_TABLE_SIZE).x * (1.0 - fx) + image_value(row + SHEEN_TABLE_SIZE + 1u).x * fx;
    return top * (1.0 - fy) + bottom * fy;
}

// Its largest colour channel times E at cosine cos (either side): the chance of sampling it.
fn sheen_reflectance(table: u32, color: vec3f, roughness: f32, cos: f32) -> f32 {
    return max(color.x, max(color.y, color.z)) * sheen_albedo(table, abs(cos), roughness);
}

// What of the mix below shows toward wo.
fn sheen_through(table: u32, color: vec3f, roughness: f32, wo: vec3f, hit: Hit) -> f32 {
    return 1.0 - sheen_reflectance(table, color, roughness, dot(wo, hit.shading));
}

// p + (q - p) t (a kernel function named mix hides the builtin in some kernels).
fn sheen_lerp(p: f32, q: f32, t: f32) -> f32 {
    return p + (q - p) * t;
}

fn sheen_lambda(cos: f32, a: f32) -> f32 {
    let t = (1.0 - a) * (1.0 - a);
    let pa = sheen_lerp(21.5473, 25.3245, t);
    let pb = sheen_lerp(3.82987, 3.32435, t);
    let pc = sheen_lerp(0.19823, 0.16801, t);
    let pd = sheen_lerp(-1.97760, -1.27393, t);
    let pe = sheen_lerp(-4.32054, -4.85967, t);
    if cos < 0.5 {
        return exp(pa / (1.0 + pb * pow(cos, pc)) + pd * cos + pe);
    }
    let half = pa / (1.0 + pb * pow(0.5, pc)) + pd * 0.5 + pe;
    let x = max(1.0 - cos, 0.0);
    return exp(2.0 * half - (pa / (1.0 + pb * pow(x, pc)) + pd * x + pe));
}

// The sheen's BSDF x cos at (wo, wi), both above the shading normal, else 0; a is the
// roughness squared.
fn sheen_eval(color: vec3f, roughness: f32, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let a = roughness * roughness;
    let n = hit.shading;
    // Unit vectors' dot products round up to 1 + 1 ulp.
    let cos_o = min(dot(wo, n), 1.0);
    let cos_i = min(dot(wi, n), 1.0);
    if !(cos_o > MIN_COSINE && cos_i > MIN_COSINE) || below_surface(hit, wi) {
        return vec3f(0.0);
    }
    let h = normalize(wo + wi);
    let cos_h = dot(h, n);
    let sin2 = max(1.0 - cos_h * cos_h, 0.0);
    let d = (2.0 + 1.0 / a) * pow(sin2, 0.5 / a) * (0.5 / PI);
    // The visibility clamped to 1, as the sample renderer clamps it; times cos_i.
    let v = min(1.0 / ((1.0 + sheen_lambda(cos_o, a) + sheen_lambda(cos_i, a)) * 4.0 * cos_o * cos_i), 1.0) * cos_i;
    return color * (d * v);
}
//#endif
//#endif
