//! `rt-gpu view` in a real window on a virtual X display (Xvfb), drawn by lavapipe: what the
//! window shows is the batch render's PNG byte for byte, scripted moves and real X input
//! (xdotool) move the camera and restart the film, the printed `[camera]` table renders the
//! view shown, Ctrl+S writes the film `rt-gpu` writes, and a missing display or a closed window
//! end as they should. CI installs Xvfb and xdotool (.ci/setup); elsewhere these tests are
//! skipped with a note unless RT_GPU_REQUIRE_GPU is set.
#![cfg(feature = "viewer")]

use crate::common;

use common::cli::{rt_gpu, stderr};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A virtual X display for one test, ended when dropped.
struct XServer {
    child: Child,
    display: String,
}

impl Drop for XServer {
    /// SIGTERM, not SIGKILL: Xvfb then removes its lock file and socket, which a killed one
    /// leaves for the next server to trip over.
    /// A server that has not ended within a few seconds is killed.
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let deadline = Instant::now() + Duration::from_secs(5);
        while matches!(self.child.try_wait(), Ok(None)) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Xvfb servers start one at a time: parallel tests starting theirs at once are where a
/// reported display was once not the test's own.
static STARTING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Starts Xvfb on a free display number (it writes the number it took to the fd given), and
/// makes sure a client can connect to it: Xvfbs started at once by parallel tests, beside a
/// stale socket of an earlier server, once reported a display no client could open. Then it
/// tries again on another.
fn x_server() -> Option<XServer> {
    let _one_at_a_time = STARTING.lock().unwrap_or_else(|e| e.into_inner());
    for _ in 0..5 {
        let x = start_x_server()?;
        if accepts_clients(&x.display) {
            return Some(x);
        }
        eprintln!(
            "Xvfb reported display {} but it takes no client; another",
            x.display
        );
    }
    panic!("no Xvfb display that accepts clients after 5 tries")
}

/// Whether a client (xdotool, which the input test needs anyway) connects to `display`
/// within a few seconds; true when there is no xdotool to ask.
fn accepts_clients(display: &str) -> bool {
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let asked = Command::new("xdotool")
            .arg("getdisplaygeometry")
            .env("DISPLAY", display)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status();
        match asked {
            Err(_) => return true,
            Ok(status) if status.success() => return true,
            Ok(_) if Instant::now() > deadline => return false,
            Ok(_) => std::thread::sleep(Duration::from_millis(100)),
        }
    }
}

fn start_x_server() -> Option<XServer> {
    let started = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "1024x768x24",
            "-nolisten",
            "tcp",
            // The client check's disconnection must not reset the server under the viewer.
            "-noreset",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn();
    let mut child = match started {
        Ok(c) => c,
        Err(e) if std::env::var_os("RT_GPU_REQUIRE_GPU").is_some() => {
            panic!("RT_GPU_REQUIRE_GPU is set but Xvfb cannot start ({e}): run .ci/setup")
        }
        Err(e) => {
            eprintln!("skipping viewer test: no Xvfb ({e})");
            return None;
        }
    };
    let mut line = String::new();
    BufReader::new(child.stdout.take().expect("piped"))
        .read_line(&mut line)
        .expect("Xvfb reports its display");
    let number: u32 = line
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("Xvfb reported no display number: {line:?}"));
    Some(XServer {
        child,
        display: format!(":{number}"),
    })
}

/// Runs `rt-gpu view args` on `x`'s display in `dir`.
fn view(x: &XServer, args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .arg("view")
        .args(args)
        .env("DISPLAY", &x.display)
        .current_dir(dir)
        .output()
        .expect("runs")
}

fn ok(out: &std::process::Output, what: &str) {
    assert!(out.status.success(), "{what} failed: {}", stderr(out));
}

/// All a piped output of a child held, as text.
fn drain(pipe: Option<impl Read>) -> String {
    let mut text = String::new();
    pipe.expect("piped")
        .read_to_string(&mut text)
        .expect("reads");
    text
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

const SIZE: &str = "96x72";

/// The window's image after 8 spp is the PNG a batch render of 8 spp writes, byte for byte,
/// on the kernel (the Cornell box, held inlined; a scene traced through its BVH) and on the CPU
/// backend (its film uploaded each frame).
#[test]
fn the_window_shows_the_batch_render_exactly() {
    let Some(x) = x_server() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    for (scene, backend) in [("cornell", "gpu"), ("showcase", "gpu"), ("cornell", "cpu")] {
        let shot = format!("{scene}-{backend}-window.png");
        let batch = format!("{scene}-{backend}-batch.png");
        let common = ["--size", SIZE, "--backend", backend, "--seed", "3"];
        let out = view(
            &x,
            &[
                &[scene][..],
                &common,
                &["--exit-after-spp", "8", "--screenshot", &shot],
            ]
            .concat(),
            dir.path(),
        );
        ok(&out, "the viewer");
        let out = rt_gpu(
            &[&[scene][..], &common, &["--spp", "8", "-o", &batch]].concat(),
            dir.path(),
        );
        ok(&out, "the batch render");
        assert!(
            bytes(&dir.path().join(&shot)) == bytes(&dir.path().join(&batch)),
            "{scene} on {backend}: the window's image differs from the batch render's PNG"
        );
    }
}

/// F5 reads the scene file again: a textured scene reloaded at 2 spp shows its batch render
/// at 8 spp exactly (the film restarted on the reloaded scene, whose image and camera are the
/// file's), and the viewer says what it holds after the reload.
#[test]
fn reloading_the_scene_restarts_the_film_on_the_file_as_it_is() {
    let Some(x) = x_server() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = scenes.join("textured.toml");
    let scene = scene.to_str().expect("a UTF-8 path");
    let common = ["--size", SIZE, "--backend", "gpu", "--seed", "3"];
    let shot = "reloaded-window.png";
    let out = view(
        &x,
        &[
            &[scene][..],
            &common,
            &["--step", "spp:2", "--step", "reload"],
            &["--exit-after-spp", "8", "--screenshot", shot],
        ]
        .concat(),
        dir.path(),
    );
    ok(&out, "the viewer");
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains("reloaded textured: ") && said.contains("image files"),
        "{said}"
    );
    let batch = "reloaded-batch.png";
    let out = rt_gpu(
        &[&[scene][..], &common, &["--spp", "8", "-o", batch]].concat(),
        dir.path(),
    );
    ok(&out, "the batch render");
    assert!(
        bytes(&dir.path().join(shot)) == bytes(&dir.path().join(batch)),
        "the reloaded window's image differs from the batch render's PNG"
    );
}

/// A scripted orbit at 4 spp restarts the film: the window at 8 spp shows the new view's batch
/// render of 8 spp (not 4 of the old view and 4 of the new), different from the unmoved view;
/// the `[camera]` table printed (C) renders it exactly; Ctrl+S's film file holds the film,
/// identity and samples `rt-gpu` writes for that camera (the files' bytes differ: the EXR
/// writer's chunk order varies from run to run).
#[test]
fn moves_restart_the_film_and_the_printed_camera_renders_the_view() {
    let Some(x) = x_server() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let out = view(
        &x,
        &[
            "cornell",
            "--size",
            SIZE,
            "--backend",
            "gpu",
            "--step",
            "spp:4",
            "--step",
            "orbit:60,20",
            "--step",
            "dolly:1",
            "--step",
            "camera",
            "--step",
            "spp:8",
            "--step",
            "save",
            "--output",
            "saved.exr",
            "--exit-after-spp",
            "8",
            "--screenshot",
            "moved.png",
        ],
        d,
    );
    ok(&out, "the viewer");
    let table = String::from_utf8(out.stdout).expect("UTF-8");
    assert!(table.starts_with("[camera]\nlook_from = ["), "{table}");
    // The scene file with the printed camera in place of its own.
    let cornell = std::fs::read_to_string("scenes/cornell.toml").expect("scene file");
    let (head, rest) = cornell.split_once("[camera]").expect("a camera table");
    let (_, tail) = rest.split_once("[materials]").expect("materials after it");
    // Named as the built-in scene, whose name the film's identity holds.
    std::fs::write(
        d.join("cornell.toml"),
        format!("{head}{table}\n[materials]{tail}"),
    )
    .expect("writes");
    let render = |scene: &str, output: &str| {
        let args = [
            "--size",
            SIZE,
            "--backend",
            "gpu",
            "--spp",
            "8",
            "-o",
            output,
        ];
        ok(
            &rt_gpu(&[&[scene][..], &args].concat(), d),
            "the batch render",
        );
    };
    render("cornell.toml", "moved-batch.png");
    render("cornell.toml", "moved-batch.exr");
    render("cornell", "still.png");
    let shown = bytes(&d.join("moved.png"));
    assert!(
        shown == bytes(&d.join("moved-batch.png")),
        "the printed camera renders another image"
    );
    assert!(
        shown != bytes(&d.join("still.png")),
        "the move changed nothing"
    );
    assert!(
        bytes(&d.join("saved.png")) == shown,
        "Ctrl+S's PNG is not what the window shows"
    );
    let saved = rt_gpu::film::file::read(&d.join("saved.exr")).expect("a film file");
    let batch = rt_gpu::film::file::read(&d.join("moved-batch.exr")).expect("a film file");
    assert!(
        saved.0.pixels == batch.0.pixels,
        "Ctrl+S's film differs from the batch film"
    );
    assert_eq!(saved.1.identity, batch.1.identity);
    assert_eq!(saved.1.samples, batch.1.samples);
}

/// Real X input: a left-button drag in the window (xdotool, through the X server) moves the
/// camera, so the camera printed after it (C) differs from the scene's; Escape quits with 0.
/// A window destroyed by another client mid-render also ends the viewer with 0.
#[test]
fn x_input_moves_the_camera_and_closing_exits_cleanly() {
    let Some(x) = x_server() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    let xdotool = |args: &[&str]| {
        let out = Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &x.display)
            .output();
        match out {
            Ok(o) => String::from_utf8_lossy(&o.stdout).trim().to_string(),
            Err(e) => panic!("xdotool: {e} (run .ci/setup)"),
        }
    };
    let start = || {
        Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
            .args(["view", "cornell", "--size", SIZE, "--backend", "gpu"])
            .env("DISPLAY", &x.display)
            .current_dir(dir.path())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("starts")
    };
    let window = |child: &mut Child| {
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let id = xdotool(&["search", "--name", "rt-gpu view"]);
            if let Some(id) = id.lines().next().filter(|l| !l.is_empty()) {
                return id.to_string();
            }
            if let Some(status) = child.try_wait().expect("waits") {
                let errors = drain(child.stderr.take());
                panic!("the viewer ended before its window appeared: {status}: {errors}");
            }
            assert!(Instant::now() < deadline, "no viewer window appeared");
            std::thread::sleep(Duration::from_millis(100));
        }
    };
    let wait = |child: &mut Child| {
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            if let Some(status) = child.try_wait().expect("waits") {
                return status;
            }
            if Instant::now() > deadline {
                let _ = child.kill();
                panic!("the viewer did not exit");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    };

    let mut child = start();
    let id = window(&mut child);
    // Let the film start, then drag from the window's middle, print the camera and quit.
    std::thread::sleep(Duration::from_millis(500));
    xdotool(&["windowfocus", "--sync", &id]);
    xdotool(&["mousemove", "--window", &id, "48", "36"]);
    xdotool(&["mousedown", "1"]);
    for step in 1..=6 {
        let x_pos = (48 + 5 * step).to_string();
        xdotool(&["mousemove", "--window", &id, &x_pos, "36"]);
        std::thread::sleep(Duration::from_millis(30));
    }
    xdotool(&["mouseup", "1"]);
    std::thread::sleep(Duration::from_millis(200));
    xdotool(&["key", "--window", &id, "c"]);
    std::thread::sleep(Duration::from_millis(300));
    xdotool(&["key", "--window", &id, "Escape"]);
    let status = wait(&mut child);
    let printed = drain(child.stdout.take());
    let errors = drain(child.stderr.take());
    assert!(status.success(), "Escape: {status}: {errors}");
    assert!(
        printed.starts_with("[camera]\nlook_from = ["),
        "printed {printed:?}: {errors}"
    );
    assert!(
        !printed.contains("look_from = [278.0, 278.0, -800.0]"),
        "the drag did not move the camera: {printed}"
    );

    let mut child = start();
    let id = window(&mut child);
    std::thread::sleep(Duration::from_millis(300));
    xdotool(&["windowclose", &id]);
    let status = wait(&mut child);
    let errors = drain(child.stderr.take());
    assert!(status.success(), "a closed window: {status}: {errors}");
}

/// Without a display: one line saying what to do, and a non-zero exit.
#[test]
fn no_display_is_a_one_line_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(["view", "cornell"])
        .env_remove("DISPLAY")
        .current_dir(dir.path())
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let text = stderr(&out);
    assert_eq!(
        text.trim(),
        "error: no display: set DISPLAY, or render to a file with rt-gpu SCENE"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_rt-gpu"))
        .args(["view", "cornell"])
        .env("DISPLAY", ":4093")
        .current_dir(dir.path())
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let text = stderr(&out);
    assert_eq!(text.lines().count(), 1, "{text}");
    assert!(
        text.starts_with("error: cannot open the display :4093"),
        "{text}"
    );
}

/// Issue 61: a size beyond the GPU's surfaces is one line naming the limit (32768x1 passed the
/// size check and ended in a raw wgpu validation error).
#[test]
fn a_size_beyond_the_gpus_surfaces_is_one_line() {
    let Some(x) = x_server() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    let out = view(
        &x,
        &["cornell", "--size", "32768x1", "--exit-after-spp", "1"],
        dir.path(),
    );
    assert!(!out.status.success());
    let text = stderr(&out);
    assert_eq!(text.trim_end().lines().count(), 1, "{text}");
    assert!(text.contains("use a smaller --size"), "{text}");
}

/// N shows the film denoised: the window's image after `denoise` at 8 spp (the script waits for
/// the denoiser) is the PNG `--denoise --spp 8` writes, byte for byte (on the CPU backend, whose
/// feature buffers the viewer's denoiser renders too). Skipped without Open Image Denoise
/// unless RT_GPU_REQUIRE_OIDN=1.
#[test]
fn the_denoised_window_is_the_batch_denoised_render() {
    let Some(x) = x_server() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    let common = ["cornell", "--size", SIZE, "--backend", "cpu", "--seed", "3"];
    let out = rt_gpu(
        &[&common[..], &["--spp", "8", "--denoise", "-o", "batch.png"]].concat(),
        dir.path(),
    );
    let no_oidn = !out.status.success() && stderr(&out).contains("Open Image Denoise");
    if no_oidn && std::env::var_os("RT_GPU_REQUIRE_OIDN").is_none_or(|v| v != "1") {
        eprintln!("skipped: {}", stderr(&out));
        return;
    }
    ok(&out, "the batch render");
    let out = view(
        &x,
        &[
            &common[..],
            &["--step", "spp:8", "--step", "denoise"],
            &["--exit-after-spp", "8", "--screenshot", "window.png"],
        ]
        .concat(),
        dir.path(),
    );
    ok(&out, "the viewer");
    assert!(
        bytes(&dir.path().join("window.png")) == bytes(&dir.path().join("batch.png")),
        "the denoised window differs from the batch render's denoised PNG"
    );
}
