//! Microfacet BSDFs (conductors, rough glass, plastic, glTF's pbr and its clear coat, sheen and specular): `sample` draws directions with exactly the
//! density `pdf` reports (chi-square over a grid of roughness, indices and incident angles, with
//! negative controls), `eval / pdf` is the sampled weight, `eval` is reciprocal, directional
//! albedo stays <= 1 (the white furnace), the conductor's Fresnel term is the complex one, bad
//! parameters are located errors, and images agree between integrators and backends. The
//! kernel's `sample`, `eval` and `pdf` equal the CPU's at 20 000 random queries. The slowest
//! tests use the CPU alone and run in the default build only: CI runs both builds, and the
//! same arithmetic twice would add a minute.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

mod clearcoat;
mod conductor;
mod dielectric;
mod histogram;
mod images;
mod microsurface;
mod pbr;
mod plastic;
mod sheen;
mod specular;

use glam::Vec3;
use rt_gpu::material::BsdfSample;
use rt_gpu::scene::Material;
use rt_gpu::shared::ray::Hit;
use rt_gpu::shared::sampler::Sampler;

const ROUGHNESS: [f32; 4] = [0.05, 0.3, 0.7, 1.0];
/// Incident angles from the normal, degrees: head-on to grazing.
const ANGLES: [f32; 4] = [0.0, 30.0, 60.0, 85.0];

/// A front-face hit on a surface with this normal.
fn hit(normal: Vec3) -> Hit {
    common::surface_hit(normal, true)
}

/// wo at `degrees` from +z, in the xz plane.
fn wo_at(degrees: f32) -> Vec3 {
    let theta = degrees.to_radians();
    Vec3::new(theta.sin(), 0.0, theta.cos())
}

const CHI_SQUARE_SAMPLES: u32 = 500_000;

/// The per-test level of `comparisons` chi-square tests at family-wise significance 0.01,
/// Sidak-corrected.
fn per_test_level(comparisons: f64) -> f64 {
    1.0 - (1.0 - 0.01f64).powf(1.0 / comparisons)
}

/// The |z| beyond which one of `comparisons` two-sided z tests fails, at family-wise 0.01,
/// Sidak-corrected.
fn z_threshold(comparisons: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::standard().inverse_cdf(1.0 - per_test_level(comparisons) / 2.0)
}

/// A normal and a wo at `degrees` from it, at azimuth 40 degrees in its frame.
fn tilted(degrees: f32) -> (Vec3, Vec3) {
    let normal = Vec3::new(0.3, 0.8, -0.52).normalize();
    let (s, t) = rt_gpu::shared::warp::basis(normal);
    let (theta, phi) = (degrees.to_radians(), 40f32.to_radians());
    let wo = (s * phi.cos() + t * phi.sin()) * theta.sin() + normal * theta.cos();
    (normal, wo.normalize())
}

/// At 2 000 random wo over a front face with normal +z, `m`'s samples are finite and, where
/// not a delta, weigh `eval / pdf` at the sampled pdf (`assert_eval_over_pdf_is_weight`); more
/// than 1 000 of them exist. `label` names the case.
fn assert_sampled_weights_are_eval_over_pdf(m: &Material, label: &str) {
    let h = hit(Vec3::Z);
    let mut sampled = 0;
    for i in 0..2000 {
        let wo = upper(i, 3);
        let mut sampler = Sampler::independent(i, 0, 4);
        let Some(s) = m.sample(wo, &h, &mut sampler) else {
            continue;
        };
        sampled += 1;
        assert!(s.weight.is_finite() && s.pdf.is_finite(), "{label}: {s:?}");
        if !s.lobe.is_delta() {
            assert_eval_over_pdf_is_weight(m, wo, &h, &s, &format!("{label}, wo {wo}"));
        }
    }
    assert!(sampled > 1000, "{label}: {sampled} sampled");
}

/// `pdf` at a sampled direction is the sampled pdf (within 1%: D changes by up to 2 / alpha
/// per radian of the half vector, which f32 recomputes from wo and wi, so at roughness 0.05
/// near grazing 1e-3 is within rounding) and `eval / pdf` there the sampled weight.
fn assert_eval_over_pdf_is_weight(m: &Material, wo: Vec3, h: &Hit, s: &BsdfSample, label: &str) {
    let (f, pdf) = (m.eval(wo, s.wi, h), m.pdf(wo, s.wi, h));
    assert!(
        (pdf - s.pdf).abs() <= 1e-2 * s.pdf,
        "{label}: pdf {pdf} against sampled {}",
        s.pdf
    );
    let expected = f / pdf;
    assert!(
        (expected - s.weight).abs().max_element() <= 1e-3 * s.weight.max_element().max(1e-3),
        "{label}: eval/pdf {expected} against weight {}",
        s.weight
    );
}

/// BSDF(wo, wi) = BSDF(wi, wo) (eval is BSDF x cos(wi)) at 10 000 random pairs above the
/// surface.
fn assert_reflection_is_reciprocal(m: &Material, label: &str) {
    let h = hit(Vec3::Z);
    for i in 0..10_000 {
        let (wo, wi) = (upper(i, 5), upper(i, 6));
        let forward = m.eval(wo, wi, &h) / wi.z;
        let backward = m.eval(wi, wo, &h) / wo.z;
        assert!(
            (forward - backward).abs().max_element() <= 2e-4 * forward.max_element().max(1e-6),
            "{label}: {forward} against {backward} at wo {wo}, wi {wi}"
        );
    }
}

/// Each (material, words) is a one-line error at the material's line of a scene file, naming
/// the problem; `good` parses.
fn assert_located_errors(good: &[&str], bad: &[(&str, &str)]) {
    let file = |material: &str| {
        format!(
            "[camera]\nlook_from = [0, 0, 1]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nm = {material}\n\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 0.5 }}\nmaterial = \"m\"\n"
        )
    };
    for material in good {
        rt_gpu::scene::file::parse(&file(material), "good.toml", "good")
            .unwrap_or_else(|e| panic!("{material} should parse: {e}"));
    }
    for (material, words) in bad {
        let message = common::scene_error(&file(material));
        assert!(
            message.starts_with("bad.toml:7:"),
            "{message:?} should start with bad.toml:7:"
        );
        assert!(
            message.contains(words),
            "{message:?} should mention {words:?}"
        );
        assert!(!message.contains('\n'), "{message:?} is not one line");
    }
}

/// The mean of `f` over `n` draws, and its standard error.
fn mean(n: u32, mut f: impl FnMut(u32) -> f64) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0, 0.0);
    for i in 0..n {
        let x = f(i);
        sum += x;
        sum2 += x * x;
    }
    let m = sum / n as f64;
    (m, ((sum2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
}

/// Random unit vectors above the plane z = 0, with their numbers from `i`.
fn upper(i: u32, seed: u32) -> Vec3 {
    let mut s = Sampler::independent(i, 1, seed);
    let v = rt_gpu::shared::warp::unit_vector(s.next_f32(), s.next_f32());
    Vec3::new(v.x, v.y, v.z.abs().max(1e-3)).normalize()
}

/// The shipped scene loads: rows of seven conductors, glasses and plastics, roughness 0 to 1,
/// and of seven pbr materials, metallic 0 to 1.
#[test]
fn the_materials_scene_loads() {
    let scene = rt_gpu::scene::file::load(std::path::Path::new("scenes/materials.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let roughness = |keep: fn(&Material) -> Option<f32>| -> Vec<f32> {
        scene.materials.iter().filter_map(keep).collect()
    };
    let conductors = roughness(|m| match m {
        Material::Conductor(c) => Some(c.roughness),
        _ => None,
    });
    assert_eq!(conductors.len(), 14);
    assert_eq!(conductors.iter().filter(|&&r| r == 0.0).count(), 2);
    let glasses = roughness(|m| match m {
        Material::Dielectric(d) => Some(d.roughness),
        _ => None,
    });
    assert_eq!(glasses, [0.0, 0.1, 0.2, 0.35, 0.5, 0.7, 1.0]);
    let plastics = roughness(|m| match m {
        Material::Plastic(p) => Some(p.roughness),
        _ => None,
    });
    assert_eq!(plastics, glasses);
    let metallic = roughness(|m| match m {
        Material::Pbr(p) => Some(p.metallic),
        _ => None,
    });
    assert_eq!(metallic, [0.0, 0.17, 0.33, 0.5, 0.67, 0.83, 1.0]);
}

/// Issue 61: every material parameter a scene file's checks accept samples finite values at the
/// edges of what is accepted (a rough plastic of ior 1e-30 sampled NaN; conductors of k or eta
/// above 4e9 overflowed; pbr transmission at ior 1.0000001 divided by nearly 0): each value is
/// parsed as a scene file would, and where accepted its samples, evals and pdfs are finite, on
/// both faces at incidences from head-on to grazing.
#[test]
fn every_accepted_parameter_samples_finite_values() {
    let edges = [
        "1e-30",
        "1e-6",
        "0.001",
        "0.01",
        "0.5",
        "0.9999999",
        "1",
        "1.0000001",
        "1.0001",
        "1.5",
        "4",
        "10",
        "100",
        "1000",
        "10000",
        "1e6",
        "1e30",
    ];
    let roughnesses = ["0", "1e-7", "0.01", "0.3", "1"];
    let mut materials = Vec::new();
    for x in edges {
        for r in roughnesses {
            materials.push(format!(
                "{{ type = \"plastic\", albedo = [0.5, 0.5, 0.5], ior = {x}, roughness = {r} }}"
            ));
            materials.push(format!(
                "{{ type = \"dielectric\", ior = {x}, roughness = {r} }}"
            ));
            materials.push(format!(
                "{{ type = \"pbr\", base_color = [0.8, 0.8, 0.8], metallic = 0.3, roughness = {r}, ior = {x}, transmission = 0.5 }}"
            ));
            materials.push(format!(
                "{{ type = \"conductor\", eta = [{x}, 1, 1], k = [{x}, {x}, 0], roughness = {r} }}"
            ));
        }
    }
    let (mut accepted, mut invalid) = (0, Vec::new());
    for text in &materials {
        let file = format!(
            "[camera]\nlook_from = [0, 0, 1]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nm = {text}\n\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 0.5 }}\nmaterial = \"m\"\n"
        );
        let Ok(scene) = rt_gpu::scene::file::parse(&file, "edge.toml", "edge") else {
            continue;
        };
        accepted += 1;
        let m = &scene.materials[0];
        for front in [true, false] {
            let h = common::surface_hit(Vec3::Z, front);
            for angle in [0.0, 45.0, 89.9] {
                let wo = wo_at(angle);
                for i in 0..300 {
                    let mut s = Sampler::independent(i, 0, 11);
                    let Some(b) = m.sample(wo, &h, &mut s) else {
                        continue;
                    };
                    let (f, pdf) = (m.eval(wo, b.wi, &h), m.pdf(wo, b.wi, &h));
                    let finite = b.weight.is_finite()
                        && b.pdf.is_finite()
                        && b.wi.is_finite()
                        && f.is_finite()
                        && pdf.is_finite();
                    let label = format!("{text} at {angle} degrees (front {front})");
                    if !finite && !invalid.contains(&label) {
                        invalid.push(label);
                    }
                }
            }
        }
    }
    assert!(
        accepted > 120,
        "only {accepted} of {} accepted",
        materials.len()
    );
    assert!(invalid.is_empty(), "{invalid:#?}");
}

/// Where the sheen's and the specular's images are rendered: `spheres` (material, centre,
/// radius) on a grey floor under a square lamp of radiance 8 x `brighter` 2.6 above it, seen
/// from `camera` (from, at, vertical fov) under a constant `sky`. Materials and objects in that
/// order: floor, spheres, lamp.
fn on_a_lit_floor(
    spheres: Vec<(Material, Vec3, f32)>,
    brighter: f32,
    (from, at, vfov): (Vec3, Vec3, f32),
    sky: f32,
) -> rt_gpu::scene::Scene {
    use rt_gpu::material::{Lambertian, Light};
    use rt_gpu::scene::{Background, Shape};
    let mut materials = vec![Material::Lambertian(Lambertian {
        albedo: Vec3::splat(0.6).into(),
        emission: Vec3::ZERO,
        normal_map: None,
    })];
    let mut objects = vec![common::object(
        Shape::quad(
            Vec3::new(-3.0, 0.0, 3.0),
            Vec3::new(6.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -6.0),
        ),
        0,
    )];
    for (material, centre, radius) in spheres {
        materials.push(material);
        objects.push(common::object(
            Shape::sphere(centre, radius),
            materials.len() as u32 - 1,
        ));
    }
    materials.push(Material::Light(Light {
        radiance: Vec3::splat(8.0 * brighter).into(),
        strength: 1.0,
        two_sided: false,
        alpha: None,
    }));
    objects.push(common::object(
        Shape::quad(
            Vec3::new(-0.6, 2.6, -0.6),
            Vec3::new(1.2, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.2),
        ),
        materials.len() as u32 - 1,
    ));
    common::scene(
        from,
        at,
        vfov,
        Background::Constant(Vec3::splat(sky)),
        materials,
        objects,
    )
}
