"""Builds a scene with a partly transmitting pane in Blender and exports it with
Blender's own glTF exporter: assets/blender_frosted.glb, a file written by a real
exporter with KHR_materials_transmission below 1. Blender is needed only to
regenerate the file, never by CI or the tests. It reuses tools/blender_scene.py's
helpers (same Blender, same exporter settings).

Produced on Debian bookworm with Blender 3.4.1 (Debian package 3.4.1+dfsg-2,
`apt-get install --no-install-recommends blender python3-numpy`), run from the
repository root:

    blender -b --factory-startup --python tools/blender_frosted.py -- --out assets/blender_frosted.glb

The scene (Blender is Z-up; the exporter writes glTF's Y-up), in metres:
- floor: a 3 m x 3 m plane at z = 0, Principled BSDF, light grey, roughness 1
  (the exporter writes metallic 0, roughness 1: Lambert here);
- a frosted pane: a 1.2 m x 1.2 m plane 0.8 m above the floor, Principled
  Transmission 0.5, roughness 0.3, IOR 1.5 (the exporter writes
  KHR_materials_transmission 0.5 and leaves out KHR_materials_ior, 1.5 being
  its default; no volume, so the pane is a thin wall);
- a light panel: a 0.6 m x 0.6 m plane 2 m up, face turned down, a bare
  Emission shader of strength 20;
- a perspective camera (35 mm lens on a 36 mm sensor, 320 x 240) at a 3/4 view
  from 2.2 m high, framing the pane and the floor it shades.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_scene as base  # noqa: E402


def build():
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 320, 240
    scene.render.resolution_percentage = 100

    floor, _ = base.principled("floor", (0.7, 0.7, 0.7), roughness=1.0)
    base.plane("floor", 3.0, floor, (0.0, 0.0, 0.0))
    frosted, _ = base.principled("frosted", (0.9, 0.95, 1.0), roughness=0.3, transmission=0.5, ior=1.5)
    base.plane("pane", 1.2, frosted, (0.0, 0.0, 0.8))

    base.panel_and_camera(scene)


base.export_built("blender_frosted.py", build)
