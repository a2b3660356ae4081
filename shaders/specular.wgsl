// glTF's specular strength and colour (KHR_materials_specular) on pbr's dielectric coat and glass (twin:
// src/material/specular.rs, whose comment gives the model): Fresnel reshaped to
// factor x (f0 + (1 - f0) w), w exact Fresnel's own shape from 0 at normal incidence to 1 at
// grazing. spec: (factor, f0's rgb); a factor below 0 is none (Fresnel's own).

// No reshaping: what plastic's coat, plain glass and a pbr without the extension pass.
const NO_SPECULAR: vec4f = vec4f(-1.0, 0.0, 0.0, 0.0);

//#if PLASTIC || PBR
//#if SPECULAR
// Exact Fresnel's shape between its ends, from f (coat_fresnel at some cosine) and f_normal
// (at normal incidence).
fn specular_shape(f: f32, f_normal: f32) -> f32 {
    return clamp((f - f_normal) / (1.0 - f_normal), 0.0, 1.0);
}

// What the coat of index ior reflects at cosine cos: factor x Fr(cos), a colour.
fn specular_reflectance(spec: vec4f, cos: f32, ior: f32) -> vec3f {
    let w = specular_shape(coat_fresnel(cos, ior), coat_fresnel(1.0, ior));
    return spec.x * (spec.yzw + (vec3f(1.0) - spec.yzw) * w);
}

// The share of light met at cosine cos that does not cross the coat: factor x max(Fr(cos)).
fn specular_opacity(spec: vec4f, cos: f32, ior: f32) -> f32 {
    let w = specular_shape(coat_fresnel(cos, ior), coat_fresnel(1.0, ior));
    let f0 = max(max(spec.y, spec.z), spec.w);
    return spec.x * (f0 + (1.0 - f0) * w);
}
//#endif
//#endif
