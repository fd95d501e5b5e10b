#!/usr/bin/env python3
"""Writes assets/stress_room.gltf: the trade study's directionality stress
scene (issue 10). Run from the repository root: python3 tools/make_stress.py

A white room 600 x 400 x 600 (open at the front like the Cornell box, a
green left wall, a white block on the floor) lit by one small
60 x 60 emitter on the left wall, facing +x, with a sharp cos^300 profile
(material extras.cosn): its light lands on a spot of the right wall, and
everything else the camera sees (floor, ceiling, back wall, block) is lit by
interreflection. Classic photon tracing spends its whole primary budget on
that spot; the adaptive mode's alpha_D cuts the primaries and splits at the
first diffuse hit."""
import math

import gltf_build

W, H, D = 600.0, 400.0, 600.0
QUADS = {
    "floor": ("white", [(W, 0, 0), (0, 0, 0), (0, 0, D), (W, 0, D)]),
    "ceiling": ("white", [(W, H, 0), (W, H, D), (0, H, D), (0, H, 0)]),
    "back_wall": ("white", [(W, 0, D), (0, 0, D), (0, H, D), (W, H, D)]),
    "left_wall": ("green", [(0, 0, D), (0, 0, 0), (0, H, 0), (0, H, D)]),
    "right_wall": ("white", [(W, 0, 0), (W, 0, D), (W, H, D), (W, H, 0)]),
    # 1 unit off the left wall, normal +x ((b - a) x (c - a)).
    "light": ("light", [(1, 270, 270), (1, 330, 270), (1, 330, 330), (1, 270, 330)]),
}
# A 150-unit cube on the floor, towards the back.
X0, X1, Z0, Z1, T = 300.0, 450.0, 330.0, 480.0, 150.0
BLOCK = [
    [(X0, T, Z0), (X0, T, Z1), (X1, T, Z1), (X1, T, Z0)],
    [(X0, 0, Z0), (X0, T, Z0), (X1, T, Z0), (X1, 0, Z0)],
    [(X1, 0, Z0), (X1, T, Z0), (X1, T, Z1), (X1, 0, Z1)],
    [(X1, 0, Z1), (X1, T, Z1), (X0, T, Z1), (X0, 0, Z1)],
    [(X0, 0, Z1), (X0, T, Z1), (X0, T, Z0), (X0, 0, Z0)],
]
COSN = 300.0
MATERIALS = [
    {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.75, 0.75, 0.75, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.63, 0.065, 0.05, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "green", "pbrMetallicRoughness": {"baseColorFactor": [0.14, 0.45, 0.091, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "light", "pbrMetallicRoughness": {"baseColorFactor": [0.78, 0.78, 0.78, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "emissiveFactor": [1.0, 0.9, 0.8],
     "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6000.0}},
     "extras": {"cosn": COSN}},
]
MAT_INDEX = {m["name"]: i for i, m in enumerate(MATERIALS)}


def main():
    meshes = [(name, mat, [quad]) for name, (mat, quad) in QUADS.items()]
    meshes.append(("block", "white", BLOCK))
    b = gltf_build.Builder()
    for name, mat, quads in meshes:
        b.quad_mesh(name, quads, MAT_INDEX[mat])
    # glTF cameras look down their local -z: half a turn about y looks along +z.
    b.nodes.append({"name": "camera", "camera": 0, "translation": [W / 2, H / 2, -700.0], "rotation": [0.0, 1.0, 0.0, 0.0]})
    camera = {"yfov": math.radians(45.0), "aspectRatio": 1.0, "znear": 1.0}
    doc = b.document("tools/make_stress.py", "stress_room", MATERIALS, camera, ["KHR_materials_emissive_strength"])
    gltf_build.write("assets/stress_room.gltf", doc)


if __name__ == "__main__":
    main()
