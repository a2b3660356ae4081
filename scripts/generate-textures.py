#!/usr/bin/env python3
"""Writes the images of scenes/textured.toml (pure Python, no dependencies): a procedural
planet (PNG, sRGB), a tile pattern (PNG) and a small HDR sky with a sun (Radiance .hdr).
Run from the repository root: python3 scripts/generate-textures.py"""
import math
import struct
import zlib

OUT = "scenes/textures/"


def png(path, width, height, pixel):
    """pixel(x, y) -> (r, g, b) in [0, 1], written as 8-bit sRGB."""
    def encode(c):
        c = min(max(c, 0.0), 1.0)
        c = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
        return int(round(c * 255))
    raw = bytearray()
    for y in range(height):
        raw.append(0)
        for x in range(width):
            raw.extend(encode(c) for c in pixel(x, y))
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                + chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


def hdr(path, width, height, pixel):
    """pixel(x, y) -> linear (r, g, b), written as flat (uncompressed) RGBE scanlines."""
    def rgbe(r, g, b):
        m = max(r, g, b)
        if m < 1e-32:
            return bytes(4)
        mantissa, exponent = math.frexp(m)
        scale = mantissa * 256.0 / m
        return bytes([int(r * scale), int(g * scale), int(b * scale), exponent + 128])
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {height} +X {width}\n".encode())
        for y in range(height):
            f.write(b"".join(rgbe(*pixel(x, y)) for x in range(width)))


def planet(x, y, w=256, h=128):
    lon = 2 * math.pi * (x + 0.5) / w
    lat = math.pi * (0.5 - (y + 0.5) / h)
    land = (math.sin(3 * lon + 1.3 * math.sin(2 * lat)) * math.cos(2 * lat + 0.7)
            + 0.6 * math.sin(7 * lon + 3 * lat) * math.sin(5 * lat - lon)
            + 0.3 * math.sin(13 * lon - 9 * lat))
    if abs(lat) > 1.25:
        return (0.9, 0.92, 0.95)
    if land > 0.35:
        t = min((land - 0.35) * 1.5, 1.0)
        return (0.12 + 0.35 * t, 0.35 - 0.1 * t, 0.08 + 0.05 * t)
    return (0.02, 0.08 + 0.1 * (land + 1.5) / 2, 0.3 + 0.1 * land)


def tiles(x, y, n=128):
    u, v = x / n * 8, y / n * 8
    edge = min(u % 1, 1 - u % 1, v % 1, 1 - v % 1)
    if edge < 0.04:
        return (0.05, 0.05, 0.05)
    shade = 0.35 + 0.25 * (((int(u) * 7 + int(v) * 13) % 5) / 4)
    return (shade, 0.8 * shade, 0.6 * shade)


SUN = (math.radians(40), math.radians(35))   # longitude, elevation


def sky(x, y, w=128, h=64):
    lon = 2 * math.pi * (x + 0.5) / w
    elevation = math.pi * (0.5 - (y + 0.5) / h)
    d = (math.cos(elevation) * math.cos(lon), math.sin(elevation), math.cos(elevation) * math.sin(lon))
    s = (math.cos(SUN[1]) * math.cos(SUN[0]), math.sin(SUN[1]), math.cos(SUN[1]) * math.sin(SUN[0]))
    if math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(d, s))))) < math.radians(6.0):
        return (111.0, 100.0, 84.0)
    if elevation < 0:
        return (0.25, 0.2, 0.15)
    t = elevation / (math.pi / 2)
    return (0.9 - 0.6 * t, 1.0 - 0.5 * t, 1.2 - 0.1 * t)


png(OUT + "planet.png", 256, 128, planet)
png(OUT + "tiles.png", 128, 128, tiles)
hdr(OUT + "sky.hdr", 128, 64, sky)
