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
