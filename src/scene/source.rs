//! What a scene argument names: a scene file (.toml), a glTF file (.glb, .gltf) seen through one
//! of its cameras, or a built-in scene. The command line, the viewer's reload and the Python
//! package read scenes through here.

use super::builtin::{BUILTINS, builtin};
use super::{Scene, file, gltf_scene};
use anyhow::{Context, bail};
use std::path::{Path, PathBuf};

/// A scene read from what an argument names.
pub struct Source {
    pub scene: Scene,
    /// The file it was read from, if any (outputs never replace it).
    pub file: Option<PathBuf>,
    /// What the reading noticed and the user should hear: what a file asks for that rt-gpu does
    /// not do, a file shadowing a built-in's name.
    pub notes: Vec<String>,
}

/// The scene `arg` names: a scene file, a glTF file (seen by its camera named `camera`, else its
/// first), or else a built-in scene.
pub fn resolve(arg: &str, camera: Option<&str>) -> anyhow::Result<Source> {
    let path = Path::new(arg);
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if let Some("glb" | "gltf") = extension.as_deref() {
        let (scene, notes) = gltf_scene::load(path, arg, camera).map_err(anyhow::Error::msg)?;
        let file = Some(path.to_path_buf());
        return Ok(Source { scene, file, notes });
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
        let notes = builtin(arg).map_or(Vec::new(), |_| {
            vec![format!(
                "note: rendering the scene file {arg}, not the built-in scene '{arg}' (rename the file to use the built-in)"
            )]
        });
        let scene = file::load(path)?;
        let file = Some(path.to_path_buf());
        return Ok(Source { scene, file, notes });
    }
    let scene = builtin(arg).with_context(|| {
        let names: Vec<&str> = BUILTINS.iter().map(|(n, _)| *n).collect();
        format!(
            "'{arg}' is neither a built-in scene ({}) nor a scene file",
            names.join(", ")
        )
    })?;
    Ok(Source {
        scene,
        file: None,
        notes: Vec::new(),
    })
}
