//! The samplers: the kernel draws exactly the CPU's numbers, and the Sobol sampler is unbiased.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

#[cfg(feature = "gpu")]
use common::gpu::renderer;
use common::stats::{ALPHA, compare};
use rt_gpu::film::Film;
use rt_gpu::options::SamplerKind;
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::shared::sampler::Sampler;

/// The CPU twin of `draw_samples` in shaders/kernel.wgsl.
fn draw_samples(kind: SamplerKind, pixel: u32, sample: u32, seed: u32) -> [u32; 12] {
    let mut sampler = Sampler::for_sample(kind, pixel, sample, seed);
    let mut out = [0; 12];
    for (i, u) in out.iter_mut().enumerate() {
        if i == 4 || i == 7 {
            sampler.begin();
        }
        *u = sampler.next_f32().to_bits();
    }
    out
}

#[cfg(feature = "gpu")]
/// Bit for bit: every sampler, several seeds and sample indices (both replicas, large indices),
/// every number of the first groups, including a group's wrap-around.
#[test]
fn the_kernel_draws_the_cpus_sample_values() {
    let Some(gpu) = renderer() else { return };
    let flat = FlatScene::new(&builtin("cornell").expect("built-in"), 16, 8).expect("valid");
    for kind in [SamplerKind::Independent, SamplerKind::Sobol] {
        for seed in [0, 7] {
            for sample in [0, 1, 2, 3, 1000, 65_537, 4_000_000_000] {
                let opts = RenderOptions {
                    first_sample: sample,
                    seed,
                    sampler: kind,
                    ..RenderOptions::new(16, 8, 1, 10)
                };
                let gpu_values = gpu.draw_samples(&flat, &opts).expect("debug kernel runs");
                for (pixel, values) in gpu_values.iter().enumerate() {
                    let cpu = draw_samples(kind, pixel as u32, sample, seed);
                    assert_eq!(
                        *values, cpu,
                        "{kind:?} seed {seed} sample {sample} pixel {pixel}"
                    );
                }
            }
        }
    }
}

/// A film whose "samples" are the means of independent renders (one per seed): its variance of
/// the mean is that of the average of independent estimates, whatever each render's sampler.
fn mean_of_seeds(scene: &rt_gpu::scene::Scene, opts: &RenderOptions, seeds: u32) -> Film {
    let mut out = Film::new(opts.width, opts.height);
    for seed in 0..seeds {
        let film = common::render_cpu(
            scene,
            &RenderOptions {
                seed: 1000 + seed,
                ..*opts
            },
        );
        for (acc, p) in out.pixels.iter_mut().zip(&film.pixels) {
            acc.add(p.mean().as_vec3());
        }
    }
    out
}

/// The Sobol sampler's mean over independent scramblings (seeds) equals the independent
/// sampler's image: Welch z per pixel and per block, Sidak-corrected at family-wise ALPHA (see
/// tests/it/common/stats.rs). Negative control: the same comparison against the independent image
/// of a scene whose white albedo is 2% higher fails.
#[test]
fn sobol_is_unbiased() {
    let scene = builtin("cornell").expect("built-in");
    let (w, h) = (16, 16);
    let sobol = RenderOptions {
        sampler: SamplerKind::Sobol,
        ..common::nee_opts(w, h, 16, 10, 0)
    };
    let estimates = mean_of_seeds(&scene, &sobol, 64);
    let independent = common::nee_opts(w, h, 1024, 10, 1);
    let reference = common::render_cpu(&scene, &independent);
    let verdict = compare(&estimates, &reference);
    assert!(
        verdict.passed(),
        "sobol differs (alpha {ALPHA}): {verdict:?}"
    );

    let brighter = common::cornell_white_2_percent_brighter();
    let changed = common::render_cpu(&brighter, &independent);
    let control = compare(&estimates, &changed);
    assert!(
        !control.passed(),
        "a 2% albedo change went undetected: {control:?}"
    );
}

/// Sample i of a pixel belongs to replica i % 2: each replica is its own scrambled sequence,
/// so the two replicas' numbers for the same point index differ, and a replica's own points
/// stay stratified (its first 2^m values of a dimension fill every interval of length 2^-m).
#[test]
fn replicas_are_separately_scrambled_and_each_stratified() {
    let first = |sample| Sampler::for_sample(SamplerKind::Sobol, 5, sample, 3).next_f32();
    assert_ne!(first(0), first(1));
    for replica in 0..2 {
        let mut seen = [false; 64];
        for j in 0..64 {
            seen[(first(2 * j + replica) * 64.0) as usize] = true;
        }
        assert!(seen.iter().all(|&s| s), "replica {replica}");
    }
}

/// The mean over pixels and channels of the squared difference of two films' means.
fn mean_squared_difference(a: &Film, b: &Film) -> f64 {
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (p.mean() - q.mean()).length_squared())
        .sum();
    sum / (a.pixels.len() * 3) as f64
}

#[cfg(feature = "gpu")]
/// Under the Sobol sampler a render's own error estimate (from its two replicas) tracks its true
/// error within 1.5x, on both backends. The true error is measured without a reference: two
/// renders with independent seeds differ by E|A - B|^2 = MSE(A) + MSE(B). The Cornell box's
/// light edge, shadows and pixel footprints are where stratification pays. Negative control:
/// the per-sample variance, which ignores the stratification, is off by more than 1.5x.
#[test]
fn error_estimates_track_the_true_error_under_sobol() {
    let scene = builtin("cornell").expect("built-in");
    let opts = |seed| RenderOptions {
        sampler: SamplerKind::Sobol,
        ..common::nee_opts(48, 48, 64, 10, seed)
    };
    let gpu = renderer();
    let mut renders: Vec<(&str, Film, Film)> = vec![(
        "cpu",
        common::render_cpu(&scene, &opts(1)),
        common::render_cpu(&scene, &opts(2)),
    )];
    if let Some(gpu) = &gpu {
        let tuning = rt_gpu::gpu::Tuning::default();
        let render = |seed| common::gpu::render_gpu(gpu, &scene, &opts(seed), &tuning);
        renders.push(("gpu", render(1), render(2)));
    }
    for (backend, a, b) in renders {
        let measured = mean_squared_difference(&a, &b).sqrt();
        let estimated = (a.estimated_rmse().powi(2) + b.estimated_rmse().powi(2)).sqrt();
        let ratio = estimated / measured;
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "{backend}: estimated {estimated:.4e} vs measured {measured:.4e} (ratio {ratio:.3})"
        );
        let naive = |f: &Film| {
            f.pixels
                .iter()
                .map(|p| p.variance_of_mean().element_sum())
                .sum::<f64>()
                / (f.pixels.len() * 3) as f64
        };
        let naive_ratio = (naive(&a) + naive(&b)).sqrt() / measured;
        eprintln!(
            "{backend}: estimate / true error {ratio:.3}; per-sample variance's {naive_ratio:.3}"
        );
        assert!(
            !(1.0 / 1.5..=1.5).contains(&naive_ratio),
            "{backend}: the per-sample variance should misjudge a stratified render, ratio {naive_ratio:.3}"
        );
    }
}
