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
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/dev/zero", d.join("zero.bin")).expect("links");
        let mut device = good.clone();
        device["buffers"][0]["uri"] = json!("zero.bin");
        refused(d, &device, None, "not a regular file");
    }
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

/// Issue 61: buffers are read by the one path that is checked, as images are (percent-decoded,
/// inside the file's folder: no absolute path, `..` or `file://`; a FIFO is refused, not waited
/// on); accessors' counts, with or without a view, sparse or not, are bounded before anything is
/// allocated; a stride shorter than an element names its accessor.
#[test]
fn gltf_buffers_and_accessors_are_bounded_before_anything_is_read_or_allocated() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let good = quad_gltf(d);

    // A correctly encoded name loads (it was refused: "No such file").
    std::fs::copy(d.join("quad.bin"), d.join("buf pct.bin")).expect("copies");
    let mut encoded = good.clone();
    encoded["buffers"][0]["uri"] = json!("buf%20pct.bin");
    assert_eq!(load_gltf(d, &encoded, None), Ok(2));
    // What images refuse, buffers refuse too.
    let absolute = d.join("quad.bin").display().to_string();
    for uri in [
        absolute.clone(),
        format!("file://{absolute}"),
        "../quad.bin".to_string(),
        "sub/../../quad.bin".to_string(),
    ] {
        let mut outside = good.clone();
        outside["buffers"][0]["uri"] = json!(uri);
        refused(d, &outside, None, "leaves the glTF file's folder");
    }
    // The name checked is the name read: `f%41.bin` is `fA.bin`, here a FIFO (it hung the
    // reader, which opened the decoded name after the check had looked at the other).
    #[cfg(unix)]
    {
        std::fs::copy(d.join("quad.bin"), d.join("f%41.bin")).expect("copies");
        let status = std::process::Command::new("mkfifo")
            .arg(d.join("fA.bin"))
            .status()
            .expect("mkfifo runs");
        assert!(status.success());
        let mut fifo = good.clone();
        fifo["buffers"][0]["uri"] = json!("f%41.bin");
        refused(d, &fifo, None, "not a regular file");
    }

    // POSITION as a sparse accessor with no view and a count of 3e9 (it aborted allocating
    // 72 GB) or 3e8 (it grew to 23.6 GB): refused at once.
    for count in [3_000_000_000u64, 300_000_000] {
        let mut sparse = good.clone();
        sparse["accessors"][0] = json!({
            "componentType": 5126, "count": count, "type": "VEC3",
            "min": [0, 0, 0], "max": [1, 1, 0],
            "sparse": {
                "count": 1,
                "indices": { "bufferView": 1, "componentType": 5123 },
                "values": { "bufferView": 0 }
            }
        });
        sparse["meshes"][0]["primitives"][0]
            .as_object_mut()
            .expect("primitive")
            .remove("indices");
        let start = std::time::Instant::now();
        let err = load_gltf(d, &sparse, None).expect_err("huge sparse accessor");
        assert!(
            err.contains("accessor 0") && err.contains(&count.to_string()),
            "{err}"
        );
        assert!(
            start.elapsed().as_secs_f64() < 5.0,
            "took {:?}",
            start.elapsed()
        );
    }
    // A sparse block outside its view, and more sparse values than elements.
    let mut outside = good.clone();
    outside["accessors"][0]["sparse"] = json!({
        "count": 4,
        "indices": { "bufferView": 1, "byteOffset": 8, "componentType": 5123 },
        "values": { "bufferView": 0 }
    });
    refused(
        d,
        &outside,
        None,
        "accessor 0's sparse indices needs 16 bytes of buffer view 1",
    );
    outside["accessors"][0]["sparse"]["count"] = json!(5);
    refused(d, &outside, None, "5 sparse values, more than its count 4");
    // A stride shorter than an element names the accessor.
    let mut stride = good.clone();
    stride["bufferViews"][0]["byteStride"] = json!(8);
    refused(d, &stride, None, "accessor 0 has elements of 12 bytes");
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
    use rt_gpu::assets::image::load as load_image;
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

/// `--backend gpu` refuses an environment its adapter cannot hold from the image's header, in
/// well under a second, rather than after decoding it (gigabytes and seconds).
#[cfg(feature = "cli")]
#[test]
fn images_the_gpu_cannot_hold_are_refused_from_their_headers() {
    let (info, limits) = match rt_gpu::gpu::context::adapter_limits(None) {
        Ok(adapter) => adapter,
        Err(e) if std::env::var_os("RT_GPU_REQUIRE_GPU").is_some() => {
            panic!("RT_GPU_REQUIRE_GPU is set but the GPU is unavailable: {e}")
        }
        Err(e) => return eprintln!("skipping GPU test: {e}"),
    };
    let capacity = rt_gpu::gpu::renderer::image_capacity(&limits);
    // Just over what the adapter holds, within what an image may have (lavapipe: 16384x4097).
    let (width, height) = (16384u64, capacity / 16384 + 1);
    if width * height > rt_gpu::assets::image::MAX_TEXELS {
        return eprintln!("skipping: {} holds any image rt-gpu reads", info.name);
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::write(d.join("sky.png"), png_header_only(16384, height as u32)).expect("writes");
    std::fs::write(
        d.join("sky.toml"),
        "[render]\nbackground = { image = \"sky.png\" }\n[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1]\nvfov = 40\n[materials]\ngrey = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n[[object]]\nsphere = { center = [0, 0, -3], radius = 1 }\nmaterial = \"grey\"\n",
    )
    .expect("writes");
    let start = std::time::Instant::now();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args([
            "sky.toml",
            "--backend",
            "gpu",
            "--spp",
            "1",
            "-o",
            "out.png",
        ])
        .current_dir(d)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!("sky.png is 16384x{height}"))
            && err.contains("largest texture holds")
            && err.contains("--backend cpu"),
        "{err}"
    );
    assert!(
        start.elapsed().as_secs_f64() < 5.0,
        "took {:?}",
        start.elapsed()
    );
    assert!(!d.join("out.png").exists());
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

/// Issue 61: an MTL map's options are read as the MTL specification gives them, so a file name
/// after them keeps its spaces; a `-bm` or `Ke` that is not a finite number is refused naming
/// the material, and a bright `Ke` is kept, not clamped.
#[test]
fn mtl_map_options_and_emission_are_read_or_refused_never_guessed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    // A normal map's colours (not grey) with a bump of `tex.png` beside `my tex.png`.
    let mut film = rt_gpu::film::Film::new(2, 2);
    for (i, p) in film.pixels.iter_mut().enumerate() {
        p.add_indexed(glam::Vec3::new(0.5, 0.4 + 0.1 * i as f32, 1.0), 0);
    }
    rt_gpu::film::output::write_image(&d.join("my tex.png"), &film).expect("writes");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl paint\nf 1/1 2/2 3/3\n";
    static CASE: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let load_with = |mtl: &str| {
        let case = CASE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        std::fs::write(d.join("m.mtl"), mtl).expect("mtl");
        let name = format!("m{case}.obj");
        std::fs::write(d.join(&name), obj).expect("obj");
        load(&d.join(&name), &name, None)
    };
    // The name with its space: `tex.png` does not exist, so reading it would fail.
    let parts = load_with("newmtl paint\nmap_Kd -s 2 2 1 my tex.png\n").expect("loads");
    let source = match &parts[0].material {
        Some(rt_gpu::scene::Material::Pbr(pbr)) => match &pbr.base_color {
            rt_gpu::assets::texture::Texture::Image(image) => image.source.clone(),
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    };
    assert!(source.ends_with("my tex.png"), "{source}");
    for (mtl, words) in [
        ("newmtl paint\nmap_Bump -bm nan my tex.png\n", "-bm"),
        ("newmtl paint\nKe inf 1 1\n", "Ke"),
        ("newmtl paint\nKe nan 1 1\n", "Ke"),
    ] {
        let err = load_with(mtl).expect_err(mtl);
        assert!(
            err.contains("\"paint\"") && err.contains(words),
            "{mtl}: {err}"
        );
    }
    // What follows the options is the name, its spaces and a leading '-' kept.
    let err = load_with("newmtl paint\nmap_Kd -s 2 2 1 -zz  my tex.png\n").expect_err("no file");
    assert!(err.contains("-zz  my tex.png"), "{err}");
    let parts = load_with("newmtl paint\nKe 1e30 1e30 1e30\n").expect("loads");
    match &parts[0].material {
        Some(rt_gpu::scene::Material::Light(light)) => {
            assert_eq!(light.radiance, glam::Vec3::splat(1e30).into())
        }
        other => panic!("{other:?}"),
    }
    // An emitter's `d` below 1 makes it see-through, as any other material's.
    let parts = load_with("newmtl paint\nKe 2 2 2\nd 0.25\n").expect("loads");
    match &parts[0].material {
        Some(rt_gpu::scene::Material::Light(light)) => assert_eq!(
            light.alpha.as_ref().map(|a| (a.mode, a.factor)),
            Some((rt_gpu::assets::alpha::AlphaMode::Blend, 0.25))
        ),
        other => panic!("{other:?}"),
    }
}

/// Issue 61: a material library that is not read is named with the reason where a part is left
/// without its material (every refusal said only `part "default" has no material of its own`),
/// and a line naming two libraries (valid OBJ) reads both.
#[test]
fn refused_material_libraries_are_named_and_two_on_a_line_are_read() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::write(d.join("a.mtl"), "newmtl red\nKd 1 0 0\n").expect("writes");
    std::fs::write(d.join("b.mtl"), "newmtl blue\nKd 0 0 1\n").expect("writes");
    std::fs::write(d.join("big.mtl"), vec![b'#'; (16 << 20) + 1]).expect("writes");
    let faces = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    static CASE: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let scene_with = |obj: &str| {
        let case = CASE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let name = format!("libs{case}.obj");
        std::fs::write(d.join(&name), obj).expect("writes");
        let text = format!(
            "[camera]\nlook_from = [0, 0, 3]\nlook_at = [0, 0, 0]\nvfov = 40\n[[object]]\nmesh = {{ file = \"{}\" }}\n",
            d.join(&name).display()
        );
        rt_gpu::scene::file::parse(&text, "libs.toml", "libs")
    };
    let two = format!("mtllib a.mtl b.mtl\n{faces}usemtl red\nf 1 2 3\nusemtl blue\nf 1 3 4\n");
    let scene = scene_with(&two).expect("both libraries read");
    assert_eq!(scene.materials.len(), 2);
    for (library, why) in [
        ("missing.mtl", "cannot be read"),
        ("/dev/zero", "not a relative path"),
        ("../a.mtl", "not a relative path"),
        ("big.mtl", "bytes, more than"),
    ] {
        let obj = format!("mtllib {library}\n{faces}usemtl red\nf 1 2 3\n");
        let err = scene_with(&obj).expect_err(library).to_string();
        assert!(
            err.contains("has no material of its own")
                && err.contains(library)
                && err.contains(why),
            "{library}: {err}"
        );
    }
}
