#!/usr/bin/env python3
"""Writes assets/velvet.gltf: cloth under KHR_materials_sheen, for the loader,
the renderer and the tests. Run from the repository root:
python3 tools/make_velvet.py

An open-fronted room (4 x 2.5 x 4 m, floor at y = 0, camera outside looking
+z and 12 degrees down, so that the floor and the spheres' rims are seen at grazing
angles, where a sheen shows):
- a carpet floor: a grey rough base under a pale sheen of roughness 0.6;
- a red velvet sphere: a dark red rough base under a pink sheen of
  roughness 0.3 (smooth shading, per-vertex NORMALs);
- a black velvet sphere: a black base under a white sheen of roughness 0.5
  (all it reflects is the sheen);
- a lacquered cushion: a blue base under a sheen of roughness 0.8 and a
  clear coat (KHR_materials_clearcoat 0.5, roughness 0.2) over both;
- plain white walls and a diffuse ceiling panel (cosn 0), facing down."""
import math

import gltf_build

from make_gallery import add_meshes, box, quad, sphere  # tools/ is first on sys.path

W, H, D = 2.0, 2.5, 2.0  # half-width, height, half-depth
RED_CENTRE = (-0.8, 0.5, 0.3)
BLACK_CENTRE = (0.75, 0.45, 0.6)


def sheen(color, roughness):
    return {"KHR_materials_sheen": {"sheenColorFactor": color, "sheenRoughnessFactor": roughness}}


MATERIALS = [
    {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.75, 0.75, 0.73, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "carpet", "pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.3, 0.32, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "extensions": sheen([0.6, 0.6, 0.55], 0.6)},
    {"name": "red_velvet", "pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.02, 0.04, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "extensions": sheen([1.0, 0.35, 0.45], 0.3)},
    {"name": "black_velvet", "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "extensions": sheen([0.9, 0.9, 0.9], 0.5)},
    {"name": "lacquered_cushion", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.15, 0.5, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7},
     "extensions": {**sheen([0.5, 0.6, 1.0], 0.8),
                    "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessFactor": 0.2}}},
    {"name": "panel", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "emissiveFactor": [1.0, 0.95, 0.88], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6.0}},
     "extras": {"cosn": 0.0}},
]
MAT = {m["name"]: i for i, m in enumerate(MATERIALS)}

# Meshes shaded with per-vertex normals: the centre of each sphere.
SMOOTH = {"red_velvet_sphere": RED_CENTRE, "black_velvet_sphere": BLACK_CENTRE}


def main():
    meshes = [
        ("floor", "carpet", *quad((-W, 0, -D), (-W, 0, D), (W, 0, D), (W, 0, -D))),
        ("ceiling", "white", *quad((-W, H, -D), (W, H, -D), (W, H, D), (-W, H, D))),
        ("back_wall", "white", *quad((-W, 0, D), (-W, H, D), (W, H, D), (W, 0, D))),
        ("left_wall", "white", *quad((W, 0, -D), (W, 0, D), (W, H, D), (W, H, -D))),
        ("right_wall", "white", *quad((-W, 0, -D), (-W, H, -D), (-W, H, D), (-W, 0, D))),
        # A centimetre under the ceiling, winding facing down.
        ("panel", "panel", *quad((-0.5, H - 0.01, -0.2), (0.5, H - 0.01, -0.2), (0.5, H - 0.01, 0.8), (-0.5, H - 0.01, 0.8))),
        ("red_velvet_sphere", "red_velvet", *sphere(RED_CENTRE, 0.5)),
        ("black_velvet_sphere", "black_velvet", *sphere(BLACK_CENTRE, 0.45)),
        ("cushion", "lacquered_cushion", *box(-0.3, 0.5, 0.0, 0.3, -0.9, -0.2, 0.3)),
    ]
    b = gltf_build.Builder()
    add_meshes(b, meshes, MAT, SMOOTH)
    # Outside the open front, 1.2 m up, looking 12 degrees down.
    tilt = math.radians(12.0)
    b.nodes.append({"name": "camera", "camera": 0, "translation": [0.0, 1.2, -3.6],
                    "rotation": [0.0, math.cos(tilt / 2), math.sin(tilt / 2), 0.0]})
    extensions_used = ["KHR_materials_emissive_strength", "KHR_materials_sheen", "KHR_materials_clearcoat"]
    camera = {"yfov": math.radians(46.0), "aspectRatio": 1.0, "znear": 0.01}
    doc = b.document("tools/make_velvet.py", "velvet", MATERIALS, camera, extensions_used, None)
    gltf_build.write("assets/velvet.gltf", doc)


if __name__ == "__main__":
    main()
