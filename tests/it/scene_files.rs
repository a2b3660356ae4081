//! Scene files: the files in scenes/ are the built-ins, and bad files give located errors.

use crate::common;

use rt_gpu::scene::builtin::{BUILTINS, builtin};
use rt_gpu::scene::file::{load, parse, to_toml};
use rt_gpu::scene::{Material, Scene, Shape, Transform};
use std::path::Path;

/// The built-ins are the files in scenes/, and every one parses.
#[test]
fn every_builtin_is_its_scene_file() {
    for (name, _) in BUILTINS {
        let from_file =
            load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml")))
                .unwrap_or_else(|e| panic!("scenes/{name}.toml: {e:#}"));
        let expected = builtin(name).expect("built-in");
        assert_eq!(resolved(&from_file), resolved(&expected), "{name}");
        assert!(!expected.objects.is_empty(), "{name}");
    }
}

/// A scene with material references resolved: files list materials in name order.
#[allow(clippy::type_complexity)]
fn resolved(s: &Scene) -> (String, Vec<(Shape, Transform, Material, String)>) {
    let objects = s
        .objects
        .iter()
        .map(|o| {
            let m = o.material as usize;
            (
                o.shape.clone(),
                o.transform,
                s.materials[m].clone(),
                s.material_names[m].clone(),
            )
        })
        .collect();
    (
        format!("{:?} {:?} {:?}", s.camera, s.background, s.defaults),
        objects,
    )
}

#[test]
fn export_round_trips() {
    for (name, _) in BUILTINS {
        let scene = builtin(name).expect("built-in");
        let text = to_toml(&scene);
        assert_eq!(
            resolved(&parse(&text, "x.toml", name).expect("parses")),
            resolved(&scene)
        );
    }
}

/// A disk's syntax: it parses, writes back as it was read, and a disk of no normal or of a
/// negative radius is refused with a located error naming the problem.
#[test]
fn disks_parse_write_back_and_are_checked() {
    let sphere = "sphere = { center = [0, 0, 0], radius = 0.5 }";
    let disk = |fields: &str| {
        GOOD.replace(
            sphere,
            &format!("disk = {{ center = [0, 0, 0], {fields} }}"),
        )
    };
    let scene = parse(&disk("normal = [0, 0, 2], radius = 0.5"), "d.toml", "d").expect("parses");
    assert_eq!(
        scene.objects[0].shape,
        Shape::Surface(rt_gpu::shape::SurfaceParams::Disk(
            rt_gpu::shape::DiskParams {
                center: glam::Vec3::ZERO,
                normal: glam::Vec3::new(0.0, 0.0, 2.0),
                radius: 0.5
            }
        ))
    );
    let again = parse(&to_toml(&scene), "d.toml", "d").expect("parses");
    assert_eq!(resolved(&again), resolved(&scene));
    for (fields, message) in [
        (
            "normal = [0, 0, 0], radius = 1",
            "disk normal must be finite and non-zero",
        ),
        (
            "normal = [0, 1, 0], radius = -1",
            "disk radius -1 is outside",
        ),
        ("normal = [0, 1, 0]", "missing field `radius`"),
    ] {
        let error = common::scene_error(&disk(fields));
        assert!(error.contains(message), "{fields}: {error}");
        assert!(
            error.contains("bad.toml:"),
            "{fields}: not located: {error}"
        );
    }
}

const GOOD: &str = r#"
[camera]
look_from = [0, 0, 1]
look_at = [0, 0, 0]
vfov = 40

[materials]
white = { type = "lambertian", albedo = [0.7, 0.7, 0.7] }

[[object]]
sphere = { center = [0, 0, 0], radius = 0.5 }
material = "white"
"#;

use common::scene_error as error_of;

#[test]
fn a_minimal_file_loads_with_defaults() {
    let scene = parse(GOOD, "good.toml", "good").expect("parses");
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.defaults.max_depth, 10);
}

#[test]
fn bad_files_name_the_file_line_and_problem() {
    let cases: &[(&str, &str, &str, &str)] = &[
        // (replace this, with this, expected location, expected words)
        (
            "radius = 0.5",
            "radius = 0.5, colour = 1",
            "bad.toml:11:",
            "unknown field `colour`",
        ),
        (
            "vfov = 40",
            "vfov = \"wide\"",
            "bad.toml:5:",
            "invalid type",
        ),
        ("radius = 0.5", "radius = nan", "bad.toml:11:", "finite"),
        (
            "look_at = [0, 0, 0]",
            "look_at = [0, 0, inf]",
            "bad.toml:4:",
            "finite",
        ),
        ("radius = 0.5", "radius = 0", "bad.toml:10:", "non-zero"),
        // Absurd sizes: squares would overflow or underflow f32.
        (
            "radius = 0.5",
            "radius = 1e30",
            "bad.toml:10:",
            "between 1e-6 and 1e8",
        ),
        (
            "radius = 0.5",
            "radius = 1e-9",
            "bad.toml:10:",
            "between 1e-6 and 1e8",
        ),
        (
            "sphere = { center = [0, 0, 0], radius = 0.5 }",
            "sphere = { center = [3e9, 0, 0], radius = 0.5 }",
            "bad.toml:10:",
            "beyond 1e8",
        ),
        (
            "sphere = { center = [0, 0, 0], radius = 0.5 }",
            "quad = { q = [0, 0, 0], u = [1e-7, 0, 0], v = [0, 1, 0] }",
            "bad.toml:10:",
            "between 1e-6 and 1e8",
        ),
        (
            "look_at = [0, 0, 0]",
            "look_at = [0, 0, 1]",
            "bad.toml:2:",
            "look_from equals look_at",
        ),
        (
            "look_at = [0, 0, 0]",
            "look_at = [0, 5, 1]\nup = [0, 1, 0]",
            "bad.toml:2:",
            "parallel",
        ),
        (
            "material = \"white\"",
            "material = \"black\"",
            "bad.toml:10:",
            "unknown material \"black\"",
        ),
        (
            "albedo = [0.7, 0.7, 0.7]",
            "albedo = [0.7, 1.7, 0.7]",
            "bad.toml:8:",
            "[0, 1]",
        ),
        (
            "albedo = [0.7, 0.7, 0.7]",
            "albedo = [0.7, 0.7]",
            "bad.toml:8:",
            "3 numbers",
        ),
        (
            "sphere = { center = [0, 0, 0], radius = 0.5 }",
            "quad = { q = [0, 0, 0], u = [1, 0, 0], v = [2, 0, 0] }",
            "bad.toml:10:",
            "zero area",
        ),
        (
            "sphere = { center = [0, 0, 0], radius = 0.5 }",
            "box = { min = [0, 0, 0], max = [1, 0, 1] }",
            "bad.toml:10:",
            "max > min",
        ),
        (
            "sphere = { center = [0, 0, 0], radius = 0.5 }",
            "",
            "bad.toml:10:",
            "exactly one of",
        ),
        ("vfov = 40", "vfov = 180", "bad.toml:2:", "field of view"),
        ("[camera]", "[camera]\n[camera]", "bad.toml:3:", "camera"),
        // Values checked after parsing still point at their own line (once all at 1:1).
        (
            "[camera]",
            "[render]\nheight = 8\nwidth = 0\n[camera]",
            "bad.toml:4:9:",
            "render.width must be in 1..=",
        ),
        (
            "[camera]",
            "[render]\nmax_depth = 100000\n[camera]",
            "bad.toml:3:13:",
            "render.max_depth",
        ),
        (
            "white = {",
            "gold = { type = \"metal\", albedo = [1, 1, 1], fuzz = 2 }\nwhite = {",
            "bad.toml:8:",
            "fuzz must be in [0, 1]",
        ),
        (
            "white = {",
            "glass = { type = \"dielectric\", ior = -1 }\nwhite = {",
            "bad.toml:8:",
            "ior must be in [0.01, 100]",
        ),
        (
            "material = \"white\"",
            "material = \"white\"\ntranslate = [2e8, 0, 0]",
            "bad.toml:13:13:",
            "beyond 1e8",
        ),
        // One message for a background, not serde's \"did not match any variant\".
        (
            "[camera]",
            "[render]\nbackground = \"skyy\"\n[camera]",
            "bad.toml:3:14:",
            "background must be a colour [r, g, b], \"sky\" or { image = \"file\", strength, rotate_y }, got \"skyy\"",
        ),
        (
            "[camera]",
            "[render]\nbackground = [1, -1, 0]\n[camera]",
            "bad.toml:3:14:",
            "no negative component",
        ),
        (
            "[camera]",
            "[render]\nbackground = 3\n[camera]",
            "bad.toml:3:14:",
            "got 3",
        ),
        (
            "[camera]",
            &format!(
                "x = {}1{}\n[camera]",
                "[".repeat(100_000),
                "]".repeat(100_000)
            ),
            "bad.toml:2:",
            "recurse",
        ),
    ];
    for (from, to, location, words) in cases {
        assert!(GOOD.contains(from), "{from}");
        let text = GOOD.replacen(from, to, 1);
        let message = error_of(&text);
        assert!(
            message.starts_with(location),
            "{message:?} should start with {location}"
        );
        assert!(
            message.contains(words),
            "{message:?} should mention {words}"
        );
        assert!(!message.contains('\n'), "{message:?} is not one line");
    }
}

/// Names and lines quoted in messages are cut short (a 5 000-character name was echoed whole),
/// and invalid UTF-8 is located.
#[test]
fn long_names_are_cut_and_bad_bytes_located() {
    let long = "x".repeat(5000);
    let text = GOOD.replacen("material = \"white\"", &format!("material = \"{long}\""), 1);
    let message = error_of(&text);
    assert!(
        message.contains("unknown material") && message.len() < 300,
        "{message}"
    );
    let text = GOOD.replacen("vfov = 40", &format!("vfov = 40 {long}"), 1);
    let message = error_of(&text);
    assert!(
        message.starts_with("bad.toml:5:") && message.len() < 400,
        "{message}"
    );

    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("latin1.toml");
    let mut bytes = GOOD.replacen("white", "whit", 1).into_bytes();
    let at = GOOD.find("white").expect("white") + 4;
    bytes.insert(at, 0xE9); // "é" in Latin-1
    std::fs::write(&path, bytes).expect("write");
    let message = rt_gpu::scene::file::load(&path)
        .expect_err("not UTF-8")
        .to_string();
    assert!(
        message.contains("latin1.toml:8:5:") && message.contains("UTF-8"),
        "{message}"
    );
}

/// Files are parsed object by object where that gives the same tables (50 MB scenes took 9 s
/// and 2.4 GB parsed whole): errors in later objects keep their line and column, and files
/// that cannot be cut (a table after the objects) still parse.
#[test]
fn object_by_object_parsing_keeps_positions_and_meaning() {
    let object =
        "\n[[object]]\nsphere = { center = [0, 0, 0], radius = 0.5 }\nmaterial = \"white\"\n";
    let three = format!(
        "{GOOD}{object}{}",
        object.replace("radius = 0.5", "radius = 0")
    );
    let message = error_of(&three);
    assert!(message.starts_with("bad.toml:18:1:"), "{message}");
    let message = error_of(&format!(
        "{GOOD}{object}\n[[object]]\nsphere = {{ center = [0, 0, nan], radius = 1 }}\n"
    ));
    assert!(message.starts_with("bad.toml:19:"), "{message}");

    let late_table = format!("{GOOD}{object}\n[render]\nmax_depth = 3\n");
    let scene = parse(&late_table, "late.toml", "late").expect("parses");
    assert_eq!((scene.objects.len(), scene.defaults.max_depth), (2, 3));
    let sub_table = format!(
        "{GOOD}\n[[object]]\nmaterial = \"white\"\n[object.sphere]\ncenter = [1, 0, 0]\nradius = 2\n"
    );
    let scene = parse(&sub_table, "sub.toml", "sub").expect("parses");
    assert_eq!(scene.objects.len(), 2);
    assert_eq!(
        scene.objects[1].shape,
        rt_gpu::scene::Shape::sphere(glam::Vec3::X, 2.0)
    );
}

/// The format reference in scenes/README.md is itself a valid scene.
#[test]
fn the_documented_example_parses() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/README.md"))
            .expect("scenes/README.md");
    let start = doc.find("```toml\n").expect("a toml block") + "```toml\n".len();
    let end = start + doc[start..].find("```").expect("closed");
    // Its image paths are relative to scenes/, as a file there would have them.
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let loader = rt_gpu::assets::loader::Loader::new(&scenes);
    let scene =
        rt_gpu::scene::file::parse_with(&loader, &doc[start..end], "scenes/README.md", "example")
            .unwrap_or_else(|e| panic!("{e}"));
    // Four shapes (a sphere, a quad, a disk, a box) and the knot of scenes/models/knot.obj.
    assert_eq!(scene.objects.len(), 5);
    assert_eq!(scene.materials.len(), 16);
}

/// Assets are owned: a scene read again while the first is held shares its images and meshes
/// (decoded once); a file edited to name others frees the old ones once the old scene (and its
/// flat form) is dropped, as the viewer's reload does.
#[test]
fn reloading_an_edited_scene_frees_what_it_no_longer_reads() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let dir = tempfile::tempdir().expect("temp dir");
    for file in [
        "textures/tiles.png",
        "textures/planet.png",
        "models/knot.obj",
    ] {
        let name = Path::new(file).file_name().expect("a name");
        std::fs::copy(repo.join(file), dir.path().join(name)).expect("copies");
    }
    let scene_text = |image: &str| {
        format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n\
             [materials.paint]\ntype = \"lambertian\"\nalbedo = {{ image = \"{image}\" }}\n\
             [[object]]\nmesh = {{ file = \"knot.obj\" }}\nmaterial = \"paint\"\n"
        )
    };
    let path = dir.path().join("scene.toml");
    let image_of = |s: &Scene| match &s.materials[0] {
        Material::Lambertian(l) => match &l.albedo {
            rt_gpu::assets::texture::Texture::Image(image) => image.clone(),
            other => panic!("not an image: {other:?}"),
        },
        other => panic!("not lambertian: {other:?}"),
    };
    let mesh_of = |s: &Scene| match &s.objects[0].shape {
        Shape::Mesh { mesh, .. } => mesh.clone(),
        other => panic!("not a mesh: {other:?}"),
    };
    std::fs::write(&path, scene_text("tiles.png")).expect("writes");
    let first = load(&path).expect("loads");
    let flat = rt_gpu::scene::flat::FlatScene::new(&first, 8, 8).expect("flattens");
    let again = load(&path).expect("loads again");
    assert!(
        std::sync::Arc::ptr_eq(&image_of(&first), &image_of(&again)),
        "decoded once"
    );
    assert!(
        std::sync::Arc::ptr_eq(&mesh_of(&first), &mesh_of(&again)),
        "read once"
    );
    drop(again);
    let (tiles, knot) = (
        std::sync::Arc::downgrade(&image_of(&first)),
        std::sync::Arc::downgrade(&mesh_of(&first)),
    );
    // Edited to read another image: the reload decodes it, and the old scene still holds
    // the first until it goes.
    std::fs::write(&path, scene_text("planet.png")).expect("writes");
    let edited = load(&path).expect("loads the edit");
    assert!(image_of(&edited).source.contains("planet"));
    assert!(tiles.upgrade().is_some(), "held by the first scene");
    drop((first, flat));
    assert!(
        tiles.upgrade().is_none(),
        "the image no scene reads is freed"
    );
    assert!(
        knot.upgrade().is_some(),
        "the mesh the edit still reads is kept"
    );
    assert!(std::sync::Arc::ptr_eq(
        &knot.upgrade().expect("held"),
        &mesh_of(&edited)
    ));
    drop(edited);
    assert!(knot.upgrade().is_none(), "and freed with the last scene");
}

/// Objects that each place one part of a mesh file share that file, read once for the parse
/// (the other parts are held while it reads): so a part placed many times is instanced.
#[test]
fn objects_placing_one_part_of_a_file_share_it() {
    let lamp = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/models/lamp.gltf");
    let object = |x: i32| {
        format!(
            "[[object]]\nmesh = {{ file = \"{}\", part = 1 }}\ntranslate = [{x}, 0, 0]\n",
            lamp.display()
        )
    };
    let text = format!(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n{}{}",
        object(0),
        object(3)
    );
    let scene = parse(&text, "parts.toml", "parts").expect("parses");
    let [Shape::Mesh { mesh: a, .. }, Shape::Mesh { mesh: b, .. }] =
        [&scene.objects[0].shape, &scene.objects[1].shape]
    else {
        panic!("two meshes");
    };
    assert!(std::sync::Arc::ptr_eq(a, b), "one read of the file");
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("flattens");
    assert_eq!(flat.instances.len(), 2, "the part instanced twice");
}

/// A punctual light's table (`scene::file::light_table`, what Python's `Scene.lights` gives)
/// reads back as the same light: a spot's direction to f32's precision (within 1e-6) wherever
/// it stands, far from the origin too (its look-at is placed as far along it as it is out).
#[test]
fn light_tables_read_back_as_their_lights() {
    use glam::Vec3;
    use rt_gpu::scene::file::{light_from_table, light_table};
    use rt_gpu::scene::punctual::Punctual;
    let direction = Vec3::new(0.3, -0.8, 0.52).normalize();
    for far in [1.0f32, 1e3, 1e5, 1e7] {
        let spot = Punctual::Spot {
            position: Vec3::new(far, -0.5 * far, 0.25),
            direction,
            intensity: Vec3::new(1.0, 2.0, 3.0),
            inner: 0.2,
            outer: 0.5,
        };
        let back = light_from_table(light_table(&spot).expect("a table")).expect("reads");
        let Punctual::Spot {
            position,
            direction: d,
            intensity,
            ..
        } = back
        else {
            panic!("{back:?}");
        };
        assert_eq!(
            (position, intensity),
            (Vec3::new(far, -0.5 * far, 0.25), Vec3::new(1.0, 2.0, 3.0))
        );
        assert!(
            (d - direction).length() < 1e-6,
            "at {far}: {d} against {direction}"
        );
    }
    let sun = Punctual::Directional {
        direction,
        irradiance: Vec3::splat(2.0),
    };
    let back = light_from_table(light_table(&sun).expect("a table")).expect("reads");
    assert!(
        matches!(back, Punctual::Directional { irradiance, .. } if irradiance == Vec3::splat(2.0))
    );
}
