//! Long renders through the command line: checkpoints that resume bit-identically after a
//! signal at any point, shards that merge bit-identically into one render, and the one-line
//! refusals of what cannot be combined.
#![cfg(feature = "cli")]

use crate::common;

use common::cli::{rt_gpu, spp_reached, stderr};
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// Arguments `base` followed by `extra`.
fn args<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
    [base, extra].concat()
}

fn ok(out: Output) -> Output {
    assert!(out.status.success(), "{}", stderr(&out));
    out
}

/// A failed run's stderr, which has one error line (clap's usage hints may follow it).
fn one_line_error(out: &Output) -> String {
    assert!(!out.status.success(), "expected a failure: {}", stderr(out));
    let err = stderr(out);
    let error_lines = err.lines().filter(|l| l.starts_with("error")).count();
    assert_eq!(error_lines, 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn read(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Shards of one render, merged in any order (also through an intermediate film file), give the
/// same image bytes as rendering every sample at once, on both backends; overlapping shards,
/// shards of another render and non-film inputs are refused in one line; a missing shard is a
/// warning that names its samples.
#[test]
fn shards_merge_bit_identically_into_one_render() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    for backend in ["cpu", "gpu"] {
        let base = ["cornell", "--backend", backend, "--size", "24x16"];
        let with = |extra: &[&'static str]| args(&base, extra);
        ok(rt_gpu(&with(&["--spp", "37", "-o", "whole.pfm"]), d));
        for k in 0..3 {
            let shard = format!("{k}/3");
            let name = format!("s{k}.exr");
            let shard_args = ["--spp", "37", "--shard", &shard, "-o", &name];
            ok(rt_gpu(&args(&base, &shard_args), d));
        }
        ok(rt_gpu(
            &["merge", "s2.exr", "s0.exr", "s1.exr", "-o", "m.pfm"],
            d,
        ));
        assert_eq!(
            read(d, "whole.pfm"),
            read(d, "m.pfm"),
            "{backend}: 3 shards"
        );
        // Two steps: a film of two shards, then the third.
        ok(rt_gpu(&["merge", "s1.exr", "s0.exr", "-o", "s01.exr"], d));
        ok(rt_gpu(&["merge", "s01.exr", "s2.exr", "-o", "m2.pfm"], d));
        assert_eq!(
            read(d, "whole.pfm"),
            read(d, "m2.pfm"),
            "{backend}: in steps"
        );
        // --samples names the same ranges: shard 1/3 of 37 is 12..24.
        ok(rt_gpu(&with(&["--samples", "12..24", "-o", "r.exr"]), d));
        ok(rt_gpu(
            &["merge", "s0.exr", "r.exr", "s2.exr", "-o", "m3.pfm"],
            d,
        ));
        assert_eq!(
            read(d, "whole.pfm"),
            read(d, "m3.pfm"),
            "{backend}: --samples"
        );

        let err = one_line_error(&rt_gpu(&["merge", "s0.exr", "s01.exr", "-o", "x.pfm"], d));
        assert!(err.contains("overlap"), "{err}");
        let out = ok(rt_gpu(&["merge", "s0.exr", "s2.exr", "-o", "gap.pfm"], d));
        assert!(
            stderr(&out).contains("samples 12..24 are missing"),
            "{}",
            stderr(&out)
        );
    }
    ok(rt_gpu(
        &[
            "cornell",
            "--backend",
            "cpu",
            "--size",
            "24x16",
            "--seed",
            "5",
            "--samples",
            "12..24",
            "-o",
            "seed5.exr",
        ],
        d,
    ));
    let err = one_line_error(&rt_gpu(&["merge", "s0.exr", "seed5.exr", "-o", "x.pfm"], d));
    assert!(err.contains("seed"), "{err}");
    ok(rt_gpu(
        &[
            "cornell",
            "--backend",
            "cpu",
            "--size",
            "4x4",
            "--spp",
            "1",
            "-o",
            "p.png",
        ],
        d,
    ));
    let err = one_line_error(&rt_gpu(&["merge", "s0.exr", "p.png", "-o", "x.pfm"], d));
    assert!(err.contains("p.png"), "{err}");
    let err = one_line_error(&rt_gpu(
        &["merge", "s0.exr", "absent.exr", "-o", "x.pfm"],
        d,
    ));
    assert!(err.contains("absent.exr"), "{err}");
    let err = one_line_error(&rt_gpu(
        &["cornell", "--spp", "8", "--shard", "0/2", "-o", "x.png"],
        d,
    ));
    assert!(err.contains(".exr"), "{err}");
    let err = one_line_error(&rt_gpu(&["cornell", "--spp", "8", "--shard", "2/2"], d));
    assert!(err.contains("K counts from 0"), "{err}");
    let err = one_line_error(&rt_gpu(&["cornell", "--checkpoint-every", "5"], d));
    assert!(err.contains("needs --checkpoint"), "{err}");
    let err = one_line_error(&rt_gpu(
        &["cornell", "--checkpoint", "c.png", "-o", "x.png"],
        d,
    ));
    assert!(err.contains("name it .exr"), "{err}");
    assert!(!d.join("x.pfm").exists() && !d.join("x.png").exists());
}

/// Starts a checkpointing render, waits `after` past its first checkpoint, and signals it.
fn interrupt(dir: &Path, args: &[&str], after: Duration, signal: &str) -> std::process::ExitStatus {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(args)
        .current_dir(dir)
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("starts");
    let start = Instant::now();
    while !dir.join("ck.exr").exists() && start.elapsed() < Duration::from_secs(60) {
        if child.try_wait().expect("polls").is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(after);
    let _ = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status();
    child.wait().expect("exits")
}

/// A render stopped by SIGINT or SIGTERM at several points, and resumed each time from its
/// checkpoint, ends with the same image bytes as an uninterrupted render; a stop exits with
/// 128 + the signal and writes the image so far; resuming with other options is one line.
#[cfg(unix)]
#[test]
fn interrupted_renders_resume_bit_identically() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    for backend in ["cpu", "gpu"] {
        let _ = std::fs::remove_file(d.join("ck.exr"));
        let scene = [
            "cornell",
            "--backend",
            backend,
            "--size",
            "32x32",
            "--max-depth",
            "4",
        ];
        // About eight seconds of work on this device (lavapipe or a real GPU), so that the stops
        // land mid-render: what one second reaches, eight times. (Five left too little after
        // the first stop, whose pass in flight may be long, once and again in CI.)
        let out = ok(rt_gpu(&args(&scene, &["--time", "1", "-o", "t.pfm"]), d));
        let spp = (8 * spp_reached(&out)).max(100).to_string();
        let base = args(&scene, &["--spp", &spp]);
        let with = |extra: &[&'static str]| args(&base, extra);
        ok(rt_gpu(&with(&["-o", "whole.pfm"]), d));
        let checkpointing = with(&[
            "--checkpoint",
            "ck.exr",
            "--checkpoint-every",
            "0.01",
            "-o",
            "part.pfm",
        ]);
        let mut stops = 0;
        let mut resumed = checkpointing.clone();
        for (after, signal) in [(0, "-INT"), (700, "-TERM"), (300, "-INT"), (1100, "-TERM")] {
            let status = interrupt(d, &resumed, Duration::from_millis(after), signal);
            if status.success() {
                break;
            }
            let expected = if signal == "-INT" { 130 } else { 143 };
            assert_eq!(status.code(), Some(expected), "{backend}: {status:?}");
            assert!(d.join("part.pfm").exists(), "{backend}: no image so far");
            stops += 1;
            // Short intervals make short passes, so that the next stop lands mid-render.
            resumed = with(&[
                "--resume",
                "ck.exr",
                "--checkpoint-every",
                "0.01",
                "-o",
                "part.pfm",
            ]);
        }
        assert!(
            stops >= 2,
            "{backend}: the render ended before being stopped twice"
        );
        ok(rt_gpu(&resumed, d));
        assert_eq!(read(d, "whole.pfm"), read(d, "part.pfm"), "{backend}");
        assert!(
            !d.join(".ck.exr.rt-gpu-lock").exists(),
            "{backend}: a lock file stays"
        );

        let other_seed = [
            &base[..],
            &["--seed", "1", "--resume", "ck.exr", "-o", "y.pfm"],
        ]
        .concat();
        let err = one_line_error(&rt_gpu(&other_seed, d));
        assert!(err.contains("seed is 1 here, 0 there"), "{err}");
        let fewer = [
            &base[..],
            &["--spp", "10", "--resume", "ck.exr", "-o", "y.pfm"],
        ]
        .concat();
        let err = one_line_error(&rt_gpu(&fewer, d));
        assert!(err.contains("at least"), "{err}");
        assert!(!d.join("y.pfm").exists());
    }
}

/// A checkpoint is never replaced by accident: an existing one is refused unless --resume or
/// --force says what to do, the checkpoint and the output are caught as one file however they
/// are spelled, a checkpoint a render holds is locked against a second render, a checkpoint
/// that cannot be written still lets the image be written (then the run fails), and temporary
/// files a killed run left are removed by the next run of the same output.
#[test]
fn checkpoints_are_never_replaced_by_accident() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let base = ["cornell", "--backend", "cpu", "--size", "8x8", "--spp", "4"];
    let with = |extra: &[&'static str]| args(&base, extra);
    ok(rt_gpu(&with(&["--checkpoint", "ck.exr", "-o", "a.png"]), d));
    let before = read(d, "ck.exr");
    let err = one_line_error(&rt_gpu(
        &with(&["--checkpoint", "ck.exr", "-o", "a.png"]),
        d,
    ));
    assert!(
        err.contains("--resume ck.exr") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        read(d, "ck.exr"),
        before,
        "the refused run touched the checkpoint"
    );
    ok(rt_gpu(
        &with(&["--checkpoint", "ck.exr", "--force", "-o", "a.png"]),
        d,
    ));
    let err = one_line_error(&rt_gpu(
        &with(&["--checkpoint", "same.exr", "-o", "./same.exr"]),
        d,
    ));
    assert!(err.contains("same file"), "{err}");

    // Another process holds the checkpoint's lock.
    let lock = std::fs::File::create(d.join(".ck.exr.rt-gpu-lock")).expect("creates");
    lock.try_lock().expect("locks");
    let err = one_line_error(&rt_gpu(
        &args(
            &base[..5],
            &["--spp", "8", "--resume", "ck.exr", "-o", "b.png"],
        ),
        d,
    ));
    assert!(err.contains("in use by another rt-gpu render"), "{err}");
    drop(lock);
    ok(rt_gpu(
        &args(
            &base[..5],
            &["--spp", "8", "--resume", "ck.exr", "-o", "b.png"],
        ),
        d,
    ));
    assert!(
        !d.join(".ck.exr.rt-gpu-lock").exists(),
        "the lock file stays"
    );

    // What a killed run left: removed, unless a live process holds it.
    std::fs::write(d.join(".rt-gpu-a.png-abcdef.tmp"), b"").expect("writes");
    let held = d.join(".rt-gpu-a.png-ghijkl.tmp");
    let live = std::fs::File::create(&held).expect("creates");
    live.try_lock().expect("locks");
    ok(rt_gpu(&with(&["-o", "a.png"]), d));
    assert!(
        !d.join(".rt-gpu-a.png-abcdef.tmp").exists(),
        "a stale file stays"
    );
    assert!(held.exists(), "a live run's file was removed");
    drop(live);

    // The checkpoint's directory disappears mid-render: the image is still written.
    std::fs::create_dir(d.join("sub")).expect("mkdir");
    let child = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(args(
            &base[..5],
            &[
                "--time",
                "6",
                "--checkpoint",
                "sub/ck.exr",
                "--checkpoint-every",
                "0.1",
                "-o",
                "kept.png",
            ],
        ))
        .current_dir(d)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("starts");
    // Once the render holds its checkpoint (its lock file is there), and a pass later.
    let start = Instant::now();
    while !d.join("sub/.ck.exr.rt-gpu-lock").exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(300));
    std::fs::remove_dir_all(d.join("sub")).expect("removes");
    let out = child.wait_with_output().expect("exits");
    let err = one_line_error(&out);
    assert!(err.contains("the image was written to kept.png"), "{err}");
    assert!(d.join("kept.png").exists());
}
