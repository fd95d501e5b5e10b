#!/usr/bin/env python3
"""Renders a glTF scene with Mitsuba 3 and compares adaptive-pm's images to it.

An independent check of the renderer's light transport: the same glTF file is
translated into a Mitsuba 3 scene (only what simple test scenes need) and
rendered with Mitsuba's unbiased `path` integrator; OpenEXR images written by
`adaptive-pm render` are then compared with it, pixel for pixel.

    pip install mitsuba numpy
    python3 tools/mitsuba_compare.py assets/cornell_glass.gltf --size 64 \\
        --spp 4096 --passes 8 --out /tmp/mitsuba/mitsuba.exr \\
        --ours /tmp/mitsuba/path_s1.exr /tmp/mitsuba/path_s2.exr --label path

What is read from the glTF file:
- the default scene's nodes, recursively, with their `matrix` or TRS;
- TRIANGLES primitives (POSITION, optional NORMAL, optional indices) from
  embedded (data URI) or external buffers; vertex normals become Mitsuba's
  shading normals;
- materials, without textures, mapped as adaptive-pm reads them:
  * metallic 0, roughness 1: Lambert of albedo baseColorFactor (two-sided);
  * metallic 1, roughness 0: a perfect mirror of reflectance baseColorFactor
    (`conductor`, material `none`, two-sided);
  * KHR_materials_transmission 1, roughness 0: a smooth dielectric of
    KHR_materials_ior (default 1.5) in vacuum; KHR_materials_volume only
    without attenuation;
  * emissiveFactor x KHR_materials_emissive_strength: a diffuse area light
    (one-sided: its counter-clockwise side) whose surface keeps its BSDF, so
    the light reflects like adaptive-pm's;
  anything else is refused rather than approximated;
- the first node carrying a perspective camera: its world transform (glTF
  cameras look down -Z with +Y up and +X to the right), yfov and aspectRatio.

Rendering: `--passes` independent Mitsuba renders of `--spp / --passes`
samples each (seeds `--seed`, `--seed`+1, ...); their average is written to
`--out` and each pass next to it (`NAME.passK.exr`), which `--reference` can
read back instead of rendering again. The per-pass spread gives the standard
error of every mean printed.

Comparison (`--ours`, repeatable; each occurrence is a group of images of the
same settings, e.g. independent seeds, averaged with equal weights):
- per-channel means ours/Mitsuba, over all pixels and over regions: the pixels
  whose primary ray (through the pixel centre) first hits each shape, the
  diffuse pixels shadowed from the light's centroid by each specular shape
  (`shadow_of_X`: where X's caustic falls), and `--region` rectangles;
  a standard error comes from the spread of passes/seeds (when there are two
  or more) and `z` is (ratio - 1) / its standard error;
- relative RMSE after `--block` N x N box downsampling, per pixel and channel,
  sqrt(mean((ours - ref)^2 / (ref^2 + eps))), and the value expected from noise
  alone, sqrt(v_ours + v_ref), where each v is estimated from the difference of
  the image's two halves (first/second half of its passes or seeds);
  blocks holding a pixel that sees an emitter are left out (`nonemitter`)
  and kept (`all`).

Images are arrays of rows, row 0 at the top, in both renderers; `--flip-ours`
is there for images that are not.
"""
import argparse
import base64
import json
import math
import os
import re
import sys
import time

import numpy as np

COMPONENT_TYPES = {
    5120: np.int8, 5121: np.uint8, 5122: np.int16,
    5123: np.uint16, 5125: np.uint32, 5126: np.float32,
}
TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
MODE_TRIANGLES = 4


# --------------------------------------------------------------------- glTF

class Unsupported(Exception):
    """A glTF feature this checker does not translate."""


class Gltf:
    """The parts of a glTF 2.0 file (.gltf, JSON) a test scene needs."""

    def __init__(self, path):
        self.path = path
        self.folder = os.path.dirname(os.path.abspath(path))
        with open(path, "rb") as f:
            head = f.read(4)
        if head == b"glTF":
            raise Unsupported("binary .glb files: use the .gltf (JSON) form")
        with open(path, encoding="utf-8") as f:
            self.doc = json.load(f)
        self.buffers = [self._load_buffer(b) for b in self.doc.get("buffers", [])]

    def _load_buffer(self, buf):
        uri = buf["uri"]
        if uri.startswith("data:"):
            data = base64.b64decode(uri.split(",", 1)[1])
        else:
            with open(os.path.join(self.folder, uri), "rb") as f:
                data = f.read()
        return data[: buf["byteLength"]]

    def accessor(self, index):
        """Accessor `index` as an array of shape (count, components)."""
        acc = self.doc["accessors"][index]
        if "sparse" in acc:
            raise Unsupported("sparse accessors")
        dtype = np.dtype(COMPONENT_TYPES[acc["componentType"]]).newbyteorder("<")
        ncomp = TYPE_SIZES[acc["type"]]
        count = acc["count"]
        if "bufferView" not in acc:
            return np.zeros((count, ncomp), dtype)
        view = self.doc["bufferViews"][acc["bufferView"]]
        data = self.buffers[view["buffer"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        elem = dtype.itemsize * ncomp
        stride = view.get("byteStride", elem)
        raw = np.frombuffer(data, np.uint8, count=(count - 1) * stride + elem, offset=start)
        rows = np.lib.stride_tricks.as_strided(raw, (count, elem), (stride, 1))
        out = np.ascontiguousarray(rows).view(dtype).reshape(count, ncomp)
        if acc.get("normalized"):
            raise Unsupported("normalized accessors")
        return out

    @staticmethod
    def local_matrix(node):
        """A node's local transform, 4 x 4, column vectors."""
        if "matrix" in node:
            return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
        t = np.eye(4)
        t[:3, 3] = node.get("translation", [0.0, 0.0, 0.0])
        x, y, z, w = node.get("rotation", [0.0, 0.0, 0.0, 1.0])
        r = np.eye(4)
        r[:3, :3] = [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
        s = np.diag(list(node.get("scale", [1.0, 1.0, 1.0])) + [1.0])
        return t @ r @ s

    def walk(self):
        """Yields (node index, node, world matrix) over the default scene."""
        scenes = self.doc.get("scenes", [])
        roots = scenes[self.doc.get("scene", 0)]["nodes"] if scenes else []
        stack = [(i, np.eye(4)) for i in reversed(roots)]
        while stack:
            i, parent = stack.pop()
            node = self.doc["nodes"][i]
            world = parent @ self.local_matrix(node)
            yield i, node, world
            for c in reversed(node.get("children", [])):
                stack.append((c, world))

    def primitives(self):
        """World-space triangle meshes: dicts of name, positions (n, 3),
        normals (n, 3) or None, faces (m, 3) and material index."""
        out = []
        for i, node, world in self.walk():
            if "mesh" not in node:
                continue
            mesh = self.doc["meshes"][node["mesh"]]
            lin = world[:3, :3]
            normal_matrix = np.linalg.inv(lin).T
            flip = np.linalg.det(lin) < 0
            for k, prim in enumerate(mesh["primitives"]):
                if prim.get("mode", MODE_TRIANGLES) != MODE_TRIANGLES:
                    raise Unsupported(f"primitive mode {prim['mode']} (only TRIANGLES)")
                if prim.get("targets"):
                    raise Unsupported("morph targets")
                attrs = prim["attributes"]
                pos = self.accessor(attrs["POSITION"]).astype(np.float64)
                pos = pos @ lin.T + world[:3, 3]
                nrm = None
                if "NORMAL" in attrs:
                    nrm = self.accessor(attrs["NORMAL"]).astype(np.float64) @ normal_matrix.T
                    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
                if "indices" in prim:
                    idx = self.accessor(prim["indices"]).astype(np.uint32).reshape(-1, 3)
                else:
                    idx = np.arange(len(pos), dtype=np.uint32).reshape(-1, 3)
                if flip:
                    idx = idx[:, ::-1]
                name = node.get("name") or mesh.get("name") or f"node{i}"
                if len(mesh["primitives"]) > 1:
                    name = f"{name}_{k}"
                out.append(dict(name=name, positions=pos, normals=nrm, faces=idx,
                                material=prim.get("material")))
        return out

    def camera(self):
        """(world matrix, perspective dict) of the first camera node."""
        for _, node, world in self.walk():
            if "camera" in node:
                cam = self.doc["cameras"][node["camera"]]
                if cam.get("type") != "perspective":
                    raise Unsupported(f"{cam.get('type')} cameras")
                return world, cam["perspective"]
        raise Unsupported("a scene without a camera")


def rgb(values):
    return {"type": "rgb", "value": [float(v) for v in values[:3]]}


def material_to_mitsuba(mat):
    """(BSDF dict, emitted radiance or None, kind) of a glTF material."""
    if mat is None:
        raise Unsupported("primitives without a material")
    pbr = mat.get("pbrMetallicRoughness", {})
    ext = mat.get("extensions", {})
    for key in ("baseColorTexture", "metallicRoughnessTexture"):
        if key in pbr:
            raise Unsupported(f"{mat.get('name')}: {key}")
    for key in ("normalTexture", "emissiveTexture", "occlusionTexture"):
        if key in mat:
            raise Unsupported(f"{mat.get('name')}: {key}")
    base = pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
    metallic = pbr.get("metallicFactor", 1.0)
    rough = pbr.get("roughnessFactor", 1.0)
    transmission = ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0)
    name = mat.get("name", "?")
    if transmission > 0.0:
        if transmission != 1.0 or rough != 0.0 or metallic != 0.0:
            raise Unsupported(f"{name}: partial or rough transmission")
        volume = ext.get("KHR_materials_volume", {})
        if math.isfinite(volume.get("attenuationDistance", math.inf)):
            raise Unsupported(f"{name}: volume attenuation")
        if any(c != 1.0 for c in base[:3]):
            raise Unsupported(f"{name}: tinted glass")
        ior = ext.get("KHR_materials_ior", {}).get("ior", 1.5)
        bsdf = {"type": "dielectric", "int_ior": float(ior), "ext_ior": 1.0}
        kind = "dielectric"
    elif metallic == 1.0 and rough == 0.0:
        bsdf = {"type": "twosided", "bsdf": {
            "type": "conductor", "material": "none", "specular_reflectance": rgb(base)}}
        kind = "mirror"
    elif metallic == 0.0 and rough == 1.0:
        bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb(base)}}
        kind = "diffuse"
    else:
        raise Unsupported(f"{name}: metallic {metallic}, roughness {rough}")
    strength = ext.get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
    emission = [c * strength for c in mat.get("emissiveFactor", [0.0, 0.0, 0.0])]
    if not any(c > 0.0 for c in emission):
        emission = None
    elif mat.get("extras", {}).get("cosn", 0.0) != 0.0:
        raise Unsupported(f"{name}: a cos^n light (Mitsuba's area lights are diffuse)")
    return bsdf, emission, kind


def write_ply(path, positions, normals, faces):
    """A binary little-endian PLY of one triangle mesh."""
    n = len(positions)
    props = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else [])
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {n}"]
    header += [f"property float {p}" for p in props]
    header += [f"element face {len(faces)}", "property list uchar uint vertex_indices", "end_header"]
    verts = positions if normals is None else np.hstack([positions, normals])
    face_rec = np.zeros(len(faces), dtype=[("n", "u1"), ("v", "<u4", (3,))])
    face_rec["n"] = 3
    face_rec["v"] = faces
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode("ascii"))
        f.write(verts.astype("<f4").tobytes())
        f.write(face_rec.tobytes())


def shape_id(name, used):
    base = re.sub(r"[^A-Za-z0-9_]", "_", name) or "shape"
    sid, k = base, 1
    while sid in used:
        sid, k = f"{base}_{k}", k + 1
    used.add(sid)
    return sid


def build_scene(gltf, args, width, height, mesh_dir):
    """The Mitsuba scene dict, and per shape id its kind and light data."""
    os.makedirs(mesh_dir, exist_ok=True)
    materials = gltf.doc.get("materials", [])
    scene = {"type": "scene",
             "integrator": {"type": "path", "max_depth": args.max_depth,
                            "rr_depth": args.rr_depth}}
    shapes, used = {}, set()
    for prim in gltf.primitives():
        mat = materials[prim["material"]] if prim["material"] is not None else None
        bsdf, emission, kind = material_to_mitsuba(mat)
        sid = shape_id(prim["name"], used)
        ply = os.path.join(mesh_dir, sid + ".ply")
        write_ply(ply, prim["positions"], prim["normals"], prim["faces"])
        shape = {"type": "ply", "id": sid, "filename": ply, "bsdf": bsdf}
        info = {"kind": kind, "emitter": emission is not None}
        if emission is not None:
            shape["emitter"] = {"type": "area", "radiance": rgb(emission)}
            p = prim["positions"][prim["faces"]]
            areas = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
            info["centroid"] = (p.mean(axis=1) * areas[:, None]).sum(0) / areas.sum()
            info["area"] = float(areas.sum())
        scene[sid] = shape
        shapes[sid] = info

    world, persp = gltf.camera()
    # glTF camera: looks down -Z, +Y up, +X right. Mitsuba camera: looks down
    # +Z, +Y up, +X to the *left*. Both flips together are a rotation.
    axes = world[:3, :3] / np.linalg.norm(world[:3, :3], axis=0)
    to_world = np.eye(4)
    to_world[:3, :3] = axes @ np.diag([-1.0, 1.0, -1.0])
    to_world[:3, 3] = world[:3, 3]
    import mitsuba as mi
    sensor = {
        "type": "perspective",
        "fov_axis": "y",
        "fov": math.degrees(persp["yfov"]),
        "to_world": mi.ScalarTransform4f(to_world.tolist()),
        "sampler": {"type": "independent", "sample_count": 1},
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "pixel_format": "rgb", "rfilter": {"type": "box"}},
    }
    if "znear" in persp:
        sensor["near_clip"] = float(persp["znear"])
    sensor["far_clip"] = float(persp.get("zfar", 1e3 * max(
        np.ptp(np.vstack([p["positions"] for p in gltf.primitives()]), axis=0).max(), 1.0)))
    scene["sensor"] = sensor
    return scene, shapes


# ------------------------------------------------------------------ images

def read_exr(path, flip=""):
    import mitsuba as mi
    bmp = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
    img = np.array(bmp, dtype=np.float64).reshape(bmp.height(), bmp.width(), 3)
    if "y" in flip:
        img = img[::-1]
    if "x" in flip:
        img = img[:, ::-1]
    return img


def write_exr(path, img):
    import mitsuba as mi
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32),
              pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)


def write_png(path, img, exposure=0.0):
    """An sRGB preview: exposure, then clamped (no tone curve)."""
    import mitsuba as mi
    x = np.clip(img * 2.0 ** exposure, 0.0, 1.0).astype(np.float32)
    bmp = mi.Bitmap(np.ascontiguousarray(x), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True).write(path)


def write_ratio_png(path, ours, ref, block, scale, span=0.2):
    """Ours / reference luminance per block: red above 1, blue below, full
    colour at 1 +- span; enlarged `scale` times."""
    lum = np.array([0.2126, 0.7152, 0.0722])
    r = blockify(ours, block) @ lum / np.maximum(blockify(ref, block) @ lum, 1e-12)
    t = np.clip((r - 1.0) / span, -1.0, 1.0)
    img = np.ones(r.shape + (3,))
    img[..., 1] -= np.abs(t)
    img[..., 0] -= np.clip(-t, 0, 1)
    img[..., 2] -= np.clip(t, 0, 1)
    img = np.repeat(np.repeat(img, scale * block, 0), scale * block, 1)
    write_png(path, img)


def blockify(img, n):
    """Box-downsamples an (h, w, ...) array by n x n (edges cropped)."""
    h, w = img.shape[0] // n * n, img.shape[1] // n * n
    x = img[:h, :w]
    return x.reshape(h // n, n, w // n, n, *img.shape[2:]).mean(axis=(1, 3))


# ----------------------------------------------------------------- regions

def primary_regions(scene, shapes, width, height):
    """Masks of the pixels whose centre ray first hits each shape, and of the
    diffuse pixels that a specular shape shadows from the light's centroid."""
    import mitsuba as mi
    sensor = scene.sensors()[0]
    lights = [s for s in shapes.values() if s["emitter"]]
    light = max(lights, key=lambda s: s["area"]) if lights else None
    masks = {sid: np.zeros((height, width), bool) for sid in shapes}
    shadow = {sid: np.zeros((height, width), bool)
              for sid, s in shapes.items() if s["kind"] != "diffuse"}
    for y in range(height):
        for x in range(width):
            ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f((x + 0.5) / width, (y + 0.5) / height),
                                       mi.Point2f(0.5, 0.5))
            si = scene.ray_intersect(ray)
            if not si.is_valid():
                continue
            sid = si.shape.id()
            masks[sid][y, x] = True
            if light is None or shapes[sid]["kind"] != "diffuse":
                continue
            si2 = scene.ray_intersect(si.spawn_ray_to(mi.Point3f(*light["centroid"])))
            if si2.is_valid() and si2.shape.id() in shadow:
                shadow[si2.shape.id()][y, x] = True
    regions = {f"hit:{sid}": m for sid, m in masks.items()}
    regions.update({f"shadow_of:{sid}": m for sid, m in shadow.items()})
    emitter = np.zeros((height, width), bool)
    for sid, s in shapes.items():
        if s["emitter"]:
            emitter |= masks[sid]
    return regions, emitter


def parse_region(text, width, height):
    name, box = text.split("=", 1)
    x0, y0, x1, y1 = (int(v) for v in box.split(","))
    m = np.zeros((height, width), bool)
    m[y0:y1, x0:x1] = True
    return f"rect:{name}", m


# -------------------------------------------------------------- statistics

class ImageSet:
    """Independent images of one setting (passes or seeds): their average,
    and standard errors from their spread."""

    def __init__(self, images):
        self.images = np.stack(images)
        self.mean = self.images.mean(axis=0)
        k = len(images)
        half = k // 2
        self.halves = ((self.images[:half].mean(0), self.images[half:2 * half].mean(0))
                       if k >= 2 else None)

    def region_mean(self, mask):
        """(per-channel mean over mask, its standard error or None)."""
        per = self.images[:, mask].mean(axis=1)  # (k, 3)
        m = per.mean(axis=0)
        k = len(per)
        se = per.std(axis=0, ddof=1) / math.sqrt(k) if k >= 2 else None
        return m, se

    def noise_mse(self, ref_blocked, block, eps, keep):
        """Estimated relative MSE of the average from noise alone: the two
        halves differ by twice the average's variance, in expectation."""
        if self.halves is None:
            return None
        a, b = (blockify(h, block)[keep] for h in self.halves)
        return float(np.mean((a - b) ** 2 / (ref_blocked ** 2 + eps)) / 4.0)


def ratio_stats(o, so, r, sr):
    ratio = o / r
    if so is None or sr is None:
        return ratio, None, None
    se = ratio * np.sqrt((so / o) ** 2 + (sr / r) ** 2)
    return ratio, se, (ratio - 1.0) / se


def rounded(x, nd=5):
    if x is None:
        return None
    if isinstance(x, np.ndarray):
        return [round(float(v), nd) for v in x]
    return round(float(x), nd)


def compare(label, ours, ref, regions, emitter, blocks, eps):
    out = {"label": label, "files": None, "regions": {}, "relrmse": {}}
    for name, mask in regions.items():
        if not mask.any():
            continue
        o, so = ours.region_mean(mask)
        r, sr = ref.region_mean(mask)
        ratio, se, z = ratio_stats(o, so, r, sr)
        out["regions"][name] = {"pixels": int(mask.sum()), "ours": rounded(o),
                                "mitsuba": rounded(r), "ratio": rounded(ratio),
                                "ratio_se": rounded(se), "z": rounded(z, 2)}
    for n in blocks:
        rb = blockify(ref.mean, n)
        ob = blockify(ours.mean, n)
        nonemitter = ~(blockify(emitter.astype(float), n) > 0)
        entry = {}
        for part, keep in (("all", np.ones_like(nonemitter)), ("nonemitter", nonemitter)):
            rel = math.sqrt(float(np.mean((ob[keep] - rb[keep]) ** 2 / (rb[keep] ** 2 + eps))))
            vo = ours.noise_mse(rb[keep], n, eps, keep)
            vr = ref.noise_mse(rb[keep], n, eps, keep)
            expected = math.sqrt(vo + vr) if vo is not None and vr is not None else None
            excess = (math.sqrt(max(rel ** 2 - expected ** 2, 0.0))
                      if expected is not None else None)
            entry[part] = {"relrmse": rounded(rel), "expected_from_noise": rounded(expected),
                           "excess": rounded(excess)}
        out["relrmse"][f"{n}x{n}"] = entry
    return out


def print_summary(report):
    """A short table of the report on stderr (the JSON goes to stdout)."""
    def fmt(v, nd=4):
        return "-" if v is None else " ".join(f"{x:.{nd}f}" for x in v)
    m = report["mitsuba"]
    print(f"mitsuba mean RGB {fmt(m['mean'])} (se {fmt(m['mean_se'])})", file=sys.stderr)
    for c in report.get("comparisons", []):
        print(f"== {c['label']} ({len(c['files'])} images)", file=sys.stderr)
        print(f"  {'region':28s} {'px':>5s}  {'ratio ours/mitsuba RGB':22s}  {'se':20s}  z",
              file=sys.stderr)
        for name, r in c["regions"].items():
            z = "-" if r["z"] is None else " ".join(f"{x:+.1f}" for x in r["z"])
            print(f"  {name:28s} {r['pixels']:5d}  {fmt(r['ratio'])}  {fmt(r['ratio_se'])}  {z}",
                  file=sys.stderr)
        for b, e in c["relrmse"].items():
            for part, v in e.items():
                print(f"  relRMSE {b:5s} {part:10s} {v['relrmse']:.4f}"
                      f" (from noise {fmt([v['expected_from_noise']]) if v['expected_from_noise'] is not None else '-'}"
                      f", excess {fmt([v['excess']]) if v['excess'] is not None else '-'})",
                      file=sys.stderr)


# --------------------------------------------------------------------- main

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("scene", help="glTF 2.0 file (.gltf)")
    ap.add_argument("--size", type=int, default=64,
                    help="image height in pixels; width from the camera's aspect (default 64)")
    ap.add_argument("--width", type=int, help="image width (overrides --size's)")
    ap.add_argument("--height", type=int, help="image height (overrides --size)")
    ap.add_argument("--spp", type=int, default=1024, help="Mitsuba samples per pixel, all passes")
    ap.add_argument("--passes", type=int, default=4,
                    help="independent Mitsuba renders splitting --spp (2+ for error bars)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the first pass")
    ap.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant (default scalar_rgb)")
    ap.add_argument("--max-depth", type=int, default=-1, help="Mitsuba path max_depth (-1: none)")
    ap.add_argument("--rr-depth", type=int, default=5, help="Mitsuba path rr_depth")
    ap.add_argument("--out", default="mitsuba.exr", help="Mitsuba's average image (OpenEXR)")
    ap.add_argument("--mesh-dir", help="folder for the PLY meshes (default: next to --out)")
    ap.add_argument("--png", action="store_true", help="also write PNG previews next to each EXR")
    ap.add_argument("--exposure", type=float, default=0.0, help="PNG preview exposure, stops")
    ap.add_argument("--reference", nargs="+", metavar="EXR",
                    help="read these Mitsuba images (passes) instead of rendering")
    ap.add_argument("--ours", nargs="+", action="append", default=[], metavar="EXR",
                    help="a group of adaptive-pm images of one setting (repeatable)")
    ap.add_argument("--label", action="append", default=[], help="a name per --ours group")
    ap.add_argument("--flip-ours", default="", choices=["", "x", "y", "xy"],
                    help="mirror --ours images before comparing")
    ap.add_argument("--block", type=int, nargs="+", default=[4, 8],
                    help="box-downsampling block sizes for relRMSE (default 4 8)")
    ap.add_argument("--eps", type=float, default=1e-2,
                    help="added to ref^2 in relRMSE's denominator (default 1e-2)")
    ap.add_argument("--region", action="append", default=[], metavar="NAME=X0,Y0,X1,Y1",
                    help="an extra pixel rectangle to report (half-open, row 0 at the top)")
    ap.add_argument("--json-out", help="also write the JSON report to this file")
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant(args.variant)

    gltf = Gltf(args.scene)
    _, persp = gltf.camera()
    height = args.height or args.size
    width = args.width or max(1, round(height * persp.get("aspectRatio", 1.0)))
    out_dir = os.path.dirname(os.path.abspath(args.out))
    os.makedirs(out_dir, exist_ok=True)
    stem = os.path.splitext(os.path.abspath(args.out))[0]
    mesh_dir = args.mesh_dir or stem + "_meshes"
    scene_dict, shapes = build_scene(gltf, args, width, height, mesh_dir)
    # No merging of meshes of equal BSDFs: the shapes must keep their ids
    # for the per-shape regions (the rendering is the same either way).
    scene = mi.load_dict(scene_dict, optimize=False)

    report = {"scene": os.path.abspath(args.scene), "width": width, "height": height,
              "variant": args.variant, "shapes": {k: v["kind"] + (" +emitter" if v["emitter"] else "")
                                                  for k, v in shapes.items()}}
    if args.reference:
        passes = [read_exr(p) for p in args.reference]
        report["mitsuba"] = {"files": args.reference}
    else:
        spp_pass = max(1, args.spp // args.passes)
        passes, seconds = [], []
        for k in range(args.passes):
            t0 = time.time()
            img = np.array(mi.render(scene, spp=spp_pass, seed=args.seed + k), dtype=np.float64)
            seconds.append(time.time() - t0)
            passes.append(img)
            write_exr(f"{stem}.pass{k}.exr", img)
            print(f"pass {k + 1}/{args.passes}: {spp_pass} spp, {seconds[-1]:.1f} s",
                  file=sys.stderr, flush=True)
        report["mitsuba"] = {"spp": spp_pass * args.passes, "passes": args.passes,
                             "seconds": round(sum(seconds), 2),
                             "files": [f"{stem}.pass{k}.exr" for k in range(args.passes)]}
    ref = ImageSet(passes)
    write_exr(args.out, ref.mean)
    if args.png:
        write_png(stem + ".png", ref.mean, args.exposure)
    report["mitsuba"]["out"] = os.path.abspath(args.out)
    everything = np.ones((height, width), bool)
    m, se = ref.region_mean(everything)
    report["mitsuba"]["mean"] = rounded(m)
    report["mitsuba"]["mean_se"] = rounded(se)

    if args.ours:
        regions, emitter = primary_regions(scene, shapes, width, height)
        regions = {"all": everything, **regions}
        for text in args.region:
            name, mask = parse_region(text, width, height)
            regions[name] = mask
        report["comparisons"] = []
        for g, files in enumerate(args.ours):
            label = args.label[g] if g < len(args.label) else f"ours{g}"
            images = [read_exr(f, args.flip_ours) for f in files]
            for f, img in zip(files, images):
                if img.shape != ref.mean.shape:
                    raise SystemExit(f"{f}: {img.shape[1]}x{img.shape[0]}, "
                                     f"Mitsuba's is {width}x{height}")
            ours = ImageSet(images)
            c = compare(label, ours, ref, regions, emitter, args.block, args.eps)
            c["files"] = files
            c["mean"] = c["regions"]["all"]["ours"]
            report["comparisons"].append(c)
            if args.png:
                base = os.path.join(out_dir, re.sub(r"[^A-Za-z0-9_.-]", "_", label))
                write_png(base + ".png", ours.mean, args.exposure)
                write_ratio_png(base + f".ratio{args.block[0]}.png", ours.mean, ref.mean,
                                args.block[0], max(1, 256 // max(width, height)))
        if args.png:
            lab = np.zeros((height, width, 3))
            palette = np.array([[0.9, 0.9, 0.9], [1, 0, 0], [0, 0.8, 0], [0, 0, 1],
                                [1, 1, 0], [1, 0, 1], [0, 1, 1], [0.5, 0.5, 0.5],
                                [1, 0.5, 0], [0.5, 0, 1], [0, 0.5, 0.5], [0.5, 0.25, 0]])
            named = [k for k in regions if k != "all"]
            for i, k in enumerate(named):
                lab[regions[k]] = palette[i % len(palette)]
            write_png(stem + ".regions.png", np.repeat(np.repeat(lab, 4, 0), 4, 1))
            report["region_colours"] = {k: palette[i % len(palette)].tolist()
                                        for i, k in enumerate(named)}

    text = json.dumps(report, indent=1)
    print(text)
    print_summary(report)
    if args.json_out:
        with open(args.json_out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
