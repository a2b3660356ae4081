//! `rt-gpu scenes` (the built-in scenes, and exporting them), and the scene argument every
//! subcommand takes: a scene file or a built-in name.

use super::args::SUBCOMMANDS;
use anyhow::{Context, bail};
use rt_gpu::scene::builtin::{BUILTINS, builtin};
use rt_gpu::scene::{Scene, file, gltf_scene};
use std::io::Write;
use std::path::{Path, PathBuf};

pub fn list_scenes(export: Option<&Path>, force: bool) -> anyhow::Result<()> {
    if let Some(dir) = export
        && !force
    {
        // A user's edited copy must not be replaced without asking.
        let existing: Vec<String> = BUILTINS
            .iter()
            .map(|(name, _)| format!("{name}.toml"))
            .filter(|file| std::fs::symlink_metadata(dir.join(file)).is_ok())
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
            // A link in DIR is replaced, not written through: the export writes into DIR only.
            if std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink()) {
                std::fs::remove_file(&path)
                    .with_context(|| format!("cannot replace the link {}", path.display()))?;
            }
            rt_gpu::film::output::write_atomically(&path, |out| {
                Ok(out.write_all(text.as_bytes())?)
            })?;
        }
    }
    Ok(())
}

/// A scene file, a glTF file (seen by its camera named `camera`, else its first), or else a
/// built-in scene; with the file's path when it is one.
pub fn resolve_scene(arg: &str, camera: Option<&str>) -> anyhow::Result<(Scene, Option<PathBuf>)> {
    let path = Path::new(arg);
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if let Some("glb" | "gltf") = extension.as_deref() {
        let (scene, notes) = gltf_scene::load(path, arg, camera).map_err(anyhow::Error::msg)?;
        for n in notes {
            note!("{n}");
        }
        return Ok((scene, Some(path.to_path_buf())));
    }
    if camera.is_some() {
        bail!("--camera picks a camera of a glTF file (.glb, .gltf); {arg} is not one");
    }
    if extension.as_deref() == Some("obj") {
        bail!(
            "{arg} is a mesh (obj), not a scene: place it in a scene file as `[[object]] mesh = {{ file = \"{arg}\" }}` (see scenes/README.md, e.g. scenes/meshes.toml)"
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
