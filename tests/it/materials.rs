//! Scattering: Fresnel, total internal reflection, mirrors, and a chi-square test that lambertian
//! scattering is cosine-distributed.

use glam::Vec3;
use rt_gpu::material::fresnel::{fresnel, refract_cos};
use rt_gpu::material::reflect;
use rt_gpu::scene::Material;
use rt_gpu::shared::sampler::Sampler;

use crate::common;
use crate::common::chi_square::{self, Domain, Draw, Rings};

use common::surface_hit as hit_with_normal;

#[test]
fn fresnel_at_normal_incidence_is_four_percent_for_glass() {
    let eta = 1.0 / 1.5;
    let cos_t = refract_cos(1.0, eta).expect("refracts");
    assert!((fresnel(1.0, cos_t, eta) - 0.04).abs() < 1e-6);
    // Same from inside the glass.
    let cos_t = refract_cos(1.0, 1.5).expect("refracts");
    assert!((fresnel(1.0, cos_t, 1.5) - 0.04).abs() < 1e-6);
    // Grazing incidence reflects everything.
    let cos_t = refract_cos(1e-4, eta).expect("refracts");
    assert!(fresnel(1e-4, cos_t, eta) > 0.999);
}

#[test]
fn total_internal_reflection_beyond_the_critical_angle() {
    // From glass (1.5) to air, the critical angle is asin(1/1.5) = 41.81 degrees.
    let critical = (1.0f32 / 1.5).asin();
    assert!(refract_cos((critical - 0.01).cos(), 1.5).is_some());
    assert!(refract_cos((critical + 0.01).cos(), 1.5).is_none());
    // A dielectric then always reflects, whatever the random number.
    let n = Vec3::Y; // the normal faces the incoming ray, inside the glass
    let angle = critical + 0.2;
    let dir_in = Vec3::new(angle.sin(), -angle.cos(), 0.0);
    for seed in 0..64 {
        let mut rng = Sampler::independent(0, 0, seed);
        let s = (Material::Dielectric(rt_gpu::material::Dielectric::clear(1.5)))
            .sample(-dir_in, &hit_with_normal(n, false), &mut rng)
            .expect("scatters");
        assert_eq!(s.weight, Vec3::ONE);
        assert!((s.wi - reflect(dir_in, n)).length() < 1e-6);
    }
}

#[test]
fn smooth_metal_is_a_mirror_and_fuzz_below_the_surface_is_absorbed() {
    let n = Vec3::Y;
    let dir_in = Vec3::new(1.0, -1.0, 0.0).normalize();
    let mirror = Material::Metal(rt_gpu::material::Metal {
        albedo: Vec3::new(0.8, 0.6, 0.2).into(),
        fuzz: 0.0,
    });
    let mut rng = Sampler::independent(1, 2, 3);
    let s = mirror
        .sample(-dir_in, &hit_with_normal(n, true), &mut rng)
        .expect("reflects");
    assert_eq!(s.weight, Vec3::new(0.8, 0.6, 0.2));
    assert!((s.wi - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);

    // At grazing incidence with full fuzz, some rays end below the surface: those are absorbed,
    // the rest leave above it.
    let grazing = Vec3::new(1.0, -0.01, 0.0).normalize();
    let fuzzy = Material::Metal(rt_gpu::material::Metal {
        albedo: Vec3::ONE.into(),
        fuzz: 1.0,
    });
    let mut absorbed = 0;
    for i in 0..1000 {
        let mut rng = Sampler::independent(i, 0, 9);
        match fuzzy.sample(-grazing, &hit_with_normal(n, true), &mut rng) {
            Some(s) => assert!(s.wi.dot(n) > 0.0),
            None => absorbed += 1,
        }
    }
    assert!(absorbed > 100 && absorbed < 900, "{absorbed}");
}

/// Chi-square p-value (`common::chi_square`) of directions about `normal` over rings of
/// cos^2 theta by sectors of phi: for a cosine-weighted distribution cos^2 theta is uniform, so
/// every cell expects the same count.
fn chi_square_p_value(normal: Vec3, sample: impl Fn(u32) -> Vec3) -> f64 {
    const N: u32 = 200_000;
    let rings = Rings::new(normal, 0.0, 2, 10, 20);
    let expected = rings.expected(&|d| (d.dot(normal).max(0.0) / std::f32::consts::PI) as f64);
    let tally = chi_square::tally(&rings, N, |i| {
        let d = sample(i);
        assert!(d.dot(normal) >= 0.0, "direction below the surface");
        Draw::Direction(d)
    });
    let (chi2, cells, p) = chi_square::test(&tally, &expected, N);
    eprintln!("chi2 {chi2:.1} over {cells} cells, p = {p:.3e}");
    p
}

/// One chi-square test at significance 0.01 (a single comparison, so no correction); expected
/// count per cell 1000, far above the usual minimum of 5. Negative control: uniform-hemisphere
/// directions, which must be rejected.
#[test]
fn lambertian_scattering_is_cosine_distributed() {
    let normal = Vec3::new(0.3, 0.8, -0.52).normalize();
    let lambertian = Material::lambertian(Vec3::ONE);
    let hit = hit_with_normal(normal, true);
    let p = chi_square_p_value(normal, |i| {
        let mut rng = Sampler::independent(i, 0, 42);
        lambertian
            .sample(normal, &hit, &mut rng)
            .expect("scatters")
            .wi
    });
    assert!(p > 0.01, "cosine sampling rejected: p = {p}");

    let p_uniform = chi_square_p_value(normal, |i| {
        let mut rng = Sampler::independent(i, 0, 42);
        let d = rt_gpu::shared::warp::unit_vector(rng.next_f32(), rng.next_f32());
        if d.dot(normal) < 0.0 { -d } else { d }
    });
    assert!(p_uniform < 1e-6, "negative control passed: p = {p_uniform}");
}
