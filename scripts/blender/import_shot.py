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

A shot with magnetizable solids ([[solids]]) also gets the object "FerroSolids": all its solids
in one flat-shaded mesh with the material "FerroSteel" (brushed steel: metallic, roughness 0.3,
anisotropic along the local z axis), read from the mesh2 blocks ferro-pov writes into each
frame's shot/magnets_NNNN.inc (FerroSolids). When every frame's solids are the same, one mesh
("ferro_solids") stays; when their keys move them, each frame has its own ("ferro_solids_NNNN")
and the frame-change handler swaps it as the fluid's. A shot without solids imports as before.

--render FRAME PNG renders that frame with Cycles on the CPU (motion blur on). --check
verifies every frame's vertex count and velocity against the PLY files (and the solids' vertex
count and positions against the magnets include) and exits non-zero on a mismatch (the test
suite's use: tests/blender/blender_import_test.sh, blender_solids_test.sh).
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

# Appended to the handler when the solids move: their frame's mesh, as the fluid's.
HANDLER_SOLIDS_TEXT = '''
def ferro_show_solids(scene, depsgraph=None):
    obj = bpy.data.objects.get("FerroSolids")
    if obj is None:
        return
    mesh = bpy.data.meshes.get("ferro_solids_%04d" % scene.frame_current)
    if mesh is not None and obj.data != mesh:
        obj.data = mesh

for h in list(bpy.app.handlers.frame_change_pre):
    if getattr(h, "__name__", "") == "ferro_show_solids":
        bpy.app.handlers.frame_change_pre.remove(h)
bpy.app.handlers.frame_change_pre.append(ferro_show_solids)
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


def read_solids(path):
    """The solids of a frame's magnets include (povray/PovSolidInclude.cpp): None when the file
    declares no solids (FerroSolidCount = 0 or absent), else (declared vertex count, vertices in
    Ferro metres, triangles) of all its mesh2 blocks together, the triangles' indices offset
    by the vertices before them."""
    text = open(path).read()
    m = re.search(r"#declare\s+FerroSolidCount\s*=\s*(\d+)\s*;", text)
    count = int(m.group(1)) if m else 0
    if count == 0:
        return None
    start = text.find("#declare FerroSolids")
    if start < 0:
        fail(path + ": FerroSolidCount is %d but there is no FerroSolids" % count)
    blocks = re.findall(r"vertex_vectors\s*\{\s*(\d+)([^}]*)\}\s*face_indices\s*\{\s*(\d+)([^}]*)\}", text[start:])
    if len(blocks) != count:
        fail(path + ": FerroSolidCount is %d but FerroSolids has %d mesh2 blocks" % (count, len(blocks)))
    declared = 0
    verts, tris = [], []
    for nv_text, vv_text, nf_text, ff_text in blocks:
        base = len(verts) // 3
        vv = re.findall(r"<([^>]*)>", vv_text)
        ff = re.findall(r"<([^>]*)>", ff_text)
        if len(ff) != int(nf_text):
            fail(path + ": face_indices declares %s triangles and lists %d" % (nf_text, len(ff)))
        declared += int(nv_text)
        for v in vv:
            x, y, z = (float(c) / 1000.0 for c in v.split(","))
            verts.extend((x, z, y))  # POV-Ray <x, z, y> in mm -> Ferro (x, y, z) in m
        for f in ff:
            a, b, c = (int(i) for i in f.split(","))
            if max(a, b, c) >= len(vv):
                fail(path + ": a face index beyond the mesh2's vertices")
            tris.extend((base + a, base + b, base + c))
    return declared, verts, tris


def steel_material():
    """Brushed steel, as look.inc's LookSteel: a metallic grey, roughness 0.3, the highlight
    stretched round the local z axis (the grooves run along it)."""
    mat = bpy.data.materials.get("FerroSteel") or bpy.data.materials.new("FerroSteel")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    bsdf = nodes.get("Principled BSDF")
    if bsdf:
        bsdf.inputs["Base Color"].default_value = (0.56, 0.57, 0.59, 1.0)
        bsdf.inputs["Metallic"].default_value = 1.0
        bsdf.inputs["Roughness"].default_value = 0.3
        bsdf.inputs["Anisotropic"].default_value = 0.5
        tangent = nodes.new("ShaderNodeTangent")
        tangent.direction_type = "RADIAL"
        tangent.axis = "Z"
        mat.node_tree.links.new(tangent.outputs["Tangent"], bsdf.inputs["Tangent"])
    return mat


def check_solids(failures, f, shown, want, include):
    """--check of frame f's solids: the mesh shown is the frame's, with the include's vertices."""
    declared, verts, _ = include
    if shown.name != want:
        failures.append("frame %d shows solids mesh %s, not %s" % (f, shown.name, want))
        return
    if len(shown.vertices) != declared:
        failures.append("frame %d solids: %d vertices, the include declares %d" % (f, len(shown.vertices), declared))
        return
    got = [0.0] * (3 * declared)
    shown.vertices.foreach_get("co", got)
    worst = max((abs(a - b) for a, b in zip(got, verts)), default=0.0)
    if worst > 1e-6:
        failures.append("frame %d solids: vertices differ from the include's by %g m" % (f, worst))
        return
    print("import_shot: frame %d solids: %d vertices match (mesh %s)" % (f, declared, shown.name))


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

    # The solids, from each frame's magnets include; one static mesh when no frame differs.
    solids = {}
    for f, _ in frames:
        inc = os.path.join(shot, "shot", "magnets_%04d.inc" % f)
        solids[f] = read_solids(inc) if os.path.isfile(inc) else "missing"
    solid_obj = None
    solids_move = False
    if any(v not in (None, "missing") for v in solids.values()):
        for f, v in solids.items():
            if v == "missing":
                fail("shot/magnets_%04d.inc: missing, and other frames have solids (export every frame)" % f)
            if v is None:
                fail("shot/magnets_%04d.inc: no solids, and other frames have them" % f)
        first = solids[frames[0][0]]
        solids_move = any(solids[f][1:] != first[1:] for f, _ in frames)
        steel = steel_material()
        for f, _ in frames if solids_move else frames[:1]:
            _, verts, tris = solids[f]
            me = make_mesh("ferro_solids_%04d" % f if solids_move else "ferro_solids", verts, tris, None)
            me.polygons.foreach_set("use_smooth", [False] * len(me.polygons))  # flat, as ferro-pov's
            me.materials.append(steel)
        solid_obj = bpy.data.objects.new("FerroSolids", bpy.data.meshes[
            "ferro_solids_%04d" % frames[0][0] if solids_move else "ferro_solids"])
        scene.collection.objects.link(solid_obj)

    # The camera of the shot: location, look-at point, horizontal field of view.
    cam = bpy.data.cameras.new("FerroCamera")
    cam.sensor_fit = "HORIZONTAL"
    cam.angle = math.radians(pov_number(pov, "FerroCameraAngle"))
    # Ferro's shots are centimetres across: Blender's default near clip (0.1 m) cut off a
    # camera closer than that; POV-Ray has none. 1 mm, and the far clip 100 m.
    cam.clip_start = 0.001
    cam.clip_end = 100.0
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
    handler = HANDLER_TEXT + (HANDLER_SOLIDS_TEXT if solids_move else "")
    text.from_string(handler)
    text.use_module = True
    exec(compile(handler, "ferro_sequence.py", "exec"), {"bpy": bpy})

    failures = []
    if check:
        for f, _ in frames:
            scene.frame_set(f)
            if solid_obj is not None:
                check_solids(failures, f, solid_obj.data, "ferro_solids_%04d" % f if solids_move else "ferro_solids", solids[f])
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
