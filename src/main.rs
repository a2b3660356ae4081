//! The `rt-gpu` command line.

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use rt_gpu::output::{ImageFormat, write_image};
use rt_gpu::render::{Backend, RenderOptions, render};
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
  rt-gpu scenes                          list the built-in scenes";

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
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
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
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Scenes { export }) => list_scenes(export.as_deref()),
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
    };
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;

    let progress = ProgressBar::new(height as u64).with_style(
        ProgressStyle::with_template(
            "{spinner} {elapsed_precise} [{bar:40}] {pos}/{len} rows, eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let start = Instant::now();
    let film = render(args.backend, &flat, &opts, &|| progress.inc(1))?;
    let seconds = start.elapsed().as_secs_f64();
    progress.finish_and_clear();
    write_image(&output, &film)?;

    let samples = width as f64 * height as f64 * opts.spp as f64;
    let mean = film.image_mean();
    eprintln!(
        "{}: {width}x{height}, {} spp, {}, {seconds:.2} s, {:.2} Msamples/s, mean radiance ({:.5}, {:.5}, {:.5}) -> {}",
        scene.name,
        opts.spp,
        args.backend.name(),
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
