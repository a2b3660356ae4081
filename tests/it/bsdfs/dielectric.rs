//! Rough glass (Walter et al. 2007): chi-square of its sampling over both hemispheres, eval
//! over pdf, reciprocity, the white furnace, bad parameters.

use super::histogram::{Histogram, sample_vs_pdf_in};
use super::*;
use rt_gpu::material::{Dielectric, Lobe};

fn glass(ior: f32, roughness: f32) -> Material {
    Material::Dielectric(Dielectric::rough(ior, roughness))
}

/// Indices of refraction: water, glass, diamond.
const IORS: [f32; 3] = [1.33, 1.5, 2.4];

/// The grid: each roughness and angle, from outside into glass of ior 1.5 and from inside it
/// (beyond 41.8 degrees, total internal reflection), and at ior 1.33 and 2.4 from outside at 30
/// and 85 degrees; four more at a tilted normal.
fn grid() -> Vec<(f32, f32, f32, bool)> {
    let mut out = Vec::new();
    for roughness in ROUGHNESS {
        for angle in ANGLES {
            out.push((1.5, roughness, angle, true));
            out.push((1.5, roughness, angle, false));
        }
        for ior in [1.33, 2.4] {
            for angle in [30.0, 85.0] {
                out.push((ior, roughness, angle, true));
            }
        }
    }
    out
}

/// Chi-square p-value of rough glass at wo `angle` degrees from the normal at `h`, the sampler
/// against `pdf_of`'s density, over cells about the mirror and the refracted direction.
fn glass_chi_square(
    material: &Material,
    pdf_of: &Material,
    h: &Hit,
    wo: Vec3,
) -> (f64, usize, f64) {
    let Material::Dielectric(d) = material else {
        unreachable!("glass")
    };
    let eta = if h.front_face { 1.0 / d.ior } else { d.ior };
    let cells = Histogram::transmitting(h.normal, wo, eta);
    sample_vs_pdf_in(material, pdf_of, h, wo, &cells, CHI_SQUARE_SAMPLES)
}

/// The grid above (48 comparisons) and four at a tilted frame: 52 at family-wise significance
/// 0.01, Sidak-corrected (each at 1 - 0.99^(1/52) = 1.9e-4). 500 000 samples each, over 1 536
/// cells (both hemispheres) plus the draws that end the path, cells expected below 5 pooled.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn dielectric_sampling_follows_its_pdf() {
    let per_test = per_test_level((grid().len() + 4) as f64);
    let mut failures = Vec::new();
    let mut check = |label: String, material: &Material, h: &Hit, wo: Vec3| {
        let (chi2, cells, p) = glass_chi_square(material, material, h, wo);
        eprintln!("{label}: chi2 {chi2:.1} over {cells} cells, p = {p:.3}");
        if p < per_test {
            failures.push((label, p));
        }
    };
    for (ior, roughness, angle, front) in grid() {
        let h = common::surface_hit(Vec3::Z, front);
        let side = if front { "outside" } else { "inside" };
        let label = format!("ior {ior}, roughness {roughness}, {angle} degrees {side}");
        check(label, &glass(ior, roughness), &h, wo_at(angle));
    }
    for (roughness, angle) in [(0.3, 30.0), (0.3, 85.0), (0.7, 30.0), (0.7, 60.0)] {
        let (normal, wo) = tilted(angle);
        let h = common::surface_hit(normal, angle < 45.0);
        let label = format!("tilted, roughness {roughness}, {angle} degrees");
        check(label, &glass(1.5, roughness), &h, wo);
    }
    assert!(
        failures.is_empty(),
        "rejected at {per_test:.1e}: {failures:?}"
    );
}

/// Negative controls: the same test rejects the sampler at the grid's per-test level against a
/// pdf whose alpha is 2% too large (each roughness, 30 degrees from outside), and against one
/// whose ior is 2% too large (roughness 0.3: the refracted lobe moves, the reflected keeps its
/// place and nearly its weight).
#[test]
fn dielectric_chi_square_detects_a_two_percent_wrong_pdf() {
    let per_test = per_test_level((grid().len() + 4) as f64);
    let h = hit(Vec3::Z);
    let mut wrongs: Vec<(String, Material, Material)> = ROUGHNESS
        .iter()
        .map(|&r| {
            let wrong = glass(1.5, 1.02f32.sqrt() * r);
            (format!("roughness {r}, alpha +2%"), glass(1.5, r), wrong)
        })
        .collect();
    wrongs.push((
        "roughness 0.3, ior +2%".into(),
        glass(1.5, 0.3),
        glass(1.5 * 1.02, 0.3),
    ));
    for (label, right, wrong) in wrongs {
        let (chi2, cells, p) = glass_chi_square(&right, &wrong, &h, wo_at(30.0));
        eprintln!("{label}: chi2 {chi2:.1} over {cells} cells, p = {p:.2e}");
        assert!(p < per_test, "{label}: the wrong pdf passed, p = {p}");
    }
}

/// Random unit vectors anywhere, with their numbers from `i`.
fn anywhere(i: u32, seed: u32) -> Vec3 {
    let mut s = Sampler::independent(i, 1, seed);
    rt_gpu::shared::warp::unit_vector(s.next_f32(), s.next_f32())
}

/// `eval / pdf` at the sampled direction is the sampled weight and `pdf` there the sampled pdf,
/// for each ior and roughness at 2 000 random wo from outside and 2 000 from inside; the lobe
/// is glossy reflection or transmission, wi on its side (smooth: delta, eval and pdf 0). Both
/// lobes are drawn, and from inside, total internal reflection.
#[test]
fn dielectric_eval_over_pdf_is_the_sampled_weight() {
    for ior in IORS {
        for roughness in [0.0, 0.05, 0.3, 0.7, 1.0] {
            let m = glass(ior, roughness);
            for front in [true, false] {
                let h = common::surface_hit(Vec3::Z, front);
                let (mut reflected, mut transmitted) = (0, 0);
                for i in 0..2000 {
                    let wo = upper(i, 3);
                    let mut sampler = Sampler::independent(i, 0, 4);
                    let Some(s) = m.sample(wo, &h, &mut sampler) else {
                        continue;
                    };
                    let label = format!("ior {ior}, roughness {roughness}, front {front}, wo {wo}");
                    assert_eq!(s.lobe.is_transmission(), s.wi.z < 0.0, "{label}");
                    if s.lobe.is_transmission() {
                        transmitted += 1;
                    } else {
                        reflected += 1;
                    }
                    if roughness == 0.0 {
                        assert!(s.lobe.is_delta(), "{label}");
                        assert_eq!(s.weight, Vec3::ONE, "{label}");
                        assert_eq!(
                            (m.eval(wo, s.wi, &h), m.pdf(wo, s.wi, &h)),
                            (Vec3::ZERO, 0.0),
                            "{label}"
                        );
                        continue;
                    }
                    assert!(
                        s.lobe == Lobe::GLOSSY_REFLECTION || s.lobe == Lobe::GLOSSY_TRANSMISSION,
                        "{label}: {:?}",
                        s.lobe
                    );
                    assert_eval_over_pdf_is_weight(&m, wo, &h, &s, &label);
                }
                assert!(
                    reflected > 20 && transmitted > 100,
                    "ior {ior}, roughness {roughness}, front {front}: {reflected} reflected, {transmitted} transmitted"
                );
            }
        }
    }
}

/// Reflection: BSDF(wo, wi) = BSDF(wi, wo). Transmission, in the importance form rough glass
/// uses (dielectric.rs): BSDF(wo, wi) = (n_t / n_i)^2 BSDF(wi, wo), from outside (n_i = 1)
/// into glass (n_t = ior) and back. 10 000 random pairs per roughness and ior.
#[test]
fn dielectric_eval_is_reciprocal() {
    let outside = hit(Vec3::Z);
    // Seen from inside, the surface's normal faces the glass.
    let inside = common::surface_hit(-Vec3::Z, false);
    for ior in IORS {
        for roughness in ROUGHNESS {
            let m = glass(ior, roughness);
            for i in 0..10_000 {
                let (wo, wi) = (upper(i, 5), anywhere(i, 6));
                let forward = m.eval(wo, wi, &outside) / wi.z.abs();
                let (backward, scale) = if wi.z > 0.0 {
                    (m.eval(wi, wo, &outside) / wo.z, 1.0)
                } else {
                    (m.eval(wi, wo, &inside) / wo.z, ior * ior)
                };
                let backward = backward * scale;
                assert!(
                    // f32 recomputes the generalised half vector from each side, in the
                    // tails of a narrow lobe to within 1%: absolutely, a tiny difference.
                    (forward - backward).abs().max_element() <= 2e-3 * forward.max_element() + 1e-5,
                    "ior {ior}, roughness {roughness}: {forward} against {backward} at wo {wo}, wi {wi}"
                );
            }
        }
    }
}

/// White furnace: directional albedo (the mean sampled weight, reflection plus transmission)
/// is <= 1 for every wo; smooth glass is lossless (exactly 1: every sample has weight 1 and
/// none is lost); rough glass keeps > 99% at roughness 0.05 and loses what single scattering
/// between microfacets loses (not compensated), printed for the record.
#[test]
fn dielectric_white_furnace() {
    const N: u32 = 100_000;
    for ior in [1.5, 2.4] {
        for roughness in [0.0, 0.05, 0.3, 0.7, 1.0] {
            let m = glass(ior, roughness);
            for front in [true, false] {
                let h = common::surface_hit(Vec3::Z, front);
                let mut row = Vec::new();
                for angle in ANGLES {
                    let wo = wo_at(angle);
                    let mut sum = 0.0f64;
                    for i in 0..N {
                        let mut s = Sampler::independent(i, 0, 8);
                        if let Some(b) = m.sample(wo, &h, &mut s) {
                            sum += b.weight.x as f64;
                        }
                    }
                    let albedo = sum / N as f64;
                    let label =
                        format!("ior {ior}, roughness {roughness}, front {front}, {angle} degrees");
                    assert!(albedo <= 1.0, "{label}: albedo {albedo}");
                    if roughness == 0.0 {
                        assert_eq!(albedo, 1.0, "{label}");
                    }
                    if roughness == 0.05 {
                        assert!(albedo > 0.99, "{label}: albedo {albedo}");
                    }
                    row.push(format!("{angle} deg: {albedo:.4}"));
                }
                let side = if front { "outside" } else { "inside" };
                eprintln!(
                    "white furnace, glass ior {ior} roughness {roughness} from {side}: {}",
                    row.join(", ")
                );
            }
        }
    }
}

/// Bad roughness is a one-line error at the material's line, naming the problem.
#[test]
fn bad_rough_glass_is_a_located_error() {
    assert_located_errors(
        &[r#"{ type = "dielectric", ior = 1.5, roughness = 0.25 }"#],
        &[
            (
                r#"{ type = "dielectric", ior = 1.5, roughness = 1.5 }"#,
                "roughness must be in [0, 1], got 1.5",
            ),
            (
                r#"{ type = "dielectric", ior = 1.5, roughness = -0.1 }"#,
                "roughness must be in [0, 1]",
            ),
            (
                r#"{ type = "dielectric", ior = 0, roughness = 0.3 }"#,
                "ior must be in [0.01, 100]",
            ),
        ],
    );
}
