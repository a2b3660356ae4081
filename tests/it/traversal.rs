//! The CPU's model of the kernel's BVH traversal (`rt_gpu::cpu::traversal_stats`), whose counts
//! `rt-gpu bench --stats` reports as the GPU's traversal cost where no GPU is at hand: it must
//! be the kernel's walk step for step. Checked ray for ray against the kernel's own loop count
//! (exact, on camera rays and diffuse bounces of scenes with meshes, shapes and instances), and
//! against the renderer's closest hits.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

use rt_gpu::cpu::traversal_stats::{
    Counts, SIMD_LANES, count_ray, group_stats, kernel_traverse, stats_rays, traversal_stats,
};
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::Scene;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::flat::FlatScene;

fn scenes() -> Vec<(&'static str, Scene)> {
    let file = |path: &str| rt_gpu::scene::file::load(std::path::Path::new(path)).expect("loads");
    vec![
        ("showcase", builtin("showcase").expect("built in")),
        ("scenes/meshes.toml", file("scenes/meshes.toml")),
        ("scenes/knots.toml", file("scenes/knots.toml")),
    ]
}

/// Both traversals find every ray's closest hit where the renderer does, and the CPU's wide
/// walk (eight or four wide) reads fewer nodes than the kernel's four-wide one; the knots are
/// entered as instances.
#[test]
fn both_counted_traversals_find_the_renderers_hits() {
    for (name, scene) in scenes() {
        let flat = FlatScene::new(&scene, 40, 30).expect("valid scene");
        let opts = RenderOptions::new(40, 30, 1, 1);
        let stats = traversal_stats(&flat, &opts).expect("a BVH");
        for (kind, s) in [("camera", stats.camera), ("bounce", stats.bounce)] {
            eprintln!("{name} {kind}: {s:?}");
            assert_eq!(s.disagreements, 0, "{name} {kind}: closest hits differ");
            assert!(s.kernel.rays > 0 && s.kernel.rays == s.wide.rays);
            assert!(
                0 < s.wide.nodes && s.wide.nodes < s.kernel.nodes,
                "{name} {kind}: CPU {} nodes, kernel {}",
                s.wide.nodes,
                s.kernel.nodes
            );
            let instanced = name.contains("knots");
            assert_eq!(s.kernel.instances > 0, instanced, "{name} {kind}");
            // Diffuse bounces' SIMD groups diverge: they run longer than their rays would alone.
            if kind == "bounce" {
                let (own, grouped) = (s.kernel.iterations, s.kernel.group_iterations);
                assert!(grouped > own, "{name} {kind}: {own} {grouped}");
            }
        }
    }
}

/// The same ray in every lane: no divergence, a group's iterations are its lanes' own.
#[test]
fn groups_of_one_ray_do_not_diverge() {
    let flat = FlatScene::new(&builtin("showcase").expect("built in"), 40, 30).expect("valid");
    let opts = RenderOptions::new(40, 30, 1, 1);
    let ray = stats_rays(&flat, &opts)[1][7];
    let single = count_ray(&flat, &ray).kernel.iterations;
    let lanes = vec![ray; 3 * SIMD_LANES + 5];
    let stats = group_stats(&flat, &lanes);
    assert_eq!(stats.kernel.iterations, lanes.len() as u64 * single);
    assert_eq!(stats.kernel.group_iterations, stats.kernel.iterations);
}

/// One slow ray among fast ones: the group runs the slow one's iterations in every lane.
#[test]
fn a_group_runs_as_long_as_its_slowest_ray() {
    let flat = FlatScene::new(&builtin("showcase").expect("built in"), 40, 30).expect("valid");
    let opts = RenderOptions::new(40, 30, 1, 1);
    let bounces = &stats_rays(&flat, &opts)[1];
    let iterations = |r: &rt_gpu::shared::ray::Ray| count_ray(&flat, r).kernel.iterations;
    let fast = bounces.iter().min_by_key(|r| iterations(r)).expect("rays");
    let slow = bounces.iter().max_by_key(|r| iterations(r)).expect("rays");
    let (f, s) = (iterations(fast), iterations(slow));
    assert!(f < s, "{f} {s}");
    let mut lanes = vec![*fast; SIMD_LANES];
    lanes[3] = *slow;
    let stats = group_stats(&flat, &lanes);
    assert_eq!(stats.kernel.iterations, 7 * f + s);
    assert_eq!(stats.kernel.group_iterations, SIMD_LANES as u64 * s);
}

/// The kernel's `trace_rays` returns its traversal loop's count per ray: the model's must be
/// the same for every ray (any step the model takes that the kernel does not, or the reverse,
/// changes it), and so must whether the ray hits anything; on a hardware GPU, 0.1% of rays may
/// differ.
#[cfg(feature = "gpu")]
#[test]
fn the_model_counts_the_kernels_loop_ray_for_ray() {
    let Some(gpu) = common::gpu::renderer() else {
        return;
    };
    for (name, scene) in scenes() {
        let flat = FlatScene::new(&scene, 48, 36).expect("valid scene");
        let opts = RenderOptions::new(48, 36, 1, 1);
        for (kind, rays) in ["camera", "bounce"].iter().zip(stats_rays(&flat, &opts)) {
            let pairs: Vec<_> = rays.iter().map(|r| (r.origin, r.dir)).collect();
            let kernel = gpu.trace_rays(&flat, &pairs).expect("trace kernel runs");
            let mut differing = 0;
            for (ray, k) in rays.iter().zip(&kernel) {
                let mut counts = Counts::default();
                let mut closest = f32::INFINITY;
                kernel_traverse(&flat, ray, &mut closest, &mut counts);
                if counts.iterations != k.scattered as u64 || closest.is_finite() != (k.hit == 1) {
                    if differing < 5 {
                        eprintln!(
                            "{name} {kind}: {ray:?}: model {} iterations, hit {}; kernel {}, hit {}",
                            counts.iterations,
                            closest.is_finite(),
                            k.scattered,
                            k.hit
                        );
                    }
                    differing += 1;
                }
                assert_eq!(count_ray(&flat, ray).disagreements, 0);
            }
            eprintln!("{name} {kind}: {} rays, {differing} differ", rays.len());
            // Exact on lavapipe (the CI's), whose arithmetic is the CPU's; a hardware GPU's
            // fused multiply-adds may move a triangle's hit by an ulp, and with it a pruning
            // decision, on a few rays.
            let lavapipe = gpu.ctx.info.name.contains("llvmpipe");
            let allowed = if lavapipe { 0 } else { rays.len() / 1000 };
            assert!(
                differing <= allowed,
                "{name} {kind}: the model is not the kernel's walk ({differing} rays differ)"
            );
        }
    }
}
