//! Shading normals as microsurfaces (`material::microsurface`, Schüssler et al. 2017): the
//! walks `sample` returns with a density (the first-order walks) are distributed as `pdf`
//! says (chi-square, with a control whose shading normal is tilted 3 degrees further), their
//! mean weight is the integral of `eval` (what next-event estimation adds up for them), and
//! every walk together keeps a white lambertian's light (directional albedo 1).

use super::common::chi_square::{self, Domain, Histogram, Tally, expected_with_lost};
use super::{per_test_level, z_threshold};
use glam::Vec3;
use rt_gpu::scene::Material;
use rt_gpu::shared::ray::Hit;
use rt_gpu::shared::sampler::Sampler;

const SAMPLES: u32 = 200_000;

/// A hit on the plane z = 0 whose shading normal is tilted `degrees` toward +x.
fn tilted_hit(degrees: f32) -> Hit {
    let t = degrees.to_radians();
    Hit {
        shading: Vec3::new(t.sin(), 0.0, t.cos()),
        ..super::hit(Vec3::Z)
    }
}

/// wo at `degrees` from +z in the xz plane (negative: toward -x, away from the tilt).
fn wo(degrees: f32) -> Vec3 {
    super::wo_at(degrees)
}

/// A normal map (any: the hit's shading normal stands for what it gives), which makes a
/// microsurface of a material that only reflects.
fn map() -> rt_gpu::assets::normal_map::NormalMap {
    let image = rt_gpu::assets::image::Image::from_linear("flat", 1, 1, vec![0.5, 0.5, 1.0])
        .expect("valid")
        .shared();
    rt_gpu::assets::normal_map::NormalMap { image, scale: 1.0 }
}

fn lambertian(albedo: f32) -> Material {
    Material::Lambertian(rt_gpu::material::Lambertian {
        albedo: Vec3::splat(albedo).into(),
        emission: Vec3::ZERO,
        normal_map: Some(map()),
    })
}

fn pbr(colour: Vec3, metallic: f32, roughness: f32) -> Material {
    let mut p = rt_gpu::material::Pbr::new(colour.into(), metallic, roughness, 1.5, 0.0);
    p.normal_map = Some(map());
    Material::Pbr(p)
}

fn materials() -> Vec<(&'static str, Material)> {
    vec![
        ("lambertian 0.7", lambertian(0.7)),
        (
            "rough plastic-like pbr",
            pbr(Vec3::new(0.8, 0.5, 0.3), 0.0, 0.3),
        ),
        ("rough metal pbr", pbr(Vec3::new(0.9, 0.7, 0.5), 1.0, 0.5)),
    ]
}

const TILTS: [f32; 2] = [25.0, 60.0];
/// Head-on, toward the tilt, grazing away from it (below the shading hemisphere at 60).
const ANGLES: [f32; 3] = [0.0, 50.0, -80.0];

struct Drawn {
    /// Counts per cell of the first-order draws, then one cell for the rest.
    tally: Tally,
    /// Sum of the first-order draws' green weights, and of their squares.
    first_order: (f64, f64),
    /// Sum of all draws' green weights, and of their squares.
    all: (f64, f64),
}

fn draw(m: &Material, h: &Hit, wo: Vec3, cells: &Histogram) -> Drawn {
    let mut d = Drawn {
        tally: Tally {
            observed: vec![0.0; cells.cells() + 1],
            outside: Vec::new(),
        },
        first_order: (0.0, 0.0),
        all: (0.0, 0.0),
    };
    for i in 0..SAMPLES {
        let mut sampler = Sampler::independent(i, 0, 23);
        let Some(s) = m.sample(wo, h, &mut sampler) else {
            d.tally.observed[cells.cells()] += 1.0;
            continue;
        };
        let w = s.weight.y as f64;
        assert!(
            s.wi.dot(h.normal) > 0.0,
            "sampled {} below the surface",
            s.wi
        );
        d.all.0 += w;
        d.all.1 += w * w;
        if s.pdf > 0.0 && !s.lobe.is_delta() {
            d.tally.observed[cells.cell(s.wi).expect("on the sphere")] += 1.0;
            d.first_order.0 += w;
            d.first_order.1 += w * w;
        } else {
            d.tally.observed[cells.cells()] += 1.0;
        }
    }
    d
}

/// z of a sample mean (from its sum and sum of squares over SAMPLES) against `expected`.
fn z((sum, squares): (f64, f64), expected: f64) -> f64 {
    let n = SAMPLES as f64;
    let mean = sum / n;
    let variance = (squares / n - mean * mean).max(0.0) / n;
    (mean - expected) / variance.sqrt().max(1e-9)
}

#[test]
fn microsurface_samples_its_pdf_and_weighs_as_its_eval() {
    let configurations = TILTS.len() * ANGLES.len() * materials().len();
    let level = per_test_level(configurations as f64);
    let z_max = z_threshold(2.0 * configurations as f64);
    for tilt in TILTS {
        let h = tilted_hit(tilt);
        let control = tilted_hit(tilt + 3.0);
        for angle in ANGLES {
            let wo = wo(angle);
            let cells = Histogram::reflecting(Vec3::Z, wo);
            for (what, m) in materials() {
                let label = format!("{what}, tilt {tilt}, wo at {angle}");
                let d = draw(&m, &h, wo, &cells);
                let p_value = |h: &Hit| {
                    let expected = expected_with_lost(&cells, &|wi| m.pdf(wo, wi, h) as f64);
                    chi_square::test(&d.tally, &expected, SAMPLES).2
                };
                let (own, other) = (p_value(&h), p_value(&control));
                let integral: f64 =
                    (cells.expected(&|wi| m.eval(wo, wi, &h).y as f64).iter()).sum();
                let z_eval = z(d.first_order, integral);
                eprintln!(
                    "{label}: p {own:.3} (control {other:.1e}), first-order weight z {z_eval:.2}, albedo {:.4}",
                    d.all.0 / SAMPLES as f64
                );
                assert!(own > level, "{label}: sample vs pdf p = {own}");
                assert!(other < level, "{label}: the control passed (p = {other})");
                assert!(
                    z_eval.abs() < z_max,
                    "{label}: first-order weights vs eval, z = {z_eval}"
                );
            }
        }
    }
}

/// Directional albedo of a white lambertian on a microsurface is 1 (every walk's weight is 1,
/// so only lost walks would show): to 1e-4 up to a 75 degree tilt, to 0.5% at 85 (where walks
/// meet `MAX_SCATTERINGS`: 0.997 head-on); a 0.98 albedo is caught.
#[test]
fn white_lambertian_microsurface_keeps_its_light() {
    for albedo in [1.0, 0.98] {
        let m = lambertian(albedo);
        for tilt in [10.0, 45.0, 75.0, 85.0] {
            let h = tilted_hit(tilt);
            for angle in [0.0, 45.0, 89.0, -45.0, -89.0] {
                let wo = wo(angle);
                let cells = Histogram::reflecting(Vec3::Z, wo);
                let d = draw(&m, &h, wo, &cells);
                let mean = d.all.0 / SAMPLES as f64;
                if albedo == 1.0 {
                    // Past 75 degrees walks grow long enough to meet MAX_SCATTERINGS.
                    let bound = if tilt > 75.0 { 0.005 } else { 1e-4 };
                    assert!(
                        (mean - 1.0).abs() < bound,
                        "tilt {tilt}, wo at {angle}: albedo {mean}"
                    );
                } else {
                    assert!(
                        mean < 0.985,
                        "tilt {tilt}, wo at {angle}: the control passed ({mean})"
                    );
                }
            }
        }
    }
}
