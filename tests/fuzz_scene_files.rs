//! A mutation fuzzer for the scene-file loader that runs on the stable toolchain, bounded so CI
//! can afford it: the shipped scene files (and the documented example) mutated by byte flips,
//! deletions, duplications, splices, truncations and insertions of tokens that have broken
//! parsers before (NaN, huge numbers, deep nesting, multi-line strings, NUL, non-ASCII). Each
//! mutant goes through everything a scene file reaches without a GPU: parsing, flattening, the
//! kernel source, a tiny CPU render and an export round trip.
//!
//! Passing means: no panic, every error one line, every render finite. Seeded, so a failure
//! reproduces; `RT_GPU_FUZZ_EXECUTIONS` (default 20 000) and `RT_GPU_FUZZ_SEED` (default 1) set
//! the run. The long run reported in the README:
//! `RT_GPU_FUZZ_EXECUTIONS=1000000 cargo test --release --test fuzz_scene_files -- --nocapture`.
//! Coverage-guided fuzzing with cargo-fuzz lives in `fuzz/` (see its README).

use rt_gpu::gpu::Features;
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::file::{parse, to_toml};
use rt_gpu::scene::flat::FlatScene;
use std::panic::{AssertUnwindSafe, catch_unwind};
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

/// SplitMix64: small, fast and good enough to pick mutations.
struct Mutator {
    state: u64,
}

impl Mutator {
    fn next(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// A range of at most `longest` bytes inside `len`.
    fn range(&mut self, len: usize, longest: usize) -> std::ops::Range<usize> {
        let start = self.below(len + 1);
        let end = (start + self.below(longest + 1)).min(len);
        start..end
    }

    fn mutate(&mut self, corpus: &[Vec<u8>]) -> Vec<u8> {
        let mut bytes = corpus[self.below(corpus.len())].clone();
        for _ in 0..1 + self.below(4) {
            let len = bytes.len();
            match self.below(9) {
                0 if len > 0 => {
                    let i = self.below(len);
                    bytes[i] = self.next() as u8;
                }
                1 => {
                    let r = self.range(len, 16);
                    bytes.drain(r);
                }
                2 => {
                    let r = self.range(len, 64);
                    let copy = bytes[r].to_vec();
                    let at = self.below(len + 1);
                    bytes.splice(at..at, copy);
                }
                3 | 4 => {
                    let token = TOKENS[self.below(TOKENS.len())].as_bytes();
                    let at = self.below(len + 1);
                    bytes.splice(at..at, token.iter().copied());
                }
                5 => {
                    // A number replaced by a token: find a digit near a random place.
                    let at = self.below(len + 1);
                    if let Some(offset) = bytes[at..].iter().position(u8::is_ascii_digit) {
                        let start = at + offset;
                        let end = start
                            + bytes[start..]
                                .iter()
                                .position(|b| !(b.is_ascii_digit() || *b == b'.'))
                                .unwrap_or(bytes.len() - start);
                        let token = TOKENS[self.below(TOKENS.len())].as_bytes();
                        bytes.splice(start..end, token.iter().copied());
                    }
                }
                6 => {
                    let other = &corpus[self.below(corpus.len())];
                    let r = self.range(other.len(), 200);
                    let at = self.below(len + 1);
                    bytes.splice(at..at, other[r].iter().copied());
                }
                7 => {
                    let at = self.below(len + 1);
                    bytes.truncate(at);
                }
                _ => {
                    // Two lines swapped.
                    let text = String::from_utf8_lossy(&bytes).into_owned();
                    let mut lines: Vec<&str> = text.lines().collect();
                    if lines.len() > 1 {
                        let (a, b) = (self.below(lines.len()), self.below(lines.len()));
                        lines.swap(a, b);
                        bytes = lines.join("\n").into_bytes();
                    }
                }
            }
        }
        bytes
    }
}

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

/// What must hold for any input; `Err` says what did not.
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
    rt_gpu::gpu::shader::compose(&Features::of(&flat), &flat)
        .map_err(|e| format!("no kernel source: {e}"))?;
    if flat.spheres.len() + flat.quads.len() <= 400 {
        let film = rt_gpu::cpu::render(&flat, &RenderOptions::new(3, 2, 1, 4), &|| {});
        if !film.pixels.iter().all(|p| p.mean().is_finite()) {
            return Err("a pixel is not finite".into());
        }
    }
    Ok(())
}

#[test]
fn mutated_scene_files_never_panic() {
    let executions: usize = std::env::var("RT_GPU_FUZZ_EXECUTIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000);
    let seed: u64 = std::env::var("RT_GPU_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let corpus = corpus();
    assert!(corpus.len() >= 5, "corpus of {}", corpus.len());
    let mut mutator = Mutator { state: seed };
    // Panics are caught and counted; their default report would flood the output.
    std::panic::set_hook(Box::new(|_| {}));
    let start = std::time::Instant::now();
    let (mut parsed, mut failures) = (0usize, Vec::new());
    for i in 0..executions {
        let bytes = mutator.mutate(&corpus);
        let text = String::from_utf8_lossy(&bytes);
        parsed += parse(&text, "x", "x").is_ok() as usize;
        let outcome = catch_unwind(AssertUnwindSafe(|| check(&text)));
        let problem = match outcome {
            Ok(Ok(())) => continue,
            Ok(Err(problem)) => problem,
            Err(panic) => format!(
                "panic: {}",
                panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default()
            ),
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
