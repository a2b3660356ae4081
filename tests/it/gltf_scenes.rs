//! A glTF file rendered whole (`rt-gpu model.gltf`): its cameras placed by their nodes (and
//! picked by name), a framing camera where it has none, the light it gets (its emitters, else
//! a uniform sky), its punctual lights read, and one-line errors.

use crate::common;

#[cfg(feature = "cli")]
use common::cli::{rt_gpu, stderr};
use glam::Vec3;
use rt_gpu::scene::Background;
use rt_gpu::scene::gltf_scene::{DEFAULT_HEIGHT, load};
use rt_gpu::scene::punctual::Punctual;
use std::path::{Path, PathBuf};

/// `common::gltf::write_triangle` as `name`, without reading its UVs.
fn write_gltf(dir: &Path, name: &str, material: &str, nodes: &str, extra: &str) -> PathBuf {
    crate::common::gltf::write_triangle(dir, name, false, material, nodes, extra)
}

/// The file at `path` with `from` replaced by `to`.
fn rewrite(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).expect("reads");
    std::fs::write(path, text.replace(from, to)).expect("writes");
}

const SQRT_HALF: &str = "0.70710678";

/// Node 1, "Side": camera 0 at (5, 0, 0) turned 90 degrees about +y (looking along -x). Node 2,
/// "Lift" at (0, 10, 0), with child node 3 turned -90 degrees about +x: camera 1 "Top", looking
/// down with up along -z. Camera 2 is orthographic, on no node the scene reaches but node 3's
/// sibling 4.
fn cameras_file(dir: &Path) -> PathBuf {
    let nodes = format!(
        r#"{{ "name": "Side", "camera": 0, "translation": [5, 0, 0], "rotation": [0, {SQRT_HALF}, 0, {SQRT_HALF}] }},
    {{ "name": "Lift", "translation": [0, 10, 0], "children": [3, 4] }},
    {{ "name": "TopNode", "camera": 1, "rotation": [-{SQRT_HALF}, 0, 0, {SQRT_HALF}] }},
    {{ "name": "OrthoNode", "camera": 2 }}"#
    );
    let cameras = r#""cameras": [
    { "name": "Side", "type": "perspective", "perspective": { "yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1 } },
    { "name": "Top", "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } },
    { "name": "Ortho", "type": "orthographic", "orthographic": { "xmag": 1, "ymag": 1, "zfar": 100, "znear": 0.1 } }
  ],"#;
    let path = write_gltf(dir, "cams.gltf", "", &nodes, cameras);
    // Nodes 3 and 4 are Lift's children, not roots.
    rewrite(&path, r#""nodes": [0, 1]"#, r#""nodes": [0, 1, 2]"#);
    path
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn cameras_are_placed_by_their_nodes_and_picked_by_name() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = cameras_file(dir.path());
    let (scene, notes) = load(&path, "cams.gltf", None).expect("loads");
    assert!(notes.is_empty(), "{notes:?}");
    // The first camera: Side.
    let c = &scene.camera;
    assert!(close(c.look_from, Vec3::new(5.0, 0.0, 0.0)), "{c:?}");
    let forward = (c.look_at - c.look_from).normalize();
    assert!(close(forward, Vec3::NEG_X), "{c:?}");
    assert!(close(c.up, Vec3::Y), "{c:?}");
    // Looking at the point of its view line nearest the scene's centre: the origin.
    assert!(close(c.look_at, Vec3::ZERO), "{c:?}");
    assert!((c.vfov_degrees - 0.5f32.to_degrees()).abs() < 1e-4, "{c:?}");
    assert_eq!(scene.defaults.height, DEFAULT_HEIGHT);
    assert_eq!(scene.defaults.width, 768, "aspect ratio 1.5");

    // A camera under a translated parent, rotated about x.
    let (scene, _) = load(&path, "cams.gltf", Some("Top")).expect("loads");
    let c = &scene.camera;
    assert!(close(c.look_from, Vec3::new(0.0, 10.0, 0.0)), "{c:?}");
    assert!(
        close((c.look_at - c.look_from).normalize(), Vec3::NEG_Y),
        "{c:?}"
    );
    assert!(close(c.up, Vec3::NEG_Z), "{c:?}");
    assert!((c.vfov_degrees - 0.8f32.to_degrees()).abs() < 1e-4, "{c:?}");
    assert_eq!(
        scene.defaults.width, DEFAULT_HEIGHT,
        "no aspect ratio: square"
    );

    let error = load(&path, "cams.gltf", Some("Nope")).expect_err("no such camera");
    assert!(
        error.contains("no camera named \"Nope\"") && error.contains("Side, Top, Ortho"),
        "{error}"
    );
    let error = load(&path, "cams.gltf", Some("Ortho")).expect_err("orthographic");
    assert!(error.contains("orthographic"), "{error}");
}

#[test]
fn a_file_without_cameras_is_framed_and_lit_by_a_sky_its_emitters_glow_on() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = write_gltf(dir.path(), "plain.gltf", "", "", "");
    let (scene, _) = load(&path, "plain.gltf", None).expect("loads");
    let c = &scene.camera;
    let forward = (c.look_at - c.look_from).normalize();
    let half = (c.vfov_degrees / 2.0).to_radians();
    for corner in [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ] {
        let angle = forward.angle_between(corner - c.look_from);
        assert!(
            angle < half,
            "{corner} is outside the framing camera's view: {c:?}"
        );
    }
    assert!(forward.z < 0.0, "seen from its front (+z): {c:?}");
    assert!(
        matches!(scene.background, Background::Environment(_)),
        "no lights: a sky"
    );
    assert_eq!(scene.materials.len(), 1, "glTF's default material");

    let glow = r#"{ "name": "Glow", "emissiveFactor": [1, 1, 1] }"#;
    let path = write_gltf(dir.path(), "glow.gltf", glow, "", "");
    let (scene, _) = load(&path, "glow.gltf", None).expect("loads");
    // Issue 62: emitters glow on top of the sky (DamagedHelmet's glowing details switched the
    // sky off, leaving a black helmet), and on top of the surface they colour.
    assert!(
        matches!(scene.background, Background::Environment(_)),
        "its emitters glow under the sky"
    );
    match &scene.materials[0] {
        rt_gpu::scene::Material::Pbr(pbr) => assert!(pbr.emission.is_some(), "{pbr:?}"),
        other => panic!("an emissive material is pbr that emits: {other:?}"),
    }
}

/// Issue 62: `--background` lights any scene without a scene file: a colour (0: black), the
/// sky, or an image as an environment light, read as the scene's own files are (no output may
/// replace it); a bad value is one line.
#[cfg(feature = "cli")]
#[test]
fn the_background_option_lights_a_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    write_gltf(d, "plain.gltf", "", "", "");
    let mut sky = image::Rgb32FImage::new(8, 4);
    for p in sky.pixels_mut() {
        *p = image::Rgb([0.5, 0.5, 0.5]);
    }
    image::DynamicImage::ImageRgb32F(sky)
        .save(d.join("sky.exr"))
        .expect("writes sky.exr");
    let sky_bytes = std::fs::read(d.join("sky.exr")).expect("reads");
    let mean = |background: &str| -> f64 {
        let out = rt_gpu(
            &[
                "plain.gltf",
                "--backend",
                "cpu",
                "--spp",
                "256",
                "--size",
                "8x8",
                "-o",
                "out.png",
                "--background",
                background,
            ],
            d,
        );
        let text = stderr(&out);
        assert!(out.status.success(), "{background}: {text}");
        let inside = text.split("mean radiance (").nth(1).expect("a summary");
        let values: Vec<f64> = inside
            .split(')')
            .next()
            .unwrap_or_default()
            .split(", ")
            .map(|v| v.parse().expect("a number"))
            .collect();
        values.iter().sum::<f64>() / values.len() as f64
    };
    assert_eq!(mean("0"), 0.0, "black: the file has no lights");
    let white = mean("1");
    assert!(white > 0.5, "{white}");
    assert!(mean("sky") > 0.1);
    let half = mean("sky.exr") / white;
    assert!(
        (0.45..0.55).contains(&half),
        "an image of 0.5 against 1: {half}"
    );
    for (args, expected) in [
        (
            &["plain.gltf", "--background", "sky.exr", "-o", "sky.exr"][..],
            "sky.exr, a file this run reads",
        ),
        (
            &["plain.gltf", "--background", "1,2"][..],
            "--background takes a colour",
        ),
        (
            &["plain.gltf", "--background", "nope.exr"][..],
            "--background: cannot read image nope.exr",
        ),
    ] {
        let out = rt_gpu(args, d);
        let text = stderr(&out);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(text.contains(expected), "{args:?}: {text}");
        assert_eq!(text.trim_end().lines().count(), 1, "{args:?}: {text}");
    }
    assert_eq!(std::fs::read(d.join("sky.exr")).expect("reads"), sky_bytes);
}

#[cfg(feature = "cli")]
#[test]
fn the_command_line_renders_a_gltf_file_and_its_errors_are_one_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    cameras_file(dir.path());
    let out = rt_gpu(
        &[
            "cams.gltf",
            "--camera",
            "Top",
            "--spp",
            "2",
            "--size",
            "24x16",
            "--backend",
            "cpu",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let image = image::open(dir.path().join("cams.png")).expect("writes cams.png");
    assert_eq!((image.width(), image.height()), (24, 16));

    for (args, expected) in [
        (&["cams.gltf", "--camera", "Nope"][..], "no camera named"),
        (&["cams.gltf", "--camera", "Ortho"][..], "orthographic"),
        (
            &["cornell", "--camera", "Top"][..],
            "--camera picks a camera of a glTF file",
        ),
        (&["missing.glb"][..], "missing.glb"),
    ] {
        let out = rt_gpu(args, dir.path());
        let text = stderr(&out);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(text.contains(expected), "{args:?}: {text}");
        assert_eq!(text.trim_end().lines().count(), 1, "{args:?}: {text}");
    }
}

#[test]
fn a_file_requiring_punctual_lights_is_lit_by_them() {
    let dir = tempfile::tempdir().expect("temp dir");
    let nodes = r#"{ "name": "LampNode", "translation": [0, 3, 2], "extensions": { "KHR_lights_punctual": { "light": 0 } } }"#;
    let extra = r#""extensionsUsed": ["KHR_lights_punctual"],
  "extensionsRequired": ["KHR_lights_punctual"],
  "extensions": { "KHR_lights_punctual": { "lights": [{ "name": "Lamp", "type": "point", "color": [1, 0.5, 0.25], "intensity": 683, "range": 10 }] } },"#;
    let path = write_gltf(dir.path(), "lit.gltf", "", nodes, extra);
    let (scene, notes) = load(&path, "lit.gltf", None).expect("loads");
    // 683 candela: 1 W/sr, times the colour.
    assert_eq!(
        scene.punctual,
        [Punctual::Point {
            position: Vec3::new(0.0, 3.0, 2.0),
            intensity: Vec3::new(1.0, 0.5, 0.25),
        }]
    );
    assert_eq!(
        scene.background,
        Background::Constant(Vec3::ZERO),
        "lit by its lamp alone"
    );
    assert!(
        notes.len() == 1 && notes[0].contains("range is ignored"),
        "{notes:?}"
    );
}

/// The scene a glTF file makes, under its uniform sky (an environment light of a 1x1 image,
/// sampled by next-event estimation), renders alike on the CPU and the GPU: Welch z + Sidak at
/// family-wise 0.01 (tests/it/common/stats.rs); the base colour 2% brighter on the GPU is caught
/// by the same test.
#[cfg(feature = "gpu")]
#[test]
fn a_gltf_scene_under_its_sky_matches_on_both_backends() {
    use common::gpu::{render_gpu, renderer};
    use common::stats::compare;
    let Some(gpu) = renderer() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    let clay = r#"{ "name": "Clay", "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.5, 0.3, 1], "metallicFactor": 0, "roughnessFactor": 0.6 } }"#;
    let path = write_gltf(dir.path(), "clay.gltf", clay, "", "");
    let (scene, _) = load(&path, "clay.gltf", None).expect("loads");
    let opts = |seed| common::nee_opts(24, 24, 256, 4, seed);
    let cpu = common::render_cpu(&scene, &opts(1));
    let tuning = rt_gpu::gpu::Tuning::default();
    let verdict = compare(&cpu, &render_gpu(&gpu, &scene, &opts(2), &tuning));
    eprintln!("cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let mut brighter = scene.clone();
    let rt_gpu::scene::Material::Pbr(pbr) = &mut brighter.materials[0] else {
        panic!("pbr");
    };
    pbr.base_color = rt_gpu::assets::texture::Texture::Colour(Vec3::new(0.8, 0.5, 0.3) * 1.02);
    let verdict = compare(&cpu, &render_gpu(&gpu, &brighter, &opts(2), &tuning));
    eprintln!("gpu with a 2% brighter base colour: {verdict:?}");
    assert!(
        !verdict.passed(),
        "a 2% brighter base colour went undetected"
    );
}

/// Issue 61: values the glTF specification forbids are refused in one line naming the field
/// (they were clamped or substituted silently: ior 0.5 as 1, transmission 2 as 1, a negative
/// intensity as black, a spot's inner cone beyond its outer), and what it allows loads.
#[test]
fn values_outside_the_specification_are_refused_naming_the_field() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let mut case = 0;
    let mut load_with = |material: &str, nodes: &str, extra: &str| {
        case += 1;
        let name = format!("spec{case}.gltf");
        let path = write_gltf(d, &name, material, nodes, extra);
        load(&path, &name, None)
    };
    for (material, field) in [
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_ior": { "ior": 0.5 } } }"#,
            "ior is 0.5",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_ior": { "ior": -1 } } }"#,
            "ior is -1",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_transmission": { "transmissionFactor": 2 } } }"#,
            "transmissionFactor",
        ),
        (
            r#"{ "name": "M", "pbrMetallicRoughness": { "metallicFactor": -1 } }"#,
            "metallicFactor",
        ),
        (
            r#"{ "name": "M", "pbrMetallicRoughness": { "roughnessFactor": 2 } }"#,
            "roughnessFactor",
        ),
        (
            r#"{ "name": "M", "pbrMetallicRoughness": { "baseColorFactor": [2, 0, 0, 1] } }"#,
            "baseColorFactor",
        ),
        (
            r#"{ "name": "M", "emissiveFactor": [1, 1, 1], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": -5 } } }"#,
            "emissiveStrength",
        ),
        (
            r#"{ "name": "M", "alphaMode": "MASK", "alphaCutoff": -1 }"#,
            "alphaCutoff",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_ior": { "ior": 1000 } } }"#,
            "up to 100",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_clearcoat": { "clearcoatFactor": 2 } } }"#,
            "KHR_materials_clearcoat.clearcoatFactor is 2",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_clearcoat": { "clearcoatFactor": 1, "clearcoatRoughnessFactor": -0.5 } } }"#,
            "clearcoatRoughnessFactor is -0.5",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_clearcoat": { "clearcoatFactor": "shiny" } } }"#,
            "clearcoatFactor",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_sheen": { "sheenColorFactor": [1, 2, 0] } } }"#,
            "KHR_materials_sheen.sheenColorFactor is [1,2,0]",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_sheen": { "sheenColorFactor": [1, 1, 1], "sheenRoughnessFactor": 1.5 } } }"#,
            "KHR_materials_sheen.sheenRoughnessFactor is 1.5",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_volume": { "thicknessFactor": 1, "attenuationDistance": 0 } } }"#,
            "KHR_materials_volume.attenuationDistance is 0",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_volume": { "thicknessFactor": -1 } } }"#,
            "KHR_materials_volume.thicknessFactor is -1",
        ),
        (
            r#"{ "name": "M", "extensions": { "KHR_materials_volume": { "attenuationColor": [1, 2, 1] } } }"#,
            "attenuationColor",
        ),
    ] {
        let err = load_with(material, "", "").expect_err(material);
        assert!(
            err.contains("material 0 (\"M\")") && err.contains(field) && !err.contains('\n'),
            "{material}: {err}"
        );
    }
    // What it allows: an ior of 1 or above, or 0.
    for ior in ["1", "2.4", "0"] {
        let material = format!(
            r#"{{ "name": "M", "extensions": {{ "KHR_materials_ior": {{ "ior": {ior} }} }} }}"#
        );
        assert!(load_with(&material, "", "").is_ok(), "ior {ior}");
    }
    let lamp = |light: &str| {
        (
            r#"{ "name": "LampNode", "translation": [0, 3, 2], "extensions": { "KHR_lights_punctual": { "light": 0 } } }"#.to_string(),
            format!(
                r#""extensionsUsed": ["KHR_lights_punctual"], "extensions": {{ "KHR_lights_punctual": {{ "lights": [{light}] }} }},"#
            ),
        )
    };
    for (light, words) in [
        (
            r#"{ "name": "L", "type": "point", "intensity": -10 }"#,
            "intensity of -10",
        ),
        (
            r#"{ "name": "L", "type": "point", "color": [1, -1, 1] }"#,
            "color",
        ),
        (
            r#"{ "name": "L", "type": "spot", "spot": { "innerConeAngle": 0.6, "outerConeAngle": 0.5 } }"#,
            "cone angles",
        ),
    ] {
        let (nodes, extra) = lamp(light);
        let err = load_with("", &nodes, &extra).expect_err(light);
        assert!(
            err.contains("light \"L\"") && err.contains(words),
            "{light}: {err}"
        );
    }
    // A rotation that is no unit quaternion (it was taken as the identity).
    let err = load_with("", r#"{ "name": "Turned", "rotation": [0, 0, 0, 0] }"#, "")
        .expect_err("zero quaternion");
    assert!(err.contains("unit quaternion"), "{err}");
    // A camera whose node shears it.
    let sheared = r#"{ "name": "Shear", "camera": 0, "matrix": [1, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 1, 0, 0, 0, 5, 1] }"#;
    let cameras = r#""cameras": [{ "name": "Cam", "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }],"#;
    let err = load_with("", sheared, cameras).expect_err("sheared");
    assert!(err.contains("shears"), "{err}");
    // Two cameras of one name: --camera NAME cannot pick one.
    let path = cameras_file(d);
    rewrite(&path, r#""name": "Top""#, r#""name": "Side""#);
    let err = load(&path, "cams.gltf", Some("Side")).expect_err("two of one name");
    assert!(err.contains("several cameras named \"Side\""), "{err}");
    // A name that would forge a line of output is escaped.
    let (nodes, extra) = lamp(r#"{ "name": "L\nnote: forged", "type": "point", "range": 3 }"#);
    let (_, notes) = load_with("", &nodes, &extra).expect("loads");
    assert!(notes.iter().all(|n| !n.contains('\n')), "{notes:?}");
}

/// Issue 61: ten thousand lights with a `range` make one note, not ten thousand.
#[test]
fn many_ignored_ranges_make_one_note() {
    let dir = tempfile::tempdir().expect("temp dir");
    let count = 10_000;
    let nodes: Vec<String> = (0..count)
        .map(|i| {
            format!(
                r#"{{ "translation": [0, 3, {i}], "extensions": {{ "KHR_lights_punctual": {{ "light": {i} }} }} }}"#
            )
        })
        .collect();
    let lights: Vec<String> = (0..count)
        .map(|i| format!(r#"{{ "name": "L{i}", "type": "point", "intensity": 1, "range": 5 }}"#))
        .collect();
    let extra = format!(
        r#""extensionsUsed": ["KHR_lights_punctual"], "extensions": {{ "KHR_lights_punctual": {{ "lights": [{}] }} }},"#,
        lights.join(",")
    );
    let path = write_gltf(dir.path(), "many.gltf", "", &nodes.join(",\n"), &extra);
    // Every light node is a root.
    let roots: Vec<String> = (0..=count).map(|i| i.to_string()).collect();
    let roots = format!(r#""nodes": [{}]"#, roots.join(", "));
    rewrite(&path, r#""nodes": [0, 1]"#, &roots);
    let (scene, notes) = load(&path, "many.gltf", None).expect("loads");
    assert_eq!(scene.punctual.len(), count);
    assert_eq!(notes.len(), 1, "{}", notes.len());
    assert!(notes[0].contains("10000 lights"), "{}", notes[0]);
}

/// Issue 61: a file without a camera is framed whatever size the checks accept (a quad of
/// half-size 3e7 was refused: the framing camera stood beyond 1e8), and a mesh whose corners
/// collapse in f32 says so rather than "has no triangles".
#[test]
fn any_accepted_file_is_framed_and_collapsed_corners_are_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let big = write_gltf(d, "big.gltf", "", "", "");
    rewrite(
        &big,
        r#""name": "Triangle", "mesh": 0"#,
        r#""name": "Triangle", "mesh": 0, "scale": [3e7, 3e7, 3e7]"#,
    );
    let (scene, _) = load(&big, "big.gltf", None).expect("framed");
    assert!(scene.camera.look_from.abs().max_element() <= 1e8);
    // Far from the origin, a small triangle's corners are one f32 point.
    let far = write_gltf(d, "far.gltf", "", "", "");
    rewrite(
        &far,
        r#""name": "Triangle", "mesh": 0"#,
        r#""name": "Triangle", "mesh": 0, "translation": [9.9e7, 0, 0], "scale": [0.5, 0.5, 0.5]"#,
    );
    let err = load(&far, "far.gltf", None).expect_err("collapsed");
    assert!(err.contains("coincide in f32"), "{err}");
}

/// Two materials of one name stay two materials (the sample EnvironmentTest names its white
/// and its black dielectric spheres alike; merging them by name drew the white ones black).
#[test]
fn materials_sharing_a_name_stay_apart() {
    let dir = tempfile::tempdir().expect("temp dir");
    let twins = r#"{ "name": "Same", "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1] } },
        { "name": "Same", "pbrMetallicRoughness": { "baseColorFactor": [0, 0, 0, 1] } }"#;
    let path = write_gltf(dir.path(), "twins.gltf", twins, "", "");
    rewrite(
        &path,
        r#"[{ "attributes": { "POSITION": 0 }, "material": 0 }]"#,
        r#"[{ "attributes": { "POSITION": 0 }, "material": 0 }, { "attributes": { "POSITION": 0 }, "material": 1 }]"#,
    );
    let (scene, _) = load(&path, "twins.gltf", None).expect("loads");
    let colours: Vec<Vec3> = scene
        .materials
        .iter()
        .map(|m| match m {
            rt_gpu::scene::Material::Pbr(p) => p.base_color.mean(),
            other => panic!("pbr expected: {other:?}"),
        })
        .collect();
    assert_eq!(
        colours,
        [Vec3::ONE, Vec3::ZERO],
        "{:?}",
        scene.material_names
    );
}

/// The triangle of [`write_gltf`] with COLOR_0 as normalized unsigned bytes (VEC4, alpha 255)
/// `colors` per corner, and `material` (JSON) as its material.
fn write_coloured_gltf(dir: &Path, name: &str, material: &str, colors: [[u8; 4]; 3]) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    for v in [[-1.0f32, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            bin.extend(x.to_le_bytes());
        }
    }
    bin.extend(colors.iter().flatten());
    let bin_name = format!("{name}.bin");
    std::fs::write(dir.join(&bin_name), &bin).expect("writes");
    let json = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "buffers": [{{ "uri": "{bin_name}", "byteLength": 48 }}],
  "bufferViews": [{{ "buffer": 0, "byteOffset": 0, "byteLength": 36 }}, {{ "buffer": 0, "byteOffset": 36, "byteLength": 12 }}],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 1, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4" }}
  ],
  "materials": [{material}],
  "meshes": [{{ "primitives": [{{ "attributes": {{ "POSITION": 0, "COLOR_0": 1 }}, "material": 0 }}] }}],
  "nodes": [{{ "mesh": 0 }}],
  "scenes": [{{ "nodes": [0] }}],
  "scene": 0
}}"#
    );
    let path = dir.join(name);
    std::fs::write(&path, json).expect("writes");
    path
}

/// Issue 62: COLOR_0 multiplies the base colour (it was ignored). A triangle whose corners are
/// all (51, 128, 204) / 255 renders as the same triangle without COLOR_0 whose base colour is
/// that colour (the same paths: within 1e-4 of the triangle's light), and 2% off in the base
/// colour is not; its alpha, unread, is named in a note where the material blends; COLOR_0 of
/// integers that are not normalized is refused in one line.
#[test]
fn vertex_colours_multiply_the_base_colour() {
    let dir = tempfile::tempdir().expect("temp dir");
    let white = r#"{ "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0.6 } }"#;
    let uniform = write_coloured_gltf(dir.path(), "uniform.gltf", white, [[51, 128, 204, 255]; 3]);
    let (coloured, notes) = load(&uniform, "uniform.gltf", None).expect("loads");
    assert!(
        !notes.iter().any(|n| n.contains("COLOR_0")),
        "COLOR_0 is read: {notes:?}"
    );
    let plain_with = |factor: Vec3| {
        let material = format!(
            r#"{{ "pbrMetallicRoughness": {{ "baseColorFactor": [{}, {}, {}, 1], "metallicFactor": 0, "roughnessFactor": 0.6 }} }}"#,
            factor.x, factor.y, factor.z
        );
        let path = write_gltf(dir.path(), "plain.gltf", &material, "", "");
        load(&path, "plain.gltf", None).expect("loads").0
    };
    let colour = Vec3::new(51.0, 128.0, 204.0) / 255.0;
    let opts = common::nee_opts(24, 24, 64, 4, 3);
    let render = |scene: &rt_gpu::scene::Scene| common::render_cpu(scene, &opts);
    let difference = common::relative_difference;
    let with_colours = render(&coloured);
    let same = difference(&with_colours, &render(&plain_with(colour)));
    let darker = difference(&with_colours, &render(&plain_with(colour * 0.98)));
    eprintln!("COLOR_0 vs base colour: {same:.2e}; vs 2% darker: {darker:.2e}");
    assert!(
        same < 1e-4,
        "COLOR_0 is not the base colour it should be: {same}"
    );
    assert!(
        darker > 1e-3,
        "a 2% darker base colour went unseen: {darker}"
    );
    // Its alpha is not read: named where the material blends (not where it is opaque).
    let blended = write_coloured_gltf(
        dir.path(),
        "blended.gltf",
        r#"{ "alphaMode": "BLEND", "pbrMetallicRoughness": { "metallicFactor": 0 } }"#,
        [[51, 128, 204, 128]; 3],
    );
    let (_, notes) = load(&blended, "blended.gltf", None).expect("loads");
    assert!(
        notes.iter().any(|n| n.contains("COLOR_0's alpha")),
        "{notes:?}"
    );
    // Integers that are not normalized are no colour glTF allows: one line naming COLOR_0.
    rewrite(&uniform, r#""normalized": true"#, r#""normalized": false"#);
    let error = load(&uniform, "uniform.gltf", None).expect_err("refused");
    assert!(
        error.contains("COLOR_0") && !error.contains('\n'),
        "{error}"
    );
}

/// Issue 62: KHR_materials_unlit, even required, loads (it was refused): the surface shows its
/// base colour as it is, whatever lights the scene (an emitter of that radiance that reflects
/// nothing), and its image's centre, on the triangle, is that colour exactly.
#[test]
fn an_unlit_material_shows_its_base_colour() {
    let dir = tempfile::tempdir().expect("temp dir");
    let unlit = r#"{ "pbrMetallicRoughness": { "baseColorFactor": [0.2, 0.5, 0.8, 1] }, "extensions": { "KHR_materials_unlit": {} } }"#;
    let extra = r#""extensionsUsed": ["KHR_materials_unlit"], "extensionsRequired": ["KHR_materials_unlit"],"#;
    let path = write_gltf(dir.path(), "unlit.gltf", unlit, "", extra);
    let (scene, notes) = load(&path, "unlit.gltf", None).expect("loads");
    assert!(
        !notes.iter().any(|n| n.contains("unlit")),
        "KHR_materials_unlit is read: {notes:?}"
    );
    let colour = Vec3::new(0.2, 0.5, 0.8);
    for integrator in [common::opts(9, 9, 4, 8, 1), common::nee_opts(9, 9, 4, 8, 1)] {
        let film = common::render_cpu(&scene, &integrator);
        let centre = film.pixel(4, 4).mean().as_vec3();
        assert!(
            (centre - colour).abs().max_element() < 1e-6,
            "{centre} for {colour}"
        );
    }
}

/// Issue 62: a triangle of red, green and blue corners (COLOR_0) renders alike on both backends
/// (Welch z + Sidak, tests/it/common/stats.rs), its green corner 2% darker caught.
#[cfg(feature = "gpu")]
#[test]
fn vertex_colours_match_on_both_backends() {
    let dir = tempfile::tempdir().expect("temp dir");
    let white = r#"{ "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0.6 } }"#;
    use common::gpu::{render_gpu, renderer};
    use common::stats::compare;
    let Some(gpu) = renderer() else { return };
    let corners = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]];
    let gradient = write_coloured_gltf(dir.path(), "gradient.gltf", white, corners);
    let (scene, _) = load(&gradient, "gradient.gltf", None).expect("loads");
    let darker_green = write_coloured_gltf(
        dir.path(),
        "darker.gltf",
        white,
        [corners[0], [0, 250, 0, 255], corners[2]],
    );
    let (darker, _) = load(&darker_green, "darker.gltf", None).expect("loads");
    let opts = |seed| common::nee_opts(24, 24, 1024, 4, seed);
    let cpu = common::render_cpu(&scene, &opts(1));
    let tuning = rt_gpu::gpu::Tuning::default();
    let verdict = compare(&cpu, &render_gpu(&gpu, &scene, &opts(2), &tuning));
    eprintln!("cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let verdict = compare(&cpu, &render_gpu(&gpu, &darker, &opts(2), &tuning));
    eprintln!("gpu with a 2% darker green corner: {verdict:?}");
    assert!(
        !verdict.passed(),
        "a 2% darker green corner went undetected"
    );
}

/// A glTF file `name` in `dir`: [`write_gltf`]'s triangle (accessor 0; node 0 places it), its
/// buffer also holding `arrays` as accessors 1.. (each its bytes, component type, type and
/// count), and the document then edited by `edit`.
fn write_posed_gltf(
    dir: &Path,
    name: &str,
    arrays: &[(Vec<u8>, u32, &str, usize)],
    edit: impl FnOnce(&mut serde_json::Value),
) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    for x in [-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(x.to_le_bytes());
    }
    let mut views = vec![serde_json::json!({ "buffer": 0, "byteOffset": 0, "byteLength": 36 })];
    let mut accessors = vec![serde_json::json!({
        "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
        "min": [-1, -1, 0], "max": [1, 1, 0]
    })];
    for (bytes, component, ty, count) in arrays {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(
            serde_json::json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len() }),
        );
        bin.extend(bytes);
        let mut accessor = serde_json::json!({
            "bufferView": views.len() - 1, "componentType": component, "count": count, "type": ty
        });
        // Animation inputs must give their range.
        if *ty == "SCALAR" && *component == 5126 {
            let values: Vec<f32> = (bytes.chunks_exact(4))
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            let min = values.iter().copied().fold(f32::INFINITY, f32::min);
            let max = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            accessor["min"] = serde_json::json!([min]);
            accessor["max"] = serde_json::json!([max]);
        }
        accessors.push(accessor);
    }
    let bin_name = format!("{name}.bin");
    std::fs::write(dir.join(&bin_name), &bin).expect("writes");
    let mut doc = serde_json::json!({
        "asset": { "version": "2.0" },
        "buffers": [{ "uri": bin_name, "byteLength": bin.len() }],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "nodes": [{ "name": "Triangle", "mesh": 0 }],
        "scenes": [{ "nodes": [0] }],
        "scene": 0
    });
    edit(&mut doc);
    let path = dir.join(name);
    std::fs::write(&path, doc.to_string()).expect("writes");
    path
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The positions of the one mesh part of the file at `path`.
fn posed_positions(path: &Path) -> Vec<Vec3> {
    let meshes =
        rt_gpu::scene::mesh::load(path, "posed.gltf", None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(meshes.len(), 1);
    meshes[0].positions.clone()
}

fn assert_positions(path: &Path, expected: [[f32; 3]; 3]) {
    let got = posed_positions(path);
    for (g, e) in got.iter().zip(expected) {
        assert!(
            (*g - Vec3::from(e)).length() < 1e-5,
            "{got:?} against {expected:?}"
        );
    }
}

/// Issue 62: morph targets move the vertices by their weights (they were ignored: the rest
/// pose was drawn): the mesh's default weights, the node's over them, the first animation's
/// at 0 s over both (keys at 0 s and 1 s: the first's value).
#[test]
fn morph_targets_move_vertices_by_their_weights() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Accessor 1: a target lifting every vertex by 1 along z.
    let lift = (floats(&[0.0, 0.0, 1.0].repeat(3)), 5126, "VEC3", 3);
    let times = (floats(&[0.0, 1.0]), 5126, "SCALAR", 2);
    let keyed = (floats(&[0.4, 0.6]), 5126, "SCALAR", 2);
    let at = |z: f32| [[-1.0, -1.0, z], [1.0, -1.0, z], [0.0, 1.0, z]];
    let target = |doc: &mut serde_json::Value| {
        doc["meshes"][0]["primitives"][0]["targets"] = serde_json::json!([{ "POSITION": 1 }]);
        doc["meshes"][0]["weights"] = serde_json::json!([0.5]);
    };
    let mesh_weights =
        write_posed_gltf(dir.path(), "mesh.gltf", std::slice::from_ref(&lift), target);
    assert_positions(&mesh_weights, at(0.5));
    let node_weights = write_posed_gltf(
        dir.path(),
        "node.gltf",
        std::slice::from_ref(&lift),
        |doc| {
            target(doc);
            doc["nodes"][0]["weights"] = serde_json::json!([0.25]);
        },
    );
    assert_positions(&node_weights, at(0.25));
    let animated = write_posed_gltf(
        dir.path(),
        "animated.gltf",
        &[lift.clone(), times, keyed],
        |doc| {
            target(doc);
            doc["animations"] = serde_json::json!([{
                "samplers": [{ "input": 2, "output": 3 }],
                "channels": [{ "sampler": 0, "target": { "node": 0, "path": "weights" } }]
            }]);
        },
    );
    assert_positions(&animated, at(0.4));
    // A sparse block in a buffer view with a byteStride (glTF forbids it; the gltf crate's
    // reader panicked on one shorter than an element) is refused in one line.
    let indices = (vec![0u8, 0, 0, 0], 5121, "SCALAR", 1);
    let strided = write_posed_gltf(
        dir.path(),
        "strided.gltf",
        &[lift.clone(), indices],
        |doc| {
            target(doc);
            doc["bufferViews"][1]["byteStride"] = 4.into();
            doc["accessors"][1]["sparse"] = serde_json::json!({
                "count": 1,
                "indices": { "bufferView": 2, "componentType": 5121 },
                "values": { "bufferView": 1 }
            });
        },
    );
    let error = rt_gpu::scene::mesh::load(&strided, "strided.gltf", None).expect_err("stride");
    assert!(
        error.contains("byteStride") && !error.contains('\n'),
        "{error}"
    );
    let (_, notes) = load(&animated, "animated.gltf", None).expect("loads");
    assert!(
        notes
            .iter()
            .any(|n| n.contains("its animation's motion (posed at 0 s)")),
        "{notes:?}"
    );
}

/// Issue 62: a skinned mesh is placed by its joints (it was drawn in its bind pose): a vertex
/// bound to a joint lifted 2 along z moves with it, one bound half to it half to a joint at
/// rest moves half as far, and the mesh node's own transform (a move of 5 along x) is not
/// applied, as glTF says; the joint animated moves them too. Influences of a joint the skin
/// does not have are refused in one line.
#[test]
fn skinned_meshes_are_placed_by_their_joints() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Accessors 1 (JOINTS_0) and 2 (WEIGHTS_0): vertex 0 on joint 0, 1 on joint 1, 2 on both.
    let joints = (vec![0u8, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0], 5121, "VEC4", 3);
    let weights = (
        floats(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0]),
        5126,
        "VEC4",
        3,
    );
    let skinned = |lift: &str| {
        let lift: serde_json::Value = serde_json::from_str(lift).expect("json");
        move |doc: &mut serde_json::Value| {
            doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = 1.into();
            doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = 2.into();
            doc["nodes"] = serde_json::json!([
                { "name": "Triangle", "mesh": 0, "skin": 0, "translation": [5, 0, 0] },
                { "name": "Rest" },
                { "name": "Lifted", "translation": lift }
            ]);
            doc["skins"] = serde_json::json!([{ "joints": [1, 2] }]);
            doc["scenes"] = serde_json::json!([{ "nodes": [0, 1, 2] }]);
        }
    };
    let arrays = [joints.clone(), weights.clone()];
    let path = write_posed_gltf(dir.path(), "skin.gltf", &arrays, skinned("[0, 0, 2]"));
    assert_positions(
        &path,
        [[-1.0, -1.0, 0.0], [1.0, -1.0, 2.0], [0.0, 1.0, 1.0]],
    );

    // Joint 1 animated from (0, 0, 2) at 0 s to (0, 0, 4) at 1 s: (0, 0, 2) at 0 s.
    let times = (floats(&[0.0, 1.0]), 5126, "SCALAR", 2);
    let keyed = (floats(&[0.0, 0.0, 2.0, 0.0, 0.0, 4.0]), 5126, "VEC3", 2);
    let arrays = [joints.clone(), weights.clone(), times, keyed];
    let animated = write_posed_gltf(dir.path(), "animated.gltf", &arrays, |doc| {
        skinned("[0, 0, 0]")(doc);
        doc["animations"] = serde_json::json!([{
            "samplers": [{ "input": 3, "output": 4 }],
            "channels": [{ "sampler": 0, "target": { "node": 2, "path": "translation" } }]
        }]);
    });
    assert_positions(
        &animated,
        [[-1.0, -1.0, 0.0], [1.0, -1.0, 2.0], [0.0, 1.0, 1.0]],
    );

    let beyond = (vec![0u8, 0, 0, 0, 7, 0, 0, 0, 0, 1, 0, 0], 5121, "VEC4", 3);
    let path = write_posed_gltf(
        dir.path(),
        "beyond.gltf",
        &[beyond, weights],
        skinned("[0, 0, 2]"),
    );
    let error = rt_gpu::scene::mesh::load(&path, "beyond.gltf", None).expect_err("joint 7");
    assert!(
        error.contains("joint 7") && error.contains("beyond.gltf") && !error.contains('\n'),
        "{error}"
    );

    // The skinned node's own transform neither mirrors the mesh (its winding and front face
    // stay the file's) nor, where it flattens space, refuses the file (a review found both).
    for (name, scale) in [("mirrored.gltf", "[-1, 1, 1]"), ("flat.gltf", "[0, 1, 1]")] {
        let scale: serde_json::Value = serde_json::from_str(scale).expect("json");
        let path = write_posed_gltf(dir.path(), name, &arrays, |doc| {
            skinned("[0, 0, 0]")(doc);
            doc["nodes"][0]["scale"] = scale.clone();
        });
        let meshes = rt_gpu::scene::mesh::load(&path, name, None).unwrap_or_else(|e| panic!("{e}"));
        let mesh = &meshes[0];
        let [a, b, c] = mesh.triangles[0].map(|i| mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a);
        assert!(
            normal.z > 0.0 && normal.x.abs() < 1e-6,
            "{name}: winding turned: {normal}"
        );
        assert_positions(
            &path,
            [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
        );
    }
}

/// Issue 62: the first animation places nodes at 0 s (it was ignored): a translation keyed
/// (1, 0, 0) at 0 s and (3, 0, 0) at 1 s moves the triangle by (1, 0, 0), whatever the node's
/// own translation; a channel whose values do not fit its keys, or keyed before 0 s (which glTF
/// forbids), is refused in one line.
#[test]
fn the_first_animation_places_nodes_at_time_zero() {
    let dir = tempfile::tempdir().expect("temp dir");
    let times = (floats(&[0.0, 1.0]), 5126, "SCALAR", 2);
    let keyed = (floats(&[1.0, 0.0, 0.0, 3.0, 0.0, 0.0]), 5126, "VEC3", 2);
    let animate = |doc: &mut serde_json::Value| {
        doc["nodes"][0]["translation"] = serde_json::json!([9, 9, 9]);
        doc["animations"] = serde_json::json!([{
            "samplers": [{ "input": 1, "output": 2 }],
            "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }]
        }]);
    };
    let path = write_posed_gltf(dir.path(), "moved.gltf", &[times.clone(), keyed], animate);
    assert_positions(&path, [[0.0, -1.0, 0.0], [2.0, -1.0, 0.0], [1.0, 1.0, 0.0]]);

    let short = (floats(&[0.0, 0.0, 0.0]), 5126, "VEC3", 1);
    let path = write_posed_gltf(dir.path(), "short.gltf", &[times, short], animate);
    let error = rt_gpu::scene::mesh::load(&path, "short.gltf", None).expect_err("1 value");
    assert!(
        error.contains("animation 0's channel 0") && !error.contains('\n'),
        "{error}"
    );
    // Key times below 0 are refused (glTF forbids them; -3e38..3e38 once sampled a NaN).
    let early = (floats(&[-3e38, 3e38]), 5126, "SCALAR", 2);
    let keyed = (floats(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0]), 5126, "VEC3", 2);
    let path = write_posed_gltf(dir.path(), "early.gltf", &[early, keyed], animate);
    let error = rt_gpu::scene::mesh::load(&path, "early.gltf", None).expect_err("below 0");
    assert!(
        error.contains("below 0") && !error.contains('\n'),
        "{error}"
    );
}

/// A glTF file in `dir` of issue 62's features at once, its first material's base colour factor
/// `base`: node 0 places a triangle whose material reads its base colour (RGBA, alpha MASK:
/// the right half cut away) on TEXCOORD_0 and its normal map and emission on TEXCOORD_1,
/// coloured by COLOR_0; node 1 places the same triangle, lifted by a morph target of weight 1,
/// twice (EXT_mesh_gpu_instancing), of rough glass whose transmissionTexture reads TEXCOORD_1.
/// Lit by a grey sky above a floor (a scene file placing it).
fn every_feature_scene(dir: &Path, base: f32) -> rt_gpu::scene::Scene {
    std::fs::create_dir_all(dir).expect("a folder");
    let rgba = image::RgbaImage::from_raw(2, 1, vec![255, 255, 255, 255, 200, 120, 60, 64]);
    rgba.expect("2x1")
        .save(dir.join("rgba.png"))
        .expect("writes");
    let rgb = |name: &str, w: u32, texels: Vec<u8>| {
        let image = image::RgbImage::from_raw(w, 1, texels).expect("an image");
        image.save(dir.join(name)).expect("writes");
    };
    rgb("normals.png", 1, vec![191, 128, 238]);
    rgb("glow.png", 2, vec![255, 0, 0, 128, 128, 128]);
    rgb("transmission.png", 1, vec![64, 200, 200]);
    let arrays = [
        (floats(&[0.0, 1.0, 1.0, 1.0, 0.5, 0.0]), 5126, "VEC2", 3),
        (floats(&[1.0, 0.0, 0.0, 0.0, 0.5, 1.0]), 5126, "VEC2", 3),
        (
            vec![255, 64, 64, 255, 64, 255, 64, 255, 64, 64, 255, 255],
            5121,
            "VEC4",
            3,
        ),
        (floats(&[0.0, 0.0, 0.0, 0.0, 0.0, -0.6]), 5126, "VEC3", 2),
        (floats(&[0.0, 0.0, 0.2].repeat(3)), 5126, "VEC3", 3),
    ];
    write_posed_gltf(dir, "every.gltf", &arrays, |doc| {
        doc["accessors"][3]["normalized"] = true.into();
        let attributes = serde_json::json!({ "POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 2 });
        let mut coloured = attributes.clone();
        coloured["COLOR_0"] = 3.into();
        doc["meshes"] = serde_json::json!([
            { "primitives": [{ "attributes": coloured, "material": 0 }] },
            { "primitives": [{ "attributes": attributes, "material": 1, "targets": [{ "POSITION": 5 }] }],
              "weights": [1.0] }
        ]);
        doc["materials"] = serde_json::json!([
            { "name": "Everything", "doubleSided": true, "alphaMode": "MASK", "alphaCutoff": 0.5,
              "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 },
                "baseColorFactor": [base, base, base, 1], "metallicFactor": 0, "roughnessFactor": 0.5 },
              "normalTexture": { "index": 1, "texCoord": 1 },
              "emissiveTexture": { "index": 2, "texCoord": 1 }, "emissiveFactor": [0.3, 0.3, 0.3] },
            { "name": "Glassy", "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.9, 0.9, 1],
                "metallicFactor": 0, "roughnessFactor": 0.3 },
              "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.8,
                "transmissionTexture": { "index": 3, "texCoord": 1 } } } }
        ]);
        doc["textures"] =
            serde_json::json!([{ "source": 0 }, { "source": 1 }, { "source": 2 }, { "source": 3 }]);
        doc["images"] = serde_json::json!([
            { "uri": "rgba.png" }, { "uri": "normals.png" }, { "uri": "glow.png" }, { "uri": "transmission.png" }
        ]);
        doc["nodes"] = serde_json::json!([
            { "mesh": 0, "translation": [-1.1, 0, 0] },
            { "mesh": 1, "translation": [1.1, 0, 0],
              "extensions": { "EXT_mesh_gpu_instancing": { "attributes": { "TRANSLATION": 4 } } } }
        ]);
        doc["scenes"] = serde_json::json!([{ "nodes": [0, 1] }]);
        doc["extensionsUsed"] =
            serde_json::json!(["KHR_materials_transmission", "EXT_mesh_gpu_instancing"]);
        doc["extensionsRequired"] = serde_json::json!(["EXT_mesh_gpu_instancing"]);
    });
    let text = r#"[render]
background = [0.5, 0.5, 0.5]

[camera]
look_from = [0, -2.2, 3.0]
look_at = [0, 0, -0.3]
vfov = 55

[materials]
floor = { type = "lambertian", albedo = [0.7, 0.7, 0.7] }

[[object]]
quad = { q = [-4, -4, -1], u = [8, 0, 0], v = [0, 8, 0] }
material = "floor"

[[object]]
mesh = { file = "every.gltf" }
"#;
    let path = dir.join("every.toml");
    std::fs::write(&path, text).expect("writes");
    rt_gpu::scene::file::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Issue 62: one scene of every feature the issue added (emission on a textured, alpha-masked,
/// normal-mapped surface; COLOR_0; TEXCOORD_1; a transmission texture; instancing; a morph
/// target) renders the same estimator every way (`common::renders_alike_every_way`: naive vs
/// nee on the CPU, the GPU against the CPU, Welch z + Sidak at family-wise 0.01); negative
/// control: the masked surface's base colour 2% darker, on the GPU.
#[test]
fn every_feature_of_issue_62_renders_alike_every_way() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = every_feature_scene(&dir.path().join("every"), 1.0);
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
    assert!(!flat.triangle_uvs1.is_empty() && !flat.triangle_colors.is_empty());
    assert!(flat.see_through && !flat.triangle_tangents.is_empty());
    common::renders_alike_every_way("every feature", &scene, || {
        every_feature_scene(&dir.path().join("darker"), 0.98)
    });
}

/// Issue 63: KHR_materials_clearcoat's factors are read onto the pbr material, required or not (a factor of 0,
/// glTF's default, is no coat), with no note for the extension; its factor texture is read into
/// the layers' image and its normal texture as the coat's normal map, beside the base's.
#[test]
fn a_clear_coat_is_read_and_what_is_not_is_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Required, as ClearCoatCarPaint has it (the gltf crate refuses what it does not know).
    let extra = r#""extensionsUsed": ["KHR_materials_clearcoat"], "extensionsRequired": ["KHR_materials_clearcoat"],"#;
    let coat = |ext: &str, more: &str| {
        format!(
            r#"{{ "name": "Paint", "pbrMetallicRoughness": {{ "baseColorFactor": [0.6, 0.1, 0.1, 1], "metallicFactor": 0 }}{more}, "extensions": {{ "KHR_materials_clearcoat": {ext} }} }}"#
        )
    };
    let read = |name: &str, material: &str| {
        let path = write_gltf(dir.path(), name, material, "", extra);
        let (scene, notes) = load(&path, name, None).expect("loads");
        let clearcoat = match &scene.materials[0] {
            rt_gpu::scene::Material::Pbr(p) => p.clearcoat,
            other => panic!("{other:?}"),
        };
        (clearcoat, notes)
    };
    let (clearcoat, notes) = read(
        "coat.gltf",
        &coat(
            r#"{ "clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.2 }"#,
            "",
        ),
    );
    let clearcoat = clearcoat.expect("a coat");
    assert_eq!((clearcoat.factor, clearcoat.roughness), (0.7, 0.2));
    assert!(notes.is_empty(), "{notes:?}");
    let (clearcoat, notes) = read("none.gltf", &coat("{}", ""));
    assert!(
        clearcoat.is_none() && notes.is_empty(),
        "{clearcoat:?} {notes:?}"
    );
    let textured = coat(
        r#"{ "clearcoatFactor": 1, "clearcoatTexture": { "index": 0 }, "clearcoatNormalTexture": { "index": 0 } }"#,
        r#", "normalTexture": { "index": 0 }"#,
    );
    let images = r#""textures": [{ "source": 0 }], "images": [{ "uri": "n.png" }],"#;
    image::RgbImage::from_pixel(1, 1, image::Rgb([128, 128, 255]))
        .save(dir.path().join("n.png"))
        .expect("writes");
    let extra = format!("{extra} {images}");
    let path =
        common::gltf::write_triangle(dir.path(), "textured.gltf", true, &textured, "", &extra);
    let (scene, notes) = load(&path, "textured.gltf", None).expect("loads");
    let rt_gpu::scene::Material::Pbr(p) = &scene.materials[0] else {
        panic!("{:?}", scene.materials[0]);
    };
    assert!(p.clearcoat.is_some());
    // The coat's factor texture is read: its red channel (128 of 255, linear) in the layers'
    // red, their green and blue 1 (no roughness textures).
    let layers = p.layers().expect("a layers image");
    let texel = layers.texel(0, 0);
    assert!(
        (texel - Vec3::new(128.0 / 255.0, 1.0, 1.0))
            .abs()
            .max_element()
            < 1e-6,
        "{texel}"
    );
    // Its normal texture is read, with its scale (default 1), beside the base's.
    let coat_map =
        rt_gpu::material::MaterialModel::coat_normal_map(p).expect("the coat's normal map");
    assert_eq!(coat_map.scale, 1.0);
    assert!(p.normal_map.is_some());
    assert!(notes.is_empty(), "{notes:?}");
    // A texture that does not exist, one on a UV set rt-gpu does not read, and one on a set
    // the mesh lacks are one-line errors naming it.
    for (ext, words) in [
        (
            r#"{ "clearcoatFactor": 1, "clearcoatTexture": { "index": 7 } }"#,
            "clearcoatTexture names texture 7, which does not exist",
        ),
        (
            r#"{ "clearcoatFactor": 1, "clearcoatRoughnessTexture": { "index": 0, "texCoord": 2 } }"#,
            "clearcoatRoughnessTexture reads TEXCOORD_2",
        ),
        (
            r#"{ "clearcoatFactor": 1, "clearcoatTexture": { "index": 0 }, "clearcoatRoughnessTexture": { "index": 0, "texCoord": 1 } }"#,
            "has no TEXCOORD_1, which its material \"Paint\"'s clearcoatRoughnessTexture reads",
        ),
    ] {
        let path =
            common::gltf::write_triangle(dir.path(), "bad.gltf", true, &coat(ext, ""), "", &extra);
        let err = load(&path, "bad.gltf", None).expect_err(ext);
        assert!(err.contains(words) && !err.contains('\n'), "{ext}: {err}");
    }
    // A texture of no coat (factor 0) changes nothing, and is neither read nor checked.
    let unused = coat(
        r#"{ "clearcoatFactor": 0, "clearcoatTexture": { "index": 7 } }"#,
        "",
    );
    let path = common::gltf::write_triangle(dir.path(), "unused.gltf", true, &unused, "", &extra);
    let (scene, _) = load(&path, "unused.gltf", None).expect("loads");
    assert!(
        matches!(&scene.materials[0], rt_gpu::scene::Material::Pbr(p) if p.clearcoat.is_none() && p.layers().is_none())
    );
}

/// Issue 63: KHR_materials_volume fills a transmissive material with an absorbing medium,
/// absorption -ln(attenuationColor) / attenuationDistance, required or not; a thin surface
/// (thickness 0, the default), an opaque one, or the default colour or distance fill it with
/// nothing; no note either way.
#[test]
fn a_volume_fills_transmissive_glass_with_what_absorbs() {
    let dir = tempfile::tempdir().expect("temp dir");
    let extra = r#""extensionsUsed": ["KHR_materials_transmission", "KHR_materials_volume"], "extensionsRequired": ["KHR_materials_volume"],"#;
    let volume = |transmission: f32, volume: &str| {
        format!(
            r#"{{ "name": "Tinted", "pbrMetallicRoughness": {{ "metallicFactor": 0, "roughnessFactor": 0 }}, "extensions": {{ "KHR_materials_transmission": {{ "transmissionFactor": {transmission} }}, "KHR_materials_volume": {volume} }} }}"#
        )
    };
    let mut case = 0;
    let mut read = |material: String| {
        case += 1;
        let name = format!("volume{case}.gltf");
        let path = write_gltf(dir.path(), &name, &material, "", extra);
        let (scene, notes) = load(&path, &name, None).expect("loads");
        assert!(notes.is_empty(), "{notes:?}");
        match &scene.materials[0] {
            rt_gpu::scene::Material::Pbr(p) => p.volume().copied(),
            other => panic!("{other:?}"),
        }
    };
    let tinted = r#"{ "thicknessFactor": 0.5, "attenuationDistance": 0.25, "attenuationColor": [0.5, 1, 0.25] }"#;
    let medium = read(volume(1.0, tinted)).expect("a volume");
    let want = Vec3::new(0.5f32.ln(), 0.0, 0.25f32.ln()) / -0.25;
    assert!(
        (medium.absorption - want).abs().max_element() < 1e-5,
        "{medium:?}"
    );
    assert_eq!(medium.density, 0.0);
    for (transmission, thin) in [
        (
            1.0,
            r#"{ "attenuationDistance": 0.25, "attenuationColor": [0.5, 1, 0.25] }"#,
        ),
        (0.0, tinted),
        (
            1.0,
            r#"{ "thicknessFactor": 1, "attenuationColor": [0.5, 1, 0.25] }"#,
        ),
        (1.0, r#"{ "thicknessFactor": 1, "attenuationDistance": 2 }"#),
    ] {
        assert!(
            read(volume(transmission, thin)).is_none(),
            "{transmission} {thin}"
        );
    }
}

/// Issue 63: KHR_materials_sheen's factors are read onto the pbr material, required or not (a
/// black colour, glTF's default, is no sheen); its colour texture becomes the sheen image and
/// its roughness texture's alpha channel the layers' blue; a note says where that texture takes
/// the roughness below rt-gpu's least, and only then.
#[test]
fn a_sheen_and_its_textures_are_read() {
    let dir = tempfile::tempdir().expect("temp dir");
    let extra = r#""extensionsUsed": ["KHR_materials_sheen"], "extensionsRequired": ["KHR_materials_sheen"],"#;
    let velvet = |ext: &str| {
        format!(
            r#"{{ "name": "Velvet", "pbrMetallicRoughness": {{ "metallicFactor": 0 }}, "extensions": {{ "KHR_materials_sheen": {ext} }} }}"#
        )
    };
    let mut case = 0;
    let mut read = |material: String, extra: &str| {
        case += 1;
        let name = format!("sheen{case}.gltf");
        let path = common::gltf::write_triangle(dir.path(), &name, true, &material, "", extra);
        let (scene, notes) = load(&path, &name, None).expect("loads");
        match &scene.materials[0] {
            rt_gpu::scene::Material::Pbr(p) => (p.sheen, notes),
            other => panic!("{other:?}"),
        }
    };
    let (sheen, notes) = read(
        velvet(r#"{ "sheenColorFactor": [1, 0.329, 0.1], "sheenRoughnessFactor": 0.8 }"#),
        extra,
    );
    let sheen = sheen.expect("a sheen");
    assert_eq!(
        (sheen.color, sheen.roughness),
        (Vec3::new(1.0, 0.329, 0.1), 0.8)
    );
    assert!(notes.is_empty(), "{notes:?}");
    // Black (the default colour) is no sheen, whose roughness no note names.
    for black in [
        r#"{ "sheenRoughnessFactor": 0.8 }"#,
        r#"{ "sheenRoughnessFactor": 0.1 }"#,
    ] {
        let (sheen, notes) = read(velvet(black), extra);
        assert!(sheen.is_none() && notes.is_empty(), "{sheen:?} {notes:?}");
    }
    let (_, notes) = read(velvet(r#"{ "sheenColorFactor": [1, 1, 1] }"#), extra);
    assert!(
        notes.len() == 1
            && notes[0].contains("sheenRoughnessFactor below 0.25 (1 material: taken as 0.25)"),
        "{notes:?}"
    );
    // A colour texture whose alpha channel is the roughness's, as SheenCloth's: RGB 200
    // (sRGB: 0.578 linear) and alpha 64 (linear: 0.251).
    image::RgbaImage::from_pixel(1, 1, image::Rgba([200, 200, 200, 64]))
        .save(dir.path().join("s.png"))
        .expect("writes");
    let images =
        format!(r#"{extra} "textures": [{{ "source": 0 }}], "images": [{{ "uri": "s.png" }}],"#);
    let textured = r#"{ "sheenColorFactor": [1, 1, 1], "sheenRoughnessFactor": 0.5, "sheenColorTexture": { "index": 0 }, "sheenRoughnessTexture": { "index": 0 } }"#;
    let path = common::gltf::write_triangle(
        dir.path(),
        "textured.gltf",
        true,
        &velvet(textured),
        "",
        &images,
    );
    let (scene, notes) = load(&path, "textured.gltf", None).expect("loads");
    let rt_gpu::scene::Material::Pbr(p) = &scene.materials[0] else {
        panic!("{:?}", scene.materials[0]);
    };
    // The factors as given; the textures scale them point by point.
    let sheen = p.sheen.expect("a sheen");
    assert_eq!((sheen.color, sheen.roughness), (Vec3::ONE, 0.5));
    let colour = p.sheen_image().expect("a sheen image").texel(0, 0);
    assert!(
        (colour - Vec3::splat(0.5776)).abs().max_element() < 1e-3,
        "{colour}"
    );
    let layers = p.layers().expect("a layers image").texel(0, 0);
    assert!(
        (layers - Vec3::new(1.0, 1.0, 64.0 / 255.0))
            .abs()
            .max_element()
            < 1e-6,
        "{layers}"
    );
    // Its roughness texture takes the roughness to 0.5 x 0.251, below rt-gpu's least: noted.
    assert!(
        notes.len() == 1
            && notes[0].contains(
                "the sheenRoughnessTexture of 1 material takes the sheen's roughness below 0.25 in places: taken as 0.25 there"
            ),
        "{notes:?}"
    );
    // At a factor of 1 the texel, 0.251, stays above it: nothing to note.
    let rough = textured.replace(
        "\"sheenRoughnessFactor\": 0.5",
        "\"sheenRoughnessFactor\": 1",
    );
    let path =
        common::gltf::write_triangle(dir.path(), "rough.gltf", true, &velvet(&rough), "", &images);
    let (_, notes) = load(&path, "rough.gltf", None).expect("loads");
    assert!(notes.is_empty(), "{notes:?}");
}

/// Issue 63: KHR_materials_specular's factors are read onto the pbr material, required or not
/// (the defaults, factor 1 and white, change nothing: no specular; a colour above 1 is the
/// extension's, allowed); bad values are one-line errors naming the field; its textures are
/// read where its factor lets them show (the factor's from an alpha channel, the colour's
/// from sRGB), on transmission too (the glass's Fresnel: nothing to note).
#[test]
fn a_specular_is_read_and_what_is_not_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    let extra = r#""extensionsUsed": ["KHR_materials_specular", "KHR_materials_transmission"], "extensionsRequired": ["KHR_materials_specular"],"#;
    let material = |ext: &str, more: &str| {
        format!(
            r#"{{ "name": "Glaze", "pbrMetallicRoughness": {{ "metallicFactor": 0 }}, "extensions": {{ "KHR_materials_specular": {ext} {more} }} }}"#
        )
    };
    let mut case = 0;
    let mut read = |material: String, extra: &str| {
        case += 1;
        let name = format!("specular{case}.gltf");
        let path = common::gltf::write_triangle(dir.path(), &name, true, &material, "", extra);
        load(&path, &name, None).map(|(scene, notes)| match &scene.materials[0] {
            rt_gpu::scene::Material::Pbr(p) => (p.specular().copied(), notes),
            other => panic!("{other:?}"),
        })
    };
    let (specular, notes) = read(
        material(
            r#"{ "specularFactor": 0.3, "specularColorFactor": [1, 0.5, 25] }"#,
            "",
        ),
        extra,
    )
    .expect("loads");
    let specular = specular.expect("a specular");
    assert_eq!(
        (specular.factor, specular.color),
        (0.3, Vec3::new(1.0, 0.5, 25.0))
    );
    assert!(notes.is_empty(), "{notes:?}");
    // The defaults change nothing, on transmission too: nothing to note.
    let transmits = r#", "KHR_materials_transmission": { "transmissionFactor": 0.5 }"#;
    for more in ["", transmits] {
        let (specular, notes) = read(material("{}", more), extra).expect("loads");
        assert!(
            specular.is_none() && notes.is_empty(),
            "{specular:?} {notes:?}"
        );
    }
    for (ext, field) in [
        (r#"{ "specularFactor": 1.5 }"#, "specularFactor is 1.5"),
        (
            r#"{ "specularColorFactor": [1, -1, 1] }"#,
            "specularColorFactor is [1,-1,1]",
        ),
        (
            r#"{ "specularColorFactor": "white" }"#,
            "specularColorFactor",
        ),
    ] {
        let error = read(material(ext, ""), extra).expect_err("a bad value");
        assert!(error.contains(field) && !error.contains('\n'), "{error}");
    }
    // A colour texture whose alpha channel is the factor's: RGB 200 (sRGB: 0.578 linear) and
    // alpha 64 (linear: 0.251).
    image::RgbaImage::from_pixel(1, 1, image::Rgba([200, 200, 200, 64]))
        .save(dir.path().join("s.png"))
        .expect("writes");
    let images =
        format!(r#"{extra} "textures": [{{ "source": 0 }}], "images": [{{ "uri": "s.png" }}],"#);
    let textured = r#"{ "specularFactor": 0.5, "specularTexture": { "index": 0 }, "specularColorTexture": { "index": 0 } }"#;
    let name = "textured.gltf";
    let path = common::gltf::write_triangle(
        dir.path(),
        name,
        true,
        &material(
            textured,
            r#", "KHR_materials_transmission": { "transmissionFactor": 0.5 }"#,
        ),
        "",
        &images,
    );
    let (scene, notes) = load(&path, name, None).expect("loads");
    let rt_gpu::scene::Material::Pbr(p) = &scene.materials[0] else {
        panic!("{:?}", scene.materials[0]);
    };
    // The factors as given; the textures scale them point by point.
    assert_eq!(p.specular().map(|s| s.factor), Some(0.5));
    let factor = p.specular_image().expect("a specular image").texel(0, 0);
    assert!((factor.x - 64.0 / 255.0).abs() < 1e-6, "{factor}");
    let colour = p
        .specular_color_image()
        .expect("a colour image")
        .texel(0, 0);
    assert!(
        (colour - Vec3::splat(0.5776)).abs().max_element() < 1e-3,
        "{colour}"
    );
    assert!(notes.is_empty(), "{notes:?}");
    // Textures alone keep the default factors' specular, which they scale.
    let path = common::gltf::write_triangle(
        dir.path(),
        "alone.gltf",
        true,
        &material(r#"{ "specularTexture": { "index": 0 } }"#, ""),
        "",
        &images,
    );
    let (scene, notes) = load(&path, "alone.gltf", None).expect("loads");
    let rt_gpu::scene::Material::Pbr(p) = &scene.materials[0] else {
        panic!("{:?}", scene.materials[0]);
    };
    assert_eq!(
        p.specular().map(|s| (s.factor, s.color)),
        Some((1.0, Vec3::ONE))
    );
    assert!(
        p.specular_image().is_some() && notes.is_empty(),
        "{notes:?}"
    );
    // A factor of 0 lets no texture show: they are not read (a missing one is no error).
    let (specular, _) = read(
        material(
            r#"{ "specularFactor": 0, "specularTexture": { "index": 7 } }"#,
            "",
        ),
        &images,
    )
    .expect("loads");
    assert_eq!(specular.map(|s| s.factor), Some(0.0));
    let error = read(
        material(r#"{ "specularColorTexture": { "index": 7 } }"#, ""),
        &images,
    )
    .expect_err("a missing texture");
    assert!(
        error.contains("specularColorTexture names texture 7, which does not exist"),
        "{error}"
    );
}
