"""Builds a small scene from scratch in Blender and exports it with Blender's own
glTF exporter: assets/blender_scene.glb, a file written by a real exporter (issue 25),
not by this project's generators. Blender is needed only to regenerate the file,
never by CI or the tests.

The committed assets/blender_scene.glb was produced on Debian bookworm with
Blender 3.4.1 (Debian package 3.4.1+dfsg-2+b1, `apt-get install --no-install-recommends
blender python3-numpy`), glTF exporter "Khronos glTF Blender I/O v3.4.50", by the
command, run from the repository root:

    blender -b --factory-startup --python tools/blender_scene.py -- --out assets/blender_scene.glb

Two runs give byte-identical files (sha256 587d77f7d37a894a...38f9338): Blender's
own UV sphere operator and its per-vertex normal sums were not reproducible (see
uv_sphere and smooth). `--render PATH.png` also renders a small Cycles preview of
the same scene (not committed; `--samples N`, default 64).

The scene (Blender is Z-up; the exporter writes glTF's Y-up, x' = x, y' = z, z' = -y),
everything in metres:
- floor: a 4 m x 4 m plane at z = 0, Principled BSDF (roughness 0.9), Base Color
  from an Image Texture: a 256 x 256 checkerboard of 8 x 8 squares (0.5 m each) in
  a light sand and a dark brown tone, made here pixel by pixel and packed (PNG)
  into the GLB;
- light panel: a 1 m x 1 m plane 2 m above the floor, turned 180 degrees about x
  (so that its face looks down) and 30 degrees about z, then mirrored with scale
  (-1, 1, 1) (Rz(30) Rx(180) diag(-1, 1, 1) = Rz(30) (-I): the exporter writes
  it as rotation 30 degrees about y, scale (-1, -1, -1)): the node's transform
  has a negative determinant, and the panel's
  front face still looks at the floor (a mirrored object's face normal is
  M^-T n, which the glTF rule "negative determinant: clockwise winding" keeps).
  Its material is a bare Emission shader (warm white, strength 15) with backface
  culling off, so the exporter writes doubleSided true, an emissiveFactor and
  KHR_materials_emissive_strength;
- a copper Suzanne: Principled metallic 1, roughness 0.25, with a Subdivision
  Surface modifier (level 1) applied at export (export_apply) and smooth shading,
  resting on the floor;
- three pillars, linked duplicates of one cylinder mesh (obj.copy() keeps the
  mesh datablock: Alt+D), children of an Empty turned 20 degrees about z; the
  third is 1.5 times taller (scale z); auto-smooth 30 degrees (flat caps, smooth
  sides): one glTF mesh shared by three nodes under one parent node;
- a glass ball: a UV sphere (48 x 24, built here vertex by vertex, without UVs,
  so its primitive has no TEXCOORD_0) of radius 0.4 m, Principled Transmission 1,
  IOR 1.5, roughness 0. The exporter writes KHR_materials_transmission but no
  KHR_materials_ior (1.5 is the extension's default, which it leaves out), and no
  KHR_materials_volume (it writes one only from a "glTF Material Output" node's
  Thickness), so by the glTF rules the ball is thin-walled;
- a 60 W point light (KHR_lights_punctual; the exporter's default 'SPEC' mode
  writes 60 / (4 pi) * 683 cd);
- a perspective camera (35 mm lens on a 36 mm sensor, 640 x 480: yfov 0.736 rad)
  at a 3/4 view, 1.85 m high, below the panel (so it sees the emitting face,
  edge-on at the top of the frame), that frames the floor, the panel's light
  pool, the copper, the pillars and the glass.
The world is black (the exporter writes no environment anyway).
"""
import math
import sys

import bpy
from mathutils import Euler, Vector

EXPECTED_BLENDER = "3.4.1"


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    out, render, samples = "assets/blender_scene.glb", None, 64
    i = 0
    while i < len(argv):
        if argv[i] == "--out":
            out = argv[i + 1]
            i += 2
        elif argv[i] == "--render":
            render = argv[i + 1]
            i += 2
        elif argv[i] == "--samples":
            samples = int(argv[i + 1])
            i += 2
        else:
            raise SystemExit(f"blender_scene.py: unknown argument {argv[i]!r} (use --out FILE.glb [--render FILE.png [--samples N]])")
    return out, render, samples


def clear_scene():
    """Deletes the factory startup's cube, light and camera and their data."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for coll in (bpy.data.meshes, bpy.data.materials, bpy.data.cameras, bpy.data.lights, bpy.data.images):
        for block in list(coll):
            coll.remove(block)


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def principled(name, base, metallic=0.0, roughness=0.5, transmission=0.0, ior=1.45):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Transmission"].default_value = transmission
    bsdf.inputs["IOR"].default_value = ior
    return mat, bsdf


def emission(name, color, strength):
    """A material of a bare Emission shader."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    em = nodes.new("ShaderNodeEmission")
    em.location = (-250, 0)
    em.inputs["Color"].default_value = (*color, 1.0)
    em.inputs["Strength"].default_value = strength
    links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def checker_image(name, size=256, squares=8, light=(0.85, 0.78, 0.62), dark=(0.28, 0.16, 0.09)):
    """A size x size checkerboard, squares x squares, packed into the .blend (PNG)."""
    img = bpy.data.images.new(name, size, size, alpha=False)
    cell = size // squares
    px = []
    for y in range(size):
        for x in range(size):
            c = light if ((x // cell) + (y // cell)) % 2 == 0 else dark
            px.extend((c[0], c[1], c[2], 1.0))
    img.pixels.foreach_set(px)
    img.file_format = "PNG"
    img.pack()
    return img


def mesh_object(name, mesh):
    return link(bpy.data.objects.new(name, mesh))


def primitive(op, **kw):
    """Runs a bpy.ops.mesh.primitive_* operator and returns its new object's mesh,
    deleting the object (the mesh is then linked to objects made here)."""
    op(**kw)
    obj = bpy.context.active_object
    mesh = obj.data
    bpy.data.objects.remove(obj, do_unlink=True)
    return mesh


def plane(name, size, material, location, rotation=(0.0, 0.0, 0.0)):
    """A size x size plane of `material`, placed and turned (Euler XYZ)."""
    mesh = primitive(bpy.ops.mesh.primitive_plane_add, size=size)
    mesh.name = name
    mesh.materials.append(material)
    obj = mesh_object(name, mesh)
    obj.location = location
    obj.rotation_euler = rotation
    return obj


def out_arg(script):
    """The FILE of `-- --out FILE.glb`, the one argument of the scripts that
    reuse these helpers (`script` names the caller in the usage message)."""
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 2 or argv[0] != "--out":
        raise SystemExit(f"{script}: use -- --out FILE.glb")
    return argv[1]


def panel_and_camera(scene):
    """The small scenes' light and view: a 0.6 m emitting panel 2 m up, face
    down (a bare Emission shader of strength 20), and a 35 mm camera at a 3/4
    view from 2.2 m high, looking at (0, 0, 0.3)."""
    panel = emission("panel_emission", (1.0, 1.0, 1.0), 20.0)
    plane("panel", 0.6, panel, (0.2, 0.1, 2.0), (math.pi, 0.0, 0.0))
    cam = bpy.data.cameras.new("camera")
    cam.lens, cam.sensor_width = 35.0, 36.0
    cam_obj = link(bpy.data.objects.new("camera", cam))
    cam_obj.location = Vector((2.2, -2.0, 2.2))
    target = Vector((0.0, 0.0, 0.3))
    cam_obj.rotation_euler = (target - cam_obj.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam_obj
    bpy.context.view_layer.update()


def export_built(script, build):
    """Clears the scene, runs `build`, exports to the `--out` file."""
    out = out_arg(script)
    clear_scene()
    build()
    export(out)
    print(f"{script}: wrote {out}")


def uv_sphere(name, radius, segments, rings):
    """A UV sphere built vertex by vertex: bpy.ops.mesh.primitive_uv_sphere_add
    (bmesh) orders its faces differently from one run to the next, which changes
    the exporter's vertex order and the last bit of its normals. A vertex at each
    pole, triangles around the poles, quads elsewhere, faces wound outwards."""
    verts = [(0.0, 0.0, radius)]
    for r in range(1, rings):
        theta = math.pi * r / rings
        for s in range(segments):
            phi = 2.0 * math.pi * s / segments
            verts.append((radius * math.sin(theta) * math.cos(phi), radius * math.sin(theta) * math.sin(phi), radius * math.cos(theta)))
    verts.append((0.0, 0.0, -radius))
    south = len(verts) - 1

    def ring(r, s):  # vertex index on ring r (1 .. rings-1), segment s
        return 1 + (r - 1) * segments + s % segments

    faces = [(0, ring(1, s), ring(1, s + 1)) for s in range(segments)]
    for r in range(1, rings - 1):
        faces += [(ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1)) for s in range(segments)]
    faces += [(ring(rings - 1, s + 1), ring(rings - 1, s), south) for s in range(segments)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.validate()
    return mesh


def smooth(mesh, auto_angle):
    """Smooth shading, with auto-smooth: at 180 degrees it is plain smooth
    shading, but Blender then computes the normals fan by fan (deterministic);
    without it, it sums them per vertex in parallel, and the last bit of the
    Suzanne's normals changed from one run to the next."""
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    mesh.use_auto_smooth = True
    mesh.auto_smooth_angle = math.radians(auto_angle)


def build():
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 640, 480
    scene.render.resolution_percentage = 100
    world = bpy.data.worlds.new("black") if scene.world is None else scene.world
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)

    # Floor: 4 m x 4 m, checkerboard Base Color.
    floor_mat, floor_bsdf = principled("floor_checker", (0.8, 0.8, 0.8), roughness=0.9)
    tex = floor_mat.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = checker_image("floor_checker")
    tex.location = (-400, 200)
    floor_mat.node_tree.links.new(tex.outputs["Color"], floor_bsdf.inputs["Base Color"])
    floor_mesh = primitive(bpy.ops.mesh.primitive_plane_add, size=4.0)
    floor_mesh.name = "floor"
    floor_mesh.materials.append(floor_mat)
    mesh_object("floor", floor_mesh)

    # Light panel: 1 m x 1 m at 2 m, face turned down, mirrored on x.
    panel_mat = emission("panel_emission", (1.0, 0.9, 0.75), 15.0)
    panel_mat.use_backface_culling = False
    panel_mesh = primitive(bpy.ops.mesh.primitive_plane_add, size=1.0)
    panel_mesh.name = "panel"
    panel_mesh.materials.append(panel_mat)
    panel = mesh_object("panel", panel_mesh)
    panel.location = (0.0, 0.0, 2.0)
    panel.rotation_euler = (math.pi, 0.0, math.radians(30.0))
    panel.scale = (-1.0, 1.0, 1.0)

    # Copper Suzanne, subdivided at export, resting on the floor.
    copper, _ = principled("copper", (0.955, 0.638, 0.538), metallic=1.0, roughness=0.25)
    monkey_mesh = primitive(bpy.ops.mesh.primitive_monkey_add, size=0.8)
    monkey_mesh.name = "suzanne"
    smooth(monkey_mesh, auto_angle=180.0)
    monkey_mesh.materials.append(copper)
    monkey = mesh_object("suzanne", monkey_mesh)
    sub = monkey.modifiers.new("subdivision", "SUBSURF")
    sub.levels = sub.render_levels = 1
    # Face towards the camera's side (+x, -y) and tipped back 15 degrees.
    rot = Euler((math.radians(-15.0), 0.0, math.radians(40.0)), "XYZ")
    lowest = min((rot.to_matrix() @ v.co).z for v in monkey_mesh.vertices)
    monkey.rotation_euler = rot
    monkey.location = (0.75, 0.55, -lowest + 0.005)

    # Three pillars sharing one mesh (linked duplicates) under an Empty.
    clay, _ = principled("blue_clay", (0.12, 0.22, 0.55), roughness=0.6)
    pillar_mesh = primitive(bpy.ops.mesh.primitive_cylinder_add, vertices=24, radius=0.12, depth=0.6)
    pillar_mesh.name = "pillar"
    smooth(pillar_mesh, auto_angle=30.0)
    pillar_mesh.materials.append(clay)
    group = link(bpy.data.objects.new("pillars", None))
    group.location = (-0.9, 1.0, 0.0)
    group.rotation_euler = (0.0, 0.0, math.radians(20.0))
    first = mesh_object("pillar.0", pillar_mesh)
    pillars = [first, link(first.copy()), link(first.copy())]
    for i, (obj, (x, y), sz) in enumerate(zip(pillars, [(-0.55, -0.35), (0.0, 0.1), (0.55, 0.45)], [1.0, 1.0, 1.5])):
        obj.name = f"pillar.{i}"
        obj.parent = group
        obj.scale = (1.0, 1.0, sz)
        obj.location = (x, y, 0.3 * sz)
    assert all(p.data is pillar_mesh for p in pillars)

    # Glass ball.
    glass, _ = principled("glass", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.5)
    ball_mesh = uv_sphere("glass_ball", radius=0.4, segments=48, rings=24)
    smooth(ball_mesh, auto_angle=180.0)
    ball_mesh.materials.append(glass)
    ball = mesh_object("glass_ball", ball_mesh)
    ball.location = (-0.55, -0.6, 0.4 + 0.002)

    # A dim point light beside the panel.
    lamp = bpy.data.lights.new("point", "POINT")
    lamp.energy = 60.0
    lamp.shadow_soft_size = 0.05
    lamp.color = (1.0, 1.0, 1.0)
    lamp_obj = link(bpy.data.objects.new("point", lamp))
    lamp_obj.location = (1.6, -1.4, 2.4)

    # Camera, 3/4 view.
    cam = bpy.data.cameras.new("camera")
    cam.type = "PERSP"
    cam.lens = 35.0
    cam.sensor_width = 36.0
    cam.sensor_fit = "AUTO"
    cam.clip_start, cam.clip_end = 0.1, 100.0
    cam_obj = link(bpy.data.objects.new("camera", cam))
    cam_obj.location = Vector((3.4, -3.1, 1.85))  # below the panel: it sees the emitting face
    target = Vector((-0.25, 0.3, 0.15))
    cam_obj.rotation_euler = (target - cam_obj.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam_obj
    bpy.context.view_layer.update()


def export(path):
    bpy.ops.export_scene.gltf(
        filepath=path,
        export_format="GLB",
        export_image_format="AUTO",
        export_texcoords=True,
        export_normals=True,
        export_tangents=False,
        export_materials="EXPORT",
        export_colors=False,
        export_cameras=True,
        export_lights=True,
        export_apply=True,
        export_yup=True,
        export_extras=False,
        export_animations=False,
        export_draco_mesh_compression_enable=False,
        use_selection=False,
    )


def render(path, samples):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.seed = 0
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)


def main():
    out, render_path, samples = parse_args()
    if bpy.app.version_string != EXPECTED_BLENDER:
        print(f"blender_scene.py: warning: Blender {bpy.app.version_string}, the committed file came from {EXPECTED_BLENDER}", file=sys.stderr)
    clear_scene()
    build()
    export(out)
    print(f"blender_scene.py: wrote {out}")
    if render_path:
        render(render_path, samples)
        print(f"blender_scene.py: rendered {render_path}")


if __name__ == "__main__":
    main()
