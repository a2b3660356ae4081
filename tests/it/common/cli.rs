//! Running the `rt-gpu` binary.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `rt-gpu args` in `dir`.
pub fn rt_gpu(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("runs")
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The samples per pixel a render's summary line reports ("..., 687 spp, ...").
pub fn spp_reached(out: &Output) -> u32 {
    let line = stderr(out);
    let before = line.split(" spp,").next().unwrap_or_default();
    before
        .rsplit(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no spp in {line}"))
}
