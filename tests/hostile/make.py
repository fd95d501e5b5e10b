#!/usr/bin/env python3
"""Writes the hostile glTF regression files of tests/hostile.rs (issue 12).

Each file is a small valid scene (`base.gltf`: a floor quad lit by an
emissive quad, buffer in a data URI) with one hostile change. Run from this
folder: `python3 make.py`. The expected error of each file is asserted in
tests/hostile.rs; fuzzer crash inputs are kept beside them as they are.
"""
import base64, copy, json, struct

pos = [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)]
pos_bytes = b"".join(struct.pack("<3f", *p) for p in pos)
idx_bytes = struct.pack("<6H", 0, 2, 1, 0, 3, 2) + b"\0\0"  # floor faces +y
buf = pos_bytes + idx_bytes  # 48 + 14 bytes


def data_uri(b):
    return "data:application/octet-stream;base64," + base64.b64encode(b).decode()


BASE = {
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2]}],
    "nodes": [
        {"name": "floor", "mesh": 0},
        # Light quad at y = 1 facing down (rotated 180 degrees about x).
        {"name": "lamp", "mesh": 1, "translation": [0, 1, 1], "rotation": [1, 0, 0, 0]},
        {"name": "eye", "camera": 0, "translation": [0.5, 0.5, 3]},
    ],
    "meshes": [
        {"name": "floor", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
        {"name": "lamp", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 1}]},
    ],
    "materials": [
        {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}},
        {"name": "light", "emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 1}},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.01}}],
    "accessors": [
        {"name": "pos", "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [0, 0, 0], "max": [1, 0, 1]},
        {"name": "idx", "bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
    ],
    "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": 48},
        {"buffer": 0, "byteOffset": 48, "byteLength": 12},
    ],
    "buffers": [{"byteLength": len(buf), "uri": data_uri(buf)}],
}


def variant(name, change):
    doc = copy.deepcopy(BASE)
    change(doc)
    with open(name + ".gltf", "w") as f:
        json.dump(doc, f, separators=(",", ":"))


def setp(path, value):
    def f(doc):
        o = doc
        for k in path[:-1]:
            o = o[k]
        o[path[-1]] = value
    return f


def seq(*fs):
    def f(doc):
        for g in fs:
            g(doc)
    return f


def spot(cone):
    def f(doc):
        doc["extensionsUsed"] = ["KHR_lights_punctual"]
        doc["extensions"] = {"KHR_lights_punctual": {"lights": [
            {"name": "spot", "type": "spot", "intensity": 10, "spot": {"outerConeAngle": cone}}]}}
        doc["nodes"].append({"name": "spot-node", "extensions": {"KHR_lights_punctual": {"light": 0}},
                             "translation": [0.5, 0.9, 0.5], "scale": [1, 1, 0] if cone > 0 else [1, 1, 1]})
        doc["scenes"][0]["nodes"].append(3)
    return f


def point_at(p):
    def f(doc):
        doc["extensionsUsed"] = ["KHR_lights_punctual"]
        doc["extensions"] = {"KHR_lights_punctual": {"lights": [{"name": "far", "type": "point", "intensity": 1}]}}
        doc["nodes"].append({"name": "far-light", "extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": p})
        doc["scenes"][0]["nodes"].append(3)
    return f


def dag(depth):
    def f(doc):
        # node 3 + i has node 4 + i twice as child: 2^depth instances of the floor.
        base = len(doc["nodes"])
        for i in range(depth):
            doc["nodes"].append({"name": f"level{i}", "children": [base + i + 1, base + i + 1]})
        doc["nodes"].append({"name": "leaf", "mesh": 0})
        doc["scenes"][0]["nodes"].append(base)
    return f


def external(uri):
    return setp(["buffers", 0, "uri"], uri)


if __name__ == "__main__":
    variant("base", lambda d: None)
    # Panics inside the gltf crate.
    variant("position_accessor_99", setp(["meshes", 0, "primitives", 0, "attributes", "POSITION"], 99))
    variant("index_accessor_float", setp(["accessors", 1, "componentType"], 5126))
    variant("byte_stride_4_on_vec3", setp(["bufferViews", 0, "byteStride"], 4))
    variant("camera_perspective_without_object", seq(
        setp(["cameras", 0], {"type": "perspective", "orthographic": {"xmag": 1, "ymag": 1, "zfar": 10, "znear": 0.1}})))
    variant("camera_orthographic_without_object", setp(["cameras", 0, "type"], "orthographic"))
    variant("mesh_index_out_of_range", setp(["nodes", 0, "mesh"], 7))
    # Embree aborts: coordinates beyond its range, NaN directions.
    variant("vertex_at_1e20", setp(["nodes", 0, "translation"], [1e20, 0, 0]))
    variant("point_light_at_1e20", point_at([0, 1e20, 0]))
    variant("camera_at_1e20", setp(["nodes", 2, "translation"], [0, 0, 1e20]))
    variant("spot_light_scale_0", spot(0.5))
    variant("transform_overflow", setp(["nodes", 0, "scale"], [3e38, 3e38, 3e38]))
    # Hangs and unbounded memory.
    variant("node_cycle_self", setp(["nodes", 0, "children"], [0]))
    variant("node_cycle_ab", seq(setp(["nodes", 0, "children"], [1]), setp(["nodes", 1, "children"], [0])))
    variant("node_dag_40_levels", dag(40))
    variant("sparse_count_2p31", setp(["accessors", 0], {
        "name": "sparse", "componentType": 5126, "count": 2**31, "type": "VEC3",
        "sparse": {"count": 2**31, "indices": {"bufferView": 1, "componentType": 5125},
                   "values": {"bufferView": 0}}}))
    variant("accessor_count_huge", setp(["accessors", 0, "count"], 2**40))
    variant("buffer_uri_dev_zero", external("/dev/zero"))
    variant("buffer_byte_length_2p40", seq(external("/dev/zero"), setp(["buffers", 0, "byteLength"], 2**40)))
    variant("buffer_uri_fifo", external("fifo.bin"))
    # Reading outside the scene.
    variant("buffer_uri_dotdot_passwd", external("../../../../../../../../etc/passwd"))
    variant("buffer_uri_absolute_passwd", external("/etc/passwd"))
    variant("buffer_uri_file_scheme", external("file:///etc/hostname"))
    variant("buffer_uri_proc_environ", external("/proc/self/environ"))
    variant("buffer_uri_percent_dotdot", external("%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd"))
    # Wrong or misleading messages, silent clamps.
    variant("accessor_past_buffer", setp(["accessors", 0, "count"], 40))
    variant("degenerate_only_mesh", seq(setp(["accessors", 0, "count"], 4),
                                        setp(["nodes", 0, "scale"], [1, 1, 0]),
                                        setp(["nodes", 0, "rotation"], [0.7071068, 0, 0, 0.7071068])))
    variant("spot_cone_0", spot(0.0))
    variant("camera_yfov_0", setp(["cameras", 0, "perspective", "yfov"], 0.0))
