//! A mutation fuzzer for the scene-file loader that runs on the stable toolchain, bounded so CI
//! can afford it: the shipped scene files (and the documented example) mutated by byte flips,
//! deletions, duplications, splices, truncations and insertions of tokens that have broken
//! parsers before (NaN, huge numbers, deep nesting, multi-line strings, NUL, non-ASCII). Each
//! mutant goes through everything a scene file reaches without a GPU: parsing, flattening, the
//! kernel source, a tiny CPU render and an export round trip.
//!
//! Passing means: no panic, every error one line, every render finite. Seeded, so a failure
//! reproduces; `RT_GPU_FUZZ_EXECUTIONS` (default 20 000) and `RT_GPU_FUZZ_SEED` (default 1) set
//! the run. The long run reported in docs/testing.md:
//! `RT_GPU_FUZZ_EXECUTIONS=1000000 cargo test --release --test it fuzz_scene_files -- --nocapture`.
//! Coverage-guided fuzzing with cargo-fuzz lives in `fuzz/` (see its README).
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

use common::mutate::Mutator;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::Features;
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::file::{parse, to_toml};
use rt_gpu::scene::flat::FlatScene;
use std::path::Path;

/// Tokens that have broken parsers and validators before.
const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "-0",
    "0",
    "0.0",
    "1e-45",
    "1e-38",
    "4294967296",
    "-1",
    "99999999999999999999",
    "1e8",
    "9.9e7",
    "1e7",
    "3.4e38",
    "true",
    "\"\"",
    "\"",
    "[",
    "]",
    "{",
    "}",
    "=",
    ",",
    "\n",
    "#",
    "'''",
    "\"\"\"",
    "\0",
    "é",
    "\u{feff}",
    "\\u0000",
    "[[object]]\n",
    "[object.sphere]\n",
    "[object.disk]\n",
    "normal = [0, 0, 0]",
    "[render]\n",
    "[materials]\n",
    "[camera]\n",
    "[[[[[[[[[[[[[[[[",
    "]]]]]]]]]]]]]]]]",
    "{a={b={c={d={e=1}}}}}",
    "rotate_y = 1e30\n",
    "translate = [1e8, 1e8, 1e8]\n",
    "up = [0, 1e20, 0]\n",
    "focus_distance = 1e-30\n",
    "aperture = 1e30\n",
    "width = 0\n",
    "max_depth = 4294967295\n",
    "two_sided = true",
    "type = \"light\"",
    "type = \"dielectric\"",
    "ior = 0",
    "fuzz = -1",
    "radius = -1e-7",
    "background = \"sky\"",
    "background = [1e38, 0, 0]",
];

fn corpus() -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut corpus: Vec<Vec<u8>> = std::fs::read_dir(root.join("scenes"))
        .expect("scenes/")
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| std::fs::read(p).expect("readable"))
        .collect();
    let doc = std::fs::read_to_string(root.join("scenes/README.md")).expect("scenes/README.md");
    for block in doc.split("```toml\n").skip(1) {
        corpus.push(block.split("```").next().unwrap_or("").as_bytes().to_vec());
    }
    corpus.sort();
    corpus
}

/// What must hold for any input; `Err` says what did not (the kernel's source only where the
/// `gpu` feature builds the kernel).
fn check(text: &str) -> Result<(), String> {
    let scene = match parse(text, "fuzz.toml", "fuzz") {
        Ok(scene) => scene,
        Err(e) => {
            let message = e.to_string();
            if message.contains('\n') || message.len() > 2000 {
                return Err(format!("error is not one short line: {message:?}"));
            }
            return Ok(());
        }
    };
    let again = parse(&to_toml(&scene), "export.toml", "fuzz")
        .map_err(|e| format!("the exported scene does not parse: {e}"))?;
    if again != scene {
        return Err("the exported scene reads back different".into());
    }
    let flat = match FlatScene::new(&scene, 3, 2) {
        Ok(flat) => flat,
        Err(e) if e.to_string().contains('\n') => return Err(format!("multi-line error: {e}")),
        Err(_) => return Ok(()),
    };
    #[cfg(feature = "gpu")]
    rt_gpu::gpu::shader::compose(&Features::of(&flat), &flat)
        .map_err(|e| format!("no kernel source: {e}"))?;
    if flat.shapes.len() <= 400 {
        let film = rt_gpu::cpu::render(&flat, &RenderOptions::new(3, 2, 1, 4), &|| {});
        if !film.pixels.iter().all(|p| p.mean().is_finite()) {
            return Err("a pixel is not finite".into());
        }
    }
    Ok(())
}

#[test]
fn mutated_scene_files_never_panic() {
    let (executions, seed) = common::mutate::run_settings(20_000);
    let corpus = corpus();
    assert!(corpus.len() >= 5, "corpus of {}", corpus.len());
    let mut mutator = Mutator { state: seed };
    // Panics are caught and counted; their default report would flood the output.
    std::panic::set_hook(Box::new(|_| {}));
    let start = std::time::Instant::now();
    let (mut parsed, mut failures) = (0usize, Vec::new());
    for i in 0..executions {
        let bytes = mutator.mutate(&corpus, TOKENS);
        let text = String::from_utf8_lossy(&bytes);
        parsed += parse(&text, "x", "x").is_ok() as usize;
        let outcome = common::mutate::problem(|| check(&text));
        let Some(problem) = outcome else {
            continue;
        };
        failures.push((i, problem, text.into_owned()));
    }
    let _ = std::panic::take_hook();
    eprintln!(
        "fuzz: {executions} executions (seed {seed}) in {:.1} s, {parsed} mutants parsed, {} failures",
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    if let Some((i, problem, text)) = failures.first() {
        panic!(
            "{} of {executions} mutants failed; the first (execution {i}): {problem}\n--- input ---\n{text}",
            failures.len()
        );
    }
}
