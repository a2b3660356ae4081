//! The built-in scenes: the files in `scenes/`, compiled in, so there is one copy of each
//! (`rt-gpu scenes --export DIR` writes them back out as they are, comments included).

use super::Scene;
use super::file::parse;

/// (name, one-line description) of every built-in scene.
pub const BUILTINS: &[(&str, &str)] = &[
    (
        "cornell",
        "the original project's Cornell box: two rotated boxes and a glass sphere",
    ),
    (
        "cornell-empty",
        "the Cornell box and its light with nothing inside",
    ),
    (
        "cornell-smoke",
        "the Cornell box with its boxes made of smoke: one absorbing, one scattering",
    ),
    (
        "cornell-sss",
        "the Cornell box with a jade sphere: glass filled with a scattering medium",
    ),
    (
        "spheres",
        "three spheres (diffuse, glass, metal) on a large ground sphere under a sky",
    ),
    (
        "showcase",
        "several hundred random small spheres around three large ones, a rotated metal box and a quad light",
    ),
];

/// The scene file of built-in scene `name`.
pub fn source(name: &str) -> Option<&'static str> {
    match name {
        "cornell" => Some(include_str!("../../scenes/cornell.toml")),
        "cornell-empty" => Some(include_str!("../../scenes/cornell-empty.toml")),
        "cornell-smoke" => Some(include_str!("../../scenes/cornell-smoke.toml")),
        "cornell-sss" => Some(include_str!("../../scenes/cornell-sss.toml")),
        "spheres" => Some(include_str!("../../scenes/spheres.toml")),
        "showcase" => Some(include_str!("../../scenes/showcase.toml")),
        _ => None,
    }
}

/// Built-in scene `name`, parsed from its file.
pub fn builtin(name: &str) -> Option<Scene> {
    let text = source(name)?;
    // The files are part of the program and a test parses every one: a failure is a bug.
    let scene = parse(text, &format!("scenes/{name}.toml"), name)
        .unwrap_or_else(|e| panic!("built-in scene {e}"));
    Some(scene)
}
