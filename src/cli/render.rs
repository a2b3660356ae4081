//! Rendering a scene to an image, the default subcommand: the options checked into a [`Plan`]
//! before anything is opened, the outputs claimed, the passes run with a progress bar (and
//! checkpoints), the outputs written, and a one-line summary.

use super::args::{RenderArgs, RenderBackendArg};
use super::scenes::resolve_scene;
use super::shown_radiance;
use super::signals::{GRACEFUL, STOP_SIGNAL};
use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use rt_gpu::film::file as film_file;
use rt_gpu::film::output::ImageFormat;
use rt_gpu::render::progressive::{Outcome, Progress};
use rt_gpu::render::request::{Checkpoint, Finished, Hooks, Request};
use rt_gpu::render::{Backend, GpuChoice};
use rt_gpu::scene::Scene;
use rt_gpu::scene::flat::FlatScene;
use std::io::Write;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

/// A render as the command line asks for it, every option checked: the library's request, and
/// what the summary says of it.
struct Plan {
    request: Request,
    /// Why `--backend auto` chose the request's backend.
    backend_reason: Option<String>,
    /// Only some of the render's samples (--samples, --shard): a film file for `rt-gpu merge`.
    partial: bool,
}

pub fn run_render(args: &RenderArgs) -> anyhow::Result<()> {
    let plan = plan(args)?;
    if args.print_shader {
        return print_shader(&plan);
    }
    let progress = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:40}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let finished = plan.request.run(&Hooks {
        // From the first pass on, with a checkpoint, Ctrl-C ends the pass in flight and writes
        // it (before, it ends the process).
        ready: &|| GRACEFUL.store(plan.request.checkpoint.is_some(), Ordering::SeqCst),
        progress: &|p| show_progress(&progress, args.time, &p),
        stop: &|| STOP_SIGNAL.load(Ordering::SeqCst) != 0,
    });
    progress.finish_and_clear();
    let finished = finished?;
    let done = finished.done;
    print_summary(&plan, &finished);
    if let Some(target) = args.target_error {
        let target = super::shown_number(target);
        let film = &finished.rendered.film;
        let reached = rt_gpu::render::progressive::relative_error(film);
        let black = film.image_mean() == glam::DVec3::ZERO;
        if black && finished.outcome == Outcome::TargetReached {
            note!(
                "target error {target}: the image is exactly black at {done} spp (every sample 0), so it has no relative error to estimate: more samples would change nothing"
            );
        } else if finished.outcome == Outcome::TargetReached {
            note!(
                "target error {target} reached at {done} spp (estimated relative error {reached:.3e})"
            );
        } else if finished.outcome != Outcome::Stopped {
            note!(
                "target error {target} not reached: estimated relative error {reached:.3e} at {done} spp"
            );
        }
    }
    if finished.outcome == Outcome::Stopped {
        let signal = STOP_SIGNAL.load(Ordering::SeqCst);
        if plan.request.denoise {
            note!("stopped before denoising: the image written is the noisy one");
        }
        if let Some(c) = &plan.request.checkpoint {
            note!(
                "stopped at sample {done}: continue with the same command and --resume {}",
                c.path.display()
            );
        }
        std::process::exit(128 + signal);
    }
    Ok(())
}

/// The render the options ask for, or the first problem with them.
fn plan(args: &RenderArgs) -> anyhow::Result<Plan> {
    let Some(scene_arg) = &args.scene else {
        bail!("no scene given: try `rt-gpu cornell`, or `rt-gpu scenes` for the list");
    };
    args.options.check()?;
    let partial = args.samples.is_some() || args.shard.is_some();
    let gpu = args.options.gpu(args.unspecialised);
    let chosen = chosen_backend(args, partial);
    // `--backend auto` looks at the adapter while the scene loads: the drivers' start and the
    // load (mostly a large mesh's, on every core) overlap where the load runs on one core.
    std::thread::scope(|threads| {
        let look = chosen.is_none().then(|| {
            std::thread::Builder::new()
                .name("adapter look".into())
                .spawn_scoped(threads, || rt_gpu::render::look_for_adapter(&gpu))
        });
        let loaded = match &chosen {
            Some((Backend::Gpu, _)) => {
                rt_gpu::assets::image::with_device_check(rt_gpu::render::image_check(&gpu), || {
                    load(args, scene_arg, partial, &gpu, &chosen)
                })
            }
            _ => load(args, scene_arg, partial, &gpu, &chosen),
        };
        // Joined on an error too, so that a panic of the look is reported here; looked for on
        // this thread where none could be started.
        let look = look.map(|spawned| match spawned {
            Ok(thread) => thread
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p)),
            Err(_) => rt_gpu::render::look_for_adapter(&gpu),
        });
        let mut plan = loaded?;
        if let Some(look) = look {
            let auto = rt_gpu::render::auto_backend_seeing(&look, &gpu, &plan.request.flat);
            (plan.request.backend, plan.backend_reason) = (auto.backend, Some(auto.reason));
        }
        Ok(plan)
    })
}

/// The scene loaded and the options checked into a plan, on the backend `chosen` (when no
/// backend is chosen, the CPU until `--backend auto` decides).
fn load(
    args: &RenderArgs,
    scene_arg: &str,
    partial: bool,
    gpu: &GpuChoice,
    chosen: &Option<(Backend, Option<String>)>,
) -> anyhow::Result<Plan> {
    let (scene, scene_file) = resolve_scene(scene_arg, args.options.camera.as_deref())?;
    let scene = args.options.with_background(scene)?;
    if let Some(note) = args.options.note_for(&scene) {
        note!("{note}");
    }
    let range = sample_range(args)?;
    if let Some(x) = args.target_error {
        if !(x > 0.0 && x.is_finite()) {
            bail!(
                "--target-error must be a positive relative error such as 0.01, got {}",
                super::shown_number(x)
            );
        }
        if partial {
            bail!(
                "--target-error renders until the whole image reaches it: not with --samples or --shard"
            );
        }
    }
    let output = output_path(args, &scene, &range, partial)?;
    let checkpoint = checkpoint_path(args, &output)?;
    let (width, height) = args.options.size(&scene);
    if let Some(t) = args.time
        && !(t > 0.0 && t.is_finite())
    {
        bail!(
            "--time must be a positive number of seconds, got {}",
            super::shown_number(t)
        );
    }
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    let opts = args.options.render_options(&scene, range.clone());
    let (backend, backend_reason) = chosen.clone().unwrap_or((Backend::Cpu, None));
    Ok(Plan {
        request: Request {
            scene,
            scene_file,
            flat,
            opts,
            backend,
            gpu: gpu.clone(),
            budget: args.time,
            target_error: args.target_error,
            output: Some(output),
            gamma: args.gamma,
            checkpoint,
            unspecialised: args.unspecialised,
            pass_seconds: None,
            denoise: args.denoise,
        },
        backend_reason,
        partial,
    })
}

/// The backend the options decide without a look at the adapter and the scene, and why
/// (`--backend auto`'s reason); `None` where `--backend auto` must look.
fn chosen_backend(args: &RenderArgs, partial: bool) -> Option<(Backend, Option<String>)> {
    match args.options.backend {
        RenderBackendArg::Gpu => Some((Backend::Gpu, None)),
        RenderBackendArg::Cpu => Some((Backend::Cpu, None)),
        // An adapter asked for by name, the unspecialised kernel or its source: the GPU asked for.
        RenderBackendArg::Auto
            if args.options.adapter.is_some() || args.unspecialised || args.print_shader =>
        {
            Some((Backend::Gpu, None))
        }
        // Films merge only with films of one backend: shards on different machines must not
        // choose differently.
        RenderBackendArg::Auto if partial => Some((
            Backend::Gpu,
            Some("shards and sample ranges render on the kernel, so that every machine's films merge".into()),
        )),
        // A checkpoint continues on the backend it was made on.
        RenderBackendArg::Auto
            if let Some(Ok(Some(recorded))) = args.resume.as_deref().map(film_file::recorded_backend) =>
        {
            Some((recorded, Some("the backend the checkpoint was rendered on".into())))
        }
        RenderBackendArg::Auto => None,
    }
}

/// The sample indices a render covers: FIRST..END, or 0..spp.
fn sample_range(args: &RenderArgs) -> anyhow::Result<Range<u32>> {
    if let Some(range) = &args.samples {
        return Ok(range.clone());
    }
    let spp = match (args.spp, args.time.or(args.target_error)) {
        (Some(spp), _) => spp,
        // Unlimited: the budget or the target ends it.
        (None, Some(_)) => u32::MAX,
        (None, None) => 64,
    };
    Ok(match args.shard {
        Some((k, n)) => {
            let bound = |i: u32| (spp as u64 * i as u64 / n as u64) as u32;
            let range = bound(k)..bound(k + 1);
            if range.is_empty() {
                bail!("shard {k}/{n} of {spp} spp has no samples: use fewer shards");
            }
            range
        }
        None => 0..spp,
    })
}

/// Where the image goes (-o, or named after the scene), its format checked.
fn output_path(
    args: &RenderArgs,
    scene: &Scene,
    range: &Range<u32>,
    partial: bool,
) -> anyhow::Result<PathBuf> {
    let output = args.output.clone().unwrap_or_else(|| {
        PathBuf::from(if partial {
            format!("{}-samples-{}-{}.exr", scene.name, range.start, range.end)
        } else {
            format!("{}.png", scene.name)
        })
    });
    let format = ImageFormat::from_path(&output)?;
    if partial && format != ImageFormat::Exr {
        bail!(
            "--shard and --samples write a film file for `rt-gpu merge`: name an .exr output, not {}",
            output.display()
        );
    }
    Ok(output)
}

/// Where checkpoints go, if anywhere (--checkpoint, or --resume's file), and how often.
fn checkpoint_path(args: &RenderArgs, output: &Path) -> anyhow::Result<Option<Checkpoint>> {
    let checkpoint = args.checkpoint.clone().or_else(|| args.resume.clone());
    if let Some(c) = &checkpoint
        && ImageFormat::from_path(c).ok() != Some(ImageFormat::Exr)
    {
        bail!(
            "a checkpoint is a film file: name it .exr, not {}",
            c.display()
        );
    }
    if let Some(c) = &checkpoint
        && rt_gpu::film::output::resolved(c) == rt_gpu::film::output::resolved(output)
    {
        bail!(
            "the checkpoint {} and the output {} are the same file: name them apart",
            c.display(),
            output.display()
        );
    }
    if let Some(c) = &args.checkpoint
        && args.resume.is_none()
        && !args.force
        && std::fs::symlink_metadata(c).is_ok()
    {
        bail!(
            "{} exists: continue that render with --resume {0}, or add --force to start over and replace it",
            c.display()
        );
    }
    let checkpoint_every = args.checkpoint_every.unwrap_or(60.0);
    if !(checkpoint_every > 0.0 && checkpoint_every.is_finite()) {
        bail!(
            "--checkpoint-every must be a positive number of seconds, got {}",
            super::shown_number(checkpoint_every)
        );
    }
    if args.checkpoint_every.is_some() && checkpoint.is_none() {
        bail!("--checkpoint-every needs --checkpoint FILE (or --resume FILE)");
    }
    Ok(checkpoint.map(|path| Checkpoint {
        path,
        every: checkpoint_every,
        resume: args.resume.is_some(),
    }))
}

/// --print-shader: the kernel this render would run, on stdout.
fn print_shader(plan: &Plan) -> anyhow::Result<()> {
    let Request { flat, opts, .. } = &plan.request;
    let mut features = (plan.request.gpu.features(flat, opts.integrator)).for_render(flat, opts);
    // A BVH kernel counts its loops on a software adapter (lavapipe's budget): the adapter the
    // render would open decides; without one, a hardware GPU's kernel is shown.
    if features.bvh {
        let adapter = plan.request.gpu.adapter.as_deref();
        if let Ok(ctx) = rt_gpu::gpu::GpuContext::new(adapter) {
            features = rt_gpu::gpu::GpuRenderer::new(ctx).for_device(features);
        }
    }
    let source = rt_gpu::gpu::shader::compose(&features, flat).map_err(anyhow::Error::msg)?;
    std::io::stdout().lock().write_all(source.as_bytes())?;
    Ok(())
}

/// The progress bar at `p`: samples per pixel reached, of how many, and the time left.
fn show_progress(progress: &ProgressBar, budget: Option<f64>, p: &Progress) {
    let fraction = match (budget, p.total_spp) {
        (Some(budget), u32::MAX) => p.elapsed / budget,
        _ => p.spp / p.total_spp as f64,
    };
    progress.set_position((fraction.min(1.0) * 1000.0) as u64);
    let total = if p.total_spp == u32::MAX {
        String::new()
    } else {
        format!(" of {}", p.total_spp)
    };
    let eta = p
        .eta
        .map(|s| format!(", {s:.0} s left"))
        .unwrap_or_default();
    progress.set_message(format!("{:.0}{total} spp{eta}", p.spp.floor()));
}

/// The summary line on stderr, and the warnings and notes the render calls for.
fn print_summary(plan: &Plan, finished: &Finished) {
    let Plan { request, .. } = plan;
    let Finished {
        rendered,
        seconds,
        resumed_at,
        done,
        ..
    } = finished;
    let (seconds, resumed_at, done) = (*seconds, *resumed_at, *done);
    let first = request.opts.first_sample;
    let output = request.output.as_deref().unwrap_or(Path::new("-"));
    let film = &rendered.film;
    let (width, height) = (request.opts.width, request.opts.height);
    let spp = done - first;
    // This run's samples: a resumed render's earlier ones took no time here.
    let samples = width as f64 * height as f64 * (done - resumed_at) as f64;
    let gpu_time = match (rendered.gpu_seconds, rendered.longest_dispatch_seconds) {
        (Some(s), Some(d)) => format!(" ({s:.2} s on the GPU, longest dispatch {:.0} ms)", d * 1e3),
        (None, Some(d)) => format!(" (longest dispatch {:.0} ms)", d * 1e3),
        _ => String::new(),
    };
    let mut shown_samples = if first > 0 || plan.partial {
        format!("samples {first}..{done}")
    } else {
        format!("{spp} spp")
    };
    if resumed_at > first {
        shown_samples += &format!(" (resumed at {resumed_at})");
    }
    note!(
        "{}: {width}x{height}, {shown_samples}, {} [{}]{}, {}, {}, {seconds:.2} s{gpu_time}, {:.2} Msamples/s, mean radiance {}, estimated RMSE {:.3e} -> {}",
        request.scene.name,
        request.backend.name(),
        rendered.device,
        plan.backend_reason
            .as_ref()
            .map_or(String::new(), |why| format!(" (auto: {why})")),
        request.opts.integrator.name(),
        request.opts.sampler.name(),
        samples / seconds / 1e6,
        shown_radiance(film.image_mean()),
        film.estimated_rmse(),
        output.display()
    );
    if let Some(d) = &finished.denoised {
        note!(
            "denoised: albedo and normal buffers at {} spp in {:.2} s, then {:.2} s in {}",
            d.feature_spp,
            d.feature_seconds,
            d.denoise_seconds,
            d.denoiser
        );
    }
    if film.invalid_samples > 0 {
        note!(
            "warning: {} samples were NaN, infinite or negative, or on lavapipe needed more loop iterations than one dispatch allows, and were counted as black",
            film.invalid_samples
        );
    }
    if request.backend == Backend::Gpu
        && rendered.device.contains("llvmpipe")
        && !rt_gpu::gpu::Features::of(&request.flat).inline_scene
    {
        note!(
            "note: lavapipe traces scenes through their BVH 3-10x slower than `--backend cpu` does on the same cores (`--backend cpu`, or `auto` without --adapter, runs them there)"
        );
    }
}
