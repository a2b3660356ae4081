/* Whether this CPU has the instruction set extensions rt-gpu was built for (the table is
   src/cli/host_cpu.rs's). build.rs compiles this file for plain x86-64, whatever target-cpu the
   Rust code is built for: the check must run, and its error print, on the very CPUs that lack
   them. */
#include <cpuid.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <unistd.h>

#if defined(__SSE3__) || defined(__SSSE3__) || defined(__SSE4_1__) || defined(__POPCNT__) || \
    defined(__AVX__) || defined(__BMI__) || defined(__BMI2__) || defined(__LZCNT__) ||      \
    defined(__MOVBE__) || defined(__FMA__) || defined(__F16C__)
#error "host_cpu.c must be compiled for plain x86-64: the compiler (CC) adds instructions"
#endif

struct rt_gpu_feature {
    const char *name;
    /* Where cpuid reports it: leaf, subleaf, register (0-3: eax, ebx, ecx, edx), bit. */
    uint32_t leaf, subleaf, reg, bit;
    /* Register state the operating system must save: 0 none, 1 AVX, 2 AVX-512. */
    uint32_t os_state;
    /* Whether the build uses it. */
    uint32_t built_for;
};

/* Whether cpuid sets the bit (0 for a leaf or subleaf beyond the CPU's last). */
static int cpuid_bit(uint32_t leaf, uint32_t subleaf, uint32_t reg, uint32_t bit) {
    unsigned r[4];
    if (leaf == 7 && subleaf > 0) {
        if (!__get_cpuid_count(7, 0, &r[0], &r[1], &r[2], &r[3]) || r[0] < subleaf) return 0;
    }
    if (!__get_cpuid_count(leaf, subleaf, &r[0], &r[1], &r[2], &r[3])) return 0;
    return (r[reg & 3] >> (bit & 31)) & 1;
}

/* Whether the operating system saves the registers of os_state (XCR0, readable where OSXSAVE
   is set). */
static int os_saves(uint32_t os_state) {
    if (os_state == 0) return 1;
    if (!cpuid_bit(1, 0, 2, 27)) return 0;
    uint32_t low, high;
    __asm__ volatile("xgetbv" : "=a"(low), "=d"(high) : "c"(0));
    (void)high;
    /* SSE and AVX state; with AVX-512, its mask and upper registers too. */
    uint32_t needed = os_state == 1 ? 0x6 : 0xe6;
    return (low & needed) == needed;
}

/* How many of the count features the build uses this CPU lacks; their names, comma-separated,
   in names (at most capacity bytes with the terminating 0, cut short if longer). */
int rt_gpu_missing_cpu_features(const struct rt_gpu_feature *features, size_t count,
                                char *names, size_t capacity) {
    int missing = 0;
    size_t length = 0;
    if (capacity > 0) names[0] = 0;
    for (size_t i = 0; i < count; i++) {
        const struct rt_gpu_feature *f = &features[i];
        if (!f->built_for || (cpuid_bit(f->leaf, f->subleaf, f->reg, f->bit) && os_saves(f->os_state)))
            continue;
        missing++;
        if (length + 1 >= capacity) continue;
        int written = snprintf(names + length, capacity - length, "%s%s", missing > 1 ? ", " : "", f->name);
        if (written > 0) length += (size_t)written < capacity - length ? (size_t)written : capacity - length - 1;
    }
    return missing;
}

/* 0 where this CPU has every feature the build uses; else prints the one-line error and returns
   how many it lacks. */
int rt_gpu_check_cpu(const struct rt_gpu_feature *features, size_t count) {
    char names[1024];
    int missing = rt_gpu_missing_cpu_features(features, count, names, sizeof names);
    if (missing > 0) {
        fprintf(stderr,
                "error: this rt-gpu was built for another CPU: this one lacks %s; rebuild it here "
                "(`cargo clean && cargo build --release`: cargo reuses a target/ built elsewhere), or "
                "build one for any x86-64 CPU with `RUSTFLAGS=\"-C target-cpu=x86-64\" cargo build "
                "--release`\n",
                names);
    }
    return missing;
}

/* The table of src/cli/host_cpu.rs, as the Rust side exports it. */
struct rt_gpu_features {
    const struct rt_gpu_feature *table;
    size_t count;
};
extern const struct rt_gpu_features RT_GPU_FEATURES;

/* The check at load time, before the Rust runtime starts: the runtime allocates before `main`,
   and the process's allocator (src/cli/huge_pages.rs) is this crate's own code, built for the
   building machine's CPU. Exits as `main` would have, with 1. */
__attribute__((constructor)) static void rt_gpu_check_cpu_at_load(void) {
    if (rt_gpu_check_cpu(RT_GPU_FEATURES.table, RT_GPU_FEATURES.count) > 0) _exit(1);
}
