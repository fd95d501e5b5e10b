#!/usr/bin/env python3
"""Writes assets/cornell_box.gltf: the Cornell Program of Computer Graphics'
measured Cornell box (both blocks, the 130 x 105 ceiling light) as glTF 2.0 with
an embedded buffer. Run from the repository root: python3 tools/make_cornell.py

With --empty it writes assets/cornell_empty.gltf instead: the same five walls,
light, albedos and camera without the blocks (12 triangles), the paper's test
scene (§3.2: "une source lumineuse et des parois idéalement diffuses").

The light sits 0.1 below the ceiling (y = 548.7) so the two never coincide,
and faces down. The cos^n exponent of the light is the material's
extras.cosn (0 = diffuse)."""
import base64, json, math, struct, sys

QUADS = {
    "floor": ("white", [(552.8, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 559.2), (549.6, 0.0, 559.2)]),
    "ceiling": ("white", [(556.0, 548.8, 0.0), (556.0, 548.8, 559.2), (0.0, 548.8, 559.2), (0.0, 548.8, 0.0)]),
    "back_wall": ("white", [(549.6, 0.0, 559.2), (0.0, 0.0, 559.2), (0.0, 548.8, 559.2), (556.0, 548.8, 559.2)]),
    "green_wall": ("green", [(0.0, 0.0, 559.2), (0.0, 0.0, 0.0), (0.0, 548.8, 0.0), (0.0, 548.8, 559.2)]),
    "red_wall": ("red", [(552.8, 0.0, 0.0), (549.6, 0.0, 559.2), (556.0, 548.8, 559.2), (556.0, 548.8, 0.0)]),
    "light": ("light", [(343.0, 548.7, 227.0), (343.0, 548.7, 332.0), (213.0, 548.7, 332.0), (213.0, 548.7, 227.0)]),
}
BLOCKS = {
    "short_block": [
        [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0), (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)],
        [(290.0, 0.0, 114.0), (290.0, 165.0, 114.0), (240.0, 165.0, 272.0), (240.0, 0.0, 272.0)],
        [(130.0, 0.0, 65.0), (130.0, 165.0, 65.0), (290.0, 165.0, 114.0), (290.0, 0.0, 114.0)],
        [(82.0, 0.0, 225.0), (82.0, 165.0, 225.0), (130.0, 165.0, 65.0), (130.0, 0.0, 65.0)],
        [(240.0, 0.0, 272.0), (240.0, 165.0, 272.0), (82.0, 165.0, 225.0), (82.0, 0.0, 225.0)],
    ],
    "tall_block": [
        [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0), (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)],
        [(423.0, 0.0, 247.0), (423.0, 330.0, 247.0), (472.0, 330.0, 406.0), (472.0, 0.0, 406.0)],
        [(472.0, 0.0, 406.0), (472.0, 330.0, 406.0), (314.0, 330.0, 456.0), (314.0, 0.0, 456.0)],
        [(314.0, 0.0, 456.0), (314.0, 330.0, 456.0), (265.0, 330.0, 296.0), (265.0, 0.0, 296.0)],
        [(265.0, 0.0, 296.0), (265.0, 330.0, 296.0), (423.0, 330.0, 247.0), (423.0, 0.0, 247.0)],
    ],
}
MATERIALS = [
    {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.725, 0.71, 0.68, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.63, 0.065, 0.05, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "green", "pbrMetallicRoughness": {"baseColorFactor": [0.14, 0.45, 0.091, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "light", "pbrMetallicRoughness": {"baseColorFactor": [0.78, 0.78, 0.78, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "emissiveFactor": [1.0, 12.0 / 17.0, 4.0 / 17.0],
     "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 17.0}},
     "extras": {"cosn": 0.0}},
]
MAT_INDEX = {m["name"]: i for i, m in enumerate(MATERIALS)}


def main():
    empty = "--empty" in sys.argv[1:]
    meshes = [(name, mat, [quad]) for name, (mat, quad) in QUADS.items()]
    if not empty:
        meshes += [(name, "white", quads) for name, quads in BLOCKS.items()]
    blob = bytearray()
    accessors, views, gl_meshes, nodes = [], [], [], []
    for name, mat, quads in meshes:
        pos = [v for q in quads for v in q]
        idx = []
        for qi in range(len(quads)):
            b = 4 * qi
            idx += [b, b + 1, b + 2, b, b + 2, b + 3]
        off = len(blob)
        for v in pos:
            blob += struct.pack("<3f", *v)
        views.append({"buffer": 0, "byteOffset": off, "byteLength": 12 * len(pos), "target": 34962})
        lo = [min(v[i] for v in pos) for i in range(3)]
        hi = [max(v[i] for v in pos) for i in range(3)]
        accessors.append({"bufferView": len(views) - 1, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi})
        off = len(blob)
        for i in idx:
            blob += struct.pack("<I", i)
        views.append({"buffer": 0, "byteOffset": off, "byteLength": 4 * len(idx), "target": 34963})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"})
        gl_meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1, "material": MAT_INDEX[mat]}]})
        nodes.append({"name": name, "mesh": len(gl_meshes) - 1})
    # glTF cameras look down their local -z: turn half a turn about y to look along +z.
    nodes.append({"name": "camera", "camera": 0, "translation": [278.0, 273.0, -800.0], "rotation": [0.0, 1.0, 0.0, 0.0]})
    doc = {
        "asset": {"version": "2.0", "generator": "adaptive-pm tools/make_cornell.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "cornell_empty" if empty else "cornell_box", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gl_meshes,
        "materials": MATERIALS,
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(39.3077), "aspectRatio": 1.0, "znear": 1.0}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
    }
    out = "assets/cornell_empty.gltf" if empty else "assets/cornell_box.gltf"
    with open(out, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
