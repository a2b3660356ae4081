//! `rt-gpu bench`: million samples per second of each backend, side by side in one run.

use super::args::{BenchArgs, BenchRun};
use super::one_line;
use super::scenes::resolve_scene;
use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use rt_gpu::film::check_memory;
use rt_gpu::options::SamplerKind;
use rt_gpu::render::{Backend, GpuChoice, Integrator, RenderOptions, Rendered, Session};
use rt_gpu::scene::flat::FlatScene;
use std::io::Write;
use std::time::Instant;

/// Renders the same scene on each backend (and the GPU with both kernels) in one run, or on
/// those `--runs` names.
pub fn bench(args: &BenchArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let (scene, _) = resolve_scene(&args.scene, None)?;
    let loading = start.elapsed().as_secs_f64();
    let (width, height) = args.size;
    let start = Instant::now();
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    let flattening = start.elapsed().as_secs_f64();
    describe_geometry(&flat, loading, flattening)?;
    check_memory(width, height).map_err(anyhow::Error::msg)?;
    let opts = RenderOptions {
        width,
        height,
        spp: args.spp,
        first_sample: 0,
        seed: 1,
        max_depth: args.max_depth,
        integrator: args.integrator.into(),
        sampler: args.sampler.into(),
        roulette_depth: args.roulette_depth,
    };
    if args.stats {
        return traversal_stats(&flat, &opts);
    }
    let samples = width as f64 * height as f64 * args.spp as f64;
    say!(
        "{}: {width}x{height}, {} spp, max depth {}, {} integrator, {} sampler, roulette depth {}",
        scene.name,
        args.spp,
        args.max_depth,
        Integrator::from(args.integrator).name(),
        SamplerKind::from(args.sampler).name(),
        opts.roulette_depth
    )?;
    let mut rates = Vec::new();
    let mut failed = Vec::new();
    // The CPU counts its rays; the kernel, whose sample values and paths are the CPU's, is
    // credited with the same rays per sample (where the CPU runs: it runs first).
    let mut rays_per_sample = None;
    let runs = [
        (BenchRun::Cpu, "cpu", Backend::Cpu, false),
        (BenchRun::Gpu, "gpu specialised kernel", Backend::Gpu, false),
        (
            BenchRun::GpuEverything,
            "gpu everything-enabled kernel",
            Backend::Gpu,
            true,
        ),
    ];
    let runs: Vec<_> = runs
        .into_iter()
        .filter(|run| args.runs.contains(&run.0))
        .collect();
    for &(run, label, backend, everything) in &runs {
        let gpu = GpuChoice {
            adapter: args.adapter.clone(),
            everything,
        };
        match timed_render(backend, &gpu, &flat, &opts) {
            Ok((rendered, setup, seconds)) => {
                let rate = samples / seconds / 1e6;
                if let Some(rays) = rendered.rays {
                    rays_per_sample = Some(rays as f64 / samples);
                }
                let mrays = |rate: f64| {
                    rays_per_sample
                        .map(|r| format!(" ({:.1} Mrays/s)", rate * r))
                        .unwrap_or_default()
                };
                let gpu_time = rendered
                    .gpu_seconds
                    .map(|s| {
                        let rate = samples / s / 1e6;
                        format!(", {rate:.3} Msamples/s{} by GPU time", mrays(rate))
                    })
                    .unwrap_or_default();
                let longest = rendered
                    .longest_dispatch_seconds
                    .map(|d| format!(", longest dispatch {:.0} ms", d * 1e3))
                    .unwrap_or_default();
                // The film's host share: reading the accumulators back and converting them.
                let host = rendered
                    .host_seconds
                    .map(|h| {
                        let pixels = width as f64 * height as f64;
                        format!(
                            ", host {:.0} ms ({:.3} us a pixel)",
                            h * 1e3,
                            h * 1e6 / pixels
                        )
                    })
                    .unwrap_or_default();
                say!(
                    "  {label:<30} {:<28} {seconds:8.2} s {rate:8.3} Msamples/s{}{gpu_time}{longest}{host}; setup {setup:.2} s (device, kernel, warm-up)",
                    rendered.device,
                    mrays(rate)
                )?;
                rates.push((run, rate));
            }
            Err(e) => {
                say!("  {label:<30} failed: {}", one_line(&format!("{e:#}")))?;
                failed.push(label);
            }
        }
    }
    let rate = |run: BenchRun| rates.iter().find(|(r, _)| *r == run).map(|(_, r)| *r);
    if let Some(r) = rays_per_sample {
        say!("  rays per sample (the CPU's count: camera, bounce and shadow rays): {r:.2}")?;
    }
    if let (Some(gpu), Some(cpu)) = (rate(BenchRun::Gpu), rate(BenchRun::Cpu)) {
        say!("  gpu / cpu speed: {:.2}x", gpu / cpu)?;
    }
    if let (Some(special), Some(general)) = (rate(BenchRun::Gpu), rate(BenchRun::GpuEverything)) {
        say!(
            "  specialised / everything-enabled kernel speed: {:.2}x",
            special / general
        )?;
    }
    if !failed.is_empty() {
        bail!(
            "{} of {} runs failed ({})",
            failed.len(),
            runs.len(),
            failed.join(", ")
        );
    }
    Ok(())
}

/// The scene's geometry and what preparing it cost: reading it (mesh files included), flattening
/// it, building its BVH (timed again on its own), and its size on the GPU.
fn describe_geometry(flat: &FlatScene, loading: f64, flattening: f64) -> anyhow::Result<()> {
    let (triangles, primitives) = (flat.triangles.len(), flat.primitive_count());
    let placed = flat.placed_triangles();
    let instances = if flat.instances.is_empty() {
        String::new()
    } else {
        format!(
            "; {} mesh placements instanced, {placed} triangles placed",
            flat.instances.len()
        )
    };
    say!(
        "  scene: {primitives} primitives ({triangles} triangles, {} lights{instances}); read in {loading:.3} s, flattened in {flattening:.3} s",
        flat.lights.len()
    )?;
    if !flat.bvh.nodes.is_empty() {
        // Both levels, as flattening builds them: every primitive stored, and the instances.
        let mut rebuilt = flat.clone();
        let built = primitives + flat.instances.len();
        let start = Instant::now();
        rebuilt.build_bvh();
        let seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let kernel_nodes = rebuilt.kernel_bvh().nodes.len();
        let collapse = start.elapsed().as_secs_f64();
        let bvh = rebuilt.bvh;
        let geometry = rt_gpu::gpu::layout::geometry_bytes(flat);
        let per_triangle = if placed != triangles {
            format!(
                ", {:.1} bytes per triangle stored, {:.2} per triangle placed",
                geometry as f64 / triangles as f64,
                geometry as f64 / placed as f64
            )
        } else if triangles > 0 {
            format!(
                ", {:.1} bytes per triangle",
                geometry as f64 / triangles as f64
            )
        } else {
            String::new()
        };
        say!(
            "  bvh: built in {seconds:.3} s ({:.2} M primitives/s on {} threads), {} nodes, depth {}; the kernel's collapsed in {collapse:.3} s, {kernel_nodes} nodes; GPU geometry {:.1} MB{per_triangle}",
            built as f64 / seconds / 1e6,
            rayon::current_num_threads(),
            bvh.nodes.len(),
            bvh.depth,
            geometry as f64 / 1e6
        )?;
    }
    Ok(())
}

/// `bench --stats`: the traversal counts per ray, kernel and CPU side by side, for the backends
/// that walk the scene's BVH.
fn traversal_stats(flat: &FlatScene, opts: &RenderOptions) -> anyhow::Result<()> {
    use rt_gpu::accel::quantized::GROUP_NODE_LIMIT;
    use rt_gpu::cpu::traversal_stats::{KERNEL_NODE_BYTES, SIMD_LANES, cpu_traverses};
    // The kernel of a scene of a few shapes holds them as constants and tests them all.
    #[cfg(feature = "gpu")]
    let kernel_traverses = rt_gpu::gpu::Features::of(flat).bvh;
    #[cfg(not(feature = "gpu"))]
    let kernel_traverses = !flat.bvh.nodes.is_empty();
    let cpu_traverses = cpu_traverses(flat);
    if !kernel_traverses {
        say!(
            "  kernel: no traversal (the scene's primitives are constants in its kernel, all tested)"
        )?;
    }
    if !cpu_traverses {
        say!("  cpu: no traversal (the scene's few shapes are tested in turn)")?;
    }
    if !(kernel_traverses || cpu_traverses) {
        return Ok(());
    }
    let nodes = flat.kernel_bvh().nodes.len();
    if nodes > GROUP_NODE_LIMIT as usize {
        bail!(
            "the scene's BVH has {nodes} nodes, more than the kernel's traversal addresses ({GROUP_NODE_LIMIT}): count a smaller scene"
        );
    }
    let start = Instant::now();
    let Some(stats) = rt_gpu::cpu::traversal_stats::traversal_stats(flat, opts) else {
        return Ok(());
    };
    let seconds = start.elapsed().as_secs_f64();
    say!(
        "  traversal per ray, one camera ray through each of {}x{} pixels and a diffuse bounce from each hit ({seconds:.1} s; node bytes: interior nodes only):",
        opts.width,
        opts.height
    )?;
    say!(
        "  {:<8} {:<32} {:>8} {:>11} {:>8} {:>11} {:>10} {:>14} {:>11}",
        "rays",
        "traversal",
        "nodes",
        "node bytes",
        "leaves",
        "primitives",
        "instances",
        "stack mean/max",
        "iterations"
    )?;
    let width = rt_gpu::accel::wide::WIDTH;
    let wide_node = std::mem::size_of::<rt_gpu::accel::wide::WideNode>();
    let kernel_label = format!("kernel, 4-wide ({KERNEL_NODE_BYTES} B nodes)");
    let wide_label = format!("cpu, {width}-wide ({wide_node} B nodes)");
    let mut disagreements = 0;
    for (kind, s) in [("camera", &stats.camera), ("bounce", &stats.bounce)] {
        let rows = [
            (kernel_traverses, &kernel_label, &s.kernel),
            (cpu_traverses, &wide_label, &s.wide),
        ];
        for (_, label, c) in rows.iter().filter(|(walks, _, _)| *walks) {
            // Only the kernel's loop counts iterations (lavapipe's budget).
            let iterations = if c.iterations > 0 {
                format!("{:.1}", c.per_ray(c.iterations))
            } else {
                String::new()
            };
            let stack = format!("{:.1}/{}", c.per_ray(c.stack_depth_sum), c.stack_depth_max);
            say!(
                "  {kind:<8} {label:<32} {:>8.1} {:>11.0} {:>8.2} {:>11.2} {:>10.2} {stack:>14} {iterations:>11}",
                c.per_ray(c.nodes),
                c.per_ray(c.node_bytes),
                c.per_ray(c.leaves),
                c.per_ray(c.primitives),
                c.per_ray(c.instances),
            )?;
        }
        if kernel_traverses {
            let k = &s.kernel;
            say!(
                "  {kind:<8} kernel, each {SIMD_LANES} consecutive rays as long as their slowest (a SIMD group): {:.1} iterations per ray, {:.2}x the rays' own",
                k.per_ray(k.group_iterations),
                k.group_iterations as f64 / k.iterations.max(1) as f64
            )?;
        }
        if kernel_traverses && cpu_traverses {
            say!(
                "  {kind:<8} cpu / kernel: nodes {:.2}x, node bytes {:.2}x, primitives {:.2}x ({} rays)",
                s.wide.nodes as f64 / s.kernel.nodes.max(1) as f64,
                s.wide.node_bytes as f64 / s.kernel.node_bytes.max(1) as f64,
                s.wide.primitives as f64 / s.kernel.primitives.max(1) as f64,
                s.kernel.rays
            )?;
        }
        disagreements += s.disagreements;
    }
    if disagreements > 0 {
        say!(
            "  {disagreements} rays' closest hits differ from the renderer's{}",
            if flat.see_through {
                " (the counts take alpha-tested surfaces as opaque)"
            } else {
                ""
            }
        )?;
    }
    Ok(())
}

/// Renders with a progress bar on stderr; returns the result, the wall seconds of making the
/// backend ready (opening the device, compiling the kernel, a one-sample warm-up render) and of
/// the render itself, apart: on a fast GPU the first can be a hundred times the second. A GPU
/// render still uploads the scene's buffers itself, as every render does.
fn timed_render(
    backend: Backend,
    gpu: &GpuChoice,
    flat: &FlatScene,
    opts: &RenderOptions,
) -> anyhow::Result<(Rendered, f64, f64)> {
    let progress = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template(
            "{spinner} {elapsed_precise} [{bar:40}] {percent}%, eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let start = Instant::now();
    let session = Session::new(backend, gpu, flat, opts.integrator)?;
    // Drivers such as lavapipe compile a pipeline at its first dispatch: a one-sample render
    // first, so that the timed render is the steady state.
    let warm_up = RenderOptions { spp: 1, ..*opts };
    session.render(flat, &warm_up, &|_| {})?;
    let setup = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let result = session.render(flat, opts, &|f| progress.set_position((f * 1000.0) as u64));
    let seconds = start.elapsed().as_secs_f64();
    progress.finish_and_clear();
    Ok((result?, setup, seconds))
}
