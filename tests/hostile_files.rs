//! Hostile and malformed mesh files: each is one error naming the file and what is wrong (no
//! panic, no hang, no gigabytes read), and what is well-formed still loads. The cases are those
//! an adversarial run found (glTF node graphs, accessors, versions; OBJ material libraries,
//! encodings and vertex lines).

use rt_gpu::scene::mesh::load;
use serde_json::{Value, json};
use std::path::Path;

/// A quad (two triangles) as a glTF document whose buffer is `quad.bin` beside it: positions
/// (accessor 0, 4 x VEC3 FLOAT) then u16 indices (accessor 1, 6).
fn quad_gltf(dir: &Path) -> Value {
    let mut bin = Vec::new();
    for p in [
        [0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ] {
        p.iter().for_each(|c| bin.extend(c.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    std::fs::write(dir.join("quad.bin"), &bin).expect("writes");
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "name": "quad" }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "buffers": [{ "byteLength": bin.len(), "uri": "quad.bin" }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    })
}

/// Loads `doc` (under a new name each time: the loader caches files by name, size and time).
fn load_gltf(dir: &Path, doc: &Value, node: Option<&str>) -> Result<usize, String> {
    static CASE: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let case = CASE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let name = format!("case{case}.gltf");
    let path = dir.join(&name);
    std::fs::write(&path, serde_json::to_string(doc).expect("json")).expect("writes");
    load(&path, &name, node).map(|parts| parts.iter().map(|m| m.triangles.len()).sum())
}

fn refused(dir: &Path, doc: &Value, node: Option<&str>, what: &str) {
    let err = load_gltf(dir, doc, node).expect_err(what);
    assert!(err.contains(".gltf") && err.contains(what), "{err}");
    assert!(!err.contains('\n'), "{err}");
}

#[test]
fn malformed_gltf_files_are_one_line_errors_naming_the_problem() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let good = quad_gltf(d);
    assert_eq!(load_gltf(d, &good, None), Ok(2));

    // Node graphs: a node its own child, a shared child, a longer cycle.
    let mut own_child = good.clone();
    own_child["nodes"][0]["children"] = json!([0]);
    refused(d, &own_child, None, "its own child");
    let mut diamond = good.clone();
    diamond["nodes"] = json!([
        { "children": [1, 2] }, { "children": [3] }, { "children": [3] }, { "mesh": 0 }
    ]);
    refused(d, &diamond, None, "two parents");
    // A diamond without meshes is not called a cycle.
    let mut bare = diamond.clone();
    bare["nodes"][3] = json!({});
    let err = load_gltf(d, &bare, None).expect_err("diamond");
    assert!(
        err.contains("two parents") && !err.contains("cycle"),
        "{err}"
    );
    let mut cycle = good.clone();
    cycle["scenes"] = json!([{ "nodes": [] }]);
    cycle["nodes"] = json!([{ "children": [1], "mesh": 0 }, { "children": [0] }]);
    refused(d, &cycle, Some("x"), "cycle");

    // Accessors the gltf crate would panic on or misread.
    let mut float_indices = good.clone();
    float_indices["accessors"][1]["componentType"] = json!(5126);
    refused(d, &float_indices, None, "not SCALAR unsigned integers");
    let mut missing = good.clone();
    missing["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99);
    refused(d, &missing, None, "accessor 99");
    let mut overrun = good.clone();
    overrun["accessors"][1]["count"] = json!(12);
    refused(d, &overrun, None, "needs 24 bytes of buffer view 1");
    let mut partial = good.clone();
    partial["accessors"][1]["count"] = json!(5);
    refused(d, &partial, None, "not a multiple of 3");
    for (component, ty) in [(5121, "VEC3"), (5126, "VEC2"), (5126, "MAT4")] {
        let mut wrong = good.clone();
        wrong["accessors"][0]["componentType"] = json!(component);
        wrong["accessors"][0]["type"] = json!(ty);
        refused(d, &wrong, None, "POSITION (accessor 0)");
    }

    // Nodes and versions.
    let mut projective = good.clone();
    projective["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 1]);
    refused(d, &projective, None, "projective matrix");
    let mut far = good.clone();
    far["nodes"][0]["translation"] = json!([1e9, 0, 0]);
    refused(d, &far, None, "beyond 1e8");
    let mut future = good.clone();
    future["asset"]["version"] = json!("3.0");
    refused(d, &future, None, "glTF version 3.0");
    let mut twins = good.clone();
    twins["nodes"] = json!([{ "mesh": 0, "name": "a" }, { "mesh": 0, "name": "a" }]);
    twins["scenes"] = json!([{ "nodes": [0, 1] }]);
    refused(d, &twins, Some("a"), "several nodes named \"a\"");
    assert_eq!(load_gltf(d, &twins, None), Ok(4));

    // Buffers: a device is not read (it would be, without end), nor a short file trusted.
    let mut device = good.clone();
    device["buffers"][0]["uri"] = json!("/dev/zero");
    refused(d, &device, None, "not a regular file");
    let mut short = good.clone();
    short["buffers"][0]["byteLength"] = json!(1000);
    refused(d, &short, None, "fewer than its byteLength 1000");

    // A binary container whose header's length is below its own size (the gltf crate
    // subtracted unchecked: found by the coverage-guided fuzzer), or another version.
    for (name, bytes) in [
        ("short.gltf", b"glTF\x02\0\0\0\x04\0\0\0".to_vec()),
        ("v1.glb", b"glTF\x01\0\0\0\x0c\0\0\0".to_vec()),
        ("cut.glb", b"glTF\x02\0".to_vec()),
    ] {
        std::fs::write(d.join(name), &bytes).expect("writes");
        let err = load(&d.join(name), name, None).expect_err("bad container");
        assert!(err.contains(name) && err.contains("binary glTF"), "{err}");
        assert!(!err.contains("reader failed"), "{err}");
    }
    // A .glb whose magic is wrong says so, not "JSON error at 1:1".
    std::fs::write(d.join("bad.glb"), b"glTX\x02\0\0\0 not a glb").expect("writes");
    let err = load(&d.join("bad.glb"), "bad.glb", None).expect_err("bad magic");
    assert!(err.contains("not a binary glTF file"), "{err}");
}

#[test]
fn obj_material_libraries_are_not_opened_and_odd_text_is_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let body = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    let write = |name: &str, bytes: &[u8]| {
        std::fs::write(d.join(name), bytes).expect("writes");
        load(&d.join(name), name, None).map(|parts| parts.len())
    };
    // /dev/zero would be read until memory ran out, a FIFO would block forever.
    let libraries = format!("mtllib /dev/zero\nmtllib ../../etc/passwd\n{body}");
    assert_eq!(write("libs.obj", libraries.as_bytes()), Ok(1));
    #[cfg(unix)]
    {
        let fifo = d.join("fifo.mtl");
        if std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            let text = format!("mtllib fifo.mtl\n{body}");
            assert_eq!(write("fifo.obj", text.as_bytes()), Ok(1));
        }
    }
    // Latin-1 names load; UTF-16 says what it is.
    let mut latin1 = b"o caf\xe9\n".to_vec();
    latin1.extend(body.as_bytes());
    assert_eq!(write("latin1.obj", &latin1), Ok(1));
    let utf16: Vec<u8> = [0xff, 0xfe]
        .into_iter()
        .chain(body.encode_utf16().flat_map(|u| u.to_le_bytes()))
        .collect();
    let err = write("utf16.obj", &utf16).expect_err("UTF-16");
    assert!(err.contains("UTF-16"), "{err}");
    // Seven numbers on a vertex line: its line and what a vertex line may hold.
    let err = write("seven.obj", b"v 0 0 0\nv 1 0 0 1 1 1 1\nv 1 1 0\nf 1 2 3\n")
        .expect_err("seven numbers");
    assert!(
        err.contains("seven.obj:2") && err.contains("x y z r g b"),
        "{err}"
    );
}

/// A PNG that says it is `width` x `height` and holds no pixels (a few dozen bytes).
fn png_header_only(width: u32, height: u32) -> Vec<u8> {
    fn crc(bytes: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]); // 8-bit RGB
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    // The header, then an empty zlib stream as its only data, then the end.
    let idat = [
        b"IDAT".as_slice(),
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ]
    .concat();
    for chunk in [ihdr, idat, b"IEND".to_vec()] {
        png.extend((chunk.len() as u32 - 4).to_be_bytes());
        png.extend(&chunk);
        png.extend(crc(&chunk).to_be_bytes());
    }
    png
}

#[test]
fn images_are_checked_from_their_headers_and_radiance_files_of_any_writer_load() {
    use rt_gpu::scene::image::load as load_image;
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    // 16384^2: refused from the header, before gigabytes are decoded.
    std::fs::write(d.join("huge.png"), png_header_only(16384, 16384)).expect("writes");
    let start = std::time::Instant::now();
    let err = load_image(&d.join("huge.png"), "huge.png").expect_err("too large");
    assert!(err.contains("huge.png is 16384x16384"), "{err}");
    assert!(
        start.elapsed().as_secs_f64() < 1.0,
        "took {:?}",
        start.elapsed()
    );

    // Radiance HDR as Mitsuba writes it (#?RGBE), a flat 2x1 image of RGBE (128, 64, 32, 129).
    let pixels = [128u8, 64, 32, 129, 128, 64, 32, 129];
    let mut rgbe = b"#?RGBE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
    rgbe.extend(pixels);
    std::fs::write(d.join("mitsuba.hdr"), &rgbe).expect("writes");
    let image = load_image(&d.join("mitsuba.hdr"), "mitsuba.hdr").expect("#?RGBE loads");
    assert_eq!((image.width, image.height), (2, 1));
    // A header cut short says so.
    std::fs::write(d.join("cut.hdr"), b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n").expect("writes");
    let err = load_image(&d.join("cut.hdr"), "cut.hdr").expect_err("truncated");
    assert!(
        err.contains("cut.hdr") && err.contains("header is truncated"),
        "{err}"
    );
}

// Runs the command line.
#[cfg(feature = "cli")]
#[test]
fn errors_say_what_to_do_with_meshes_and_incomplete_scenes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
            .args(args)
            .current_dir(d)
            .output()
            .expect("runs");
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(
            err.lines().filter(|l| l.starts_with("error")).count(),
            1,
            "{err}"
        );
        err
    };
    std::fs::write(d.join("model.obj"), b"v 0 0 0\n").expect("writes");
    let err = run(&["model.obj"]);
    assert!(
        err.contains("is a mesh") && err.contains("[[object]]"),
        "{err}"
    );
    // A glTF file is a scene of its own: a truncated one is an error naming it.
    std::fs::write(d.join("model.glb"), b"glTF").expect("writes");
    let err = run(&["model.glb"]);
    assert!(err.contains("model.glb"), "{err}");
    std::fs::write(
        d.join("nocamera.toml"),
        "[[object]]\nsphere = { center = [0, 0, 0], radius = 1 }\nmaterial = \"m\"\n",
    )
    .expect("writes");
    let err = run(&["nocamera.toml"]);
    assert!(
        err.contains("no [camera] table") && !err.contains("(in `"),
        "{err}"
    );
}

/// A checker finer than f32 resolves where the scene lies would render as one colour or noise:
/// refused, saying the finest scale that works.
#[test]
fn checkers_finer_than_f32_resolves_are_refused() {
    let scene = |checker: &str| {
        format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nc = {{ type = \"lambertian\", albedo = {{ {checker} }} }}\n\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 1 }}\nmaterial = \"c\"\n"
        )
    };
    let flat = |checker: &str| {
        let scene = rt_gpu::scene::file::parse(&scene(checker), "c.toml", "c").expect("parses");
        rt_gpu::scene::flat::FlatScene::new(&scene, 4, 4).map(|_| ())
    };
    let colours = "even = [1, 1, 1], odd = [0, 0, 0]";
    assert!(flat(&format!("checker = {{ scale = 0.1, {colours} }}")).is_ok());
    let err = flat(&format!("checker = {{ scale = 1e-30, {colours} }}")).expect_err("too fine");
    assert!(err.to_string().contains("finer than f32 resolves"), "{err}");
    let err = flat(&format!("uv_checker = {{ scale = 1e7, {colours} }}")).expect_err("too many");
    assert!(err.to_string().contains("at most 65536"), "{err}");
}
