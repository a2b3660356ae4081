#!/usr/bin/env python3
"""rt-gpu against Mitsuba 3 on the same scene, measured in one run.

Builds the scene of an rt-gpu scene file (quads, boxes rotated about y, spheres; lambertian,
dielectric and light materials) for Mitsuba 3 (variant llvm_ad_rgb, `path` integrator with NEE and
MIS, box pixel filter, independent sampler, the same max depth), renders it there at SPP samples
per pixel, and finds how long rt-gpu needs to reach the same error.

Error is estimated the same way for both renderers, without a reference: two renders of n/2 spp
with different seeds, A and B, give the n-spp image (A + B) / 2 and its RMSE as
sqrt(mean((A - B)^2)) / 2 (the difference of independent unbiased estimates has twice their
variance, and averaging halves it twice). rt-gpu then climbs a ladder of spp on its backend until
its error is at or below Mitsuba's; its time there (interpolated in log-log between rungs) is
compared with Mitsuba's.

Also printed, as a check that the scenes agree: the mean radiance of both images, and the RMSE of
their difference against what noise alone would give.

Usage (from the repository root, after `cargo build --release`):
    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy
    /tmp/mi/bin/python benches/mitsuba/compare.py scenes/cornell.toml --spp 1024

Dr.Jit's LLVM backend needs a newer libLLVM than Debian 12's default 15 (with it, rendering aborts
with "LLVM ERROR: Cannot select ... fminimum"): `apt-get install libllvm19` and set
DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1.
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
import tomllib

import numpy as np


def rotate_y(p, degrees):
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    x, y, z = p
    return np.array([c * x + s * z, y, -s * x + c * z])


def box_faces(lo, hi):
    """As src/scene/flat.rs: (corner, u, v), u x v outward."""
    d = hi - lo
    dx, dy, dz = np.array([d[0], 0, 0]), np.array([0, d[1], 0]), np.array([0, 0, d[2]])
    return [
        (np.array([lo[0], lo[1], hi[2]]), dx, dy),
        (np.array([hi[0], lo[1], hi[2]]), -dz, dy),
        (np.array([hi[0], lo[1], lo[2]]), -dx, dy),
        (np.array([lo[0], lo[1], lo[2]]), dz, dy),
        (np.array([lo[0], hi[1], hi[2]]), dx, -dz),
        (np.array([lo[0], lo[1], lo[2]]), dx, dz),
    ]


def mitsuba_scene(path, width, height, max_depth):
    import mitsuba as mi

    scene = tomllib.load(open(path, "rb"))
    render = scene.get("render", {})
    width = width or render.get("width", 512)
    height = height or render.get("height", 512)
    max_depth = max_depth or render.get("max_depth", 10)
    background = render.get("background", [0, 0, 0])
    if background != [0, 0, 0]:
        sys.exit("only black backgrounds are translated")
    cam = scene["camera"]
    if cam.get("aperture", 0) != 0:
        sys.exit("only pinhole cameras are translated")

    bsdfs, emitters = {}, {}
    for name, m in scene["materials"].items():
        kind = m["type"]
        if kind == "lambertian":
            if any(m.get("emission", [0, 0, 0])):
                sys.exit("emissive lambertian materials are not translated")
            # rt-gpu's lambertian reflects on both faces.
            bsdfs[name] = {
                "type": "twosided",
                "inner": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["albedo"]}},
            }
        elif kind == "dielectric":
            bsdfs[name] = {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
        elif kind == "light":
            if m.get("two_sided", False):
                sys.exit("two-sided lights are not translated")
            # A black, one-sided area light: Mitsuba's area emitters face the shape's normal.
            bsdfs[name] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}}
            emitters[name] = {"type": "area", "radiance": {"type": "rgb", "value": m["radiance"]}}
        else:
            sys.exit(f"material type {kind} is not translated")

    shapes = {}

    def add_quad(q, u, v, material):
        # Mitsuba's rectangle is [-1, 1]^2 in z = 0 with normal +z: map it onto q + a u + b v.
        n = np.cross(u, v)
        n = n / np.linalg.norm(n)
        m = np.identity(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = u / 2, v / 2, n, q + (u + v) / 2
        shape = {"type": "rectangle", "to_world": mi.ScalarTransform4f(m.tolist()), "bsdf": bsdfs[material]}
        if material in emitters:
            shape["emitter"] = emitters[material]
        shapes[f"shape{len(shapes)}"] = shape

    for obj in scene["object"]:
        angle = obj.get("rotate_y", 0.0)
        t = np.array(obj.get("translate", [0, 0, 0]), dtype=float)
        material = obj["material"]
        if "quad" in obj:
            q = obj["quad"]
            add_quad(rotate_y(q["q"], angle) + t, rotate_y(q["u"], angle), rotate_y(q["v"], angle), material)
        elif "box" in obj:
            b = obj["box"]
            for q, u, v in box_faces(np.array(b["min"], float), np.array(b["max"], float)):
                add_quad(rotate_y(q, angle) + t, rotate_y(u, angle), rotate_y(v, angle), material)
        elif "sphere" in obj:
            s = obj["sphere"]
            if s["radius"] <= 0:
                sys.exit("hollow spheres are not translated")
            shape = {
                "type": "sphere",
                "center": (rotate_y(s["center"], angle) + t).tolist(),
                "radius": s["radius"],
                "bsdf": bsdfs[material],
            }
            if material in emitters:
                shape["emitter"] = emitters[material]
            shapes[f"shape{len(shapes)}"] = shape

    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": {
            "type": "perspective",
            "fov": cam["vfov"],
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=cam["look_from"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])
            ),
            "sampler": {"type": "independent", "sample_count": 1},
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
        **shapes,
    }, width, height, max_depth


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return np.flipud(data.reshape(h, w, 3)).astype(np.float64)


def split_rmse(a, b):
    return math.sqrt(np.mean((a - b) ** 2)) / 2


def rt_gpu_pair(binary, scene, spp, args, out):
    """Two renders of spp/2 with seeds 1 and 2; (seconds for both, image, rmse)."""
    images, seconds = [], 0.0
    for seed in (1, 2):
        path = os.path.join(out, f"rt-{spp}-{seed}.pfm")
        cmd = [binary, scene, "--spp", str(spp // 2), "--seed", str(seed), "--backend", args.backend,
               "--size", f"{args.width}x{args.height}", "--max-depth", str(args.max_depth), "-o", path]
        start = time.perf_counter()
        subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
        seconds += time.perf_counter() - start
        images.append(read_pfm(path))
    return seconds, (images[0] + images[1]) / 2, split_rmse(*images)


def render_mitsuba(args):
    """Two renders of spp/2 with seeds 1 and 2, timed, saved to args.mitsuba_only."""
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    desc, width, height, max_depth = mitsuba_scene(args.scene, args.width, args.height, args.max_depth)
    scene = mi.load_dict(desc)
    # Warm-up: Mitsuba compiles its kernels on the first render.
    np.array(mi.render(scene, spp=1, seed=99))
    halves, seconds = [], 0.0
    for seed in (1, 2):
        start = time.perf_counter()
        img = mi.render(scene, spp=args.spp // 2, seed=seed)
        halves.append(np.array(img, dtype=np.float64))  # forces evaluation
        seconds += time.perf_counter() - start
    np.savez(args.mitsuba_only, a=halves[0], b=halves[1], seconds=seconds, width=width, height=height,
             max_depth=max_depth, version=mi.__version__)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene")
    parser.add_argument("--spp", type=int, default=1024, help="Mitsuba's samples per pixel")
    parser.add_argument("--width", type=int)
    parser.add_argument("--height", type=int)
    parser.add_argument("--max-depth", type=int)
    parser.add_argument("--backend", default="gpu", help="rt-gpu backend")
    parser.add_argument("--binary", default="target/release/rt-gpu")
    parser.add_argument("--mitsuba-only", metavar="NPZ", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.mitsuba_only:
        render_mitsuba(args)
        return

    with tempfile.TemporaryDirectory() as out:
        # Mitsuba renders in a process of its own, which has exited before rt-gpu starts: Dr.Jit's
        # worker threads would otherwise compete with rt-gpu's for the same cores.
        halves_path = os.path.join(out, "mitsuba.npz")
        subprocess.run([sys.executable, __file__, args.scene, "--spp", str(args.spp), "--mitsuba-only", halves_path]
                       + (["--width", str(args.width)] if args.width else [])
                       + (["--height", str(args.height)] if args.height else [])
                       + (["--max-depth", str(args.max_depth)] if args.max_depth else []), check=True)
        data = np.load(halves_path)
        halves, mi_seconds = [data["a"], data["b"]], float(data["seconds"])
        args.width, args.height, args.max_depth = int(data["width"]), int(data["height"]), int(data["max_depth"])
        pixels = args.width * args.height
        mi_image = (halves[0] + halves[1]) / 2
        mi_rmse = split_rmse(*halves)
        print(f"mitsuba {str(data['version'])} llvm_ad_rgb: {args.spp} spp in {mi_seconds:.2f} s "
              f"({pixels * args.spp / mi_seconds / 1e6:.2f} Msamples/s), RMSE {mi_rmse:.4e}", flush=True)
        # Warm-up of rt-gpu's device and page cache.
        rt_gpu_pair(args.binary, args.scene, 2, args, out)
        rungs = []
        spp = 2
        while True:
            seconds, image, rmse = rt_gpu_pair(args.binary, args.scene, spp, args, out)
            rungs.append((spp, seconds, rmse, image))
            print(f"rt-gpu {args.backend}: {spp:6d} spp in {seconds:8.2f} s "
                  f"({pixels * spp / seconds / 1e6:.2f} Msamples/s), RMSE {rmse:.4e}")
            if rmse <= mi_rmse or spp >= 1 << 20:
                break
            spp *= 2
    (s0, t0, e0, _), (s1, t1, e1, rt_image) = rungs[-2] if len(rungs) > 1 else rungs[-1], rungs[-1]
    # RMSE ~ t^-1/2 between the last two rungs: interpolate the time to Mitsuba's error in log-log.
    if len(rungs) > 1 and e1 < e0:
        k = math.log(e1 / e0) / math.log(t1 / t0)
        t_match = t0 * (mi_rmse / e0) ** (1 / k)
    else:
        t_match = t1
    print(f"time to Mitsuba's error at {args.spp} spp: rt-gpu {t_match:.2f} s, mitsuba {mi_seconds:.2f} s: "
          f"rt-gpu is {mi_seconds / t_match:.2f}x {'faster' if t_match < mi_seconds else 'as fast'}")

    # Do the two renderers compute the same image?
    diff = math.sqrt(np.mean((mi_image - rt_image) ** 2))
    noise = math.sqrt(mi_rmse**2 + e1**2)
    print(f"mean radiance: mitsuba {mi_image.mean(axis=(0, 1)).round(5)}, rt-gpu {rt_image.mean(axis=(0, 1)).round(5)}; "
          f"RMSE between the images {diff:.4e} against {noise:.4e} from noise alone")


if __name__ == "__main__":
    main()
