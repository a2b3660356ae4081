//! The same scene and seed give the same image whatever the thread count.

use crate::common;

use rt_gpu::scene::builtin::builtin;

#[test]
fn same_seed_same_image_with_one_and_two_threads() {
    let scene = builtin("cornell").expect("built-in");
    let opts = common::opts(24, 20, 4, 10, 5);
    let render_with = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| common::render_cpu(&scene, &opts))
    };
    let one = render_with(1);
    let two = render_with(2);
    assert!(one == two, "images differ between 1 and 2 threads");

    // And a different seed gives a different image (the comparison above can fail).
    let other = common::render_cpu(&scene, &common::opts(24, 20, 4, 10, 6));
    assert!(other != one);
    // Splitting the samples into two renders and merging gives the same statistics.
    let mut first = common::render_cpu(&scene, &common::opts(24, 20, 1, 10, 5));
    let mut rest_opts = common::opts(24, 20, 3, 10, 5);
    rest_opts.first_sample = 1;
    first.merge(&common::render_cpu(&scene, &rest_opts));
    for (a, b) in first.pixels.iter().zip(&one.pixels) {
        assert_eq!(a.n, b.n);
        assert!((a.mean() - b.mean()).abs().max_element() < 1e-9);
    }
}

/// The Sobol sampler too: a render continued from sample 3 and merged equals the whole render,
/// the replicas' statistics included (odd and even samples counted across the split).
#[test]
fn sobol_renders_continue_and_merge_exactly() {
    let scene = builtin("cornell").expect("built-in");
    let sobol = |spp, first_sample| rt_gpu::render::RenderOptions {
        sampler: rt_gpu::options::SamplerKind::Sobol,
        first_sample,
        ..common::opts(24, 20, spp, 10, 5)
    };
    let whole = common::render_cpu(&scene, &sobol(8, 0));
    let mut first = common::render_cpu(&scene, &sobol(3, 0));
    first.merge(&common::render_cpu(&scene, &sobol(5, 3)));
    for (a, b) in first.pixels.iter().zip(&whole.pixels) {
        assert_eq!((a.n, a.odd_n), (b.n, b.odd_n));
        assert!((a.mean() - b.mean()).abs().max_element() < 1e-9);
        assert!((a.odd_mean() - b.odd_mean()).abs().max_element() < 1e-9);
    }
}

/// `rt-gpu bench`'s rays per second come from the CPU's count of rays, which is exact: inside a
/// closed box every path of the naive integrator without roulette traces `max_depth` rays, and
/// towards an empty sky each traces one.
#[test]
fn the_cpu_counts_every_ray_it_traces() {
    use glam::Vec3;
    use rt_gpu::scene::{Background, Material, Shape};
    let (width, height, spp, max_depth) = (6, 5, 3, 4);
    let samples = (width * height * spp) as u64;
    let count = |scene: &rt_gpu::scene::Scene| {
        let opts = common::opts(width, height, spp, max_depth, 1);
        let flat = rt_gpu::scene::flat::FlatScene::new(scene, width, height).expect("valid");
        rt_gpu::cpu::render_counting_rays(&flat, &opts, &|| {}).1
    };
    let inside = common::scene(
        Vec3::splat(0.5),
        Vec3::new(0.5, 0.5, 0.0),
        60.0,
        Background::Constant(Vec3::ONE),
        vec![Material::lambertian(Vec3::splat(0.5))],
        vec![common::object(
            Shape::Cuboid {
                min: Vec3::ZERO,
                max: Vec3::ONE,
            },
            0,
        )],
    );
    assert_eq!(count(&inside), samples * max_depth as u64);
    // The box behind the camera: every camera ray escapes.
    let mut outside = inside.clone();
    outside.camera.look_from = Vec3::new(0.5, 0.5, 2.0);
    outside.camera.look_at = Vec3::new(0.5, 0.5, 3.0);
    assert_eq!(count(&outside), samples);
}

/// A whole render through the library's request (`render::request`, what the CLI runs) gives
/// the film a plain render of the same options does, writes nothing without an output, and
/// writes the image it returns with one.
#[test]
fn a_request_renders_the_plain_render_and_writes_its_output() {
    use rt_gpu::render::progressive::Outcome;
    use rt_gpu::render::request::{Hooks, Request};
    let scene = builtin("cornell").expect("built-in");
    let opts = common::opts(24, 20, 4, 10, 5);
    let dir = tempfile::tempdir().expect("temp dir");
    let request = |output: Option<std::path::PathBuf>| Request {
        scene: scene.clone(),
        scene_file: None,
        flat: rt_gpu::scene::flat::FlatScene::new(&scene, 24, 20).expect("valid"),
        opts,
        backend: rt_gpu::render::Backend::Cpu,
        gpu: Default::default(),
        budget: None,
        target_error: None,
        output,
        gamma: None,
        checkpoint: None,
        unspecialised: false,
        pass_seconds: None,
        denoise: false,
    };
    let hooks = Hooks {
        ready: &|| {},
        progress: &|_| {},
        stop: &|| false,
    };
    let finished = request(None).run(&hooks).expect("renders");
    assert_eq!(finished.outcome, Outcome::Complete);
    assert_eq!((finished.resumed_at, finished.done), (0, 4));
    assert!(finished.rendered.film == common::render_cpu(&scene, &opts));
    assert_eq!(std::fs::read_dir(dir.path()).expect("lists").count(), 0);
    let path = dir.path().join("box.pfm");
    let written = request(Some(path.clone())).run(&hooks).expect("renders");
    assert!(written.rendered.film == finished.rendered.film);
    assert!(std::fs::metadata(&path).expect("written").len() > 24 * 20 * 12);
}

/// The CPU's progress never goes back: rows finish on many threads, and a callback that takes
/// its time (as a Python one does, waiting for the interpreter) still sees the fractions in
/// order, ending at 1. (A count taken apart from its report once reached a Python callback
/// after a later one.)
#[test]
fn the_cpus_progress_arrives_in_order() {
    let scene = builtin("cornell").expect("built-in");
    let opts = common::opts(4, 400, 1, 4, 0);
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 4, 400).expect("valid");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .expect("a pool");
    for _ in 0..5 {
        let seen = std::sync::Mutex::new(Vec::new());
        pool.install(|| {
            rt_gpu::render::render(
                rt_gpu::render::Backend::Cpu,
                &Default::default(),
                &flat,
                &opts,
                &|f| {
                    std::thread::yield_now();
                    seen.lock().expect("not poisoned").push(f);
                },
            )
        })
        .expect("renders");
        let seen = seen.into_inner().expect("not poisoned");
        assert_eq!(seen.len(), 400);
        assert!(
            seen.windows(2).all(|w| w[0] < w[1]),
            "out of order: {seen:?}"
        );
        assert_eq!(seen.last(), Some(&1.0));
    }
}
