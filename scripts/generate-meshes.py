#!/usr/bin/env python3
"""Writes the models of scenes/meshes.toml (pure Python, no dependencies): a trefoil torus knot
as an OBJ of quad faces with vertex normals (scenes/models/knot.obj), and a glTF lamp (scenes/models/lamp.gltf and
lamp.bin: a white hexagonal stand with a glowing icosphere on top, nodes with transforms, its
own materials). Run from the repository root: python3 scripts/generate-meshes.py

For benchmarks, `python3 scripts/generate-meshes.py --knot SEGMENTS SIDES OUT.obj` writes a
finer knot: 2 x SEGMENTS x SIDES triangles (1000 x 500: a million)."""
import json
import math
import struct
import sys


def knot_point(t):
    """The (2, 3) torus knot."""
    r = 2 + math.cos(3 * t)
    return (r * math.cos(2 * t), r * math.sin(2 * t), -math.sin(3 * t))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normalize(a):
    n = math.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2)
    return (a[0] / n, a[1] / n, a[2] / n)


def write_knot(path, segments, sides, radius=0.45):
    """A tube around the knot: `segments` rings of `sides` vertices, each with the tube's
    outward normal (smooth shading), quads between them, counter-clockwise seen from outside."""
    with open(path, "w") as f:
        f.write("# (2, 3) torus knot tube, %d x %d quads (scripts/generate-meshes.py)\n"
                % (segments, sides))
        for i in range(segments):
            t = 2 * math.pi * i / segments
            p = knot_point(t)
            tangent = normalize(sub(knot_point(t + 1e-4), knot_point(t - 1e-4)))
            side = normalize(cross(tangent, (0.0, 0.0, 1.0)))
            up = cross(side, tangent)
            for j in range(sides):
                a = 2 * math.pi * j / sides
                c, s = math.cos(a), math.sin(a)
                normal = tuple(c * side[k] + s * up[k] for k in range(3))
                v = tuple(p[k] + radius * normal[k] for k in range(3))
                f.write("v %.5f %.5f %.5f\nvn %.4f %.4f %.4f\n" % (v + normal))
        for i in range(segments):
            n = (i + 1) % segments
            for j in range(sides):
                m = (j + 1) % sides
                a, b = i * sides + j + 1, n * sides + j + 1
                c, d = n * sides + m + 1, i * sides + m + 1
                f.write("f %d//%d %d//%d %d//%d %d//%d\n" % (a, a, b, b, c, c, d, d))


def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    verts = [normalize(v) for v in [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t),
                                    (0, 1, t), (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1),
                                    (-t, 0, -1), (-t, 0, 1)]]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        cache = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                pa, pb = verts[a], verts[b]
                verts.append(normalize(tuple((pa[k] + pb[k]) / 2 for k in range(3))))
                cache[key] = len(verts) - 1
            return cache[key]
        new = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return verts, faces


def hex_prism():
    """A closed hexagonal prism of radius 1 from y = 0 to y = 1, outward-facing."""
    ring = [(math.cos(math.pi * k / 3), math.sin(math.pi * k / 3)) for k in range(6)]
    verts = [(x, 0.0, z) for x, z in ring] + [(x, 1.0, z) for x, z in ring]
    verts += [(0.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
    faces = []
    for k in range(6):
        n = (k + 1) % 6
        faces += [(k, n + 6, n), (k, k + 6, n + 6)]
        faces += [(12, k, n), (13, n + 6, k + 6)]
    return verts, faces


def write_lamp(gltf_path, bin_path, bin_uri):
    meshes = [hex_prism(), icosphere(2)]
    data = bytearray()
    views, accessors = [], []
    for verts, faces in meshes:
        start = len(data)
        for v in verts:
            data += struct.pack("<3f", *v)
        views.append({"buffer": 0, "byteOffset": start, "byteLength": len(data) - start})
        lo = [min(v[k] for v in verts) for k in range(3)]
        hi = [max(v[k] for v in verts) for k in range(3)]
        accessors.append({"bufferView": len(views) - 1, "componentType": 5126,
                          "count": len(verts), "type": "VEC3", "min": lo, "max": hi})
        start = len(data)
        for f in faces:
            data += struct.pack("<3I", *f)
        views.append({"buffer": 0, "byteOffset": start, "byteLength": len(data) - start})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125,
                          "count": 3 * len(faces), "type": "SCALAR"})
    with open(bin_path, "wb") as f:
        f.write(data)
    doc = {
        "asset": {"version": "2.0", "generator": "rt-gpu scripts/generate-meshes.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "buffers": [{"uri": bin_uri, "byteLength": len(data)}],
        "bufferViews": views,
        "accessors": accessors,
        "materials": [
            {"name": "Porcelain", "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.78, 0.72, 1], "metallicFactor": 0}},
            {"name": "Glow", "emissiveFactor": [1.0, 0.75, 0.45],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6}}},
        ],
        "meshes": [
            {"name": "Stand", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                              "material": 0}]},
            {"name": "Bulb", "primitives": [{"attributes": {"POSITION": 2}, "indices": 3,
                                             "material": 1}]},
        ],
        "nodes": [
            {"name": "Fixture", "children": [1, 2], "translation": [0, 0, 0]},
            {"name": "Stand", "mesh": 0, "scale": [0.35, 1.6, 0.35]},
            {"name": "Bulb", "mesh": 1, "translation": [0, 2.1, 0], "scale": [0.5, 0.5, 0.5]},
        ],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    with open(gltf_path, "w") as f:
        json.dump(doc, f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "--knot":
        write_knot(sys.argv[4], int(sys.argv[2]), int(sys.argv[3]))
    else:
        write_knot("scenes/models/knot.obj", 240, 24)
        write_lamp("scenes/models/lamp.gltf", "scenes/models/lamp.bin", "lamp.bin")
