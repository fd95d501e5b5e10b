#!/usr/bin/env python3
"""Writes a large textured glTF scene (GLB) for the loader's, the tracer's
and the renderer's timings on real sizes (issue: real glTF scenes, item 6).

    python3 tools/make_large_textured.py OUT.glb [--quads N] [--texture PX] [--flat]

A 10 x 10 m terrain of N x N quads (2 N^2 triangles; N = 708 gives
1 002 528), its height a sum of sines up to 0.4 m, with per-vertex normals
and texture coordinates, and a PX x PX PNG checker of 16 x 16 squares as its
base colour (glossy dielectric, roughness 0.6); a 2 x 2 m lamp 4 m above
its centre facing down, and a camera. Not committed (28 MB at N = 708): docs/performance.md gives
the commands that build and measure it. Standard library only."""
import argparse, json, math, struct, zlib


def png_checker(px, squares=16):
    light, dark = (220, 200, 160), (70, 45, 30)
    rows = []
    for j in range(px):
        row = bytearray([0])  # filter type 0
        for i in range(px):
            c = light if ((i * squares // px) + (j * squares // px)) % 2 == 0 else dark
            row.extend(c)
        rows.append(bytes(row))
    raw = b"".join(rows)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", px, px, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")


def height(x, z):
    return 0.2 * math.sin(1.3 * x) * math.cos(0.9 * z) + 0.2 * math.sin(0.7 * x + 0.4 * z)


def terrain(n, size=10.0):
    pos, nor, uv = bytearray(), bytearray(), bytearray()
    lo, hi = [1e30] * 3, [-1e30] * 3
    e = 1e-3
    for j in range(n + 1):
        for i in range(n + 1):
            x, z = size * (i / n - 0.5), size * (j / n - 0.5)
            y = height(x, z)
            p = (x, y, z)
            for k in range(3):
                lo[k], hi[k] = min(lo[k], p[k]), max(hi[k], p[k])
            pos += struct.pack("<3f", *p)
            dx = (height(x + e, z) - height(x - e, z)) / (2 * e)
            dz = (height(x, z + e) - height(x, z - e)) / (2 * e)
            l = math.sqrt(dx * dx + 1 + dz * dz)
            nor += struct.pack("<3f", -dx / l, 1 / l, -dz / l)
            uv += struct.pack("<2f", i / n, j / n)
    idx = bytearray()
    w = n + 1
    for j in range(n):
        for i in range(n):
            a, b, c, d = j * w + i, j * w + i + 1, (j + 1) * w + i + 1, (j + 1) * w + i
            # (d - a) x (b - a) = +z x +x = +y: up-facing.
            idx += struct.pack("<6I", a, d, c, a, c, b)
    return pos, nor, uv, idx, lo, hi, (n + 1) ** 2, 6 * n * n


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--quads", type=int, default=708)
    ap.add_argument("--texture", type=int, default=1024)
    ap.add_argument("--flat", action="store_true",
                    help="no texture: the checker's mean colour as a factor (to time the texture's cost)")
    a = ap.parse_args()
    pos, nor, uv, idx, lo, hi, nv, ni = terrain(a.quads)
    png = png_checker(a.texture)
    lamp_pos = struct.pack("<12f", -1, 4, -1, 1, 4, -1, 1, 4, 1, -1, 4, 1)
    lamp_idx = struct.pack("<6I", 0, 1, 2, 0, 2, 3)  # (b - a) x (c - a) = x x z = -y: faces down
    bin_, views = bytearray(), []
    for blob in (pos, nor, uv, idx, lamp_pos, lamp_idx, png):
        views.append({"buffer": 0, "byteOffset": len(bin_), "byteLength": len(blob)})
        bin_ += blob
        while len(bin_) % 4:
            bin_.append(0)
    acc = [
        {"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3", "min": lo, "max": hi},
        {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": nv, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5125, "count": ni, "type": "SCALAR"},
        {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 4, -1], "max": [1, 4, 1]},
        {"bufferView": 5, "componentType": 5125, "count": 6, "type": "SCALAR"},
    ]
    doc = {
        "asset": {"version": "2.0", "generator": "adaptive-pm tools/make_large_textured.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "terrain", "mesh": 0},
            {"name": "lamp", "mesh": 1},
            {"name": "camera", "camera": 0, "translation": [0.0, 4.0, 8.0],
             "rotation": [-math.sin(math.radians(15)), 0.0, 0.0, math.cos(math.radians(15))]},
        ],
        "meshes": [
            {"name": "terrain", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0}]},
            {"name": "lamp", "primitives": [{"attributes": {"POSITION": 4}, "indices": 5, "material": 1}]},
        ],
        "materials": [
            {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 0.6}},
            {"name": "lamp", "emissiveFactor": [1.0, 0.95, 0.9], "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0}},
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9987}],
        "images": [{"bufferView": 6, "mimeType": "image/png"}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(50.0), "aspectRatio": 1.0, "znear": 0.1}}],
        "accessors": acc,
        "bufferViews": views,
        "buffers": [{"byteLength": len(bin_)}],
    }
    if a.flat:
        pbr = doc["materials"][0]["pbrMetallicRoughness"]
        del pbr["baseColorTexture"], doc["textures"], doc["samplers"], doc["images"]
        srgb = lambda c: ((c / 255 + 0.055) / 1.055) ** 2.4 if c / 255 > 0.04045 else c / 255 / 12.92
        pbr["baseColorFactor"] = [(srgb(l) + srgb(d)) / 2 for l, d in zip((220, 200, 160), (70, 45, 30))] + [1.0]
    js = json.dumps(doc, separators=(",", ":")).encode()
    while len(js) % 4:
        js += b" "
    glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(bin_))
    glb += struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(bin_), 0x004E4942) + bytes(bin_)
    with open(a.out, "wb") as f:
        f.write(glb)
    print(f"wrote {a.out}: {ni // 3} triangles, {a.texture} x {a.texture} texture, {len(glb)} bytes")


if __name__ == "__main__":
    main()
