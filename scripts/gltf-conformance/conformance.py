"""Renders Khronos glTF sample models with rt-gpu and with Cycles (through Blender's own glTF
importer), same camera and lighting rule, and writes a table of how far they agree.

    blender -b --factory-startup -P scripts/gltf-conformance/conformance.py -- \
        --models MODELS_DIR --out OUT_DIR [--rt-gpu target/release/rt-gpu] \
        [--spp 128] [--size 400x300] [MODEL...]

MODELS_DIR holds the sample models as glTF-Sample-Assets lays them out
(MODELS_DIR/NAME/glTF-Binary/NAME.glb or MODELS_DIR/NAME/glTF/NAME.gltf); `fetch-models.sh`
copies them out of a clone. Without MODEL names, every model in MODELS_DIR is tried; models whose
files ask for an extension neither renderer is compared on here (see UNCOMPARED) are listed as
skipped, with the extension.

For each model, OUT_DIR gets NAME-rtgpu.pfm, NAME-cycles.exr, NAME.png (the two side by side,
rt-gpu left, Cycles' over the world it rendered under) and NAME.log (rt-gpu's notes); OUT_DIR/table.md gets one row: rt-gpu's mean
luminance over Cycles' over the pixels the model covers in Cycles' render (alpha 1), and the
correlation of the log luminance of the 4x4 blocks inside those pixels. The verdict is "agrees"
where the ratio is within 0.85-1.18 and the correlation at least 0.95 (issue 62's goal: Blender's
Principled v1 diffuse is brighter than glTF's).

The Blender side follows ../shared/notes/blender-gltf-import.md: numpy's removed aliases are
restored for the importer, animated files are shown at 0 s (frame 0), punctual lights are made
punctual, alphaMode MASK is thresholded,
meshes without a material get glTF's default one (times COLOR_0), the camera is rt-gpu's (the file's first
camera with a vertical field of view, else rt-gpu's framing camera), the world is black where
the file has lamps and a uniform sky of radiance 1 otherwise (rt-gpu's default lighting), and
Cycles renders with the settings listed in `cycles_settings`.

Blender 3.4 (Debian's `blender`, with python3-numpy). CI never runs this: it needs Blender and
the sample models, neither of which the tests carry.
"""

import json
import math
import os
import struct
import subprocess
import sys
import time

import numpy as np

# Blender 3.4's glTF importer still uses numpy's removed aliases.
for alias, value in (("bool", bool), ("int", int), ("float", float), ("object", object)):
    if alias not in np.__dict__:
        setattr(np, alias, value)

import bpy  # noqa: E402
import mathutils  # noqa: E402

# Extensions rt-gpu reads (or those whose absence changes nothing the table measures).
READ = {
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_unlit",
    "KHR_materials_clearcoat",
    "KHR_materials_volume",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    # Both renderers draw the default materials of a file with variants.
    "KHR_materials_variants",
    "EXT_mesh_gpu_instancing",
    "KHR_mesh_quantization",
    "KHR_texture_basisu",
}
# Extensions a model may use that neither renderer is compared on here: the material-extensions
# issue (anisotropy, ...) and compressed or variant files.
UNCOMPARED = {
    "KHR_materials_anisotropy",
    "KHR_materials_iridescence",
    "KHR_materials_dispersion",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "EXT_texture_webp",
}

FRAMING_VFOV = 40.0  # src/scene/gltf_scene.rs
MIN_SIZE = 1e-4  # src/scene/mod.rs


def args():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    opts = {"--rt-gpu": "target/release/rt-gpu", "--spp": "128", "--size": "400x300"}
    models = []
    i = 0
    while i < len(argv):
        if argv[i].startswith("--"):
            opts[argv[i]] = argv[i + 1]
            i += 2
        else:
            models.append(argv[i])
            i += 1
    for required in ("--models", "--out"):
        if required not in opts:
            sys.exit(f"conformance.py: {required} DIR is required (see the docstring)")
    return opts, models


def model_file(models_dir, name):
    for variant, ext in (("glTF-Binary", ".glb"), ("glTF", ".gltf")):
        path = os.path.join(models_dir, name, variant, name + ext)
        if os.path.exists(path):
            return path
    return None


def gltf_json(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        length = struct.unpack_from("<I", data, 12)[0]
        return json.loads(data[20 : 20 + length])
    return json.loads(data)


def render_rtgpu(opts, path, pfm, log):
    width, height = opts["--size"].split("x")
    cmd = [
        opts["--rt-gpu"],
        path,
        "--backend",
        "cpu",
        "--size",
        f"{width}x{height}",
        "--spp",
        opts["--spp"],
        "--max-depth",
        "11",
        "-o",
        pfm,
    ]
    start = time.time()
    done = subprocess.run(cmd, capture_output=True, text=True)
    with open(log, "w") as f:
        f.write(" ".join(cmd) + "\n" + done.stdout + done.stderr)
    return done.returncode, (done.stderr.strip().splitlines() or [""])[-1], time.time() - start


def fix_import(doc):
    """Where Blender's importer departs from glTF (../shared/notes/blender-gltf-import.md)."""
    # The importer keys an animation's time t at frame t x fps and leaves the scene at frame 1
    # (1/24 s in); rt-gpu draws the first animation at 0 s (src/scene/gltf_pose.rs).
    if doc.get("animations"):
        bpy.context.scene.frame_set(0)
    for light in bpy.data.lights:
        if light.type in ("POINT", "SPOT"):
            light.shadow_soft_size = 0.0
        if light.type == "SUN":
            light.angle = 0.0
    for mat in bpy.data.materials:
        if not mat.use_nodes or mat.blend_method != "CLIP":
            continue
        for node in mat.node_tree.nodes:
            if node.type != "BSDF_PRINCIPLED":
                continue
            alpha = node.inputs["Alpha"]
            if alpha.is_linked:
                source = alpha.links[0].from_socket
                step = mat.node_tree.nodes.new("ShaderNodeMath")
                step.operation = "GREATER_THAN"
                step.inputs[1].default_value = mat.alpha_threshold - 1e-6
                mat.node_tree.links.new(source, step.inputs[0])
                mat.node_tree.links.new(step.outputs[0], alpha)
            else:
                alpha.default_value = 1.0 if alpha.default_value >= mat.alpha_threshold else 0.0
    for obj in bpy.data.objects:
        if obj.type == "MESH" and not obj.data.materials:
            # glTF's default material: base colour 1 (times COLOR_0), metallic 1, roughness 1.
            default = bpy.data.materials.new("glTF default")
            default.use_nodes = True
            bsdf = default.node_tree.nodes["Principled BSDF"]
            bsdf.inputs["Base Color"].default_value = (1, 1, 1, 1)
            bsdf.inputs["Metallic"].default_value = 1.0
            bsdf.inputs["Roughness"].default_value = 1.0
            colors = getattr(obj.data, "color_attributes", None)
            if colors is not None and len(colors) > 0:
                node = default.node_tree.nodes.new("ShaderNodeVertexColor")
                node.layer_name = colors[0].name
                default.node_tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
            obj.data.materials.append(default)


def mesh_bounds():
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in bpy.data.objects:
        if obj.type != "MESH":
            continue
        ev = obj.evaluated_get(depsgraph)
        mesh = ev.to_mesh()
        n = len(mesh.vertices)
        if n:
            co = np.empty(3 * n)
            mesh.vertices.foreach_get("co", co)
            co = co.reshape(n, 3)
            m = np.array(ev.matrix_world)
            world = co @ m[:3, :3].T + m[:3, 3]
            lo = np.minimum(lo, world.min(axis=0))
            hi = np.maximum(hi, world.max(axis=0))
        ev.to_mesh_clear()
    return lo, hi


def to_blender(v):
    """glTF (x, y, z) is Blender (x, -z, y)."""
    return mathutils.Vector((v[0], -v[2], v[1]))


def place_camera(doc, width, height):
    scene = bpy.context.scene
    cams = doc.get("cameras", [])
    imported = [o for o in bpy.data.objects if o.type == "CAMERA"]
    first = None
    if cams and imported:
        # rt-gpu takes the default scene's first camera node; the importer names camera data
        # after the glTF camera, so match by name where it can.
        name = cams[0].get("name")
        first = next((o for o in imported if name and o.data.name == name), imported[0])
    if first is not None and cams[0].get("type") == "perspective":
        cam = first
        cam.data.sensor_fit = "VERTICAL"
        cam.data.angle_y = cams[0]["perspective"]["yfov"]
    else:
        lo_b, hi_b = mesh_bounds()
        lo = np.array([lo_b[0], lo_b[2], -hi_b[1]])
        hi = np.array([hi_b[0], hi_b[2], -lo_b[1]])
        center = (lo + hi) / 2
        radius = max(np.linalg.norm(hi - lo) / 2, MIN_SIZE)
        half = math.radians(FRAMING_VFOV / 2)
        distance = 1.1 * radius / math.sin(half)
        direction = np.array([0.0, 0.25, 1.0])
        direction /= np.linalg.norm(direction)
        eye = center + distance * direction
        data = bpy.data.cameras.new("rt-gpu framing")
        cam = bpy.data.objects.new("rt-gpu framing", data)
        scene.collection.objects.link(cam)
        cam.location = to_blender(eye)
        look = to_blender(center) - to_blender(eye)
        cam.rotation_euler = look.to_track_quat("-Z", "Z").to_euler()
        data.sensor_fit = "VERTICAL"
        data.angle_y = math.radians(FRAMING_VFOV)
        data.clip_start = distance * 1e-3
        data.clip_end = distance * 10
    scene.camera = cam


def cycles_settings(spp, width, height):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.seed = 0
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.max_bounces = 10
    c.diffuse_bounces = 10
    c.glossy_bounces = 10
    c.transmission_bounces = 10
    c.volume_bounces = 10
    c.transparent_max_bounces = 64
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    scene.render.film_transparent = True
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGBA"


def world(radiance):
    w = bpy.data.worlds.new("rt-gpu lighting")
    w.use_nodes = True
    bg = w.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (radiance, radiance, radiance, 1)
    bg.inputs["Strength"].default_value = 1.0
    bpy.context.scene.world = w


def render_cycles(opts, path, exr):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    doc = gltf_json(path)
    fix_import(doc)
    width, height = (int(v) for v in opts["--size"].split("x"))
    cycles_settings(int(opts["--spp"]), width, height)
    place_camera(doc, width, height)
    lamps = any(o.type == "LIGHT" for o in bpy.data.objects)
    background = 0.0 if lamps else 1.0
    world(background)
    bpy.context.scene.render.filepath = exr
    start = time.time()
    bpy.ops.render.render(write_still=True)
    return time.time() - start, background


def pixels(path, width, height):
    img = bpy.data.images.load(path, check_existing=False)
    if tuple(img.size) != (width, height):
        sys.exit(f"conformance.py: {path} is {tuple(img.size)}, not {width}x{height}")
    px = np.array(img.pixels[:], dtype=np.float32)
    bpy.data.images.remove(img)
    return px.reshape(height, width, 4)


def pfm(path, width, height):
    """rt-gpu's .pfm: rows bottom to top, as Blender's pixels; alpha 1."""
    with open(path, "rb") as f:
        data = f.read()
    header = data.split(b"\n", 3)
    w, h = (int(v) for v in header[1].split())
    if (w, h) != (width, height) or header[0] != b"PF":
        sys.exit(f"conformance.py: {path} is not a {width}x{height} colour PFM")
    order = "<" if float(header[2]) < 0 else ">"
    rgb = np.frombuffer(header[3], dtype=order + "f4").reshape(h, w, 3)
    return np.concatenate([rgb, np.ones((h, w, 1), dtype=np.float32)], axis=2)


def figures(rt, cy):
    lum = lambda p: 0.2126 * p[..., 0] + 0.7152 * p[..., 1] + 0.0722 * p[..., 2]  # noqa: E731
    mask = cy[..., 3] > 0.999
    if mask.sum() < 16:
        return None, None, int(mask.sum())
    y_rt, y_cy = lum(rt), lum(cy)
    ratio = float(y_rt[mask].mean() / max(y_cy[mask].mean(), 1e-12))
    h, w = mask.shape
    bh, bw = h // 4, w // 4
    blocks = lambda a: a[: 4 * bh, : 4 * bw].reshape(bh, 4, bw, 4).mean(axis=(1, 3))  # noqa: E731
    full = blocks(mask.astype(np.float64)) >= 1.0
    if full.sum() < 4:
        return ratio, None, int(mask.sum())
    a = np.log(np.maximum(blocks(y_rt)[full], 1e-4))
    b = np.log(np.maximum(blocks(y_cy)[full], 1e-4))
    corr = float(np.corrcoef(a, b)[0, 1]) if a.std() > 0 and b.std() > 0 else None
    return ratio, corr, int(mask.sum())


def side_by_side(rt, cy, path, background):
    """rt-gpu's image beside Cycles' over the world it was rendered under (Cycles renders the
    world transparent, for the mask), as 8-bit sRGB."""
    h, w = rt.shape[:2]
    out = np.zeros((h, 2 * w, 4), dtype=np.float32)
    out[:, :w, :3] = rt[..., :3]
    out[:, w:, :3] = cy[..., :3] + (1 - cy[..., 3:4]) * background
    out[..., 3] = 1
    # sRGB for the PNG.
    c = np.clip(out[..., :3], 0, 1)
    out[..., :3] = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    img = bpy.data.images.new("pair", 2 * w, h, alpha=False, float_buffer=False)
    img.colorspace_settings.name = "Non-Color"
    img.pixels.foreach_set(out.ravel())
    img.filepath_raw = path
    img.file_format = "PNG"
    img.save()
    bpy.data.images.remove(img)


def main():
    opts, names = args()
    out = opts["--out"]
    os.makedirs(out, exist_ok=True)
    models_dir = opts["--models"]
    names = names or sorted(os.listdir(models_dir))
    width, height = (int(v) for v in opts["--size"].split("x"))
    rows = []
    for name in names:
        path = model_file(models_dir, name)
        if path is None:
            rows.append((name, "", "", "skipped", "no .glb or .gltf variant here"))
            continue
        doc = gltf_json(path)
        used = set(doc.get("extensionsUsed", []))
        uncompared = sorted(used & UNCOMPARED)
        if uncompared:
            rows.append((name, "", "", "skipped", "uses " + ", ".join(uncompared)))
            continue
        rt_pfm = os.path.join(out, name + "-rtgpu.pfm")
        cy_exr = os.path.join(out, name + "-cycles.exr")
        code, last, rt_s = render_rtgpu(opts, path, rt_pfm, os.path.join(out, name + ".log"))
        if code != 0:
            rows.append((name, "", "", "refused", last))
            continue
        cy_s, background = render_cycles(opts, os.path.abspath(path), os.path.abspath(cy_exr))
        rt = pfm(rt_pfm, width, height)
        cy = pixels(cy_exr, width, height)
        side_by_side(rt, cy, os.path.abspath(os.path.join(out, name + ".png")), background)
        ratio, corr, covered = figures(rt, cy)
        if ratio is None:
            rows.append((name, "", "", "no model pixels", f"{covered} covered pixels"))
            continue
        agrees = 0.85 <= ratio <= 1.18 and corr is not None and corr >= 0.95
        note = f"rt-gpu {rt_s:.0f} s, Cycles {cy_s:.0f} s"
        rows.append(
            (
                name,
                f"{ratio:.2f}",
                "" if corr is None else f"{corr:.2f}",
                "agrees" if agrees else "differs",
                note,
            )
        )
        print(f"conformance: {name}: {rows[-1][1:]}", flush=True)
        write_table(out, rows)
    write_table(out, rows)


def write_table(out, rows):
    with open(os.path.join(out, "table.md"), "w") as f:
        f.write("| model | mean ratio | block correlation | verdict | note |\n")
        f.write("|---|---|---|---|---|\n")
        for row in rows:
            f.write("| " + " | ".join(row) + " |\n")


main()
