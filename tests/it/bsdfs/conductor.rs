//! The conductor: chi-square of its sampling, eval over pdf, reciprocity, the white furnace,
//! its Fresnel term, bad parameters.

use super::histogram::{sample_vs_pdf, sample_vs_pdf_at};
use super::*;
use rt_gpu::material::conductor::{METALS, fresnel_conductor};
use rt_gpu::material::microfacet::Ggx;
use rt_gpu::material::{Conductor, Lobe};

pub fn gold(roughness: f32) -> Material {
    Material::Conductor(Conductor::metal("Au", roughness).expect("known metal"))
}

/// The grid's comparisons: (roughness, angle) about +z, and four more at a tilted normal with
/// wo off the plane of the frame's first axis (the local frame's both axes and signs in use).
const CHI_SQUARE_COMPARISONS: f64 = (ROUGHNESS.len() * ANGLES.len() + 4) as f64;

/// One chi-square test per (roughness, angle) and four at a tilted frame: 20 comparisons at
/// family-wise significance 0.01, Sidak-corrected (each at 1 - 0.99^(1/20) = 5.0e-4). 500 000
/// samples each, cells expected below 5 pooled. Sampling does not depend on eta and k, so one
/// metal stands for all.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn conductor_sampling_follows_its_pdf() {
    let per_test = per_test_level(CHI_SQUARE_COMPARISONS);
    let mut failures = Vec::new();
    for roughness in ROUGHNESS {
        for angle in ANGLES {
            let m = gold(roughness);
            let (chi2, cells, p) = sample_vs_pdf(&m, &m, wo_at(angle), CHI_SQUARE_SAMPLES);
            eprintln!(
                "roughness {roughness}, {angle} degrees: chi2 {chi2:.1} over {cells} cells, p = {p:.3}"
            );
            if p < per_test {
                failures.push((roughness, angle, p));
            }
        }
    }
    for (roughness, angle) in [(0.3, 30.0), (0.3, 85.0), (0.7, 30.0), (0.7, 85.0)] {
        let m = gold(roughness);
        let (normal, wo) = tilted(angle);
        let (chi2, cells, p) = sample_vs_pdf_at(&m, &m, normal, wo, CHI_SQUARE_SAMPLES);
        eprintln!(
            "tilted, roughness {roughness}, {angle} degrees: chi2 {chi2:.1} over {cells} cells, p = {p:.3}"
        );
        if p < per_test {
            failures.push((roughness, angle, p));
        }
    }
    assert!(
        failures.is_empty(),
        "rejected at {per_test:.1e}: {failures:?}"
    );
}

/// Negative control: the same test, with a pdf whose alpha is 2% too large, rejects the
/// sampler at the per-test level of the grid above, at every roughness (30 degrees).
#[test]
fn conductor_chi_square_detects_a_two_percent_wrong_pdf() {
    let per_test = per_test_level(CHI_SQUARE_COMPARISONS);
    for roughness in ROUGHNESS {
        let wrong = gold((1.02f32).sqrt() * roughness);
        let (chi2, cells, p) =
            sample_vs_pdf(&gold(roughness), &wrong, wo_at(30.0), CHI_SQUARE_SAMPLES);
        eprintln!(
            "roughness {roughness}, alpha +2%: chi2 {chi2:.1} over {cells} cells, p = {p:.2e}"
        );
        assert!(
            p < per_test,
            "a 2% wrong pdf passed at roughness {roughness}: p = {p}"
        );
    }
}

/// `eval / pdf` at the sampled direction is the sampled weight, and `pdf` there is the sampled
/// pdf, for every metal and roughness at 2 000 random wo each; the lobe is glossy reflection
/// (smooth: delta, with zero eval and pdf).
#[test]
fn conductor_eval_over_pdf_is_the_sampled_weight() {
    let h = hit(Vec3::Z);
    for (name, _, _) in METALS {
        for roughness in [0.0, 0.05, 0.3, 0.7, 1.0] {
            let m = Material::Conductor(Conductor::metal(name, roughness).expect("known"));
            let mut sampled = 0;
            for i in 0..2000 {
                let wo = upper(i, 3);
                let mut sampler = Sampler::independent(i, 0, 4);
                let Some(s) = m.sample(wo, &h, &mut sampler) else {
                    continue;
                };
                sampled += 1;
                if roughness == 0.0 {
                    assert_eq!(s.lobe, Lobe::DELTA_REFLECTION);
                    assert_eq!(
                        (m.eval(wo, s.wi, &h), m.pdf(wo, s.wi, &h)),
                        (Vec3::ZERO, 0.0)
                    );
                    continue;
                }
                assert_eq!(s.lobe, Lobe::GLOSSY_REFLECTION);
                assert_eval_over_pdf_is_weight(&m, wo, &h, &s, &format!("{name} {roughness}"));
            }
            assert!(
                sampled > 1000,
                "{name} {roughness}: {sampled} of 2000 sampled"
            );
        }
    }
}

/// BSDF(wo, wi) = BSDF(wi, wo) (eval is BSDF x cos(wi)), at 10 000 random pairs per roughness.
#[test]
fn conductor_eval_is_reciprocal() {
    for roughness in ROUGHNESS {
        assert_reflection_is_reciprocal(&gold(roughness), &format!("roughness {roughness}"));
    }
}

/// White furnace: the directional albedo of GGX with a perfect mirror's Fresnel (1), i.e. the
/// mean of G2 / G1 over visible normals, is <= 1 at every roughness and angle; it is the energy
/// single scattering keeps (not compensated: no Kulla-Conty term), printed for the record; at
/// roughness 0.05 it keeps > 99.5%, and at roughness 1 head-on it is the analytic 1 - ln 2. Each
/// measured metal's albedo (roughness 0.7) stays <= 1 too.
#[test]
fn conductor_white_furnace() {
    const N: u32 = 200_000;
    for roughness in ROUGHNESS {
        let ggx = Ggx {
            alpha: roughness * roughness,
        };
        let mut row = Vec::new();
        for angle in ANGLES {
            let wo = wo_at(angle);
            let mut sum = 0.0f64;
            for i in 0..N {
                let mut s = Sampler::independent(i, 0, 8);
                let m = ggx.sample_visible(wo, s.next_f32(), s.next_f32());
                let wi = rt_gpu::material::reflect(-wo, m);
                if wi.z > 0.0 {
                    sum += (ggx.g2(wo, wi) / ggx.g1(wo)) as f64;
                }
            }
            let albedo = sum / N as f64;
            assert!(
                albedo <= 1.0,
                "roughness {roughness}, {angle} degrees: albedo {albedo}"
            );
            if roughness == 0.05 {
                assert!(albedo > 0.995, "{angle} degrees: albedo {albedo}");
            }
            if roughness == 1.0 {
                // At alpha = 1, D = 1 / pi and Lambda = (1 / cos - 1) / 2: head-on, the
                // albedo integrates to 1 - ln 2; at 60 and 85 degrees, quadrature in f64 of the
                // height-correlated form gives 0.4507 and 0.7801 (the separable G1 G1: 0.4091
                // and 0.5645). Samples of G2 / G1 lie in [0, 1], so the mean's standard
                // deviation is below 0.5 / sqrt(N) = 1.1e-3: 4 of them.
                let exact = match angle {
                    0.0 => Some(1.0 - std::f64::consts::LN_2),
                    60.0 => Some(0.4507),
                    85.0 => Some(0.7801),
                    _ => None,
                };
                if let Some(exact) = exact {
                    assert!(
                        (albedo - exact).abs() < 4.5e-3,
                        "alpha 1, {angle} degrees: {albedo} against {exact}"
                    );
                }
            }
            row.push(format!("{angle} deg: {albedo:.4}"));
        }
        eprintln!("white furnace, roughness {roughness}: {}", row.join(", "));
    }
    let h = hit(Vec3::Z);
    for (name, _, _) in METALS {
        let m = Material::Conductor(Conductor::metal(name, 0.7).expect("known"));
        for angle in ANGLES {
            let wo = wo_at(angle);
            let mut sum = Vec3::ZERO;
            for i in 0..20_000 {
                let mut s = Sampler::independent(i, 0, 9);
                if let Some(b) = m.sample(wo, &h, &mut s) {
                    sum += b.weight;
                }
            }
            let albedo = sum / 20_000.0;
            assert!(
                albedo.max_element() <= 1.0,
                "{name}, {angle} degrees: {albedo}"
            );
        }
    }
}

/// The closed-form conductor Fresnel equals the complex-arithmetic one (pbrt-v4's FrComplex,
/// here in f64) for every metal at 1 000 incidence cosines, and is F0 head-on.
#[test]
fn conductor_fresnel_is_the_complex_one() {
    fn complex(cos_i: f64, eta: f64, k: f64) -> f64 {
        // eta_c = eta + i k; sin2_t = sin2_i / eta_c^2; cos_t = sqrt(1 - sin2_t).
        type C = (f64, f64);
        let mul = |a: C, b: C| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        let div = |a: C, b: C| {
            let d = b.0 * b.0 + b.1 * b.1;
            ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
        };
        let sqrt = |a: C| {
            let r = (a.0 * a.0 + a.1 * a.1).sqrt();
            let re = ((r + a.0) / 2.0).sqrt();
            let im = ((r - a.0) / 2.0).sqrt().copysign(a.1);
            (re, im)
        };
        let n: C = (eta, k);
        let sin2_i = 1.0 - cos_i * cos_i;
        let sin2_t = div((sin2_i, 0.0), mul(n, n));
        let cos_t = sqrt((1.0 - sin2_t.0, -sin2_t.1));
        let ci: C = (cos_i, 0.0);
        let sub = |a: C, b: C| (a.0 - b.0, a.1 - b.1);
        let add = |a: C, b: C| (a.0 + b.0, a.1 + b.1);
        let r_parl = div(sub(mul(n, ci), cos_t), add(mul(n, ci), cos_t));
        let r_perp = div(sub(ci, mul(n, cos_t)), add(ci, mul(n, cos_t)));
        let norm = |a: C| a.0 * a.0 + a.1 * a.1;
        (norm(r_parl) + norm(r_perp)) / 2.0
    }
    for (name, eta, k) in METALS {
        let (eta, k) = (Vec3::from(*eta), Vec3::from(*k));
        for i in 0..=1000 {
            let cos = i as f32 / 1000.0;
            let f = fresnel_conductor(cos, eta, k);
            for c in 0..3 {
                let exact = complex(cos as f64, eta[c] as f64, k[c] as f64);
                assert!(
                    (f[c] as f64 - exact).abs() < 1e-5,
                    "{name} channel {c} at cos {cos}: {} against {exact}",
                    f[c]
                );
            }
        }
        let f0 = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        assert!(
            (fresnel_conductor(1.0, eta, k) - f0).abs().max_element() < 1e-6,
            "{name}"
        );
    }
}

/// Bad conductor parameters are one-line errors at the material's line, naming the problem;
/// an unknown metal's lists the known ones.
#[test]
fn bad_conductors_are_located_errors() {
    assert_located_errors(
        &[r#"{ type = "conductor", metal = "Au", roughness = 0.3 }"#],
        &[
            (
                r#"{ type = "conductor", metal = "Au", roughness = 1.5 }"#,
                "roughness must be in [0, 1], got 1.5",
            ),
            (
                r#"{ type = "conductor", metal = "Au", roughness = -0.1 }"#,
                "roughness must be in [0, 1]",
            ),
            (
                r#"{ type = "conductor", metal = "Xx" }"#,
                "unknown metal \"Xx\": known metals are Ag, Al, Au, Cr, Cu, Fe, Ni, Ti",
            ),
            (
                r#"{ type = "conductor", eta = [0, 1, 1], k = [3, 3, 3] }"#,
                "eta must be at least",
            ),
            (
                r#"{ type = "conductor", eta = [1, 1, 1], k = [3, -1, 3] }"#,
                "no negative component",
            ),
            (
                r#"{ type = "conductor", metal = "Au", eta = [1, 1, 1], k = [1, 1, 1] }"#,
                "not both",
            ),
            (
                r#"{ type = "conductor", eta = [1, 1, 1] }"#,
                "both eta and k",
            ),
            (
                r#"{ type = "conductor", metal = "Au", fuzz = 0.1 }"#,
                "unknown field `fuzz`",
            ),
            (
                r#"{ type = "conductor", eta = [1, 2, 2], k = [0, 3, 3] }"#,
                "eta 1 with k 0",
            ),
        ],
    );
}
