//! The command line: renders in every format, and every bad input exits non-zero with one clear
//! line, leaving an existing output file untouched.
#![cfg(feature = "cli")]

use crate::common;

use common::cli::{rt_gpu, spp_reached, stderr};
use std::path::Path;
use std::process::Command;

/// A render that takes milliseconds (add `-o FILE`).
const TINY_CPU_RENDER: &[&str] = &["cornell", "--backend", "cpu", "--spp", "1", "--size", "4x4"];

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
    let (w, h, rgb) = rt_gpu::film::output::read_pfm(&dir.path().join("out.pfm")).expect("reads");
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

/// 8-bit outputs: PNG uses the sRGB curve viewers assume, PPM gamma 2 as the original project
/// did, and `--gamma` chooses (a grey background of radiance 0.2: sRGB 124, gamma 2 114).
#[test]
fn png_is_srgb_and_gamma_2_on_request() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grey = "[render]\nbackground = [0.2, 0.2, 0.2]\n[camera]\nlook_from = [0, 0, 1]\nlook_at = [0, 0, 0]\nvfov = 40\n";
    std::fs::write(dir.path().join("grey.toml"), grey).expect("write");
    let value = |args: &[&str], file: &str| {
        let all: Vec<&str> = [
            "grey.toml",
            "--backend",
            "cpu",
            "--spp",
            "1",
            "--size",
            "2x2",
            "-o",
            file,
        ]
        .into_iter()
        .chain(args.iter().copied())
        .collect();
        let out = rt_gpu(&all, dir.path());
        assert!(out.status.success(), "{}", stderr(&out));
        if file.ends_with(".png") {
            image::open(dir.path().join(file))
                .expect("png")
                .into_rgb8()
                .get_pixel(0, 0)
                .0[0]
        } else {
            let text = std::fs::read_to_string(dir.path().join(file)).expect("ppm");
            text.split_whitespace()
                .nth(4)
                .expect("a value")
                .parse()
                .expect("a number")
        }
    };
    assert_eq!(value(&[], "a.png"), 124);
    assert_eq!(value(&["--gamma", "2"], "b.png"), 114);
    assert_eq!(value(&[], "c.ppm"), 114);
    assert_eq!(value(&["--gamma", "srgb"], "d.ppm"), 124);
    let out = rt_gpu(&["grey.toml", "--gamma", "bright"], dir.path());
    assert!(!out.status.success() && stderr(&out).contains("srgb"));
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
    std::fs::write(
        dir.path().join("huge.toml"),
        format!("{SMALL_SCENE}\n[render]\nwidth = 32768\nheight = 32768\n"),
    )
    .expect("write");
    let cases: &[(&[&str], &str)] = &[
        (&["no-such-scene"], "neither a built-in scene"),
        (&["missing.toml"], "cannot read scene file missing.toml"),
        (&["broken.toml"], "broken.toml:1:"),
        (&["nan.toml"], "nan.toml:3:"),
        (&["cornell", "--spp", "0"], "--spp"),
        (
            &["cornell", "--target-error", "0"],
            "--target-error must be a positive",
        ),
        (
            &["cornell", "--target-error", "nan"],
            "--target-error must be a positive",
        ),
        (
            &["cornell", "--target-error", "0.1", "--shard", "1/2"],
            "not with --samples or --shard",
        ),
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
        (
            &["cornell", "-o", "keep.png/x.png"],
            "keep.png is a file, not a directory",
        ),
        (
            &["cornell", "--backend", "cpu", "--adapter", "x"],
            "--adapter",
        ),
        (&["scenes"], "is a subcommand"),
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
    // A scene's own size meets the same pixel cap as --size (it once aborted allocating 60 GB).
    let out = rt_gpu(&["huge.toml", "--spp", "1", "-o", "keep.png"], dir.path());
    assert!(!out.status.success());
    assert!(stderr(&out).contains("pixels"), "{}", stderr(&out));
    assert_eq!(stderr(&out).lines().count(), 1, "{}", stderr(&out));
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
    let pfm = |name: &str, scale: &str, value: f32| {
        let mut bytes = format!("PF\n4 4\n{scale}\n").into_bytes();
        for _ in 0..48 {
            bytes.extend_from_slice(&value.to_le_bytes());
        }
        std::fs::write(dir.path().join(name), bytes).expect("write");
    };
    pfm("nan.pfm", "-1.0", f32::NAN);
    pfm("negative.pfm", "-1.0", -0.5);
    pfm("nan-scale.pfm", "nan", 0.5);
    let reference = |file: &'static str| -> Vec<&'static str> {
        vec![
            "converge",
            "cornell",
            "--size",
            "4x4",
            "--reference",
            file,
            "--backends",
            "cpu",
        ]
    };
    let owned: Vec<(Vec<&str>, &str)> = vec![
        (reference("nan.pfm"), "not a finite non-negative radiance"),
        (
            reference("negative.pfm"),
            "not a finite non-negative radiance",
        ),
        (reference("nan-scale.pfm"), "not an RGB PFM file"),
        (
            vec!["converge", "cornell", "--backends", "cpu,cpu"],
            "--backends lists cpu twice",
        ),
        (
            vec![
                "converge",
                "cornell",
                "--reference",
                "x.pfm",
                "--reference-spp",
                "8",
            ],
            "no effect with --reference",
        ),
    ];
    let listed: [(&[&str], &str); 4] = [
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
    ];
    let cases = owned
        .iter()
        .map(|(args, words)| (args.as_slice(), *words))
        .chain(listed);
    for (args, words) in cases {
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

/// With no Vulkan driver `--backend gpu` says what to install and how to render without it;
/// with WGPU_BACKEND naming a backend that has no adapter (Metal, on Linux), it says so instead.
/// `--backend auto` (the default) renders on the CPU then, and says why.
#[cfg(target_os = "linux")]
#[test]
fn a_missing_gpu_is_one_line_that_says_what_to_do() {
    let dir = tempfile::tempdir().expect("tempdir");
    let no_driver = "/nonexistent/icd.json";
    let auto = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(["cornell", "--spp", "1", "--size", "8x8"])
        .envs([
            ("VK_ICD_FILENAMES", no_driver),
            ("VK_DRIVER_FILES", no_driver),
        ])
        .current_dir(dir.path())
        .output()
        .expect("runs");
    let summary = stderr(&auto);
    assert!(auto.status.success(), "{summary}");
    assert!(
        summary.contains(", cpu [") && summary.contains("(auto: no GPU adapter"),
        "{summary}"
    );
    let run = |env: &[(&str, &str)]| {
        let out = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
            .args(["cornell", "--spp", "1", "--size", "8x8", "--backend", "gpu"])
            .envs(env.iter().copied())
            .current_dir(dir.path())
            .output()
            .expect("runs");
        assert!(!out.status.success());
        let err = stderr(&out);
        assert_eq!(err.lines().count(), 1, "{err}");
        err
    };
    let err = run(&[
        ("VK_ICD_FILENAMES", no_driver),
        ("VK_DRIVER_FILES", no_driver),
    ]);
    assert!(
        err.contains("no GPU adapter found")
            && err.contains("mesa-vulkan-drivers")
            && err.contains("--backend cpu"),
        "{err}"
    );
    let err = run(&[("WGPU_BACKEND", "metal")]);
    let gpu_here = std::env::var_os("RT_GPU_REQUIRE_GPU").is_some();
    assert!(
        err.contains("WGPU_BACKEND=metal") || (!gpu_here && err.contains("no GPU adapter found")),
        "{err}"
    );
}

/// Destinations that cannot take the image fail before the render starts (the GPU adapter named
/// here does not exist, so an error about it means the render was tried first), with one line,
/// and change nothing on disk.
#[test]
fn unwritable_outputs_fail_before_rendering() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = |name: &str| dir.path().join(name);
    std::fs::create_dir(path("folder.png")).expect("mkdir");
    std::fs::write(path("locked.png"), b"keep").expect("write");
    let mut perms = std::fs::metadata(path("locked.png"))
        .expect("meta")
        .permissions();
    perms.set_readonly(true);
    std::fs::set_permissions(path("locked.png"), perms).expect("chmod");
    std::fs::write(path("scene.toml"), SMALL_SCENE).expect("write");
    let long_name = format!("{}.png", "a".repeat(300));
    let mut cases = vec![
        ("folder.png", "is a directory"),
        ("locked.png", "read-only"),
        (long_name.as_str(), "255"),
        ("no/such/dir/x.png", "does not exist"),
    ];
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("scene.toml", path("scene.png")).expect("symlink");
        cases.push(("scene.png", "a file this run reads"));
        if Path::new("/proc/self").exists() {
            cases.push(("/proc/x.png", "cannot create a file in /proc"));
        }
    }
    for (output, words) in cases {
        let out = rt_gpu(
            &["scene.toml", "--adapter", "no-such-gpu-xyz", "-o", output],
            dir.path(),
        );
        let err = stderr(&out);
        assert!(!out.status.success(), "{output} succeeded");
        assert!(
            err.contains(words),
            "{output}: {err:?} should mention {words:?}"
        );
        assert_eq!(err.lines().count(), 1, "{output}: {err:?}");
    }
    assert_eq!(std::fs::read(path("locked.png")).expect("kept"), b"keep");
    assert_eq!(
        std::fs::read_to_string(path("scene.toml")).expect("kept"),
        SMALL_SCENE
    );
    assert_no_temporary_files(dir.path());
}

const SMALL_SCENE: &str = "[camera]\nlook_from = [0, 0, 3]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nwhite = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n\n[[object]]\nsphere = { center = [0, 0, 0], radius = 1 }\nmaterial = \"white\"\n";

fn assert_no_temporary_files(dir: &Path) {
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .expect("lists")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "left behind: {leftovers:?}");
}

/// A symbolic link is written through, as `cp` would: the link stays a link.
#[cfg(unix)]
#[test]
fn a_symlinked_output_stays_a_link() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("real.png"), b"old").expect("write");
    std::os::unix::fs::symlink("real.png", dir.path().join("link.png")).expect("symlink");
    let out = rt_gpu(&[TINY_CPU_RENDER, &["-o", "link.png"]].concat(), dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let link = std::fs::symlink_metadata(dir.path().join("link.png")).expect("exists");
    assert!(
        link.file_type().is_symlink(),
        "the link was replaced by a file"
    );
    let image = std::fs::read(dir.path().join("real.png")).expect("target");
    assert!(image.starts_with(b"\x89PNG"), "the target was not written");
}

/// `scenes --export` never replaces a user's files unless told to.
#[test]
fn export_refuses_to_overwrite_without_force() {
    let dir = tempfile::tempdir().expect("tempdir");
    let export = |force: bool| {
        let mut args = vec!["scenes", "--export", "."];
        if force {
            args.push("--force");
        }
        rt_gpu(&args, dir.path())
    };
    assert!(export(false).status.success());
    std::fs::write(dir.path().join("cornell.toml"), b"# my edits").expect("write");
    let out = export(false);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("cornell.toml") && stderr(&out).contains("--force"));
    assert_eq!(
        std::fs::read(dir.path().join("cornell.toml")).expect("kept"),
        b"# my edits"
    );
    assert!(export(true).status.success());
    assert_ne!(
        std::fs::read(dir.path().join("cornell.toml")).expect("exported"),
        b"# my edits"
    );
}

/// A reader that goes away (`rt-gpu scenes | head -1`) ends the program quietly; a full device
/// is one line of error; neither panics.
#[cfg(target_os = "linux")]
#[test]
fn closed_pipes_and_full_devices_do_not_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    for args in [
        &["scenes"][..],
        &["cornell", "--print-shader"],
        &["devices"],
    ] {
        let (reader, writer) = std::io::pipe().expect("pipe");
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
            .args(args)
            .current_dir(dir.path())
            .stdout(writer)
            .output()
            .expect("runs");
        let err = stderr(&out);
        assert!(
            !err.contains("panicked") && !err.contains("internal error"),
            "{args:?}: {err}"
        );
        if args[0] != "devices" {
            assert!(out.status.success(), "{args:?}: {err}");
        }
    }
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full")
    };
    let out = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .arg("scenes")
        .stdout(full())
        .output()
        .expect("runs");
    let err = stderr(&out);
    assert!(!out.status.success());
    assert!(
        err.contains("No space left") && !err.contains("panicked"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    // A render whose stderr (progress, summary) cannot be written still writes its image.
    let status = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(TINY_CPU_RENDER)
        .args(["-o", "x.png"])
        .current_dir(dir.path())
        .stderr(full())
        .status()
        .expect("runs");
    assert!(status.success(), "{status:?}");
    assert!(dir.path().join("x.png").exists());
}

/// `bench` fails when a run fails (here every GPU run: no such adapter).
#[test]
fn bench_fails_when_a_run_fails() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = rt_gpu(
        &[
            "bench",
            "--adapter",
            "no-such-gpu-xyz",
            "--spp",
            "1",
            "--size",
            "4x4",
        ],
        dir.path(),
    );
    assert!(!out.status.success());
    assert!(stderr(&out).contains("runs failed"), "{}", stderr(&out));
}

/// `bench --runs cpu` times the CPU alone: with a GPU adapter that does not exist, nothing
/// fails, and no GPU line is printed.
#[test]
fn bench_times_only_the_runs_asked_for() {
    let dir = tempfile::tempdir().expect("tempdir");
    let args = [
        "bench",
        "--adapter",
        "no-such-gpu-xyz",
        "--spp",
        "1",
        "--size",
        "4x4",
    ];
    let out = rt_gpu(&[&args[..], &["--runs", "cpu"]].concat(), dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let printed = String::from_utf8_lossy(&out.stdout);
    assert!(printed.contains("  cpu "), "{printed}");
    for label in ["gpu specialised kernel", "gpu everything-enabled kernel"] {
        assert!(!printed.contains(label), "{printed}");
    }
}

/// `bench --stats` counts the kernel's and the CPU's traversals, and the kernel's SIMD groups.
#[test]
fn bench_stats_prints_both_walks_and_the_simd_groups() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = rt_gpu(
        &["bench", "showcase", "--stats", "--size", "16x16"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let printed = String::from_utf8_lossy(&out.stdout);
    for line in ["kernel, 4-wide", "cpu / kernel", "(a SIMD group)"] {
        assert!(printed.contains(line), "{line}: {printed}");
    }
}

/// SIGTERM (or Ctrl-C) during a render exits non-zero (128 + the signal) and leaves no
/// temporary file and no partial image.
#[cfg(unix)]
#[test]
fn a_signal_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("keep.png"), b"precious").expect("write");
    let mut child = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args([
            "cornell",
            "--backend",
            "cpu",
            "--spp",
            "1000000",
            "--size",
            "64x64",
        ])
        .args(["-o", "keep.png"])
        .current_dir(dir.path())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("starts");
    // Wait until the output is claimed (its temporary file exists), then signal.
    let claimed = (0..200).any(|_| {
        std::thread::sleep(std::time::Duration::from_millis(25));
        std::fs::read_dir(dir.path())
            .expect("lists")
            .filter_map(|e| e.ok())
            .any(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
    });
    assert!(claimed, "no temporary file appeared");
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
    let status = child.wait().expect("exits");
    assert_eq!(status.code(), Some(128 + 15), "{status:?}");
    assert_eq!(
        std::fs::read(dir.path().join("keep.png")).expect("kept"),
        b"precious"
    );
    assert_no_temporary_files(dir.path());
}

/// `--time` renders passes until the budget is spent and says how many samples per pixel it
/// reached; with `--spp` too, whichever comes first; a budget that is not a positive number is one
/// line.
#[test]
fn time_budgets_stop_the_render_and_report_the_spp_reached() {
    let dir = tempfile::tempdir().expect("tempdir");
    let base = [
        "cornell",
        "--backend",
        "cpu",
        "--size",
        "8x8",
        "-o",
        "t.pfm",
    ];
    let start = std::time::Instant::now();
    let out = rt_gpu(&[&base[..], &["--time", "0.5"]].concat(), dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    // Samples take microseconds here: the budget, not a sample count, ended the render.
    let reached = spp_reached(&out);
    assert!(reached > 64, "{}", stderr(&out));
    assert!(start.elapsed().as_secs_f64() < 30.0);
    // Its passes add up to the same image as one render of that many samples.
    let budgeted = std::fs::read(dir.path().join("t.pfm")).expect("written");
    let spp = reached.to_string();
    let out = rt_gpu(&[&base[..], &["--spp", &spp]].concat(), dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        std::fs::read(dir.path().join("t.pfm")).expect("written"),
        budgeted
    );
    let out = rt_gpu(
        &[&base[..], &["--time", "100", "--spp", "3"]].concat(),
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(spp_reached(&out), 3);
    for bad in ["--time=0", "--time=-1", "--time=nan", "--time=inf"] {
        let out = rt_gpu(&[&base[..], &[bad]].concat(), dir.path());
        assert!(!out.status.success());
        let err = stderr(&out);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

/// `--backend auto` (the default) names what ran and why. On a software adapter (lavapipe, as
/// in CI) it runs the kernel for a scene the kernel inlines (`cornell-empty`) and the CPU
/// backend for one traced through a BVH (`showcase`); on a GPU, the kernel for both. `--backend
/// gpu` and `cpu` force one, with no reason shown.
#[test]
fn auto_backend_picks_per_scene_and_says_why() {
    let dir = tempfile::tempdir().expect("tempdir");
    let summary = |scene: &str, backend: &str| {
        let out = rt_gpu(
            &[
                scene,
                "--backend",
                backend,
                "--spp",
                "1",
                "--size",
                "16x16",
                "-o",
                "a.png",
                "--force",
            ],
            dir.path(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
        stderr(&out)
    };
    let inlined = summary("cornell-empty", "auto");
    let bvh = summary("showcase", "auto");
    // What the machine has, from `rt-gpu devices` (its device types), not from auto itself.
    let devices = rt_gpu(&["devices"], dir.path());
    let listed = String::from_utf8_lossy(&devices.stdout).into_owned();
    let hardware = ["DiscreteGpu", "IntegratedGpu", "VirtualGpu"]
        .iter()
        .any(|kind| listed.contains(kind));
    let software = listed.contains(" Cpu,");
    if hardware {
        assert!(
            inlined.contains(", gpu [") && bvh.contains(", gpu [") && bvh.contains("(auto: a GPU)"),
            "{inlined}\n{bvh}"
        );
    } else if software {
        assert!(
            inlined.contains(", gpu [") && inlined.contains("inlined"),
            "{inlined}"
        );
        assert!(bvh.contains(", cpu [") && bvh.contains("BVH"), "{bvh}");
    } else {
        assert!(
            inlined.contains("(auto: no GPU adapter") && inlined.contains(", cpu ["),
            "{inlined}"
        );
    }
    let forced: &[&str] = if hardware || software {
        &["gpu", "cpu"]
    } else {
        &["cpu"]
    };
    for backend in forced {
        let summary = summary("showcase", backend);
        assert!(
            summary.contains(&format!(", {backend} [")) && !summary.contains("auto:"),
            "{summary}"
        );
    }
    // A checkpoint continues on the backend it was made on, whatever auto would pick.
    let out = rt_gpu(
        &[
            "showcase",
            "--backend",
            "cpu",
            "--spp",
            "2",
            "--size",
            "16x16",
            "--checkpoint",
            "ck.exr",
            "-o",
            "b.png",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let out = rt_gpu(
        &[
            "showcase",
            "--spp",
            "4",
            "--size",
            "16x16",
            "--resume",
            "ck.exr",
            "--checkpoint",
            "ck.exr",
            "-o",
            "b.png",
            "--force",
        ],
        dir.path(),
    );
    let resumed = stderr(&out);
    assert!(out.status.success(), "{resumed}");
    assert!(
        resumed.contains(", cpu [")
            && resumed.contains("(auto: the backend the checkpoint was rendered on)"),
        "{resumed}"
    );
    // Shards render on the kernel, so that films from any machine merge.
    if hardware || software {
        let out = rt_gpu(
            &[
                "showcase", "--spp", "4", "--size", "16x16", "--shard", "0/2", "-o", "s.exr",
            ],
            dir.path(),
        );
        let shard = stderr(&out);
        assert!(
            out.status.success() && shard.contains(", gpu [") && shard.contains("shards"),
            "{shard}"
        );
    }
}

/// `--target-error X` stops where the true relative error (RMSE against an 8 192-spp reference,
/// its own noise removed in quadrature, over the mean radiance) is within 1.5x of X: on the
/// Cornell box at 32x32, where Sobol stratification of the large pixels makes the error fall
/// far faster than 1/sqrt(spp) (5% at ~500 spp; independent samples need ~12 000), and with
/// independent samples (at 10%). The summary says the target was reached, and at how many spp.
#[test]
fn target_error_stops_near_the_true_error() {
    use rt_gpu::options::SamplerKind;
    use rt_gpu::render::{Integrator, RenderOptions};
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = rt_gpu::scene::builtin::builtin("cornell").expect("built-in");
    let reference_opts = RenderOptions {
        integrator: Integrator::Nee,
        sampler: SamplerKind::Sobol,
        ..RenderOptions::new(32, 32, 8192, scene.defaults.max_depth)
    };
    let reference = common::render_cpu(&scene, &reference_opts);
    let reference_noise = reference.estimated_rmse();
    let mean = reference.image_mean();
    let mean = (mean[0] + mean[1] + mean[2]) as f64 / 3.0;
    // Cornell at 32x32 on the CPU with `sampler`, seed 9, and `limits`, into `output`.
    let render = |sampler: &str, limits: &[&str], output: &str| {
        let mut args = vec![
            "cornell",
            "--backend",
            "cpu",
            "--size",
            "32x32",
            "--sampler",
            sampler,
            "--seed",
            "9",
            "-o",
            output,
            "--force",
        ];
        args.extend_from_slice(limits);
        rt_gpu(&args, dir.path())
    };
    for (sampler, target) in [("sobol", "0.05"), ("independent", "0.1")] {
        // --spp is a bound, so that a target ignored fails rather than hangs.
        let out = render(
            sampler,
            &["--target-error", target, "--spp", "50000"],
            "t.exr",
        );
        let summary = stderr(&out);
        assert!(out.status.success(), "{summary}");
        assert!(
            summary.contains(&format!("target error {target} reached at")),
            "{summary}"
        );
        let target: f64 = target.parse().expect("a number");
        let (film, _) = rt_gpu::film::file::read(&dir.path().join("t.exr")).expect("film file");
        let mse: f64 = film
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| (a.mean() - b.mean()).length_squared())
            .sum::<f64>()
            / (film.pixels.len() * 3) as f64;
        let true_error = (mse - reference_noise * reference_noise).max(0.0).sqrt() / mean;
        eprintln!(
            "{sampler}: {} spp, true relative error {true_error:.4} (reference noise {:.4})",
            spp_reached(&out),
            reference_noise / mean
        );
        // The image is the one `--spp` of the count reached renders.
        let spp = spp_reached(&out).to_string();
        let plain = render(sampler, &["--spp", &spp], "p.exr");
        assert!(plain.status.success(), "{}", stderr(&plain));
        let (plain, _) = rt_gpu::film::file::read(&dir.path().join("p.exr")).expect("film file");
        assert!(
            film.pixels
                .iter()
                .zip(&plain.pixels)
                .all(|(a, b)| a.mean() == b.mean()),
            "{sampler}: not the image of --spp {spp}"
        );
        assert!(
            true_error <= 1.5 * target && true_error >= target / 1.5,
            "{sampler}: true relative error {true_error} against the target {target}"
        );
    }
}

/// A textured scene in `dir`: `tex.png` as an albedo, `env.exr` as the environment, and an OBJ
/// whose material library gives it `kd.png` (issue 61's cases).
fn scene_reading_files(dir: &Path) {
    let image = |name: &str, width: u32| {
        let mut film = rt_gpu::film::Film::new(width, 2);
        for (i, p) in film.pixels.iter_mut().enumerate() {
            p.add_indexed(glam::Vec3::new(0.2, 0.5, 0.1 * i as f32), 0);
        }
        rt_gpu::film::output::write_image(&dir.join(name), &film).expect("writes an image");
    };
    image("tex.png", 2);
    image("kd.png", 2);
    image("env.exr", 4);
    std::fs::write(dir.join("m.mtl"), "newmtl paint\nKd 1 1 1\nmap_Kd kd.png\n").expect("mtl");
    std::fs::write(
        dir.join("tri.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl paint\nf 1/1 2/2 3/3\n",
    )
    .expect("obj");
    std::fs::write(
        dir.join("ts.toml"),
        "[render]\nbackground = { image = \"env.exr\" }\n[camera]\nlook_from = [0, 0, 3]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\ntex = { type = \"lambertian\", albedo = { image = \"tex.png\" } }\n\n[[object]]\nsphere = { center = [-1, 0, 0], radius = 0.5 }\nmaterial = \"tex\"\n\n[[object]]\nmesh = { file = \"tri.obj\" }\n",
    )
    .expect("scene");
}

/// Issue 61, data loss: no output (`-o`, `--checkpoint`, `converge -o`'s files) may replace a
/// file the scene reads (a texture, an environment, an MTL's map; by a hard link too).
#[test]
fn outputs_never_replace_a_file_the_scene_reads() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    scene_reading_files(d);
    let before: Vec<Vec<u8>> = ["tex.png", "kd.png", "env.exr"]
        .iter()
        .map(|f| std::fs::read(d.join(f)).expect("reads"))
        .collect();
    std::fs::hard_link(d.join("tex.png"), d.join("linked.png")).expect("links");
    let render = ["ts.toml", "--backend", "cpu", "--spp", "1", "--size", "4x4"];
    for extra in [
        &["-o", "tex.png"][..],
        &["-o", "kd.png"],
        &["-o", "env.exr"],
        &["-o", "linked.png"],
        &["-o", "ok.png", "--checkpoint", "env.exr", "--force"],
    ] {
        let args: Vec<&str> = render.iter().chain(extra).copied().collect();
        let out = rt_gpu(&args, d);
        let err = stderr(&out);
        assert!(!out.status.success(), "{extra:?} succeeded");
        assert!(
            err.contains("a file this run reads") && err.lines().count() == 1,
            "{extra:?}: {err}"
        );
    }
    // The render itself reads them: a render to another file succeeds.
    let args: Vec<&str> = render.iter().chain(&["-o", "ok.png"]).copied().collect();
    assert!(rt_gpu(&args, d).status.success());
    // converge -o writes converge.png into the folder: refused before any render.
    std::fs::create_dir(d.join("report")).expect("mkdir");
    std::fs::copy(d.join("tex.png"), d.join("report/converge.png")).expect("copies");
    let scene = std::fs::read_to_string(d.join("ts.toml")).expect("reads");
    std::fs::write(
        d.join("report/ts.toml"),
        scene.replace("\"tex.png\"", "\"converge.png\""),
    )
    .expect("writes");
    std::fs::copy(d.join("env.exr"), d.join("report/env.exr")).expect("copies");
    std::fs::copy(d.join("tri.obj"), d.join("report/tri.obj")).expect("copies");
    std::fs::copy(d.join("m.mtl"), d.join("report/m.mtl")).expect("copies");
    std::fs::copy(d.join("kd.png"), d.join("report/kd.png")).expect("copies");
    let out = rt_gpu(
        &[
            "converge",
            "report/ts.toml",
            "-o",
            "report",
            "--budget",
            "1",
        ],
        d,
    );
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("a file this run reads"),
        "{}",
        stderr(&out)
    );
    assert_eq!(
        std::fs::read(d.join("report/converge.png")).expect("kept"),
        before[0]
    );
    let after: Vec<Vec<u8>> = ["tex.png", "kd.png", "env.exr"]
        .iter()
        .map(|f| std::fs::read(d.join(f)).expect("reads"))
        .collect();
    assert_eq!(before, after);
}

/// Issue 61: a film knows the contents of the files its scene read, not only their names:
/// shards or a checkpoint of a scene whose texture, OBJ or MTL changed since neither merge
/// nor resume, and the message names the file.
#[test]
fn films_of_a_scene_whose_files_changed_neither_merge_nor_resume() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    scene_reading_files(d);
    let shard = |k: &str| {
        let out = format!("s{}.exr", k.replace('/', "_"));
        let args = [
            "ts.toml",
            "--backend",
            "cpu",
            "--spp",
            "2",
            "--size",
            "4x4",
            "--shard",
        ];
        let args: Vec<&str> = args.iter().copied().chain([k, "-o", &out]).collect();
        let run = rt_gpu(&args, d);
        assert!(run.status.success(), "{}", stderr(&run));
    };
    for (file, change) in [
        ("tex.png", None),
        ("kd.png", None),
        ("tri.obj", Some("v 0 0 0.5\n")),
        ("m.mtl", Some("Ns 10\n")),
    ] {
        let original = std::fs::read(d.join(file)).expect("reads");
        shard("0/2");
        // A PNG with bytes after its end decodes the same: the contents, not the image, count.
        let mut changed = original.clone();
        changed.extend(change.unwrap_or("\n").as_bytes());
        std::fs::write(d.join(file), &changed).expect("changes");
        shard("1/2");
        let out = rt_gpu(&["merge", "s0_2.exr", "s1_2.exr", "-o", "m.exr"], d);
        let err = stderr(&out);
        assert!(!out.status.success(), "{file}: merged");
        assert!(
            err.contains(&format!("file {file} differs")) && err.lines().count() == 1,
            "{file}: {err}"
        );
        std::fs::write(d.join(file), &original).expect("restores");
        shard("1/2");
        let out = rt_gpu(&["merge", "s0_2.exr", "s1_2.exr", "-o", "m.exr"], d);
        assert!(out.status.success(), "{file}: {}", stderr(&out));
    }
    // A checkpoint does not resume once the environment changed.
    let args = [
        "ts.toml",
        "--backend",
        "cpu",
        "--spp",
        "1",
        "--size",
        "4x4",
        "--checkpoint",
        "c.exr",
    ];
    assert!(rt_gpu(&args, d).status.success());
    let mut env = std::fs::read(d.join("env.exr")).expect("reads");
    env.push(0);
    std::fs::write(d.join("env.exr"), &env).expect("changes");
    let out = rt_gpu(
        &[
            "ts.toml",
            "--backend",
            "cpu",
            "--spp",
            "2",
            "--size",
            "4x4",
            "--resume",
            "c.exr",
        ],
        d,
    );
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("file env.exr differs"),
        "{}",
        stderr(&out)
    );
}

/// Issue 61: `scenes --export DIR --force` replaces a link in DIR with the file rather than
/// writing through it to a file outside DIR.
#[cfg(unix)]
#[test]
fn export_replaces_links_rather_than_writing_through_them() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::create_dir(d.join("out")).expect("mkdir");
    std::fs::write(d.join("precious.txt"), b"keep").expect("writes");
    std::os::unix::fs::symlink("../precious.txt", d.join("out/cornell.toml")).expect("links");
    std::os::unix::fs::symlink("../missing.txt", d.join("out/spheres.toml")).expect("links");
    let out = rt_gpu(&["scenes", "--export", "out"], d);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("spheres.toml"), "{}", stderr(&out));
    let out = rt_gpu(&["scenes", "--export", "out", "--force"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        std::fs::read(d.join("precious.txt")).expect("kept"),
        b"keep"
    );
    let exported = d.join("out/cornell.toml");
    assert!(
        !std::fs::symlink_metadata(&exported)
            .expect("exists")
            .file_type()
            .is_symlink()
    );
    assert!(
        std::fs::read_to_string(exported)
            .expect("reads")
            .contains("[camera]")
    );
    assert!(!d.join("missing.txt").exists());
}

/// Issue 61: mistakes in the arguments are one line each, and a negative number reaches the
/// option's own check rather than clap's tip that makes it the scene.
#[test]
fn argument_mistakes_are_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (args, words) in [
        (
            &["cornell", "--time", "-1"][..],
            "--time must be a positive",
        ),
        (
            &["cornell", "--target-error", "-1"],
            "--target-error must be a positive",
        ),
        (
            &["cornell", "--spp", "4", "--shard", "-1/2"],
            "expected K/N",
        ),
        (&["cornell", "--size", "0x0"], "--size"),
        (
            &["cornell", "--spp", "4", "--shard", "1/1"],
            "does not exist",
        ),
        (&["cornell", "--no-such-option"], "--no-such-option"),
        (&["converge", "cornell", "--budget", "-1"], "budget"),
    ] {
        let out = rt_gpu(args, dir.path());
        let err = stderr(&out);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(words), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(!err.contains("'-- -1'"), "{args:?}: {err}");
    }
    // --help is still clap's, whole, on stdout.
    let out = rt_gpu(&["--help"], dir.path());
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).lines().count() > 10);
}

/// Issue 61: `converge` on a scene that renders exactly black (every error 0) ends: the CSV is
/// written, the table says why nothing is fitted, and the plot is skipped with a reason (a log
/// axis over a degenerate range never ended).
#[test]
fn converge_on_a_black_scene_ends_and_says_why_nothing_is_fitted() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::write(
        d.join("black.toml"),
        "[render]\nbackground = [0, 0, 0]\n[camera]\nlook_from = [0, 0, 3]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nwhite = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n\n[[object]]\nsphere = { center = [0, 0, 0], radius = 1 }\nmaterial = \"white\"\n",
    )
    .expect("writes");
    let mut child = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args([
            "converge",
            "black.toml",
            "--backends",
            "cpu",
            "--integrators",
            "nee",
            "--size",
            "8x8",
            "--budget",
            "0.5",
            "--reference-spp",
            "4",
            "-o",
            "rep",
        ])
        .current_dir(d)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("runs");
    let start = std::time::Instant::now();
    while child.try_wait().expect("waits").is_none() {
        if start.elapsed().as_secs() > 120 {
            let _ = child.kill();
            panic!("converge on a black scene did not end in 120 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let out = child.wait_with_output().expect("output");
    let (stdout, err) = (String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert!(out.status.success(), "{err}");
    assert!(stdout.contains("nothing to fit"), "{stdout}");
    assert!(
        err.contains("no plot") && err.contains("error is 0"),
        "{err}"
    );
    assert!(d.join("rep/converge.csv").exists());
    // --target-error on it says the image is black rather than that an error of 0 was reached.
    let out = rt_gpu(
        &[
            "black.toml",
            "--backend",
            "cpu",
            "--size",
            "8x8",
            "--target-error",
            "0.01",
            "-o",
            "b.png",
        ],
        d,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("exactly black"), "{}", stderr(&out));
}
