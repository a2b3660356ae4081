//! `rt-gpu scenes` (the built-in scenes, and exporting them), and the scene argument every
//! subcommand takes: a scene file or a built-in name.

use super::args::SUBCOMMANDS;
use anyhow::{Context, bail};
use rt_gpu::scene::Scene;
use rt_gpu::scene::builtin::BUILTINS;
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

/// The scene `arg` names (`rt_gpu::scene::source`), its notes printed; with the file's path
/// when it is one.
pub fn resolve_scene(arg: &str, camera: Option<&str>) -> anyhow::Result<(Scene, Option<PathBuf>)> {
    let source = rt_gpu::scene::source::resolve(arg, camera).map_err(|e| {
        if SUBCOMMANDS.contains(&arg) {
            anyhow::anyhow!(
                "{e:#}: `{arg}` is a subcommand, so it must come before any option (`rt-gpu {arg} --help`)"
            )
        } else {
            e
        }
    })?;
    for n in source.notes {
        note!("{n}");
    }
    Ok((source.scene, source.file))
}
