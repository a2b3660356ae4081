//! Coverage-guided fuzzing of the mesh (OBJ, glTF, GLB) and film-file loaders:
//! `cargo +nightly fuzz run mesh_and_film_files` (see fuzz/README.md). The first byte picks the
//! format, the rest is the file. The stable, bounded twin that CI runs is
//! tests/fuzz_mesh_files.rs.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::sync::atomic::{AtomicUsize, Ordering};

const EXTENSIONS: [&str; 4] = ["obj", "gltf", "glb", "exr"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, file)) = data.split_first() else {
        return;
    };
    let extension = EXTENSIONS[pick as usize % EXTENSIONS.len()];
    // A new name each time: the loaders cache files by name, size and time.
    static CASE: AtomicUsize = AtomicUsize::new(0);
    let name = format!("fuzz{}.{extension}", CASE.fetch_add(1, Ordering::Relaxed));
    let dir = std::env::temp_dir().join("rt-gpu-fuzz");
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(&name);
    std::fs::write(&path, file).expect("writes the input");
    let error = if extension == "exr" {
        rt_gpu::film::file::read(&path).err().map(|e| format!("{e:#}"))
    } else {
        rt_gpu::scene::mesh::load(&path, &name, None).err()
    };
    let _ = std::fs::remove_file(&path);
    if let Some(e) = error {
        assert!(!e.contains('\n'), "multi-line error: {e}");
        assert!(
            !e.contains("the glTF reader failed"),
            "the gltf crate panicked: {e}"
        );
    }
});
