#!/usr/bin/env python3
"""Writes assets/door.gltf: Veach's door scene (issue 27), two rooms joined by
a door left ajar, the only light in the room the camera does not see. Run
from the repository root: python3 tools/make_door.py

Units are centimetres (1 unit = 1 cm), so the rooms are sized like real ones:
- room A (the camera's) spans x in [0, 400], room B (the light's) x in
  [415, 815]; both z in [0, 400], floor at y = 0, ceiling at y = 260;
- between them a 15 cm partition wall with a doorway 90 wide and 210 high
  (z in [150, 240]);
- the door, a 4 cm slab 98 wide and 215 high (4 cm wider than the doorway
  on each side), is hinged on room B's side at the doorway's edge (x = 415, z = 150) and turned into room B by
  asin(10 / 90) = 6.38 degrees, so the narrowest passage between its face
  and the far jamb (415, 240) is 10 cm: light passes only through that gap.
  Its hinge side, top and bottom reach into the wall and the floor, so no
  crack of another kind lets light by;
- one 80 x 80 ceiling panel in room B (x in [575, 655], z in [280, 360],
  0.1 below the ceiling, facing down) is the only light: on the far side
  of the gap from the door's face, so its direct light streams through the
  gap onto room A's floor.

Every wall, the floor, the ceiling and the door are closed boxes of real
thickness (10 cm for the outer shell): a photon renderer's zero-thickness
walls leak light. Boxes overlap where they meet (a face inside another box is
never reached), so no two faces coincide. Materials are diffuse glTF
metallicRoughness (metallic 0, roughness 1). The camera stands in room A and
looks at the door and the floor and jamb that the gap lights."""
import math

import gltf_build

W = 400.0        # room width (z) and depth (x)
H = 260.0        # ceiling height
T = 10.0         # outer shell thickness
WALL_X0, WALL_X1 = 400.0, 415.0   # the partition
DOOR_Z0, DOOR_Z1, DOOR_H = 150.0, 240.0, 210.0   # the doorway
B_X1 = WALL_X1 + W                # room B's far wall
GAP = 10.0
DOOR_ANGLE = math.asin(GAP / (DOOR_Z1 - DOOR_Z0))
DOOR_THICK, DOOR_WIDE, DOOR_TOP, DOOR_SINK, DOOR_OVERLAP = 4.0, 98.0, 215.0, 1.0, 4.0
LIGHT = (575.0, 655.0, 280.0, 360.0)   # x0, x1, z0, z1 of the ceiling panel
EMISSIVE_STRENGTH = 400.0

# (name, material, [x0, x1], [y0, y1], [z0, z1]): axis-aligned boxes.
BOXES = [
    ("floor", "floor", (-T, B_X1 + T), (-T, 0.0), (-T, W + T)),
    ("ceiling", "white", (-T, B_X1 + T), (H, H + T), (-T, W + T)),
    ("wall_a_back", "white", (-T, 0.0), (-T, H + T), (-T, W + T)),
    ("wall_b_back", "white", (B_X1, B_X1 + T), (-T, H + T), (-T, W + T)),
    ("wall_left", "blue", (-T, B_X1 + T), (-T, H + T), (-T, 0.0)),
    ("wall_right", "white", (-T, B_X1 + T), (-T, H + T), (W, W + T)),
    # The partition in three boxes around the doorway, sunk into floor and ceiling.
    ("partition_left", "white", (WALL_X0, WALL_X1), (-1.0, H + 1.0), (-1.0, DOOR_Z0)),
    ("partition_right", "white", (WALL_X0, WALL_X1), (-1.0, H + 1.0), (DOOR_Z1, W + 1.0)),
    ("lintel", "white", (WALL_X0, WALL_X1), (DOOR_H, H + 1.0), (DOOR_Z0 - 1.0, DOOR_Z1 + 1.0)),
]
MATERIALS = [
    {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.75, 0.75, 0.75, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.55, 0.5, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "blue", "pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.35, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "door", "pbrMetallicRoughness": {"baseColorFactor": [0.55, 0.38, 0.25, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "light", "pbrMetallicRoughness": {"baseColorFactor": [0.78, 0.78, 0.78, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "emissiveFactor": [1.0, 0.85, 0.65],
     "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": EMISSIVE_STRENGTH}},
     "extras": {"cosn": 0.0}},
]
MAT_INDEX = {m["name"]: i for i, m in enumerate(MATERIALS)}


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def normalize(a):
    n = math.sqrt(dot(a, a))
    return tuple(x / n for x in a)


def box_quads(xs, ys, zs, place=lambda p: p):
    """The six faces of a box as quads wound counter-clockwise seen from
    outside (glTF's front side), each corner moved by `place`."""
    corner = lambda i, j, k: (xs[i], ys[j], zs[k])
    faces = [
        [corner(1, 0, 0), corner(1, 1, 0), corner(1, 1, 1), corner(1, 0, 1)],  # +x
        [corner(0, 0, 1), corner(0, 1, 1), corner(0, 1, 0), corner(0, 0, 0)],  # -x
        [corner(0, 1, 0), corner(0, 1, 1), corner(1, 1, 1), corner(1, 1, 0)],  # +y
        [corner(0, 0, 0), corner(1, 0, 0), corner(1, 0, 1), corner(0, 0, 1)],  # -y
        [corner(0, 0, 1), corner(1, 0, 1), corner(1, 1, 1), corner(0, 1, 1)],  # +z
        [corner(0, 1, 0), corner(1, 1, 0), corner(1, 0, 0), corner(0, 0, 0)],  # -z
    ]
    centre = tuple((a[0] + a[1]) / 2 for a in (xs, ys, zs))
    for q in faces:
        n = cross(sub(q[1], q[0]), sub(q[2], q[0]))
        mid = tuple(sum(v[i] for v in q) / 4 for i in range(3))
        assert dot(n, sub(mid, centre)) > 0, "box face wound inwards"
    return [[place(v) for v in q] for q in faces]


def door_quads():
    """The door: a box in its closed place (on room B's face of the wall,
    its hinge side 4 cm past the hinge into the wall, sunk 1 cm into the
    floor), turned about the vertical hinge axis at (x, z) = (415, 150) so its
    free edge swings into room B."""
    xs = (WALL_X1, WALL_X1 + DOOR_THICK)
    zs = (DOOR_Z0 - DOOR_OVERLAP, DOOR_Z0 - DOOR_OVERLAP + DOOR_WIDE)
    c, s = math.cos(DOOR_ANGLE), math.sin(DOOR_ANGLE)

    def turn(p):
        dx, dz = p[0] - WALL_X1, p[2] - DOOR_Z0
        # z towards +x: the free edge (dz > 0) moves into room B.
        return (WALL_X1 + dx * c + dz * s, p[1], DOOR_Z0 - dx * s + dz * c)

    return box_quads(xs, (-DOOR_SINK, DOOR_TOP), zs, turn)


def light_quad():
    x0, x1, z0, z1 = LIGHT
    y = H - 0.1
    q = [(x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1)]
    n = cross(sub(q[1], q[0]), sub(q[2], q[0]))
    assert n[1] < 0, "the light faces down"
    return [q]


def look_at(eye, target):
    """A glTF node rotation (x, y, z, w) whose camera (looking down its local
    -z, +y up) looks from `eye` at `target`."""
    f = normalize(sub(target, eye))
    r = normalize(cross(f, (0.0, 1.0, 0.0)))
    u = cross(r, f)
    # Columns of the rotation: local x -> r, y -> u, z -> -f.
    m = [[r[0], u[0], -f[0]], [r[1], u[1], -f[1]], [r[2], u[2], -f[2]]]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        return [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
    i = max(range(3), key=lambda k: m[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(1.0 + m[i][i] - m[j][j] - m[k][k]) * 2
    q = [0.0, 0.0, 0.0, (m[k][j] - m[j][k]) / s]
    q[i] = 0.25 * s
    q[j] = (m[j][i] + m[i][j]) / s
    q[k] = (m[k][i] + m[i][k]) / s
    return q


CAMERA_EYE = (40.0, 150.0, 330.0)
CAMERA_TARGET = (400.0, 60.0, 200.0)


def meshes():
    """(name, material, quads) of every mesh: one per box, the door, the light."""
    out = [(name, mat, box_quads(xs, ys, zs)) for name, mat, xs, ys, zs in BOXES]
    out.append(("door", "door", door_quads()))
    out.append(("light", "light", light_quad()))
    return out


def main():
    b = gltf_build.Builder()
    for name, mat, quads in meshes():
        b.quad_mesh(name, quads, MAT_INDEX[mat], round_bounds=True)
    b.nodes.append({"name": "camera", "camera": 0, "translation": list(CAMERA_EYE), "rotation": look_at(CAMERA_EYE, CAMERA_TARGET)})
    camera = {"yfov": math.radians(60.0), "aspectRatio": 1.0, "znear": 1.0}
    doc = b.document("tools/make_door.py", "door", MATERIALS, camera, ["KHR_materials_emissive_strength"])
    gltf_build.write("assets/door.gltf", doc)


if __name__ == "__main__":
    main()
