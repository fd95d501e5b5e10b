#!/usr/bin/env python3
"""LuxCore's PhotonGI photon tracing on our Cornell box, beside ours.

Builds assets/cornell_box.gltf in LuxCore (pyluxcore, from the Python
registry: `pip install pyluxcore`), runs PhotonGI's preprocess with N photons
on every core, and prints LuxCore's photons stored per second of photon
tracing (from its own log lines, timed as they arrive), then runs
`adaptive-pm trace cornell --mode classic --n-max N --json` and prints ours.

    python3 scripts/luxcore_photongi.py [N] [path/to/adaptive-pm]
"""
import base64
import json
import os
import re
import struct
import subprocess
import sys
import time

import pyluxcore

HERE = os.path.dirname(os.path.abspath(__file__))
GLTF = os.path.join(HERE, "..", "assets", "cornell_box.gltf")


def load_gltf(path):
    g = json.load(open(path))
    uri = g["buffers"][0]["uri"]
    data = base64.b64decode(uri.split(",", 1)[1])

    def accessor(i):
        a = g["accessors"][i]
        v = g["bufferViews"][a["bufferView"]]
        off = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        n = a["count"]
        if a["type"] == "VEC3":
            return [struct.unpack_from("<3f", data, off + 12 * k) for k in range(n)]
        assert a["componentType"] == 5125, "indices must be uint32"
        return list(struct.unpack_from("<%dI" % n, data, off))

    meshes = []
    for node in g["nodes"]:
        if "mesh" not in node:
            continue
        assert not any(k in node for k in ("matrix", "translation", "rotation", "scale"))
        for prim in g["meshes"][node["mesh"]]["primitives"]:
            mat = g["materials"][prim["material"]]
            meshes.append((node["name"], accessor(prim["attributes"]["POSITION"]),
                           accessor(prim["indices"]), mat))
    return meshes


LOG = []


def luxcore_rate(n):
    lines = LOG
    pyluxcore.Init(lambda msg: lines.append((time.time(), msg)))
    scene = pyluxcore.Scene()
    props = pyluxcore.Properties()
    for name, pos, idx, mat in load_gltf(GLTF):
        tris = [tuple(idx[i:i + 3]) for i in range(0, len(idx), 3)]
        scene.DefineMesh(name + "_mesh", pos, tris, None, None, None, None)
        c = mat["pbrMetallicRoughness"]["baseColorFactor"][:3]
        m = "scene.materials.%s_mat." % name
        props.SetFromString(m + "type = matte\n" + m + "kd = %f %f %f\n" % tuple(c))
        if "emissiveFactor" in mat:
            e = mat["emissiveFactor"]
            s = mat.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get(
                "emissiveStrength", 1.0)
            props.SetFromString(m + "emission = %f %f %f\n" % tuple(x * s for x in e))
        o = "scene.objects.%s." % name
        props.SetFromString(o + "shape = %s_mesh\n" % name + o + "material = %s_mat\n" % name)
    props.SetFromString(
        "scene.camera.type = perspective\n"
        "scene.camera.lookat.orig = 278 273 -800\n"
        "scene.camera.lookat.target = 278 273 0\n"
        "scene.camera.up = 0 1 0\n"
        "scene.camera.fieldofview = 39.3\n")
    scene.Parse(props)
    cfg = pyluxcore.Properties()
    cfg.SetFromString(
        "renderengine.type = PATHCPU\n"
        "sampler.type = SOBOL\n"
        "film.width = 64\nfilm.height = 64\n"
        "path.photongi.sampler.type = RANDOM\n"
        "path.photongi.photon.maxcount = %d\n"
        "path.photongi.photon.maxdepth = 64\n"
        "path.photongi.indirect.enabled = 1\n"
        "path.photongi.indirect.maxsize = %d\n"
        # Trace all N photons: LuxCore otherwise stops once its cache
        # converges or holds maxsize photons (set far above what N stores).
        "path.photongi.indirect.haltthreshold = 0\n"
        "path.photongi.caustic.enabled = 0\n" % (n, 100 * n))
    session = pyluxcore.RenderSession(pyluxcore.RenderConfig(cfg, scene))
    session.Start()
    session.Stop()
    pyluxcore.SetLogHandler(None)
    # LuxCore 2.11's own lines: "PhotonGI tracing indirect cache photons",
    # then "PhotonGI additional indirect photon stored: S" and "PhotonGI
    # total photon traced: T" when the tracing threads have joined.
    start = next(t for t, m in lines if "PhotonGI tracing indirect cache photons" in m)
    end, stored, traced = None, None, None
    for t, m in lines:
        hit = re.search(r"PhotonGI (?:total|additional) indirect photon stored: (\d+)", m)
        if hit:
            end, stored = t, int(hit.group(1))
        hit = re.search(r"PhotonGI total photon traced: (\d+)", m)
        if hit:
            traced = int(hit.group(1))
    if end is None or traced is None:
        raise StopIteration
    return stored, traced, end - start, lines


def ours(n, exe):
    out = subprocess.run([exe, "trace", "cornell", "--mode", "classic", "--n-max", str(n),
                          "--json"], capture_output=True, text=True, check=True).stdout
    d = json.loads(out)
    return d["stored"], d["emitted"], d["trace_s"]


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2_000_000
    exe = sys.argv[2] if len(sys.argv) > 2 else os.path.join(HERE, "..", "target", "release",
                                                             "adaptive-pm")
    try:
        stored, traced, secs, _ = luxcore_rate(n)
    except StopIteration:
        sys.exit("LuxCore's log had no PhotonGI tracing line: see its output above")
    # LuxCore's "stored" counts a photon's deposits on the visibility
    # particles near each hit (several per hit), ours one record per hit:
    # photons traced (emitted) per second is the like-for-like rate.
    print("luxcore PhotonGI: %d traced, %d stored, in %.2f s: %.3f M traced/s, %.2f M stored/s"
          % (traced, stored, secs, traced / secs / 1e6, stored / secs / 1e6))
    s, e, t = ours(n, exe)
    print("adaptive-pm classic: %d emitted, %d stored, in %.2f s: %.3f M traced/s, %.2f M stored/s"
          % (e, s, t, e / t / 1e6, s / t / 1e6))
    print("ours / LuxCore: %.2f traced per second, %.2f stored per second"
          % ((e / t) / (traced / secs), (s / t) / (stored / secs)))


if __name__ == "__main__":
    main()
