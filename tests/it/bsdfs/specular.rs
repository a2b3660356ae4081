//! glTF's specular strength and colour on pbr's dielectric (KHR_materials_specular,
//! `material::specular`): the reshaped Fresnel's ends and identity, chi-square of the sampling,
//! eval over pdf, the white furnace, a factor of 0 leaving a pure diffuse surface, bad values,
//! and images every way.

use super::histogram::{Histogram, sample_vs_pdf_in};
use super::*;
use rt_gpu::assets::texture::Texture;
use rt_gpu::material::Pbr;
use rt_gpu::material::coat::coat_fresnel;
use rt_gpu::material::specular::Specular;

/// A dielectric pbr of `base` and `roughness` (metallic `metallic`) with `specular`.
fn specular(base: Vec3, metallic: f32, roughness: f32, specular: Specular) -> Material {
    Material::Pbr(
        Pbr::new(Texture::Colour(base), metallic, roughness, 1.5, 0.0)
            .with_specular(Some(specular)),
    )
}

const RED: Vec3 = Vec3::new(0.7, 0.1, 0.1);

/// A weaker one, a tinted one whose F0 exceeds 1 in blue (clamped), and none.
const SPECULARS: [Specular; 3] = [
    Specular {
        factor: 0.5,
        color: Vec3::ONE,
    },
    Specular {
        factor: 0.8,
        color: Vec3::new(0.2, 1.0, 30.0),
    },
    Specular {
        factor: 0.0,
        color: Vec3::ONE,
    },
];

/// Its ends as the extension's: F0 x colour (clamped to 1) times the factor at normal
/// incidence, the factor at grazing; and exact Fresnel itself at the default factor and
/// colour (to rounding), at 1 000 cosines and indices 1.33, 1.5 and 2.4.
#[test]
fn the_reshaped_fresnel_has_the_extensions_ends_and_is_fresnel_by_default() {
    for ior in [1.33f32, 1.5, 2.4] {
        let f0 = coat_fresnel(1.0, ior);
        let tinted = Specular {
            factor: 0.7,
            color: Vec3::new(0.5, 1.0, 100.0),
        }
        .fresnel(ior);
        let at_normal = tinted.reflectance(1.0, ior);
        let expected = 0.7 * Vec3::new(0.5 * f0, f0, 1.0);
        assert!(
            (at_normal - expected).abs().max_element() < 1e-6,
            "{at_normal} against {expected}"
        );
        assert!(
            (tinted.reflectance(0.0, ior) - Vec3::splat(0.7))
                .abs()
                .max_element()
                < 1e-6
        );
        assert!(
            (tinted.opacity(0.3, ior) - tinted.reflectance(0.3, ior).max_element()).abs() < 1e-6
        );
        let plain = Specular::default().fresnel(ior);
        for i in 0..=1000 {
            let cos = i as f32 / 1000.0;
            let (fresnel, reshaped) = (coat_fresnel(cos, ior), plain.reflectance(cos, ior));
            assert!(
                (reshaped - Vec3::splat(fresnel)).abs().max_element() <= 1e-6,
                "ior {ior}, cos {cos}: {reshaped} against {fresnel}"
            );
        }
    }
}

/// The coat's mean opacity, from which its internal reflectance follows (and so a smooth coat's
/// furnace), is the cosine-weighted mean of its opacity: against a midpoint sum over 200 000
/// cosines, within 1e-5, at indices 1.33 to 100 (at large indices Fresnel dips below its head-on
/// value, where the shape is clamped, and a mean taken from Fresnel's own mean is off).
#[test]
fn the_mean_opacity_is_the_opacitys_mean() {
    for ior in [1.33f32, 1.5, 2.4, 10.0, 100.0] {
        for s in [
            SPECULARS[0],
            SPECULARS[1],
            Specular {
                factor: 1.0,
                color: Vec3::splat(0.5),
            },
        ] {
            let fresnel = s.fresnel(ior);
            const N: usize = 200_000;
            let sum: f64 = (0..N)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / N as f64;
                    fresnel.opacity(mu as f32, ior) as f64 * mu
                })
                .sum();
            let expected = 2.0 * sum / N as f64;
            let mean = fresnel.mean_opacity() as f64;
            assert!(
                (mean - expected).abs() < 1e-5,
                "ior {ior}, {s:?}: {mean} against {expected}"
            );
        }
    }
}

/// Each specular over a smooth (its coat's mirror a delta) and a rough (0.4) red dielectric and
/// a rough half metal, at 30 and 85 degrees: 18 comparisons at family-wise 0.01,
/// Sidak-corrected, 500 000 samples each.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn specular_sampling_follows_its_pdf() {
    let per_test = per_test_level(18.0);
    let h = hit(Vec3::Z);
    let mut failures = Vec::new();
    let mut cases = 0;
    for s in SPECULARS {
        for (metallic, roughness) in [(0.0, 0.0), (0.0, 0.4), (0.5, 0.4)] {
            for angle in [30.0, 85.0] {
                cases += 1;
                let m = specular(RED, metallic, roughness, s);
                let wo = wo_at(angle);
                let cells = Histogram::reflecting(Vec3::Z, wo);
                let (chi2, cells, p) = sample_vs_pdf_in(&m, &m, &h, wo, &cells, CHI_SQUARE_SAMPLES);
                eprintln!(
                    "{s:?} over metallic {metallic}, roughness {roughness}, {angle} degrees: chi2 {chi2:.1} over {cells} cells, p = {p:.3}"
                );
                if p < per_test {
                    failures.push((s, metallic, roughness, angle, p));
                }
            }
        }
    }
    assert_eq!(cases, 18);
    assert!(
        failures.is_empty(),
        "rejected at {per_test:.1e}: {failures:?}"
    );
}

/// Negative control at the grid's level: a pdf whose specular factor is 2% smaller (the chance
/// of the coat, about a half here, moves by 1.2%), over a red dielectric of roughness 0.1 under
/// a specular of factor 1 and colour 5 (F0 0.2) at 60 degrees.
#[test]
fn specular_chi_square_detects_a_two_percent_wrong_pdf() {
    let per_test = per_test_level(18.0);
    let h = hit(Vec3::Z);
    let wo = wo_at(60.0);
    let tinted = Specular {
        factor: 1.0,
        color: Vec3::splat(5.0),
    };
    let right = specular(RED, 0.0, 0.1, tinted);
    let wrong = specular(
        RED,
        0.0,
        0.1,
        Specular {
            factor: 0.98,
            ..tinted
        },
    );
    let cells = Histogram::reflecting(Vec3::Z, wo);
    let (chi2, cells, p) = sample_vs_pdf_in(&right, &wrong, &h, wo, &cells, CHI_SQUARE_SAMPLES);
    eprintln!("specular factor -2%: chi2 {chi2:.1} over {cells} cells, p = {p:.2e}");
    assert!(p < per_test, "the wrong pdf passed, p = {p}");
}

/// `eval / pdf` is the sampled weight and `pdf` the sampled pdf at 2 000 random wo per
/// specular and roughness.
#[test]
fn specular_eval_over_pdf_is_the_sampled_weight() {
    for s in SPECULARS {
        for roughness in [0.0, 0.05, 0.4, 1.0] {
            let m = specular(RED, 0.0, roughness, s);
            assert_sampled_weights_are_eval_over_pdf(&m, &format!("{s:?}, roughness {roughness}"));
        }
    }
}

/// The white furnace: over a white base, each specular's albedo is at most 1 in every channel
/// (within 5 standard errors, 200 000 samples) at every angle, and exactly 1 in its strongest
/// channel where smooth (what the coat does not reflect reaches the base and leaves it: the
/// coat's K follows its reshaped mean).
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn specular_white_furnace() {
    const N: u32 = 200_000;
    let h = hit(Vec3::Z);
    for s in SPECULARS {
        for roughness in [0.0, 0.4, 1.0] {
            let m = specular(Vec3::ONE, 0.0, roughness, s);
            let strongest = (s.fresnel(1.5).f0() * s.factor).max_position();
            let mut row = Vec::new();
            for angle in ANGLES {
                let wo = wo_at(angle);
                let channel = |c: usize| {
                    mean(N, |i| {
                        let mut sampler = Sampler::independent(i, 0, 8);
                        m.sample(wo, &h, &mut sampler)
                            .map_or(0.0, |b| b.weight[c] as f64)
                    })
                };
                for c in 0..3 {
                    let (albedo, e) = channel(c);
                    let label =
                        format!("{s:?}, roughness {roughness}, {angle} degrees, channel {c}");
                    assert!(
                        albedo <= 1.0 + 5.0 * e + 1e-5,
                        "{label}: {albedo} (s.e. {e:.1e})"
                    );
                    if roughness == 0.0 && c == strongest {
                        assert!(
                            (albedo - 1.0).abs() <= 5.0 * e + 1e-5,
                            "{label}: {albedo} (s.e. {e:.1e})"
                        );
                    }
                    if c == strongest {
                        row.push(format!("{angle} deg: {albedo:.4}"));
                    }
                }
            }
            eprintln!(
                "white furnace, {s:?}, roughness {roughness}: {}",
                row.join(", ")
            );
        }
    }
}

/// A factor of 0 leaves a pure diffuse surface, as the extension says: its BSDF is the
/// lambertian's of its base colour (to 1e-5), at 1 000 random pairs of directions, smooth and
/// rough.
#[test]
fn a_specular_factor_of_zero_is_lambertian() {
    let h = hit(Vec3::Z);
    for roughness in [0.0, 0.5] {
        let m = specular(RED, 0.0, roughness, SPECULARS[2]);
        for i in 0..1000 {
            let (wo, wi) = (upper(i, 5), upper(i, 6));
            let f = m.eval(wo, wi, &h);
            let lambert = RED * wi.z * std::f32::consts::FRAC_1_PI;
            assert!(
                (f - lambert).abs().max_element() <= 1e-5,
                "roughness {roughness}: {f} against {lambert}"
            );
        }
    }
}

/// Bad speculars are one-line errors at the material's line; `specular = {}` is the default
/// (nothing changed) and a colour above 1 is allowed, as the extension allows it.
#[test]
fn bad_speculars_are_located_errors() {
    assert_located_errors(
        &[
            r#"{ type = "pbr", base_color = [0.8, 0.1, 0.1], specular = {} }"#,
            r#"{ type = "pbr", base_color = [0.8, 0.1, 0.1], specular = { factor = 0.5, color = [1, 2, 25] } }"#,
        ],
        &[
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], specular = { factor = 1.5 } }"#,
                "specular factor must be in [0, 1], got 1.5",
            ),
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], specular = { color = [1, -1, 1] } }"#,
                "color",
            ),
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], specular = { factor = 1, shine = 2 } }"#,
                "shine",
            ),
        ],
    );
}

/// A floor, a lamp and three spheres under the extension (a black smooth base with a tinted
/// specular, as the Khronos SpecularTest draws them; a red rough one with factor 0.3; a white
/// one with factor 0, a pure diffuse) render the same estimator every way
/// (`common::renders_alike_every_way`: naive vs nee on the CPU, the GPU against the CPU, Welch
/// z + Sidak at family-wise 0.01); negative control: the lamp 2% brighter, on the GPU.
#[test]
fn speculars_render_alike_every_way() {
    let scene = |brighter: f32| {
        let sphere = |base: Vec3, roughness: f32, s: Specular, x: f32| {
            let m =
                Pbr::new(Texture::Colour(base), 0.0, roughness, 1.5, 0.0).with_specular(Some(s));
            (Material::Pbr(m), Vec3::new(x, 0.5, 0.0), 0.5)
        };
        let mirror = Specular {
            factor: 1.0,
            color: Vec3::new(10.0, 10.0, 0.0),
        };
        let weak = Specular {
            factor: 0.3,
            color: Vec3::ONE,
        };
        let spheres = vec![
            sphere(Vec3::ZERO, 0.0, mirror, -1.1),
            sphere(RED, 0.4, weak, 0.0),
            sphere(Vec3::splat(0.8), 0.2, SPECULARS[2], 1.1),
        ];
        let camera = (Vec3::new(0.0, 1.2, 3.4), Vec3::new(0.0, 0.5, 0.0), 45.0);
        on_a_lit_floor(spheres, brighter, camera, 0.1)
    };
    common::renders_alike_every_way("speculars", &scene(1.0), || scene(1.02));
}
