#!/usr/bin/env python3
"""rt-gpu against Mitsuba 3 on the same scene, measured in one run.

Builds the scene of an rt-gpu scene file (quads, boxes rotated about y, spheres, OBJ meshes; lambertian,
dielectric (`dielectric`, or `roughdielectric`), mirror metal (fuzz 0: a `conductor` of material
`none`), conductor (`conductor`, or `roughconductor`), plastic (`plastic` or `roughplastic`, with
`nonlinear`), all rough ones GGX with visible-normal sampling, and light materials;
homogeneous media: a `medium` material becomes a `null` BSDF with a `homogeneous` interior
medium and an `hg` phase function, a dielectric's `medium` its interior; image textures as
`bitmap`s (bilinear, repeating), `uv_checker` as `checkerboard`, with shapes' UV frames arranged
to agree; an environment background as an `envmap` whose frame is arranged to agree, a colour
as a `constant` emitter) for Mitsuba 3 (variant llvm_ad_rgb, `path` integrator with NEE and MIS, or `volpath`
for scenes with media, both with Russian roulette from depth 5 as rt-gpu's default; box pixel
filter, the same max depth, sampler `--mitsuba-sampler`, default multijitter, its best here),
renders it there at SPP samples per pixel, and finds how long rt-gpu, with its default settings,
needs to reach the same error.

Errors: both renderers' images are compared with one high-spp reference (`--reference`, or one
rt-gpu renders with `--reference-spp` and caches), RMSE and relMSE (mean of d^2 / (ref^2 + 0.01)).
The reference's own noise (rt-gpu's estimate from its independent randomisations) is removed in
quadrature, and must be at most a third of every error compared. (Splitting a render into two
halves and differencing them, as this script did before, penalises stratified samplers: a half
has more than twice the variance of the whole.) Both renderers draw with seed `--seed`; one
image's error varies from seed to seed by several percent where caustics and edges dominate it
(docs/benchmarks.md), so `--all` runs each row with seeds 1 and 2.

Timing: Mitsuba in a process of its own, warm (its kernels compiled by a first 1-spp render),
one render of SPP; rt-gpu as whole processes (device start and kernel compilation included), one
per rung of a ladder of spp, until its error is at or below Mitsuba's; the time to Mitsuba's error
is interpolated in log-log between the last two rungs. That ratio (rt-gpu's start and scene load
counted, Mitsuba's not) is the one the table's goal is set in. Two like-for-like ratios are
printed beside it: both as whole processes (Mitsuba's: its process's wall time less the 1-spp
warm-up render, so Python's start, the import, the scene's load and the render, without the
kernels' first compilation: a lower bound) and both renders alone (rt-gpu's render time from its summary line, Mitsuba's warm
render).

Usage (from the repository root, after `cargo build --release`):
    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy
    /tmp/mi/bin/python benches/mitsuba/compare.py scenes/cornell.toml --spp 1024
    /tmp/mi/bin/python benches/mitsuba/compare.py --all

`--all` measures every scene class of ALL_ROWS (below) twice, one run after the other, with
rt-gpu's default backend (`auto`), and writes the table, dated, with the command and the CPU
model, at the top of docs/benchmarks.md.

Dr.Jit's LLVM backend needs a newer libLLVM than Debian 12's default 15 (with it, rendering aborts
with "LLVM ERROR: Cannot select ... fminimum"): `apt-get install libllvm19` and set
DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1.
"""

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time
import tomllib

import numpy as np


# rt-gpu's measured metals that Mitsuba ships as conductor presets (the table in
# src/material/conductor.rs is Mitsuba's reduction of the same spectra); the others are passed
# as rt-gpu's RGB eta and k.
MITSUBA_METALS = {"Ag": "Ag", "Al": "Al", "Au": "Au", "Cr": "Cr", "Cu": "Cu", "Ni": "Ni_palik"}


def rt_gpu_metals():
    """rt-gpu's METALS table: name -> (eta, k)."""
    source = open(os.path.join(os.path.dirname(__file__), "../../src/material/conductor.rs")).read()
    number = r"\s*([-0-9.e]+)\s*"
    triple = r"\[" + ",".join([number] * 3) + r"\]"
    out = {}
    for found in re.finditer(r'\("(\w+)",\s*' + triple + r",\s*" + triple + r"\)", source):
        values = [float(v) for v in found.groups()[1:]]
        out[found.group(1)] = (values[:3], values[3:])
    return out


def rotate_y(p, degrees):
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    x, y, z = p
    return np.array([c * x + s * z, y, -s * x + c * z])


def rotation_y(degrees):
    """rt-gpu's rotation about +y as a 4x4 matrix: x' = cos x + sin z, z' = -sin x + cos z."""
    a = math.radians(degrees)
    return np.array([[math.cos(a), 0, math.sin(a), 0], [0, 1, 0, 0], [-math.sin(a), 0, math.cos(a), 0],
                     [0, 0, 0, 1]], float)


def sky_bitmap(rows=1025, cols=8):
    """rt-gpu's `sky` background (src/cpu/background.rs: t = (y + 1) / 2 between white and the
    zenith colour) as an envmap bitmap, its rows at theta = j pi / (rows - 1) from +y (Mitsuba's
    rows, see corner_aligned). The sky is linear in cos(theta); Mitsuba's linear interpolation in
    theta between 1025 rows stays within 2e-6 of it."""
    import mitsuba as mi

    zenith = np.array([0.5, 0.7, 1.0], np.float32)  # SKY_ZENITH, src/shared/constants.rs
    t = 0.5 * (np.cos(np.arange(rows) * np.pi / (rows - 1)) + 1.0)
    row = (1.0 - t)[:, None] + t[:, None] * zenith
    return mi.Bitmap(np.ascontiguousarray(np.repeat(row[:, None, :], cols, axis=1), dtype=np.float32))


def corner_aligned(path):
    """The environment image at `path` for Mitsuba 3.9's envmap, which puts row j at
    theta = j pi / (H - 1) (rows aligned with the poles), where rt-gpu puts it at (j + 1/2) pi / H
    (texel centres) and clamps over the poles: 2H + 1 rows sampling rt-gpu's bilinear lookup at
    its texel centres and halfway between (the top and bottom at the poles), between which it is
    linear, so Mitsuba's linear interpolation gives the same values."""
    import mitsuba as mi

    bitmap = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
    rows = np.array(bitmap, dtype=np.float32)
    h = rows.shape[0]
    out = np.empty((2 * h + 1,) + rows.shape[1:], np.float32)
    out[1::2] = rows
    out[0], out[-1] = rows[0], rows[-1]
    out[2:-1:2] = 0.5 * (rows[:-1] + rows[1:])
    return mi.Bitmap(out)


def transform3(m):
    """A 3x3 matrix as a Mitsuba texture-coordinate transform."""
    import mitsuba as mi

    kind = getattr(mi, "ScalarTransform3f", None) or getattr(mi, "ScalarAffineTransform3f")
    return kind(m.tolist())


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


def mitsuba_scene(path, width, height, max_depth, sampler, roulette_depth=5):
    import mitsuba as mi

    scene = tomllib.load(open(path, "rb"))
    render = scene.get("render", {})
    width = width or render.get("width", 512)
    height = height or render.get("height", 512)
    max_depth = max_depth or render.get("max_depth", 10)
    background = render.get("background", [0, 0, 0])
    base = os.path.dirname(os.path.abspath(path))
    environment = {}
    if isinstance(background, dict):
        # rt-gpu's column s = (atan2(-z, x) + pi) / 2 pi of the direction turned by -rotate_y;
        # Mitsuba's u = atan2(x', -z') / 2 pi of its local direction: they agree where
        # (x', y', z') = (z, y, x) (a reflection), so to_world = rotate_y . swap(x, z). Rows agree.
        swap = np.array([[0, 0, 1, 0], [0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1]], float)
        environment["environment"] = {
            "type": "envmap",
            "bitmap": corner_aligned(os.path.join(base, background["image"])),
            "scale": background.get("strength", 1.0),
            "to_world": mi.ScalarTransform4f((rotation_y(background.get("rotate_y", 0.0)) @ swap).tolist()),
        }
    elif background == "sky":
        environment["environment"] = {"type": "envmap", "bitmap": sky_bitmap()}
    elif background != [0, 0, 0]:
        environment["environment"] = {"type": "constant", "radiance": {"type": "rgb", "value": background}}
    cam = scene["camera"]
    # rt-gpu's depth of field is a thin lens of diameter `aperture` focused on the plane at
    # `focus_distance` along the view (default: at look_at), as Mitsuba's `thinlens`.
    lens = {}
    if cam.get("aperture", 0) != 0:
        distance = math.dist(cam["look_from"], cam["look_at"])
        lens = {"type": "thinlens", "aperture_radius": cam["aperture"] / 2,
                "focus_distance": cam.get("focus_distance", distance)}

    bsdfs, emitters, interiors = {}, {}, {}

    def homogeneous(medium):
        return {
            "type": "homogeneous",
            "sigma_t": medium["density"],
            "albedo": {"type": "rgb", "value": medium["albedo"]},
            "phase": {"type": "hg", "g": medium.get("g", 0.0)},
        }

    textured = set()

    def texture(name, value):
        """A colour or texture. UVs are arranged (see add_quad and the spheres) so that Mitsuba's
        v is rt-gpu's 1 - v: Mitsuba's bitmaps put v = 0 at the top row, rt-gpu's at the bottom."""
        if isinstance(value, list):
            return {"type": "rgb", "value": value}
        textured.add(name)
        if "image" in value:
            return {"type": "bitmap", "filename": os.path.join(base, value["image"]),
                    "filter_type": "bilinear", "wrap_mode": "repeat"}
        if "uv_checker" in value:
            c = value["uv_checker"]
            k = c["scale"]
            # Mitsuba's checkerboard has color0 where frac(u) and frac(v) are both below or both
            # above 1/2: rt-gpu's even cells, at u, v scaled by k / 2 (and v turned back).
            to_uv = np.array([[k / 2, 0, 0], [0, -k / 2, k / 2], [0, 0, 1]], float)
            return {"type": "checkerboard", "color0": {"type": "rgb", "value": c["even"]},
                    "color1": {"type": "rgb", "value": c["odd"]}, "to_uv": transform3(to_uv)}
        sys.exit(f"material {name}: only colours, images and uv_checker textures are translated")

    for name, m in scene["materials"].items():
        kind = m["type"]
        if kind == "lambertian":
            if any(m.get("emission", [0, 0, 0])):
                sys.exit("emissive lambertian materials are not translated")
            # rt-gpu's lambertian reflects on both faces.
            bsdfs[name] = {
                "type": "twosided",
                "inner": {"type": "diffuse", "reflectance": texture(name, m["albedo"])},
            }
        elif kind == "metal":
            if m.get("fuzz", 0) != 0:
                sys.exit("fuzzy metal is not translated")
            # rt-gpu's metal is a mirror reflecting its albedo, no Fresnel.
            bsdfs[name] = {"type": "conductor", "material": "none",
                           "specular_reflectance": texture(name, m["albedo"])}
        elif kind == "conductor":
            if "metal" in m and m["metal"] in MITSUBA_METALS:
                index = {"material": MITSUBA_METALS[m["metal"]]}
            else:
                eta, k = (m["eta"], m["k"]) if "eta" in m else rt_gpu_metals()[m["metal"]]
                index = {"eta": {"type": "rgb", "value": eta}, "k": {"type": "rgb", "value": k}}
            roughness = m.get("roughness", 0.0)
            if roughness == 0:
                inner = {"type": "conductor", **index}
            else:
                # Mitsuba's GGX uses the separable Smith G1(wo) G1(wi), rt-gpu the
                # height-correlated form: very rough metals come out a little darker there.
                inner = {"type": "roughconductor", "distribution": "ggx", "alpha": roughness ** 2,
                         "sample_visible": True, **index}
            # rt-gpu's conductors reflect on both faces.
            bsdfs[name] = {"type": "twosided", "inner": inner}
        elif kind == "dielectric":
            roughness = m.get("roughness", 0.0)
            if roughness == 0:
                bsdfs[name] = {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
            else:
                # Mitsuba's separable masking again; its radiance is scaled by eta^2 where it
                # refracts, rt-gpu's not, which cancels on paths through closed objects.
                bsdfs[name] = {"type": "roughdielectric", "distribution": "ggx",
                               "alpha": roughness ** 2, "sample_visible": True,
                               "int_ior": m["ior"], "ext_ior": 1.0}
            if "medium" in m:
                interiors[name] = homogeneous(m["medium"])
        elif kind == "plastic":
            # Mitsuba's plastic with `nonlinear` is rt-gpu's closed form; its rough one takes the
            # base's Fresnel terms from the rough coat's tabulated transmittance, rt-gpu from
            # the smooth coat's, and its masking is the separable form.
            coat = {"diffuse_reflectance": texture(name, m["albedo"]), "int_ior": m.get("ior", 1.5),
                    "ext_ior": 1.0, "nonlinear": True}
            roughness = m.get("roughness", 0.0)
            if roughness == 0:
                inner = {"type": "plastic", **coat}
            else:
                inner = {"type": "roughplastic", "distribution": "ggx", "alpha": roughness ** 2,
                         "sample_visible": True, **coat}
            bsdfs[name] = {"type": "twosided", "inner": inner}
        elif kind == "pbr":
            sys.exit("pbr has no exact Mitsuba twin: compare a scene without it "
                     "(of scenes/materials.toml, its back row of pbr-* spheres)")
        elif kind == "medium":
            bsdfs[name] = {"type": "null"}
            interiors[name] = homogeneous(m)
        elif kind == "light":
            if m.get("two_sided", False):
                sys.exit("two-sided lights are not translated")
            # A black, one-sided area light: Mitsuba's area emitters face the shape's normal.
            if not isinstance(m["radiance"], list):
                sys.exit("textured lights are not translated")
            bsdfs[name] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}}
            radiance = [c * m.get("strength", 1.0) for c in m["radiance"]]
            emitters[name] = {"type": "area", "radiance": {"type": "rgb", "value": radiance}}
        else:
            sys.exit(f"material type {kind} is not translated")

    shapes = {}

    def add_quad(q, u, v, material):
        # Mitsuba's rectangle is [-1, 1]^2 in z = 0 with normal +z: map it onto q + a u + b v.
        n = np.cross(u, v)
        n = n / np.linalg.norm(n)
        m = np.identity(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = u / 2, v / 2, n, q + (u + v) / 2
        if material in textured:
            m[:3, 1] = -v / 2  # Mitsuba's v runs along -v: its v is rt-gpu's 1 - v
        shape = {"type": "rectangle", "to_world": mi.ScalarTransform4f(m.tolist()), "bsdf": bsdfs[material]}
        if material in emitters:
            shape["emitter"] = emitters[material]
        if material in interiors:
            shape["interior"] = interiors[material]
        shapes[f"shape{len(shapes)}"] = shape

    for obj in scene["object"]:
        angle = obj.get("rotate_y", 0.0)
        t = np.array(obj.get("translate", [0, 0, 0]), dtype=float)
        material = obj.get("material")
        if "quad" in obj:
            q = obj["quad"]
            add_quad(rotate_y(q["q"], angle) + t, rotate_y(q["u"], angle), rotate_y(q["v"], angle), material)
        elif "box" in obj:
            b = obj["box"]
            for q, u, v in box_faces(np.array(b["min"], float), np.array(b["max"], float)):
                add_quad(rotate_y(q, angle) + t, rotate_y(u, angle), rotate_y(v, angle), material)
        elif "mesh" in obj:
            mesh = obj["mesh"]
            if not mesh["file"].lower().endswith(".obj") or "node" in mesh:
                sys.exit("only OBJ meshes are translated (Mitsuba reads OBJ and PLY, not glTF)")
            if material is None:
                sys.exit("a mesh object needs a material to be translated")
            scale = obj.get("scale", 1.0)
            scale = [scale] * 3 if not isinstance(scale, list) else scale
            place = rotation_y(angle) @ np.diag(list(scale) + [1.0])
            place[:3, 3] = t
            # rt-gpu shades with the file's vertex normals and flat without them; Mitsuba would
            # make up smooth normals for a file without any, so it is told not to.
            filename = os.path.join(base, mesh["file"])
            with open(filename) as f:
                has_normals = any(line.startswith("vn ") for line in f)
            shape = {"type": "obj", "filename": filename, "face_normals": not has_normals,
                     "to_world": mi.ScalarTransform4f(place.tolist()), "bsdf": bsdfs[material]}
            if material in emitters:
                shape["emitter"] = emitters[material]
            shapes[f"shape{len(shapes)}"] = shape
        elif "sphere" in obj:
            s = obj["sphere"]
            if s["radius"] <= 0:
                sys.exit("hollow spheres are not translated")
            # Mitsuba's sphere UV: u = atan2(y', x') / 2 pi, v = acos(z') / pi of its local
            # (x', y', z'); rt-gpu's: u = (atan2(-z, x) + pi) / 2 pi, v = acos(-y) / pi. With
            # (x', y', z') = (-x, z, y) Mitsuba's u is rt-gpu's u and its v rt-gpu's 1 - v.
            frame = np.array([[-1, 0, 0, 0], [0, 0, 1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], float)
            place = np.identity(4)
            place[:3, 3] = rotate_y(s["center"], angle) + t
            size = np.diag([s["radius"]] * 3 + [1.0])
            shape = {
                "type": "sphere",
                "to_world": mi.ScalarTransform4f((place @ frame @ size).tolist()),
                "bsdf": bsdfs[material],
            }
            if material in emitters:
                shape["emitter"] = emitters[material]
            if material in interiors:
                shape["interior"] = interiors[material]
            shapes[f"shape{len(shapes)}"] = shape

    # Media: volpath. Roulette as rt-gpu's (default depth 5, Mitsuba's own default too; off is a
    # depth no path reaches); Mitsuba's max_depth counts segments as rt-gpu's does.
    integrator = {"type": "volpath" if interiors else "path", "max_depth": max_depth,
                  "rr_depth": roulette_depth if roulette_depth > 0 else max_depth + 1}
    return {
        "type": "scene",
        "integrator": integrator,
        "sensor": {
            "type": "perspective",
            **lens,
            "fov": cam["vfov"],
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=cam["look_from"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])
            ),
            "sampler": {"type": sampler, "sample_count": 1},
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
        **shapes,
        **environment,
    }, width, height, max_depth


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return np.flipud(data.reshape(h, w, 3)).astype(np.float64)


def errors(image, reference, noise):
    """(RMSE, relMSE) of image against reference, the reference's noise (its RMSE) removed in
    quadrature: for RMSE exactly; for relMSE with the noise spread as the pixels' weights."""
    d2 = (image - reference) ** 2
    weight = 1.0 / (reference**2 + 0.01)
    rmse = math.sqrt(max(np.mean(d2) - noise**2, 0.0))
    relmse = max(np.mean(d2 * weight) - noise**2 * np.mean(weight), 0.0)
    return rmse, relmse


SUMMARY = re.compile(r"estimated RMSE ([0-9.e+-]+)")
# The render's own seconds, from the summary line ("..., nee, sobol, 3.90 s, 1.07 Msamples/s").
RENDER_SECONDS = re.compile(r", ([0-9.]+) s(?:,| \()")
# The backend that ran, from the summary line ("..., 16 spp, cpu [cpu (2 threads)] (auto: ...)").
BACKEND = re.compile(r" spp, (\w+) \[")


def rt_gpu(binary, scene, spp, args, path, extra=()):
    """One render as a whole process: (seconds, image, its own RMSE estimate, the backend that
    ran, the render's own seconds from its summary)."""
    cmd = [binary, scene, "--spp", str(spp), "--seed", str(args.seed), "--backend", args.backend,
           "--size", f"{args.width}x{args.height}", "--max-depth", str(args.max_depth),
           "--roulette-depth", str(args.roulette_depth), "-o", path, *extra]
    start = time.perf_counter()
    done = subprocess.run(cmd, check=True, stderr=subprocess.PIPE, text=True)
    seconds = time.perf_counter() - start
    estimate = SUMMARY.search(done.stderr)
    backend = BACKEND.search(done.stderr)
    render = RENDER_SECONDS.search(done.stderr)
    return (seconds, read_pfm(path), float(estimate.group(1)) if estimate else None,
            backend.group(1) if backend else args.backend, float(render.group(1)) if render else seconds)


def reference(args, cache):
    """The reference image and its noise (RMSE)."""
    if args.reference:
        if args.reference_noise is None:
            sys.exit("--reference needs --reference-noise (its RMSE)")
        return read_pfm(args.reference), args.reference_noise
    key = f"{os.path.basename(args.scene)}-{args.width}x{args.height}-d{args.max_depth}-{args.reference_spp}"
    path = os.path.join(cache, f"reference-{key}.pfm")
    noise_path = path + ".noise"
    if os.path.exists(path) and os.path.exists(noise_path):
        return read_pfm(path), float(open(noise_path).read())
    print(f"rendering the reference: {args.reference_spp} spp with rt-gpu's defaults", flush=True)
    _, image, noise, _, _ = rt_gpu(args.binary, args.scene, args.reference_spp, args, path, ["--seed", "77"])
    with open(noise_path, "w") as f:
        f.write(f"{noise}\n")
    return image, noise


def render_mitsuba(args):
    """One render of args.spp, timed warm, saved to args.mitsuba_only."""
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    desc, width, height, max_depth = mitsuba_scene(args.scene, args.width, args.height, args.max_depth,
                                                   args.mitsuba_sampler, args.roulette_depth)
    scene = mi.load_dict(desc)
    # Warm-up: Mitsuba compiles its kernels on the first render.
    start = time.perf_counter()
    np.array(mi.render(scene, spp=1, seed=99))
    warmup_seconds = time.perf_counter() - start
    start = time.perf_counter()
    img = np.array(mi.render(scene, spp=args.spp, seed=args.seed), dtype=np.float64)  # forces evaluation
    seconds = time.perf_counter() - start
    np.savez(args.mitsuba_only, image=img, seconds=seconds, warmup_seconds=warmup_seconds, width=width, height=height,
             max_depth=max_depth, version=mi.__version__)


def run_mitsuba(args, mi_path):
    """Mitsuba's render (render_mitsuba) in a process of its own, saved to mi_path; returns the
    process's wall time."""
    start = time.perf_counter()
    subprocess.run([sys.executable, __file__, args.scene, "--spp", str(args.spp), "--mitsuba-only", mi_path,
                    "--seed", str(args.seed),
                    "--mitsuba-sampler", args.mitsuba_sampler, "--roulette-depth", str(args.roulette_depth)]
                   + (["--width", str(args.width)] if args.width else [])
                   + (["--height", str(args.height)] if args.height else [])
                   + (["--max-depth", str(args.max_depth)] if args.max_depth else []), check=True)
    return time.perf_counter() - start


# Every scene class `--all` measures: (row, scene file, width, height, Mitsuba's spp, reference
# spp: its noise at most a third of Mitsuba's error). Sizes keep a reference under a few minutes
# on two cores; the BVH scenes are smaller.
# Not here: scenes/meshes.toml (its glTF lamp has no translation) and showcase (the original
# project's fuzzed metal has no Mitsuba twin).
ALL_ROWS = [
    ("`cornell` (surfaces, inlined kernel)", "scenes/cornell.toml", 256, 256, 1024, 16384),
    ("`cornell-smoke` lifted (media)", "benches/mitsuba/cornell-smoke-lifted.toml", 256, 256, 1024, 8192),
    ("`scenes/textured.toml` (images, HDR environment)", "scenes/textured.toml", 240, 136, 1024, 16384),
    ("`cornell` + 1 M-triangle knot (BVH)", "benches/mitsuba/cornell-knot.toml", 128, 128, 256, 4096),
]


def run_all(args):
    """Every row of ALL_ROWS twice; the table goes to the top of docs/benchmarks.md."""
    knot = "benches/mitsuba/knot-1m.obj"
    if not os.path.exists(knot):
        subprocess.run([sys.executable, "scripts/generate-meshes.py", "--knot", "1000", "500", knot], check=True)
    cpu = next((line.split(":", 1)[1].strip() for line in subprocess.run(
        ["lscpu"], capture_output=True, text=True).stdout.splitlines() if line.startswith("Model name")), "unknown")
    rows = []
    for name, scene, width, height, spp, reference_spp in ALL_ROWS:
        runs = []
        # A seed per run: one seed for both runs would repeat one image's luck.
        for seed in (1, 2):
            cmd = [sys.executable, __file__, scene, "--spp", str(spp), "--width", str(width), "--height", str(height),
                   "--backend", "auto", "--reference-spp", str(reference_spp), "--cache", args.cache,
                   "--binary", args.binary, "--seed", str(seed)]
            print("$ " + " ".join(cmd[1:]), flush=True)
            done = subprocess.run(cmd, capture_output=True, text=True)
            out = done.stdout
            print(out, done.stderr, flush=True)
            if done.returncode != 0:
                sys.exit(f"{scene}: compare.py failed; its output is above")
            mi = re.search(r"in ([0-9.]+) s \(([0-9.]+) Msamples/s\), RMSE ([0-9.e+-]+), relMSE ([0-9.e+-]+)", out)
            ratios = re.findall(r"takes ([0-9.]+)x Mitsuba's time", out)
            backend = re.search(r"rt-gpu (\w+):", out)
            alike = re.search(r"both whole processes: .*?: ([0-9.]+)x; both renders alone: .*?: ([0-9.]+)x", out)
            runs.append((float(mi.group(2)), float(mi.group(3)), float(mi.group(4)), ratios, backend.group(1),
                         alike.groups()))
        rows.append((name, width, height, spp, runs))
    table = [
        f"## {time.strftime('%Y-%m-%d')}: rt-gpu against Mitsuba 3 on every scene class (`compare.py --all`)",
        "",
        f"Machine: `{cpu}` (lscpu). Command: `benches/mitsuba/compare.py --all` (each row:",
        "`compare.py SCENE --spp N --width W --height H --backend auto --seed S`, run twice, one after",
        "the other, seeds 1 and 2 for both renderers; rt-gpu's default backend, its error against a",
        "reference rt-gpu renders once per row).",
        "Mitsuba 3's sampler `multijitter`; rt-gpu's time to Mitsuba's error over Mitsuba's time",
        "(lower is faster; below 1, rt-gpu is ahead): rt-gpu's whole process against Mitsuba's warm",
        "render, then, to Mitsuba's RMSE, like for like: both whole processes (Mitsuba's Python",
        "start, import, scene load and render, without its kernels' first compilation), both renders",
        "alone.",
        "",
        "| scene | size, Mitsuba spp | Mitsuba Msamples/s | Mitsuba RMSE; relMSE | rt-gpu backend | "
        "time to Mitsuba's RMSE | time to its relMSE | RMSE, both whole processes | RMSE, both renders alone |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, width, height, spp, runs in rows:
        rate = " / ".join(f"{r[0]:.2f}" for r in runs)
        errors = (" / ".join(f"{r[1]:.3e}" for r in runs) + "; " + " / ".join(f"{r[2]:.3e}" for r in runs))
        rmse = " / ".join(f"{r[3][0]}x" for r in runs)
        relmse = " / ".join(f"{r[3][1]}x" for r in runs)
        whole = " / ".join(f"{r[5][0]}x" for r in runs)
        alone = " / ".join(f"{r[5][1]}x" for r in runs)
        table.append(f"| {name} | {width}x{height}, {spp} | {rate} | {errors} | {runs[0][4]} | {rmse} | {relmse} "
                     f"| {whole} | {alone} |")
    path = os.path.join(os.path.dirname(__file__), "../../docs/benchmarks.md")
    text = open(path).read()
    at = text.index("\n## ") + 1
    open(path, "w").write(text[:at] + "\n".join(table) + "\n\n" + text[at:])
    print("\n".join(table))


def main():
    if "--all" in sys.argv[1:]:
        parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
        parser.add_argument("--all", action="store_true")
        parser.add_argument("--binary", default="target/release/rt-gpu")
        parser.add_argument("--cache", default="converge", help="where rendered references are kept")
        run_all(parser.parse_args())
        return
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene")
    parser.add_argument("--spp", type=int, default=1024, help="Mitsuba's samples per pixel")
    parser.add_argument("--width", type=int)
    parser.add_argument("--height", type=int)
    parser.add_argument("--max-depth", type=int)
    parser.add_argument("--mitsuba-sampler", default="multijitter",
                        help="independent, stratified, multijitter, ldsampler, orthogonal")
    parser.add_argument("--backend", default="gpu", help="rt-gpu backend")
    parser.add_argument("--roulette-depth", type=int, default=5, metavar="N",
                        help="Russian roulette from segment N on in both renderers, 0: off [default: 5, "
                             "rt-gpu's and Mitsuba's default]")
    parser.add_argument("--binary", default="target/release/rt-gpu")
    parser.add_argument("--reference", metavar="PFM", help="reference image [default: render one]")
    parser.add_argument("--reference-noise", type=float, metavar="RMSE", help="the reference's own RMSE")
    parser.add_argument("--reference-spp", type=int, default=8192)
    parser.add_argument("--seed", type=int, default=1,
                        help="both renderers' seed (the reference's is its own, 77)")
    parser.add_argument("--cache", default="converge", help="where a rendered reference is kept")
    parser.add_argument("--rates", action="store_true",
                        help="only samples per second: Mitsuba's render, then `rt-gpu bench` of both "
                             "backends at the same size, spp and depth (no reference, no errors)")
    parser.add_argument("--bench-spp", type=int,
                        help="with --rates: rt-gpu's spp [default: --spp] (Mitsuba recompiles per spp, "
                             "so its rate needs many; rt-gpu's does not)")
    parser.add_argument("--mitsuba-only", metavar="NPZ", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.mitsuba_only:
        render_mitsuba(args)
        return
    if args.rates:
        with tempfile.TemporaryDirectory() as out:
            mi_path = os.path.join(out, "mitsuba.npz")
            run_mitsuba(args, mi_path)
            data = np.load(mi_path)
            w, h, depth, seconds = int(data["width"]), int(data["height"]), int(data["max_depth"]), float(data["seconds"])
            mean = data["image"].reshape(-1, data["image"].shape[-1])[:, :3].mean(axis=0)
            print(f"Mitsuba {data['version']} ({args.mitsuba_sampler}): {w}x{h}, {args.spp} spp, max depth {depth}: "
                  f"{seconds:.2f} s, {w * h * args.spp / seconds / 1e6:.3f} Msamples/s, "
                  f"mean radiance ({mean[0]:.5f}, {mean[1]:.5f}, {mean[2]:.5f})", flush=True)
        subprocess.run([args.binary, "bench", args.scene, "--spp", str(args.bench_spp or args.spp), "--size", f"{w}x{h}",
                        "--max-depth", str(depth), "--roulette-depth", str(args.roulette_depth)], check=False)
        return

    os.makedirs(args.cache, exist_ok=True)
    with tempfile.TemporaryDirectory() as out:
        # Mitsuba renders in a process of its own, which has exited before rt-gpu starts: Dr.Jit's
        # worker threads would otherwise compete with rt-gpu's for the same cores.
        mi_path = os.path.join(out, "mitsuba.npz")
        mi_process = run_mitsuba(args, mi_path)
        data = np.load(mi_path)
        mi_image, mi_seconds = data["image"], float(data["seconds"])
        # A cold process's single render: the whole process less its warm-up render.
        mi_whole = mi_process - float(data["warmup_seconds"])
        args.width, args.height, args.max_depth = int(data["width"]), int(data["height"]), int(data["max_depth"])
        pixels = args.width * args.height
        ref, ref_noise = reference(args, args.cache)
        mi_rmse, mi_relmse = errors(mi_image, ref, ref_noise)
        print(f"reference noise (RMSE) {ref_noise:.3e}")
        print(f"mitsuba {str(data['version'])} llvm_ad_rgb {args.mitsuba_sampler}: {args.spp} spp in "
              f"{mi_seconds:.2f} s ({pixels * args.spp / mi_seconds / 1e6:.2f} Msamples/s), "
              f"RMSE {mi_rmse:.4e}, relMSE {mi_relmse:.4e}", flush=True)
        # Warm-up of rt-gpu's device and page cache.
        rt_gpu(args.binary, args.scene, 1, args, os.path.join(out, "warm.pfm"))
        rungs = []
        spp = 16
        while True:
            seconds, image, _, backend, render = rt_gpu(args.binary, args.scene, spp, args,
                                                        os.path.join(out, f"rt-{spp}.pfm"))
            rmse, relmse = errors(image, ref, ref_noise)
            rungs.append((spp, seconds, rmse, relmse, render))
            print(f"rt-gpu {backend}: {spp:6d} spp in {seconds:8.2f} s "
                  f"({pixels * spp / seconds / 1e6:.2f} Msamples/s), RMSE {rmse:.4e}, relMSE {relmse:.4e}",
                  flush=True)
            if (rmse <= mi_rmse and relmse <= mi_relmse) or spp >= 1 << 20:
                break
            spp *= 2
        last = image
    for name, index, target in (("RMSE", 2, mi_rmse), ("relMSE", 3, mi_relmse)):
        t_match = time_to(rungs, index, target)
        print(f"time to Mitsuba's {name} at {args.spp} spp: rt-gpu {t_match:.2f} s, mitsuba {mi_seconds:.2f} s: "
              f"rt-gpu takes {t_match / mi_seconds:.2f}x Mitsuba's time")
    t_match = time_to(rungs, 2, mi_rmse)
    print(f"like for like, to Mitsuba's RMSE: both whole processes: rt-gpu {t_match:.2f} s, mitsuba "
          f"{mi_whole:.2f} s: {t_match / mi_whole:.2f}x; ", end="")
    t_match = time_to(rungs, 2, mi_rmse, time_index=4)
    print(f"both renders alone: rt-gpu {t_match:.2f} s, mitsuba {mi_seconds:.2f} s: {t_match / mi_seconds:.2f}x")
    compared = [mi_rmse] + [r[2] for r in rungs[-2:]]
    if ref_noise > min(compared) / 3:
        print(f"warning: the reference's noise {ref_noise:.3e} is more than a third of an error compared "
              f"({min(compared):.3e}): use a higher --reference-spp")

    # Do the two renderers compute the same image? The image means' difference against the
    # noise of the means (each pixel's error spread over the pixels, as if independent).
    mi_mean, ref_mean = mi_image.mean(axis=(0, 1)), ref.mean(axis=(0, 1))
    print(f"mean radiance: mitsuba {mi_mean.round(5)}, rt-gpu {last.mean(axis=(0, 1)).round(5)}, "
          f"reference {ref_mean.round(5)}")
    noise = math.sqrt((mi_rmse**2 + ref_noise**2) / pixels)
    z = np.abs(mi_mean - ref_mean) / noise
    print(f"mitsuba vs reference, mean radiance per channel: z = {z.round(2)} (noise of a mean {noise:.2e}; "
          f"|z| < 3 is agreement within noise)")
    # The same per region: a grid of 8 x 4 blocks, each block's mean against the noise of that
    # mean, so that a difference confined to a few objects is not averaged away.
    rows, cols = 4, 8
    worst = []
    for r in range(rows):
        line = []
        for c in range(cols):
            ys = slice(r * args.height // rows, (r + 1) * args.height // rows)
            xs = slice(c * args.width // cols, (c + 1) * args.width // cols)
            block = (mi_image[ys, xs] - ref[ys, xs])[..., :3]
            n = block.shape[0] * block.shape[1]
            mi_block_rmse = np.sqrt(np.mean(block ** 2))
            block_noise = math.sqrt((mi_block_rmse ** 2 + ref_noise ** 2) / n)
            zb = np.abs(block.mean(axis=(0, 1))) / block_noise
            rel = block.mean(axis=(0, 1)) / np.maximum(ref[ys, xs][..., :3].mean(axis=(0, 1)), 1e-6)
            line.append(f"{zb.max():5.1f} ({100 * rel[np.argmax(zb)]:+.1f}%)")
            worst.append(zb.max())
        print("  region z (relative difference): " + " ".join(line))
    print(f"regions: {sum(z > 3 for z in worst)} of {len(worst)} with max-channel |z| > 3")


def time_to(rungs, index, target, time_index=1):
    """Seconds (the rungs' `time_index`: whole process, or 4: render alone) at which the rungs'
    error `index` reaches target: log-log between the first rung at or below it and the one
    before."""
    below = next((i for i, r in enumerate(rungs) if r[index] <= target), len(rungs) - 1)
    if below == 0:
        return rungs[0][time_index]
    (t0, e0) = (rungs[below - 1][time_index], rungs[below - 1][index])
    (t1, e1) = (rungs[below][time_index], rungs[below][index])
    if not (e1 < e0 and e1 > 0):
        return t1
    k = math.log(e1 / e0) / math.log(t1 / t0)
    return t0 * (target / e0) ** (1 / k)


if __name__ == "__main__":
    main()
