"""`import rtgpu` (python/, docs/python.md): arrays of the right shape, the command line's bytes,
errors as exceptions, Ctrl-C, renders in threads. Run by .ci/run after `pip install .`:
`pytest tests/python`. GPU tests run where wgpu sees an adapter, and must where
RT_GPU_REQUIRE_GPU=1 (lavapipe in CI)."""

import _thread
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

import rtgpu

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cli():
    """The rt-gpu binary cargo built beside the tests, else the one on PATH."""
    for profile in ("debug", "release"):
        built = ROOT / "target" / profile / "rt-gpu"
        if built.exists():
            return str(built)
    found = shutil.which("rt-gpu")
    if found is None:
        pytest.skip("no rt-gpu binary: run cargo build first")
    return found


def has_gpu():
    if rtgpu.devices():
        return True
    if os.environ.get("RT_GPU_REQUIRE_GPU") == "1":
        pytest.fail("RT_GPU_REQUIRE_GPU=1, and wgpu sees no adapter")
    return False


def test_a_render_is_a_float32_image_of_the_asked_size():
    scene = rtgpu.load("cornell")
    assert scene.name == "cornell" and scene.size == (512, 512)
    r = rtgpu.render(scene, spp=4, size=(40, 30), backend="cpu")
    image = r.image
    assert image.shape == (30, 40, 3) and image.dtype == np.float32
    assert np.isfinite(image).all() and image.mean() > 0.01
    assert r.spp == 4 and r.backend == "cpu" and r.seconds > 0
    assert 0 < r.estimated_rmse < 1


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_the_same_bytes_as_the_command_line(tmp_path, backend):
    if backend == "gpu" and not has_gpu():
        pytest.skip("no GPU adapter")
    args = ["cornell", "--spp", "16", "--seed", "3", "--backend", backend, "--size", "64x48"]
    subprocess.run([cli(), *args, "-o", "cli.pfm"], cwd=tmp_path, check=True, capture_output=True)
    r = rtgpu.render(rtgpu.load("cornell"), spp=16, seed=3, backend=backend, size=(64, 48))
    r.write(str(tmp_path / "py.pfm"))
    assert (tmp_path / "py.pfm").read_bytes() == (tmp_path / "cli.pfm").read_bytes()
    # The array is the film's mean, rows from the top (the PFM stores them from the bottom).
    pfm = np.frombuffer((tmp_path / "cli.pfm").read_bytes()[-64 * 48 * 12 :], dtype="<f4")
    assert np.array_equal(r.image, pfm.reshape(48, 64, 3)[::-1])


def has_oidn(tmp_path):
    """Whether the command line finds Open Image Denoise (required where RT_GPU_REQUIRE_OIDN=1)."""
    out = subprocess.run([cli(), "cornell", "--spp", "1", "--size", "4x4", "--backend", "cpu",
                          "--denoise", "-o", "probe.pfm"], cwd=tmp_path, capture_output=True)
    if out.returncode == 0:
        return True
    if os.environ.get("RT_GPU_REQUIRE_OIDN") == "1":
        pytest.fail(f"RT_GPU_REQUIRE_OIDN=1, and: {out.stderr.decode()}")
    return False


def test_a_denoised_render_is_the_command_lines_with_its_buffers(tmp_path):
    if not has_oidn(tmp_path):
        pytest.skip("no Open Image Denoise (scripts/install-oidn.py)")
    args = ["cornell", "--spp", "16", "--seed", "3", "--backend", "cpu", "--size", "64x48"]
    subprocess.run([cli(), *args, "--denoise", "-o", "cli.pfm"], cwd=tmp_path, check=True,
                   capture_output=True)
    r = rtgpu.render(rtgpu.load("cornell"), spp=16, seed=3, backend="cpu", size=(64, 48),
                     denoise=True)
    r.write(str(tmp_path / "py.pfm"))
    assert (tmp_path / "py.pfm").read_bytes() == (tmp_path / "cli.pfm").read_bytes()
    assert "denoised" in repr(r)
    plain = rtgpu.render(rtgpu.load("cornell"), spp=16, seed=3, backend="cpu", size=(64, 48))
    assert np.array_equal(r.noisy, plain.image) and not np.array_equal(r.image, plain.image)
    assert plain.albedo is None and plain.normal is None
    assert r.albedo.shape == r.normal.shape == (48, 64, 3)
    assert r.albedo.min() >= 0 and r.albedo.max() <= 1
    assert r.normal.min() >= -1 and r.normal.max() <= 1
    # Closer than the noisy image to a 512-spp render (relative MSE, as converge reports it).
    reference = rtgpu.render(rtgpu.load("cornell"), spp=512, seed=9, backend="cpu",
                             size=(64, 48)).image
    rel_mse = lambda img: np.mean((img - reference) ** 2 / (reference**2 + 0.01))
    assert rel_mse(r.image) < 0.5 * rel_mse(r.noisy)


def test_a_scene_from_text_renders_what_its_parameters_say():
    def scene(albedo):
        return rtgpu.load_string(
            f"""
[camera]
look_from = [0, 0, 4]
look_at = [0, 0, 0]
vfov = 30
[render]
background = [1, 1, 1]
[materials.grey]
type = "lambertian"
albedo = [{albedo}, {albedo}, {albedo}]
[[object]]
sphere = {{ center = [0, 0, 0], radius = 1 }}
material = "grey"
"""
        )

    # A lambertian sphere under a white sky of radiance 1, one bounce: it shows its albedo.
    dim, bright = (
        rtgpu.render(scene(a), spp=256, size=(16, 16), backend="cpu", max_depth=2).image
        for a in (0.25, 0.5)
    )
    centre = (slice(6, 10), slice(6, 10))
    assert abs(dim[centre].mean() - 0.25) < 0.01 and abs(bright[centre].mean() - 0.5) < 0.02
    assert np.allclose(bright[0, 0], 1.0)  # the sky


def test_errors_are_value_errors_with_the_one_line_message(tmp_path):
    with pytest.raises(ValueError, match="neither a built-in scene"):
        rtgpu.load("no-such-scene")
    with pytest.raises(ValueError, match="<string>:"):
        rtgpu.load_string("[camera]\nlook_from = [0, 0")
    with pytest.raises(ValueError, match="backend"):
        rtgpu.render(rtgpu.load("cornell"), spp=1, size=(8, 8), backend="tpu")
    with pytest.raises(ValueError, match="format"):
        rtgpu.render(rtgpu.load("cornell"), spp=1, size=(8, 8), backend="cpu").write(
            str(tmp_path / "x.jpg2")
        )


def test_ctrl_c_stops_a_render_with_keyboard_interrupt():
    # Far more samples than the test waits for; Ctrl-C (SIGINT's handler) a second in. Python's
    # own handler, even where the tests were started with SIGINT ignored (a background job of a
    # shell without job control), where interrupt_main would do nothing and the render run on.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Timer(1.0, _thread.interrupt_main).start()
        with pytest.raises(KeyboardInterrupt):
            rtgpu.render(rtgpu.load("cornell"), spp=1_000_000, size=(64, 64), backend="cpu")
    finally:
        signal.signal(signal.SIGINT, previous)


def test_two_renders_in_threads_give_each_its_own_image():
    scene = rtgpu.load("cornell")
    results = {}

    def run(seed):
        results[seed] = rtgpu.render(scene, spp=8, size=(32, 32), seed=seed, backend="cpu").image

    threads = [threading.Thread(target=run, args=(seed,)) for seed in (1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    alone = rtgpu.render(scene, spp=8, size=(32, 32), seed=1, backend="cpu").image
    assert np.array_equal(results[1], alone)
    assert not np.array_equal(results[1], results[2])


def test_a_brighter_light_set_from_python_doubles_the_image_exactly():
    scene = rtgpu.load("cornell")
    light = scene.material("light")
    assert light["type"] == "light" and light["radiance"] == [15, 15, 15]
    before = rtgpu.render(scene, spp=4, size=(24, 24), backend="cpu").image
    scene.set_material("light", radiance=[30, 30, 30])
    after = rtgpu.render(scene, spp=4, size=(24, 24), backend="cpu").image
    # Every sample is the light's radiance times a path's throughput: doubling is exact.
    assert np.array_equal(after, 2 * before)
    with pytest.raises(ValueError, match="albedo"):
        scene.set_material("white", albedo=[2, 0, 0])
    with pytest.raises(ValueError, match="no material"):
        scene.set_material("chrome", albedo=[1, 1, 1])


def test_the_camera_reads_and_moves():
    scene = rtgpu.load("cornell")
    camera = scene.camera
    assert camera["look_at"] == [278, 278, 0] and camera["aperture"] == 0
    wide = rtgpu.render(scene, spp=2, size=(16, 16), backend="cpu").image
    scene.camera = {"vfov": 20}
    assert scene.camera["vfov"] == 20 and scene.camera["look_at"] == [278, 278, 0]
    narrow = rtgpu.render(scene, spp=2, size=(16, 16), backend="cpu").image
    assert not np.array_equal(wide, narrow)
    with pytest.raises(ValueError, match="vfov"):
        scene.camera = {"vfov": 200}


def test_an_array_is_written_as_the_command_line_writes_a_render(tmp_path):
    r = rtgpu.render(rtgpu.load("cornell"), spp=4, size=(20, 10), backend="cpu")
    for name in ("r.png", "r.pfm"):
        r.write(str(tmp_path / name))
        rtgpu.write(str(tmp_path / ("a" + name)), r.image.astype(np.float64))
        assert (tmp_path / name).read_bytes() == (tmp_path / ("a" + name)).read_bytes(), name
    with pytest.raises(ValueError, match="finite and >= 0"):
        rtgpu.write(str(tmp_path / "bad.png"), np.full((2, 2, 3), np.nan))
    with pytest.raises(ValueError, match="height, width, 3"):
        rtgpu.write(str(tmp_path / "bad.png"), np.zeros((2, 2, 4)))


def test_progress_is_reported_up_to_the_whole_render():
    seen = []
    rtgpu.render(
        rtgpu.load("cornell"), spp=4, size=(16, 16), backend="cpu", progress=seen.append
    )
    assert seen and seen == sorted(seen) and seen[-1] == 1.0


def test_the_command_lines_limits_and_defaults(tmp_path):
    scene = rtgpu.load("cornell")
    # A time alone is no longer 64 spp: the samples are unlimited, as with --time.
    seen = []
    r = rtgpu.render(scene, size=(8, 8), backend="cpu", time=1.0, progress=seen.append)
    assert r.spp > 64 and 0 < seen[-1] <= 1
    for bad in (dict(spp=0), dict(time=-1), dict(target_error=float("nan")), dict(max_depth=0)):
        with pytest.raises(ValueError):
            rtgpu.render(scene, size=(8, 8), backend="cpu", **bad)
    with pytest.raises(ValueError, match="height, width, 3"):
        rtgpu.write(str(tmp_path / "flat.png"), np.zeros((4, 4)))


def test_what_a_scene_reads_is_never_written_over(tmp_path):
    shutil.copy(ROOT / "scenes" / "textured.toml", tmp_path)
    shutil.copytree(ROOT / "scenes" / "textures", tmp_path / "textures")
    scene = rtgpu.load(str(tmp_path / "textured.toml"))
    r = rtgpu.render(scene, spp=1, size=(8, 8), backend="cpu")
    before = (tmp_path / "textures" / "tiles.png").read_bytes()
    with pytest.raises(ValueError):
        r.write(str(tmp_path / "textures" / "tiles.png"))
    assert (tmp_path / "textures" / "tiles.png").read_bytes() == before


def test_a_material_a_mesh_file_made_is_not_edited_through_a_table():
    scene = rtgpu.load(str(ROOT / "scenes" / "blender" / "bumpy.glb"))
    with pytest.raises(ValueError, match="mesh file"):
        scene.set_material(scene.materials[0], roughness=0.5)


LAMP_LIT = """
[camera]
look_from = [0, 0, 4]
look_at = [0, 0, 0]
vfov = 30
[render]
background = [0, 0, 0]
[materials.grey]
type = "lambertian"
albedo = [0.5, 0.5, 0.5]
[[object]]
sphere = { center = [0, 0, 0], radius = 1 }
material = "grey"
[[light]]
point = { position = [2, 2, 3], intensity = [10, 10, 10] }
"""


def test_punctual_lights_read_and_set_from_python():
    scene = rtgpu.load_string(LAMP_LIT)
    assert scene.lights == [{"point": {"position": [2, 2, 3], "intensity": [10, 10, 10]}}]
    before = rtgpu.render(scene, spp=4, size=(16, 16), backend="cpu").image
    assert before.max() > 0
    scene.set_light(0, intensity=[20, 20, 20])
    # Every sample is the lamp's intensity times a path's throughput: doubling is exact.
    assert np.array_equal(rtgpu.render(scene, spp=4, size=(16, 16), backend="cpu").image, 2 * before)
    # The list round-trips; an empty one leaves the sphere unlit.
    scene.lights = [{"point": {"position": [2, 2, 3], "intensity": [10, 10, 10]}}]
    assert np.array_equal(rtgpu.render(scene, spp=4, size=(16, 16), backend="cpu").image, before)
    scene.lights = []
    assert rtgpu.render(scene, spp=4, size=(16, 16), backend="cpu").image.max() == 0
    scene.lights = [{"directional": {"direction": [0, 0, -1], "irradiance": [1, 1, 1]}}]
    assert scene.lights[0]["directional"]["irradiance"] == [1, 1, 1]
    with pytest.raises(ValueError, match="intensity"):
        rtgpu.load_string(LAMP_LIT).set_light(0, intensity=[-1, 0, 0])
    with pytest.raises(ValueError, match="no light 3"):
        scene.set_light(3, irradiance=[2, 2, 2])
    with pytest.raises(ValueError, match="light 0"):
        scene.lights = [{"point": {"position": [0, 0, 0]}}]


def test_load_takes_overrides():
    scene = rtgpu.load(
        "cornell",
        size=(20, 10),
        max_depth=3,
        camera={"vfov": 20},
        materials={"light": {"radiance": [30, 30, 30]}},
    )
    assert scene.size == (20, 10) and scene.max_depth == 3 and scene.camera["vfov"] == 20
    assert scene.material("light")["radiance"] == [30, 30, 30]
    assert rtgpu.render(scene, spp=1, backend="cpu").image.shape == (10, 20, 3)
    # The same as setting each afterwards.
    plain = rtgpu.load("cornell")
    plain.size, plain.max_depth, plain.camera = (20, 10), 3, {"vfov": 20}
    plain.set_material("light", radiance=[30, 30, 30])
    assert np.array_equal(
        rtgpu.render(plain, spp=2, backend="cpu").image,
        rtgpu.render(scene, spp=2, backend="cpu").image,
    )
    with pytest.raises(ValueError, match="no override \"spp\""):
        rtgpu.load("cornell", spp=4)
    with pytest.raises(ValueError, match="image sides must be in"):
        rtgpu.load("cornell", size=(0, 10))
    with pytest.raises(ValueError, match="image sides must be in"):
        rtgpu.load("cornell", size=(40000, 8))
    with pytest.raises(ValueError, match="max_depth must be in"):
        rtgpu.load("cornell", max_depth=10**9)


@pytest.mark.parametrize("example", ["roughness_sweep.py", "compare_backends.py"])
def test_the_examples_run_as_they_are(tmp_path, example):
    """examples/python/ as a user runs them (in a scratch directory: they write their plots
    there); CI installs matplotlib beside the package."""
    if example == "roughness_sweep.py":
        pytest.importorskip("matplotlib")
    if example == "compare_backends.py" and not has_gpu():
        pytest.skip("no GPU adapter")
    run = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "python" / example)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    if example == "roughness_sweep.py":
        assert (tmp_path / "roughness_sweep.png").stat().st_size > 10_000
    else:
        assert "RMS difference" in run.stdout, run.stdout
