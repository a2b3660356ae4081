//! Coverage-guided fuzzing of the scene-file loader: `cargo +nightly fuzz run scene_file`
//! (see fuzz/README.md). The stable, bounded twin that CI runs is tests/fuzz_scene_files.rs.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rt_gpu::scene::file::parse;
use rt_gpu::scene::flat::FlatScene;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match parse(text, "fuzz.toml", "fuzz") {
        Err(e) => assert!(!e.to_string().contains('\n'), "multi-line error: {e}"),
        Ok(scene) => {
            if let Ok(flat) = FlatScene::new(&scene, 3, 2) {
                let features = rt_gpu::gpu::Features::of(&flat);
                rt_gpu::gpu::shader::compose(&features, &flat).expect("kernel source");
            }
        }
    }
});
