//! A mutation fuzzer for the mesh and film loaders, on the stable toolchain and bounded so CI
//! can afford it (the coverage-guided twin is `fuzz/fuzz_targets/mesh_and_film_files.rs`):
//! small OBJ files, the shipped glTF lamp (as .gltf beside its buffer, and as one .glb) and
//! a film file, mutated as tests/it/fuzz_scene_files.rs mutates scenes, with tokens that have
//! broken these loaders (accessor types and counts, node cycles, device paths, huge numbers).
//!
//! Passing means: no panic (nor the glTF or OBJ loader's own panic guard firing: that is a
//! panic in the `gltf` crate or tobj that the checks missed), every error one line naming the
//! file, and every mesh that loads finite. Seeded; `RT_GPU_FUZZ_EXECUTIONS` (default 3000) and
//! `RT_GPU_FUZZ_SEED` (default 1) set the run.

use crate::common;
use crate::common::gltf_mutations;

use common::mutate::Mutator;
use std::path::Path;

const TOKENS: &[&str] = &[
    "\"componentType\": 5126",
    "\"componentType\": 5121",
    "\"type\": \"MAT4\"",
    "\"type\": \"VEC2\"",
    "\"count\": 4294967295",
    "\"count\": 0",
    "\"byteOffset\": 4294967295",
    "\"byteStride\": 252",
    "\"children\": [0]",
    "\"children\": [0, 0]",
    "\"mesh\": 99",
    "\"indices\": 99",
    "\"POSITION\": 99",
    "\"uri\": \"/dev/zero\"",
    "\"uri\": \"data:application/octet-stream;base64,AAAA\"",
    "\"matrix\": [1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]",
    "\"translation\": [1e9, 0, 0]",
    "\"scale\": [0, 0, 0]",
    "\"version\": \"3.0\"",
    "\"extensionsRequired\": [\"KHR_draco_mesh_compression\"]",
    "mtllib /dev/zero\n",
    "mtllib ../../etc/passwd\n",
    "v 1e39 0 0\n",
    "v 1 2 3 4 5 6 7\n",
    "vn nan 0 0\n",
    "f 1 2 999999\n",
    "f -5 -6 -7\n",
    "f 1//1 2//2 3//3\n",
    "vt 0.5\n",
    "o \u{e9}\n",
    "\0",
    "-1",
    "1e39",
    "nan",
    "4294967296",
    "{",
    "}",
    "[",
    "]",
    ",",
    "\n",
];

const CUBE_OBJ: &str = "# a cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nvn 0 0 -1\nvn 0 0 1\nf 1//1 3//1 2//1\nf 1//1 4//1 3//1\nf 5//2 6//2 7//2\nf 5//2 7//2 8//2\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

/// A binary glTF of `json` and `bin`, as the container's specification lays it out.
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |mut v: Vec<u8>, with: u8| {
        while !v.len().is_multiple_of(4) {
            v.push(with);
        }
        v
    };
    let (json, bin) = (pad(json.to_vec(), b' '), pad(bin.to_vec(), 0));
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

/// The inputs, each with the extension it is written with.
fn corpus(dir: &Path) -> Vec<(Vec<u8>, &'static str)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/models");
    let gltf = std::fs::read(root.join("lamp.gltf")).expect("lamp.gltf");
    let bin = std::fs::read(root.join("lamp.bin")).expect("lamp.bin");
    std::fs::write(dir.join("lamp.bin"), &bin).expect("writes");
    // The .glb holds the buffer itself: its JSON names no URI.
    let text = String::from_utf8_lossy(&gltf).replace("\"uri\" : \"lamp.bin\",", "");
    let text = text.replace("\"uri\": \"lamp.bin\",", "");
    let mut film = rt_gpu::film::Film::new(3, 2);
    film.stratified = true;
    for (i, p) in film.pixels.iter_mut().enumerate() {
        for s in 0..4u32 {
            p.add_indexed(glam::Vec3::new(0.1 * i as f32, 1e-20, 1e20), s);
        }
    }
    let meta = rt_gpu::film::file::FilmMeta {
        identity: "scene=0 size=3x2".to_string(),
        samples: std::iter::once(0..4).collect(),
        device: "fuzz".to_string(),
    };
    let film = rt_gpu::film::file::encode(&film, Some(&meta)).expect("encodes");
    vec![
        (CUBE_OBJ.as_bytes().to_vec(), "obj"),
        (gltf.clone(), "gltf"),
        (glb(text.as_bytes(), &bin), "glb"),
        (film, "exr"),
    ]
}

/// An error must be one short line naming the file `name`, and no loader's panic guard's.
fn one_line_naming(e: &str, name: &str) -> Result<(), String> {
    if e.contains('\n') || e.len() > 2000 || !e.contains(name) {
        Err(format!(
            "error is not one short line naming the file: {e:?}"
        ))
    } else if e.contains("the glTF reader failed") {
        Err(format!("the gltf crate panicked: {e}"))
    } else if e.contains("the OBJ reader failed") {
        Err(format!(
            "tobj panicked on a file the faces' check passed: {e}"
        ))
    } else {
        Ok(())
    }
}

/// What must hold for any input; `Err` says what did not.
fn check(path: &Path, name: &str, extension: &str) -> Result<(), String> {
    let one_line = |e: &str| one_line_naming(e, name);
    if extension == "exr" {
        return match rt_gpu::film::file::read(path) {
            Ok((film, _)) if film.pixels.iter().all(|p| p.mean().is_finite()) => Ok(()),
            Ok(_) => Err("a film read back with a non-finite pixel".into()),
            Err(e) => one_line(&format!("{e:#}")),
        };
    }
    match rt_gpu::scene::mesh::load(path, name, None) {
        Ok(parts) => {
            for mesh in parts {
                if !mesh.positions.iter().all(|p| p.is_finite()) {
                    return Err("a mesh loaded with a non-finite vertex".into());
                }
            }
            Ok(())
        }
        Err(e) => one_line(&e),
    }
}

#[test]
fn mutated_mesh_and_film_files_never_panic() {
    let (executions, seed) = common::mutate::run_settings(3000);
    let dir = tempfile::tempdir().expect("tempdir");
    let corpus = corpus(dir.path());
    let mut mutator = Mutator { state: seed };
    let start = std::time::Instant::now();
    let mut failures = Vec::new();
    // Panics are caught and counted; their default report would flood the output.
    std::panic::set_hook(Box::new(|_| {}));
    for i in 0..executions {
        let which = mutator.below(corpus.len());
        let (_, extension) = corpus[which];
        let bytes = mutator.mutate(&[corpus[which].0.clone()], TOKENS);
        // A new name each time: the loaders cache files by name, size and time.
        let name = format!("m{i}.{extension}");
        let path = dir.path().join(&name);
        std::fs::write(&path, &bytes).expect("writes");
        let outcome = common::mutate::problem(|| check(&path, &name, extension));
        let _ = std::fs::remove_file(&path);
        let Some(problem) = outcome else {
            continue;
        };
        failures.push((i, problem, String::from_utf8_lossy(&bytes).into_owned()));
    }
    let _ = std::panic::take_hook();
    eprintln!(
        "fuzz: {executions} mesh and film files (seed {seed}) in {:.1} s, {} failures",
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    if let Some((i, problem, text)) = failures.first() {
        let shown: String = text.chars().take(3000).collect();
        panic!(
            "{} of {executions} mutants failed; the first (execution {i}): {problem}\n--- input ---\n{shown}",
            failures.len()
        );
    }
}

impl gltf_mutations::Choices for Mutator {
    fn below(&mut self, n: usize) -> usize {
        Mutator::below(self, n)
    }
}

/// The JSON and binary chunks of a `.glb`.
fn glb_chunks(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let word =
        |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize;
    let json_len = word(12);
    let json = bytes[20..20 + json_len].to_vec();
    let bin_at = 20 + json_len;
    let bin = if bin_at + 8 <= bytes.len() {
        bytes[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

/// What must hold for a glTF file rendered whole: loaded, or refused in one line naming it;
/// notes one line each; a scene it makes renders finite (no NaN, infinite or negative sample
/// from values the checks accepted).
fn check_scene(path: &Path, name: &str) -> Result<(), String> {
    let one_line = |e: &str| one_line_naming(e, name);
    let (scene, notes) = match rt_gpu::scene::gltf_scene::load(path, name, None) {
        Ok(loaded) => loaded,
        Err(e) => return one_line(&e),
    };
    if let Some(note) = notes.iter().find(|n| n.contains('\n') || n.len() > 2000) {
        return Err(format!("a note is not one short line: {note:?}"));
    }
    let opts = common::nee_opts(6, 4, 1, 4, 0);
    let flat = match rt_gpu::scene::flat::FlatScene::new(&scene, opts.width, opts.height) {
        Ok(flat) => flat,
        Err(e) => return one_line(&format!("{name}: {e}")),
    };
    let film = rt_gpu::cpu::render(&flat, &opts, &|| {});
    if film.invalid_samples > 0 {
        return Err(format!(
            "{} samples of an accepted file were NaN, infinite or negative",
            film.invalid_samples
        ));
    }
    Ok(())
}

/// Issue 61: glTF files mutated by their structure (`common/gltf_mutations.rs`: accessors'
/// counts and sparse blocks, views, URIs, nodes, materials and their extensions, lights,
/// cameras) from the shipped lamp and Blender's files, each loaded whole and, where accepted,
/// rendered: no panic, one-line errors naming the file, finite samples. Seeded;
/// `RT_GPU_FUZZ_EXECUTIONS` (default 1000) and `RT_GPU_FUZZ_SEED` set the run.
#[test]
fn structured_gltf_mutants_load_or_fail_in_one_line_and_render_finite() {
    let (executions, seed) = common::mutate::run_settings(1000);
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    std::fs::copy(root.join("models/lamp.bin"), d.join("lamp.bin")).expect("copies");
    #[cfg(unix)]
    {
        let _ = std::process::Command::new("mkfifo")
            .arg(d.join("fifo.bin"))
            .status();
    }
    // (JSON, binary chunk: None for a .gltf beside lamp.bin)
    let mut seeds: Vec<(serde_json::Value, Option<Vec<u8>>)> = Vec::new();
    let lamp = std::fs::read(root.join("models/lamp.gltf")).expect("lamp.gltf");
    seeds.push((serde_json::from_slice(&lamp).expect("json"), None));
    for glb in [
        "blender/textured.glb",
        "blender/lamps.glb",
        "blender/worn.glb",
    ] {
        let (json, bin) = glb_chunks(&std::fs::read(root.join(glb)).expect("glb"));
        seeds.push((serde_json::from_slice(&json).expect("json"), Some(bin)));
    }
    let mut mutator = Mutator { state: seed };
    let start = std::time::Instant::now();
    let mut failures = Vec::new();
    std::panic::set_hook(Box::new(|_| {}));
    for i in 0..executions {
        let (seed_doc, bin) = &seeds[mutator.below(seeds.len())];
        let mut doc = seed_doc.clone();
        gltf_mutations::mutate(&mut doc, &mut mutator);
        let json = serde_json::to_vec(&doc).expect("json");
        let (name, bytes) = match bin {
            None => (format!("s{i}.gltf"), json.clone()),
            Some(bin) => (format!("s{i}.glb"), glb(&json, bin)),
        };
        let path = d.join(&name);
        std::fs::write(&path, &bytes).expect("writes");
        let outcome = common::mutate::problem(|| check_scene(&path, &name));
        if let Some(problem) = outcome {
            failures.push((i, problem, String::from_utf8_lossy(&json).into_owned()));
            // Kept for a replay with panics reported (below).
            if failures.len() == 1 {
                continue;
            }
        }
        let _ = std::fs::remove_file(&path);
    }
    let _ = std::panic::take_hook();
    if let Some((i, ..)) = failures.first() {
        // Where the first failure's panic (if any) was: replayed with the default hook.
        let name = ["gltf", "glb"]
            .iter()
            .map(|e| format!("s{i}.{e}"))
            .find(|n| d.join(n).exists())
            .unwrap_or_default();
        let _ = common::mutate::problem(|| check_scene(&d.join(&name), &name));
    }
    eprintln!(
        "fuzz: {executions} structured glTF mutants (seed {seed}) in {:.1} s, {} failures",
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    if let Some((i, problem, text)) = failures.first() {
        let shown: String = text.chars().take(4000).collect();
        let others: Vec<String> = (failures.iter().skip(1).take(5))
            .map(|(i, p, _)| format!("{i}: {p}"))
            .collect();
        panic!(
            "{} of {executions} mutants failed; the first (execution {i}): {problem}\nothers: {others:#?}\n--- JSON ---\n{shown}",
            failures.len()
        );
    }
}
