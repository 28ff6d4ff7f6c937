"""Imports a Ferro shot into Blender (3.4) as one object whose mesh changes every frame.

    blender -b --python scripts/blender/import_shot.py -- SHOT_DIR [--save FILE.blend]
            [--render FRAME PNG] [--samples N] [--check]

SHOT_DIR is a shot directory of scripts/shot.sh: the meshes come from spiky/spiky_NNNN.ply
(or surface/surface_NNNN.ply when the shot has no spikes), the frame rate, camera and image
size from shot/shot.pov and shot/render.ini. Every frame's mesh is one mesh datablock
("ferro_NNNN"); the object "FerroFluid" shows the frame's mesh through a frame-change handler,
which also rides in the .blend as a registered text block (Blender runs it on load when
"Auto Run Python Scripts" is allowed). Each mesh carries the fluid's velocity [m/s] as the
point attribute "velocity", which Cycles' motion blur reads for meshes whose topology changes
from frame to frame. Ferro's coordinates are Blender's: metres, z up.

--render FRAME PNG renders that frame with Cycles on the CPU (motion blur on). --check
verifies every frame's vertex count and velocity against the PLY files and exits non-zero on
a mismatch (the test suite's use: tests/blender/blender_import_test.sh).
"""
import math
import os
import re
import struct
import sys

import bpy

HANDLER_TEXT = '''import bpy

def ferro_show_frame(scene, depsgraph=None):
    obj = bpy.data.objects.get("FerroFluid")
    if obj is None:
        return
    mesh = bpy.data.meshes.get("ferro_%04d" % scene.frame_current)
    if mesh is not None and obj.data != mesh:
        obj.data = mesh

for h in list(bpy.app.handlers.frame_change_pre):
    if getattr(h, "__name__", "") == "ferro_show_frame":
        bpy.app.handlers.frame_change_pre.remove(h)
bpy.app.handlers.frame_change_pre.append(ferro_show_frame)
'''


def fail(message):
    print("import_shot: error: " + message, file=sys.stderr)
    sys.exit(2)


def read_ply(path):
    """Ferro's binary PLY: vertices (x y z [nx ny nz] [vx vy vz] as floats), triangles."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        fail(path + ": not a PLY file")
    header = data[:end].decode("ascii", "replace").split("\n")
    if "format binary_little_endian 1.0" not in header:
        fail(path + ": not a binary little-endian PLY (write it with Ferro)")
    nv = nf = 0
    props = []
    element = None
    for line in header:
        w = line.split()
        if len(w) == 3 and w[0] == "element":
            element = w[1]
            if element == "vertex":
                nv = int(w[2])
            elif element == "face":
                nf = int(w[2])
        elif w[:1] == ["property"] and element == "vertex":
            if w[1] != "float":
                fail(path + ": vertex property " + w[-1] + " is not a float")
            props.append(w[-1])
    offset = end + len(b"end_header\n")
    cols = len(props)
    values = struct.unpack_from("<%df" % (nv * cols), data, offset)
    offset += 4 * nv * cols

    def column(name):
        if name not in props:
            return None
        k = props.index(name)
        return values[k::cols]

    xs, ys, zs = column("x"), column("y"), column("z")
    verts = [c for i in range(nv) for c in (xs[i], ys[i], zs[i])]
    vel = None
    if column("vx") is not None:
        vx, vy, vz = column("vx"), column("vy"), column("vz")
        vel = [c for i in range(nv) for c in (vx[i], vy[i], vz[i])]
    tris = []
    for _ in range(nf):
        n = data[offset]
        idx = struct.unpack_from("<%dI" % n, data, offset + 1)
        offset += 1 + 4 * n
        for k in range(2, n):  # polygons as fans, as Ferro reads them
            tris.extend((idx[0], idx[k - 1], idx[k]))
    return nv, verts, tris, vel


def shot_meshes(shot):
    for folder, prefix in (("spiky", "spiky_"), ("surface", "surface_")):
        d = os.path.join(shot, folder)
        if not os.path.isdir(d):
            continue
        frames = sorted(int(m.group(1)) for m in (re.fullmatch(prefix + r"(\d{4,})\.ply", f) for f in os.listdir(d)) if m)
        if frames:
            return [(f, os.path.join(d, "%s%04d.ply" % (prefix, f))) for f in frames]
    fail(shot + ": no spiky/spiky_NNNN.ply or surface/surface_NNNN.ply")


def pov_vector(text, name):
    m = re.search(r"#declare\s+" + name + r"\s*=\s*<([^>]*)>", text)
    if not m:
        fail("shot/shot.pov: no " + name)
    x, y, z = (float(c) / 1000.0 for c in m.group(1).split(","))
    return (x, z, y)  # POV-Ray <x, z, y> in mm -> Ferro (x, y, z) in m


def pov_number(text, name, default=None):
    m = re.search(r"#declare\s+" + name + r"\s*=\s*([-0-9.eE+]+)", text)
    if not m:
        if default is None:
            fail("shot/shot.pov: no " + name)
        return default
    return float(m.group(1))


def make_mesh(name, verts, tris, vel):
    me = bpy.data.meshes.get(name) or bpy.data.meshes.new(name)
    me.clear_geometry()
    nv, nt = len(verts) // 3, len(tris) // 3
    me.vertices.add(nv)
    me.vertices.foreach_set("co", verts)
    me.loops.add(3 * nt)
    me.loops.foreach_set("vertex_index", tris)
    me.polygons.add(nt)
    me.polygons.foreach_set("loop_start", list(range(0, 3 * nt, 3)))
    me.polygons.foreach_set("loop_total", [3] * nt)
    me.polygons.foreach_set("use_smooth", [True] * nt)
    me.update()
    if vel is not None:
        attr = me.attributes.get("velocity") or me.attributes.new("velocity", "FLOAT_VECTOR", "POINT")
        attr.data.foreach_set("vector", vel)
    me.use_fake_user = True  # kept in the .blend although only one frame's mesh is shown
    return me


def fluid_material():
    mat = bpy.data.materials.get("FerroFluid") or bpy.data.materials.new("FerroFluid")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    if bsdf:
        bsdf.inputs["Base Color"].default_value = (0.005, 0.005, 0.006, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.05
        bsdf.inputs["Specular"].default_value = 0.5
    return mat


def main(argv):
    if not argv or argv[0].startswith("-"):
        fail("usage: blender -b --python import_shot.py -- SHOT_DIR [--save F.blend] [--render FRAME PNG] [--samples N] [--check]")
    shot = argv[0]
    save = render_png = None
    render_frame = None
    samples = 16
    check = False
    i = 1
    while i < len(argv):
        a = argv[i]
        if a == "--save" and i + 1 < len(argv):
            save, i = argv[i + 1], i + 2
        elif a == "--render" and i + 2 < len(argv):
            render_frame, render_png, i = int(argv[i + 1]), argv[i + 2], i + 3
        elif a == "--samples" and i + 1 < len(argv):
            samples, i = int(argv[i + 1]), i + 2
        elif a == "--check":
            check, i = True, i + 1
        else:
            fail("unknown or incomplete option " + a)

    pov_path = os.path.join(shot, "shot", "shot.pov")
    if not os.path.isfile(pov_path):
        fail(pov_path + ": missing (run the shot's export first)")
    pov = open(pov_path).read()
    ini = open(os.path.join(shot, "shot", "render.ini")).read() if os.path.isfile(os.path.join(shot, "shot", "render.ini")) else ""
    frames = shot_meshes(shot)

    # A clean scene: the shot's object, camera and lights only.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # Debian's build has no OpenImageDenoise
    scene.view_settings.view_transform = "Standard"  # as POV-Ray's PNGs: no filmic lift of the black fluid
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 0.5
    fps = pov_number(pov, "FerroFps")
    scene.render.fps = max(1, int(round(fps)))
    scene.render.fps_base = scene.render.fps / fps
    scene.frame_start, scene.frame_end = frames[0][0], frames[-1][0]
    m = re.search(r"Width=(\d+)", ini)
    n = re.search(r"Height=(\d+)", ini)
    if m and n:
        scene.render.resolution_x, scene.render.resolution_y = int(m.group(1)), int(n.group(1))
        scene.render.resolution_percentage = 100

    meshes = {}
    for f, path in frames:
        nv, verts, tris, vel = read_ply(path)
        meshes[f] = (nv, vel)
        make_mesh("ferro_%04d" % f, verts, tris, vel)
    obj = bpy.data.objects.new("FerroFluid", bpy.data.meshes["ferro_%04d" % frames[0][0]])
    scene.collection.objects.link(obj)
    obj.data.materials.append(fluid_material())
    for f, _ in frames:
        me = bpy.data.meshes["ferro_%04d" % f]
        if not me.materials:
            me.materials.append(bpy.data.materials["FerroFluid"])

    # The camera of the shot: location, look-at point, horizontal field of view.
    cam = bpy.data.cameras.new("FerroCamera")
    cam.sensor_fit = "HORIZONTAL"
    cam.angle = math.radians(pov_number(pov, "FerroCameraAngle"))
    cam_obj = bpy.data.objects.new("FerroCamera", cam)
    scene.collection.objects.link(cam_obj)
    location = pov_vector(pov, "FerroCameraLocation")
    target = pov_vector(pov, "FerroCameraLookAt")
    cam_obj.location = location
    from mathutils import Vector
    cam_obj.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam_obj
    # Light: a soft key from above and a bright backdrop (as look.inc's white studio), whose
    # reflections show the black fluid's shape.
    light = bpy.data.lights.new("FerroKey", "AREA")
    light.energy = 20.0
    light.size = 0.3
    light_obj = bpy.data.objects.new("FerroKey", light)
    light_obj.location = (0.0, -0.05, 0.3)
    scene.collection.objects.link(light_obj)
    world = bpy.data.worlds.new("FerroWorld")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.8, 0.8, 0.82, 1.0)
    scene.world = world

    # The frame-change handler, in this session and as a registered text block of the .blend.
    text = bpy.data.texts.get("ferro_sequence.py") or bpy.data.texts.new("ferro_sequence.py")
    text.from_string(HANDLER_TEXT)
    text.use_module = True
    exec(compile(HANDLER_TEXT, "ferro_sequence.py", "exec"), {"bpy": bpy})

    failures = []
    if check:
        for f, _ in frames:
            scene.frame_set(f)
            shown = obj.data
            nv, vel = meshes[f]
            if shown.name != "ferro_%04d" % f:
                failures.append("frame %d shows mesh %s" % (f, shown.name))
                continue
            if len(shown.vertices) != nv:
                failures.append("frame %d: %d vertices, the PLY has %d" % (f, len(shown.vertices), nv))
            attr = shown.attributes.get("velocity")
            if vel is None or attr is None or attr.data_type != "FLOAT_VECTOR" or attr.domain != "POINT":
                failures.append("frame %d: no point attribute 'velocity' (FLOAT_VECTOR)" % f)
                continue
            got = [0.0] * (3 * nv)
            attr.data.foreach_get("vector", got)
            worst = max((abs(a - b) for a, b in zip(got, vel)), default=0.0)
            if worst > 1e-6:
                failures.append("frame %d: velocity differs from the PLY's by %g m/s" % (f, worst))
            print("import_shot: frame %d: %d vertices, velocity attribute matches (max |v| %.4g m/s)" %
                  (f, nv, max((math.sqrt(got[3 * k] ** 2 + got[3 * k + 1] ** 2 + got[3 * k + 2] ** 2) for k in range(nv)), default=0.0)))
        if abs(scene.render.fps / scene.render.fps_base - fps) > 1e-9:
            failures.append("frame rate %g, the shot's is %g" % (scene.render.fps / scene.render.fps_base, fps))

    if render_png is not None:
        scene.frame_set(render_frame)
        scene.render.filepath = os.path.abspath(render_png)
        scene.render.image_settings.file_format = "PNG"
        bpy.ops.render.render(write_still=True)
        if not os.path.isfile(scene.render.filepath):
            failures.append("render: no image written to " + scene.render.filepath)
    if save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(save))
    if failures:
        for f in failures:
            print("import_shot: FAILED: " + f, file=sys.stderr)
        sys.exit(1)


main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
