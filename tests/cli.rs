//! The command line: renders in every format, and every bad input exits non-zero with one clear
//! line, leaving an existing output file untouched.

use std::path::Path;
use std::process::{Command, Output};

fn rt_gpu(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn renders_each_format_with_a_summary_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (ext, integrator) in [
        ("png", "nee"),
        ("ppm", "naive"),
        ("exr", "nee"),
        ("pfm", "naive"),
    ] {
        let name = format!("out.{ext}");
        let out = rt_gpu(
            &[
                "cornell",
                "--spp",
                "2",
                "--size",
                "16x12",
                "--backend",
                "cpu",
                "--integrator",
                integrator,
                "-o",
                &name,
            ],
            dir.path(),
        );
        assert!(out.status.success(), "{ext}: {}", stderr(&out));
        let summary = stderr(&out);
        assert!(summary.contains("16x12, 2 spp, cpu"), "{summary}");
        assert!(summary.contains(&format!("], {integrator}, ")), "{summary}");
        assert!(summary.contains("Msamples/s"), "{summary}");
        let bytes = std::fs::read(dir.path().join(&name)).expect("written");
        let magic: &[u8] = match ext {
            "png" => b"\x89PNG",
            "ppm" => b"P3\n16 12\n255\n",
            "exr" => b"\x76\x2f\x31\x01",
            _ => b"PF\n16 12\n-1.0\n",
        };
        assert!(bytes.starts_with(magic), "{ext} header");
    }
    // The PFM holds linear radiance that reads back to the right size, all finite.
    let (w, h, rgb) = rt_gpu::output::read_pfm(&dir.path().join("out.pfm")).expect("reads");
    assert_eq!((w, h, rgb.len()), (16, 12, 192));
    assert!(rgb.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
    // No temporary files are left behind.
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .expect("lists")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn scenes_lists_builtins() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = rt_gpu(&["scenes"], dir.path());
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["cornell", "cornell-empty", "spheres", "showcase"] {
        assert!(text.contains(name), "{text}");
    }
}

#[test]
fn bad_inputs_fail_with_one_line_and_leave_the_output_untouched() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("keep.png"), b"precious").expect("write");
    std::fs::write(
        dir.path().join("broken.toml"),
        "[camera\nlook_from = [0,0,1]",
    )
    .expect("write");
    std::fs::write(
        dir.path().join("nan.toml"),
        "[camera]\nlook_from = [0, 0, 1]\nlook_at = [0, 0, nan]\nvfov = 40\n",
    )
    .expect("write");
    let cases: &[(&[&str], &str)] = &[
        (&["no-such-scene"], "neither a built-in scene"),
        (&["missing.toml"], "cannot read scene file missing.toml"),
        (&["broken.toml"], "broken.toml:1:"),
        (&["nan.toml"], "nan.toml:3:"),
        (&["cornell", "--spp", "0"], "--spp"),
        (&["cornell", "--spp", "many"], "--spp"),
        (&["cornell", "--size", "0x10"], "1..="),
        (&["cornell", "--size", "512"], "WIDTHxHEIGHT"),
        (&["cornell", "--size", "30000x30000"], "pixels"),
        (&["cornell", "--max-depth", "0"], "--max-depth"),
        (&["cornell", "--backend", "tpu"], "--backend"),
        (
            &["cornell", "--adapter", "no-such-gpu-xyz"],
            "no GPU adapter",
        ),
        (&["cornell", "-o", "image.jpg"], ".png, .ppm, .exr or .pfm"),
        (&["cornell", "-o", "no/such/dir/x.png"], "does not exist"),
        (&[], "no scene given"),
    ];
    for (args, words) in cases {
        // Later flags override earlier ones, so each case's own arguments win.
        let all: Vec<&str> = ["-o", "keep.png", "--size", "8x8", "--spp", "1"]
            .into_iter()
            .chain(args.iter().copied())
            .collect();
        let out = rt_gpu(&all, dir.path());
        let err = stderr(&out);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(
            err.contains(words),
            "{args:?}: {err:?} should mention {words:?}"
        );
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
        let first_error_lines = err.lines().filter(|l| l.starts_with("error")).count();
        assert_eq!(first_error_lines, 1, "{args:?}: {err:?}");
        let kept = std::fs::read(dir.path().join("keep.png")).expect("still there");
        assert_eq!(kept, b"precious", "{args:?} clobbered the output");
    }
}

#[cfg(unix)]
#[test]
fn images_are_readable_by_others() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let out = rt_gpu(
        &["cornell", "--spp", "1", "--size", "4x4", "-o", "x.png"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let mode = std::fs::metadata(dir.path().join("x.png"))
        .expect("written")
        .permissions()
        .mode();
    assert_eq!(mode & 0o644, 0o644, "{mode:o}");
}

#[test]
fn print_shader_shows_the_specialised_kernel() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = rt_gpu(&["cornell-empty", "--print-shader"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let wgsl = String::from_utf8_lossy(&out.stdout);
    assert!(wgsl.contains("fn render("), "{wgsl}");
    assert!(
        wgsl.contains("features: QUADS LAMBERTIAN LIGHT"),
        "{}",
        wgsl.lines().next().unwrap_or("")
    );
    assert!(!wgsl.contains("fn fresnel"));
    rt_gpu::gpu::shader::validate(&wgsl).expect("valid WGSL");
}

#[test]
fn converge_rejects_bad_options_in_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (args, words) in [
        (
            &[
                "converge",
                "cornell",
                "--integrators",
                "magic",
                "--backends",
                "cpu",
            ][..],
            "invalid value 'magic' for '--integrators",
        ),
        (
            &["converge", "cornell", "--budget", "0", "--backends", "cpu"][..],
            "--budget",
        ),
        (
            &[
                "converge",
                "cornell",
                "--reference",
                "missing.pfm",
                "--backends",
                "cpu",
            ][..],
            "missing.pfm",
        ),
        (
            &["converge", "cornell", "--backends", "tpu"][..],
            "--backends",
        ),
    ] {
        let out = rt_gpu(args, dir.path());
        let err = stderr(&out);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(
            err.contains(words),
            "{args:?}: {err:?} should mention {words:?}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// With no usable adapter (here: only Metal allowed, which Linux lacks) the GPU backend says what
/// to install and how to render without it.
#[cfg(target_os = "linux")]
#[test]
fn a_missing_gpu_is_one_line_that_says_what_to_do() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(["cornell", "--spp", "1", "--size", "8x8"])
        .env("WGPU_BACKEND", "metal")
        .current_dir(dir.path())
        .output()
        .expect("runs");
    let err = stderr(&out);
    assert!(!out.status.success());
    assert!(
        err.contains("no GPU adapter found")
            && err.contains("mesa-vulkan-drivers")
            && err.contains("--backend cpu"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}
