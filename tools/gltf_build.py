"""The glTF writing the scene tools share (tools/make_cornell.py,
make_door.py, make_gallery.py, make_stress.py): one buffer embedded as
base64, an accessor and a buffer view per array, a mesh and a node per
primitive, the document written with one-space indents."""
import base64
import json
import struct

ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
FLOAT, UNSIGNED_INT = 5126, 5125


def float32(x):
    """x as a float32 holds it: the validator wants an accessor's bounds as stored."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def quad_indices(quads):
    """Two triangles a quad (0 1 2, 0 2 3) of 4 vertices each, in order."""
    return [b + o for qi in range(quads) for b in [4 * qi] for o in (0, 1, 2, 0, 2, 3)]


class Builder:
    def __init__(self):
        self.blob = bytearray()
        self.accessors, self.views, self.meshes, self.nodes = [], [], [], []

    def _view(self, data, fmt, size, target):
        off = len(self.blob)
        for item in data:
            self.blob += struct.pack(fmt, *item) if isinstance(item, (tuple, list)) else struct.pack(fmt, item)
        self.views.append({"buffer": 0, "byteOffset": off, "byteLength": size * len(data), "target": target})
        return len(self.views) - 1

    def vec3(self, data, bounds=False, round_bounds=False):
        """An accessor of 3-float vectors, with their min and max if `bounds`
        (rounded to float32 if `round_bounds`)."""
        acc = {"bufferView": self._view(data, "<3f", 12, ARRAY_BUFFER), "componentType": FLOAT, "count": len(data), "type": "VEC3"}
        if bounds:
            r = float32 if round_bounds else (lambda x: x)
            acc["min"] = [r(min(v[i] for v in data)) for i in range(3)]
            acc["max"] = [r(max(v[i] for v in data)) for i in range(3)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, flat):
        """An accessor of 32-bit vertex indices."""
        view = self._view(flat, "<I", 4, ELEMENT_ARRAY_BUFFER)
        self.accessors.append({"bufferView": view, "componentType": UNSIGNED_INT, "count": len(flat), "type": "SCALAR"})
        return len(self.accessors) - 1

    def triangles(self, tris):
        """An accessor of triangles' vertex indices, three a triangle."""
        view = self._view(tris, "<3I", 12, ELEMENT_ARRAY_BUFFER)
        self.accessors.append({"bufferView": view, "componentType": UNSIGNED_INT, "count": 3 * len(tris), "type": "SCALAR"})
        return len(self.accessors) - 1

    def mesh(self, name, attributes, indices, material, **node):
        """A mesh of one primitive and the node that holds it."""
        self.meshes.append({"name": name, "primitives": [{"attributes": attributes, "indices": indices, "material": material}]})
        self.nodes.append({"name": name, "mesh": len(self.meshes) - 1, **node})

    def quad_mesh(self, name, quads, material, round_bounds=False):
        """A mesh of quads (4 corners each), two triangles a quad."""
        pos = [tuple(float(c) for c in v) for q in quads for v in q]
        position = self.vec3(pos, bounds=True, round_bounds=round_bounds)
        self.mesh(name, {"POSITION": position}, self.indices(quad_indices(len(quads))), material)

    def document(self, generator, scene, materials, camera, extensions_used, extensions=None):
        """The glTF document of what was added, with one perspective camera
        `camera` (the node that holds it must be added first)."""
        doc = {
            "asset": {"version": "2.0", "generator": "adaptive-pm " + generator},
            "extensionsUsed": extensions_used,
        }
        if extensions is not None:
            doc["extensions"] = extensions
        doc.update({
            "scene": 0,
            "scenes": [{"name": scene, "nodes": list(range(len(self.nodes)))}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": materials,
            "cameras": [{"type": "perspective", "perspective": camera}],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{"byteLength": len(self.blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.blob)).decode()}],
        })
        return doc


def write(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
