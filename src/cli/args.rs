//! The command line's syntax: the subcommands and their options (clap), and how option values
//! are parsed. What each subcommand does is in its own file beside this one.

use clap::{Args, Parser, Subcommand, ValueEnum};
use rt_gpu::film::check_image_size;
use rt_gpu::film::file as film_file;
use rt_gpu::film::output::Transfer;
use rt_gpu::options::SamplerKind;
use rt_gpu::render::{Backend, GpuChoice, Integrator, RenderOptions};
use rt_gpu::scene::Scene;
use rt_gpu::scene::file::MAX_DEPTH_LIMIT;
use std::ops::Range;
use std::path::PathBuf;

/// Where to render (the CLI's names for [`Backend`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
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

/// Where a render runs: a backend, or the faster one for the scene here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RenderBackendArg {
    /// The faster for this scene here: a GPU runs the kernel; on a software adapter (lavapipe,
    /// SwiftShader, WARP) the kernel only where it holds the scene inlined, else the CPU
    /// backend; with no adapter, the CPU backend. The summary line says which ran and why.
    Auto,
    /// The WGSL compute kernel through wgpu (any Vulkan, Metal or DX12 device, or Mesa lavapipe).
    Gpu,
    /// The CPU reference renderer (rayon over all cores).
    Cpu,
}

/// How paths find light (the CLI's names for [`Integrator`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorArg {
    /// Paths find light only by hitting it (the original project's estimator).
    Naive,
    /// Next-event estimation: each diffuse hit and each scattering event in a medium also
    /// samples a light with a shadow ray, combined with BSDF (or phase function) sampling by
    /// multiple importance sampling (power heuristic).
    Nee,
    /// No light: each pixel's surface colour (albedo) at the first hit that is not a mirror or
    /// smooth glass, the feature buffer a denoiser reads (what `--denoise` renders beside the
    /// image).
    Albedo,
    /// No light: each pixel's shading normal there, as the usual normal picture ((n + 1) / 2),
    /// the denoiser's other feature buffer.
    Normal,
}

/// Where a sample's random numbers come from (the CLI's names for [`SamplerKind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SamplerArg {
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
            IntegratorArg::Albedo => Integrator::Albedo,
            IntegratorArg::Normal => Integrator::Normal,
        }
    }
}

/// The subcommands, for a hint when one is given where a scene was expected.
pub const SUBCOMMANDS: &[&str] = &["view", "scenes", "devices", "bench", "converge", "merge"];

pub const EXAMPLES: &str = "\
Examples:
  rt-gpu cornell --spp 1000              render the Cornell box to cornell.png
  rt-gpu scenes/showcase.toml -o a.exr   render a scene file to linear EXR
  rt-gpu spheres --size 800x450 --backend cpu --seed 7 -o spheres.ppm
  rt-gpu view cornell                    watch it converge in a window; drag to orbit
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
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Subcommand)]
pub enum Command {
    /// List the built-in scenes (each also exists as a file in scenes/).
    Scenes {
        /// Write every built-in scene as DIR/<name>.toml, a starting point for your own.
        #[arg(long, value_name = "DIR")]
        export: Option<PathBuf>,
        /// With --export: overwrite scene files that already exist in DIR.
        #[arg(long, requires = "export")]
        force: bool,
    },
    /// Watch a scene converge in a window and move the camera: drag to orbit, right-drag or
    /// shift-drag to pan, wheel to dolly, W A S D Q E to fly; any move starts the film again.
    /// Ctrl+S writes the film (an .exr film file and a .png beside it), C prints the camera as
    /// a [camera] table for the scene file, R restarts, F5 reads the scene file again, Esc quits.
    #[cfg(feature = "viewer")]
    View(ViewArgs),
    /// List the GPU adapters wgpu can see (pick one with --adapter).
    Devices,
    /// Measure million samples per second of each backend, side by side in one run: the render
    /// alone, with the setup (opening the device, compiling the kernel) timed apart.
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
pub struct MergeArgs {
    /// Film files to combine: disjoint sample ranges of the same render.
    #[arg(required = true, value_name = "FILM")]
    pub films: Vec<PathBuf>,
    /// Output image or film file (.exr); the extension picks the format, as for a render.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// How .png and .ppm encode light: `srgb`, or a gamma such as 2 [default: srgb for .png, 2
    /// for .ppm].
    #[arg(long, value_name = "srgb|G", value_parser = Transfer::parse)]
    pub gamma: Option<Transfer>,
}

#[derive(Args)]
pub struct ConvergeArgs {
    /// A built-in scene name or a scene file.
    pub scene: String,
    /// Reference image (.exr or .pfm, same size) [default: render one at high spp on the
    /// fastest backend and cache it in DIR].
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a rendered reference [default: 8x what the fastest series reaches].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub reference_spp: Option<u32>,
    /// Backends to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "gpu,cpu")]
    pub backends: Vec<BackendArg>,
    /// Integrators to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "naive,nee")]
    pub integrators: Vec<IntegratorArg>,
    /// Samplers to compare, comma-separated: a series per backend, integrator and sampler.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "sobol")]
    pub samplers: Vec<SamplerArg>,
    /// Russian roulette from this many path segments on (0: off).
    #[arg(long, value_name = "N", default_value_t = rt_gpu::options::DEFAULT_ROULETTE_DEPTH)]
    pub roulette_depth: u32,
    /// Seconds each series may spend on its ladder.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 30.0,
        allow_negative_numbers = true
    )]
    pub budget: f64,
    /// Image size WIDTHxHEIGHT [default: the scene's].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Path segments per sample [default: the scene's].
    #[arg(long, value_name = "D", value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH_LIMIT as i64))]
    pub max_depth: Option<u32>,
    /// RMSE the time-to-error comparison aims at [default: the CPU series' error at its largest spp].
    #[arg(long, value_name = "RMSE", allow_negative_numbers = true)]
    pub target_rmse: Option<f64>,
    /// GPU adapter (part of its name).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Output directory.
    #[arg(short, long, value_name = "DIR", default_value = "converge")]
    pub output: PathBuf,
    /// Also denoise every render (Open Image Denoise, as `--denoise` does): a series
    /// `<series>-denoised` beside each, its time including the feature buffers' and the
    /// denoiser's, and a summary of what denoising gains.
    #[arg(long)]
    pub denoise: bool,
}

#[derive(Args)]
pub struct BenchArgs {
    /// A built-in scene name or a scene file.
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Samples per pixel of each measured render.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    #[arg(long, value_name = "D", default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH_LIMIT as i64))]
    pub max_depth: u32,
    #[arg(long, value_enum, default_value_t = IntegratorArg::Nee)]
    pub integrator: IntegratorArg,
    #[arg(long, value_enum, default_value_t = SamplerArg::Sobol)]
    pub sampler: SamplerArg,
    /// Russian roulette from this many path segments on, as a render's (0: off).
    #[arg(long, value_name = "N", default_value_t = rt_gpu::options::DEFAULT_ROULETTE_DEPTH)]
    pub roulette_depth: u32,
    /// GPU adapter (part of its name).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Instead of timing renders, count what BVH traversal reads per ray: nodes, their bytes,
    /// leaves, primitives, instances entered and stack depth, and the kernel's loop iterations
    /// (alone, and with each 8 consecutive rays charged their slowest's: lavapipe's SIMD lanes at
    /// 256 bits), for the kernel's four-wide walk (a model of it, step for step) and the CPU's
    /// wide one, over a camera ray through every
    /// pixel and a diffuse bounce from each hit. Hardware-independent: the GPU's traversal cost
    /// where no GPU is at hand.
    #[arg(long)]
    pub stats: bool,
    /// Which renders to time, comma-separated (the CPU's run also counts the rays per sample,
    /// which the GPU's lines are credited with: Mrays/s).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "cpu,gpu,gpu-everything",
        conflicts_with = "stats"
    )]
    pub runs: Vec<BenchRun>,
}

/// A render `bench` times.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchRun {
    /// The CPU reference renderer.
    Cpu,
    /// The GPU kernel specialised to the scene (what a render runs).
    Gpu,
    /// The GPU's general kernel, every feature enabled.
    GpuEverything,
}

#[cfg(feature = "viewer")]
#[derive(Args)]
pub struct ViewArgs {
    /// A built-in scene name (see `rt-gpu scenes`) or a scene file (.toml).
    pub scene: String,
    /// Stop adding samples at this many per pixel (the image stays shown).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Stop adding samples after this many seconds of a view (the image stays shown).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub time: Option<f64>,
    #[command(flatten)]
    pub options: RenderOptionArgs,
    /// Where Ctrl+S writes the film file (.exr), with a .png beside it [default:
    /// <scene>-view.exr].
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Test aid: a scripted input (orbit:DX,DY, pan:DX,DY, dolly:N, fly:F,R,U, save, camera,
    /// restart, reload, denoise, quit) or a wait (spp:N), run in order; repeatable.
    #[arg(long = "step", value_name = "STEP", hide = true, value_parser = rt_gpu::viewer::Step::parse)]
    pub steps: Vec<rt_gpu::viewer::Step>,
    /// Test aid: exit once the script has run and the film holds N samples per pixel.
    #[arg(long, value_name = "N", hide = true)]
    pub exit_after_spp: Option<u32>,
    /// Test aid: with --exit-after-spp, write the window's last image to FILE (.png).
    #[arg(long, value_name = "FILE", hide = true, requires = "exit_after_spp")]
    pub screenshot: Option<PathBuf>,
}

/// The options that say what a render computes and where, shared by a batch render and the
/// viewer: the same flags give both the same estimator, hence the same image.
#[derive(Args, Clone)]
pub struct RenderOptionArgs {
    /// The camera of a glTF scene (.glb, .gltf) to render through, by name [default: its
    /// first; one framing the scene if it has none].
    #[arg(long, value_name = "NAME")]
    pub camera: Option<String>,
    /// Image size WIDTHxHEIGHT [default: the scene's].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Light the scene by this background instead of its own: a colour R,G,B (or one number,
    /// a grey; 0 is black), `sky`, or an equirectangular image (.hdr, .exr, .png) as an
    /// environment light, e.g. `rt-gpu model.glb --background studio.hdr`.
    #[arg(long, value_name = "R,G,B|sky|FILE")]
    pub background: Option<String>,
    /// Random seed: the same scene, seed and backend give the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Path segments per sample [default: the scene's].
    #[arg(long, value_name = "D", value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH_LIMIT as i64))]
    pub max_depth: Option<u32>,
    /// Where to render.
    #[arg(long, value_enum, default_value_t = RenderBackendArg::Auto)]
    pub backend: RenderBackendArg,
    /// How paths find light: nee samples lights directly at diffuse hits (with multiple
    /// importance sampling); naive waits for paths to hit them (the original project's way).
    #[arg(long, value_enum, default_value_t = IntegratorArg::Nee)]
    pub integrator: IntegratorArg,
    /// Where each sample's random numbers come from: sobol stratifies them (lower error for
    /// the same samples); independent is plain Monte Carlo.
    #[arg(long, value_enum, default_value_t = SamplerArg::Sobol)]
    pub sampler: SamplerArg,
    /// Russian roulette from this many path segments on: paths end at random, in proportion to
    /// how little they can still carry, and survivors are reweighted (unbiased), as in Mitsuba 3
    /// and pbrt-v4; 0: off.
    #[arg(long, value_name = "N", default_value_t = rt_gpu::options::DEFAULT_ROULETTE_DEPTH)]
    pub roulette_depth: u32,
    /// GPU adapter to use: part of its name, as `rt-gpu devices` lists them.
    #[arg(long, value_name = "NAME")]
    pub adapter: Option<String>,
}

/// `--background`'s value: a colour, `sky`, or an image read (into `inputs`) as an environment.
fn background_arg(
    arg: &str,
    inputs: &mut Vec<rt_gpu::assets::inputs::InputFile>,
) -> anyhow::Result<rt_gpu::scene::Background> {
    use rt_gpu::scene::Background;
    if arg == "sky" {
        return Ok(Background::Sky);
    }
    let numbers: Option<Vec<f32>> = arg.split(',').map(|w| w.trim().parse().ok()).collect();
    if let Some(numbers) = numbers {
        let colour = match numbers[..] {
            [grey] => glam::Vec3::splat(grey),
            [r, g, b] => glam::Vec3::new(r, g, b),
            _ => anyhow::bail!(
                "--background takes a colour R,G,B (or one number, a grey), sky, or an image file, got {arg}"
            ),
        };
        if !(colour.is_finite() && colour.min_element() >= 0.0) {
            anyhow::bail!("--background's colour must be finite numbers >= 0, got {arg}");
        }
        return Ok(Background::Constant(colour));
    }
    let (image, read) = rt_gpu::assets::inputs::recorded(|| {
        rt_gpu::assets::image::load(std::path::Path::new(arg), arg)
    });
    let image = image.map_err(|e| anyhow::anyhow!("--background: {e}"))?;
    inputs.extend(read);
    let environment = rt_gpu::assets::environment::Environment::new(image, 1.0, 0.0)
        .map_err(|e| anyhow::anyhow!("--background: {e}"))?;
    Ok(Background::Environment(environment))
}

impl RenderOptionArgs {
    /// The first contradiction among these options, if any.
    pub fn check(&self) -> anyhow::Result<()> {
        if self.adapter.is_some() && self.backend == RenderBackendArg::Cpu {
            anyhow::bail!(
                "--adapter picks a GPU, but --backend cpu renders on the CPU: drop one of them"
            );
        }
        Ok(())
    }

    /// A note for the user where these options leave part of `scene` unseen.
    pub fn note_for(&self, scene: &Scene) -> Option<String> {
        (self.integrator == IntegratorArg::Naive && !scene.punctual.is_empty()).then(|| {
            "note: the naive integrator never finds punctual lights (points, spots, the sun), which only light sampling reaches: they are left out (use --integrator nee)".to_string()
        })
    }

    /// `scene` under `--background`, where given (an image is read as the scene's own files
    /// are: it joins the files outputs must not replace and films' identities digest).
    pub fn with_background(&self, mut scene: Scene) -> anyhow::Result<Scene> {
        let Some(arg) = &self.background else {
            return Ok(scene);
        };
        scene.background = background_arg(arg, &mut scene.inputs)?;
        Ok(scene)
    }

    /// The image size: --size, or the scene's.
    pub fn size(&self, scene: &Scene) -> (u32, u32) {
        self.size
            .unwrap_or((scene.defaults.width, scene.defaults.height))
    }

    /// What rendering `scene`'s sample indices `samples` with these options computes.
    pub fn render_options(&self, scene: &Scene, samples: Range<u32>) -> RenderOptions {
        let (width, height) = self.size(scene);
        RenderOptions {
            width,
            height,
            spp: samples.end - samples.start,
            first_sample: samples.start,
            seed: self.seed,
            max_depth: self.max_depth.unwrap_or(scene.defaults.max_depth),
            integrator: self.integrator.into(),
            sampler: self.sampler.into(),
            roulette_depth: self.roulette_depth,
        }
    }

    /// The GPU these options ask for.
    pub fn gpu(&self, everything: bool) -> GpuChoice {
        GpuChoice {
            adapter: self.adapter.clone(),
            everything,
        }
    }
}

#[derive(Args)]
pub struct RenderArgs {
    /// A built-in scene name (see `rt-gpu scenes`) or a scene file (.toml).
    pub scene: Option<String>,
    /// Samples per pixel [default: 64, or unlimited with --time or --target-error].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Render until this many seconds are spent, in whole passes over the image, then write the
    /// image; with --spp too, whichever comes first. The summary says how many samples per pixel
    /// were reached.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Render until the image's estimated relative error (its self-estimated RMSE over its mean
    /// radiance; with sobol, from the spread of independent replicas) falls to X, e.g. 0.01,
    /// then write the image; with --spp or --time too, whichever comes first. The summary says
    /// how many samples per pixel were reached.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub target_error: Option<f64>,
    /// Write the render's state to FILE (a film file, .exr) every --checkpoint-every seconds, at
    /// the end, and when interrupted (Ctrl-C or SIGTERM finish the pass in flight, write it and
    /// the image so far, and exit non-zero); --resume FILE continues it.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints [default: 60].
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub checkpoint_every: Option<f64>,
    /// Continue the render saved in FILE by --checkpoint (same scene and options; --spp or
    /// --time may grow), checkpointing to FILE again [default: where --checkpoint says]. The
    /// image is bit-identical to one uninterrupted render.
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
    /// Start over although the --checkpoint FILE exists, replacing its samples (without it,
    /// an existing checkpoint is refused: continue it with --resume FILE).
    #[arg(long)]
    pub force: bool,
    /// Render only sample indices FIRST..END of every pixel (END exclusive) and write a film
    /// file (-o FILE.exr) for `rt-gpu merge`.
    #[arg(long, value_name = "FIRST..END", value_parser = film_file::parse_range, conflicts_with_all = ["shard", "spp", "time"])]
    pub samples: Option<std::ops::Range<u32>>,
    /// Render the K-th of N equal parts of --spp's samples (K from 0, as Slurm's
    /// $SLURM_ARRAY_TASK_ID) and write a film file for `rt-gpu merge`.
    #[arg(long, value_name = "K/N", value_parser = parse_shard, allow_hyphen_values = true, requires = "spp", conflicts_with = "time")]
    pub shard: Option<(u32, u32)>,
    #[command(flatten)]
    pub options: RenderOptionArgs,
    /// Print the WGSL kernel built for this scene and exit.
    #[arg(long)]
    pub print_shader: bool,
    /// Run the general everything-enabled GPU kernel instead of the scene's specialised one.
    #[arg(long, hide = true)]
    pub unspecialised: bool,
    /// Output image; the extension picks the format: .png (8-bit sRGB) and .ppm (8-bit, gamma 2,
    /// as the original project), .exr and .pfm (linear radiance) [default: <scene>.png].
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// How .png and .ppm encode light: `srgb`, or a gamma such as 2 (the original project's
    /// look) [default: srgb for .png, 2 for .ppm].
    #[arg(long, value_name = "srgb|G", value_parser = Transfer::parse)]
    pub gamma: Option<Transfer>,
    /// Denoise the image with Intel Open Image Denoise, guided by albedo and normal buffers
    /// rendered after it (up to 64 spp): a clean image from few samples. An .exr output then
    /// holds the denoised image with the noisy one and the buffers as layers (noisy.R, albedo.R,
    /// normal.X, ...), not a film file; --checkpoint still writes the exact film. Needs OIDN 2:
    /// `python3 scripts/install-oidn.py` (run by .ci/setup), or OIDN_DIR.
    #[arg(long, conflicts_with_all = ["shard", "samples"])]
    pub denoise: bool,
}

pub fn parse_shard(s: &str) -> Result<(u32, u32), String> {
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

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected WIDTHxHEIGHT such as 512x512, got '{s}'");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    );
    check_image_size(w, h)?;
    Ok((w, h))
}
