//! Homogeneous media (twin: `shaders/medium.wgsl`): free paths sampled exactly from the
//! exponential distribution (no ray marching), the Henyey-Greenstein phase function, and
//! transmittance. Extinction is one number for all channels, so a sampled free path needs no
//! spectral weighting: scattering multiplies the throughput by the albedo and nothing else.

use crate::shared::warp::basis;
use glam::Vec3;
use std::f32::consts::PI;

/// A distance to the next interaction in a medium of extinction `density`, exponentially
/// distributed (pdf density x exp(-density s)), from a uniform `u` in [0, 1).
#[inline]
pub fn free_flight(density: f32, u: f32) -> f32 {
    -(1.0 - u).ln() / density
}

/// The fraction of light crossing `distance` of a medium of extinction `density`.
#[inline]
pub fn transmittance(density: f32, distance: f32) -> f32 {
    (-density * distance).exp()
}

/// Henyey-Greenstein phase function of asymmetry `g` for the cosine between the direction of
/// travel before and after scattering; normalised over the sphere, so it is also the
/// solid-angle pdf of [`sample_hg`].
#[inline]
pub fn hg_pdf(g: f32, cos: f32) -> f32 {
    let d = (1.0 + g * g - 2.0 * g * cos).max(1e-12);
    (1.0 - g * g) / (4.0 * PI * d * d.sqrt())
}

/// The cosine of a Henyey-Greenstein scattering angle from a uniform `u`: the inverse of its
/// cumulative distribution; for g near 0 (where that divides by g) isotropic, 2u - 1, which
/// the exact inverse approaches as g -> 0.
#[inline]
pub fn hg_cosine(g: f32, u: f32) -> f32 {
    if g.abs() < 1e-3 {
        return 2.0 * u - 1.0;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// A direction scattered from unit `dir` (the direction of travel) by the Henyey-Greenstein
/// phase function. Its weight (phase / pdf) is exactly 1.
#[inline]
pub fn sample_hg(g: f32, dir: Vec3, u1: f32, u2: f32) -> Vec3 {
    let cos_theta = hg_cosine(g, u1);
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (sin_phi, cos_phi) = crate::shared::angles::sin_cos_pi(2.0 * u2 - 1.0);
    let (t, b) = basis(dir);
    (cos_theta * dir + sin_theta * (cos_phi * t + sin_phi * b)).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hg_cosine_inverts_the_cdf() {
        // The HG cdf of cos: (1 - g^2) / (2g) (1 / sqrt(1 + g^2 - 2g cos) - 1 / (1 + g)).
        for g in [-0.9f32, -0.3, 0.2, 0.8] {
            for u in [0.05f32, 0.3, 0.5, 0.9] {
                let c = hg_cosine(g, u) as f64;
                let g = g as f64;
                let cdf = (1.0 - g * g) / (2.0 * g)
                    * (1.0 / (1.0 + g * g - 2.0 * g * c).sqrt() - 1.0 / (1.0 + g));
                assert!((cdf - u as f64).abs() < 1e-4, "g {g} u {u}: cdf {cdf}");
            }
        }
        assert_eq!(hg_cosine(0.0, 0.0), -1.0);
        assert_eq!(hg_cosine(0.5, 0.0), -1.0);
        assert!((hg_cosine(0.5, 1.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn free_flights_are_finite_and_ordered() {
        assert_eq!(free_flight(2.0, 0.0), 0.0);
        let last_below_one = f32::from_bits(1.0f32.to_bits() - 1);
        let far = free_flight(1e-8, last_below_one);
        assert!(far.is_finite() && far > 1e9, "{far}");
        assert!(free_flight(1.0, 0.5) < free_flight(1.0, 0.6));
    }
}
