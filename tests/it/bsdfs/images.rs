//! Images of the box with microfacet materials: nee against naive, the kernel against the CPU,
//! and the kernel's BSDF functions against the CPU's.

use super::conductor::gold;
use super::*;
#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use common::{nee_opts, object, opts, render_cpu};
use rt_gpu::assets::texture::Texture;
use rt_gpu::material::clearcoat::Clearcoat;
use rt_gpu::material::conductor::METALS;
use rt_gpu::material::sheen::Sheen;
use rt_gpu::material::specular::Specular;
use rt_gpu::material::{Conductor, Dielectric, Pbr, Plastic};
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::{Scene, Shape};

/// The Cornell box with microfacet materials: the short box rough gold (0.3), its glass ball a
/// smooth silver mirror, a rough copper sphere (0.7) in the air, a rough glass one (0.5) in the
/// front corner by the green wall, a blue plastic one (0.2) on the floor at the front and a
/// half-metallic pbr one (0.4) by the red wall, a red pbr one (0.6) under a smooth clear coat
/// at the back left and a pbr metal (0.5) under a rough one (0.3, factor 0.7) high at the front
/// right, a velvet one (a red rough pbr under a white sheen of roughness 0.5) at the front
/// left, and at the back left on the floor a glass of every glTF layer at once (issue 63: a
/// rough transmissive pbr, tinted by its base and by an absorbing interior, under a tinted
/// specular of factor 0.6 and a rough clear coat):
/// smooth and rough lobes, reflected and refracted, over a diffuse base, light sampled at the
/// rough ones only. (Glass above the short box casts a shadow there that only its caustic
/// lights: without nee, 20 000 spp find too few of those paths, and the dim pixels fail the
/// test where 200 000 agree.)
fn cornell_with_microfacets() -> Scene {
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
    let frosted = add("frosted", Material::Dielectric(Dielectric::rough(1.5, 0.5)));
    let brass = add(
        "brass",
        Material::Pbr(Pbr::new(
            Texture::Colour(Vec3::new(0.8, 0.7, 0.2)),
            0.5,
            0.4,
            1.5,
            0.0,
        )),
    );
    let varnish = add(
        "varnish",
        Material::Plastic(Plastic::new(
            Texture::Colour(Vec3::new(0.2, 0.5, 0.8)),
            1.5,
            0.2,
        )),
    );
    let coat = |roughness, factor| Some(Clearcoat { factor, roughness });
    let lacquer = add(
        "lacquer",
        Material::Pbr(
            Pbr::new(
                Texture::Colour(Vec3::new(0.7, 0.1, 0.1)),
                0.0,
                0.6,
                1.5,
                0.0,
            )
            .with_clearcoat(coat(0.0, 1.0)),
        ),
    );
    let paint = add(
        "paint",
        Material::Pbr(
            Pbr::new(
                Texture::Colour(Vec3::new(0.2, 0.4, 0.8)),
                1.0,
                0.5,
                1.5,
                0.0,
            )
            .with_clearcoat(coat(0.3, 0.7)),
        ),
    );
    scene.objects.push(object(
        Shape::sphere(Vec3::new(150.0, 250.0, 400.0), 50.0),
        lacquer,
    ));
    scene.objects.push(object(
        Shape::sphere(Vec3::new(460.0, 450.0, 100.0), 45.0),
        paint,
    ));
    let velvet = add(
        "velvet",
        Material::Pbr(
            Pbr::new(
                Texture::Colour(Vec3::new(0.6, 0.05, 0.1)),
                0.0,
                0.8,
                1.5,
                0.0,
            )
            .with_sheen(Some(Sheen {
                color: Vec3::ONE,
                roughness: 0.5,
            })),
        ),
    );
    scene.objects.push(object(
        Shape::sphere(Vec3::new(90.0, 300.0, 120.0), 50.0),
        velvet,
    ));
    let short = scene.objects.len() - 5;
    scene.objects[short].material = gold;
    scene.objects[short + 1].material = silver;
    scene.objects.push(object(
        Shape::sphere(Vec3::new(400.0, 380.0, 200.0), 70.0),
        copper,
    ));
    scene.objects.push(object(
        Shape::sphere(Vec3::new(70.0, 45.0, 60.0), 45.0),
        frosted,
    ));
    scene.objects.push(object(
        Shape::sphere(Vec3::new(300.0, 40.0, 40.0), 40.0),
        varnish,
    ));
    scene.objects.push(object(
        Shape::sphere(Vec3::new(500.0, 50.0, 200.0), 50.0),
        brass,
    ));
    let layered = Pbr::new(
        Texture::Colour(Vec3::new(0.9, 0.9, 0.7)),
        0.0,
        0.3,
        1.5,
        1.0,
    )
    .with_specular(Some(Specular {
        factor: 0.6,
        color: Vec3::new(1.0, 2.0, 4.0),
    }))
    .with_clearcoat(coat(0.1, 0.5))
    .with_attenuation(Some((Vec3::new(0.8, 0.5, 0.3), 100.0)))
    .expect("valid attenuation");
    let layered = add("every layer", Material::Pbr(layered));
    scene.objects.push(object(
        Shape::sphere(Vec3::new(100.0, 60.0, 400.0), 60.0),
        layered,
    ));
    scene
}

/// The CPU's films of the box with microfacets, 16x16 at 20 000 spp, naive (seed 1) and nee
/// (seed 2): rendered once for the tests of both integrators and of both backends.
fn cpu_films() -> &'static [rt_gpu::film::Film; 2] {
    static FILMS: std::sync::OnceLock<[rt_gpu::film::Film; 2]> = std::sync::OnceLock::new();
    FILMS.get_or_init(|| {
        let scene = cornell_with_microfacets();
        [
            render_cpu(&scene, &opts(16, 16, 20_000, 10, 1)),
            render_cpu(&scene, &nee_opts(16, 16, 20_000, 10, 2)),
        ]
    })
}

/// nee and naive converge to the same image of the box with microfacets (CPU; 16x16 at 20 000
/// spp, the equivalence test of tests/it/common/stats.rs), and the same test catches nee with the
/// light 2% brighter.
#[test]
#[cfg_attr(
    not(feature = "gpu"),
    ignore = "CPU-only and slow: the default build runs it"
)]
fn microfacet_nee_and_naive_agree() {
    let scene = cornell_with_microfacets();
    let [naive, nee] = cpu_films();
    assert_eq!(naive.invalid_samples + nee.invalid_samples, 0);
    let verdict = compare(naive, nee);
    eprintln!("microfacets: naive vs nee: {verdict:?}");
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
        alpha: None,
    });
    let verdict = compare(
        naive,
        &render_cpu(&brighter, &nee_opts(16, 16, 20_000, 10, 2)),
    );
    eprintln!("microfacets, light +2%: {verdict:?}");
    assert!(
        !verdict.passed(),
        "a 2% brighter light went undetected: {verdict:?}"
    );
}

#[cfg(feature = "gpu")]
/// The kernel renders the box with microfacets as the CPU does, with either integrator (16x16
/// at 20 000 spp); the 2% control is the test above's.
#[test]
fn microfacet_gpu_matches_cpu() {
    let Some(gpu) = renderer() else {
        return;
    };
    let scene = cornell_with_microfacets();
    let [naive, nee] = cpu_films();
    for (label, cpu, b) in [
        ("naive", naive, opts(16, 16, 20_000, 10, 3)),
        ("nee", nee, nee_opts(16, 16, 20_000, 10, 4)),
    ] {
        let gpu_film = render_gpu(&gpu, &scene, &b, &rt_gpu::gpu::Tuning::default());
        assert_eq!(gpu_film.invalid_samples, 0, "{label}");
        let verdict = compare(cpu, &gpu_film);
        eprintln!("microfacets, {label}: cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{label}: cpu and gpu differ: {verdict:?}");
    }
}

#[cfg(feature = "gpu")]
/// The kernel's `bsdf_sample`, `bsdf_eval` and `bsdf_pdf` equal the CPU's at 20 000 random
/// queries (a conductor, glass or plastic of the grid, a random normal, wo on either side of it, a random
/// wi, front or back face, the sample's numbers from the independent sampler): the same lobe,
/// and directions, weights and densities within 1e-3 relative. Up to 0.1% of queries may differ where a direction lies within
/// rounding of the horizon (the kernel's sin, cos and sqrt round differently).
#[test]
fn microfacet_kernel_matches_cpu() {
    use rt_gpu::gpu::BsdfQuery;
    use rt_gpu::scene::flat::FlatScene;
    let Some(gpu) = renderer() else {
        return;
    };
    let mut scene = cornell_with_microfacets();
    let first = scene.materials.len() as u32;
    for roughness in [0.0, 0.05, 0.3, 0.7, 1.0] {
        for (name, _, _) in METALS {
            scene.materials.push(Material::Conductor(
                Conductor::metal(name, roughness).expect("known"),
            ));
            scene.material_names.push(format!("{name}-{roughness}"));
        }
        for ior in [1.33, 1.5, 2.4] {
            scene
                .materials
                .push(Material::Dielectric(Dielectric::rough(ior, roughness)));
            scene
                .material_names
                .push(format!("glass-{ior}-{roughness}"));
        }
        for (albedo, ior) in [(Vec3::new(0.6, 0.05, 0.05), 1.5), (Vec3::splat(0.8), 2.0)] {
            let coat = Plastic::new(Texture::Colour(albedo), ior, roughness);
            scene.materials.push(Material::Plastic(coat));
            scene
                .material_names
                .push(format!("plastic-{ior}-{roughness}"));
        }
        for (metallic, transmission) in [(0.0, 0.0), (0.5, 0.0), (1.0, 0.0), (0.0, 0.5)] {
            let base = Texture::Colour(Vec3::new(0.8, 0.7, 0.2));
            let m = Pbr::new(base, metallic, roughness, 1.5, transmission);
            scene.materials.push(Material::Pbr(m));
            scene
                .material_names
                .push(format!("pbr-{metallic}-{transmission}-{roughness}"));
            // Under a sheen, and under a sheen and a clear coat.
            for coat in [
                None,
                Some(Clearcoat {
                    factor: 0.6,
                    roughness: 0.1,
                }),
            ] {
                let base = Texture::Colour(Vec3::new(0.8, 0.7, 0.2));
                let m = Pbr::new(base, metallic, roughness, 1.5, transmission)
                    .with_sheen(Some(Sheen {
                        color: Vec3::new(1.0, 0.5, 0.3),
                        roughness: 1.0 - roughness,
                    }))
                    .with_clearcoat(coat);
                scene.materials.push(Material::Pbr(m));
                scene.material_names.push(format!(
                    "sheen-{metallic}-{transmission}-{roughness}-{}",
                    coat.is_some()
                ));
            }
            // With a weaker, tinted specular (KHR_materials_specular), alone and under a coat.
            for coat in [
                None,
                Some(Clearcoat {
                    factor: 0.5,
                    roughness: 0.2,
                }),
            ] {
                let base = Texture::Colour(Vec3::new(0.8, 0.7, 0.2));
                let m = Pbr::new(base, metallic, roughness, 1.5, transmission)
                    .with_specular(Some(Specular {
                        factor: 0.6,
                        color: Vec3::new(2.0, 1.0, 0.3),
                    }))
                    .with_clearcoat(coat);
                scene.materials.push(Material::Pbr(m));
                scene.material_names.push(format!(
                    "specular-{metallic}-{transmission}-{roughness}-{}",
                    coat.is_some()
                ));
            }
            // Under a clear coat, smooth and rough.
            for coat_roughness in [0.0, 0.2] {
                let base = Texture::Colour(Vec3::new(0.8, 0.7, 0.2));
                let m = Pbr::new(base, metallic, roughness, 1.5, transmission).with_clearcoat(
                    Some(Clearcoat {
                        factor: 0.8,
                        roughness: coat_roughness,
                    }),
                );
                scene.materials.push(Material::Pbr(m));
                scene.material_names.push(format!(
                    "coated-{metallic}-{transmission}-{roughness}-{coat_roughness}"
                ));
            }
        }
    }
    // Every material is used, so that the kernel holds them.
    for m in first..scene.materials.len() as u32 {
        scene.objects.push(object(
            Shape::sphere(Vec3::new(20.0 + 10.0 * (m - first) as f32, 20.0, 20.0), 2.0),
            m,
        ));
    }
    const QUERIES: u32 = 20_000;
    let options = nee_opts(QUERIES, 1, 1, 10, 7);
    let flat = FlatScene::new(&scene, options.width, options.height).expect("valid");
    let microfacets: Vec<u32> = (0..flat.materials.len() as u32)
        .filter(|&m| {
            matches!(
                flat.materials[m as usize],
                Material::Conductor(_)
                    | Material::Dielectric(_)
                    | Material::Plastic(_)
                    | Material::Pbr(_)
            )
        })
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
                material: microfacets[i as usize % microfacets.len()],
                wo,
                wi: unit(),
                normal,
                front_face: s.next_f32() < 0.5,
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
        let h = common::surface_hit(q.normal, q.front_face);
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

/// Issue 63's textures of the layers: a lacquered sphere whose clear coat's factor and
/// roughness follow the stripes of a layers image (red 1 / 0.2, green 1 / 0.25), and a velvet
/// one whose sheen's colour and roughness follow those of a sheen image and the layers' blue,
/// on a grey ground under a warm sky. `sheen_scale` scales the sheen image (the negative
/// control's change); without `textured` the images are left out.
fn layered_spheres(sheen_scale: f32, textured: bool) -> Scene {
    let lacquer = Pbr::new(
        Texture::Colour(Vec3::new(0.7, 0.1, 0.1)),
        0.0,
        0.6,
        1.5,
        0.0,
    )
    .with_clearcoat(Some(Clearcoat {
        factor: 1.0,
        roughness: 0.4,
    }))
    .with_layer_images(stripes("coat", [1.0; 3], [0.2, 0.25, 1.0]), None);
    let lacquer = if textured {
        lacquer
    } else {
        lacquer.with_layer_images(None, None)
    };
    let s = sheen_scale;
    let velvet = Pbr::new(
        Texture::Colour(Vec3::new(0.1, 0.2, 0.6)),
        0.0,
        0.8,
        1.5,
        0.0,
    )
    .with_sheen(Some(Sheen {
        color: Vec3::ONE,
        roughness: 0.8,
    }))
    .with_layer_images(
        stripes("sheen roughness", [1.0; 3], [1.0, 1.0, 0.4]),
        stripes("sheen colour", [s; 3], [0.2 * s, 0.9 * s, 0.3 * s]),
    );
    let velvet = if textured {
        velvet
    } else {
        velvet.with_layer_images(None, None)
    };
    two_spheres(Material::Pbr(lacquer), Material::Pbr(velvet))
}

/// Stripes of two colours, `a` and `b`, across an 8x4 image named `name`.
fn stripes(
    name: &str,
    a: [f32; 3],
    b: [f32; 3],
) -> Option<std::sync::Arc<rt_gpu::assets::image::Image>> {
    let texels: Vec<f32> = (0..8 * 4)
        .flat_map(|i| if (i % 8) % 2 == 0 { a } else { b })
        .collect();
    Some(
        rt_gpu::assets::image::Image::from_linear(name, 8, 4, texels)
            .expect("valid")
            .shared(),
    )
}

/// Spheres of materials `left` and `right` side by side on a grey ground under a warm sky.
fn two_spheres(left: Material, right: Material) -> Scene {
    let ground = Material::lambertian(Vec3::splat(0.5));
    common::scene(
        Vec3::new(0.0, 0.3, 3.2),
        Vec3::new(0.0, -0.1, 0.0),
        40.0,
        rt_gpu::scene::Background::Constant(Vec3::new(0.9, 0.8, 0.7)),
        vec![left, right, ground],
        vec![
            object(Shape::sphere(Vec3::new(-0.55, 0.0, 0.0), 0.5), 0),
            object(Shape::sphere(Vec3::new(0.55, 0.0, 0.0), 0.5), 1),
            object(Shape::sphere(Vec3::new(0.0, -100.5, 0.0), 100.0), 2),
        ],
    )
}

/// The layers' textures render the same estimator every way (`common::renders_alike_every_way`:
/// naive vs nee on the CPU, the kernel vs the CPU; Welch z + Sidak at family-wise 0.01, 1 401
/// comparisons), and the sheen image 10% darker is told apart on the kernel (5% is not, at
/// these 2 048 spp: worst block z 3.4 against 4.5). On the CPU, the images change the picture:
/// without them the same test fails.
#[test]
fn layer_images_render_alike_every_way() {
    let nee = common::renders_alike_every_way("layer images", &layered_spheres(1.0, true), || {
        layered_spheres(0.9, true)
    });
    assert_eq!(nee.invalid_samples, 0);
    let plain = render_cpu(&layered_spheres(1.0, false), &nee_opts(24, 18, 2048, 5, 2));
    let verdict = compare(&nee, &plain);
    eprintln!("layer images against none: {verdict:?}");
    assert!(!verdict.passed(), "the layer images change nothing");
}

/// Two near-black pbr spheres, smooth and rough (0.4), whose specular factor (1) and colour
/// ([2, 1.5, 1]: F0 tinted past white) follow stripes of a specular image (red: 1 and 0.3,
/// scaled by `factor_scale`, the negative control's change) and a specular colour image
/// (`two_spheres`): nearly all they show is their reshaped Fresnel. Without `textured` the
/// images are left out.
fn specular_spheres(factor_scale: f32, textured: bool) -> Scene {
    let s = factor_scale;
    let sphere = |roughness: f32| {
        let pbr = Pbr::new(Texture::Colour(Vec3::splat(0.05)), 0.0, roughness, 1.5, 0.0)
            .with_specular(Some(Specular {
                factor: 1.0,
                color: Vec3::new(2.0, 1.5, 1.0),
            }));
        if !textured {
            return Material::Pbr(pbr);
        }
        Material::Pbr(pbr.with_specular_images(
            stripes("specular", [s; 3], [0.3 * s; 3]),
            stripes("specular colour", [1.0; 3], [0.2, 1.0, 0.5]),
        ))
    };
    two_spheres(sphere(0.0), sphere(0.4))
}

/// The specular images render the same estimator every way (`common::renders_alike_every_way`:
/// naive vs nee on the CPU, the kernel vs the CPU; Welch z + Sidak at family-wise 0.01, 1 401
/// comparisons), and the specular image 10% darker is told apart on the kernel. On the CPU,
/// the images change the picture: without them the same test fails.
#[test]
fn specular_images_render_alike_every_way() {
    let nee =
        common::renders_alike_every_way("specular images", &specular_spheres(1.0, true), || {
            specular_spheres(0.9, true)
        });
    assert_eq!(nee.invalid_samples, 0);
    let plain = render_cpu(&specular_spheres(1.0, false), &nee_opts(24, 18, 2048, 5, 2));
    let verdict = compare(&nee, &plain);
    eprintln!("specular images against none: {verdict:?}");
    assert!(!verdict.passed(), "the specular images change nothing");
}

/// A specular image of one value everywhere is its factor scaled by it, and a specular colour
/// image its colour: the BSDF, its pdf and its samples at 2 000 random pairs of directions are
/// bit for bit those of the material with the scaled factor and colour (the scales are powers
/// of two, so that scaling the tint or the colour rounds alike), smooth and rough, the coat's K
/// included (it follows from the mean opacity per hit). Without the images, they differ.
#[test]
fn constant_specular_images_are_scaled_factors() {
    use rt_gpu::assets::image::Image;
    use rt_gpu::material::MaterialModel;
    use rt_gpu::shared::sampler::Sampler;
    let constant = |name: &str, v: [f32; 3]| {
        Some(
            Image::from_linear(name, 2, 2, v.repeat(4))
                .expect("valid")
                .shared(),
        )
    };
    let h = hit(Vec3::Z);
    for roughness in [0.0, 0.4] {
        let pbr = |factor: f32, color: Vec3| {
            Pbr::new(
                Texture::Colour(Vec3::new(0.9, 0.5, 0.2)),
                0.0,
                roughness,
                1.5,
                0.0,
            )
            .with_specular(Some(Specular { factor, color }))
        };
        let imaged = pbr(0.8, Vec3::new(2.0, 1.0, 0.5)).with_specular_images(
            constant("factor", [0.5; 3]),
            constant("colour", [0.25, 1.0, 0.5]),
        );
        let scaled = pbr(0.4, Vec3::new(0.5, 1.0, 0.25));
        let unscaled = pbr(0.8, Vec3::new(2.0, 1.0, 0.5));
        let mut rng = Sampler::independent(7, 0, 8);
        let mut differs_from_unscaled = false;
        for i in 0..2000 {
            let wo = rt_gpu::shared::warp::unit_vector(rng.next_f32(), rng.next_f32());
            let wi = rt_gpu::shared::warp::unit_vector(rng.next_f32(), rng.next_f32());
            assert_eq!(imaged.eval(wo, wi, &h), scaled.eval(wo, wi, &h), "pair {i}");
            assert_eq!(imaged.pdf(wo, wi, &h), scaled.pdf(wo, wi, &h), "pair {i}");
            let a = imaged.sample(wo, &h, &mut Sampler::independent(i, 1, 8));
            let b = scaled.sample(wo, &h, &mut Sampler::independent(i, 1, 8));
            assert_eq!(
                a.map(|s| (s.wi, s.weight, s.pdf)),
                b.map(|s| (s.wi, s.weight, s.pdf)),
                "pair {i}"
            );
            differs_from_unscaled |= imaged.eval(wo, wi, &h) != unscaled.eval(wo, wi, &h);
        }
        assert!(differs_from_unscaled, "the images change nothing");
    }
}
