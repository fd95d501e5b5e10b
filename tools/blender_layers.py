"""Builds a scene whose materials set Principled BSDF's Specular, Specular Tint
and Clearcoat, and exports it with Blender's own glTF exporter:
assets/blender_layers.glb, a file written by a real exporter with
KHR_materials_specular and KHR_materials_clearcoat. Blender is needed
only to regenerate the file, never by CI or the tests. It reuses
tools/blender_scene.py's helpers (same Blender, same exporter settings).

Produced on Debian bookworm with Blender 3.4.1 (Debian package 3.4.1+dfsg-2,
`apt-get install --no-install-recommends blender python3-numpy`), run from the
repository root:

    blender -b --factory-startup --python tools/blender_layers.py -- --out assets/blender_layers.glb

Blender 3.4's exporter writes Specular `s` and Specular Tint `t` on a base
colour `b` (transmission 0) as `specularColorFactor = 0.08 s k / f0(ior)`,
`k = (1 - t) + t b / lum(b)` (lum: 0.3, 0.6, 0.1), so that the extension's
dielectric `f0 = min(f0(ior) specularColorFactor, 1)` is Blender's `0.08 s k`
whatever the IOR; at Specular 0.5 and Tint 0 it writes no extension.

The scene (Blender is Z-up; the exporter writes glTF's Y-up), in metres:
- floor: a 3 m x 3 m plane at z = 0, grey 0.6, roughness 0.5, Specular 0.25;
- tinted: a 1 m x 1 m plane 0.5 m up, orange (0.8, 0.3, 0.1), roughness 0.4,
  Specular 1.0, Specular Tint 0.5, IOR 1.45;
- matte: a 1 m x 1 m plane 0.3 m up, grey 0.5, roughness 1, Specular 0 (the
  exporter writes a black specularColorFactor: no reflection at all);
- plain: a 1 m x 1 m plane 0.7 m up, roughness 0.5, Blender's defaults
  (Specular 0.5, no extension);
- lacquer: a 1 m x 1 m plane 0.9 m up, red (0.6, 0.05, 0.05), roughness 0.5,
  Clearcoat 1, Clearcoat Roughness 0.1 (the exporter writes
  KHR_materials_clearcoat with both factors);
- a light panel: a 0.6 m x 0.6 m plane 2 m up, face turned down, a bare
  Emission shader of strength 20;
- a perspective camera at a 3/4 view from 2.2 m high.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_scene as base  # noqa: E402


def specular(name, colour, roughness, spec, tint=0.0, ior=1.5):
    mat, bsdf = base.principled(name, colour, roughness=roughness, ior=ior)
    bsdf.inputs["Specular"].default_value = spec
    bsdf.inputs["Specular Tint"].default_value = tint
    return mat


def build():
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 320, 240
    scene.render.resolution_percentage = 100

    base.plane("floor", 3.0, specular("floor", (0.6, 0.6, 0.6), 0.5, 0.25), (0.0, 0.0, 0.0))
    tinted = specular("tinted", (0.8, 0.3, 0.1), 0.4, 1.0, tint=0.5, ior=1.45)
    base.plane("tinted", 1.0, tinted, (-0.6, 0.0, 0.5))
    base.plane("matte", 1.0, specular("matte", (0.5, 0.5, 0.5), 1.0, 0.0), (0.6, 0.0, 0.3))
    base.plane("plain", 1.0, specular("plain", (0.5, 0.5, 0.5), 0.5, 0.5), (0.0, 0.8, 0.7))
    lacquer, bsdf = base.principled("lacquer", (0.6, 0.05, 0.05), roughness=0.5, ior=1.5)
    bsdf.inputs["Clearcoat"].default_value = 1.0
    bsdf.inputs["Clearcoat Roughness"].default_value = 0.1
    base.plane("lacquer", 1.0, lacquer, (0.0, -0.8, 0.9))

    base.panel_and_camera(scene)


base.export_built("blender_layers.py", build)
