#!/usr/bin/env python3
"""Writes assets/cornell_box.gltf: the Cornell Program of Computer Graphics'
measured Cornell box (both blocks, the 130 x 105 ceiling light) as glTF 2.0 with
an embedded buffer. Run from the repository root: python3 tools/make_cornell.py

With --empty it writes assets/cornell_empty.gltf instead: the same five walls,
light, albedos and camera without the blocks (12 triangles), the paper's test
scene (§3.2: "une source lumineuse et des parois idéalement diffuses").

With --glass it writes assets/cornell_glass.gltf: the empty box and two spheres
of radius 100 standing on the floor, a mirror (metallic 1, roughness 0) at
(370, 100, 350) and a smooth glass ball (KHR_materials_transmission 1,
KHR_materials_ior 1.5, KHR_materials_volume thicknessFactor 200: a refracting
volume, no absorption) at (185, 100, 170). Both are one icosphere of 20480
triangles (an icosahedron with a vertex at each pole, subdivided 5 times) with
its vertices on the sphere, per-vertex normals and outward (counter-clockwise
from outside) winding, placed by its node's translation; the two meshes share
its accessors.

The light sits 0.1 below the ceiling (y = 548.7) so the two never coincide,
and faces down. The cos^n exponent of the light is the material's
extras.cosn (0 = diffuse)."""
import math, struct, sys

import gltf_build

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
SPHERE_RADIUS = 100.0
SPHERE_LEVELS = 5
# (name, material, centre); the materials follow MATERIALS in the glass scene.
SPHERES = [
    ("mirror_sphere", {"name": "mirror", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0}},
     (370.0, SPHERE_RADIUS, 350.0)),
    ("glass_sphere", {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0},
                      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                                     "KHR_materials_ior": {"ior": 1.5},
                                     "KHR_materials_volume": {"thicknessFactor": 2.0 * SPHERE_RADIUS}}},
     (185.0, SPHERE_RADIUS, 170.0)),
]


def icosphere(levels):
    """Unit vectors and outward-wound triangles of an icosahedron with a vertex
    at each pole (so a sphere on the floor touches it), each triangle split
    into four `levels` times, new vertices pushed onto the sphere."""
    ring = 1.0 / math.sqrt(5.0)
    verts = [(0.0, 1.0, 0.0)]
    for k in range(5):
        a = 2.0 * math.pi * k / 5.0
        verts.append((2.0 * ring * math.cos(a), ring, 2.0 * ring * math.sin(a)))
    for k in range(5):
        a = 2.0 * math.pi * (k + 0.5) / 5.0
        verts.append((2.0 * ring * math.cos(a), -ring, 2.0 * ring * math.sin(a)))
    verts.append((0.0, -1.0, 0.0))
    up = lambda k: 1 + k % 5
    low = lambda k: 6 + k % 5
    tris = []
    for k in range(5):
        tris += [(0, up(k), up(k + 1)), (up(k), low(k), up(k + 1)),
                 (up(k + 1), low(k), low(k + 1)), (11, low(k + 1), low(k))]

    def outward(t):
        a, b, c = (verts[i] for i in t)
        e1 = [b[i] - a[i] for i in range(3)]
        e2 = [c[i] - a[i] for i in range(3)]
        n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        centroid = [a[i] + b[i] + c[i] for i in range(3)]
        return sum(n[i] * centroid[i] for i in range(3)) > 0.0

    # Wind every face counter-clockwise seen from outside; splitting keeps it.
    tris = [t if outward(t) else (t[0], t[2], t[1]) for t in tris]
    for _ in range(levels):
        mid = {}

        def midpoint(i, j):
            key = (min(i, j), max(i, j))
            if key not in mid:
                p = [verts[i][k] + verts[j][k] for k in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                verts.append(tuple(x / n for x in p))
                mid[key] = len(verts) - 1
            return mid[key]

        split = []
        for a, b, c in tris:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        tris = split
    assert all(outward(t) for t in tris)
    return verts, tris


def add_sphere_meshes(b, materials):
    """The SPHERES: one icosphere's positions, normals and indices, shared by
    one mesh per sphere (its own material), each placed by its node."""
    verts, tris = icosphere(SPHERE_LEVELS)
    pos = [struct.unpack("<3f", struct.pack("<3f", *(SPHERE_RADIUS * x for x in v))) for v in verts]
    attributes = {"POSITION": b.vec3(pos, bounds=True), "NORMAL": b.vec3(verts)}
    indices = b.triangles(tris)
    for name, material, centre in SPHERES:
        materials.append(material)
        b.mesh(name, attributes, indices, len(materials) - 1, translation=list(centre))


def main():
    glass = "--glass" in sys.argv[1:]
    empty = glass or "--empty" in sys.argv[1:]
    meshes = [(name, mat, [quad]) for name, (mat, quad) in QUADS.items()]
    if not empty:
        meshes += [(name, "white", quads) for name, quads in BLOCKS.items()]
    materials = list(MATERIALS)
    b = gltf_build.Builder()
    for name, mat, quads in meshes:
        b.quad_mesh(name, quads, MAT_INDEX[mat])
    if glass:
        add_sphere_meshes(b, materials)
    # glTF cameras look down their local -z: turn half a turn about y to look along +z.
    b.nodes.append({"name": "camera", "camera": 0, "translation": [278.0, 273.0, -800.0], "rotation": [0.0, 1.0, 0.0, 0.0]})
    name = "cornell_glass" if glass else "cornell_empty" if empty else "cornell_box"
    extensions = ["KHR_materials_emissive_strength"] + (["KHR_materials_ior", "KHR_materials_transmission", "KHR_materials_volume"] if glass else [])
    camera = {"yfov": math.radians(39.3077), "aspectRatio": 1.0, "znear": 1.0}
    doc = b.document("tools/make_cornell.py", name, materials, camera, extensions)
    gltf_build.write("assets/" + name + ".gltf", doc)


if __name__ == "__main__":
    main()
