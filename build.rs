//! Compiles the startup check of the CPU (src/cli/host_cpu.c) for plain x86-64: the crate itself
//! is built for the building machine's CPU (.cargo/config.toml), and the check must run on CPUs
//! without those instructions.

fn main() {
    println!("cargo:rerun-if-changed=src/cli/host_cpu.c");
    let x86_64 = std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("x86_64");
    if x86_64 && std::env::var_os("CARGO_FEATURE_CLI").is_some() {
        cc::Build::new()
            .file("src/cli/host_cpu.c")
            .inherit_rustflags(false)
            .flag("-march=x86-64")
            .flag("-mtune=generic")
            .compile("rt_gpu_host_cpu");
    }
}
