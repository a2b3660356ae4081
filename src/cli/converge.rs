//! `rt-gpu converge`: error against run time, with a progress bar per task.

use super::args::ConvergeArgs;
use super::one_line;
use super::scenes::resolve_scene;
use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use rt_gpu::film::check_memory;
use rt_gpu::render::GpuChoice;
use rt_gpu::scene::file;
use rt_gpu::scene::flat::FlatScene;
use std::io::Write;

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

pub fn converge(args: &ConvergeArgs) -> anyhow::Result<()> {
    if args.reference.is_some() && args.reference_spp.is_some() {
        bail!(
            "--reference-spp sets the spp of a rendered reference; it has no effect with --reference"
        );
    }
    let (scene, scene_file) = resolve_scene(&args.scene, None)?;
    check_outputs_are_not_inputs(&args.output, &scene, scene_file.as_deref())?;
    let (width, height) = args
        .size
        .unwrap_or((scene.defaults.width, scene.defaults.height));
    let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
    check_memory(width, height).map_err(anyhow::Error::msg)?;
    if let Some(t) = args.target_rmse
        && !(t > 0.0 && t.is_finite())
    {
        bail!(
            "--target-rmse must be a positive number, got {}",
            super::shown_number(t)
        );
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
        denoise: args.denoise,
    };
    let report = rt_gpu::converge::run_with(&options, &ConvergeBars::default())?;
    let target = report.target_rmse(args.target_rmse);
    write!(std::io::stdout().lock(), "{}", report.table(target))?;
    let csv = args.output.join("converge.csv");
    rt_gpu::film::output::write_atomically(&csv, |out| {
        use std::io::Write;
        Ok(out.write_all(report.csv().as_bytes())?)
    })?;
    let title = format!(
        "{} {width}x{height}, max depth {}",
        scene.name, options.max_depth
    );
    match rt_gpu::converge::plot::write_plot(&report, &title, &args.output.join("converge")) {
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

/// Refuses an output folder where the report's files (`converge.csv`, `.svg`, `.png`, the cached
/// reference's `reference-*` files) would replace a file the scene reads, before any render.
fn check_outputs_are_not_inputs(
    dir: &std::path::Path,
    scene: &rt_gpu::scene::Scene,
    scene_file: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    let inputs: Vec<&std::path::Path> = scene_file.into_iter().chain(scene.input_paths()).collect();
    for name in ["converge.csv", "converge.svg", "converge.png"] {
        rt_gpu::film::output::check_not_input(&dir.join(name), &inputs)?;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        if entry
            .file_name()
            .to_string_lossy()
            .starts_with("reference-")
        {
            rt_gpu::film::output::check_not_input(&entry.path(), &inputs)?;
        }
    }
    Ok(())
}
