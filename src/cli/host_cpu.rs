//! Whether this CPU runs what the binary was built for. `.cargo/config.toml` builds for the
//! building machine's CPU (`-C target-cpu=native`), as Mitsuba's JIT and Cycles' per-ISA kernels
//! use the host's instructions; a binary copied to a CPU without them would die of an illegal
//! instruction, so `main` checks first and stops with a line that says what to do.

/// A CPU feature the compiler may use: its name, whether this build uses it, whether this CPU
/// has it.
pub struct Feature {
    pub name: &'static str,
    pub built_for: bool,
    pub present: fn() -> bool,
}

/// Every x86 feature `-C target-cpu=native` may let the compiler use in ordinary code, with where
/// `cpuid` reports it: leaf, subleaf, register (0-3: eax, ebx, ecx, edx), bit. Read here rather
/// than through `is_x86_feature_detected!`, which answers yes for any feature the build enables
/// without asking the CPU. Each bit is a constant, so the test itself needs no newer instruction.
#[cfg(target_arch = "x86_64")]
macro_rules! x86_features {
    ($(($name:tt, $leaf:literal, $sub:literal, $reg:literal, $bit:literal $(, $state:ident)?)),* $(,)?) => {
        &[$(Feature {
            name: $name,
            built_for: cfg!(target_feature = $name),
            present: || cpuid_bit($leaf, $sub, $reg, $bit) $(&& os_saves(OsState::$state))?,
        }),*]
    };
}

#[cfg(target_arch = "x86_64")]
pub const FEATURES: &[Feature] = x86_features!(
    ("sse3", 1, 0, 2, 0),
    ("pclmulqdq", 1, 0, 2, 1),
    ("ssse3", 1, 0, 2, 9),
    ("fma", 1, 0, 2, 12, Avx),
    ("cmpxchg16b", 1, 0, 2, 13),
    ("sse4.1", 1, 0, 2, 19),
    ("sse4.2", 1, 0, 2, 20),
    ("movbe", 1, 0, 2, 22),
    ("popcnt", 1, 0, 2, 23),
    ("aes", 1, 0, 2, 25),
    ("xsave", 1, 0, 2, 26),
    ("avx", 1, 0, 2, 28, Avx),
    ("f16c", 1, 0, 2, 29, Avx),
    ("rdrand", 1, 0, 2, 30),
    ("bmi1", 7, 0, 1, 3),
    ("avx2", 7, 0, 1, 5, Avx),
    ("bmi2", 7, 0, 1, 8),
    ("avx512f", 7, 0, 1, 16, Avx512),
    ("avx512dq", 7, 0, 1, 17, Avx512),
    ("rdseed", 7, 0, 1, 18),
    ("adx", 7, 0, 1, 19),
    ("avx512ifma", 7, 0, 1, 21, Avx512),
    ("avx512cd", 7, 0, 1, 28, Avx512),
    ("sha", 7, 0, 1, 29),
    ("avx512bw", 7, 0, 1, 30, Avx512),
    ("avx512vl", 7, 0, 1, 31, Avx512),
    ("avx512vbmi", 7, 0, 2, 1, Avx512),
    ("avx512vbmi2", 7, 0, 2, 6, Avx512),
    ("gfni", 7, 0, 2, 8),
    ("vaes", 7, 0, 2, 9, Avx),
    ("vpclmulqdq", 7, 0, 2, 10, Avx),
    ("avx512vnni", 7, 0, 2, 11, Avx512),
    ("avx512bitalg", 7, 0, 2, 12, Avx512),
    ("avx512vpopcntdq", 7, 0, 2, 14, Avx512),
    ("avx512vp2intersect", 7, 0, 3, 8, Avx512),
    ("avx512fp16", 7, 0, 3, 23, Avx512),
    ("avxvnni", 7, 1, 0, 4, Avx),
    ("avx512bf16", 7, 1, 0, 5, Avx512),
    ("lzcnt", 0x8000_0001, 0, 2, 5),
    ("sse4a", 0x8000_0001, 0, 2, 6),
    ("tbm", 0x8000_0001, 0, 2, 21),
);

/// Register state the operating system must save for a feature's instructions to run.
#[cfg(target_arch = "x86_64")]
enum OsState {
    Avx,
    Avx512,
}

/// Whether `cpuid` leaf `leaf`, subleaf `sub`, sets bit `bit` of register `reg` (a leaf beyond
/// the CPU's last reports nothing).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn cpuid_bit(leaf: u32, sub: u32, reg: usize, bit: u32) -> bool {
    use std::arch::x86_64::__cpuid_count;
    let last = __cpuid_count(leaf & 0x8000_0000, 0).eax;
    if leaf > last {
        return false;
    }
    let r = __cpuid_count(leaf, sub);
    [r.eax, r.ebx, r.ecx, r.edx][reg] & (1 << bit) != 0
}

/// Whether the operating system saves the registers of `state` (XCR0, read where the CPU says
/// it can be: OSXSAVE).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn os_saves(state: OsState) -> bool {
    if !cpuid_bit(1, 0, 2, 27) {
        return false;
    }
    let (low, _high): (u32, u32);
    // SAFETY: xgetbv with ecx = 0 reads XCR0, allowed wherever OSXSAVE is set.
    unsafe {
        std::arch::asm!("xgetbv", in("ecx") 0, out("eax") low, out("edx") _high,
                        options(nomem, nostack, preserves_flags));
    }
    // SSE and AVX state; with AVX-512, its mask and upper registers too.
    let needed = match state {
        OsState::Avx => 0x6,
        OsState::Avx512 => 0xe6,
    };
    low & needed == needed
}

/// Other architectures are not checked (their `native` builds have not been tried elsewhere).
#[cfg(not(target_arch = "x86_64"))]
pub const FEATURES: &[Feature] = &[];

/// The features of `features` this build uses and this CPU lacks.
pub fn missing(features: &[Feature]) -> Vec<&'static str> {
    features
        .iter()
        .filter(|f| f.built_for && !(f.present)())
        .map(|f| f.name)
        .collect()
}

/// Err with the line to print where this CPU lacks a feature the build uses.
pub fn check(features: &[Feature]) -> Result<(), String> {
    let missing = missing(features);
    if missing.is_empty() {
        return Ok(());
    }
    Err(format!(
        "this rt-gpu was built for another CPU: this one lacks {}; build it on this machine \
         (`cargo build --release`), or build one that runs on any x86-64 CPU since 2009 with \
         `RUSTFLAGS=\"-C target-cpu=x86-64-v2\" cargo build --release`",
        missing.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_cpu_runs_this_build() {
        assert_eq!(check(FEATURES), Ok(()));
    }

    #[test]
    fn a_feature_built_for_and_absent_is_named() {
        let features = [
            Feature {
                name: "sse4.1",
                built_for: true,
                present: || true,
            },
            Feature {
                name: "avx2",
                built_for: true,
                present: || false,
            },
            Feature {
                name: "avx512f",
                built_for: false,
                present: || false,
            },
            Feature {
                name: "fma",
                built_for: true,
                present: || false,
            },
        ];
        assert_eq!(missing(&features), ["avx2", "fma"]);
        let line = check(&features).unwrap_err();
        assert!(line.contains("lacks avx2, fma;"), "{line}");
        assert!(!line.contains('\n'));
    }
}
