#!/usr/bin/env python3
"""Writes the small test scenes of this folder. Run from it: `python3 make.py`.

sun_floor.gltf: a 2 x 2 white floor (y = 0, facing +y), a 0.4 x 0.4 emissive
panel at y = 1.5 facing down, and a Sun (KHR_lights_punctual directional,
irradiance (2, 1.9, 1.8)) shining 30 degrees from the vertical, towards -z.
The panel's sun shadow on the floor is the square x in [-0.2, 0.2],
z in [0.1 - 1.5 tan 30, 0.5 - 1.5 tan 30]. Buffers in a data URI.
tests/library/directional_light.rs asserts these numbers.
"""
import base64, json, math, struct

floor = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
lamp = [(-0.2, 1.5, 0.1), (0.2, 1.5, 0.1), (0.2, 1.5, 0.5), (-0.2, 1.5, 0.5)]
floor_idx = [0, 3, 2, 0, 2, 1]  # faces +y
lamp_idx = [0, 2, 3, 0, 1, 2]  # faces -y


def f32s(points):
    return b"".join(struct.pack("<3f", *p) for p in points)


def u16s(idx):
    return struct.pack("<%dH" % len(idx), *idx)


buf = f32s(floor) + f32s(lamp) + u16s(floor_idx) + u16s(lamp_idx)


def bounds(points):
    return [min(p[i] for p in points) for i in range(3)], [max(p[i] for p in points) for i in range(3)]


def quat_x(degrees):
    h = math.radians(degrees) / 2
    return [math.sin(h), 0.0, 0.0, math.cos(h)]


def position_accessor(name, view, points):
    lo, hi = bounds(points)
    return {"name": name, "bufferView": view, "componentType": 5126, "count": 4,
            "type": "VEC3", "min": lo, "max": hi}


doc = {
    "asset": {"version": "2.0", "generator": "tests/scenes/make.py"},
    "extensionsUsed": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "sun", "type": "directional", "color": [1.0, 0.95, 0.9], "intensity": 2.0},
    ]}},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2, 3]}],
    "nodes": [
        # -Z turned -60 degrees about x: (0, -cos 30, -sin 30).
        {"name": "sun", "rotation": quat_x(-60), "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "floor", "mesh": 0},
        {"name": "lamp", "mesh": 1},
        {"name": "eye", "camera": 0, "translation": [0, 1.2, 3.2], "rotation": quat_x(-20)},
    ],
    "meshes": [
        {"name": "floor", "primitives": [{"attributes": {"POSITION": 0}, "indices": 2, "material": 0}]},
        {"name": "lamp", "primitives": [{"attributes": {"POSITION": 1}, "indices": 3, "material": 1}]},
    ],
    "materials": [
        {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}},
        {"name": "panel", "emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 1}},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
    "accessors": [
        position_accessor("floor positions", 0, floor),
        position_accessor("lamp positions", 1, lamp),
        {"name": "floor indices", "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        {"name": "lamp indices", "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
    ],
    "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": 48, "target": 34962},
        {"buffer": 0, "byteOffset": 48, "byteLength": 48, "target": 34962},
        {"buffer": 0, "byteOffset": 96, "byteLength": 12, "target": 34963},
        {"buffer": 0, "byteOffset": 108, "byteLength": 12, "target": 34963},
    ],
    "buffers": [{"byteLength": len(buf),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}],
}

with open("sun_floor.gltf", "w") as f:
    json.dump(doc, f, indent=1)
    f.write("\n")
