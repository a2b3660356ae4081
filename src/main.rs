//! The `rt-gpu` command line.

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use rt_gpu::film::{check_image_size, check_memory};
use rt_gpu::gpu::list_adapters;
use rt_gpu::options::SamplerKind;
use rt_gpu::output::{ImageFormat, PendingOutput, Transfer};
use rt_gpu::render::{Backend, GpuChoice, Integrator, RenderOptions, Rendered, Session, render};

/// Where to render (the CLI's names for [`Backend`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    /// The WGSL compute kernel through wgpu (any Vulkan, Metal or DX12 device, or Mesa lavapipe).
    Gpu,
    /// The CPU reference renderer (rayon over all cores).
    Cpu,
}

impl From<BackendArg> for Backend {
    fn from(arg: BackendArg) -> Self {
        match arg {
            BackendArg::Gpu => Backend::Gpu,
            BackendArg::Cpu => Backend::Cpu,
        }
    }
}

/// How paths find light (the CLI's names for [`Integrator`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum IntegratorArg {
    /// Paths find light only by hitting it (the original project's estimator).
    Naive,
    /// Next-event estimation: each diffuse hit and each scattering event in a medium also
    /// samples a light with a shadow ray, combined with BSDF (or phase function) sampling by
    /// multiple importance sampling (power heuristic).
    Nee,
}

/// Where a sample's random numbers come from (the CLI's names for [`SamplerKind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum SamplerArg {
    /// Independent uniform numbers: plain Monte Carlo, error falling as 1/sqrt(spp).
    Independent,
    /// Owen-scrambled Sobol points (Burley 2020), stratified in every 2D projection a path
    /// uses: edges, soft shadows and glossy reflections converge faster.
    Sobol,
}

impl From<SamplerArg> for SamplerKind {
    fn from(arg: SamplerArg) -> Self {
        match arg {
            SamplerArg::Independent => SamplerKind::Independent,
            SamplerArg::Sobol => SamplerKind::Sobol,
        }
    }
}

impl From<IntegratorArg> for Integrator {
    fn from(arg: IntegratorArg) -> Self {
        match arg {
            IntegratorArg::Naive => Integrator::Naive,
            IntegratorArg::Nee => Integrator::Nee,
        }
    }
}
use rt_gpu::film::Film;
use rt_gpu::film_file::{self, FilmMeta};
use rt_gpu::progressive::{Job, Outcome};
use rt_gpu::scene::builtin::{BUILTINS, builtin};
use rt_gpu::scene::file::MAX_DEPTH_LIMIT;
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::{Scene, file};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::time::Instant;

/// Prints a line to stdout. A closed pipe or a full device is an error to return with `?`,
/// never a panic (`println!` panics).
macro_rules! say {
    ($($arg:tt)*) => { writeln!(std::io::stdout().lock(), $($arg)*) };
}

/// Prints a line to stderr, ignoring failure: there is nowhere left to report it.
macro_rules! note {
    ($($arg:tt)*) => {{ let _ = writeln!(std::io::stderr().lock(), $($arg)*); }};
}

/// The subcommands, for a hint when one is given where a scene was expected.
const SUBCOMMANDS: &[&str] = &["scenes", "devices", "bench", "converge", "merge"];

const EXAMPLES: &str = "\
Examples:
  rt-gpu cornell --spp 1000              render the Cornell box to cornell.png
  rt-gpu scenes/showcase.toml -o a.exr   render a scene file to linear EXR
  rt-gpu spheres --size 800x450 --backend cpu --seed 7 -o spheres.ppm
  rt-gpu cornell --print-shader          show the GPU kernel built for a scene
  rt-gpu scenes                          list the built-in scenes
  rt-gpu devices                         list GPU adapters
  rt-gpu bench                           compare backends' speed on the Cornell box
  rt-gpu converge cornell --budget 20    error against time for each backend
  rt-gpu cornell --spp 100000 --checkpoint c.exr     a long render, saved every minute
  rt-gpu cornell --spp 100000 --resume c.exr         ... continued after a stop
  rt-gpu cornell --spp 4096 --shard 0/4 -o s0.exr    a quarter of the samples (one job of four)
  rt-gpu merge s0.exr s1.exr s2.exr s3.exr -o c.png  the four quarters as one image";

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
        /// With --export: overwrite scene files that already exist in DIR.
        #[arg(long, requires = "export")]
        force: bool,
    },
    /// List the GPU adapters wgpu can see (pick one with --adapter).
    Devices,
    /// Measure million samples per second of each backend, side by side in one run.
    Bench(BenchArgs),
    /// Combine film files (from --shard, --samples or --checkpoint) of one scene and options into
    /// one image, or one film file with -o FILE.exr: bit-identical to rendering all their samples
    /// at once.
    Merge(MergeArgs),
    /// Error against run time: ladders of renders at 1, 2, 4, ... spp per backend, compared with
    /// a reference; writes a table, DIR/converge.csv and a log-log plot (DIR/converge.svg, .png).
    Converge(ConvergeArgs),
}

#[derive(Args)]
struct MergeArgs {
    /// Film files to combine: disjoint sample ranges of the same render.
    #[arg(required = true, value_name = "FILM")]
    films: Vec<PathBuf>,
    /// Output image or film file (.exr); the extension picks the format, as for a render.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// How .png and .ppm encode light: `srgb`, or a gamma such as 2 [default: srgb for .png, 2
    /// for .ppm].
    #[arg(long, value_name = "srgb|G", value_parser = Transfer::parse)]
    gamma: Option<Transfer>,
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
    backends: Vec<BackendArg>,
    /// Integrators to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "naive,nee")]
    integrators: Vec<IntegratorArg>,
    /// Samplers to compare, comma-separated: a series per backend, integrator and sampler.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "sobol")]
    samplers: Vec<SamplerArg>,
    /// Russian roulette from this many path segments on (0: off).
    #[arg(long, value_name = "N", default_value_t = rt_gpu::options::DEFAULT_ROULETTE_DEPTH)]
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
    #[arg(long, value_enum, default_value_t = IntegratorArg::Nee)]
    integrator: IntegratorArg,
    #[arg(long, value_enum, default_value_t = SamplerArg::Sobol)]
    sampler: SamplerArg,
    /// Russian roulette from this many path segments on, as a render's (0: off).
    #[arg(long, value_name = "N", default_value_t = rt_gpu::options::DEFAULT_ROULETTE_DEPTH)]
    roulette_depth: u32,
    /// GPU adapter (part of its name).
    #[arg(long)]
    adapter: Option<String>,
}

#[derive(Args)]
struct RenderArgs {
    /// A built-in scene name (see `rt-gpu scenes`) or a scene file (.toml).
    scene: Option<String>,
    /// Samples per pixel [default: 64, or unlimited with --time].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Render until this many seconds are spent, in whole passes over the image, then write the
    /// image; with --spp too, whichever comes first. The summary says how many samples per pixel
    /// were reached.
    #[arg(long, value_name = "SECONDS")]
    time: Option<f64>,
    /// Write the render's state to FILE (a film file, .exr) every --checkpoint-every seconds, at
    /// the end, and when interrupted (Ctrl-C or SIGTERM finish the pass in flight, write it and
    /// the image so far, and exit non-zero); --resume FILE continues it.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints [default: 60].
    #[arg(long, value_name = "SECONDS")]
    checkpoint_every: Option<f64>,
    /// Continue the render saved in FILE by --checkpoint (same scene and options; --spp or
    /// --time may grow), checkpointing to FILE again [default: where --checkpoint says]. The
    /// image is bit-identical to one uninterrupted render.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Start over although the --checkpoint FILE exists, replacing its samples (without it,
    /// an existing checkpoint is refused: continue it with --resume FILE).
    #[arg(long)]
    force: bool,
    /// Render only sample indices FIRST..END of every pixel (END exclusive) and write a film
    /// file (-o FILE.exr) for `rt-gpu merge`.
    #[arg(long, value_name = "FIRST..END", value_parser = film_file::parse_range, conflicts_with_all = ["shard", "spp", "time"])]
    samples: Option<std::ops::Range<u32>>,
    /// Render the K-th of N equal parts of --spp's samples (K from 0, as Slurm's
    /// $SLURM_ARRAY_TASK_ID) and write a film file for `rt-gpu merge`.
    #[arg(long, value_name = "K/N", value_parser = parse_shard, requires = "spp", conflicts_with = "time")]
    shard: Option<(u32, u32)>,
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
    #[arg(long, value_enum, default_value_t = BackendArg::Gpu)]
    backend: BackendArg,
    /// How paths find light: nee samples lights directly at diffuse hits (with multiple
    /// importance sampling); naive waits for paths to hit them (the original project's way).
    #[arg(long, value_enum, default_value_t = IntegratorArg::Nee)]
    integrator: IntegratorArg,
    /// Where each sample's random numbers come from: sobol stratifies them (lower error for
    /// the same samples); independent is plain Monte Carlo.
    #[arg(long, value_enum, default_value_t = SamplerArg::Sobol)]
    sampler: SamplerArg,
    /// Russian roulette from this many path segments on: paths end at random, in proportion to
    /// how little they can still carry, and survivors are reweighted (unbiased), as in Mitsuba 3
    /// and pbrt-v4; 0: off.
    #[arg(long, value_name = "N", default_value_t = rt_gpu::options::DEFAULT_ROULETTE_DEPTH)]
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
    /// Output image; the extension picks the format: .png (8-bit sRGB) and .ppm (8-bit, gamma 2,
    /// as the original project), .exr and .pfm (linear radiance) [default: <scene>.png].
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// How .png and .ppm encode light: `srgb`, or a gamma such as 2 (the original project's
    /// look) [default: srgb for .png, 2 for .ppm].
    #[arg(long, value_name = "srgb|G", value_parser = Transfer::parse)]
    gamma: Option<Transfer>,
}

fn parse_shard(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected K/N such as 0/4 (the first of 4 shards), got '{s}'");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (u32, u32) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if n == 0 || k >= n {
        return Err(format!(
            "shard {k}/{n} does not exist: K counts from 0 to N-1"
        ));
    }
    Ok((k, n))
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected WIDTHxHEIGHT such as 512x512, got '{s}'");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    );
    check_image_size(w, h)?;
    Ok((w, h))
}

fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa's Vulkan drivers print an "error:" line on every start without it.
        // SAFETY: nothing else runs yet: no other thread can read the environment concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    // A bug is one line too, never a backtrace.
    std::panic::set_hook(Box::new(|info| {
        if rt_gpu::panics_are_quiet() {
            return;
        }
        note!(
            "error: internal error, a bug in rt-gpu (please report it): {}",
            one_line(&info.to_string())
        )
    }));
    install_signal_handler();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Scenes { export, force }) => list_scenes(export.as_deref(), force),
        Some(Command::Devices) => list_devices(),
        Some(Command::Bench(args)) => bench(&args),
        Some(Command::Converge(args)) => converge(&args),
        Some(Command::Merge(args)) => merge(&args),
        None => run_render(&cli.render),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`rt-gpu scenes | head -1`): stop quietly, as `cat` would.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {}", one_line(&format!("{e:#}")));
            ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Most characters of an error message: a scene can hold names megabytes long.
const MAX_MESSAGE_CHARS: usize = 600;

/// `message` on one line, its middle cut out if it is too long.
fn one_line(message: &str) -> String {
    let flat = message.replace(['\n', '\r'], " ");
    let count = flat.chars().count();
    if count <= MAX_MESSAGE_CHARS {
        return flat;
    }
    let keep = MAX_MESSAGE_CHARS / 2;
    let head: String = flat.chars().take(keep).collect();
    let tail: String = flat.chars().skip(count - keep).collect();
    format!("{head} [... {} characters ...] {tail}", count - 2 * keep)
}

/// Set while a render can stop gracefully (it checkpoints): a first signal then asks it to stop.
static GRACEFUL: AtomicBool = AtomicBool::new(false);
/// The signal that asked a graceful render to stop (0: none).
static STOP_SIGNAL: AtomicI32 = AtomicI32::new(0);

/// On SIGINT, SIGTERM or SIGHUP: during a checkpointing render, the first asks it to finish the
/// pass in flight, write the checkpoint and the image so far, and exit with 128 + the signal.
/// Otherwise (or at a second signal) remove temporary output files (a killed process runs no
/// destructors, and they can be as large as the image) and exit with 128 + the signal.
#[cfg(unix)]
fn install_signal_handler() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        for signal in signals.forever() {
            if GRACEFUL.load(Ordering::SeqCst)
                && STOP_SIGNAL
                    .compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst)
                    .is_ok()
            {
                note!(
                    "\nstopping: finishing this pass (at most 10 s), then writing the checkpoint and the image (signal again to quit at once)"
                );
                continue;
            }
            rt_gpu::output::remove_pending_files();
            if GRACEFUL.load(Ordering::SeqCst) {
                note!("\ninterrupted: the last checkpoint is kept");
            } else {
                note!("\ninterrupted: nothing was written");
            }
            std::process::exit(128 + signal);
        }
    });
}

#[cfg(not(unix))]
fn install_signal_handler() {}

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

/// A mean radiance as the summary line shows it: five decimals where that shows five
/// significant digits' worth, else in scientific notation (a dim or bright scene is not 0.00000).
fn shown_radiance(mean: glam::DVec3) -> String {
    let one = |x: f64| {
        if x == 0.0 || (1e-2..1e6).contains(&x.abs()) {
            format!("{x:.5}")
        } else {
            format!("{x:.4e}")
        }
    };
    format!("({}, {}, {})", one(mean.x), one(mean.y), one(mean.z))
}

/// The convergence report's progress as a bar per task on stderr.
#[derive(Default)]
struct ConvergeBars(std::sync::Mutex<Option<ProgressBar>>);

impl rt_gpu::converge::Progress for ConvergeBars {
    fn start(&self, task: &str) {
        let bar = ProgressBar::new(1000).with_style(
            ProgressStyle::with_template("{msg} [{bar:30}] {percent}% {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(task.to_string());
        *self.0.lock().unwrap_or_else(|p| p.into_inner()) = Some(bar);
    }

    fn advance(&self, fraction: f64) {
        if let Some(bar) = &*self.0.lock().unwrap_or_else(|p| p.into_inner()) {
            bar.set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
        }
    }

    fn finish(&self) {
        if let Some(bar) = self.0.lock().unwrap_or_else(|p| p.into_inner()).take() {
            bar.finish_and_clear();
        }
    }
}

fn converge(args: &ConvergeArgs) -> anyhow::Result<()> {
    if args.reference.is_some() && args.reference_spp.is_some() {
        bail!(
            "--reference-spp sets the spp of a rendered reference; it has no effect with --reference"
        );
    }
    let (scene, _) = resolve_scene(&args.scene)?;
    let (width, height) = args
        .size
        .unwrap_or((scene.defaults.width, scene.defaults.height));
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    check_memory(width, height).map_err(anyhow::Error::msg)?;
    if let Some(t) = args.target_rmse
        && !(t > 0.0 && t.is_finite())
    {
        bail!("--target-rmse must be a positive number, got {t}");
    }
    let options = rt_gpu::converge::ConvergeOptions {
        scene: flat,
        scene_name: scene.name.clone(),
        scene_digest: file::digest(&scene),
        width,
        height,
        max_depth: args.max_depth.unwrap_or(scene.defaults.max_depth),
        backends: args.backends.iter().map(|&b| b.into()).collect(),
        integrators: args.integrators.iter().map(|&i| i.into()).collect(),
        samplers: args.samplers.iter().map(|&s| s.into()).collect(),
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
    let report = rt_gpu::converge::run_with(&options, &ConvergeBars::default())?;
    let target = report.target_rmse(args.target_rmse);
    write!(std::io::stdout().lock(), "{}", report.table(target))?;
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
        Ok(()) => say!(
            "wrote {}, {} and {}",
            csv.display(),
            args.output.join("converge.svg").display(),
            args.output.join("converge.png").display()
        )?,
        Err(e) => {
            say!("wrote {}", csv.display())?;
            note!("warning: no plot: {}", one_line(&format!("{e:#}")));
        }
    }
    Ok(())
}

fn list_devices() -> anyhow::Result<()> {
    let adapters = list_adapters();
    if adapters.is_empty() {
        bail!("{}", rt_gpu::gpu::context::no_adapter_error());
    }
    for a in adapters {
        say!(
            "{:<40} {:?} {:?}, driver {} {}",
            a.name,
            a.backend,
            a.device_type,
            a.driver,
            a.driver_info
        )?;
    }
    Ok(())
}

/// Renders the same scene on each backend (and the GPU with both kernels) in one run.
fn bench(args: &BenchArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let (scene, _) = resolve_scene(&args.scene)?;
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
                    .map(|s| format!(", {:.3} Msamples/s by GPU time", samples / s / 1e6))
                    .unwrap_or_default();
                let longest = rendered
                    .longest_dispatch_seconds
                    .map(|d| format!(", longest dispatch {:.0} ms", d * 1e3))
                    .unwrap_or_default();
                say!(
                    "  {label:<30} {:<28} {seconds:8.2} s {rate:8.3} Msamples/s{gpu_time}{longest}",
                    rendered.device
                )?;
                rates.push((label, rate));
            }
            Err(e) => {
                say!("  {label:<30} failed: {}", one_line(&format!("{e:#}")))?;
                failed.push(label);
            }
        }
    }
    let rate = |name: &str| rates.iter().find(|(l, _)| *l == name).map(|(_, r)| *r);
    if let (Some(gpu), Some(cpu)) = (rate(runs[1].0), rate(runs[0].0)) {
        say!("  gpu / cpu speed: {:.2}x", gpu / cpu)?;
    }
    if let (Some(special), Some(general)) = (rate(runs[1].0), rate(runs[2].0)) {
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
            "  bvh: built in {seconds:.3} s ({:.2} M primitives/s on {} threads), {} nodes, depth {}; GPU geometry {:.1} MB{per_triangle}",
            built as f64 / seconds / 1e6,
            rayon::current_num_threads(),
            bvh.nodes.len(),
            bvh.depth,
            geometry as f64 / 1e6
        )?;
    }
    Ok(())
}

fn list_scenes(export: Option<&Path>, force: bool) -> anyhow::Result<()> {
    if let Some(dir) = export
        && !force
    {
        // A user's edited copy must not be replaced without asking.
        let existing: Vec<String> = BUILTINS
            .iter()
            .map(|(name, _)| format!("{name}.toml"))
            .filter(|file| dir.join(file).exists())
            .collect();
        if !existing.is_empty() {
            bail!(
                "{} already holds {}: add --force to overwrite",
                dir.display(),
                existing.join(", ")
            );
        }
    }
    for (name, about) in BUILTINS {
        say!("{name:<14} {about}")?;
        if let (Some(dir), Some(text)) = (export, rt_gpu::scene::builtin::source(name)) {
            let path = dir.join(format!("{name}.toml"));
            rt_gpu::output::write_atomically(&path, |out| Ok(out.write_all(text.as_bytes())?))?;
        }
    }
    Ok(())
}

/// A scene file, or else a built-in scene; with the file's path when it is one.
fn resolve_scene(arg: &str) -> anyhow::Result<(Scene, Option<PathBuf>)> {
    let path = Path::new(arg);
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if let Some(ext @ ("glb" | "gltf" | "obj")) = extension.as_deref() {
        bail!(
            "{arg} is a mesh ({ext}), not a scene: place it in a scene file as `[[object]] mesh = {{ file = \"{arg}\" }}` (see scenes/README.md, e.g. scenes/meshes.toml)"
        );
    }
    if path.is_file() || arg.ends_with(".toml") {
        if builtin(arg).is_some() {
            note!(
                "note: rendering the scene file {arg}, not the built-in scene '{arg}' (rename the file to use the built-in)"
            );
        }
        return Ok((file::load(path)?, Some(path.to_path_buf())));
    }
    let scene = builtin(arg).with_context(|| {
        let names: Vec<&str> = BUILTINS.iter().map(|(n, _)| *n).collect();
        let hint = if SUBCOMMANDS.contains(&arg) {
            format!(": `{arg}` is a subcommand, so it must come before any option (`rt-gpu {arg} --help`)")
        } else {
            String::new()
        };
        format!(
            "'{arg}' is neither a built-in scene ({}) nor a scene file{hint}",
            names.join(", ")
        )
    })?;
    Ok((scene, None))
}

/// The sample indices a render covers: FIRST..END, or 0..spp.
fn sample_range(args: &RenderArgs) -> anyhow::Result<std::ops::Range<u32>> {
    if let Some(range) = &args.samples {
        return Ok(range.clone());
    }
    let spp = match (args.spp, args.time) {
        (Some(spp), _) => spp,
        // Unlimited: the budget ends it.
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

fn run_render(args: &RenderArgs) -> anyhow::Result<()> {
    let Some(scene_arg) = &args.scene else {
        bail!("no scene given: try `rt-gpu cornell`, or `rt-gpu scenes` for the list");
    };
    let backend = Backend::from(args.backend);
    if args.adapter.is_some() && backend == Backend::Cpu {
        bail!("--adapter picks a GPU, but --backend cpu renders on the CPU: drop one of them");
    }
    let (scene, scene_file) = resolve_scene(scene_arg)?;
    let range = sample_range(args)?;
    let partial = args.samples.is_some() || args.shard.is_some();
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
        && rt_gpu::output::resolved(c) == rt_gpu::output::resolved(&output)
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
        bail!("--checkpoint-every must be a positive number of seconds, got {checkpoint_every}");
    }
    if args.checkpoint_every.is_some() && checkpoint.is_none() {
        bail!("--checkpoint-every needs --checkpoint FILE (or --resume FILE)");
    }
    let (width, height) = args
        .size
        .unwrap_or((scene.defaults.width, scene.defaults.height));
    if let Some(t) = args.time
        && !(t > 0.0 && t.is_finite())
    {
        bail!("--time must be a positive number of seconds, got {t}");
    }
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    let opts = RenderOptions {
        width,
        height,
        spp: range.end - range.start,
        first_sample: range.start,
        seed: args.seed,
        max_depth: args.max_depth.unwrap_or(scene.defaults.max_depth),
        integrator: args.integrator.into(),
        sampler: args.sampler.into(),
        roulette_depth: args.roulette_depth,
    };
    let gpu = GpuChoice {
        adapter: args.adapter.clone(),
        everything: args.unspecialised,
    };
    if args.print_shader {
        let features = gpu
            .features(&flat, opts.integrator)
            .for_render(&flat, &opts);
        let source = rt_gpu::gpu::shader::compose(&features, &flat).map_err(anyhow::Error::msg)?;
        std::io::stdout().lock().write_all(source.as_bytes())?;
        return Ok(());
    }
    check_memory(width, height).map_err(anyhow::Error::msg)?;
    // Only film files carry the identity (digesting a scene of many objects takes a while).
    let writes_film = checkpoint.is_some() || format == ImageFormat::Exr;
    let identity = if writes_film {
        film_file::identity(file::digest(&scene), backend, &opts, args.unspecialised)
    } else {
        String::new()
    };
    // Held until the render ends: a second render checkpointing to the same file is refused.
    let checkpoint_lock = match &checkpoint {
        Some(c) => Some(rt_gpu::output::FileLock::acquire(c)?),
        None => None,
    };
    let resume = match &args.resume {
        Some(path) => Some(resume_from(path, &identity, &range)?),
        None => None,
    };
    // Claimed now, so an unwritable destination fails before a long render, not after it.
    let inputs: Vec<&Path> = scene_file.iter().map(|p| p.as_path()).collect();
    let pending = PendingOutput::claim(&output, &inputs)?;
    if let Some(c) = &checkpoint {
        // Fail now, not at the first checkpoint a minute in.
        drop(PendingOutput::claim(c, &inputs)?);
    }

    let resumed_at = resume.as_ref().map_or(range.start, |(_, done)| *done);
    let session = Session::new(backend, &gpu, &flat, opts.integrator)?;
    let device = session.device();
    let meta = |done: u32| FilmMeta {
        identity: identity.clone(),
        samples: std::iter::once(range.start..done).collect(),
        device: device.clone(),
    };
    let progress = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:40}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let job = Job {
        session: &session,
        scene: &flat,
        opts,
        budget: args.time,
        pass_seconds: pass_seconds(checkpoint.is_some().then_some(checkpoint_every), args.time),
    };
    let mut last_checkpoint = Instant::now();
    let checkpoint_failure: std::cell::RefCell<Option<anyhow::Error>> = Default::default();
    let mut checkpoints = CheckpointWriter {
        path: checkpoint.clone(),
        writing: None,
    };
    GRACEFUL.store(checkpoint.is_some(), Ordering::SeqCst);
    let start = Instant::now();
    let (rendered, outcome) = job.run(
        resume,
        &mut |film, done| {
            // A checkpoint that cannot be written stops the render; the image so far is still
            // written before the error is reported.
            if last_checkpoint.elapsed().as_secs_f64() >= checkpoint_every
                && checkpoint_failure.borrow().is_none()
            {
                if let Err(e) = checkpoints.write(film, meta(done)) {
                    *checkpoint_failure.borrow_mut() = Some(e);
                }
                last_checkpoint = Instant::now();
            }
            Ok(())
        },
        &|p| {
            let fraction = match (args.time, p.total_spp) {
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
        },
        &|| STOP_SIGNAL.load(Ordering::SeqCst) != 0 || checkpoint_failure.borrow().is_some(),
    )?;
    let seconds = start.elapsed().as_secs_f64();
    progress.finish_and_clear();
    let film = &rendered.film;
    let spp = film.pixels.first().map_or(0, |p| p.n) as u32;
    let done = range.start + spp;
    // The last checkpoint and an .exr output hold the same film file: encoded once (a 512x512
    // film takes about 0.3 s), written twice.
    let output_is_film = format == ImageFormat::Exr;
    let encoded = if checkpoints.path.is_some() || output_is_film {
        Some(film_file::encode(film, Some(&meta(done)))?)
    } else {
        None
    };
    let checkpointed = match checkpoint_failure.into_inner() {
        Some(e) => Err(e),
        None => checkpoints.finish(encoded.as_deref()),
    };
    match &encoded {
        Some(bytes) if output_is_film => pending.commit(bytes)?,
        _ => pending.commit_image(film, args.gamma)?,
    }
    checkpointed.with_context(|| {
        format!(
            "the image was written to {}, but not the checkpoint",
            output.display()
        )
    })?;

    // This run's samples: a resumed render's earlier ones took no time here.
    let samples = width as f64 * height as f64 * (done - resumed_at) as f64;
    let mean = film.image_mean();
    let gpu_time = match (rendered.gpu_seconds, rendered.longest_dispatch_seconds) {
        (Some(s), Some(d)) => format!(" ({s:.2} s on the GPU, longest dispatch {:.0} ms)", d * 1e3),
        (None, Some(d)) => format!(" (longest dispatch {:.0} ms)", d * 1e3),
        _ => String::new(),
    };
    let mut shown_samples = if range.start > 0 || partial {
        format!("samples {}..{done}", range.start)
    } else {
        format!("{spp} spp")
    };
    if resumed_at > range.start {
        shown_samples += &format!(" (resumed at {resumed_at})");
    }
    note!(
        "{}: {width}x{height}, {shown_samples}, {} [{}], {}, {}, {seconds:.2} s{gpu_time}, {:.2} Msamples/s, mean radiance {}, estimated RMSE {:.3e} -> {}",
        scene.name,
        backend.name(),
        rendered.device,
        opts.integrator.name(),
        opts.sampler.name(),
        samples / seconds / 1e6,
        shown_radiance(mean),
        rt_gpu::converge::estimated_rmse(film),
        output.display()
    );
    if film.invalid_samples > 0 {
        note!(
            "warning: {} samples were NaN, infinite or negative, or on lavapipe needed more loop iterations than one dispatch allows, and were counted as black",
            film.invalid_samples
        );
    }
    if backend == Backend::Gpu
        && rendered.device.contains("llvmpipe")
        && !rt_gpu::gpu::Features::of(&flat).inline_scene
    {
        note!(
            "note: lavapipe traces scenes through their BVH 3-10x slower than `--backend cpu` does on the same cores"
        );
    }
    if outcome == Outcome::Stopped {
        let signal = STOP_SIGNAL.load(Ordering::SeqCst);
        if let Some(c) = &checkpoint {
            note!(
                "stopped at sample {done}: continue with the same command and --resume {}",
                c.display()
            );
        }
        // Exiting runs no destructors: the lock file goes now.
        drop(checkpoint_lock);
        std::process::exit(128 + signal);
    }
    Ok(())
}

/// Writes checkpoints on a thread of their own while the next passes render (encoding a
/// 512x512 film takes about 0.3 s); each waits for the one before, so they land in order.
struct CheckpointWriter {
    path: Option<PathBuf>,
    writing: Option<std::thread::JoinHandle<anyhow::Result<()>>>,
}

impl CheckpointWriter {
    /// Starts writing `film` where checkpoints go, if anywhere, on a thread of its own (after
    /// the one before it).
    fn write(&mut self, film: &Film, meta: FilmMeta) -> anyhow::Result<()> {
        let Some(path) = self.path.clone() else {
            return Ok(());
        };
        self.wait()?;
        let pending = PendingOutput::claim(&path, &[])?;
        let film = film.clone();
        self.writing = Some(std::thread::spawn(move || {
            pending.commit_film(&film, &meta)
        }));
        Ok(())
    }

    /// Waits for the checkpoint in flight, if any, and reports how its writing went.
    fn wait(&mut self) -> anyhow::Result<()> {
        match self.writing.take() {
            Some(writing) => writing
                .join()
                .map_err(|_| anyhow::anyhow!("writing a checkpoint failed unexpectedly"))?,
            None => Ok(()),
        }
    }

    /// Waits for the checkpoint in flight, then writes the last one, `encoded` (a film file's
    /// bytes; `None` only when there are no checkpoints).
    fn finish(&mut self, encoded: Option<&[u8]>) -> anyhow::Result<()> {
        self.wait()?;
        match (&self.path, encoded) {
            (Some(path), Some(bytes)) => PendingOutput::claim(path, &[])?.commit(bytes),
            _ => Ok(()),
        }
    }
}

/// How long a pass should take. Each pass costs the host about 0.1 s on lavapipe (setting up,
/// reading back and merging its film), so passes are as long as what happens between them
/// allows: a quarter of the checkpoint interval (a stop waits for the pass in flight, so at most
/// 10 s) or a twentieth of the time budget, at least a second; one pass when nothing happens.
fn pass_seconds(checkpoint_every: Option<f64>, budget: Option<f64>) -> f64 {
    let limits = [checkpoint_every.map(|c| c / 4.0), budget.map(|b| b / 20.0)];
    match limits.into_iter().flatten().reduce(f64::min) {
        Some(limit) => limit.clamp(1.0, 10.0),
        None => f64::INFINITY,
    }
}

/// The film saved in `path` by a checkpoint of this render, and the sample it reached.
fn resume_from(
    path: &Path,
    identity: &str,
    range: &std::ops::Range<u32>,
) -> anyhow::Result<(Film, u32)> {
    let (film, meta) = film_file::read(path)?;
    if let Some(why) = film_file::identity_difference(identity, &meta.identity) {
        bail!(
            "{} is a checkpoint of another render ({why}): resume it with the options it was made with",
            path.display()
        );
    }
    let done = match meta.samples.as_slice() {
        [r] if r.start == range.start => r.end,
        _ => bail!(
            "{} holds samples {}, not a start of this render's {}..{}",
            path.display(),
            film_file::format_ranges(&meta.samples),
            range.start,
            range.end
        ),
    };
    if done > range.end {
        bail!(
            "{} already holds samples {}..{done}, more than this render's {}..{}: ask for at least {} spp",
            path.display(),
            range.start,
            range.start,
            range.end,
            done - range.start
        );
    }
    Ok((film, done))
}

/// Combines film files of disjoint sample ranges of one render.
fn merge(args: &MergeArgs) -> anyhow::Result<()> {
    ImageFormat::from_path(&args.output)?;
    let inputs: Vec<&Path> = args.films.iter().map(|p| p.as_path()).collect();
    let pending = PendingOutput::claim(&args.output, &inputs)?;
    let mut films = Vec::new();
    for path in &args.films {
        let (film, meta) = film_file::read(path)?;
        films.push(film_file::NamedFilm {
            name: path.display().to_string(),
            film,
            meta,
        });
    }
    let combined = film_file::combine(films)?;
    let (merged, meta) = (combined.film, combined.meta);
    if !combined.missing.is_empty() {
        note!(
            "warning: samples {} are missing: the image holds the others' {} spp (merge the missing films too for the full render)",
            film_file::format_ranges(&combined.missing),
            meta.spp()
        );
    }
    pending.commit_render(&merged, &meta, args.gamma)?;
    let mean = merged.image_mean();
    note!(
        "merged {} films: samples {}, {}x{}, mean radiance {}, estimated RMSE {:.3e} -> {}",
        args.films.len(),
        film_file::format_ranges(&meta.samples),
        merged.width,
        merged.height,
        shown_radiance(mean),
        rt_gpu::converge::estimated_rmse(&merged),
        args.output.display()
    );
    Ok(())
}
