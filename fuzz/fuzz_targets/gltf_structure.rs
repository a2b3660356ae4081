//! Coverage-guided fuzzing of glTF files rendered whole, with a structure-aware mutator (issue
//! 61): libFuzzer's inputs are glTF JSON documents (beside the shipped lamp's buffer), mutated by
//! tests/it/common/gltf_mutations.rs (accessors' counts and sparse blocks, views, URIs, nodes,
//! materials and their extensions, lights, cameras) as well as byte by byte. Each is loaded as
//! `rt-gpu FILE.gltf` loads it and, where accepted, rendered on the CPU at 6x4, 1 spp:
//! no panic, errors and notes one line, finite samples. Seeds: `fuzz/README.md`.
#![no_main]

#[path = "../../tests/it/common/gltf_mutations.rs"]
mod gltf_mutations;

use libfuzzer_sys::{fuzz_mutator, fuzz_target};
use std::sync::atomic::{AtomicUsize, Ordering};

/// SplitMix64 from libFuzzer's seed: the choices of one structural mutation.
struct Seeded(u64);

impl gltf_mutations::Choices for Seeded {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) % n.max(1) as u64) as usize
    }
}

fuzz_mutator!(|data: &mut [u8], size: usize, max_size: usize, seed: u32| {
    // Half the time, and whenever the input is not JSON, libFuzzer's own byte mutations.
    let parsed = (seed % 2 == 0)
        .then(|| serde_json::from_slice::<serde_json::Value>(&data[..size]).ok())
        .flatten();
    let Some(mut doc) = parsed else {
        return libfuzzer_sys::fuzzer_mutate(data, size, max_size);
    };
    gltf_mutations::mutate(&mut doc, &mut Seeded(seed as u64));
    let bytes = serde_json::to_vec(&doc).unwrap_or_default();
    if bytes.is_empty() || bytes.len() > max_size {
        return libfuzzer_sys::fuzzer_mutate(data, size, max_size);
    }
    data[..bytes.len()].copy_from_slice(&bytes);
    bytes.len()
});

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join("rt-gpu-fuzz-gltf");
    let _ = std::fs::create_dir_all(&dir);
    let lamp = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/models/lamp.bin");
    if !dir.join("lamp.bin").exists() {
        std::fs::copy(lamp, dir.join("lamp.bin")).expect("copies the lamp's buffer");
    }
    // A new name each time: the loaders cache files by name, size and time.
    static CASE: AtomicUsize = AtomicUsize::new(0);
    let name = format!("fuzz{}.gltf", CASE.fetch_add(1, Ordering::Relaxed));
    let path = dir.join(&name);
    std::fs::write(&path, data).expect("writes the input");
    let loaded = rt_gpu::scene::gltf_scene::load(&path, &name, None);
    let _ = std::fs::remove_file(&path);
    let (scene, notes) = match loaded {
        Ok(loaded) => loaded,
        Err(e) => {
            assert!(!e.contains('\n'), "multi-line error: {e}");
            assert!(!e.contains("the glTF reader failed"), "the gltf crate panicked: {e}");
            return;
        }
    };
    assert!(notes.iter().all(|n| !n.contains('\n')), "multi-line note: {notes:?}");
    let opts = rt_gpu::options::RenderOptions::new(6, 4, 1, 4);
    let Ok(flat) = rt_gpu::scene::flat::FlatScene::new(&scene, opts.width, opts.height) else {
        return;
    };
    let film = rt_gpu::cpu::render(&flat, &opts, &|| {});
    assert_eq!(film.invalid_samples, 0, "non-finite samples from an accepted file");
});
