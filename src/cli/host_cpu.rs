//! Whether this CPU runs what the binary was built for. `.cargo/config.toml` builds for the
//! building machine's CPU (`-C target-cpu=native`), as Mitsuba's JIT and Cycles' per-ISA kernels
//! use the host's instructions; a binary copied to a CPU without them would die of an illegal
//! instruction, so the binary checks first and stops with a line that says what to do. The check
//! is C (`host_cpu.c`), which build.rs compiles for plain x86-64: this crate's own code, the
//! check's included, may use any instruction of the building machine. It runs when the binary
//! is loaded (a C constructor), before the Rust runtime, which allocates through this crate's
//! allocator (`huge_pages.rs`) before `main`; `main` asks again ([`runs_here`]), a call that
//! also links the C object, constructor and all. It reads cpuid itself, as
//! `is_x86_feature_detected!` answers yes for any feature the build enables.

use std::ffi::{c_char, c_int};

/// A CPU feature the compiler may use, as `host_cpu.c` reads it: where cpuid reports it (leaf,
/// subleaf, register 0-3 for eax-edx, bit), the register state the operating system must save
/// (0 none, 1 AVX, 2 AVX-512), and whether this build uses it.
#[repr(C)]
pub struct Feature {
    name: *const c_char,
    leaf: u32,
    subleaf: u32,
    register: u32,
    bit: u32,
    os_state: u32,
    built_for: u32,
}

// SAFETY: `name` points to a static C string, never written.
unsafe impl Sync for Feature {}

/// Every x86 feature `-C target-cpu=native` may let the compiler use in ordinary code (each a
/// name rustc knows: tested). Unstable ones, XOP and APX among them, are not `cfg`-visible on
/// stable Rust and so not checked.
#[cfg(all(target_arch = "x86_64", not(target_env = "msvc")))]
macro_rules! x86_features {
    ($(($name:tt, $leaf:literal, $sub:literal, $reg:literal, $bit:literal $(, $state:literal)?)),* $(,)?) => {
        &[$(Feature {
            name: concat!($name, "\0").as_ptr().cast(),
            leaf: $leaf,
            subleaf: $sub,
            register: $reg,
            bit: $bit,
            os_state: 0 $(+ $state)?,
            built_for: cfg!(target_feature = $name) as u32,
        }),*]
    };
}

#[cfg(all(target_arch = "x86_64", not(target_env = "msvc")))]
pub static FEATURES: &[Feature] = x86_features!(
    ("sse3", 1, 0, 2, 0),
    ("pclmulqdq", 1, 0, 2, 1),
    ("ssse3", 1, 0, 2, 9),
    ("fma", 1, 0, 2, 12, 1),
    ("cmpxchg16b", 1, 0, 2, 13),
    ("sse4.1", 1, 0, 2, 19),
    ("sse4.2", 1, 0, 2, 20),
    ("movbe", 1, 0, 2, 22),
    ("popcnt", 1, 0, 2, 23),
    ("aes", 1, 0, 2, 25),
    ("xsave", 1, 0, 2, 26),
    ("avx", 1, 0, 2, 28, 1),
    ("f16c", 1, 0, 2, 29, 1),
    ("rdrand", 1, 0, 2, 30),
    ("bmi1", 7, 0, 1, 3),
    ("avx2", 7, 0, 1, 5, 1),
    ("bmi2", 7, 0, 1, 8),
    ("avx512f", 7, 0, 1, 16, 2),
    ("avx512dq", 7, 0, 1, 17, 2),
    ("rdseed", 7, 0, 1, 18),
    ("adx", 7, 0, 1, 19),
    ("avx512ifma", 7, 0, 1, 21, 2),
    ("avx512cd", 7, 0, 1, 28, 2),
    ("sha", 7, 0, 1, 29),
    ("avx512bw", 7, 0, 1, 30, 2),
    ("avx512vl", 7, 0, 1, 31, 2),
    ("avx512vbmi", 7, 0, 2, 1, 2),
    ("avx512vbmi2", 7, 0, 2, 6, 2),
    ("gfni", 7, 0, 2, 8),
    ("vaes", 7, 0, 2, 9, 1),
    ("vpclmulqdq", 7, 0, 2, 10, 1),
    ("avx512vnni", 7, 0, 2, 11, 2),
    ("avx512bitalg", 7, 0, 2, 12, 2),
    ("avx512vpopcntdq", 7, 0, 2, 14, 2),
    ("avx512vp2intersect", 7, 0, 3, 8, 2),
    ("avx512fp16", 7, 0, 3, 23, 2),
    ("avxvnni", 7, 1, 0, 4, 1),
    ("avx512bf16", 7, 1, 0, 5, 2),
    ("lzcnt", 0x8000_0001, 0, 2, 5),
    ("sse4a", 0x8000_0001, 0, 2, 6),
    ("tbm", 0x8000_0001, 0, 2, 21),
    ("sha512", 7, 1, 0, 0, 1),
    ("sm3", 7, 1, 0, 1, 1),
    ("sm4", 7, 1, 0, 2, 1),
    ("avxifma", 7, 1, 0, 23, 1),
    ("avxvnniint8", 7, 1, 3, 4, 1),
    ("avxneconvert", 7, 1, 3, 5, 1),
    ("avxvnniint16", 7, 1, 3, 10, 1),
    ("kl", 7, 0, 2, 23),
    ("widekl", 0x19, 0, 1, 2),
);

/// [`FEATURES`] as `host_cpu.c`'s constructor reads it: before the Rust runtime starts, through
/// a symbol of its own (a slice has no C layout).
#[cfg(all(target_arch = "x86_64", not(target_env = "msvc")))]
#[repr(C)]
pub struct Features {
    table: *const Feature,
    count: usize,
}

// SAFETY: `table` points to the static table, never written.
#[cfg(all(target_arch = "x86_64", not(target_env = "msvc")))]
unsafe impl Sync for Features {}

#[cfg(all(target_arch = "x86_64", not(target_env = "msvc")))]
#[unsafe(no_mangle)]
pub static RT_GPU_FEATURES: Features = Features {
    table: FEATURES.as_ptr(),
    count: FEATURES.len(),
};

/// Other architectures are not checked (their `native` builds have not been tried elsewhere),
/// nor Windows' MSVC toolchain (the check's C is GCC's and Clang's).
#[cfg(not(all(target_arch = "x86_64", not(target_env = "msvc"))))]
pub static FEATURES: &[Feature] = &[];

#[cfg(all(target_arch = "x86_64", not(target_env = "msvc")))]
unsafe extern "C" {
    #[cfg(test)]
    fn rt_gpu_missing_cpu_features(
        features: *const Feature,
        count: usize,
        names: *mut c_char,
        capacity: usize,
    ) -> c_int;
    fn rt_gpu_check_cpu(features: *const Feature, count: usize) -> c_int;
}

/// Whether this CPU has every feature the build uses; where it lacks one, the error line is
/// printed (by the C side, before any of this build's own instructions could fail).
#[inline(never)]
pub fn runs_here() -> bool {
    #[cfg(all(target_arch = "x86_64", not(target_env = "msvc")))]
    // SAFETY: FEATURES is a valid array of its length, its names 0-terminated.
    return unsafe { rt_gpu_check_cpu(FEATURES.as_ptr(), FEATURES.len()) } == 0;
    #[cfg(not(all(target_arch = "x86_64", not(target_env = "msvc"))))]
    true
}

#[cfg(all(test, target_arch = "x86_64", not(target_env = "msvc")))]
mod tests {
    use super::*;

    /// The features of `features` this CPU lacks, as `host_cpu.c` names them.
    fn missing(features: &[Feature]) -> (c_int, String) {
        let mut names = [0 as c_char; 64];
        // SAFETY: valid array and buffer of their lengths.
        let count = unsafe {
            rt_gpu_missing_cpu_features(features.as_ptr(), features.len(), names.as_mut_ptr(), 64)
        };
        let names = unsafe { std::ffi::CStr::from_ptr(names.as_ptr()) };
        (count, names.to_string_lossy().into_owned())
    }

    fn feature(name: &'static std::ffi::CStr, leaf: u32, bit: u32, built_for: u32) -> Feature {
        Feature {
            name: name.as_ptr(),
            leaf,
            subleaf: 0,
            register: 3,
            bit,
            os_state: 0,
            built_for,
        }
    }

    #[test]
    fn this_cpu_runs_this_build() {
        assert_eq!(missing(FEATURES), (0, String::new()));
    }

    /// SSE2 (leaf 1, edx bit 26) is on every x86-64 CPU; a leaf past the last reports nothing.
    #[test]
    fn features_built_for_and_absent_are_named() {
        let features = [
            feature(c"sse2", 1, 26, 1),
            feature(c"beyond", 0x7fff_ffff, 0, 1),
            feature(c"unused", 0x7fff_ffff, 0, 0),
            feature(c"far-beyond", 0x8fff_ffff, 3, 1),
        ];
        assert_eq!(missing(&features), (2, "beyond, far-beyond".into()));
        // Names past the buffer are cut, the count is not.
        let many: Vec<_> = (0..20)
            .map(|_| feature(c"beyond", 0x7fff_ffff, 0, 1))
            .collect();
        let (count, names) = missing(&many);
        assert_eq!((count, names.len()), (20, 63));
    }

    /// Every name of the table is one rustc knows (`rustc --print target-features`): a
    /// misspelt one would never be `cfg`-enabled, so never checked, and rustc does not warn.
    #[test]
    fn the_table_names_features_rustc_knows() {
        let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
        let out = std::process::Command::new(rustc)
            .args([
                "--print",
                "target-features",
                "--target",
                "x86_64-unknown-linux-gnu",
            ])
            .output()
            .expect("rustc runs");
        let known = String::from_utf8_lossy(&out.stdout);
        let known: Vec<&str> = known
            .lines()
            .filter_map(|l| l.split_whitespace().next())
            .collect();
        for f in FEATURES {
            // SAFETY: the table's names are 0-terminated literals.
            let name = unsafe { std::ffi::CStr::from_ptr(f.name) }
                .to_str()
                .unwrap();
            assert!(known.contains(&name), "{name} is not a feature rustc knows");
        }
        assert!(!known.contains(&"avx2x"));
    }
}
