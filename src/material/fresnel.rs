//! The Fresnel reflectance of a boundary between two dielectrics (twin:
//! `shaders/fresnel.wgsl`), shared by glass and plastic's coat.

/// The indices of refraction a dielectric boundary takes: beyond them the coat's and the rough
/// glass's terms lose f32 (a rough plastic of index 1e-30, a pbr coat of index 1000, sampled
/// NaN); glasses lie near 1.5, diamond 2.42, and a relative index below 1 (a bubble) near 0.75.
pub const MIN_IOR: f32 = 1e-2;
pub const MAX_IOR: f32 = 100.0;

/// Refuses an index of refraction outside [`MIN_IOR`, `MAX_IOR`].
pub fn check_ior(ior: f32) -> Result<(), String> {
    if (MIN_IOR..=MAX_IOR).contains(&ior) {
        Ok(())
    } else {
        Err(format!("ior must be in [{MIN_IOR}, {MAX_IOR}], got {ior}"))
    }
}

/// Cosine of the refracted angle for incidence cosine `cos_i` and relative index
/// `eta = n_incident / n_transmitted`, or `None` under total internal reflection.
#[inline]
pub fn refract_cos(cos_i: f32, eta: f32) -> Option<f32> {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    (sin2_t < 1.0).then(|| (1.0 - sin2_t).sqrt())
}

/// Exact unpolarised Fresnel reflectance: the mean of the s and p reflectances.
#[inline]
pub fn fresnel(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}
