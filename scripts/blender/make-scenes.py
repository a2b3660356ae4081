"""Builds rt-gpu's Blender test scenes from Blender's own primitives and writes each as Blender
writes it (glTF 2.0 .glb, and .obj + .mtl), with a Cycles render of each as a reference.

    blender -b --factory-startup -P scripts/blender/make-scenes.py -- OUT_DIR [SAMPLES [SCENE...]]

With SCENE names, only those scenes are built (the others' files stay as they are).

Blender 3.4 (Debian's `blender` package, with `python3-numpy` for the glTF exporter). The
values set here are the ones tests/it/blender_scenes.rs expects to read back; the outputs are
committed under scenes/blender/, so tests never need Blender.

Scenes:
- `spheres`: a floor, three spheres (rough gold, smooth chrome, glass) and a grey diffuse
  cube, lit only by an emissive panel (the world is black): everything in it both renderers
  model, so rt-gpu's image is compared with Cycles'.
  `spheres-lambert-cycles.exr` renders it with the floor and the cube as Cycles' Diffuse BSDF
  (Lambert) instead of the Principled BSDF's diffuse, for `spheres-lambert.toml`, which places
  the file's objects with rt-gpu's `lambertian` there: where both renderers model the same
  thing, their images must agree (tests/it/blender_scenes.rs).
- `lamps`: the same objects lit by a point light, a spot light and a sun (KHR_lights_punctual),
  with a second camera; `lamps-lambert-cycles.exr` as `spheres-lambert-cycles.exr`.
- `lamps-no-spot`: only `lamps-no-spot-lambert-cycles.exr`, Cycles' render of `lamps`' Lambert
  variant without its spot, with at least 16384 samples. Blender's spot (a smoothstep over
  `spot_blend` in cos(angle), times cos(angle)) is not the falloff its glTF exporter writes
  (glTF's ramp between an inner cone of `spot_size / 2 x (1 - spot_blend)` and the outer one),
  so the spot's penumbra differs by design; without it both renderers model the same light.
- `textured`: the floor and the cube of `spheres` with an image as their base colour (four
  coloured quadrants, `textured-quadrants.png`, embedded in the .glb and named by the .mtl),
  through their UV maps, under the emissive panel. `textured-lambert-cycles.exr` renders them as
  Cycles' Diffuse BSDF with the image as its colour, for `textured-lambert.toml`: a wrong UV
  convention (v up or down the image) or a wrong colour space shows in region means.
- `bumpy`: the floor and cube of `textured`, grey, with a tangent-space normal map
  (`bumpy-normals.png`: per quadrant the normal tilted 30 degrees toward +u, +v, -v or -u,
  through Blender's Normal Map node, which the exporter writes as glTF's normalTexture and the
  .mtl as map_Bump), lit by a low sun from the side: each quadrant's brightness depends on its
  tilt. `bumpy-lambert-cycles.exr` renders them as Cycles' Diffuse BSDF with the same normal
  map: a wrong tangent frame (its handedness, the green channel's sign) shows in region means.
- `worn`: the floor and cube of `textured` with metallic and roughness from an image
  (`worn-metal-rough.png`, linear: per quadrant metallic 1 or 0 in blue, roughness 0.3 to 0.9
  in green, through a Separate RGB node, which the exporter writes as glTF's
  metallicRoughnessTexture) and the quadrant image as base colour, both through a Mapping node
  scaling them 2x (KHR_texture_transform); the floor's base colour read Closest (nearest), the
  cube's with Extend (clamp to edge) beyond its mapping's 1.5x, under the emissive panel.
  `worn-cycles.exr` is Cycles' render of it with its Principled BSDF.
"""

import math
import os
import sys

import bpy
from mathutils import Vector

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
OUT = os.path.abspath(argv[0] if argv else "scenes/blender")
SAMPLES = int(argv[1]) if len(argv) > 1 else 1024
SCENES = argv[2:] or ["spheres", "lamps", "lamps-no-spot", "textured", "bumpy", "worn"]
WIDTH, HEIGHT = 160, 120
os.makedirs(OUT, exist_ok=True)


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    return scene


def material(name, color, metallic=0.0, roughness=0.5, transmission=0.0, ior=1.45,
             emission=None, strength=0.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Transmission"].default_value = transmission
    bsdf.inputs["IOR"].default_value = ior
    if emission is not None:
        bsdf.inputs["Emission"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    return m


def place(obj, mat):
    obj.data.materials.append(mat)
    return obj


def sphere(name, location, radius, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=radius,
                                         location=location)
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    return place(obj, mat)


def objects():
    bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
    floor = bpy.context.active_object
    floor.name = "Floor"
    place(floor, material("Floor", (0.6, 0.6, 0.6), roughness=1.0))
    sphere("Gold", (-1.6, 0, 0.7), 0.7, material("Gold", (1.0, 0.77, 0.34), metallic=1.0,
                                                 roughness=0.3))
    sphere("Chrome", (0, 0.4, 0.7), 0.7, material("Chrome", (0.9, 0.9, 0.9), metallic=1.0,
                                                  roughness=0.05))
    sphere("Glass", (1.6, 0, 0.7), 0.7, material("Glass", (1.0, 1.0, 1.0), roughness=0.0,
                                                 transmission=1.0, ior=1.5))
    bpy.ops.mesh.primitive_cube_add(size=0.8, location=(0.2, -1.3, 0.4),
                                    rotation=(0, 0, math.radians(30)))
    cube = bpy.context.active_object
    cube.name = "Cube"
    place(cube, material("Clay", (0.8, 0.3, 0.2), roughness=1.0))


def camera(name, location, target, lens_mm=35.0):
    data = bpy.data.cameras.new(name)
    data.lens = lens_mm
    data.sensor_fit = "HORIZONTAL"
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    direction = Vector(target) - Vector(location)
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    return obj


def light(name, kind, location, energy, color=(1, 1, 1), target=None, **settings):
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    data.color = color
    for key, value in settings.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    if target is not None:
        obj.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    return obj


def render_settings(scene, cam):
    scene.camera = cam
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.seed = 0
    # rt-gpu's max_depth 10 (emission at the 10th hit counts) is Cycles' 9 bounces.
    scene.cycles.max_bounces = 9
    for kind in ("diffuse", "glossy", "transmission", "volume", "transparent_max"):
        setattr(scene.cycles, kind if kind.endswith("max") else kind + "_bounces", 9)
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.cycles.blur_glossy = 0.0
    scene.cycles.caustics_reflective = True
    scene.cycles.caustics_refractive = True
    scene.render.resolution_x = WIDTH
    scene.render.resolution_y = HEIGHT
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    # Cycles' pixel filter stays its default (Blackman-Harris, 1.5 px): a region's mean is the
    # same under any filter of unit integral (rt-gpu's is a one-pixel box) but at its edges.
    scene.cycles.filter_width = 1.5
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGB"
    settings.color_depth = "16"
    settings.exr_codec = "ZIP"


def lambert_variant(name, materials):
    """Renders the scene again with `materials` as Cycles' Diffuse BSDF (Lambert), their
    colour and normal inputs kept."""
    for material_name in materials:
        tree = bpy.data.materials[material_name].node_tree
        principled = tree.nodes["Principled BSDF"]
        diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
        base = principled.inputs["Base Color"]
        diffuse.inputs["Color"].default_value = base.default_value
        for link in base.links:
            tree.links.new(link.from_socket, diffuse.inputs["Color"])
        for link in principled.inputs["Normal"].links:
            tree.links.new(link.from_socket, diffuse.inputs["Normal"])
        diffuse.inputs["Roughness"].default_value = 0.0
        tree.links.new(diffuse.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])
    bpy.context.scene.render.filepath = os.path.join(OUT, name + "-cycles.exr")
    bpy.ops.render.render(write_still=True)


def export(name, cycles=True):
    path = os.path.join(OUT, name)
    bpy.ops.export_scene.gltf(filepath=path + ".glb", export_format="GLB",
                              export_cameras=True, export_lights=True, export_apply=True)
    bpy.ops.wm.obj_export(filepath=path + ".obj", export_materials=True,
                          export_triangulated_mesh=True)
    if cycles:
        bpy.context.scene.render.filepath = path + "-cycles.exr"
        bpy.ops.render.render(write_still=True)


def quadrant_image(name, size=64):
    """An image of four coloured quadrants (sRGB values), saved beside the scenes."""
    image = bpy.data.images.new(name, size, size, alpha=False)
    # Blender's pixels run from the bottom row up.
    colours = {(0, 1): (0.9, 0.2, 0.1), (1, 1): (0.2, 0.8, 0.2),
               (0, 0): (0.2, 0.3, 0.9), (1, 0): (0.9, 0.9, 0.3)}
    pixels = []
    for y in range(size):
        for x in range(size):
            pixels.extend((*colours[(2 * x // size, 2 * y // size)], 1.0))
    image.pixels = pixels
    image.filepath_raw = os.path.join(OUT, name + ".png")
    image.file_format = "PNG"
    image.save()
    return image


def textured_material(name, image):
    m = material(name, (1.0, 1.0, 1.0), roughness=1.0)
    tree = m.node_tree
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Linear"
    tree.links.new(texture.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])
    return m


def normal_quadrants(name, size=64, tilt=math.radians(30)):
    """A tangent-space normal map (OpenGL convention, as glTF: green toward +v) whose
    quadrants tilt the normal toward +u (top left), +v (top right), -v (bottom left) and -u
    (bottom right), saved beside the scenes as linear data."""
    image = bpy.data.images.new(name, size, size, alpha=False)
    image.colorspace_settings.name = "Non-Color"
    toward = {(0, 1): (1, 0), (1, 1): (0, 1), (0, 0): (0, -1), (1, 0): (-1, 0)}
    pixels = []
    for y in range(size):
        for x in range(size):
            du, dv = toward[(2 * x // size, 2 * y // size)]
            n = (math.sin(tilt) * du, math.sin(tilt) * dv, math.cos(tilt))
            pixels.extend((*(0.5 * c + 0.5 for c in n), 1.0))
    image.pixels = pixels
    image.filepath_raw = os.path.join(OUT, name + ".png")
    image.file_format = "PNG"
    image.save()
    return image


def normal_mapped_material(name, color, image):
    m = material(name, color, roughness=1.0)
    tree = m.node_tree
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Linear"
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.space = "TANGENT"
    normal_map.inputs["Strength"].default_value = 1.0
    tree.links.new(texture.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], tree.nodes["Principled BSDF"].inputs["Normal"])
    return m


# `worn-metal-rough.png`'s quadrants (as in quadrant_image: (column, row from the bottom)):
# (metallic, roughness).
WORN = {(0, 1): (1.0, 0.3), (1, 1): (0.0, 0.3), (0, 0): (1.0, 0.8), (1, 0): (0.0, 0.9)}


def metal_rough_quadrants(name, size=64):
    """Metallic in blue and roughness in green, per quadrant as WORN says, as linear data."""
    image = bpy.data.images.new(name, size, size, alpha=False)
    image.colorspace_settings.name = "Non-Color"
    pixels = []
    for y in range(size):
        for x in range(size):
            metallic, roughness = WORN[(2 * x // size, 2 * y // size)]
            pixels.extend((0.0, roughness, metallic, 1.0))
    image.pixels = pixels
    image.filepath_raw = os.path.join(OUT, name + ".png")
    image.file_format = "PNG"
    image.save()
    return image


def worn_material(name, colours, metal_rough, scale, interpolation, extension):
    """Base colour `colours` and metallic and roughness from `metal_rough`'s blue and green,
    both through one Mapping node scaling the UVs by `scale`."""
    m = material(name, (1.0, 1.0, 1.0), metallic=1.0, roughness=1.0)
    tree = m.node_tree
    principled = tree.nodes["Principled BSDF"]
    uv = tree.nodes.new("ShaderNodeTexCoord")
    mapping = tree.nodes.new("ShaderNodeMapping")
    mapping.inputs["Scale"].default_value = (scale, scale, 1.0)
    tree.links.new(uv.outputs["UV"], mapping.inputs["Vector"])
    def image_node(image):
        node = tree.nodes.new("ShaderNodeTexImage")
        node.image = image
        node.interpolation = interpolation
        node.extension = extension
        tree.links.new(mapping.outputs["Vector"], node.inputs["Vector"])
        return node
    tree.links.new(image_node(colours).outputs["Color"], principled.inputs["Base Color"])
    mr = image_node(metal_rough)
    separate = tree.nodes.new("ShaderNodeSeparateColor")
    tree.links.new(mr.outputs["Color"], separate.inputs["Color"])
    tree.links.new(separate.outputs["Green"], principled.inputs["Roughness"])
    tree.links.new(separate.outputs["Blue"], principled.inputs["Metallic"])
    return m


def floor_and_cube(floor_material, cube_material):
    """The 8 m floor and the turned 1.2 m cube of `textured` and `bumpy`."""
    bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
    floor = bpy.context.active_object
    floor.name = "Floor"
    place(floor, floor_material)
    bpy.ops.mesh.primitive_cube_add(size=1.2, location=(0.6, -1.0, 0.6),
                                    rotation=(0, 0, math.radians(30)))
    cube = bpy.context.active_object
    cube.name = "Cube"
    place(cube, cube_material)


def panel():
    bpy.ops.mesh.primitive_plane_add(size=2.5, location=(0, 1.5, 3.2),
                                     rotation=(math.radians(200), 0, 0))
    obj = bpy.context.active_object
    obj.name = "Panel"
    place(obj, material("Panel", (0, 0, 0), roughness=1.0, emission=(1.0, 0.9, 0.8),
                        strength=8.0))


if "spheres" in SCENES:
    scene = reset()
    objects()
    panel()
    cam = camera("Camera", (0, -7, 3.2), (0, 0, 0.6))
    render_settings(scene, cam)
    export("spheres")
    lambert_variant("spheres-lambert", ["Floor", "Clay"])

def lamps(spot=True):
    """The lamps of `lamps`: a point, a spot (unless `spot` is false) and a sun."""
    light("Point", "POINT", (-2, -2, 3), 400.0, color=(1.0, 0.8, 0.6), shadow_soft_size=0.0)
    if spot:
        light("Spot", "SPOT", (2.5, -2.5, 4), 800.0, target=(1.6, 0, 0.7),
              spot_size=math.radians(40), spot_blend=0.25, shadow_soft_size=0.0)
    light("Sun", "SUN", (0, 0, 10), 2.0, target=(0.5, 0.3, 0), angle=0.0)


if "lamps" in SCENES:
    scene = reset()
    objects()
    lamps()
    cam = camera("Camera", (0, -7, 3.2), (0, 0, 0.6))
    camera("Closeup", (3, -3, 1.5), (1.6, 0, 0.7), lens_mm=50.0)
    render_settings(scene, cam)
    export("lamps")
    lambert_variant("lamps-lambert", ["Floor", "Clay"])

if "lamps-no-spot" in SCENES:
    # Only Cycles' render (lamps.glb is the file: tests drop its spot).
    scene = reset()
    objects()
    lamps(spot=False)
    render_settings(scene, camera("Camera", (0, -7, 3.2), (0, 0, 0.6)))
    # The chrome's highlights and the caustic paths through it converge slowly.
    scene.cycles.samples = max(SAMPLES, 16384)
    lambert_variant("lamps-no-spot-lambert", ["Floor", "Clay"])

if "textured" in SCENES:
    scene = reset()
    quadrants = quadrant_image("textured-quadrants")
    floor_and_cube(textured_material("Floor", quadrants), textured_material("Box", quadrants))
    panel()
    cam = camera("Camera", (0, -7, 3.2), (0, 0, 0.6))
    render_settings(scene, cam)
    export("textured", cycles=False)
    lambert_variant("textured-lambert", ["Floor", "Box"])

if "bumpy" in SCENES:
    scene = reset()
    normals = normal_quadrants("bumpy-normals")
    floor_and_cube(normal_mapped_material("Floor", (0.8, 0.8, 0.8), normals),
                   normal_mapped_material("Box", (0.8, 0.8, 0.8), normals))
    # Light travelling along -(0.61, 0.35, 0.71): 45 degrees up, from +x turned 30 degrees
    # toward +y, so all four tilts (and both signs of each tangent axis) light differently.
    light("Sun", "SUN", (6.12, 3.54, 7.07), 3.0, target=(0, 0, 0), angle=0.0)
    cam = camera("Camera", (0, -7, 3.2), (0, 0, 0.6))
    render_settings(scene, cam)
    export("bumpy", cycles=False)
    lambert_variant("bumpy-lambert", ["Floor", "Box"])

if "worn" in SCENES:
    scene = reset()
    quadrants = bpy.data.images.get("textured-quadrants") or quadrant_image("textured-quadrants")
    metal_rough = metal_rough_quadrants("worn-metal-rough")
    floor_and_cube(worn_material("Floor", quadrants, metal_rough, 2.0, "Closest", "REPEAT"),
                   worn_material("Box", quadrants, metal_rough, 1.5, "Linear", "EXTEND"))
    panel()
    cam = camera("Camera", (0, -7, 3.2), (0, 0, 0.6))
    render_settings(scene, cam)
    export("worn")
