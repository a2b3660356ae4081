//! The `rt-gpu` command line.

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use rt_gpu::gpu::list_adapters;
use rt_gpu::output::{ImageFormat, write_image};
use rt_gpu::render::{Backend, GpuChoice, Integrator, RenderOptions, Rendered, render};
use rt_gpu::scene::builtin::{BUILTINS, builtin};
use rt_gpu::scene::file::{MAX_DEPTH_LIMIT, MAX_IMAGE_SIDE};
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::{Scene, file};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Most pixels one image may have (the film keeps 56 bytes of statistics per pixel).
const MAX_PIXELS: u64 = 1 << 26;

const EXAMPLES: &str = "\
Examples:
  rt-gpu cornell --spp 1000              render the Cornell box to cornell.png
  rt-gpu scenes/showcase.toml -o a.exr   render a scene file to linear EXR
  rt-gpu spheres --size 800x450 --backend cpu --seed 7 -o spheres.ppm
  rt-gpu cornell --print-shader          show the GPU kernel built for a scene
  rt-gpu scenes                          list the built-in scenes
  rt-gpu devices                         list GPU adapters
  rt-gpu bench                           compare backends' speed on the Cornell box
  rt-gpu converge cornell --budget 20    error against time for each backend";

/// A physically based path tracer: a WGSL compute kernel via wgpu, and a CPU reference
/// renderer that computes the same estimator.
#[derive(Parser)]
#[command(
    name = "rt-gpu",
    version,
    args_conflicts_with_subcommands = true,
    args_override_self = true,
    after_help = EXAMPLES
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    render: RenderArgs,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes (each also exists as a file in scenes/).
    Scenes {
        /// Write every built-in scene as DIR/<name>.toml, a starting point for your own.
        #[arg(long, value_name = "DIR")]
        export: Option<PathBuf>,
    },
    /// List the GPU adapters wgpu can see (pick one with --adapter).
    Devices,
    /// Measure million samples per second of each backend, side by side in one run.
    Bench(BenchArgs),
    /// Error against run time: ladders of renders at 1, 2, 4, ... spp per backend, compared with
    /// a reference; writes a table, DIR/converge.csv and a log-log plot (DIR/converge.svg, .png).
    Converge(ConvergeArgs),
}

#[derive(Args)]
struct ConvergeArgs {
    /// A built-in scene name or a scene file.
    scene: String,
    /// Reference image (.exr or .pfm, same size) [default: render one at high spp on the
    /// fastest backend and cache it in DIR].
    #[arg(long, value_name = "FILE")]
    reference: Option<PathBuf>,
    /// Samples per pixel of a rendered reference [default: 8x what the fastest series reaches].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: Option<u32>,
    /// Backends to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "gpu,cpu")]
    backends: Vec<Backend>,
    /// Integrators to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "naive,nee")]
    integrators: Vec<Integrator>,
    /// Russian roulette from this many path segments on (0: off).
    #[arg(long, value_name = "N", default_value_t = 0)]
    roulette_depth: u32,
    /// Seconds each series may spend on its ladder.
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0)]
    budget: f64,
    /// Image size WIDTHxHEIGHT [default: the scene's].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Path segments per sample [default: the scene's].
    #[arg(long, value_name = "D", value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH_LIMIT as i64))]
    max_depth: Option<u32>,
    /// RMSE the time-to-error comparison aims at [default: the CPU series' error at its largest spp].
    #[arg(long, value_name = "RMSE")]
    target_rmse: Option<f64>,
    /// GPU adapter (part of its name).
    #[arg(long)]
    adapter: Option<String>,
    /// Output directory.
    #[arg(short, long, value_name = "DIR", default_value = "converge")]
    output: PathBuf,
}

#[derive(Args)]
struct BenchArgs {
    /// A built-in scene name or a scene file.
    #[arg(default_value = "cornell")]
    scene: String,
    /// Samples per pixel of each measured render.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..))]
    spp: u32,
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    size: (u32, u32),
    #[arg(long, value_name = "D", default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH_LIMIT as i64))]
    max_depth: u32,
    #[arg(long, value_enum, default_value_t = Integrator::Nee)]
    integrator: Integrator,
    /// GPU adapter (part of its name).
    #[arg(long)]
    adapter: Option<String>,
}

#[derive(Args)]
struct RenderArgs {
    /// A built-in scene name (see `rt-gpu scenes`) or a scene file (.toml).
    scene: Option<String>,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    spp: u32,
    /// Image size WIDTHxHEIGHT [default: the scene's].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Random seed: the same scene, seed and backend give the same image.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Path segments per sample [default: the scene's].
    #[arg(long, value_name = "D", value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH_LIMIT as i64))]
    max_depth: Option<u32>,
    /// Where to render.
    #[arg(long, value_enum, default_value_t = Backend::Gpu)]
    backend: Backend,
    /// How paths find light: nee samples lights directly at diffuse hits (with multiple
    /// importance sampling); naive waits for paths to hit them (the original project's way).
    #[arg(long, value_enum, default_value_t = Integrator::Nee)]
    integrator: Integrator,
    /// Russian roulette from this many path segments on: paths end at random, in proportion to
    /// how little they can still carry, and survivors are reweighted (unbiased) [0: off].
    #[arg(long, value_name = "N", default_value_t = 0)]
    roulette_depth: u32,
    /// GPU adapter to use: part of its name, as `rt-gpu devices` lists them.
    #[arg(long, value_name = "NAME")]
    adapter: Option<String>,
    /// Print the WGSL kernel built for this scene and exit.
    #[arg(long)]
    print_shader: bool,
    /// Run the general everything-enabled GPU kernel instead of the scene's specialised one.
    #[arg(long, hide = true)]
    unspecialised: bool,
    /// Output image; the extension picks the format: .png and .ppm (8-bit, gamma 2), .exr and
    /// .pfm (linear radiance) [default: <scene>.png].
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected WIDTHxHEIGHT such as 512x512, got '{s}'");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    );
    if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(format!(
            "each side must be in 1..={MAX_IMAGE_SIDE}, got {w}x{h}"
        ));
    }
    if w as u64 * h as u64 > MAX_PIXELS {
        return Err(format!("{w}x{h} has more than {MAX_PIXELS} pixels"));
    }
    Ok((w, h))
}

fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa's Vulkan drivers print an "error:" line on every start without it.
        // SAFETY: nothing else runs yet: no other thread can read the environment concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Scenes { export }) => list_scenes(export.as_deref()),
        Some(Command::Devices) => list_devices(),
        Some(Command::Bench(args)) => bench(&args),
        Some(Command::Converge(args)) => converge(&args),
        None => run_render(&cli.render),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Renders with a progress bar on stderr; returns the result and wall seconds.
fn timed_render(
    backend: Backend,
    gpu: &GpuChoice,
    flat: &FlatScene,
    opts: &RenderOptions,
) -> anyhow::Result<(Rendered, f64)> {
    let progress = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template(
            "{spinner} {elapsed_precise} [{bar:40}] {percent}%, eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let start = Instant::now();
    let result = render(backend, gpu, flat, opts, &|f| {
        progress.set_position((f * 1000.0) as u64)
    });
    let seconds = start.elapsed().as_secs_f64();
    progress.finish_and_clear();
    Ok((result?, seconds))
}

/// A stable 64-bit FNV-1a digest, for cache keys that must not change between builds.
fn digest(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

fn converge(args: &ConvergeArgs) -> anyhow::Result<()> {
    let scene = resolve_scene(&args.scene)?;
    let (width, height) = args
        .size
        .unwrap_or((scene.defaults.width, scene.defaults.height));
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    if let Some(t) = args.target_rmse
        && !(t > 0.0 && t.is_finite())
    {
        bail!("--target-rmse must be a positive number, got {t}");
    }
    let options = rt_gpu::converge::ConvergeOptions {
        scene: flat,
        scene_name: scene.name.clone(),
        scene_digest: digest(&file::to_toml(&scene)),
        width,
        height,
        max_depth: args.max_depth.unwrap_or(scene.defaults.max_depth),
        backends: args.backends.clone(),
        integrators: args.integrators.clone(),
        roulette_depth: args.roulette_depth,
        budget: args.budget,
        reference: args.reference.clone(),
        reference_spp: args.reference_spp,
        out_dir: args.output.clone(),
        gpu: GpuChoice {
            adapter: args.adapter.clone(),
            everything: false,
        },
    };
    let report = rt_gpu::converge::run(&options)?;
    let target = report.target_rmse(args.target_rmse);
    print!("{}", report.table(target));
    let csv = args.output.join("converge.csv");
    rt_gpu::output::write_atomically(&csv, |out| {
        use std::io::Write;
        Ok(out.write_all(report.csv().as_bytes())?)
    })?;
    let title = format!(
        "{} {width}x{height}, max depth {}",
        scene.name, options.max_depth
    );
    match rt_gpu::plot::write_plot(&report, &title, &args.output.join("converge")) {
        Ok(()) => println!(
            "wrote {}, {} and {}",
            csv.display(),
            args.output.join("converge.svg").display(),
            args.output.join("converge.png").display()
        ),
        Err(e) => {
            println!("wrote {}", csv.display());
            eprintln!("warning: no plot: {e:#}");
        }
    }
    Ok(())
}

fn list_devices() -> anyhow::Result<()> {
    let adapters = list_adapters();
    if adapters.is_empty() {
        bail!("{}", rt_gpu::gpu::GpuError::NoAdapter);
    }
    for a in adapters {
        println!(
            "{:<40} {:?} {:?}, driver {} {}",
            a.name, a.backend, a.device_type, a.driver, a.driver_info
        );
    }
    Ok(())
}

/// Renders the same scene on each backend (and the GPU with both kernels) in one run.
fn bench(args: &BenchArgs) -> anyhow::Result<()> {
    let scene = resolve_scene(&args.scene)?;
    let (width, height) = args.size;
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    let opts = RenderOptions {
        width,
        height,
        spp: args.spp,
        first_sample: 0,
        seed: 1,
        max_depth: args.max_depth,
        integrator: args.integrator,
        roulette_depth: 0,
    };
    let samples = width as f64 * height as f64 * args.spp as f64;
    println!(
        "{}: {width}x{height}, {} spp, max depth {}, {} integrator",
        scene.name,
        args.spp,
        args.max_depth,
        args.integrator.name()
    );
    let mut rates = Vec::new();
    let runs = [
        ("cpu", Backend::Cpu, false),
        ("gpu specialised kernel", Backend::Gpu, false),
        ("gpu everything-enabled kernel", Backend::Gpu, true),
    ];
    for (label, backend, everything) in runs {
        let gpu = GpuChoice {
            adapter: args.adapter.clone(),
            everything,
        };
        match timed_render(backend, &gpu, &flat, &opts) {
            Ok((rendered, seconds)) => {
                let rate = samples / seconds / 1e6;
                let gpu_time = rendered
                    .gpu_seconds
                    .map(|s| format!(", {:.2} Msamples/s by GPU time", samples / s / 1e6))
                    .unwrap_or_default();
                let longest = rendered
                    .longest_dispatch_seconds
                    .map(|d| format!(", longest dispatch {:.0} ms", d * 1e3))
                    .unwrap_or_default();
                println!(
                    "  {label:<30} {:<28} {seconds:8.2} s {rate:8.3} Msamples/s{gpu_time}{longest}",
                    rendered.device
                );
                rates.push((label, rate));
            }
            Err(e) => println!("  {label:<30} unavailable: {e:#}"),
        }
    }
    let rate = |name: &str| rates.iter().find(|(l, _)| *l == name).map(|(_, r)| *r);
    if let (Some(gpu), Some(cpu)) = (rate(runs[1].0), rate(runs[0].0)) {
        println!("  gpu / cpu speed: {:.2}x", gpu / cpu);
    }
    if let (Some(special), Some(general)) = (rate(runs[1].0), rate(runs[2].0)) {
        println!(
            "  specialised / everything-enabled kernel speed: {:.2}x",
            special / general
        );
    }
    Ok(())
}

fn list_scenes(export: Option<&Path>) -> anyhow::Result<()> {
    for (name, about) in BUILTINS {
        println!("{name:<14} {about}");
        if let (Some(dir), Some(scene)) = (export, builtin(name)) {
            let path = dir.join(format!("{name}.toml"));
            let text = file::to_toml(&scene);
            rt_gpu::output::write_atomically(&path, |out| {
                use std::io::Write;
                Ok(out.write_all(text.as_bytes())?)
            })?;
        }
    }
    Ok(())
}

/// A built-in name, or else a scene file.
fn resolve_scene(arg: &str) -> anyhow::Result<Scene> {
    let path = Path::new(arg);
    if path.is_file() || arg.ends_with(".toml") {
        return file::load(path);
    }
    builtin(arg).with_context(|| {
        let names: Vec<&str> = BUILTINS.iter().map(|(n, _)| *n).collect();
        format!(
            "'{arg}' is neither a built-in scene ({}) nor a scene file",
            names.join(", ")
        )
    })
}

fn run_render(args: &RenderArgs) -> anyhow::Result<()> {
    let Some(scene_arg) = &args.scene else {
        bail!("no scene given: try `rt-gpu cornell`, or `rt-gpu scenes` for the list");
    };
    let scene = resolve_scene(scene_arg)?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}.png", scene.name)));
    // Fail on an unwritable destination now, not after a long render.
    ImageFormat::from_path(&output)?;
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        bail!("output directory {} does not exist", dir.display());
    }
    let (width, height) = args
        .size
        .unwrap_or((scene.defaults.width, scene.defaults.height));
    let opts = RenderOptions {
        width,
        height,
        spp: args.spp,
        first_sample: 0,
        seed: args.seed,
        max_depth: args.max_depth.unwrap_or(scene.defaults.max_depth),
        integrator: args.integrator,
        roulette_depth: args.roulette_depth,
    };
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    let gpu = GpuChoice {
        adapter: args.adapter.clone(),
        everything: args.unspecialised,
    };
    if args.print_shader {
        let features = gpu.features(&flat, opts.integrator);
        print!(
            "{}",
            rt_gpu::gpu::shader::compose(&features, &flat).map_err(anyhow::Error::msg)?
        );
        return Ok(());
    }

    let (rendered, seconds) = timed_render(args.backend, &gpu, &flat, &opts)?;
    let film = &rendered.film;
    write_image(&output, film)?;

    let samples = width as f64 * height as f64 * opts.spp as f64;
    let mean = film.image_mean();
    let gpu_time = match (rendered.gpu_seconds, rendered.longest_dispatch_seconds) {
        (Some(s), Some(d)) => format!(" ({s:.2} s on the GPU, longest dispatch {:.0} ms)", d * 1e3),
        (None, Some(d)) => format!(" (longest dispatch {:.0} ms)", d * 1e3),
        _ => String::new(),
    };
    eprintln!(
        "{}: {width}x{height}, {} spp, {} [{}], {}, {seconds:.2} s{gpu_time}, {:.2} Msamples/s, mean radiance ({:.5}, {:.5}, {:.5}) -> {}",
        scene.name,
        opts.spp,
        args.backend.name(),
        rendered.device,
        opts.integrator.name(),
        samples / seconds / 1e6,
        mean.x,
        mean.y,
        mean.z,
        output.display()
    );
    if film.invalid_samples > 0 {
        eprintln!(
            "warning: {} samples were NaN or infinite and were counted as black",
            film.invalid_samples
        );
    }
    Ok(())
}
