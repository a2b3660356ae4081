//! Compiles the startup check of the CPU (src/cli/host_cpu.c) for plain x86-64: the crate itself
//! is built for the building machine's CPU (.cargo/config.toml), and the check must run on CPUs
//! without those instructions.

fn main() {
    println!("cargo:rerun-if-changed=src/cli/host_cpu.c");
    let x86_64 = std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("x86_64");
    let msvc = std::env::var("CARGO_CFG_TARGET_ENV").as_deref() == Ok("msvc");
    if x86_64 && !msvc && std::env::var_os("CARGO_FEATURE_CLI").is_some() {
        // cc puts CFLAGS (and TARGET_CFLAGS, CFLAGS_<target>...) after the flags below, where a
        // `-march=native` would undo them: the check is built without them. (A CC with flags
        // of its own that add instructions stops the build: host_cpu.c's #error.)
        let cflags: Vec<_> = std::env::vars_os()
            .map(|(key, _)| key)
            .filter(|key| {
                key.to_str().is_some_and(|k| {
                    k == "CFLAGS" || k.starts_with("CFLAGS_") || k.ends_with("_CFLAGS")
                })
            })
            .collect();
        for key in cflags {
            // SAFETY: a build script runs on one thread.
            unsafe { std::env::remove_var(key) };
        }
        cc::Build::new()
            .file("src/cli/host_cpu.c")
            .inherit_rustflags(false)
            .flag("-march=x86-64")
            .flag("-mtune=generic")
            .compile("rt_gpu_host_cpu");
    }
}
