"""Writes a large glTF scene for load-time measurements: a wavy sheet of about 1 M triangles
with normals and TEXCOORD_0, its base colour a 4096x4096 PNG (gradients with noise, so it
compresses as a photograph does, not as a flat colour), embedded in one .glb; and the same
sheet without the texture, so the image's decoding can be told from the rest.

    python3 benches/large-gltf/make.py OUT_DIR    # needs numpy and Pillow
    rt-gpu bench OUT_DIR/large-textured.glb       # read (parse + decode) and flatten times

Not committed (about 70 MB); docs/benchmarks.md gives the figures.
"""

import io
import json
import os
import struct
import sys

import numpy as np
from PIL import Image

OUT = sys.argv[1] if len(sys.argv) > 1 else "."
N = 708  # quads per side: 2 x 708^2 = 1.0 M triangles
SIDE = 4096
os.makedirs(OUT, exist_ok=True)

u, v = np.meshgrid(np.linspace(0, 1, N + 1, dtype=np.float32),
                   np.linspace(0, 1, N + 1, dtype=np.float32))
x, y = 4 * u - 2, 4 * v - 2
z = 0.1 * np.sin(6 * x) * np.cos(5 * y)
positions = np.stack([x, z, -y], -1).reshape(-1, 3).astype(np.float32)
dzdx = 0.6 * np.cos(6 * x) * np.cos(5 * y)
dzdy = -0.5 * np.sin(6 * x) * np.sin(5 * y)
normals = np.stack([-dzdx, np.ones_like(x), dzdy], -1)
normals = (normals / np.linalg.norm(normals, axis=-1, keepdims=True)).reshape(-1, 3)
normals = normals.astype(np.float32)
uvs = np.stack([u, 1 - v], -1).reshape(-1, 2).astype(np.float32)
i = np.arange(N * N)
row, col = i // N, i % N
a = row * (N + 1) + col
b, c, d = a + 1, a + N + 1, a + N + 2
indices = np.stack([a, b, d, a, d, c], -1).reshape(-1).astype(np.uint32)

rng = np.random.default_rng(1)
s, t = np.meshgrid(np.linspace(0, 1, SIDE), np.linspace(0, 1, SIDE))
rgb = np.stack([0.5 + 0.4 * np.sin(20 * s), 0.5 + 0.4 * np.cos(13 * t), 0.5 * s * t], -1)
rgb = np.clip(rgb + rng.normal(0, 0.04, rgb.shape), 0, 1)
png = io.BytesIO()
Image.fromarray((rgb * 255).astype(np.uint8)).save(png, format="PNG")
png = png.getvalue()


def write(name, textured):
    chunks = [positions.tobytes(), normals.tobytes(), uvs.tobytes(), indices.tobytes()]
    if textured:
        chunks.append(png)
    views, offset, blob = [], 0, b""
    for chunk in chunks:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(chunk)})
        padded = chunk + b"\0" * (-len(chunk) % 4)
        blob += padded
        offset += len(padded)
    count = len(positions)
    material = {"name": "Sheet", "pbrMetallicRoughness": {"metallicFactor": 0,
                                                         "roughnessFactor": 0.8}}
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
             "min": positions.min(0).tolist(), "max": positions.max(0).tolist()},
            {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": count, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
        ],
        "materials": [material],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1,
                                                   "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "nodes": [{"name": "Sheet", "mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    if textured:
        material["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        doc["textures"] = [{"source": 0}]
        doc["images"] = [{"bufferView": 4, "mimeType": "image/png"}]
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = (struct.pack("<II", len(text), 0x4E4F534A) + text
            + struct.pack("<II", len(blob), 0x004E4942) + blob)
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)


write("large-textured.glb", True)
write("large-plain.glb", False)
print(f"{len(indices) // 3} triangles, a {SIDE}x{SIDE} PNG of {len(png) / 1e6:.1f} MB")
