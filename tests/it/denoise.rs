//! The denoiser (issue 65): the albedo and normal feature buffers on both backends, and Open
//! Image Denoise on the film. Tests that need OIDN skip with a note where it is absent, unless
//! `RT_GPU_REQUIRE_OIDN=1` (CI, whose set-up installs it) makes its absence a failure.
#![cfg(feature = "cli")]

use crate::common::{self, cli, gpu::render_gpu, gpu::renderer, stats::compare};
use rt_gpu::denoise::{Denoiser, FeatureBuffers};
use rt_gpu::film::Film;
use rt_gpu::gpu::Tuning;
use rt_gpu::render::{Backend, GpuChoice, Integrator, RenderOptions};
use rt_gpu::scene::Scene;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::flat::FlatScene;

/// OIDN's CPU device, or `None` (with a note) where it is not installed and not required.
fn denoiser() -> Option<Denoiser> {
    match Denoiser::new(None) {
        Ok(d) => Some(d),
        Err(e) if std::env::var_os("RT_GPU_REQUIRE_OIDN").is_some_and(|v| v == "1") => {
            panic!("RT_GPU_REQUIRE_OIDN=1 but: {e}")
        }
        Err(e) => {
            eprintln!("skipped: {e}");
            None
        }
    }
}

fn feature_opts(integrator: Integrator, size: u32, spp: u32, seed: u32) -> RenderOptions {
    RenderOptions {
        integrator,
        ..common::opts(size, size, spp, 10, seed)
    }
}

fn render_cpu(scene: &Scene, opts: &RenderOptions) -> Film {
    let flat = FlatScene::new(scene, opts.width, opts.height).expect("valid scene");
    rt_gpu::cpu::render(&flat, opts, &|| {})
}

/// A camera facing a surface that fills the view, from a scene file's text.
fn facing(material: &str) -> Scene {
    let text = format!(
        r#"
[render]
width = 8
height = 8
background = [2.0, 1.0, 0.5]

[camera]
look_from = [0, 0, -5]
look_at = [0, 0, 0]
vfov = 20

[materials]
surface = {material}

[[object]]
quad = {{ q = [-10, -10, 0], u = [20, 0, 0], v = [0, 20, 0] }}
material = "surface"
"#
    );
    rt_gpu::scene::file::parse(&text, "facing.toml", "facing").expect("parses")
}

/// Each pixel's mean, on both backends where a GPU is at hand.
fn means_every_way(scene: &Scene, integrator: Integrator) -> Vec<Vec<[f32; 3]>> {
    let opts = feature_opts(integrator, 8, 16, 1);
    let mut films = vec![render_cpu(scene, &opts)];
    if let Some(gpu) = renderer() {
        films.push(render_gpu(&gpu, scene, &opts, &Tuning::default()));
    }
    films.iter().map(|f| f.mean_rgb()).collect()
}

/// A diffuse surface's albedo buffer is its albedo and its normal buffer its normal facing the
/// camera, at every sample; a mirror is seen through, to the background, weighted by its
/// reflectance, with no normal (0, stored as 0.5); a light gives its colour.
#[test]
fn feature_buffers_are_the_first_diffuse_surface() {
    let diffuse = r#"{ type = "lambertian", albedo = [0.2, 0.4, 0.6] }"#;
    let mirror = r#"{ type = "metal", albedo = [0.8, 0.6, 0.4] }"#;
    let light = r#"{ type = "light", radiance = [4, 8, 2], two_sided = true }"#;
    for (material, integrator, expected, what) in [
        (
            diffuse,
            Integrator::Albedo,
            [0.2, 0.4, 0.6],
            "albedo of a diffuse surface",
        ),
        // The quad's normal is +z; facing the camera at -z it is -z: stored (0.5, 0.5, 0).
        (
            diffuse,
            Integrator::Normal,
            [0.5, 0.5, 0.0],
            "normal of a diffuse surface",
        ),
        // Back to the camera and past it: the background (2, 1, 0.5), colour (1, 0.5, 0.25).
        (
            mirror,
            Integrator::Albedo,
            [0.8, 0.3, 0.1],
            "albedo through a mirror",
        ),
        (
            mirror,
            Integrator::Normal,
            [0.5, 0.5, 0.5],
            "normal through a mirror",
        ),
        (
            light,
            Integrator::Albedo,
            [0.5, 1.0, 0.25],
            "albedo of a light",
        ),
    ] {
        let means = means_every_way(&facing(material), integrator);
        for (backend, pixels) in means.iter().enumerate() {
            for p in pixels {
                let off = (0..3).any(|c| (p[c] - expected[c]).abs() > 1e-5);
                assert!(
                    !off,
                    "{what}, backend {backend}: {p:?}, expected {expected:?}"
                );
            }
        }
    }
}

/// The kernel's albedo and normal buffers equal the CPU's under the image-equivalence test
/// (Welch z per pixel and block, Sidak-corrected at a family-wise 1%: common/stats.rs), on the
/// Cornell box (glass followed through) and the showcase (rough metals, plastic, textures);
/// the negative control, the Cornell box's white albedo 2% higher, is detected.
#[test]
fn feature_buffers_match_on_both_backends() {
    let Some(gpu) = renderer() else { return };
    let cornell = builtin("cornell").expect("built-in");
    for (name, scene) in [
        ("cornell", cornell.clone()),
        ("showcase", builtin("showcase").expect("built-in")),
    ] {
        for integrator in [Integrator::Albedo, Integrator::Normal] {
            let cpu = render_cpu(&scene, &feature_opts(integrator, 32, 256, 1));
            let gpu_film = render_gpu(
                &gpu,
                &scene,
                &feature_opts(integrator, 32, 256, 2),
                &Tuning::default(),
            );
            assert_eq!(gpu_film.invalid_samples + cpu.invalid_samples, 0, "{name}");
            let verdict = compare(&cpu, &gpu_film);
            eprintln!("{name} {}: {verdict:?}", integrator.name());
            assert!(
                verdict.passed(),
                "{name} {}: {verdict:?}",
                integrator.name()
            );
        }
    }
    let cpu = render_cpu(&cornell, &feature_opts(Integrator::Albedo, 32, 256, 1));
    let brighter = common::cornell_white_2_percent_brighter();
    let gpu_film = render_gpu(
        &gpu,
        &brighter,
        &feature_opts(Integrator::Albedo, 32, 256, 2),
        &Tuning::default(),
    );
    let verdict = compare(&cpu, &gpu_film);
    eprintln!("white albedo +2%: {verdict:?}");
    assert!(
        !verdict.passed(),
        "a 2% albedo change went undetected: {verdict:?}"
    );
}

/// The RMSE of `a` against `b` as displayed: each value clamped to [0, 1] first. (The raw HDR
/// RMSE of the Cornell box is its light's: 1.5% of the pixels, at 15, whose edges carry most of
/// the squared error, noisy or denoised.)
fn display_rmse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let sum: f64 = (a.iter().zip(b))
        .flat_map(|(p, q)| {
            (0..3).map(move |c| (p[c].clamp(0.0, 1.0) as f64 - q[c].clamp(0.0, 1.0) as f64).powi(2))
        })
        .sum();
    (sum / (3 * a.len()) as f64).sqrt()
}

/// The relative MSE of `a` against reference `b`: mean (a - b)^2 / (b^2 + 0.01), the HDR
/// error denoising papers report.
fn rel_mse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let sum: f64 = (a.iter().zip(b))
        .flat_map(|(p, q)| {
            (0..3)
                .map(move |c| (p[c] as f64 - q[c] as f64).powi(2) / ((q[c] as f64).powi(2) + 0.01))
        })
        .sum();
    sum / (3 * a.len()) as f64
}

fn render(scene: &FlatScene, opts: &RenderOptions) -> Film {
    rt_gpu::render::render(Backend::Cpu, &GpuChoice::default(), scene, opts, &|_| {})
        .expect("renders")
        .film
}

/// The denoised 16-spp Cornell box is closer to a 1024-spp render than the noisy 64-spp one,
/// by the RMSE of the displayed image and by relative MSE (the reference's own noise adds to
/// both), and its mean is within 2% of the reference's; the same input denoised twice gives the
/// same bytes.
#[test]
fn the_denoised_image_beats_four_times_the_samples() {
    let Some(denoiser) = denoiser() else { return };
    let scene = builtin("cornell").expect("built-in");
    let size = 128;
    let flat = FlatScene::new(&scene, size, size).expect("valid");
    let opts = |spp, seed, integrator| RenderOptions {
        integrator,
        seed,
        ..rt_gpu::options::RenderOptions::new(size, size, spp, 10)
    };
    let reference = render(&flat, &opts(1024, 7, Integrator::Nee)).mean_rgb();
    let noisy_64 = render(&flat, &opts(64, 1, Integrator::Nee)).mean_rgb();
    let noisy_16 = render(&flat, &opts(16, 1, Integrator::Nee)).mean_rgb();
    let features = FeatureBuffers::from_films(
        &render(&flat, &opts(16, 1, Integrator::Albedo)),
        &render(&flat, &opts(16, 1, Integrator::Normal)),
    );
    let denoised = denoiser
        .denoise(size, size, &noisy_16, Some(&features))
        .expect("denoises");
    for (what, error) in [
        (
            "display RMSE",
            display_rmse as fn(&[[f32; 3]], &[[f32; 3]]) -> f64,
        ),
        ("relMSE", rel_mse),
    ] {
        let (e16, e64, ed) = (
            error(&noisy_16, &reference),
            error(&noisy_64, &reference),
            error(&denoised, &reference),
        );
        eprintln!(
            "{what} against 1024 spp: noisy 16 spp {e16:.5}, noisy 64 spp {e64:.5}, denoised 16 spp {ed:.5}"
        );
        assert!(
            ed < e64,
            "{what}: denoised {ed} not below the noisy 64-spp {e64}"
        );
    }
    let mean = |img: &[[f32; 3]]| {
        img.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * img.len()) as f64
    };
    let bias = mean(&denoised) / mean(&reference) - 1.0;
    eprintln!("denoised mean over the reference's: {bias:+.4}");
    assert!(bias.abs() < 0.02, "denoised mean off by {bias}");
    let again = denoiser
        .denoise(size, size, &noisy_16, Some(&features))
        .expect("denoises");
    assert!(
        again
            .iter()
            .flatten()
            .map(|v| v.to_bits())
            .eq(denoised.iter().flatten().map(|v| v.to_bits())),
        "the same input denoised twice differs"
    );
}

/// Without OIDN, or with a broken one, `--denoise` is one line naming the problem and how to
/// install it, a non-zero exit before rendering, and nothing written.
#[test]
fn a_missing_or_broken_denoiser_is_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let junk = dir.path().join("junk");
    std::fs::create_dir_all(junk.join("lib")).expect("mkdir");
    std::fs::write(junk.join("lib/libOpenImageDenoise.so.2"), b"not a library").expect("write");
    for (oidn_dir, expected) in [
        (dir.path().join("absent"), "no such file (from OIDN_DIR)"),
        (junk, "cannot load Open Image Denoise from"),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
            .args([
                "cornell",
                "--spp",
                "1",
                "--size",
                "8x8",
                "--backend",
                "cpu",
                "--denoise",
                "-o",
                "out.png",
            ])
            .env("OIDN_DIR", &oidn_dir)
            .current_dir(dir.path())
            .output()
            .expect("runs");
        let err = cli::stderr(&out);
        assert!(!out.status.success(), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(
            err.contains(expected) && err.contains("scripts/install-oidn.py"),
            "{err}"
        );
        assert!(!dir.path().join("out.png").exists());
    }
}

/// `converge --denoise` puts a denoised series beside each, whose 16-spp render is closer to
/// the reference than the noisy one by relative MSE, and says what denoising gained; the feature
/// buffers are no series of their own (`--integrators albedo` is refused).
#[test]
fn converge_puts_a_denoised_series_beside_each() {
    use rt_gpu::converge::{ConvergeOptions, run};
    let Some(_) = denoiser() else { return };
    let scene = builtin("cornell").expect("built-in");
    let dir = tempfile::tempdir().expect("tempdir");
    let options = ConvergeOptions {
        scene: FlatScene::new(&scene, 64, 64).expect("valid"),
        scene_name: "cornell".into(),
        scene_digest: 1,
        width: 64,
        height: 64,
        max_depth: 10,
        backends: vec![Backend::Cpu],
        integrators: vec![Integrator::Nee],
        samplers: vec![rt_gpu::options::SamplerKind::Sobol],
        roulette_depth: 5,
        budget: 2.0,
        reference: None,
        reference_spp: Some(1024),
        out_dir: dir.path().to_path_buf(),
        gpu: GpuChoice::default(),
        denoise: true,
    };
    let report = run(&options).expect("runs");
    let at_16 = |series: &str| {
        (report.rungs.iter())
            .find(|r| r.series == series && r.spp == 16)
            .unwrap_or_else(|| panic!("no 16-spp {series}\n{}", report.table(None)))
            .errors
    };
    let (noisy, denoised) = (at_16("cpu-nee-sobol"), at_16("cpu-nee-sobol-denoised"));
    assert!(denoised.relmse < noisy.relmse, "{noisy:?} {denoised:?}");
    let table = report.table(None);
    assert!(
        table.contains("denoised by Open Image Denoise 2."),
        "{table}"
    );
    assert!(table.contains("denoised 16 spp: RMSE"), "{table}");
    let refused = run(&ConvergeOptions {
        integrators: vec![Integrator::Albedo],
        denoise: false,
        ..options
    });
    let message = refused.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(message.contains("not the albedo buffer"), "{message}");
}
