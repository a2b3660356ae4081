//! glTF's clear coat over pbr (KHR_materials_clearcoat, `material::clearcoat`): chi-square of
//! its sampling over the mixes below it, eval over pdf, the view's scaling, the white furnace
//! and the layering as the model states it, bad parameters.

use super::histogram::{Histogram, sample_vs_pdf_between, sample_vs_pdf_in};
use super::*;
use rt_gpu::assets::texture::Texture;
use rt_gpu::material::Pbr;
use rt_gpu::material::clearcoat::{Clearcoat, CoatDirection};

/// A pbr material of `base` (metallic, transmission, roughness) under a coat of `factor` and
/// `coat_roughness`.
fn coated(
    base: Vec3,
    (metallic, transmission, roughness): (f32, f32, f32),
    factor: f32,
    coat_roughness: f32,
) -> Material {
    Material::Pbr(
        Pbr::new(
            Texture::Colour(base),
            metallic,
            roughness,
            1.5,
            transmission,
        )
        .with_clearcoat(Some(Clearcoat {
            factor,
            roughness: coat_roughness,
        })),
    )
}

const RED: Vec3 = Vec3::new(0.7, 0.1, 0.1);

/// (metallic, transmission, roughness) of the mixes under the coat: a rough dielectric, a rough
/// metal, rough half glass, and a smooth dielectric (its own coat a delta).
const MIXES: [(f32, f32, f32); 4] = [
    (0.0, 0.0, 0.4),
    (1.0, 0.0, 0.4),
    (0.0, 0.5, 0.4),
    (0.0, 0.0, 0.0),
];

fn cells_for(transmission: f32, wo: Vec3) -> Histogram {
    if transmission > 0.0 {
        Histogram::transmitting(Vec3::Z, wo, 1.0 / 1.5)
    } else {
        Histogram::reflecting(Vec3::Z, wo)
    }
}

/// Each mix under a coat of factor 1 and roughness 0 (its mirror a delta), 0.05 and 0.3, at 30
/// and 85 degrees, and under a coat of factor 0.5 and roughness 0.3 at 60 degrees: 28
/// comparisons at family-wise 0.01, Sidak-corrected (each at 3.6e-4), 500 000 samples each.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn clearcoat_sampling_follows_its_pdf() {
    let per_test = per_test_level(28.0);
    let h = hit(Vec3::Z);
    let mut cases = Vec::new();
    for mix in MIXES {
        for coat_roughness in [0.0, 0.05, 0.3] {
            for angle in [30.0, 85.0] {
                cases.push((mix, 1.0, coat_roughness, angle));
            }
        }
        cases.push((mix, 0.5, 0.3, 60.0));
    }
    assert_eq!(cases.len(), 28);
    let mut failures = Vec::new();
    for (mix, factor, coat_roughness, angle) in cases {
        let m = coated(RED, mix, factor, coat_roughness);
        let wo = wo_at(angle);
        let cells = cells_for(mix.1, wo);
        let (chi2, cells, p) = sample_vs_pdf_in(&m, &m, &h, wo, &cells, CHI_SQUARE_SAMPLES);
        eprintln!(
            "mix {mix:?} under a coat of {factor}, roughness {coat_roughness}, {angle} degrees: chi2 {chi2:.1} over {cells} cells, p = {p:.3}"
        );
        if p < per_test {
            failures.push((mix, factor, coat_roughness, angle, p));
        }
    }
    assert!(
        failures.is_empty(),
        "rejected at {per_test:.1e}: {failures:?}"
    );
}

/// Negative controls at the grid's level, over the smooth dielectric at 85 degrees (where the
/// coat is sampled 42% of the time): a pdf whose coat has alpha 2% too large, and one whose
/// factor is 2% too small (the chance of the coat and the base's share move).
#[test]
fn clearcoat_chi_square_detects_a_two_percent_wrong_pdf() {
    let per_test = per_test_level(28.0);
    let h = hit(Vec3::Z);
    let smooth = (0.0, 0.0, 0.0);
    for (label, angle, right, wrong) in [
        (
            "coat alpha +2%",
            85.0,
            coated(RED, smooth, 1.0, 0.3),
            coated(RED, smooth, 1.0, 0.3 * 1.02f32.sqrt()),
        ),
        (
            "coat factor -2%",
            85.0,
            coated(RED, smooth, 1.0, 0.3),
            coated(RED, smooth, 0.98, 0.3),
        ),
    ] {
        let wo = wo_at(angle);
        let cells = Histogram::reflecting(Vec3::Z, wo);
        let (chi2, cells, p) = sample_vs_pdf_in(&right, &wrong, &h, wo, &cells, CHI_SQUARE_SAMPLES);
        eprintln!("{label}: chi2 {chi2:.1} over {cells} cells, p = {p:.2e}");
        assert!(p < per_test, "{label}: the wrong pdf passed, p = {p}");
    }
}

/// `eval / pdf` is the sampled weight and `pdf` the sampled pdf at 2 000 random wo per mix and
/// coat.
#[test]
fn clearcoat_eval_over_pdf_is_the_sampled_weight() {
    for mix in MIXES {
        for (factor, coat_roughness) in [(1.0, 0.0), (1.0, 0.05), (0.6, 0.3), (1.0, 1.0)] {
            let m = coated(RED, mix, factor, coat_roughness);
            let label = format!("mix {mix:?}, coat {factor} {coat_roughness}");
            assert_sampled_weights_are_eval_over_pdf(&m, &label);
        }
    }
}

/// Not reciprocal, as the extension's model is not (the view's Fresnel alone scales the mix
/// below): BSDF(wo, wi) and BSDF(wi, wo) differ by the ratio of what the coat lets through at
/// each, exactly, where the coat is a mirror.
#[test]
fn clearcoat_scales_the_mix_by_the_view_alone() {
    let h = hit(Vec3::Z);
    let c = Clearcoat {
        factor: 0.8,
        roughness: 0.0,
    };
    let m = coated(RED, (0.0, 0.0, 0.4), c.factor, c.roughness);
    for i in 0..10_000 {
        let (wo, wi) = (upper(i, 5), upper(i, 6));
        let forward = m.eval(wo, wi, &h) / wi.z / c.through(wo, &h);
        let backward = m.eval(wi, wo, &h) / wo.z / c.through(wi, &h);
        assert!(
            (forward - backward).abs().max_element() <= 2e-4 * forward.max_element().max(1e-6),
            "{forward} against {backward} at wo {wo}, wi {wi}"
        );
    }
}

/// The white furnace: a white coat (factor 1) over each white mix reflects at most what comes
/// in (its albedo <= 1 within 5 standard errors, 200 000 samples) at every angle, exactly 1 for
/// a smooth coat over the lossless smooth dielectric, and exactly what the model states: the
/// coat's own albedo plus what the mix below reflects, seen through it, `E_coat(wo) + (1 -
/// F(cos_o)) E_mix(wo)`, the right side estimated independently from the coat's and the
/// uncoated mix's own samples (within 5 combined standard errors).
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn clearcoat_white_furnace_is_the_stated_layering() {
    const N: u32 = 200_000;
    let h = hit(Vec3::Z);
    for mix in [
        (0.0, 0.0, 0.0),
        (0.0, 0.0, 0.4),
        (1.0, 0.0, 0.4),
        (0.0, 0.5, 0.4),
        (0.0, 0.0, 1.0),
    ] {
        for coat_roughness in [0.0, 0.3, 1.0] {
            let clearcoat = Clearcoat {
                factor: 1.0,
                roughness: coat_roughness,
            };
            let m = coated(Vec3::ONE, mix, 1.0, coat_roughness);
            let (metallic, transmission, roughness) = mix;
            let bare = Material::Pbr(Pbr::new(
                Texture::Colour(Vec3::ONE),
                metallic,
                roughness,
                1.5,
                transmission,
            ));
            let mut row = Vec::new();
            for angle in ANGLES {
                let wo = wo_at(angle);
                let weight = |material: &Material, i: u32, seed: u32| {
                    let mut s = Sampler::independent(i, 0, seed);
                    material.sample(wo, &h, &mut s)
                };
                let (albedo, e1) = mean(N, |i| weight(&m, i, 8).map_or(0.0, |b| b.weight.x as f64));
                let r_o = clearcoat.reflectance(wo.z) as f64;
                // The coat's own albedo: its mirror's reflectance, or its rough lobe's f / pdf.
                let (coat, e2) = mean(N, |i| {
                    let mut s = Sampler::independent(i, 0, 9);
                    match clearcoat.sample(wo, &h, s.next_f32(), s.next_f32()) {
                        Some(CoatDirection::Mirror(_)) => r_o,
                        Some(CoatDirection::Rough(wi)) => {
                            let (f, pdf) = clearcoat.lobe(wo, wi, &h);
                            if pdf > 0.0 { (f / pdf) as f64 } else { 0.0 }
                        }
                        None => 0.0,
                    }
                });
                let (below, e3) = mean(N, |i| {
                    weight(&bare, i, 10).map_or(0.0, |b| b.weight.x as f64)
                });
                let stated = coat + (1.0 - r_o) * below;
                let error = (e1 * e1 + e2 * e2 + (1.0 - r_o).powi(2) * e3 * e3).sqrt();
                let label = format!(
                    "mix {mix:?} under a coat of roughness {coat_roughness}, {angle} degrees"
                );
                assert!(
                    albedo <= 1.0 + 5.0 * e1,
                    "{label}: {albedo} (s.e. {e1:.1e})"
                );
                if coat_roughness == 0.0 && mix == (0.0, 0.0, 0.0) {
                    assert!(
                        (albedo - 1.0).abs() <= 5.0 * e1 + 1e-6,
                        "{label}: {albedo} (s.e. {e1:.1e})"
                    );
                }
                assert!(
                    (albedo - stated).abs() <= 5.0 * error + 1e-6,
                    "{label}: albedo {albedo}, the model's {stated} (s.e. {error:.1e})"
                );
                row.push(format!("{angle} deg: {albedo:.4} (bare {below:.4})"));
            }
            eprintln!(
                "white furnace, coat roughness {coat_roughness} over pbr {mix:?}: {}",
                row.join(", ")
            );
        }
    }
}

/// Bad clear coats are one-line errors at the material's line; `clearcoat = {}` is a smooth
/// coat of factor 1.
#[test]
fn bad_clearcoats_are_located_errors() {
    assert_located_errors(
        &[
            r#"{ type = "pbr", base_color = [0.8, 0.1, 0.1], metallic = 0, clearcoat = {} }"#,
            r#"{ type = "pbr", base_color = [0.8, 0.1, 0.1], clearcoat = { factor = 0.5, roughness = 0.2 } }"#,
        ],
        &[
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], clearcoat = { factor = 1.5 } }"#,
                "clearcoat factor must be in [0, 1], got 1.5",
            ),
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], clearcoat = { roughness = -0.1 } }"#,
                "clearcoat roughness must be in [0, 1]",
            ),
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], clearcoat = { factor = 1, shine = 2 } }"#,
                "shine",
            ),
        ],
    );
}

/// A front-face hit on the plane z = 0 whose coat's normal (`Hit::coat`, a clear coat normal
/// map's) leans 20 degrees toward +x, the base's staying +z.
fn tilted_coat_hit() -> Hit {
    let t = 20f32.to_radians();
    Hit {
        coat: Vec3::new(t.sin(), 0.0, t.cos()),
        ..hit(Vec3::Z)
    }
}

/// With a coat normal of its own, the coat and the mix below still sample their stated pdf:
/// a rough (0.3) and a near-smooth (0.05) coat over the rough dielectric, at 30 and 50 degrees
/// from +z away from the lean and 30 and 70 toward it: 8 comparisons at family-wise 0.01, Sidak-corrected,
/// 500 000 samples each. `eval / pdf` is the sampled weight at 2 000 random wo per coat (the
/// smooth coat's mirror about the leaning normal included). Negative control: the pdf of the
/// coat's normal left upright (the base's) is rejected.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn a_coat_with_its_own_normal_samples_its_pdf() {
    let per_test = per_test_level(8.0);
    let h = tilted_coat_hit();
    let mut failures = Vec::new();
    for coat_roughness in [0.3, 0.05] {
        let m = coated(RED, MIXES[0], 1.0, coat_roughness);
        for angle in [-50.0, -30.0, 30.0, 70.0] {
            let wo = wo_at(angle);
            let cells = Histogram::reflecting(Vec3::Z, wo);
            let (chi2, cells, p) = sample_vs_pdf_in(&m, &m, &h, wo, &cells, CHI_SQUARE_SAMPLES);
            eprintln!(
                "coat {coat_roughness} leaning 20 degrees, wo at {angle}: chi2 {chi2:.1} over {cells} cells, p = {p:.3}"
            );
            if p < per_test {
                failures.push((coat_roughness, angle, p));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "rejected at {per_test:.1e}: {failures:?}"
    );
    for coat_roughness in [0.0, 0.05, 0.3] {
        let m = coated(RED, MIXES[0], 1.0, coat_roughness);
        let mut sampled = 0;
        for i in 0..2000 {
            let wo = upper(i, 3);
            let Some(s) = m.sample(wo, &h, &mut Sampler::independent(i, 0, 4)) else {
                continue;
            };
            sampled += 1;
            assert!(s.weight.is_finite() && s.pdf.is_finite(), "{s:?}");
            if !s.lobe.is_delta() {
                let label = format!("coat {coat_roughness} leaning, wo {wo}");
                assert_eval_over_pdf_is_weight(&m, wo, &h, &s, &label);
            }
        }
        assert!(sampled > 1000, "{sampled} sampled");
    }
    // The control: sampled with the leaning coat, weighed as if it stood upright.
    let m = coated(RED, MIXES[0], 1.0, 0.3);
    let wo = wo_at(30.0);
    let cells = Histogram::reflecting(Vec3::Z, wo);
    let upright = hit(Vec3::Z);
    let (_, _, p) = sample_vs_pdf_between(&m, &h, (&m, &upright), wo, &cells, CHI_SQUARE_SAMPLES);
    assert!(p < per_test, "the upright coat's pdf passed, p = {p}");
}
