//! glTF's sheen over pbr (KHR_materials_sheen, `material::sheen`): its albedo table against
//! its quadrature, chi-square of its sampling over the mixes below it, eval over pdf,
//! reciprocity, the white furnace and the layering as the model states it, bad parameters.

use super::histogram::{Histogram, sample_vs_pdf_in};
use super::*;
use rt_gpu::assets::texture::Texture;
use rt_gpu::material::Pbr;
use rt_gpu::material::sheen::{self, Sheen};

/// A pbr material of `base` (metallic, transmission, roughness) under a sheen of `color` and
/// `roughness`.
fn sheened(
    base: Vec3,
    (metallic, transmission, roughness): (f32, f32, f32),
    color: Vec3,
    sheen_roughness: f32,
) -> Material {
    Material::Pbr(
        Pbr::new(
            Texture::Colour(base),
            metallic,
            roughness,
            1.5,
            transmission,
        )
        .with_sheen(Some(Sheen {
            color,
            roughness: sheen_roughness,
        })),
    )
}

const RED: Vec3 = Vec3::new(0.7, 0.1, 0.1);
const VELVET: Vec3 = Vec3::new(1.0, 0.6, 0.3);

/// (metallic, transmission, roughness) of the mixes under the sheen: a rough dielectric, a
/// rough metal, rough half glass, and a smooth dielectric.
const MIXES: [(f32, f32, f32); 4] = [
    (0.0, 0.0, 0.5),
    (1.0, 0.0, 0.4),
    (0.0, 0.5, 0.4),
    (0.0, 0.0, 0.0),
];

/// Writes `src/material/sheen_albedo.bin`, the table `sheen::albedo_table` reads (run once
/// after changing the model: `cargo test --release --test it write_sheen_table -- --ignored`).
#[test]
#[ignore = "writes the table into the source tree"]
fn write_sheen_table() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/material/sheen_albedo.bin");
    std::fs::write(path, sheen::table_bytes(&sheen::albedo_values(256, 256))).expect("writes");
}

/// The shipped table is the quadrature at 256 x 256 exactly, and halving the quadrature moves
/// no entry by more than 3e-4 (the midpoint rule's error falls fourfold per doubling: the
/// table's own is about a third of that); each E is in (0, 1).
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn sheen_table_is_its_quadrature() {
    let values = sheen::albedo_values(256, 256);
    assert_eq!(
        sheen::table_bytes(&values),
        include_bytes!("../../../src/material/sheen_albedo.bin").to_vec(),
        "run write_sheen_table"
    );
    assert!(values.iter().all(|&e| e > 0.0 && e < 1.0), "{values:?}");
    let coarser = sheen::albedo_values(128, 128);
    let worst = (values.iter().zip(&coarser))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    eprintln!("sheen table: largest change on halving the quadrature {worst:.1e}");
    assert!(worst < 3e-4, "{worst}");
}

/// Each mix under a sheen of roughness 0.3 and 0.8, at 30 and 85 degrees: 16 comparisons at
/// family-wise 0.01, Sidak-corrected, 500 000 samples each.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn sheen_sampling_follows_its_pdf() {
    let per_test = per_test_level(16.0);
    let h = hit(Vec3::Z);
    let mut failures = Vec::new();
    for mix in MIXES {
        for sheen_roughness in [0.3, 0.8] {
            for angle in [30.0, 85.0] {
                let m = sheened(RED, mix, VELVET, sheen_roughness);
                let wo = wo_at(angle);
                let cells = if mix.1 > 0.0 {
                    Histogram::transmitting(Vec3::Z, wo, 1.0 / 1.5)
                } else {
                    Histogram::reflecting(Vec3::Z, wo)
                };
                let (chi2, cells, p) = sample_vs_pdf_in(&m, &m, &h, wo, &cells, CHI_SQUARE_SAMPLES);
                eprintln!(
                    "mix {mix:?} under a sheen of roughness {sheen_roughness}, {angle} degrees: chi2 {chi2:.1} over {cells} cells, p = {p:.3}"
                );
                if p < per_test {
                    failures.push((mix, sheen_roughness, angle, p));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "rejected at {per_test:.1e}: {failures:?}"
    );
}

/// Negative control at the grid's level: a pdf whose sheen colour is 2% dimmer (the chance of
/// the sheen moves) over the smooth dielectric at 85 degrees.
#[test]
fn sheen_chi_square_detects_a_two_percent_wrong_pdf() {
    let per_test = per_test_level(16.0);
    let h = hit(Vec3::Z);
    let wo = wo_at(85.0);
    let right = sheened(RED, (0.0, 0.0, 0.0), Vec3::ONE, 0.5);
    let wrong = sheened(RED, (0.0, 0.0, 0.0), Vec3::splat(0.98), 0.5);
    let cells = Histogram::reflecting(Vec3::Z, wo);
    let (chi2, cells, p) = sample_vs_pdf_in(&right, &wrong, &h, wo, &cells, CHI_SQUARE_SAMPLES);
    eprintln!("sheen colour -2%: chi2 {chi2:.1} over {cells} cells, p = {p:.2e}");
    assert!(p < per_test, "the wrong pdf passed, p = {p}");
}

/// `eval / pdf` is the sampled weight and `pdf` the sampled pdf at 2 000 random wo per mix and
/// sheen.
#[test]
fn sheen_eval_over_pdf_is_the_sampled_weight() {
    for mix in MIXES {
        for sheen_roughness in [0.0, 0.3, 1.0] {
            let m = sheened(RED, mix, VELVET, sheen_roughness);
            assert_sampled_weights_are_eval_over_pdf(
                &m,
                &format!("mix {mix:?}, sheen {sheen_roughness}"),
            );
        }
    }
}

/// The sheen's own BSDF is reciprocal; the mix below is scaled by the view alone (as the
/// extension's simplified albedo scaling): BSDF(wo, wi) - sheen and BSDF(wi, wo) - sheen differ
/// by the ratio of what shows through at each.
#[test]
fn sheen_is_reciprocal_and_scales_the_mix_by_the_view() {
    let h = hit(Vec3::Z);
    for sheen_roughness in [0.1, 0.5, 1.0] {
        let s = Sheen {
            color: VELVET,
            roughness: sheen_roughness,
        };
        let m = sheened(RED, (0.0, 0.0, 0.5), s.color, s.roughness);
        for i in 0..10_000 {
            let (wo, wi) = (upper(i, 5), upper(i, 6));
            let (forward, backward) = (s.eval(wo, wi, &h) / wi.z, s.eval(wi, wo, &h) / wo.z);
            assert!(
                (forward - backward).abs().max_element() <= 2e-4 * forward.max_element().max(1e-6),
                "sheen {forward} against {backward} at wo {wo}, wi {wi}"
            );
            let below = (m.eval(wo, wi, &h) - s.eval(wo, wi, &h)) / wi.z / s.through(wo, &h);
            let back = (m.eval(wi, wo, &h) - s.eval(wi, wo, &h)) / wo.z / s.through(wi, &h);
            assert!(
                (below - back).abs().max_element() <= 1e-3 * below.max_element().max(1e-6),
                "the mix {below} against {back} at wo {wo}, wi {wi}"
            );
        }
    }
}

/// The white furnace: a white sheen over each white mix reflects at most what comes in (albedo
/// <= 1 within 5 standard errors, 200 000 samples), exactly 1 over the lossless smooth
/// dielectric, and the sheen's own albedo, estimated by
/// cosine sampling of its eval, is the table's E (within 5 standard errors + 2e-3 for the
/// bilinear lookup) at every angle and roughness.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn sheen_white_furnace_and_its_albedo() {
    const N: u32 = 200_000;
    let h = hit(Vec3::Z);
    for sheen_roughness in [0.0, 0.3, 0.7, 1.0] {
        let s = Sheen {
            color: Vec3::ONE,
            roughness: sheen_roughness,
        };
        for angle in ANGLES {
            let wo = wo_at(angle);
            let (e, error) = mean(N, |i| {
                let mut r = Sampler::independent(i, 0, 12);
                let d = Vec3::Z + rt_gpu::shared::warp::unit_vector(r.next_f32(), r.next_f32());
                let wi = d.normalize();
                (s.eval(wo, wi, &h).x / (wi.z * std::f32::consts::FRAC_1_PI)) as f64
            });
            let table = s.reflectance(wo.z) as f64;
            assert!(
                (e - table).abs() <= 5.0 * error + 2e-3,
                "roughness {sheen_roughness}, {angle} degrees: E {e} (s.e. {error:.1e}), table {table}"
            );
        }
        let mut row = Vec::new();
        for mix in [
            (0.0, 0.0, 0.0),
            (0.0, 0.0, 0.5),
            (1.0, 0.0, 0.4),
            (0.0, 0.5, 0.4),
        ] {
            let m = sheened(Vec3::ONE, mix, Vec3::ONE, sheen_roughness);
            for angle in ANGLES {
                let wo = wo_at(angle);
                let (albedo, error) = mean(N, |i| {
                    let mut r = Sampler::independent(i, 0, 8);
                    m.sample(wo, &h, &mut r).map_or(0.0, |b| b.weight.x as f64)
                });
                let label = format!(
                    "mix {mix:?} under a sheen of roughness {sheen_roughness}, {angle} degrees"
                );
                assert!(
                    albedo <= 1.0 + 5.0 * error,
                    "{label}: {albedo} (s.e. {error:.1e})"
                );
                if mix == (0.0, 0.0, 0.0) {
                    assert!(
                        (albedo - 1.0).abs() <= 5.0 * error + 2e-3,
                        "{label}: {albedo} (s.e. {error:.1e})"
                    );
                }
                row.push(format!("{mix:?} {angle} deg: {albedo:.4}"));
            }
        }
        eprintln!(
            "white furnace, sheen roughness {sheen_roughness}: {}",
            row.join(", ")
        );
    }
}

/// Bad sheens are one-line errors at the material's line.
#[test]
fn bad_sheens_are_located_errors() {
    assert_located_errors(
        &[
            r#"{ type = "pbr", base_color = [0.8, 0.1, 0.1], metallic = 0, sheen = {} }"#,
            r#"{ type = "pbr", base_color = [0.8, 0.1, 0.1], sheen = { color = [1, 0.5, 0.2], roughness = 0.4 } }"#,
        ],
        &[
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], sheen = { roughness = 1.5 } }"#,
                "sheen roughness must be in [0, 1], got 1.5",
            ),
            (
                r#"{ type = "pbr", base_color = [0.5, 0.5, 0.5], sheen = { color = [2, 0, 0] } }"#,
                "albedo",
            ),
        ],
    );
}

/// A scene whose only extra is a sheen (a velvet sphere on a floor under a lamp, no texture,
/// no sky: the kernel's image array is there for the sheen's table alone) renders the same
/// estimator every way (`common::renders_alike_every_way`: naive vs nee on the CPU, the GPU
/// against the CPU, Welch z + Sidak at family-wise 0.01); negative control: the lamp 2%
/// brighter, on the GPU (the sheen's colour 2% dimmer moves only its rims: not caught).
#[test]
fn a_sheen_alone_renders_alike_every_way() {
    let scene = |brighter: f32| {
        let velvet = Pbr::new(
            Texture::Colour(Vec3::new(0.3, 0.02, 0.05)),
            0.0,
            0.9,
            1.5,
            0.0,
        )
        .with_sheen(Some(Sheen {
            color: Vec3::new(1.0, 0.7, 0.6),
            roughness: 0.4,
        }));
        let camera = (Vec3::new(0.0, 1.2, 3.2), Vec3::new(0.0, 0.7, 0.0), 40.0);
        let sphere = (Material::Pbr(velvet), Vec3::new(0.0, 0.8, 0.0), 0.8);
        on_a_lit_floor(vec![sphere], brighter, camera, 0.05)
    };
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene(1.0), 8, 8).expect("valid");
    let images: usize = flat.materials.iter().map(|m| m.images().len()).sum();
    assert_eq!(images, 1, "the sheen's table alone");
    common::renders_alike_every_way("a sheen alone", &scene(1.0), || scene(1.02));
}
