#!/usr/bin/env python3
"""Writes assets/gallery.gltf: a scene beyond the Cornell box for the renderer
and `bench tradeoff`. Run from the repository root: python3 tools/make_gallery.py

An open-fronted room (6 x 3 x 6 m, floor at y = 0, camera outside looking +z):
- a perfect mirror standing before the back wall, turned 31 degrees about the
  vertical and tipped 5 degrees down so that the camera sees the gold sphere,
  the lit floor and the sand wall in it (facing the camera it showed the open
  front: black); the sharp panel's light it reflects lands on the floor as a
  caustic only photons find (metallic 1, roughness 0 -> Mirror);
- a glossy gold sphere (metallic 1, roughness 0.3 -> Cook-Torrance, m = 0.09)
  with per-vertex NORMALs (smooth shading);
- a glossy red plastic block (metallic 0, roughness 0.25 -> Cook-Torrance with a
  diffuse base), see brdf::from_gltf_pbr for the mapping;
- a smooth glass ball in front, on the floor between the gold sphere and the
  red block (KHR_materials_transmission 1, KHR_materials_ior 1.5,
  KHR_materials_volume thicknessFactor = its diameter: a refracting volume, no
  absorption -> Dielectric): tools/make_cornell.py's icosphere (outward
  winding, a vertex at each pole), 4 subdivisions (5120 triangles), with
  per-vertex NORMALs, lifted 2 mm off the floor so the two never touch;
- four lights of different power, size and exponent: a large diffuse ceiling
  panel (cosn 0), a small sharp panel (extras.cosn = 20), a KHR_lights_punctual
  spot light and a dim point light.
Light panels face down (their winding gives a -y normal): area lights are one-sided."""
import math

import gltf_build

from make_cornell import icosphere  # tools/ is the script's directory, first on sys.path

W, H, D = 3.0, 3.0, 3.0  # half-width, height, half-depth
GOLD_CENTRE = (1.2, 0.7, 0.9)
GLASS_RADIUS = 0.5
GLASS_CENTRE = (0.3, GLASS_RADIUS + 0.002, -1.3)
GLASS_LEVELS = 4

MATERIALS = [
    {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.72, 0.72, 0.7, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "blue", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "sand", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.55, 0.3, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    {"name": "mirror", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0}},
    {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.78, 0.34, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3}},
    {"name": "red_plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.1, 0.08, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.25}},
    {"name": "panel_diffuse", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "emissiveFactor": [1.0, 0.95, 0.85], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
     "extras": {"cosn": 0.0}},
    {"name": "panel_sharp", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
     "emissiveFactor": [1.0, 0.7, 0.4], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 80.0}},
     "extras": {"cosn": 20.0}},
    {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0},
     "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                    "KHR_materials_ior": {"ior": 1.5},
                    "KHR_materials_volume": {"thicknessFactor": 2.0 * GLASS_RADIUS}}},
]
MAT = {m["name"]: i for i, m in enumerate(MATERIALS)}


def quad(a, b, c, d):
    return [a, b, c, d], [(0, 1, 2), (0, 2, 3)]


def box(x0, x1, y0, y1, z0, z1, angle):
    """An axis-aligned box turned by `angle` about its vertical axis; outward winding."""
    cx, cz = (x0 + x1) / 2, (z0 + z1) / 2
    ca, sa = math.cos(angle), math.sin(angle)

    def p(x, y, z):
        dx, dz = x - cx, z - cz
        return (cx + ca * dx + sa * dz, y, cz - sa * dx + ca * dz)

    v = [p(x, y, z) for y in (y0, y1) for z in (z0, z1) for x in (x0, x1)]
    # v index: bit0 x, bit1 z, bit2 y
    faces = [(4, 6, 7, 5), (0, 1, 3, 2), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = [t for f in faces for t in ((f[0], f[1], f[2]), (f[0], f[2], f[3]))]
    return v, tris


def mirror_panel(centre, half_w, half_h, normal):
    """A rectangle about `centre` facing the unit `normal` (horizontal sides)."""
    nx, ny, nz = normal
    right = (-nz, 0.0, nx)
    k = math.sqrt(right[0] ** 2 + right[2] ** 2)
    right = (right[0] / k, 0.0, right[2] / k)
    up = (ny * right[2] - nz * right[1], nz * right[0] - nx * right[2], nx * right[1] - ny * right[0])
    def p(a, b):
        return tuple(centre[i] + a * half_w * right[i] + b * half_h * up[i] for i in range(3))
    return [p(-1, -1), p(1, -1), p(1, 1), p(-1, 1)], [(0, 1, 2), (0, 2, 3)]


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def sphere(c, r, nu=32, nv=16):
    v, t = [], []
    for j in range(nv + 1):
        th = math.pi * j / nv
        for i in range(nu):
            ph = 2 * math.pi * i / nu
            v.append((c[0] + r * math.sin(th) * math.cos(ph), c[1] + r * math.cos(th), c[2] + r * math.sin(th) * math.sin(ph)))
    for j in range(nv):
        for i in range(nu):
            a, b = j * nu + i, j * nu + (i + 1) % nu
            c2, d = a + nu, b + nu
            if j > 0:
                t.append((a, b, c2))
            if j < nv - 1:
                t.append((b, d, c2))
    return v, t


def glass_ball(c, r, levels):
    """make_cornell's icosphere of radius `r` about `c` (outward winding)."""
    verts, tris = icosphere(levels)
    return [tuple(c[i] + r * v[i] for i in range(3)) for v in verts], tris


# Meshes shaded with per-vertex normals: the centre of each sphere.
SMOOTH = {"gold_sphere": GOLD_CENTRE, "glass_sphere": GLASS_CENTRE}


def add_meshes(b, meshes, mat_index, smooth):
    """Adds each (name, material name, positions, triangles) to builder `b`;
    a mesh named in `smooth` (name -> sphere centre) gets per-vertex NORMALs
    pointing away from its centre."""
    for name, mat, pos, idx in meshes:
        attributes = {}
        if name in smooth:
            centre = smooth[name]
            attributes["NORMAL"] = b.vec3([unit(tuple(p[i] - centre[i] for i in range(3))) for p in pos])
        attributes["POSITION"] = b.vec3(pos, bounds=True)
        b.mesh(name, attributes, b.triangles(idx), mat_index[mat])


def look_rotation(d):
    """Quaternion (x, y, z, w) turning local -z onto the unit vector d."""
    f = (0.0, 0.0, -1.0)
    n = math.sqrt(sum(x * x for x in d))
    d = tuple(x / n for x in d)
    axis = (f[1] * d[2] - f[2] * d[1], f[2] * d[0] - f[0] * d[2], f[0] * d[1] - f[1] * d[0])
    s = math.sqrt(sum(x * x for x in axis))
    ang = math.atan2(s, sum(a * b for a, b in zip(f, d)))
    axis = tuple(x / s for x in axis) if s > 1e-9 else (0.0, 1.0, 0.0)
    h = math.sin(ang / 2)
    return [axis[0] * h, axis[1] * h, axis[2] * h, math.cos(ang / 2)]


def main():
    meshes = [
        ("floor", "white", *quad((-W, 0, -D), (-W, 0, D), (W, 0, D), (W, 0, -D))),
        ("ceiling", "white", *quad((-W, H, -D), (W, H, -D), (W, H, D), (-W, H, D))),
        ("back_wall", "white", *quad((-W, 0, D), (-W, H, D), (W, H, D), (W, 0, D))),
        ("left_wall", "sand", *quad((W, 0, -D), (W, 0, D), (W, H, D), (W, H, -D))),
        ("right_wall", "blue", *quad((-W, 0, -D), (-W, H, -D), (-W, H, D), (-W, 0, D))),
        # Normal from the mirror's centre: halfway between the camera and the sphere.
        ("mirror", "mirror", *mirror_panel((-1.5, 1.35, D - 0.6), 0.9, 0.95, unit((0.506, -0.095, -0.848)))),
        # Panels a centimetre under the ceiling, winding facing down.
        ("panel_diffuse", "panel_diffuse", *quad((-0.6, H - 0.01, -0.6), (0.6, H - 0.01, -0.6), (0.6, H - 0.01, 0.6), (-0.6, H - 0.01, 0.6))),
        ("panel_sharp", "panel_sharp", *quad((-1.85, H - 0.01, -1.35), (-1.55, H - 0.01, -1.35), (-1.55, H - 0.01, -1.05), (-1.85, H - 0.01, -1.05))),
        ("gold_sphere", "gold", *sphere(GOLD_CENTRE, 0.7)),
        ("red_block", "red_plastic", *box(-1.9, -1.0, 0.0, 0.9, -0.2, 0.7, 0.4)),
        ("glass_sphere", "glass", *glass_ball(GLASS_CENTRE, GLASS_RADIUS, GLASS_LEVELS)),
    ]
    b = gltf_build.Builder()
    add_meshes(b, meshes, MAT, SMOOTH)
    spot_pos = (2.2, 2.8, -1.8)
    target = GOLD_CENTRE
    spot_dir = tuple(t - p for t, p in zip(target, spot_pos))
    b.nodes.append({"name": "spot", "translation": list(spot_pos), "rotation": look_rotation(spot_dir),
                    "extensions": {"KHR_lights_punctual": {"light": 0}}})
    b.nodes.append({"name": "point", "translation": [-2.4, 1.2, 2.2], "extensions": {"KHR_lights_punctual": {"light": 1}}})
    b.nodes.append({"name": "camera", "camera": 0, "translation": [0.0, 1.5, -7.2], "rotation": [0.0, 1.0, 0.0, 0.0]})
    extensions_used = ["KHR_materials_emissive_strength", "KHR_lights_punctual",
                       "KHR_materials_ior", "KHR_materials_transmission", "KHR_materials_volume"]
    lights = {"KHR_lights_punctual": {"lights": [
        {"name": "spot", "type": "spot", "color": [0.6, 0.75, 1.0], "intensity": 12.0,
         "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.4}},
        {"name": "point", "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 0.3},
    ]}}
    camera = {"yfov": math.radians(40.0), "aspectRatio": 1.0, "znear": 0.01}
    doc = b.document("tools/make_gallery.py", "gallery", MATERIALS, camera, extensions_used, lights)
    gltf_build.write("assets/gallery.gltf", doc)


if __name__ == "__main__":
    main()
