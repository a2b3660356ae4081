//! Microfacet BSDFs (the conductor): `sample` draws directions with exactly the density `pdf`
//! reports (chi-square over a grid of roughness and incident angles, with a negative control),
//! `eval / pdf` is the sampled weight, `eval` is reciprocal, directional albedo stays <= 1 (the
//! white furnace), the conductor's Fresnel term is the complex one, bad parameters are located
//! errors, and images agree between integrators and backends. The kernel's `sample`, `eval`
//! and `pdf` equal the CPU's at 20 000 random queries.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

mod common;

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::{chi_square, compare};
use common::{nee_opts, object, opts, render_cpu};
use glam::Vec3;
use rt_gpu::material::conductor::{METALS, fresnel_conductor};
use rt_gpu::material::microfacet::Ggx;
use rt_gpu::material::{Conductor, Lobe};
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::{Material, Scene, Shape};
use rt_gpu::shared::ray::Hit;
use rt_gpu::shared::sampler::Sampler;
use std::f64::consts::PI;

const ROUGHNESS: [f32; 4] = [0.05, 0.3, 0.7, 1.0];
/// Incident angles from the normal, degrees: head-on to grazing.
const ANGLES: [f32; 4] = [0.0, 30.0, 60.0, 85.0];

fn hit(normal: Vec3) -> Hit {
    common::surface_hit(normal, true)
}

/// wo at `degrees` from +z, in the xz plane.
fn wo_at(degrees: f32) -> Vec3 {
    let theta = degrees.to_radians();
    Vec3::new(theta.sin(), 0.0, theta.cos())
}

fn gold(roughness: f32) -> Material {
    Material::Conductor(Conductor::metal("Au", roughness).expect("known metal"))
}

/// The histogram's cells: directions in polar coordinates about the mirror direction `r`
/// (theta' = pi u^3 for u in [0, 1], so that cells shrink toward `r` where glossy lobes are
/// narrow; phi' uniform).
const CELLS_U: usize = 24;
const CELLS_PHI: usize = 32;

struct Polar {
    r: Vec3,
    s: Vec3,
    t: Vec3,
}

impl Polar {
    fn new(r: Vec3) -> Self {
        let (s, t) = rt_gpu::shared::warp::basis(r);
        Polar { r, s, t }
    }
    fn cell(&self, d: Vec3) -> usize {
        // The angle from atan2 of the transverse and axial parts, in f64: the cells near `r`
        // are narrower than an f32 cosine resolves.
        let (x, y, z) = (
            d.dot(self.s) as f64,
            d.dot(self.t) as f64,
            d.dot(self.r) as f64,
        );
        let u = ((x * x + y * y).sqrt().atan2(z) / PI).cbrt();
        let phi = y.atan2(x) + PI;
        let a = ((u * CELLS_U as f64) as usize).min(CELLS_U - 1);
        let b = ((phi / (2.0 * PI) * CELLS_PHI as f64) as usize).min(CELLS_PHI - 1);
        a * CELLS_PHI + b
    }
    fn dir(&self, u: f64, phi: f64) -> Vec3 {
        let theta = PI * u * u * u;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = (phi - PI).sin_cos();
        (self.s * (st * cp) as f32 + self.t * (st * sp) as f32 + self.r * ct as f32).normalize()
    }
    /// The integral of `pdf` over each cell, in (u, phi) with the Jacobian sin(theta)
    /// dtheta/du: adaptive Simpson on 4 x 4 sub-cells per cell, each halved (to depth 6) until
    /// its estimate changes by under 1e-9, so that the horizon's cut and narrow lobes inside a
    /// cell are integrated too.
    fn expected(&self, pdf: impl Fn(Vec3) -> f32) -> Vec<f64> {
        let f = |u: f64, phi: f64| {
            let theta = PI * u * u * u;
            pdf(self.dir(u, phi)) as f64 * theta.sin() * 3.0 * PI * u * u
        };
        let du = 1.0 / CELLS_U as f64;
        let dphi = 2.0 * PI / CELLS_PHI as f64;
        let mut out = vec![0.0; CELLS_U * CELLS_PHI];
        for a in 0..CELLS_U {
            for b in 0..CELLS_PHI {
                let mut sum = 0.0;
                for i in 0..4 {
                    for j in 0..4 {
                        let u0 = (a as f64 + i as f64 / 4.0) * du;
                        let p0 = (b as f64 + j as f64 / 4.0) * dphi;
                        let (u1, p1) = (u0 + du / 4.0, p0 + dphi / 4.0);
                        let whole = simpson(&f, u0, u1, p0, p1);
                        sum += adaptive(&f, u0, u1, p0, p1, whole, 6, 1e-9);
                    }
                }
                out[a * CELLS_PHI + b] = sum;
            }
        }
        out
    }
}

/// Simpson's rule on one panel pair in each dimension.
fn simpson(f: &impl Fn(f64, f64) -> f64, u0: f64, u1: f64, p0: f64, p1: f64) -> f64 {
    let w = [1.0, 4.0, 1.0];
    let mut sum = 0.0;
    for (i, wu) in w.iter().enumerate() {
        for (j, wp) in w.iter().enumerate() {
            let u = u0 + (u1 - u0) * i as f64 / 2.0;
            let p = p0 + (p1 - p0) * j as f64 / 2.0;
            sum += wu * wp * f(u, p);
        }
    }
    sum * (u1 - u0) * (p1 - p0) / 36.0
}

#[allow(clippy::too_many_arguments)]
fn adaptive(
    f: &impl Fn(f64, f64) -> f64,
    u0: f64,
    u1: f64,
    p0: f64,
    p1: f64,
    whole: f64,
    depth: u32,
    tolerance: f64,
) -> f64 {
    let (um, pm) = ((u0 + u1) / 2.0, (p0 + p1) / 2.0);
    let quarters = [
        (u0, um, p0, pm),
        (um, u1, p0, pm),
        (u0, um, pm, p1),
        (um, u1, pm, p1),
    ];
    let parts = quarters.map(|(a, b, c, d)| simpson(f, a, b, c, d));
    let sum: f64 = parts.iter().sum();
    if depth == 0 || (sum - whole).abs() <= 15.0 * tolerance {
        return sum + (sum - whole) / 15.0;
    }
    quarters
        .iter()
        .zip(parts)
        .map(|(&(a, b, c, d), part)| adaptive(f, a, b, c, d, part, depth - 1, tolerance / 4.0))
        .sum()
}

/// Chi-square p-value of `samples` draws of `material.sample` at `wo` against the density
/// `pdf_of.pdf` (the same material, or a wrong one for the control), over the polar cells
/// plus one cell for the draws that end the path (expected: 1 - the integral of the pdf).
fn sample_vs_pdf(
    material: &Material,
    pdf_of: &Material,
    wo: Vec3,
    samples: u32,
) -> (f64, usize, f64) {
    sample_vs_pdf_at(material, pdf_of, Vec3::Z, wo, samples)
}

/// [`sample_vs_pdf`] at a surface whose normal is `normal`.
fn sample_vs_pdf_at(
    material: &Material,
    pdf_of: &Material,
    normal: Vec3,
    wo: Vec3,
    samples: u32,
) -> (f64, usize, f64) {
    let h = hit(normal);
    let polar = Polar::new(rt_gpu::material::reflect(-wo, normal));
    let mut observed = vec![0.0; CELLS_U * CELLS_PHI + 1];
    for i in 0..samples {
        let mut sampler = Sampler::independent(i, 0, 17);
        match material.sample(wo, &h, &mut sampler) {
            Some(s) => {
                // Pooling cells hides draws where the density is zero: each is checked.
                assert!(
                    material.pdf(wo, s.wi, &h) > 0.0,
                    "{material:?} sampled {} at wo {wo}, where its pdf is 0",
                    s.wi
                );
                observed[polar.cell(s.wi)] += 1.0
            }
            None => observed[CELLS_U * CELLS_PHI] += 1.0,
        }
    }
    let mut expected = polar.expected(|wi| pdf_of.pdf(wo, wi, &h));
    let covered: f64 = expected.iter().sum();
    expected.push((1.0 - covered).max(0.0));
    chi_square(&expected, &observed, samples as f64)
}

const CHI_SQUARE_SAMPLES: u32 = 500_000;

/// The grid's comparisons: (roughness, angle) about +z, and four more at a tilted normal with
/// wo off the plane of the frame's first axis (the local frame's both axes and signs in use).
const CHI_SQUARE_COMPARISONS: f64 = (ROUGHNESS.len() * ANGLES.len() + 4) as f64;

/// A normal and a wo at `degrees` from it, at azimuth 40 degrees in its frame.
fn tilted(degrees: f32) -> (Vec3, Vec3) {
    let normal = Vec3::new(0.3, 0.8, -0.52).normalize();
    let (s, t) = rt_gpu::shared::warp::basis(normal);
    let (theta, phi) = (degrees.to_radians(), 40f32.to_radians());
    let wo = (s * phi.cos() + t * phi.sin()) * theta.sin() + normal * theta.cos();
    (normal, wo.normalize())
}

/// One chi-square test per (roughness, angle) and four at a tilted frame: 20 comparisons at
/// family-wise significance 0.01, Sidak-corrected (each at 1 - 0.99^(1/20) = 5.0e-4). 500 000
/// samples each, cells expected below 5 pooled. Sampling does not depend on eta and k, so one
/// metal stands for all.
#[test]
fn conductor_sampling_follows_its_pdf() {
    let per_test = 1.0 - (1.0 - 0.01f64).powf(1.0 / CHI_SQUARE_COMPARISONS);
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
    let per_test = 1.0 - (1.0 - 0.01f64).powf(1.0 / CHI_SQUARE_COMPARISONS);
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

/// Random unit vectors above the plane z = 0, with their numbers from `i`.
fn upper(i: u32, seed: u32) -> Vec3 {
    let mut s = Sampler::independent(i, 1, seed);
    let v = rt_gpu::shared::warp::unit_vector(s.next_f32(), s.next_f32());
    Vec3::new(v.x, v.y, v.z.abs().max(1e-3)).normalize()
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
                let (f, pdf) = (m.eval(wo, s.wi, &h), m.pdf(wo, s.wi, &h));
                // D changes by up to 2 / alpha per radian of the half vector, which f32
                // recomputes from wo + wi: at roughness 0.05 near grazing a relative 1e-3
                // is within rounding.
                assert!(
                    (pdf - s.pdf).abs() <= 1e-2 * s.pdf,
                    "{name} {roughness}: pdf {pdf} against sampled {}",
                    s.pdf
                );
                let expected = f / pdf;
                assert!(
                    (expected - s.weight).abs().max_element()
                        <= 1e-3 * s.weight.max_element().max(1e-3),
                    "{name} {roughness}: eval/pdf {expected} against weight {}",
                    s.weight
                );
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
    let h = hit(Vec3::Z);
    for roughness in ROUGHNESS {
        let m = gold(roughness);
        for i in 0..10_000 {
            let (wo, wi) = (upper(i, 5), upper(i, 6));
            let forward = m.eval(wo, wi, &h) / wi.z;
            let backward = m.eval(wi, wo, &h) / wo.z;
            assert!(
                (forward - backward).abs().max_element() <= 2e-4 * forward.max_element().max(1e-6),
                "roughness {roughness}: {forward} against {backward} at wo {wo}, wi {wi}"
            );
        }
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

/// The Cornell box with conductors: the tall box rough gold (0.3), the short box a smooth
/// silver mirror, and a rough copper sphere (0.7): smooth and rough lobes, light sampled at the
/// rough ones only.
fn cornell_with_conductors() -> Scene {
    let mut scene = builtin("cornell").expect("built-in");
    let mut add = |name: &str, material: Material| {
        scene.materials.push(material);
        scene.material_names.push(name.into());
        scene.materials.len() as u32 - 1
    };
    let gold = add("gold", gold(0.3));
    let silver = add(
        "silver",
        Material::Conductor(Conductor::metal("Ag", 0.0).expect("known")),
    );
    let copper = add(
        "copper",
        Material::Conductor(Conductor::metal("Cu", 0.7).expect("known")),
    );
    let tall = scene.objects.len() - 2;
    scene.objects[tall].material = gold;
    scene.objects[tall + 1].material = silver;
    scene.objects.push(object(
        Shape::Sphere {
            center: Vec3::new(400.0, 380.0, 200.0),
            radius: 70.0,
        },
        copper,
    ));
    scene
}

/// nee and naive converge to the same image of the box with conductors (CPU; 16x16 at 20 000
/// spp, the equivalence test of tests/common/stats.rs), and the same test catches nee with the
/// light 2% brighter.
#[test]
fn conductor_nee_and_naive_agree() {
    let scene = cornell_with_conductors();
    let naive = render_cpu(&scene, &opts(16, 16, 20_000, 10, 1));
    let nee = render_cpu(&scene, &nee_opts(16, 16, 20_000, 10, 2));
    assert_eq!(naive.invalid_samples + nee.invalid_samples, 0);
    let verdict = compare(&naive, &nee);
    eprintln!("conductors: naive vs nee: {verdict:?}");
    assert!(verdict.passed(), "naive and nee differ: {verdict:?}");

    let mut brighter = scene.clone();
    let light = brighter
        .material_names
        .iter()
        .position(|n| n == "light")
        .expect("light");
    brighter.materials[light] = Material::Light(rt_gpu::material::Light {
        radiance: Vec3::splat(15.0 * 1.02).into(),
        strength: 1.0,
        two_sided: false,
    });
    let verdict = compare(
        &naive,
        &render_cpu(&brighter, &nee_opts(16, 16, 20_000, 10, 2)),
    );
    eprintln!("conductors, light +2%: {verdict:?}");
    assert!(
        !verdict.passed(),
        "a 2% brighter light went undetected: {verdict:?}"
    );
}

#[cfg(feature = "gpu")]
/// The kernel renders the box with conductors as the CPU does, with either integrator (16x16
/// at 20 000 spp); the 2% control is the test above's.
#[test]
fn conductor_gpu_matches_cpu() {
    let Some(gpu) = renderer() else {
        return;
    };
    let scene = cornell_with_conductors();
    for (label, a, b) in [
        (
            "naive",
            opts(16, 16, 20_000, 10, 1),
            opts(16, 16, 20_000, 10, 3),
        ),
        (
            "nee",
            nee_opts(16, 16, 20_000, 10, 2),
            nee_opts(16, 16, 20_000, 10, 4),
        ),
    ] {
        let cpu = render_cpu(&scene, &a);
        let gpu_film = render_gpu(&gpu, &scene, &b, &rt_gpu::gpu::Tuning::default());
        assert_eq!(gpu_film.invalid_samples, 0, "{label}");
        let verdict = compare(&cpu, &gpu_film);
        eprintln!("conductors, {label}: cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{label}: cpu and gpu differ: {verdict:?}");
    }
}

#[cfg(feature = "gpu")]
/// The kernel's `bsdf_sample`, `bsdf_eval` and `bsdf_pdf` equal the CPU's at 20 000 random
/// queries (a material of the grid, a random normal, wo on either side of it, a random wi, the
/// sample's numbers from the independent sampler): the same lobe, and directions, weights and
/// densities within 1e-3 relative. Up to 0.1% of queries may differ where a direction lies within
/// rounding of the horizon (the kernel's sin, cos and sqrt round differently).
#[test]
fn conductor_kernel_matches_cpu() {
    use rt_gpu::gpu::BsdfQuery;
    use rt_gpu::scene::flat::FlatScene;
    let Some(gpu) = renderer() else {
        return;
    };
    let mut scene = cornell_with_conductors();
    let first = scene.materials.len() as u32;
    for (name, _, _) in METALS {
        for roughness in [0.0, 0.05, 0.3, 0.7, 1.0] {
            scene.materials.push(Material::Conductor(
                Conductor::metal(name, roughness).expect("known"),
            ));
            scene.material_names.push(format!("{name}-{roughness}"));
        }
    }
    // Every material is used, so that the kernel holds them.
    for m in first..scene.materials.len() as u32 {
        scene.objects.push(object(
            Shape::Sphere {
                center: Vec3::new(20.0 + 10.0 * (m - first) as f32, 20.0, 20.0),
                radius: 2.0,
            },
            m,
        ));
    }
    const QUERIES: u32 = 20_000;
    let options = nee_opts(QUERIES, 1, 1, 10, 7);
    let flat = FlatScene::new(&scene, options.width, options.height).expect("valid");
    let conductors: Vec<u32> = (0..flat.materials.len() as u32)
        .filter(|&m| matches!(flat.materials[m as usize], Material::Conductor(_)))
        .collect();
    let queries: Vec<BsdfQuery> = (0..QUERIES)
        .map(|i| {
            let mut s = Sampler::independent(i, 5, 11);
            let mut unit = || rt_gpu::shared::warp::unit_vector(s.next_f32(), s.next_f32());
            let normal = unit();
            let wo = unit();
            let wo = if i % 10 == 0 || wo.dot(normal) > 0.0 {
                wo
            } else {
                -wo
            };
            BsdfQuery {
                material: conductors[i as usize % conductors.len()],
                wo,
                wi: unit(),
                normal,
            }
        })
        .collect();
    let answers = gpu
        .sample_bsdf(&flat, &options, &queries)
        .expect("kernel runs");
    let close =
        |a: Vec3, b: Vec3| (a - b).abs().max_element() <= 1e-3 * a.abs().max_element().max(1e-3);
    let close_f = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(1e-3);
    let mut differ = Vec::new();
    let mut sampled = 0;
    for (i, (q, g)) in queries.iter().zip(&answers).enumerate() {
        let m = &flat.materials[q.material as usize];
        let h = hit(q.normal);
        let mut sampler = Sampler::independent(i as u32, options.first_sample, options.seed);
        sampler.begin();
        let cpu = m.sample(q.wo, &h, &mut sampler);
        let same_sample = match cpu {
            None => g.lobe == 0,
            Some(s) => {
                sampled += 1;
                g.lobe == s.lobe.0
                    && close(s.wi, g.wi)
                    && close(s.weight, g.weight)
                    && close_f(s.pdf, g.pdf)
            }
        };
        let (f, pdf) = if m.samples_lights() {
            (m.eval(q.wo, q.wi, &h), m.pdf(q.wo, q.wi, &h))
        } else {
            (Vec3::ZERO, 0.0)
        };
        if !(same_sample && close(f, g.eval) && close_f(pdf, g.eval_pdf)) {
            differ.push((i, *q, cpu, *g, f, pdf));
        }
    }
    eprintln!(
        "{} of {QUERIES} queries differ ({sampled} sampled)",
        differ.len()
    );
    for d in differ.iter().take(5) {
        eprintln!("{d:?}");
    }
    assert!(sampled > QUERIES / 2);
    assert!(
        differ.len() as u32 <= QUERIES / 1000,
        "{} of {QUERIES} differ",
        differ.len()
    );
}

/// Bad conductor parameters are one-line errors at the material's line, naming the problem;
/// an unknown metal's lists the known ones.
#[test]
fn bad_conductors_are_located_errors() {
    let file = |material: &str| {
        format!(
            "[camera]\nlook_from = [0, 0, 1]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nm = {material}\n\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 0.5 }}\nmaterial = \"m\"\n"
        )
    };
    let good = file(r#"{ type = "conductor", metal = "Au", roughness = 0.3 }"#);
    rt_gpu::scene::file::parse(&good, "good.toml", "good").expect("a good conductor parses");
    for (material, words) in [
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
            "eta must be > 0",
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
    ] {
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

/// The shipped scene loads: two rows of seven conductors, roughness 0 to 1.
#[test]
fn the_materials_scene_loads() {
    let scene = rt_gpu::scene::file::load(std::path::Path::new("scenes/materials.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let conductors: Vec<f32> = scene
        .materials
        .iter()
        .filter_map(|m| match m {
            Material::Conductor(c) => Some(c.roughness),
            _ => None,
        })
        .collect();
    assert_eq!(conductors.len(), 14);
    assert_eq!(conductors.iter().filter(|&&r| r == 0.0).count(), 2);
}
