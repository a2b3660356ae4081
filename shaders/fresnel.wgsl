// The Fresnel reflectance of a boundary between two dielectrics (twin:
// src/material/fresnel.rs), shared by glass and plastic's coat.

//#if DIELECTRIC || PLASTIC || PBR
// Exact unpolarised Fresnel reflectance; eta = n_incident / n_transmitted.
fn fresnel(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}
//#endif
