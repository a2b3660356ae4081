//! `rt-gpu view SCENE`: the options checked, then the window (`rt_gpu::viewer`).

use super::args::{RenderBackendArg, ViewArgs};
use super::scenes::resolve_scene;
use anyhow::{Context, bail};
use rt_gpu::film::check_memory;
use rt_gpu::film::output::ImageFormat;
use rt_gpu::render::Backend;
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::viewer::{ViewConfig, run};
use std::io::Write;
use std::path::PathBuf;

pub fn view(args: &ViewArgs) -> anyhow::Result<()> {
    args.options.check()?;
    if let Some(t) = args.time
        && !(t > 0.0 && t.is_finite())
    {
        bail!(
            "--time must be a positive number of seconds, got {}",
            super::shown_number(t)
        );
    }
    let (scene, _) = resolve_scene(&args.scene, args.options.camera.as_deref())?;
    let scene = args.options.with_background(scene)?;
    if let Some(note) = args.options.note_for(&scene) {
        note!("{note}");
    }
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}-view.exr", scene.name)));
    if ImageFormat::from_path(&output)? != ImageFormat::Exr {
        bail!(
            "the viewer writes a film file with a .png beside it: name an .exr output, not {}",
            output.display()
        );
    }
    if let Some(s) = &args.screenshot
        && ImageFormat::from_path(s)? != ImageFormat::Png
    {
        bail!("--screenshot writes a .png, not {}", s.display());
    }
    let (width, height) = args.options.size(&scene);
    check_memory(width, height).map_err(anyhow::Error::msg)?;
    let opts = args.options.render_options(&scene, 0..0);
    let gpu = args.options.gpu(false);
    let backend = match args.options.backend {
        RenderBackendArg::Gpu => Backend::Gpu,
        RenderBackendArg::Cpu => Backend::Cpu,
        RenderBackendArg::Auto => {
            let flat = FlatScene::new(&scene, width, height).context("invalid scene")?;
            rt_gpu::render::auto_backend(&gpu, &flat).backend
        }
    };
    run(ViewConfig {
        scene,
        opts,
        backend,
        gpu,
        stop_spp: args.spp,
        stop_seconds: args.time,
        output,
        script: args.steps.clone(),
        exit_after_spp: args.exit_after_spp,
        screenshot: args.screenshot.clone(),
        reload: Some(Box::new(reloader(args))),
    })
}

/// Reads the scene again as `view` first read it (F5 in the window).
fn reloader(args: &ViewArgs) -> impl Fn() -> anyhow::Result<rt_gpu::scene::Scene> + use<> {
    let (scene, options) = (args.scene.clone(), args.options.clone());
    move || {
        let (scene, _) = resolve_scene(&scene, options.camera.as_deref())?;
        options.with_background(scene)
    }
}
